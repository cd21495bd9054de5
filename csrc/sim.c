// The continuous and sampled closed-loop run loops over caller-owned output arrays.
#include "sim.h"
#include "ode.h"

// What the right-hand side needs: controller, plant, applied voltage (sampled loop) and the status seen.
struct loop {
    struct smc *ctrl;
    const struct sim_plant *plant;
    fs_real v[2];
    uint32_t status;
};

// Returns true when all four state components are finite.
static bool state_finite(const fs_real x[4])
{
    return fs_isfinite(x[0]) && fs_isfinite(x[1]) && fs_isfinite(x[2]) && fs_isfinite(x[3]);
}

// Returns nothing; writes the controller's measurement of the plant state x: (ia, ib, omega, theta, theta'')
// with the true acceleration: ideal sensors (sampled.c has the drive's encoder, ADC and observer).
static void sense(const struct sim_plant *plant, const fs_real x[4], fs_real y[5])
{
    int k;
    for (k = 0; k < 4; k++)
        y[k] = x[k];
    y[4] = motor_acceleration(&plant->motor, x, plant->load);
}

// Returns nothing; writes the voltage the phases see for a commanded v: an ideal bridge (drive.c has the bus
// saturation and computation delay that sampled_run applies).
static void drive(const fs_real v[2], fs_real v_applied[2])
{
    v_applied[0] = v[0];
    v_applied[1] = v[1];
}

// Returns 0, or 1 when the controller faulted (the stage is then rejected); the continuous closed loop.
static int closed_loop_rhs(void *ctx, fs_real t, const fs_real *x, fs_real *dx)
{
    struct loop *c = ctx;
    fs_real y[5], v[2];
    uint32_t status;
    sense(c->plant, x, y);
    status = smc_step(c->ctrl, t, y, v);
    c->status |= status;
    if (status & ~(uint32_t)SMC_SATURATED)
        return 1;
    motor_rhs(&c->plant->motor, x, v, c->plant->load, dx);
    return 0;
}

// Returns 0; the plant under the held voltage of the sampled loop.
static int held_rhs(void *ctx, fs_real t, const fs_real *x, fs_real *dx)
{
    struct loop *c = ctx;
    (void)t;
    motor_rhs(&c->plant->motor, x, c->v, c->plant->load, dx);
    return 0;
}

// Returns the SIM_* code of an ODE_* failure.
static int sim_error(int ode_status)
{
    return ode_status == ODE_EHMIN ? SIM_EHMIN : (ode_status == ODE_ERHS ? SIM_ECONTROL : SIM_EARGS);
}

// Returns true when the output times are finite and nondecreasing.
static bool times_valid(const fs_real *t, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!fs_isfinite(t[i]) || (i > 0 && t[i] < t[i - 1]))
            return false;
    return n > 0;
}

