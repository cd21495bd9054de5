// cascade_init / cascade_reset / cascade_step: the law of flatstep.control.cascade, in its operation order.
#include "cascade.h"

// Returns true when x is finite and > 0.
static bool positive(fs_real x)
{
    return fs_isfinite(x) && x > 0;
}

// Returns CASCADE_PARAMS_OK, or the cascade_param_error naming the invalid group (s is then unusable).
int cascade_init(struct cascade *s, const struct cascade_params *p)
{
    const struct motor_params *m = &p->motor;
    const struct cascade_gains *g = &p->gains;
    fs_real wc = g->current_bandwidth;
    if (!motor_params_valid(m))
        return CASCADE_EMOTOR;
    if (!plan_valid(&p->plan))
        return CASCADE_EPLAN;
    if (!positive(wc) || !positive(g->k_theta) || !positive(g->k_omega)
        || !(fs_isfinite(g->ki_omega) && g->ki_omega >= 0) || !(fs_isfinite(g->d_hold) && g->d_hold >= 0))
        return CASCADE_EGAINS;
    s->p = *p;
    s->kp = m->L * wc;
    s->L_Nr = m->L * m->Nr;
    if (!(fs_isfinite(s->kp) && fs_isfinite(m->R * wc) && fs_isfinite(s->L_Nr)))
        return CASCADE_EGAINS;
    if (!positive(p->Ts))
        return CASCADE_EPERIOD;
    s->ki_omega_Ts = g->ki_omega * p->Ts;
    s->ki_Ts = m->R * wc * p->Ts;
    if (!(fs_isfinite(s->ki_omega_Ts) && fs_isfinite(s->ki_Ts)))
        return CASCADE_EPERIOD;
    if (!(p->v_limit > 0))
        return CASCADE_ELIMITS;
    if (!torque_model_valid(&p->torques))
        return CASCADE_ETORQUES;
    plan_init(&s->plan, &p->plan);
    cascade_reset(s);
    return CASCADE_PARAMS_OK;
}

// Returns nothing; sets the three integrals to 0.
void cascade_reset(struct cascade *s)
{
    s->integral[0] = s->integral[1] = s->integral[2] = 0;
}

// Returns R iq_ff + L iq_ff', the voltage of the q current the plan needs: iq_ff = (J theta*'' + B theta*' + E*) / Km
// and its rate, with the known torques along the plan (flatstep.control.feedforward.reference in d-q).
static fs_real cascade_reference_voltage(const struct cascade *s, fs_real t, const fs_real *ref)
{
    const struct motor_params *m = &s->p.motor;
    fs_real E = torque_model_torque(&s->p.torques, m->Nr, t, ref[PLAN_THETA], ref[PLAN_DTHETA]);
    fs_real dE = torque_model_rate(&s->p.torques, m->Nr, t, ref[PLAN_THETA], ref[PLAN_DTHETA], ref[PLAN_DDTHETA]);
    fs_real iq_ff = (m->J * ref[PLAN_DDTHETA] + m->B * ref[PLAN_DTHETA] + E) / m->Km;
    fs_real diq_ff = (m->J * ref[PLAN_DDDTHETA] + m->B * ref[PLAN_DDTHETA] + dE) / m->Km;
    return m->R * iq_ff + m->L * diq_ff;
}

