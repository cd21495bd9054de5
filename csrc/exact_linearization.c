// exact_linearization_init / _reset / _step: the law of flatstep.control.exact_linearization, in its operation order.
#include "exact_linearization.h"

// Returns true when x is finite and > 0.
static bool positive(fs_real x)
{
    return fs_isfinite(x) && x > 0;
}

// Returns EXACT_LINEARIZATION_PARAMS_OK, or the exact_linearization_param_error naming the invalid group.
int exact_linearization_init(struct exact_linearization *s, const struct exact_linearization_params *p)
{
    const struct exact_linearization_gains *g = &p->gains;
    fs_real a1, a2;
    if (!motor_params_valid(&p->motor) || !fs_isfinite(p->motor.L / p->motor.Km)
        || !fs_isfinite(p->motor.L * p->motor.Nr))
        return EXACT_LINEARIZATION_EMOTOR;
    if (!plan_valid(&p->plan))
        return EXACT_LINEARIZATION_EPLAN;
    if (!(positive(g->wn) && positive(g->xi) && positive(g->p3) && positive(g->pd)))
        return EXACT_LINEARIZATION_EGAINS;
    a1 = g->wn * g->wn;
    a2 = 2 * g->xi * g->wn;
    s->k0 = g->p3 * a1;
    s->k1 = a1 + g->p3 * a2;
    s->k2 = a2 + g->p3;
    if (!(fs_isfinite(s->k0) && fs_isfinite(s->k1) && fs_isfinite(s->k2) && fs_isfinite(p->motor.L * g->pd)))
        return EXACT_LINEARIZATION_EGAINS;
    if (p->measurement != EXACT_LINEARIZATION_MEASURED && p->measurement != EXACT_LINEARIZATION_MODEL)
        return EXACT_LINEARIZATION_EMEASUREMENT;
    if (!(p->v_limit > 0))
        return EXACT_LINEARIZATION_ELIMITS;
    if (!torque_model_valid(&p->torques))
        return EXACT_LINEARIZATION_ETORQUES;
    s->p = *p;
    plan_init(&s->plan, &p->plan);
    s->L_Nr = p->motor.L * p->motor.Nr;
    s->L_Km = p->motor.L / p->motor.Km;
    return EXACT_LINEARIZATION_PARAMS_OK;
}

// Returns nothing; the law has no state.
void exact_linearization_reset(struct exact_linearization *s)
{
    (void)s;
}

// Returns ctrl_status bits; writes the law's voltages v (exact_linearization.h).
uint32_t exact_linearization_step(struct exact_linearization *s, fs_real t, const fs_real *y, fs_real *v)
{
    // u = theta*''' - k2 e'' - k1 e' - k0 e; vq = R iq + L Nr omega id + Km omega + L / Km (J u + B theta'' + E'),
    // vd = R id - L Nr omega iq - L pd id (theta''' = u, id' = -pd id); v = inverse Park of (vd, vq).
    const struct motor_params *m = &s->p.motor;
    const struct torque_model *E = &s->p.torques;
    fs_real ref[PLAN_FLAG_LEN], sn, cs, id, iq, acc, u, dE, vd, vq, out[2], z;
    bool measured = s->p.measurement == EXACT_LINEARIZATION_MEASURED;
    v[0] = v[1] = 0;
    // x - x is 0 for a finite x and NaN otherwise: one test covers every input used.
    z = (t - t) + (y[0] - y[0]) + (y[1] - y[1]) + (y[2] - y[2]) + (y[3] - y[3]);
    if (measured)
        z += y[4] - y[4];
    if (z != 0)
        return CTRL_NONFINITE;
    // Park transform by Nr theta: id = ia c + ib s, iq = -ia s + ib c.
    fs_sincos(m->Nr * y[3], &sn, &cs);
    id = y[0] * cs + y[1] * sn;
    iq = -y[0] * sn + y[1] * cs;
    acc = measured ? y[4] : (m->Km * iq - m->B * y[2] - torque_model_torque(E, m->Nr, t, y[3], y[2])) / m->J;
    dE = torque_model_rate(E, m->Nr, t, y[3], y[2], acc);
    plan_flag(&s->plan, t, ref);
    u = ref[PLAN_DDDTHETA] - s->k2 * (acc - ref[PLAN_DDTHETA]) - s->k1 * (y[2] - ref[PLAN_DTHETA])
        - s->k0 * (y[3] - ref[PLAN_THETA]);
    vq = m->R * iq + s->L_Nr * y[2] * id + m->Km * y[2] + s->L_Km * (m->J * u + m->B * acc + dE);
    vd = m->R * id - s->L_Nr * y[2] * iq - m->L * s->p.gains.pd * id;
    out[0] = vd * cs - vq * sn;
    out[1] = vd * sn + vq * cs;
    if (!(fs_isfinite(out[0]) && fs_isfinite(out[1])))
        return CTRL_OVERFLOW;
    v[0] = out[0];
    v[1] = out[1];
    return fs_fabs(out[0]) > s->p.v_limit || fs_fabs(out[1]) > s->p.v_limit ? CTRL_SATURATED : CTRL_OK;
}

// Returns exact_linearization_step's status for the interface's untyped state.
static uint32_t exact_linearization_step_any(void *self, fs_real t, const fs_real *y, fs_real *v)
{
    return exact_linearization_step(self, t, y, v);
}

// Returns nothing; exact_linearization_reset for the interface's untyped state.
static void exact_linearization_reset_any(void *self)
{
    exact_linearization_reset(self);
}

// Returns nothing; binds s into the run loops' interface (stateless: the continuous loop may evaluate it).
void exact_linearization_controller(struct exact_linearization *s, struct controller *c)
{
    c->self = s;
    c->step = exact_linearization_step_any;
    c->reset = exact_linearization_reset_any;
    c->stateless = true;
}