// Returns SIM_OK or an error sim_status; runs the continuous closed loop from x0 at t_out[0], the law
// evaluated at every stage, integration restarted at the plan's knots t0 and tf, and writes the state at
// each of the n_out nondecreasing times t_out into x_out (n_out x 4, row-major).
int sim_continuous(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], const fs_real *t_out,
                   size_t n_out, const struct sim_continuous_params *p, fs_real *x_out, struct sim_stats *st)
{
    struct loop c = {ctrl, plant, {0, 0}, SMC_OK};
    struct ode_dopri5_params op = {p->rtol, p->atol, p->h_max};
    struct ode_dopri5 ode;
    fs_real edges[4], x[4], t_end;
    size_t i = 0, n_edges = 0, k;
    int rc = SIM_OK, e, m;
    st->steps = st->rejected = st->rhs_evals = 0;
    st->smc_status = SMC_OK;
    st->t_fail = 0;
    if (!times_valid(t_out, n_out) || !state_finite(x0) || !motor_params_valid(&plant->motor)
        || !fs_isfinite(plant->load) || !(p->rtol > 0) || !(p->atol > 0) || !(p->h_max > 0))
        return SIM_EARGS;
    t_end = t_out[n_out - 1];
    edges[n_edges++] = t_out[0];
    if (ctrl->p.plan.t0 > t_out[0] && ctrl->p.plan.t0 < t_end)
        edges[n_edges++] = ctrl->p.plan.t0;
    if (ctrl->p.plan.tf > t_out[0] && ctrl->p.plan.tf < t_end)
        edges[n_edges++] = ctrl->p.plan.tf;
    edges[n_edges++] = t_end;
    for (m = 0; m < 4; m++)
        x[m] = x0[m];
    for (; i < n_out && t_out[i] <= t_out[0]; i++)
        for (m = 0; m < 4; m++)
            x_out[4 * i + m] = x0[m];
    for (k = 0; k + 1 < n_edges && rc == SIM_OK; k++) {
        // A new segment restarts the integrator, as simulate.py restarts solve_ivp at each knot.
        e = ode_dopri5_init(&ode, &op, 4, closed_loop_rhs, &c, edges[k], x);
        while (e == ODE_OK && ode.t < edges[k + 1]) {
            if (st->steps + ode.steps >= p->max_steps) {
                rc = SIM_EMAXSTEPS;
                break;
            }
            e = ode_dopri5_step(&ode, edges[k + 1]);
            for (; e == ODE_OK && i < n_out && t_out[i] <= ode.t; i++) {
                if (t_out[i] == ode.t)
                    for (m = 0; m < 4; m++)
                        x_out[4 * i + m] = ode.x[m];
                else
                    ode_dopri5_dense(&ode, t_out[i], &x_out[4 * i]);
            }
        }
        st->steps += ode.steps;
        st->rejected += ode.rejected;
        st->rhs_evals += ode.rhs_evals;
        if (e != ODE_OK)
            rc = sim_error(e);
        if (rc != SIM_OK)
            st->t_fail = ode.t;
        for (m = 0; m < 4; m++)
            x[m] = ode.x[m];
    }
    st->smc_status = c.status;
    return rc;
}

// Returns SIM_OK or an error sim_status; runs the sampled loop from x0 at t_start for n_periods periods
// (controller at t_k = t_start + k Ts, voltage held, plant by RK4 substeps) and writes the state at every
// t_k, k = 0..n_periods, into x_out ((n_periods + 1) x 4) and the voltage applied from t_k into v_out
// ((n_periods + 1) x 2). Controller faults do not stop the run: the controller then applies 0 V.
int sim_sampled(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], fs_real t_start,
                size_t n_periods, const struct sim_sampled_params *p, fs_real *x_out, fs_real *v_out,
                struct sim_stats *st)
{
    struct loop c = {ctrl, plant, {0, 0}, SMC_OK};
    fs_real x[4], y[5], v[2], t, h;
    size_t k;
    uint32_t j;
    int m;
    st->steps = st->rejected = st->rhs_evals = 0;
    st->smc_status = SMC_OK;
    st->t_fail = 0;
    if (!state_finite(x0) || !fs_isfinite(t_start) || !motor_params_valid(&plant->motor)
        || !fs_isfinite(plant->load) || !(p->Ts > 0) || !fs_isfinite(p->Ts) || p->substeps < 1)
        return SIM_EARGS;
    h = p->Ts / (fs_real)p->substeps;
    for (m = 0; m < 4; m++)
        x[m] = x0[m];
    for (k = 0;; k++) {
        t = t_start + (fs_real)k * p->Ts;
        for (m = 0; m < 4; m++)
            x_out[4 * k + m] = x[m];
        if (!state_finite(x)) {
            st->t_fail = t;
            st->smc_status = c.status;
            return SIM_ENONFINITE;
        }
        // One period: sense -> control -> drive -> plant, all ideal; sampled_run (sampled.c) models the drive.
        sense(plant, x, y);
        c.status |= smc_step(ctrl, t, y, v);
        drive(v, c.v);
        v_out[2 * k] = c.v[0];
        v_out[2 * k + 1] = c.v[1];
        if (k == n_periods)
            break;
        for (j = 0; j < p->substeps; j++)
            ode_rk4_step(held_rhs, &c, 4, t + (fs_real)j * h, h, x);
        st->steps += p->substeps;
        st->rhs_evals += 4 * p->substeps;
    }
    st->smc_status = c.status;
    return SIM_OK;
}
