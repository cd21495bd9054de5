// The controllers and the plant built from fuzz input, and the wrapper checking every controller call.
#include "laws.h"
#include <float.h>
#include <stdio.h>
#include <stdlib.h>

// Returns true when motor.h's documented ranges hold: R, L, Km, J finite and > 0, B finite and >= 0, Nr >= 1.
static bool motor_ok(const struct motor_params *m)
{
    return fz_positive(m->R) && fz_positive(m->L) && fz_positive(m->Km) && fz_positive(m->J) && isfinite(m->B)
           && m->B >= 0 && m->Nr >= 1;
}

// Returns true when plan.h's documented ranges hold: finite, angles and currents within DBL_MAX / 4, rho1, rho2 > 0,
// tf > t0 with (tf - t0)^3 > 0.
static bool plan_ok(const struct plan *p)
{
    return fabs(p->theta1) <= DBL_MAX / 4 && fabs(p->theta2) <= DBL_MAX / 4 && p->rho1 <= DBL_MAX / 4
           && p->rho2 <= DBL_MAX / 4 && fz_positive(p->rho1) && fz_positive(p->rho2) && isfinite(p->t0)
           && isfinite(p->tf) && p->tf > p->t0 && pow(p->tf - p->t0, 3) > 0;
}

// Returns nothing; decodes a motor around the paper's (all fields when hostile, else the nominal).
void fz_motor(struct fz_reader *r, bool hostile, struct motor_params *m)
{
    const struct motor_params paper = {8.4, 0.010, 0.05, 3.6e-6, 1e-4, 50};
    *m = paper;
    if (hostile)
        fz_motor_fields(r, true, m);  // any Nr, or 0..127
}

// Returns nothing; decodes a plan around the nominal one (t0 .. tf) when hostile.
void fz_plan(struct fz_reader *r, bool hostile, double t0, double tf, struct plan *p)
{
    p->theta1 = 0, p->theta2 = 0.02, p->rho1 = 0.4, p->rho2 = 0.4, p->t0 = t0, p->tf = tf, p->traj = NULL;
    if (!hostile)
        return;
    p->theta1 = fz_value(r, p->theta1), p->theta2 = fz_value(r, p->theta2), p->rho1 = fz_value(r, p->rho1);
    p->rho2 = fz_value(r, p->rho2), p->t0 = fz_value(r, p->t0), p->tf = fz_value(r, p->tf);
}

// Returns nothing; decodes the plant's load and effects (each group hostile or off by its bit in mask):
// 1 load, 2 detent, 4 Coulomb friction, 8 iron loss, 16 a plant motor of its own.
void fz_plant(struct fz_reader *r, uint8_t mask, const struct motor_params *m, struct plant *p)
{
    struct plant_effects *e = &p->effects;
    p->motor = *m;
    if (mask & 16)
        fz_motor(r, true, &p->motor);
    p->load = mask & 1 ? fz_value(r, 5e-3) : 0;
    e->detent_torque = 0, e->detent_harmonic = 0, e->coulomb_torque = 0, e->coulomb_speed = 0;
    e->magnetizing_resistance = 0;
    if (mask & 2) {
        e->detent_torque = fz_value(r, 2e-3);
        e->detent_harmonic = fz_byte(r, 4) & 0x80 ? fz_u32(r, 4) : fz_byte(r, 4) % 9;
    }
    if (mask & 4)
        e->coulomb_torque = fz_value(r, 1e-3), e->coulomb_speed = fz_value(r, 1.0);
    if (mask & 8)
        e->magnetizing_resistance = fz_value(r, 100.0);
}

// Returns true when plant.h's documented ranges hold (motor, load and effects finite and in range).
bool fz_plant_ok(const struct plant *p)
{
    const struct plant_effects *e = &p->effects;
    return motor_ok(&p->motor) && isfinite(p->load) && isfinite(e->detent_torque) && e->detent_torque >= 0
           && (e->detent_torque == 0 || e->detent_harmonic >= 1) && isfinite(e->coulomb_torque)
           && e->coulomb_torque >= 0 && (e->coulomb_torque == 0 || fz_positive(e->coulomb_speed))
           && isfinite(e->magnetizing_resistance) && e->magnetizing_resistance >= 0;
}

