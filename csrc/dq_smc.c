// dq_smc_init / dq_smc_reset / dq_smc_step: the law of flatstep.control.dq_smc, in its operation order.
#include "dq_smc.h"

// Returns true when x is finite and > 0.
static bool positive(fs_real x)
{
    return fs_isfinite(x) && x > 0;
}

// Returns nothing; fills p with the paper's motor, move and gains, i_d* = 0, no torque model, ideal measurement
// and v_limit = 1e3 V.
void dq_smc_params_default(struct dq_smc_params *p)
{
    struct smc_params sp;
    struct dq_smc_current none = {0};  // i_d* = 0, no table
    struct torque_model tm = {0, 4, 0, 0, FS_C(0.01), 0, 0, 0, 1};
    smc_params_default(&sp);
    p->motor = sp.motor;
    p->plan = sp.plan;
    none.tf = 1;
    p->current = none;
    p->gains = sp.gains;
    p->torques = tm;
    p->measurement = SMC_IDEAL;
    p->v_limit = FS_C(1e3);
    p->integral.ki = 0;
    p->integral.Ts = 0;
    p->integral.v_hold = 0;
    p->adapt.rate = 0;
    p->adapt.phi0 = 0;
    p->adapt.range = 0;
    p->adapt.Ts = 0;
    p->adapt.v_hold = 0;
    p->advance = 0;
}

// Returns true when the d-current table is absent or has 2..DQ_SMC_ID_KNOTS finite knots at rising times.
static bool current_table_valid(const struct dq_smc_current *c)
{
    uint32_t i;
    if (c->n_knots == 0)
        return true;
    if (c->n_knots < 2 || c->n_knots > DQ_SMC_ID_KNOTS)
        return false;
    for (i = 0; i < c->n_knots; i++)
        if (!(fs_isfinite(c->knot_t[i]) && fs_isfinite(c->knot_id[i]) && fs_isfinite(c->knot_did[i])
              && (i == 0 || c->knot_t[i] > c->knot_t[i - 1])))
            return false;
    return true;
}

// Returns DQ_SMC_PARAMS_OK, or the dq_smc_param_error naming the invalid group (s is then left unusable).
int dq_smc_init(struct dq_smc *s, const struct dq_smc_params *p)
{
    const struct smc_gains *g = &p->gains;
    const struct dq_smc_current *c = &p->current;
    if (!motor_params_valid(&p->motor))
        return DQ_SMC_EMOTOR;
    if (!plan_valid(&p->plan)
        || !(fs_isfinite(c->i_d1) && fs_isfinite(c->i_d2) && fs_isfinite(c->t0) && fs_isfinite(c->tf)
             && (c->i_d2 == c->i_d1 || c->tf > c->t0) && fs_isfinite(c->weakening) && c->weakening >= 0
             && fs_isfinite(c->weakening_speed) && c->weakening_speed >= 0 && current_table_valid(c)))
        return DQ_SMC_EPLAN;
    if (!(positive(g->W1) && positive(g->W2) && positive(g->eps1) && positive(g->eps2) && positive(g->xi)
          && positive(g->wn) && g->hold_damping == 0))
        return DQ_SMC_EGAINS;
    if (p->measurement != SMC_IDEAL && p->measurement != SMC_MODEL)
        return DQ_SMC_EMEASUREMENT;
    if (!(fs_isfinite(p->v_limit) && p->v_limit >= FS_C(1e-3)))
        return DQ_SMC_ELIMITS;
    if (!torque_model_valid(&p->torques))
        return DQ_SMC_ETORQUES;
    if (!(fs_isfinite(p->integral.ki) && p->integral.ki >= 0
          && (p->integral.ki == 0 || (positive(p->integral.Ts) && positive(p->integral.v_hold)))))
        return DQ_SMC_EINTEGRAL;
    if (!(fs_isfinite(p->adapt.rate) && p->adapt.rate >= 0
          && (p->adapt.rate == 0
              || (positive(p->adapt.Ts) && positive(p->adapt.v_hold) && positive(p->adapt.phi0)
                  && p->adapt.phi0 * p->adapt.phi0 > 0  // phi0^2 + phi^2 is never 0 (dq_smc_adapt divides by it)
                  && positive(p->adapt.range) && p->adapt.range < 1))))
        return DQ_SMC_EADAPT;
    if (!(fs_isfinite(p->advance) && p->advance >= 0))
        return DQ_SMC_EADVANCE;
    s->p = *p;
    plan_init(&s->plan, &p->plan);
    s->alpha1 = fs_pow(g->wn, 2);
    s->alpha2 = 2 * g->xi * g->wn;
    if (!(fs_isfinite(s->alpha1) && fs_isfinite(s->alpha2)))
        return DQ_SMC_EGAINS;
    dq_smc_reset(s);
    return DQ_SMC_PARAMS_OK;
}

