// Benchmark driver: milliseconds per sampled closed-loop run of Fig. 1 (clocks live here, never in csrc/).
//
// Usage: sampled_bench RUNS
//   Runs the paper's controller at 20 kHz (Ts = 50 us, 10 RK4 substeps, 1200 periods: 60 ms) RUNS times from
//   the plan's start state and prints "ms_per_run X", "plant_evals N" (per run) and "theta_final X".
//   Under `valgrind --tool=callgrind` the per-function counts divided by RUNS * plant_evals give the
//   instructions per plant evaluation.
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "flat.h"
#include "sampled.h"
#include "smc.h"

#define PERIODS 1200

// Returns the time in seconds from a monotonic clock.
static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    static fs_real x[(PERIODS + 1) * 4], v[(PERIODS + 1) * 2];
    struct smc_params p;
    struct smc s;
    struct sim_stats st = {0, 0, 0, 0, 0};
    struct sampled_params sp = {0};
    struct sampled loop;
    struct controller c;
    struct plant plant = {{0, 0, 0, 0, 0, 0}, 0, {0, 0, 0, 0, 0}};
    fs_real flag[PLAN_FLAG_LEN], x0[4], v0[2];
    double t_start;
    long runs, r;
    if (argc != 2 || (runs = atol(argv[1])) < 1) {
        fprintf(stderr, "usage: %s RUNS\n", argv[0]);
        return 2;
    }
    smc_params_default(&p);
    if (smc_init(&s, &p) != SMC_PARAMS_OK)
        return 1;
    smc_controller(&s, &c);
    plant.motor = p.motor;
    sp.Ts = FS_C(5e-5);
    sp.substeps = 10;
    sp.drive.v_bus = INFINITY;
    sp.model = p.motor;
    if (sampled_init(&loop, &sp) != SIM_OK)
        return 1;
    plan_eval(&p.plan, 0, flag);
    flat_to_state(&p.motor, flag, 0, x0, v0);
    t_start = now();
    for (r = 0; r < runs; r++)
        if (sampled_run(&loop, &c, &plant, x0, PERIODS, NULL, x, v, NULL, NULL, &st) != SIM_OK)
            return 1;
    printf("ms_per_run %.4f\n", (now() - t_start) * 1e3 / (double)runs);
    printf("plant_evals %u\n", (unsigned)st.rhs_evals);
    printf("theta_final %.17g\n", x[PERIODS * 4 + 3]);
    return 0;
}
