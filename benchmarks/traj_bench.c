// Benchmark driver: nanoseconds per sample of traj_flag (every derivative of the flag) beside plan_flag.
//
// Build and run (clocks live here, never in csrc/):
//   cc -O2 -std=c99 -Icsrc benchmarks/traj_bench.c csrc/trajectory.c csrc/plan.c -lm -o build/traj_bench
//   build/traj_bench
// Prints, per case, the median ns per sample over REPEAT timed loops of NT samples, for times in order (a control
// loop's) and shuffled (every lookup a cold bisection), and the ratio to plan_flag on the paper's move.
#define _POSIX_C_SOURCE 199309L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "plan.h"
#include "trajectory.h"

#define NT 4096
#define REPEAT 41
#define MAXSEG 1000

static double breaks[MAXSEG + 1], theta[MAXSEG * TRAJ_NCOEF], rho[MAXSEG * TRAJ_NCOEF];
static const double PSI[TRAJ_NCOEF] = {-126, 700, -1575, 1800, -1050, 252, 0, 0, 0, 0, 0};

// Returns the monotonic clock in seconds.
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

// Returns a uniform number in [0, 1) from a 64-bit LCG.
static double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 9007199254740992.0;
}

// Returns nothing; a table of n psi moves of 1 rad, 10 ms each.
static void make_table(size_t n)
{
    size_t i, j;
    for (i = 0; i <= n; i++)
        breaks[i] = 0.01 * (double)i;
    for (i = 0; i < n; i++)
        for (j = 0; j < TRAJ_NCOEF; j++) {
            theta[i * TRAJ_NCOEF + j] = PSI[j] + (j == TRAJ_NCOEF - 1 ? (double)i : 0);
            rho[i * TRAJ_NCOEF + j] = j == TRAJ_NCOEF - 1 ? 0.5 : 0;
        }
}

// Returns nothing; NT times over [lo, hi], in order or shuffled.
static void make_times(double lo, double hi, int shuffled, double *t)
{
    uint64_t seed = 7;
    size_t i, k;
    double tmp;
    for (i = 0; i < NT; i++)
        t[i] = lo + (hi - lo) * ((double)i + 0.5) / NT;
    for (i = NT - 1; shuffled && i > 0; i--) {
        k = (size_t)(uniform(&seed) * (double)(i + 1));
        tmp = t[i], t[i] = t[k], t[k] = tmp;
    }
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

// Returns the median ns per sample of traj_flag (tr != NULL; with a segment guess kept from call to call when
// hint), or plan_flag over the times t; adds to *sum.
static double time_it(const struct traj *tr, int hint, const struct plan_coef *pc, const double *t, double *sum)
{
    double runs[REPEAT], flag[PLAN_FLAG_LEN], t0;
    size_t seg = 0;
    int r, i, k;
    for (r = 0; r < REPEAT; r++) {
        t0 = now();
        for (i = 0; i < NT; i++) {
            if (tr && hint)
                traj_flag_seg(tr, t[i], &seg, flag);
            else if (tr)
                traj_flag(tr, t[i], flag);
            else
                plan_flag(pc, t[i], flag);
            for (k = 0; k < PLAN_FLAG_LEN; k++)
                *sum += flag[k];
        }
        runs[r] = (now() - t0) / NT * 1e9;
    }
    qsort(runs, REPEAT, sizeof runs[0], cmp);
    return runs[REPEAT / 2];
}

// Returns 0; prints the table of timings.
int main(void)
{
    static const size_t sizes[] = {1, 10, 100, 1000};
    static double t[NT];
    const struct plan paper = {0, 1, 0.5, 0.5, 0, 0.01, NULL};
    struct plan_coef pc;
    struct traj tr;
    double sum = 0, base, ns;
    size_t s;
    int shuffled;
    plan_init(&pc, &paper);
    make_times(0, 0.01, 0, t);
    base = time_it(NULL, 0, &pc, t, &sum);
    printf("plan_flag (the paper's psi, one move)              %6.2f ns/sample\n", base);
    for (s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        make_table(sizes[s]);
        tr.n = sizes[s], tr.breaks = breaks, tr.theta = theta, tr.rho = rho;
        for (shuffled = 0; shuffled < 2; shuffled++) {
            make_times(0, 0.01 * (double)sizes[s], shuffled, t);
            ns = time_it(&tr, 0, NULL, t, &sum);
            printf("traj_flag     %4zu segment(s), times %-8s %6.2f ns/sample  (%.2f x plan_flag)\n", sizes[s],
                   shuffled ? "shuffled" : "in order", ns, ns / base);
            ns = time_it(&tr, 1, NULL, t, &sum);
            printf("traj_flag_seg %4zu segment(s), times %-8s %6.2f ns/sample  (%.2f x plan_flag)\n", sizes[s],
                   shuffled ? "shuffled" : "in order", ns, ns / base);
        }
    }
    printf("checksum %g\n", sum);
    return 0;
}