// Returns true when plant_acceleration at x is plant.h's formula, eq. (1) with the load and the effects:
// (Km (ib cos Nr theta - ia sin Nr theta) - B omega - load - T_d sin(h Nr theta) - T_c tanh(omega / omega_s)
// - Km^2 / R_m omega) / J, up to rounding (not compared where a term is beyond 1e300 or not finite).
bool fz_acceleration_ok(const struct plant *p, const double x[4])
{
    const struct motor_params *m = &p->motor;
    const struct plant_effects *e = &p->effects;
    double a = m->Nr * x[3], terms[7], sum = 0, size = 0, acc = plant_acceleration(p, x);
    int k;
    terms[0] = m->Km * x[1] * cos(a), terms[1] = -m->Km * x[0] * sin(a), terms[2] = -m->B * x[2];
    terms[3] = -p->load;
    terms[4] = e->detent_torque > 0 ? -e->detent_torque * sin((double)e->detent_harmonic * a) : 0;
    terms[5] = e->coulomb_torque > 0 ? -e->coulomb_torque * tanh(x[2] / e->coulomb_speed) : 0;
    terms[6] = e->magnetizing_resistance > 0 ? -m->Km * m->Km / e->magnetizing_resistance * x[2] : 0;
    for (k = 0; k < 7; k++) {
        if (!(fabs(terms[k]) <= 1e300))
            return true;
        sum += terms[k], size += fabs(terms[k]);
    }
    if (!(fabs(a) <= 1e5) || !(fabs((double)e->detent_harmonic * a) <= 1e5) || !isfinite(sum / m->J)
        || !isfinite(size / m->J))
        return true;  // libm's and fs_sincos's reductions of a huge angle differ by more than rounding
    // rounding: of the sum, and of the angles (an ulp of Nr theta or h Nr theta moves sin by as much)
    size = 1e-12 * size
           + 8 * DBL_EPSILON
                 * ((fabs(terms[0]) + fabs(terms[1]) + fabs(m->Km * x[0]) + fabs(m->Km * x[1])) * fabs(a)
                    + e->detent_torque * fabs((double)e->detent_harmonic * a));
    // and of subnormal terms and products (each carries an absolute error up to the smallest subnormal,
    // DBL_MIN DBL_EPSILON; the core forms ib cos - ia sin before it multiplies by Km, which scales that error)
    size += 16 * DBL_MIN * DBL_EPSILON * (1 + m->Km + m->B + e->detent_torque + e->coulomb_torque);
    return fabs(acc - sum / m->J) <= size / m->J + 1e-300;
}

