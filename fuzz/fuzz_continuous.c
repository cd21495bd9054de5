// libFuzzer harness for continuous_run: the closed loop as one ODE (DOP853, DOPRI5 or DOP853 with 7th-order output)
// with any controller and plant either refuses its arguments with SIM_EARGS, stops with a documented status, or
// writes finite states at every output time; the laws with state are refused.
//
// Input: a header byte (law, its options), a 32-bit mask of the groups decoded hostile (the others take the
// nominal: the paper's motor and move, rtol 1e-6, outputs every 5 ms to 50 ms), then the groups' values
// (fuzz/decode.h). Each input is bounded by max_steps <= 1020 accepted steps.
#include <stdio.h>
#include <stdlib.h>
#include "continuous.h"
#include "laws.h"

#define N_OUT_MAX 32

// Returns true when the n times are finite and nondecreasing, and at least n_min of them.
static bool times_ok(const double *t, size_t n, size_t n_min)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(t[i]) || (i > 0 && t[i] < t[i - 1]))
            return false;
    return n >= n_min;
}

// Returns 0 (libFuzzer's convention); aborts when a contract of the continuous loop is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct fz_law law;
    struct fz_reader r = {data, size};
    struct motor_params model;
    struct plan plan;
    struct plant plant;
    struct continuous_params p;
    struct sim_stats st;
    double x0[4], t_out[N_OUT_MAX], x_out[4 * N_OUT_MAX], knots[3];
    uint8_t head = fz_byte(&r, 0);
    uint32_t mask = fz_u32(&r, 0);
    volatile uint32_t cancel = 0;
    size_t n_out, i;
    bool bad;
    int rc, m;
    fz_motor(&r, mask & 1, &model);
    fz_plan(&r, mask & (1u << 15), 0.02, 0.04, &plan);
    fz_plant(&r, (uint8_t)((mask >> 1) & 31), &model, &plant);
    if (fz_law_init(&law, head & 3, &r, mask & (1u << 16), (uint8_t)(head >> 2), &model, &plan, 2e-4, INFINITY) != 0)
        return 0;
    x0[0] = plan.rho1 * cos(plant.motor.Nr * plan.theta1), x0[1] = plan.rho1 * sin(plant.motor.Nr * plan.theta1);
    x0[2] = 0, x0[3] = plan.theta1;
    for (m = 0; mask & (1u << 17) && m < 4; m++)
        x0[m] = fz_value(&r, x0[m]);
    p.rtol = 1e-6, p.atol = 1e-8, p.h_max = 1e-3, p.method = fz_byte(&r, 0) % 3, p.cancel = &cancel;
    p.max_steps = 4u * fz_byte(&r, 100);
    if (mask & (1u << 6)) {
        p.rtol = fz_value(&r, p.rtol), p.atol = fz_value(&r, p.atol), p.h_max = fz_value(&r, p.h_max);
        p.method = fz_byte(&r, 0) % 5;  // 3 and 4 are not methods
    }
    knots[0] = plan.t0, knots[1] = plan.tf, knots[2] = 1.0, p.knots = knots, p.n_knots = 2;
    if (mask & (1u << 7)) {
        p.n_knots = fz_byte(&r, 2) % 4;
        for (i = 0; i < p.n_knots; i++)
            knots[i] = fz_value(&r, knots[i]);
    }
    n_out = mask & (1u << 8) ? fz_byte(&r, 11) % (N_OUT_MAX + 1) : 11;
    for (i = 0; i < n_out; i++)
        t_out[i] = mask & (1u << 9) ? (i ? t_out[i - 1] : 0) + fz_value(&r, i ? 5e-3 : 0) : 5e-3 * (double)i;
    if (mask & (1u << 19)) {
        law.cancel = &cancel;
        law.cancel_at = fz_byte(&r, 100);  // 0: set before the run
        cancel = law.cancel_at == 0;
    }
    for (i = 0; i < 4 * N_OUT_MAX; i++)
        x_out[i] = NAN;
    bad = !law.outer.stateless || !times_ok(t_out, n_out, 1) || !times_ok(knots, p.n_knots, 0)
          || !(isfinite(x0[0]) && isfinite(x0[1]) && isfinite(x0[2]) && isfinite(x0[3])) || !fz_plant_ok(&plant)
          || !(p.rtol > 0) || !(p.atol > 0) || !(p.h_max > 0) || p.method > CONTINUOUS_DOP853_DENSE;
    rc = continuous_run(&law.outer, &plant, x0, t_out, n_out, &p, x_out, &st);
#ifdef FZ_VERBOSE
    fprintf(stderr, "continuous: law %d method %u status %d, %u steps %u rejected %u evaluations, status %u\n",
            law.kind, (unsigned)p.method, rc, (unsigned)st.steps, (unsigned)st.rejected, (unsigned)st.rhs_evals,
            (unsigned)st.controller_status);
#endif
    if (rc != SIM_OK && rc != SIM_EARGS && rc != SIM_ECONTROL && rc != SIM_EHMIN && rc != SIM_EMAXSTEPS
        && rc != SIM_ECANCELLED)
        FZ_FAIL("continuous_run returned %d, not a documented status", rc);
    if ((rc == SIM_EARGS) != bad)
        FZ_FAIL("continuous_run returned %d on %s arguments", rc, bad ? "invalid" : "valid");
    if (rc == SIM_EARGS)
        return 0;
    if (rc == SIM_ECANCELLED && !cancel)
        FZ_FAIL("SIM_ECANCELLED, yet the cancel flag was never set");
    if (st.steps > p.max_steps || st.controller_status != law.status_or)
        FZ_FAIL("sim_stats: %u steps for max_steps %u, status %u for the controller's %u", (unsigned)st.steps,
                (unsigned)p.max_steps, (unsigned)st.controller_status, (unsigned)law.status_or);
    if (rc != SIM_OK && !(st.t_fail >= t_out[0] && st.t_fail <= t_out[n_out - 1]))
        FZ_FAIL("status %d at t_fail %.17g outside the run [%g, %g]", rc, st.t_fail, t_out[0], t_out[n_out - 1]);
    for (i = 0; i < n_out && t_out[i] <= t_out[0]; i++)
        if (memcmp(&x_out[4 * i], x0, sizeof x0) != 0)
            FZ_FAIL("output %zu at the start time is not x0", i);
    for (i = 0; rc == SIM_OK && i < n_out; i++)
        for (m = 0; m < 4; m++)
            if (!isfinite(x_out[4 * i + m]))
                FZ_FAIL("SIM_OK with a non-finite or unwritten state x[%d] = %g at t = %.17g (output %zu of %zu)", m,
                        x_out[4 * i + m], t_out[i], i, n_out);
    return 0;
}
