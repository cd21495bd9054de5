// The C work of simulate(engine="c") on Fig. 1: continuous_run (DOP853, rtol 1e-7) then arrays_result on the
// 6001 output samples, each repeated; for callgrind (instructions per evaluation and per result sample).
//   cc -std=c99 -O2 -g -Icsrc csrc/*.c benchmarks/result_bench.c -lm -o /tmp/result_bench
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/cgr.out /tmp/result_bench 5
//   callgrind_annotate --inclusive=yes /tmp/cgr.out
#include <stdio.h>
#include <stdlib.h>
#include "arrays.h"
#include "continuous.h"

#define N 6001

static double t[N], x[4 * N], out[RES_LEN * N];
static uint32_t status[N];

// Returns 0; runs the loop and the result assembly argv[1] times each (default 50).
int main(int argc, char **argv)
{
    struct smc_params p;
    struct smc s;
    struct plant plant = {{0, 0, 0, 0, 0, 0}, 0, {0, 0, 0, 0, 0}};
    struct controller c;
    struct sim_stats st;
    const double knots[2] = {0.02, 0.04};
    struct continuous_params cp = {1e-7, 1e-9, 1.0, 1000000, CONTINUOUS_DOP853, knots, 2, NULL};
    double x0[4] = {0.4, 0, 0, 0};
    int reps = argc > 1 ? atoi(argv[1]) : 50, r, i, rc = SIM_OK;
    smc_params_default(&p);
    smc_init(&s, &p);
    smc_controller(&s, &c);
    plant.motor = p.motor;
    for (i = 0; i < N; i++)
        t[i] = 0.06 * i / (N - 1);
    for (r = 0; r < reps; r++)
        rc |= continuous_run(&c, &plant, x0, t, N, &cp, x, &st);
    for (r = 0; r < reps; r++)
        arrays_result(&s, &plant, t, x, N, out, status);
    printf("rc %d, rhs_evals %u, steps %u, result samples %d\n", rc, st.rhs_evals, st.steps, N);
    return rc;
}
