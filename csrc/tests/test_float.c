// The single-precision build (FS_SINGLE): the law on the paper's plan and a short continuous run.
#include <stdio.h>
#include "flat.h"
#include "continuous.h"
#include "smc.h"

// Returns 0 when the float core reproduces the feedforward and tracks the paper's move, 1 otherwise.
int main(void)
{
    struct smc_params p;
    struct smc s;
    struct plant plant = {{0, 0, 0, 0, 0, 0}, 0, {0, 0, 0, 0, 0}};
    struct controller c;
    const float knots[2] = {0.02f, 0.04f};
    struct continuous_params cp = {1e-5f, 1e-8f, 1.0f, 100000, CONTINUOUS_DOP853, knots, 2, NULL};
    struct sim_stats st;
    float f[PLAN_FLAG_LEN], x[4], vff[2], y[5], v[2], t_out[2] = {0.0f, 0.06f}, x_out[8], x0[4] = {0.4f, 0, 0, 0};
    int i, failures = 0, rc;
    smc_params_default(&p);
    if (smc_init(&s, &p) != SMC_PARAMS_OK || sizeof(fs_real) != sizeof(float))
        failures++;
    for (i = 0; i <= 20; i++) {
        float t = 0.02f + 0.001f * (float)i;
        plan_eval(&p.plan, t, f);
        flat_to_state(&p.motor, f, 0, x, vff);
        y[0] = x[0], y[1] = x[1], y[2] = x[2], y[3] = x[3], y[4] = f[PLAN_DDTHETA];
        if (smc_step(&s, t, y, v) != SMC_OK || fabsf(v[0] - vff[0]) > 1e-4f * (1 + fabsf(vff[0]))
            || fabsf(v[1] - vff[1]) > 1e-4f * (1 + fabsf(vff[1]))) {
            printf("FAIL t %g: v (%g, %g) vs feedforward (%g, %g)\n", (double)t, (double)v[0], (double)v[1],
                   (double)vff[0], (double)vff[1]);
            failures++;
        }
    }
    plant.motor = p.motor;
    plant.load = 0;
    smc_controller(&s, &c);
    rc = continuous_run(&c, &plant, x0, t_out, 2, &cp, x_out, &st);
    printf("float: Fig. 1 run rc %d, theta(0.06) = %.7g (want 0.02), %u steps\n", rc, (double)x_out[7], st.steps);
    if (rc != SIM_OK || fabsf(x_out[7] - 0.02f) > 1e-5f)
        failures++;
    printf("float: %d failed\n", failures);
    return failures != 0;
}