// Returns nothing; aborts unless the call kept controller.h's contract (and the law's own header's).
static void check_call(const struct fz_law *c, double t, const double *y, uint32_t st, const double *v)
{
    bool nonfinite = !isfinite(t), fault = (st & CTRL_FAULTS) != 0;
    double peak = fmax(fabs(v[0]), fabs(v[1]));
    int k;
    for (k = 0; k < CTRL_Y_LEN; k++)
        if (c->used_y & (1u << k))
            nonfinite |= !isfinite(y[k]);
    if (st & ~(uint32_t)(CTRL_FAULTS | CTRL_SATURATED))
        FZ_FAIL("law %d: undocumented status bits %u", c->kind, (unsigned)st);
    if (!isfinite(v[0]) || !isfinite(v[1]))
        FZ_FAIL("law %d: non-finite voltage %g %g (status %u)", c->kind, v[0], v[1], (unsigned)st);
    if (fault && (v[0] != 0 || v[1] != 0))
        FZ_FAIL("law %d: fault %u with v = %g %g, not 0 V", c->kind, (unsigned)st, v[0], v[1]);
    if (((st & CTRL_NONFINITE) != 0) != nonfinite)
        FZ_FAIL("law %d: CTRL_NONFINITE %u but non-finite input %d (t %g y %g %g %g %g %g)", c->kind, (unsigned)st,
                nonfinite, t, y[0], y[1], y[2], y[3], y[4]);
    if (c->kind == FZ_SMC) {
        if (st != SMC_OK && st != SMC_NONFINITE && st != SMC_RHO && st != SMC_SQRT && st != SMC_OVERFLOW
            && st != SMC_SATURATED)
            FZ_FAIL("smc: not exactly one documented status: %u", (unsigned)st);
        if (!(hypot(v[0], v[1]) <= c->v_limit * (1 + 4 * DBL_EPSILON)))
            FZ_FAIL("smc: |v| = %.17g beyond v_limit %.17g", hypot(v[0], v[1]), c->v_limit);
    } else if (!fault && ((st & CTRL_SATURATED) != 0) != (peak > c->v_limit)) {
        FZ_FAIL("law %d: CTRL_SATURATED %u but max|v| %.17g vs v_limit %.17g", c->kind, (unsigned)st, peak, c->v_limit);
    }
}

// Returns the law's status; the wrapper's step: calls the law, checks and records the call, sets the cancel flag.
static uint32_t outer_step(void *self, fs_real t, const fs_real *y, fs_real *v)
{
    struct fz_law *c = self;
    uint32_t st = c->inner.step(c->inner.self, t, y, v), st2;
    double v2[2];
    check_call(c, t, y, st, v);
    if (c->inner.stateless) {  // a stateless law gives the same bits for the same call
        st2 = c->inner.step(c->inner.self, t, y, v2);
        if (st2 != st || memcmp(v, v2, sizeof v2) != 0)
            FZ_FAIL("law %d: stateless, yet a repeated call differs", c->kind);
    }
    if (c->calls < FZ_RECORD) {
        c->t[c->calls] = t;
        memcpy(c->y[c->calls], y, sizeof c->y[0]);
        c->v[c->calls][0] = v[0], c->v[c->calls][1] = v[1];
        c->status[c->calls] = st;
    }
    c->status_or |= st;
    c->fault_calls += (st & CTRL_FAULTS) != 0;
    if (++c->calls == c->cancel_at && c->cancel)
        *c->cancel = 1;
    return st;
}

// Returns nothing; the wrapper's reset: the law's, and the record starts afresh.
static void outer_reset(void *self)
{
    struct fz_law *c = self;
    c->inner.reset(c->inner.self);
    c->calls = c->status_or = c->fault_calls = 0;
}

// What every law is built from: the loop's model, plan, control period and bus.
struct setup {
    const struct motor_params *model;
    const struct plan *plan;
    double Ts, v_limit;
};