// Returns nothing; clears the accumulated status and the integral, and sets Km^ = motor.Km.
void dq_smc_reset(struct dq_smc *s)
{
    s->status_seen = CTRL_OK;
    s->z = 0;
    s->km = s->p.motor.Km;
}

// Returns the regressor phi along the plan: the q-current rate the planned move demands less its back EMF's [A/s].
static fs_real dq_smc_regressor(const struct dq_smc *s, fs_real t, const fs_real ref[PLAN_FLAG_LEN])
{
    const struct motor_params *m = &s->p.motor;
    fs_real dE = torque_model_rate(&s->p.torques, m->Nr, t, ref[PLAN_THETA], ref[PLAN_DTHETA], ref[PLAN_DDTHETA]);
    return (m->J * ref[PLAN_DDDTHETA] + m->B * ref[PLAN_DDTHETA] + dE) / s->km - s->km * ref[PLAN_DTHETA] / m->L;
}

// Returns nothing; advances Km^ by one period of its gradient law along the regressor phi, projected into range.
static void dq_smc_adapt(struct dq_smc *s, fs_real s2, fs_real phi)
{
    const struct dq_smc_adaptation *a = &s->p.adapt;
    fs_real lo = s->p.motor.Km * (1 - a->range), hi = s->p.motor.Km * (1 + a->range);
    fs_real gain = a->Ts * a->rate * s->p.motor.J * s->p.gains.W2 / s->p.gains.eps2;
    fs_real km = s->km + gain * s2 * phi / (a->phi0 * a->phi0 + phi * phi);
    s->km = km < lo ? lo : (km > hi ? hi : km);
}

// Returns nothing; writes the planned d current and its rate at time t, for the planned speed w and acceleration a.
static void dq_smc_current_ref(const struct dq_smc_current *c, fs_real t, fs_real w, fs_real a, fs_real *i_d,
                               fs_real *di_d)
{
    fs_real span = c->i_d2 - c->i_d1, h, u, p0, p1, m0, m1;
    uint32_t lo = 0, hi, mid;
    if (c->n_knots >= 2) {  // the cubic Hermite table, held outside its knots
        hi = c->n_knots - 1;
        if (t <= c->knot_t[0] || t >= c->knot_t[hi]) {
            *i_d = t <= c->knot_t[0] ? c->knot_id[0] : c->knot_id[hi];
            *di_d = 0;
        } else {
            while (hi - lo > 1) {
                mid = (lo + hi) / 2;
                if (c->knot_t[mid] <= t)
                    lo = mid;
                else
                    hi = mid;
            }
            h = c->knot_t[hi] - c->knot_t[lo];
            u = (t - c->knot_t[lo]) / h;
            p0 = c->knot_id[lo], p1 = c->knot_id[hi], m0 = c->knot_did[lo] * h, m1 = c->knot_did[hi] * h;
            *i_d = ((2 * u - 3) * u * u + 1) * p0 + ((u - 2) * u + 1) * u * m0 + (3 - 2 * u) * u * u * p1
                   + (u - 1) * u * u * m1;
            *di_d = (6 * (u - 1) * u * (p0 - p1) + ((3 * u - 4) * u + 1) * m0 + (3 * u - 2) * u * m1) / h;
        }
    } else if (span == 0) {
        *i_d = c->i_d1;
        *di_d = 0;
    } else {
        *i_d = c->i_d1 + plan_psi(t, c->t0, c->tf, 0) * span;
        *di_d = plan_psi(t, c->t0, c->tf, 1) * span;
    }
    if (c->weakening != 0 && fs_fabs(w) > c->weakening_speed) {
        *i_d = *i_d - c->weakening * (fs_fabs(w) - c->weakening_speed);
        *di_d = *di_d - c->weakening * (w > 0 ? a : -a);
    }
}

