// continuous_run: the closed loop as one ODE, the controller inside the plant's right-hand side.
#include "continuous.h"
#include "ode.h"

// What the right-hand side needs: the controller, the plant and the status bits seen.
struct loop {
    const struct controller *ctrl;
    const struct plant *plant;
    uint32_t status;
};

// Returns true when all four state components are finite.
static bool state_finite(const fs_real x[4])
{
    return fs_isfinite(x[0]) && fs_isfinite(x[1]) && fs_isfinite(x[2]) && fs_isfinite(x[3]);
}

// Returns 0, or 1 when the controller faulted (the stage is then rejected); the closed loop with ideal sensors.
static int closed_loop_rhs(void *ctx, fs_real t, const fs_real *x, fs_real *dx)
{
    struct loop *c = ctx;
    fs_real y[CTRL_Y_LEN], v[2];
    uint32_t status;
    int k;
    for (k = 0; k < 4; k++)
        y[k] = x[k];
    y[CTRL_Y_ACC] = plant_acceleration(c->plant, x);
    status = c->ctrl->step(c->ctrl->self, t, y, v);
    c->status |= status;
    if (status & CTRL_FAULTS)
        return 1;
    plant_rhs(c->plant, x, v, dx);
    return 0;
}

// Returns the SIM_* code of an ODE_* failure.
static int sim_error(int ode_status)
{
    return ode_status == ODE_EHMIN ? SIM_EHMIN : (ode_status == ODE_ERHS ? SIM_ECONTROL : SIM_EARGS);
}

// Returns true when the n times are finite and nondecreasing (n_min of them at least).
static bool times_valid(const fs_real *t, size_t n, size_t n_min)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!fs_isfinite(t[i]) || (i > 0 && t[i] < t[i - 1]))
            return false;
    return n >= n_min;
}

// One segment's integrator: DOPRI5 or DOP853 (enum continuous_method).
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
    if (g->method == CONTINUOUS_DOPRI5)
        return ode_dopri5_init(&g->u.d5, op, 4, closed_loop_rhs, c, t, x);
    return ode_dop853_init(&g->u.d8, op, 4, closed_loop_rhs, c, t, x);
}

// Returns an ODE_* status; one accepted step towards t_end.
static int seg_step(struct segment *g, fs_real t_end)
{
    return g->method == CONTINUOUS_DOPRI5 ? ode_dopri5_step(&g->u.d5, t_end) : ode_dop853_step(&g->u.d8, t_end);
}

// Returns an ODE_* status; writes the dense-output state at t within the last step.
static int seg_dense(struct segment *g, fs_real t, fs_real *x)
{
    if (g->method == CONTINUOUS_DOPRI5)
        ode_dopri5_dense(&g->u.d5, t, x);
    else if (g->method == CONTINUOUS_DOP853)
        ode_dop853_hermite(&g->u.d8, t, x);
    else
        return ode_dop853_dense(&g->u.d8, t, x);
    return ODE_OK;
}

// Returns nothing; adds the segment's work to st and writes its current time and state.
static void seg_end(const struct segment *g, struct sim_stats *st, fs_real *t, fs_real x[4])
{
    const fs_real *xs = g->method == CONTINUOUS_DOPRI5 ? g->u.d5.x : g->u.d8.x;
    int m;
    st->steps += g->method == CONTINUOUS_DOPRI5 ? g->u.d5.steps : g->u.d8.steps;
    st->rejected += g->method == CONTINUOUS_DOPRI5 ? g->u.d5.rejected : g->u.d8.rejected;
    st->rhs_evals += g->method == CONTINUOUS_DOPRI5 ? g->u.d5.rhs_evals : g->u.d8.rhs_evals;
    *t = g->method == CONTINUOUS_DOPRI5 ? g->u.d5.t : g->u.d8.t;
    for (m = 0; m < 4; m++)
        x[m] = xs[m];
}

// Returns the end of the segment that starts at t: the first knot more than `tiny` after t and before t_end, or
// t_end (a knot closer than that would make a segment shorter than the integrator's rounding level).
static fs_real segment_end(const struct continuous_params *p, fs_real t, fs_real t_end, fs_real tiny)
{
    size_t k;
    for (k = 0; k < p->n_knots; k++)
        if (p->knots[k] > t + tiny && p->knots[k] < t_end - tiny)
            return p->knots[k];
    return t_end;
}

// Returns SIM_OK or an error sim_status; runs the closed loop from x0 at t_out[0] with ideal sensors (the state
// and the plant's true acceleration), the controller evaluated at every stage (a fault rejects the stage),
// integration restarted at each knot inside the run, and writes the state at each of the n_out
// nondecreasing times t_out into x_out (n_out x 4, row-major). SIM_EARGS for a controller with state.
int continuous_run(const struct controller *ctrl, const struct plant *plant, const fs_real *x0, const fs_real *t_out,
                   size_t n_out, const struct continuous_params *p, fs_real *x_out, struct sim_stats *st)
{
    struct loop c = {ctrl, plant, CTRL_OK};
    struct ode_params op;
    struct segment g;
    const fs_real *xs;
    fs_real x[4], t_end, a, b, t = 0;
    size_t i = 0;
    uint32_t steps = 0;
    int rc = SIM_OK, e, m;
    st->steps = st->rejected = st->rhs_evals = 0;
    st->controller_status = CTRL_OK;
    st->fault_periods = 0;
    st->t_fail = st->t_first_fault = 0;
    if (!ctrl->stateless || !times_valid(t_out, n_out, 1) || !times_valid(p->knots, p->n_knots, 0) || !state_finite(x0)
        || !plant_valid(plant) || !(p->rtol > 0) || !(p->atol > 0) || !(p->h_max > 0)
        || p->method > CONTINUOUS_DOP853_DENSE)
        return SIM_EARGS;
    op.rtol = p->rtol;
    op.atol = p->atol;
    op.h_max = p->h_max;
    ctrl->reset(ctrl->self);
    g.method = p->method;
    t_end = t_out[n_out - 1];
    for (m = 0; m < 4; m++)
        x[m] = x0[m];
    for (; i < n_out && t_out[i] <= t_out[0]; i++)
        for (m = 0; m < 4; m++)
            x_out[4 * i + m] = x0[m];
    for (a = t_out[0]; a < t_end && rc == SIM_OK; a = b) {
        // A new segment at each knot restarts the integrator, as the scipy engine restarts solve_ivp.
        b = segment_end(p, a, t_end, (fs_real)1e-12 * (t_end - t_out[0]));
        e = seg_init(&g, &op, &c, a, x);
        xs = g.method == CONTINUOUS_DOPRI5 ? g.u.d5.x : g.u.d8.x;
        for (t = a; e == ODE_OK && t < b; steps++) {
            if (steps >= p->max_steps || (p->cancel && *p->cancel)) {
                rc = steps >= p->max_steps ? SIM_EMAXSTEPS : SIM_ECANCELLED;
                break;
            }
            e = seg_step(&g, b);
            t = g.method == CONTINUOUS_DOPRI5 ? g.u.d5.t : g.u.d8.t;
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
    st->controller_status = c.status;
    return rc;
}