// Returns smc_init's status; decodes the paper's law (options: 1 model measurement, 2 the detent hold,
// 4 any measurement mode). Aborts when smc.h's requirements are broken yet accepted, or met yet refused.
static int init_smc(struct fz_law *c, struct fz_reader *r, bool hostile, uint8_t options, const struct setup *u)
{
    struct smc_params p;
    struct smc_gains *g = &p.gains;
    bool ok;
    int rc;
    smc_params_default(&p);
    p.motor = *u->model, p.plan = *u->plan;
    p.measurement = options & 1 ? SMC_MODEL : SMC_IDEAL;
    g->hold_damping = options & 2 ? 0.7 : 0;
    p.v_limit = isfinite(u->v_limit) ? u->v_limit : 1e3;
    if (hostile) {
        g->W1 = fz_value(r, g->W1), g->W2 = fz_value(r, g->W2), g->eps1 = fz_value(r, g->eps1);
        g->eps2 = fz_value(r, g->eps2), g->xi = fz_value(r, g->xi), g->wn = fz_value(r, g->wn);
        g->hold_damping = fz_value(r, g->hold_damping), p.v_limit = fz_value(r, p.v_limit);
        p.rho_min = fz_value(r, p.rho_min);
        if (options & 4)
            p.measurement = (int)(signed char)fz_byte(r, 0);
    }
    ok = motor_ok(&p.motor) && plan_ok(&p.plan) && fz_positive(g->W1) && fz_positive(g->W2) && fz_positive(g->eps1)
         && fz_positive(g->eps2) && fz_positive(g->xi) && fz_positive(g->wn) && isfinite(g->hold_damping)
         && g->hold_damping >= 0 && (p.measurement == SMC_IDEAL || p.measurement == SMC_MODEL) && isfinite(p.v_limit)
         && p.v_limit >= 1e-3 && fz_positive(p.rho_min);
    rc = smc_init(&c->u.smc, &p);
    // refused although valid: allowed only for the hold's documented overflow (hold_damping > 0)
    if (ok != (rc == SMC_PARAMS_OK) && !(ok && g->hold_damping > 0 && rc == SMC_EGAINS))
        FZ_FAIL("smc_init returned %d on %s parameters", rc, ok ? "valid" : "invalid");
    smc_controller(&c->u.smc, &c->inner);
    c->v_limit = p.v_limit;
    c->used_y = p.measurement == SMC_IDEAL ? 31 : 15;
    return rc;
}

// Returns microstep_init's status; decodes the driver (options: 1 no feedforward, 2 the back EMF, 4 the load angle). Aborts when a documented
// requirement is broken yet accepted.
static int init_microstep(struct fz_law *c, struct fz_reader *r, bool hostile, uint8_t options, const struct setup *u)
{
    struct microstep_params p;
    bool ok;
    int rc;
    p.motor = *u->model, p.plan = *u->plan, p.Ts = u->Ts, p.v_limit = u->v_limit;
    p.gains.current_bandwidth = 0.3 / u->Ts, p.gains.feedforward = !(options & 1);
    p.gains.back_emf = (options & 2) != 0;
    p.gains.load_angle = (options & 4) != 0;
    if (hostile) {
        p.gains.current_bandwidth = fz_value(r, p.gains.current_bandwidth), p.Ts = fz_value(r, p.Ts);
        p.v_limit = fz_value(r, p.v_limit);
    }
    ok = motor_ok(&p.motor) && plan_ok(&p.plan) && fz_positive(p.gains.current_bandwidth) && fz_positive(p.Ts)
         && p.v_limit > 0;
    rc = microstep_init(&c->u.ms, &p);
    if (!ok && rc == MICROSTEP_PARAMS_OK)
        FZ_FAIL("microstep_init accepted invalid parameters");
    microstep_controller(&c->u.ms, &c->inner);
    c->v_limit = p.v_limit;
    c->used_y = 3;
    return rc;
}

// Returns cascade_init's status; decodes the cascade (options: 1 no decoupling, 2 the voltage feedforward, 4 the plan's frame). Aborts when a documented
// requirement is broken yet accepted.
static int init_cascade(struct fz_law *c, struct fz_reader *r, bool hostile, uint8_t options, const struct setup *u)
{
    struct cascade_params p;
    bool ok;
    int rc;
    p.motor = *u->model, p.plan = *u->plan, p.Ts = u->Ts, p.v_limit = u->v_limit;
    p.gains.current_bandwidth = 0.3 / u->Ts, p.gains.decoupling = !(options & 1);
    p.gains.k_theta = 200.0 / 3, p.gains.k_omega = 450, p.gains.ki_omega = 30000;
    p.gains.voltage_feedforward = (options & 2) != 0, p.gains.plan_frame = (options & 4) != 0, p.gains.d_hold = 1;
    p.torques = (struct torque_model){0};
    if (hostile) {
        p.gains.current_bandwidth = fz_value(r, p.gains.current_bandwidth);
        p.gains.k_theta = fz_value(r, p.gains.k_theta), p.gains.k_omega = fz_value(r, p.gains.k_omega);
        p.gains.ki_omega = fz_value(r, p.gains.ki_omega), p.Ts = fz_value(r, p.Ts);
        p.v_limit = fz_value(r, p.v_limit);
    }
    ok = motor_ok(&p.motor) && plan_ok(&p.plan) && fz_positive(p.gains.current_bandwidth)
         && fz_positive(p.gains.k_theta) && fz_positive(p.gains.k_omega) && isfinite(p.gains.ki_omega)
         && p.gains.ki_omega >= 0 && fz_positive(p.Ts) && p.v_limit > 0;
    rc = cascade_init(&c->u.cas, &p);
    if (!ok && rc == CASCADE_PARAMS_OK)
        FZ_FAIL("cascade_init accepted invalid parameters");
    cascade_controller(&c->u.cas, &c->inner);
    c->v_limit = p.v_limit;
    c->used_y = 15;
    return rc;
}