// Returns ctrl_status bits; writes the command v and advances the integrals (cascade.h).
uint32_t cascade_step(struct cascade *s, fs_real t, const fs_real *y, fs_real *v)
{
    // e_w = theta*' + k_theta (theta* - theta) - omega; iq* = (J theta*'' + B theta*' + J (k_omega e_w + I0) + E) / Km;
    // v_dq = kp (i_dq* - i_dq) + I12 [+ decoupling] [+ (0, R iq_ff + L iq_ff')]; v = inverse Park;
    // I += ki Ts e unless max|v| > v_limit. With plan_frame: the frame at Nr theta* (not Nr theta), id* = d_hold rho*,
    // the decoupling at Nr theta*' and the back EMF Km omega (-sin Nr(theta - theta*), cos Nr(theta - theta*)),
    // the voltage feedforward (R id* + L id*', R iq_ff + L iq_ff').
    const struct motor_params *m = &s->p.motor;
    const fs_real *I = s->integral;
    const struct cascade_gains *g = &s->p.gains;
    fs_real ref[PLAN_FLAG_LEN], e_w, accel, iq_ref, id_ref = 0, sn, cs, id, iq, e_d, e_q, vd, vq, out[2], next[3], z;
    fs_real w_frame = y[2], sd = 0, cd = 1;
    bool hold;
    v[0] = v[1] = 0;
    // x - x is 0 for a finite x and NaN otherwise: one test covers every input used and the state.
    z = (t - t) + (y[0] - y[0]) + (y[1] - y[1]) + (y[2] - y[2]) + (y[3] - y[3]) + (I[0] - I[0]) + (I[1] - I[1])
        + (I[2] - I[2]);
    if (z != 0)
        return CTRL_NONFINITE;
    plan_flag(&s->plan, t, ref);
    e_w = ref[PLAN_DTHETA] + g->k_theta * (ref[PLAN_THETA] - y[3]) - y[2];
    accel = g->k_omega * e_w + I[0];
    iq_ref = (m->J * ref[PLAN_DDTHETA] + m->B * ref[PLAN_DTHETA] + m->J * accel
              + torque_model_torque(&s->p.torques, m->Nr, t, y[3], y[2]))
             / m->Km;
    // Park transform by Nr theta (Nr theta* in the plan's frame): id = ia c + ib s, iq = -ia s + ib c.
    fs_sincos(m->Nr * (g->plan_frame ? ref[PLAN_THETA] : y[3]), &sn, &cs);
    if (g->plan_frame) {
        id_ref = g->d_hold * ref[PLAN_RHO];
        w_frame = ref[PLAN_DTHETA];
        fs_sincos(m->Nr * (y[3] - ref[PLAN_THETA]), &sd, &cd);
    }
    id = y[0] * cs + y[1] * sn;
    iq = -y[0] * sn + y[1] * cs;
    e_d = id_ref - id;
    e_q = iq_ref - iq;
    vd = s->kp * e_d + I[1];
    vq = s->kp * e_q + I[2];
    if (g->decoupling) {
        vd = vd + (-s->L_Nr * w_frame * iq - m->Km * y[2] * sd);
        vq = vq + (s->L_Nr * w_frame * id + m->Km * y[2] * cd);
    }
    if (g->voltage_feedforward) {
        vq = vq + cascade_reference_voltage(s, t, ref);
        if (g->plan_frame)
            vd = vd + g->d_hold * (m->R * ref[PLAN_RHO] + m->L * ref[PLAN_DRHO]);
    }
    out[0] = vd * cs - vq * sn;
    out[1] = vd * sn + vq * cs;
    hold = fs_fabs(out[0]) > s->p.v_limit || fs_fabs(out[1]) > s->p.v_limit;
    next[0] = hold ? I[0] : I[0] + s->ki_omega_Ts * e_w;
    next[1] = hold ? I[1] : I[1] + s->ki_Ts * e_d;
    next[2] = hold ? I[2] : I[2] + s->ki_Ts * e_q;
    if (!(fs_isfinite(out[0]) && fs_isfinite(out[1]) && fs_isfinite(next[0]) && fs_isfinite(next[1])
          && fs_isfinite(next[2])))
        return CTRL_OVERFLOW;
    v[0] = out[0];
    v[1] = out[1];
    s->integral[0] = next[0];
    s->integral[1] = next[1];
    s->integral[2] = next[2];
    return hold ? CTRL_SATURATED : CTRL_OK;
}

// Returns cascade_step's status for the interface's untyped state.
static uint32_t cascade_step_any(void *self, fs_real t, const fs_real *y, fs_real *v)
{
    return cascade_step(self, t, y, v);
}

// Returns nothing; cascade_reset for the interface's untyped state.
static void cascade_reset_any(void *self)
{
    cascade_reset(self);
}

// Returns nothing; binds s into the run loops' interface (not stateless: the integrals advance each step).
void cascade_controller(struct cascade *s, struct controller *c)
{
    c->self = s;
    c->step = cascade_step_any;
    c->reset = cascade_reset_any;
    c->stateless = false;
}