// Returns ctrl_status bits; writes the law's voltages (dq_smc.h) and scales them into v_limit.
uint32_t dq_smc_step(struct dq_smc *s, fs_real t, const fs_real y[5], fs_real v[2])
{
    // Law: s1 = i_d - i_d*, s2 = e'' + a2 e' + a1 e; i_d' -> Gamma1, theta''' -> Gamma2 in the d-q model's inverse.
    const struct motor_params *m = &s->p.motor;
    const struct smc_gains *g = &s->p.gains;
    fs_real ref[PLAN_FLAG_LEN], sn, cs, i_d, i_q, E, acc, e, de, dde, s1, s2, gamma1, gamma2, dE, v_d, v_q, id_ref,
        did_ref, norm, vn, z, ki = s->p.integral.ki, km = s->km;
    uint32_t status = CTRL_OK;
    v[0] = v[1] = 0;
    // x - x is 0 for a finite x and NaN otherwise: one test covers every input used.
    z = (t - t) + (y[0] - y[0]) + (y[1] - y[1]) + (y[2] - y[2]) + (y[3] - y[3]);
    if (s->p.measurement == SMC_IDEAL)
        z += y[4] - y[4];
    if (z != 0) {
        s->status_seen |= CTRL_NONFINITE;
        return CTRL_NONFINITE;
    }
    plan_flag(&s->plan, t, ref);
    dq_smc_current_ref(&s->p.current, t, ref[PLAN_DTHETA], ref[PLAN_DDTHETA], &id_ref, &did_ref);
    // Park transform by Nr theta: i_d = ia c + ib s, i_q = -ia s + ib c.
    fs_sincos(m->Nr * y[3], &sn, &cs);
    i_d = y[0] * cs + y[1] * sn;
    i_q = -y[0] * sn + y[1] * cs;
    if (s->p.measurement == SMC_IDEAL) {
        acc = y[4];
    } else {
        E = torque_model_torque(&s->p.torques, m->Nr, t, y[3], y[2]);
        acc = (km * i_q - m->B * y[2] - E) / m->J;
    }
    e = y[3] - ref[PLAN_THETA];
    de = y[2] - ref[PLAN_DTHETA];
    dde = acc - ref[PLAN_DDTHETA];
    s1 = i_d - id_ref;
    s2 = dde + s->alpha2 * de + s->alpha1 * e;
    gamma1 = did_ref - g->W1 * s1 / (fs_fabs(s1) + g->eps1);
    gamma2 = ref[PLAN_DDDTHETA] - s->alpha2 * dde - s->alpha1 * de - g->W2 * s2 / (fs_fabs(s2) + g->eps2);
    if (ki != 0)
        gamma2 -= ki * s->z;
    dE = torque_model_rate(&s->p.torques, m->Nr, t, y[3], y[2], acc);
    v_d = m->L * gamma1 + m->R * i_d - m->L * m->Nr * y[2] * i_q;
    v_q = m->L * ((m->J * gamma2 + m->B * acc + dE) / km) + m->R * i_q + m->L * m->Nr * y[2] * i_d + km * y[2];
    if (s->p.advance != 0)  // the angle the rotor reaches over the held voltage's mean delay
        fs_sincos(m->Nr * (y[3] + y[2] * s->p.advance), &sn, &cs);
    v[0] = v_d * cs - v_q * sn;
    v[1] = v_d * sn + v_q * cs;
    if (!(fs_isfinite(v[0]) && fs_isfinite(v[1]))) {
        v[0] = v[1] = 0;
        s->status_seen |= CTRL_OVERFLOW;
        return CTRL_OVERFLOW;
    }
    vn = fs_hypot(v[0], v[1]);
    // Anti-windup: z advances only inside the boundary layer and below the bus.
    if (ki != 0 && fs_fabs(s2) <= g->eps2 && vn <= s->p.integral.v_hold)
        s->z += s->p.integral.Ts * s2;
    if (s->p.adapt.rate != 0 && fs_fabs(s2) <= g->eps2 && vn <= s->p.adapt.v_hold)
        dq_smc_adapt(s, s2, dq_smc_regressor(s, t, ref));
    if (vn > s->p.v_limit) {
        // Scale by the larger component first so that hypot cannot overflow.
        norm = fs_fabs(v[0]) > fs_fabs(v[1]) ? fs_fabs(v[0]) : fs_fabs(v[1]);
        v[0] /= norm;
        v[1] /= norm;
        norm = fs_hypot(v[0], v[1]);
        v[0] *= s->p.v_limit / norm;
        v[1] *= s->p.v_limit / norm;
        status = CTRL_SATURATED;
    }
    s->status_seen |= status;
    return status;
}

// Returns dq_smc_step's status for the interface's untyped state.
static uint32_t dq_smc_step_any(void *self, fs_real t, const fs_real *y, fs_real *v)
{
    return dq_smc_step(self, t, y, v);
}

// Returns nothing; dq_smc_reset for the interface's untyped state.
static void dq_smc_reset_any(void *self)
{
    dq_smc_reset(self);
}

// Returns nothing; binds s into the run loops' interface (stateless without integral action or adaptation: the
// continuous loop may run it).
void dq_smc_controller(struct dq_smc *s, struct controller *c)
{
    c->self = s;
    c->step = dq_smc_step_any;
    c->reset = dq_smc_reset_any;
    c->stateless = s->p.integral.ki == 0 && s->p.adapt.rate == 0;
}
