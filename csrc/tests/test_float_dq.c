// The single-precision build (FS_SINGLE) of the field-weakening planner: the benchmark's moves planned within
// TOD_FLOAT_TOL of the double build's durations (time_optimal_dq_cases.h), feasible by the float margins.
#include <math.h>
#include <stdio.h>
#include "time_optimal_dq.h"
#include "time_optimal_dq_cases.h"

static fs_real work[60000];
static struct tod_result out;

// Returns 0 when the float planner plans every move of TOD_CASES within TOD_FLOAT_TOL of the table, 1 otherwise.
int main(void)
{
    size_t c, b, i, n = sizeof work / sizeof *work;
    int rc, failures = 0;
    double ms, want, worst = 0;
    if (sizeof(fs_real) != sizeof(float) || n < time_optimal_dq_work_len()) {
        printf("FAIL float_dq: not the single-precision build or the workspace too short\n");
        return 1;
    }
    for (c = 0; c < sizeof TOD_CASES / sizeof *TOD_CASES; c++)
        for (b = 0; b < 2; b++)
            for (i = 0; i < 5; i++) {
                const struct tod_limits lim = {(fs_real)TOD_CASE_BUS[b], FS_C(0.84), (fs_real)TOD_CASES[c].i_max, 0,
                                               FS_C(20000.0)};
                rc = time_optimal_dq_plan(&TOD_CASES[c].m, &lim, (fs_real)TOD_CASE_DISTANCE[i], work, n, &out);
                ms = rc == TOD_OK ? 1e3 * (double)out.breaks[out.n] : 0.0;
                want = TOD_CASES[c].ms[b][i];
                worst = fmax(worst, fabs(ms - want) / want);
                if (rc != TOD_OK || !(fabs(ms - want) <= TOD_FLOAT_TOL * want) || !(out.margins.worst <= 0)) {
                    printf("FAIL float_dq: %s %g V %g rad: rc %d, %.4f ms (double %.4f ms)\n", TOD_CASES[c].name,
                           TOD_CASE_BUS[b], TOD_CASE_DISTANCE[i], rc, ms, want);
                    failures++;
                }
            }
    printf("float_dq: %d failed, worst duration %.4f %% from double's\n", failures, 100 * worst);
    return failures != 0;
}
