// Benchmark driver: nanoseconds per smc_step call over varied inputs (clocks live here, never in csrc/).
//
// Usage: smc_step_bench CALLS REPEAT [move]
//   With "move" the inputs lie inside the move (t0, tf) only, where the plan's polynomials are evaluated.
//   Prints one line "ns_per_call MEDIAN MIN MAX" over REPEAT timed loops of CALLS smc_step calls, then
//   "calls N", "status_or BITS" and "checksum X" (the sum of every voltage, so the loop cannot be elided).
//   Under `valgrind --tool=callgrind --toggle-collect=smc_step` the collected Ir divided by REPEAT * CALLS
//   is the instruction count of one call (callees included).
//
// Inputs: NIN samples at times spread over the paper's 60 ms horizon (before, during and after the move; with
// "move", over (t0, tf) only),
// each the planned state perturbed by a few percent in current, speed, angle and acceleration, so the law
// runs its full path (no fault short-cut) with both signs of s1 and s2.
#define _POSIX_C_SOURCE 199309L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "flat.h"
#include "plan.h"
#include "smc.h"

#define NIN 1024

// Returns a uniform number in [-1, 1) from a 64-bit LCG (deterministic across platforms).
static double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

// Returns nothing; fills t[NIN] and y[NIN][5] with perturbed planned measurements at times spread over
// [t_lo, t_hi].
static void make_inputs(const struct smc_params *p, double t_lo, double t_hi, fs_real t[NIN], fs_real y[NIN][5])
{
    uint64_t seed = 12345;
    fs_real flag[PLAN_FLAG_LEN], x[4], v[2];
    int i;
    for (i = 0; i < NIN; i++) {
        t[i] = (fs_real)(t_lo + (t_hi - t_lo) * (i + 0.5) / NIN);
        plan_eval(&p->plan, t[i], flag);
        flat_to_state(&p->motor, flag, 0, x, v);
        y[i][0] = x[0] + (fs_real)(0.02 * uniform(&seed));
        y[i][1] = x[1] + (fs_real)(0.02 * uniform(&seed));
        y[i][2] = x[2] + (fs_real)(0.5 * uniform(&seed));
        y[i][3] = x[3] + (fs_real)(1e-3 * uniform(&seed));
        y[i][4] = flag[PLAN_DDTHETA] + (fs_real)(50.0 * uniform(&seed));
    }
}

// Returns the time in seconds from a monotonic clock.
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

// Returns the comparison of two doubles for qsort.
static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    static fs_real t[NIN], y[NIN][5];
    struct smc_params p;
    struct smc s;
    fs_real v[2];
    double sum = 0, *ns, t_start;
    uint32_t status_or = 0;
    long calls, repeat, r, i;
    if (argc < 3 || argc > 4 || (calls = atol(argv[1])) < 1 || (repeat = atol(argv[2])) < 1
        || (argc == 4 && strcmp(argv[3], "move") != 0)) {
        fprintf(stderr, "usage: %s CALLS REPEAT [move]\n", argv[0]);
        return 2;
    }
    smc_params_default(&p);
    if (smc_init(&s, &p) != SMC_PARAMS_OK) {
        fprintf(stderr, "smc_init rejected the default parameters\n");
        return 1;
    }
    if (argc == 4)
        make_inputs(&p, p.plan.t0, p.plan.tf, t, y);
    else
        make_inputs(&p, 0.0, 0.06, t, y);
    ns = malloc((size_t)repeat * sizeof *ns);
    if (!ns)
        return 1;
    for (r = 0; r < repeat; r++) {
        t_start = now();
        for (i = 0; i < calls; i++) {
            status_or |= smc_step(&s, t[i % NIN], y[i % NIN], v);
            sum += v[0] + v[1];
        }
        ns[r] = (now() - t_start) * 1e9 / (double)calls;
    }
    qsort(ns, (size_t)repeat, sizeof *ns, cmp);
    printf("ns_per_call %.3f %.3f %.3f\n", ns[repeat / 2], ns[0], ns[repeat - 1]);
    printf("calls %ld\n", calls * repeat);
    printf("status_or %u\n", (unsigned)status_or);
    printf("checksum %.17g\n", sum);
    free(ns);
    return 0;
}
