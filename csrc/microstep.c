// microstep_init / microstep_reset / microstep_step: the law of flatstep.control.microstep, in its operation order.
#include "microstep.h"
#include <stddef.h>

// Returns true when x is finite and > 0.
static bool positive(fs_real x)
{
    return fs_isfinite(x) && x > 0;
}

// Returns nothing; writes i* = rho* (cos Nr theta*, sin Nr theta*) at t and, when di is not NULL, its derivative.
static void microstep_reference(const struct microstep *s, fs_real t, fs_real i[2], fs_real *di)
{
    // With the load angle the vector leads N_r theta* by delta, sin delta = c = (J theta*'' + B theta*') / (Km rho*)
    // clipped to [-1, 1]; delta' = c' / cos delta inside (0 where clipped).
    const struct motor_params *m = &s->p.motor;
    fs_real ref[PLAN_FLAG_LEN], sn, cs, w, dp, c, cd, sp, cp, den;
    plan_flag(&s->plan, t, ref);
    fs_sincos(m->Nr * ref[PLAN_THETA], &sn, &cs);
    dp = m->Nr * ref[PLAN_DTHETA];
    den = m->Km * ref[PLAN_RHO];
    c = den > 0 ? (m->J * ref[PLAN_DDTHETA] + m->B * ref[PLAN_DTHETA]) / den : 0;
    if (s->p.gains.load_angle && den > 0 && c == c) {  // no lead for a zero current vector (or a NaN demand)
        c = c > 1 ? 1 : c < -1 ? -1 : c;
        cd = fs_sqrt(1 - c * c);
        if (cd > 0)
            dp = dp + ((m->J * ref[PLAN_DDDTHETA] + m->B * ref[PLAN_DDTHETA]) - c * m->Km * ref[PLAN_DRHO]) / den / cd;
        sp = sn * cd + cs * c;
        cp = cs * cd - sn * c;
        sn = sp;
        cs = cp;
    }
    i[0] = ref[PLAN_RHO] * cs;
    i[1] = ref[PLAN_RHO] * sn;
    if (di) {
        w = dp * ref[PLAN_RHO];
        di[0] = ref[PLAN_DRHO] * cs - w * sn;
        di[1] = ref[PLAN_DRHO] * sn + w * cs;
    }
}

// Returns MICROSTEP_PARAMS_OK, or the microstep_param_error naming the invalid group (s is then unusable).
int microstep_init(struct microstep *s, const struct microstep_params *p)
{
    fs_real wc = p->gains.current_bandwidth;
    if (!motor_params_valid(&p->motor))
        return MICROSTEP_EMOTOR;
    if (!plan_valid(&p->plan))
        return MICROSTEP_EPLAN;
    if (!positive(wc) || !fs_isfinite(p->motor.L * wc) || !fs_isfinite(p->motor.R * wc))
        return MICROSTEP_EGAINS;
    if (!positive(p->Ts) || !fs_isfinite(p->motor.R * wc * p->Ts))
        return MICROSTEP_EPERIOD;
    if (!(p->v_limit > 0))
        return MICROSTEP_ELIMITS;
    s->p = *p;
    plan_init(&s->plan, &p->plan);
    s->kp = p->motor.L * wc;
    s->ki_Ts = p->motor.R * wc * p->Ts;
    microstep_reset(s);
    if (!(fs_isfinite(s->integral[0]) && fs_isfinite(s->integral[1])))
        return MICROSTEP_EPLAN;
    return MICROSTEP_PARAMS_OK;
}

// Returns nothing; sets the integrals to 0 with the feedforward, else to R i*(t0 - 1).
void microstep_reset(struct microstep *s)
{
    fs_real i[2];
    if (s->p.gains.feedforward) {
        s->integral[0] = s->integral[1] = 0;
        return;
    }
    microstep_reference(s, s->p.plan.t0 - 1, i, NULL);
    s->integral[0] = s->p.motor.R * i[0];
    s->integral[1] = s->p.motor.R * i[1];
}

// Returns nothing; writes the back EMF at the plan's angle and speed, Km theta*' (-sin Nr theta*, cos Nr theta*).
static void microstep_back_emf(struct microstep *s, fs_real t, fs_real emf[2])
{
    fs_real f[PLAN_FLAG_LEN], sn, cs;
    const struct motor_params *m = &s->p.motor;
    plan_flag(&s->plan, t, f);
    fs_sincos(m->Nr * f[PLAN_THETA], &sn, &cs);
    emf[0] = -m->Km * f[PLAN_DTHETA] * sn;
    emf[1] = m->Km * f[PLAN_DTHETA] * cs;
}

// Returns ctrl_status bits; writes the command v and advances the integrals (microstep.h).
uint32_t microstep_step(struct microstep *s, fs_real t, const fs_real *y, fs_real *v)
{
    // v = kp (i* - i) + I [+ R i* + L di*/dt] [+ Km theta*' (-sin, cos)(Nr theta*)];
    // I += ki Ts (i* - i) unless max|v| > v_limit (anti-windup).
    const struct motor_params *m = &s->p.motor;
    fs_real i[2], di[2], emf[2] = {0, 0}, e[2], out[2], next[2], z;
    bool hold;
    int k;
    v[0] = v[1] = 0;
    // x - x is 0 for a finite x and NaN otherwise: one test covers every input and the state.
    z = (t - t) + (y[0] - y[0]) + (y[1] - y[1]) + (s->integral[0] - s->integral[0]) + (s->integral[1] - s->integral[1]);
    if (z != 0)
        return CTRL_NONFINITE;
    microstep_reference(s, t, i, di);
    if (s->p.gains.back_emf)
        microstep_back_emf(s, t, emf);
    for (k = 0; k < 2; k++) {
        e[k] = i[k] - y[k];
        out[k] = s->kp * e[k] + s->integral[k];
        if (s->p.gains.feedforward)
            out[k] = out[k] + m->R * i[k] + m->L * di[k];
        out[k] = out[k] + emf[k];
    }
    hold = fs_fabs(out[0]) > s->p.v_limit || fs_fabs(out[1]) > s->p.v_limit;
    for (k = 0; k < 2; k++)
        next[k] = hold ? s->integral[k] : s->integral[k] + s->ki_Ts * e[k];
    if (!(fs_isfinite(out[0]) && fs_isfinite(out[1]) && fs_isfinite(next[0]) && fs_isfinite(next[1])))
        return CTRL_OVERFLOW;
    v[0] = out[0];
    v[1] = out[1];
    s->integral[0] = next[0];
    s->integral[1] = next[1];
    return hold ? CTRL_SATURATED : CTRL_OK;
}

// Returns microstep_step's status for the interface's untyped state.
static uint32_t microstep_step_any(void *self, fs_real t, const fs_real *y, fs_real *v)
{
    return microstep_step(self, t, y, v);
}

// Returns nothing; microstep_reset for the interface's untyped state.
static void microstep_reset_any(void *self)
{
    microstep_reset(self);
}

// Returns nothing; binds s into the run loops' interface (not stateless: the integrals advance each step).
void microstep_controller(struct microstep *s, struct controller *c)
{
    c->self = s;
    c->step = microstep_step_any;
    c->reset = microstep_reset_any;
    c->stateless = false;
}
