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

// One segment's integrator: DOPRI5 or DOP853 (enum sim_method).
struct segment {
    uint32_t method;
    union {
        struct ode_dopri5 d5;
        struct ode_dop853 d8;
    } u;
};

// Returns an ODE_* status; starts the segment's integrator at (t, x).
static int seg_init(struct segment *g, const struct ode_params *op, struct loop *c, fs_real t, const fs_real *x)
{
    if (g->method == SIM_DOPRI5)
        return ode_dopri5_init(&g->u.d5, op, 4, closed_loop_rhs, c, t, x);
    return ode_dop853_init(&g->u.d8, op, 4, closed_loop_rhs, c, t, x);
}

// Returns an ODE_* status; one accepted step towards t_end.
static int seg_step(struct segment *g, fs_real t_end)
{
    return g->method == SIM_DOPRI5 ? ode_dopri5_step(&g->u.d5, t_end) : ode_dop853_step(&g->u.d8, t_end);
}

// Returns an ODE_* status; writes the dense-output state at t within the last step.
static int seg_dense(struct segment *g, fs_real t, fs_real *x)
{
    if (g->method == SIM_DOPRI5)
        ode_dopri5_dense(&g->u.d5, t, x);
    else if (g->method == SIM_DOP853)
        ode_dop853_hermite(&g->u.d8, t, x);
    else
        return ode_dop853_dense(&g->u.d8, t, x);
    return ODE_OK;
}

// Returns nothing; adds the segment's work to st and writes its current time and state.
static void seg_end(const struct segment *g, struct sim_stats *st, fs_real *t, fs_real x[4])
{
    const fs_real *xs = g->method == SIM_DOPRI5 ? g->u.d5.x : g->u.d8.x;
    int m;
    st->steps += g->method == SIM_DOPRI5 ? g->u.d5.steps : g->u.d8.steps;
    st->rejected += g->method == SIM_DOPRI5 ? g->u.d5.rejected : g->u.d8.rejected;
    st->rhs_evals += g->method == SIM_DOPRI5 ? g->u.d5.rhs_evals : g->u.d8.rhs_evals;
    *t = g->method == SIM_DOPRI5 ? g->u.d5.t : g->u.d8.t;
    for (m = 0; m < 4; m++)
        x[m] = xs[m];
}

// Returns SIM_OK or an error sim_status; runs the continuous closed loop from x0 at t_out[0], the law
// evaluated at every stage, integration restarted at the plan's knots t0 and tf, and writes the state at
// each of the n_out nondecreasing times t_out into x_out (n_out x 4, row-major).
int sim_continuous(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], const fs_real *t_out,
                   size_t n_out, const struct sim_continuous_params *p, fs_real *x_out, struct sim_stats *st)
{
    struct loop c = {ctrl, plant, {0, 0}, SMC_OK};
    struct ode_params op = {p->rtol, p->atol, p->h_max};
    struct segment g;
    const fs_real *xs;
    fs_real edges[4], x[4], t_end, t = 0;
    size_t i = 0, n_edges = 0, k;
    uint32_t steps = 0;
    int rc = SIM_OK, e, m;
    st->steps = st->rejected = st->rhs_evals = 0;
    st->smc_status = SMC_OK;
    st->t_fail = 0;
    if (!times_valid(t_out, n_out) || !state_finite(x0) || !motor_params_valid(&plant->motor)
        || !fs_isfinite(plant->load) || !(p->rtol > 0) || !(p->atol > 0) || !(p->h_max > 0)
        || p->method > SIM_DOP853_DENSE)
        return SIM_EARGS;
    g.method = p->method;
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
        e = seg_init(&g, &op, &c, edges[k], x);
        xs = g.method == SIM_DOPRI5 ? g.u.d5.x : g.u.d8.x;
        for (t = edges[k]; e == ODE_OK && t < edges[k + 1]; steps++) {
            if (steps >= p->max_steps) {
                rc = SIM_EMAXSTEPS;
                break;
            }
            e = seg_step(&g, edges[k + 1]);
            t = g.method == SIM_DOPRI5 ? g.u.d5.t : g.u.d8.t;
            for (; e == ODE_OK && i < n_out && t_out[i] <= t; i++) {
                if (t_out[i] == t)
                    for (m = 0; m < 4; m++)
                        x_out[4 * i + m] = xs[m];
                else
                    e = seg_dense(&g, t_out[i], &x_out[4 * i]);
            }
        }
        seg_end(&g, st, &t, x);
        if (e != ODE_OK)
            rc = sim_error(e);
        if (rc != SIM_OK)
            st->t_fail = t;
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