// Returns exact_linearization_init's status; decodes the law (options: 1 model acceleration, 4 any mode).
// Aborts when a documented requirement is broken yet accepted.
static int init_exact(struct fz_law *c, struct fz_reader *r, bool hostile, uint8_t options, const struct setup *u)
{
    struct exact_linearization_params p;
    struct exact_linearization_gains *g = &p.gains;
    bool ok;
    int rc;
    p.motor = *u->model, p.plan = *u->plan, p.v_limit = u->v_limit;
    p.measurement = options & 1 ? EXACT_LINEARIZATION_MODEL : EXACT_LINEARIZATION_MEASURED;
    p.torques = (struct torque_model){0};
    g->wn = 200, g->xi = 0.8, g->p3 = 0.3 / u->Ts, g->pd = 0.3 / u->Ts;
    if (hostile) {
        g->wn = fz_value(r, g->wn), g->xi = fz_value(r, g->xi), g->p3 = fz_value(r, g->p3);
        g->pd = fz_value(r, g->pd), p.v_limit = fz_value(r, p.v_limit);
        if (options & 4)
            p.measurement = (int)(signed char)fz_byte(r, 0);
    }
    ok = motor_ok(&p.motor) && plan_ok(&p.plan) && fz_positive(g->wn) && fz_positive(g->xi) && fz_positive(g->p3)
         && fz_positive(g->pd) && p.v_limit > 0
         && (p.measurement == EXACT_LINEARIZATION_MEASURED || p.measurement == EXACT_LINEARIZATION_MODEL);
    rc = exact_linearization_init(&c->u.el, &p);
    if (!ok && rc == EXACT_LINEARIZATION_PARAMS_OK)
        FZ_FAIL("exact_linearization_init accepted invalid parameters");
    exact_linearization_controller(&c->u.el, &c->inner);
    c->v_limit = p.v_limit;
    c->used_y = p.measurement == EXACT_LINEARIZATION_MEASURED ? 31 : 15;
    return rc;
}

// Returns the law's init status (0: accepted); decodes its gains and limits and binds the wrapper (laws.h).
int fz_law_init(struct fz_law *c, int kind, struct fz_reader *r, bool hostile, uint8_t options,
                const struct motor_params *model, const struct plan *plan, double Ts, double v_limit)
{
    const struct setup u = {model, plan, Ts, v_limit};
    int rc;
    c->kind = kind;
    c->calls = c->status_or = c->fault_calls = c->cancel_at = 0;
    c->cancel = NULL;
    if (kind == FZ_SMC)
        rc = init_smc(c, r, hostile, options, &u);
    else if (kind == FZ_MICROSTEP)
        rc = init_microstep(c, r, hostile, options, &u);
    else if (kind == FZ_CASCADE)
        rc = init_cascade(c, r, hostile, options, &u);
    else
        rc = init_exact(c, r, hostile, options, &u);
    c->outer.self = c;
    c->outer.step = outer_step;
    c->outer.reset = outer_reset;
    c->outer.stateless = c->inner.stateless;
    return rc;
}
