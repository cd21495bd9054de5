// A tiny test harness: CHECK counts and reports failures, REL gives the relative difference of two values.
#ifndef FS_CHECK_H
#define FS_CHECK_H

#include <math.h>
#include <stdio.h>

extern int check_count, check_failures;

#define CHECK(cond, ...)                                            \
    do {                                                            \
        check_count++;                                              \
        if (!(cond)) {                                              \
            check_failures++;                                       \
            printf("FAIL %s:%d: (%s) ", __FILE__, __LINE__, #cond); \
            printf(__VA_ARGS__);                                    \
            printf("\n");                                           \
        }                                                           \
    } while (0)

// Returns |a - b| / |b| (0 when both are 0, infinite when only b is 0).
static inline double rel_diff(double a, double b)
{
    return a == b ? 0.0 : fabs(a - b) / fabs(b);
}

int test_vectors(const char *path);
int test_plan(void);
int test_smc(void);
int test_ode(void);
int test_sim(void);
int test_drive(void);
int test_baselines(void);
int test_dq_smc(void);
int test_dq_smc_km(void);
int test_trajectory(void);
int test_time_optimal(void);
int test_time_optimal_dq(void);

#endif
