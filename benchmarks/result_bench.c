// The C work of simulate(engine="c") on Fig. 1: sim_continuous (DOP853, rtol 1e-7) then batch_result on the
// 6001 output samples, each repeated; for callgrind (instructions per evaluation and per result sample).
//   cc -std=c99 -O2 -g -Icsrc csrc/*.c benchmarks/result_bench.c -lm -o /tmp/result_bench
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/cgr.out /tmp/result_bench 5
//   callgrind_annotate --inclusive=yes /tmp/cgr.out
#include <stdio.h>
#include <stdlib.h>
#include "batch.h"

#define N 6001

static double t[N], x[4 * N], out[RES_LEN * N];
static uint32_t status[N];

// Returns 0; runs the loop and the result assembly argv[1] times each (default 50).
int main(int argc, char **argv)
{
    struct smc_params p;
    struct smc s;
    struct sim_plant plant;
    struct sim_stats st;
    struct sim_continuous_params cp = {1e-7, 1e-9, 1.0, 1000000, SIM_DOP853};
    double x0[4] = {0.4, 0, 0, 0};
    int reps = argc > 1 ? atoi(argv[1]) : 50, r, i, rc = SIM_OK;
    smc_params_default(&p);
    smc_init(&s, &p);
    plant.motor = p.motor;
    plant.load = 0;
    for (i = 0; i < N; i++)
        t[i] = 0.06 * i / (N - 1);
    for (r = 0; r < reps; r++)
        rc |= sim_continuous(&s, &plant, x0, t, N, &cp, x, &st);
    for (r = 0; r < reps; r++)
        batch_result(&s, &p.motor, 0, t, x, N, out, status);
    printf("rc %d, rhs_evals %u, steps %u, result samples %d\n", rc, st.rhs_evals, st.steps, N);
    return rc;
}
