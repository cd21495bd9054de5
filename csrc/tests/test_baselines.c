// The baseline controllers (microstep, cascade, exact linearization): parameters, guards, anti-windup, closed loop.
#include <string.h>
#include "cascade.h"
#include "check.h"
#include "exact_linearization.h"
#include "microstep.h"
#include "motor.h"
#include "ode.h"

#define TS 1e-4  // control period of the sampled tests [s]; the current bandwidth is 0.3 / TS

static const struct motor_params MOTOR = {8.4, 0.010, 0.05, 3.6e-6, 1e-4, 50};  // the paper's
static const struct plan PLAN = {0, 0.02, 0.4, 0.4, 0.02, 0.04, NULL};          // the paper's move

// Returns nothing; fills p with the paper's motor and move, wc = 0.3 / TS, feedforward, no voltage limit.
static void microstep_defaults(struct microstep_params *p)
{
    p->motor = MOTOR;
    p->plan = PLAN;
    p->gains.current_bandwidth = 0.3 / TS;
    p->gains.feedforward = true;
    p->gains.back_emf = false;
    p->gains.load_angle = false;
    p->Ts = TS;
    p->v_limit = INFINITY;
}

// Returns nothing; fills p with the paper's motor and move, wc = 0.3 / TS, w = wc / 4, decoupling, no limit.
static void cascade_defaults(struct cascade_params *p)
{
    p->motor = MOTOR;
    p->plan = PLAN;
    p->gains.current_bandwidth = 0.3 / TS;
    p->gains.k_theta = 0.3 / TS / 4 / 3;
    p->gains.k_omega = 2.25 * (0.3 / TS / 4);
    p->gains.ki_omega = 0.75 * (0.3 / TS / 4) * (0.3 / TS / 4);
    p->gains.decoupling = true;
    p->gains.voltage_feedforward = false;
    p->gains.plan_frame = false;
    p->gains.d_hold = 1;
    p->Ts = TS;
    p->v_limit = INFINITY;
    p->torques = (struct torque_model){0, 4, 0, 0, 0.01, 0, 0, 0, 1};
}

// Returns nothing; fills p with the paper's motor and move, the design rule's poles, the zero-load model.
static void exlin_defaults(struct exact_linearization_params *p)
{
    double lambda = 0.3 / TS;
    p->motor = MOTOR;
    p->plan = PLAN;
    p->gains = (struct exact_linearization_gains){lambda / 4, 0.9, lambda, lambda};
    p->measurement = EXACT_LINEARIZATION_MODEL;
    p->v_limit = INFINITY;
    p->torques = (struct torque_model){0};
}

// Returns 0; each _init rejects each invalid group and accepts the defaults (INFINITY as v_limit among them).
static int init_checks(void)
{
    struct microstep_params mp, mq;
    struct cascade_params cp, cq;
    struct exact_linearization_params ep, eq;
    struct microstep ms;
    struct cascade cs;
    struct exact_linearization el;
    microstep_defaults(&mp);
    cascade_defaults(&cp);
    exlin_defaults(&ep);
    CHECK(microstep_init(&ms, &mp) == MICROSTEP_PARAMS_OK, "microstep defaults");
    CHECK(rel_diff(ms.kp, 30) < 1e-15 && rel_diff(ms.ki_Ts, 2.52) < 1e-15, "kp %g ki Ts %g", ms.kp, ms.ki_Ts);
    mq = mp, mq.motor.L = -1;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_EMOTOR, "L < 0");
    mq = mp, mq.plan.tf = mq.plan.t0;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_EPLAN, "tf = t0");
    mq = mp, mq.gains.current_bandwidth = 0;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_EGAINS, "wc = 0");
    mq = mp, mq.gains.current_bandwidth = 1e308;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_EGAINS, "R wc overflows");
    mq = mp, mq.Ts = NAN;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_EPERIOD, "Ts = NaN");
    mq = mp, mq.v_limit = 0;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_ELIMITS, "v_limit = 0");
    mq = mp, mq.v_limit = NAN;
    CHECK(microstep_init(&ms, &mq) == MICROSTEP_ELIMITS, "v_limit = NaN");

    CHECK(cascade_init(&cs, &cp) == CASCADE_PARAMS_OK, "cascade defaults");
    CHECK(rel_diff(cs.ki_omega_Ts, 42.1875) < 1e-14, "ki_omega Ts %g", cs.ki_omega_Ts);
    cq = cp, cq.motor.Nr = 0;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EMOTOR, "Nr = 0");
    cq = cp, cq.plan.rho2 = 0;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EPLAN, "rho2 = 0");
    cq = cp, cq.gains.k_theta = -1;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EGAINS, "k_theta < 0");
    cq = cp, cq.gains.k_omega = NAN;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EGAINS, "k_omega NaN");
    cq = cp, cq.gains.ki_omega = -1;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EGAINS, "ki_omega < 0");
    cq = cp, cq.gains.ki_omega = 0;
    CHECK(cascade_init(&cs, &cq) == CASCADE_PARAMS_OK, "ki_omega = 0: a P-P cascade");
    cq = cp, cq.gains.ki_omega = 1e300, cq.Ts = 1e10;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EPERIOD, "ki_omega Ts overflows");
    cq = cp, cq.gains.current_bandwidth = INFINITY;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EGAINS, "wc = inf");
    cq = cp, cq.Ts = 0;
    CHECK(cascade_init(&cs, &cq) == CASCADE_EPERIOD, "Ts = 0");
    cq = cp, cq.v_limit = -12;
    CHECK(cascade_init(&cs, &cq) == CASCADE_ELIMITS, "v_limit < 0");

    CHECK(exact_linearization_init(&el, &ep) == EXACT_LINEARIZATION_PARAMS_OK, "exact linearization defaults");
    // (s + 3000)(s^2 + 1350 s + 750^2): k0 = 3000 * 562500, k1 = 562500 + 3000 * 1350, k2 = 1350 + 3000
    CHECK(rel_diff(el.k0, 1.6875e9) < 1e-15 && rel_diff(el.k1, 4612500) < 1e-15 && rel_diff(el.k2, 4350) < 1e-15,
          "k0 %g k1 %g k2 %g", el.k0, el.k1, el.k2);
    eq = ep, eq.motor.Km = NAN;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_EMOTOR, "Km = NaN");
    eq = ep, eq.motor.Km = 1e-310, eq.motor.L = 1e10;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_EMOTOR, "L / Km overflows");
    eq = ep, eq.plan.t0 = INFINITY;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_EPLAN, "t0 = inf");
    eq = ep, eq.gains.xi = 0;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_EGAINS, "xi = 0");
    eq = ep, eq.gains.pd = NAN;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_EGAINS, "pd = NaN");
    eq = ep, eq.measurement = 2;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_EMEASUREMENT, "measurement 2");
    eq = ep, eq.v_limit = NAN;
    CHECK(exact_linearization_init(&el, &eq) == EXACT_LINEARIZATION_ELIMITS, "v_limit = NaN");
    return 0;
}

// Returns 0; _reset gives Python's initial_state(), and the interface binding calls the same functions.
static int reset_checks(void)
{
    struct microstep_params mp;
    struct cascade_params cp;
    struct microstep ms;
    struct cascade cs;
    struct controller c;
    double y[5] = {0.4, 0, 0, 0, 0}, v[2];
    microstep_defaults(&mp);
    cascade_defaults(&cp);
    microstep_init(&ms, &mp);
    CHECK(ms.integral[0] == 0 && ms.integral[1] == 0, "feedforward: zero integrals");
    // Without feedforward: R i*(t0 - 1) = R rho1 (cos Nr theta1, sin Nr theta1); here theta1 = 0.1 rad.
    mp.gains.feedforward = false, mp.plan.theta1 = 0.1, mp.plan.rho1 = 0.3;
    microstep_init(&ms, &mp);
    CHECK(fabs(ms.integral[0] - 8.4 * 0.3 * cos(5.0)) < 1e-14 && fabs(ms.integral[1] - 8.4 * 0.3 * sin(5.0)) < 1e-14,
          "resting integrals %.17g %.17g", ms.integral[0], ms.integral[1]);
    microstep_controller(&ms, &c);
    CHECK(c.self == &ms && !c.stateless, "microstep binding");
    CHECK(c.step(c.self, 0.03, y, v) == CTRL_OK && ms.integral[0] != 8.4 * 0.3 * cos(5.0), "a step moves the state");
    c.reset(c.self);
    CHECK(fabs(ms.integral[0] - 8.4 * 0.3 * cos(5.0)) < 1e-14, "reset through the binding %.17g", ms.integral[0]);

    cascade_init(&cs, &cp);
    cascade_controller(&cs, &c);
    CHECK(!c.stateless && c.step(c.self, 0.03, y, v) == CTRL_OK, "cascade binding");
    CHECK(cs.integral[0] != 0 && cs.integral[1] != 0 && cs.integral[2] != 0, "a step moves every integral");
    c.reset(c.self);
    CHECK(cs.integral[0] == 0 && cs.integral[1] == 0 && cs.integral[2] == 0, "reset: zero integrals");
    return 0;
}

// Returns 0; a non-finite t, used measurement or state gives CTRL_NONFINITE, 0 V and an unchanged state;
// an unused measurement is not read.
static int guard_checks(void)
{
    static const double bad[] = {NAN, INFINITY, -INFINITY};
    struct microstep_params mp;
    struct cascade_params cp;
    struct exact_linearization_params ep;
    struct microstep ms, ms0;
    struct cascade cs, cs0;
    struct exact_linearization el;
    double y[5], v[2];
    int b, k;
    microstep_defaults(&mp);
    cascade_defaults(&cp);
    exlin_defaults(&ep);
    microstep_init(&ms, &mp);
    cascade_init(&cs, &cp);
    ms.integral[0] = 0.3, ms.integral[1] = -0.2;
    cs.integral[0] = 10, cs.integral[1] = 0.1, cs.integral[2] = -0.1;
    ms0 = ms, cs0 = cs;
    for (b = 0; b < 3; b++) {
        for (k = -1; k < 5; k++) {
            double y0[5] = {0.39, 0.01, 0.5, 0.001, 3}, t = k < 0 ? bad[b] : 0.03;
            memcpy(y, y0, sizeof y);
            if (k >= 0)
                y[k] = bad[b];
            v[0] = v[1] = 1;
            CHECK(microstep_step(&ms, t, y, v) == (k < 2 ? CTRL_NONFINITE : CTRL_OK) && (k >= 2 || (!v[0] && !v[1])),
                  "microstep, bad %d at %d: v %g %g", b, k, v[0], v[1]);
            if (k < 2)
                CHECK(memcmp(&ms, &ms0, sizeof ms) == 0, "microstep state unchanged, bad %d at %d", b, k);
            ms = ms0;
            v[0] = v[1] = 1;
            CHECK(cascade_step(&cs, t, y, v) == (k < 4 ? CTRL_NONFINITE : CTRL_OK) && (k >= 4 || (!v[0] && !v[1])),
                  "cascade, bad %d at %d: v %g %g", b, k, v[0], v[1]);
            if (k < 4)
                CHECK(memcmp(&cs, &cs0, sizeof cs) == 0, "cascade state unchanged, bad %d at %d", b, k);
            cs = cs0;
            for (ep.measurement = 0; ep.measurement < 2; ep.measurement++) {
                int used = k < 4 || ep.measurement == EXACT_LINEARIZATION_MEASURED;
                exact_linearization_init(&el, &ep);
                v[0] = v[1] = 1;
                CHECK(exact_linearization_step(&el, t, y, v) == (used ? CTRL_NONFINITE : CTRL_OK)
                          && (!used || (!v[0] && !v[1])),
                      "exact linearization mode %d, bad %d at %d: v %g %g", ep.measurement, b, k, v[0], v[1]);
            }
        }
        // A non-finite integral (written by a caller) is refused the same way.
        ms.integral[1] = bad[b];
        ms0 = ms;
        CHECK(microstep_step(&ms, 0.03, y, v) == CTRL_NONFINITE && !v[0] && !v[1], "microstep NaN state");
        CHECK(memcmp(&ms, &ms0, sizeof ms) == 0, "microstep NaN state kept");
        cs.integral[0] = bad[b];
        cs0 = cs;
        CHECK(cascade_step(&cs, 0.03, y, v) == CTRL_NONFINITE && !v[0] && !v[1], "cascade NaN state");
        CHECK(memcmp(&cs, &cs0, sizeof cs) == 0, "cascade NaN state kept");
        microstep_reset(&ms), cascade_reset(&cs);
        ms0 = ms, cs0 = cs;
    }
    // Finite but huge inputs: the law overflows, 0 V and the state kept.
    {
        double y0[5] = {1e308, -1e308, 1e300, 0.001, 0};
        cascade_reset(&cs);
        cs0 = cs;
        CHECK(cascade_step(&cs, 0.03, y0, v) == CTRL_OVERFLOW && !v[0] && !v[1], "cascade overflow %g %g", v[0], v[1]);
        CHECK(memcmp(&cs, &cs0, sizeof cs) == 0, "cascade state kept on overflow");
        ms0 = ms;
        CHECK(microstep_step(&ms, 0.03, y0, v) == CTRL_OVERFLOW && !v[0] && !v[1], "microstep overflow");
        CHECK(memcmp(&ms, &ms0, sizeof ms) == 0, "microstep state kept on overflow");
        exact_linearization_init(&el, &ep);
        CHECK(exact_linearization_step(&el, 0.03, y0, v) == CTRL_OVERFLOW && !v[0] && !v[1], "exlin overflow");
    }
    return 0;
}

// Returns 0; the voltage feedforward adds (0, R iq_ff + L iq_ff') in d-q, with the torques along the plan.
static int cascade_feedforward_checks(struct cascade_params *cp)
{
    struct cascade off, on;
    double y[5] = {0.1, -0.2, 3.0, 0.01, 0}, v0[2], v1[2], f[PLAN_FLAG_LEN], E, dE, iq_ff, diq_ff, dq[2], sn, cs;
    double t = 0.027;
    const struct motor_params *m = &cp->motor;
    cascade_init(&off, cp);
    cp->gains.voltage_feedforward = true;
    CHECK(cascade_init(&on, cp) == CASCADE_PARAMS_OK, "cascade with the voltage feedforward");
    cp->gains.voltage_feedforward = false;
    CHECK(cascade_step(&off, t, y, v0) == CTRL_OK && cascade_step(&on, t, y, v1) == CTRL_OK, "steps");
    plan_flag(&on.plan, t, f);
    E = torque_model_torque(&cp->torques, m->Nr, t, f[PLAN_THETA], f[PLAN_DTHETA]);
    dE = torque_model_rate(&cp->torques, m->Nr, t, f[PLAN_THETA], f[PLAN_DTHETA], f[PLAN_DDTHETA]);
    iq_ff = (m->J * f[PLAN_DDTHETA] + m->B * f[PLAN_DTHETA] + E) / m->Km;
    diq_ff = (m->J * f[PLAN_DDDTHETA] + m->B * f[PLAN_DDTHETA] + dE) / m->Km;
    sn = sin(m->Nr * y[3]), cs = cos(m->Nr * y[3]);
    dq[0] = (v1[0] - v0[0]) * cs + (v1[1] - v0[1]) * sn;
    dq[1] = -(v1[0] - v0[0]) * sn + (v1[1] - v0[1]) * cs;
    CHECK(fabs(dq[0]) < 1e-12 && rel_diff(dq[1], m->R * iq_ff + m->L * diq_ff) < 1e-12 && fabs(dq[1]) > 1e-3,
          "cascade voltage feedforward: dq %g %g, expected %g", dq[0], dq[1], m->R * iq_ff + m->L * diq_ff);
    CHECK(off.integral[2] == on.integral[2], "the feedforward leaves the integrals alone");
    return 0;
}

// Returns 0; with a finite v_limit the integrals hold while max(|va|, |vb|) exceeds it (CTRL_SATURATED, v not
// scaled), and advance by ki Ts e when it does not.
static int windup_checks(void)
{
    struct microstep_params mp;
    struct cascade_params cp;
    struct microstep ms;
    struct cascade cs;
    double y[5] = {0, 0, 0, 0, 0}, v[2], ia;
    microstep_defaults(&mp);
    cascade_defaults(&cp);
    // Microstep from zero current at theta* = 0: e = (0.4, 0), v = (kp 0.4 + R 0.4, 0) = (15.36, 0) V before t0.
    mp.v_limit = 15;
    microstep_init(&ms, &mp);
    CHECK(microstep_step(&ms, 0, y, v) == CTRL_SATURATED && fabs(v[0] - 15.36) < 1e-12 && v[1] == 0,
          "microstep over the limit: v %.17g %g", v[0], v[1]);
    CHECK(ms.integral[0] == 0 && ms.integral[1] == 0, "microstep integrals held");
    mp.v_limit = 16;
    microstep_init(&ms, &mp);
    CHECK(microstep_step(&ms, 0, y, v) == CTRL_OK && ms.integral[0] == ms.ki_Ts * 0.4 && ms.integral[1] == 0,
          "microstep below the limit: integral %.17g", ms.integral[0]);
    // Cascade at rest at theta = 0 with no current: e_w = 0, iq* = 0, e_d = e_q = 0, v = 0; a position error of
    // 1 mrad asks for iq* = J k_omega k_theta 1e-3 / Km and v = kp iq* on the b phase.
    y[3] = -1e-3;
    cp.v_limit = 0.5;  // vb is about kp iq* = 0.91 V
    cascade_init(&cs, &cp);
    CHECK(cascade_step(&cs, 0, y, v) == CTRL_SATURATED, "cascade over the limit: v %g %g", v[0], v[1]);
    CHECK(cs.integral[0] == 0 && cs.integral[1] == 0 && cs.integral[2] == 0, "cascade integrals held");
    cp.v_limit = INFINITY;
    cascade_init(&cs, &cp);
    CHECK(cascade_step(&cs, 0, y, v) == CTRL_OK, "cascade, no limit");
    ia = cs.p.gains.k_omega * cs.p.gains.k_theta * 1e-3 * 3.6e-6 / 0.05;  // iq* at theta = -1 mrad
    CHECK(rel_diff(cs.integral[0], cs.ki_omega_Ts * cs.p.gains.k_theta * 1e-3) < 1e-14
              && rel_diff(cs.integral[2], cs.ki_Ts * ia) < 1e-14 && cs.integral[1] == 0,
          "cascade integrals %.17g %.17g", cs.integral[0], cs.integral[2]);
    return cascade_feedforward_checks(&cp);
}

// Returns 0; on the nominal plant with no load the law makes theta''' = u and i_d' = -pd i_d (model mode).
static int linearization_checks(void)
{
    struct exact_linearization_params ep;
    struct exact_linearization el;
    double x[4] = {0.3, -0.25, 2.5, 0.0123}, dx[4], v[2], y[5], f[PLAN_FLAG_LEN], s, c, id, iq, did, diq, acc, u;
    double t = 0.027;
    exlin_defaults(&ep);
    CHECK(exact_linearization_init(&el, &ep) == 0, "init");
    memcpy(y, x, sizeof x);
    y[4] = 1e9;  // not read in model mode
    CHECK(exact_linearization_step(&el, t, y, v) == CTRL_OK, "step");
    motor_rhs(&MOTOR, x, v, 0, dx);
    s = sin(50 * x[3]), c = cos(50 * x[3]);
    id = x[0] * c + x[1] * s, iq = -x[0] * s + x[1] * c;
    did = dx[0] * c + dx[1] * s + 50 * x[2] * iq;
    diq = -dx[0] * s + dx[1] * c - 50 * x[2] * id;
    acc = dx[2];
    plan_eval(&PLAN, t, f);
    u = f[PLAN_DDDTHETA] - el.k2 * (acc - f[PLAN_DDTHETA]) - el.k1 * (x[2] - f[PLAN_DTHETA])
        - el.k0 * (x[3] - f[PLAN_THETA]);
    CHECK(fabs((0.05 * diq - 1e-4 * acc) / 3.6e-6 - u) < 1e-8 * fabs(u), "theta''' %.17g vs u %.17g",
          (0.05 * diq - 1e-4 * acc) / 3.6e-6, u);
    CHECK(fabs(did + 3000 * id) < 1e-9 * fabs(3000 * id), "id' %.17g vs -pd id %.17g", did, -3000 * id);
    return 0;
}

// Returns nothing; writes i*(t) = rho* (cos Nr theta*, sin Nr theta*) of the paper's move on the paper's motor.
static void current_reference(double t, double i[2])
{
    double f[PLAN_FLAG_LEN];
    plan_eval(&PLAN, t, f);
    i[0] = f[PLAN_RHO] * cos(50 * f[PLAN_THETA]), i[1] = f[PLAN_RHO] * sin(50 * f[PLAN_THETA]);
}

// Returns 0; the feedforward and the decoupling do what they are for on the nominal model: microstepping on its
// reference at standstill gives di/dt = di*/dt (a central difference of i*), and the cascade's current loops see
// L i_dq' = PI output - R i_dq, free of the cross-coupling and the back-emf, at any state.
static int feedforward_checks(void)
{
    struct microstep_params mp;
    struct cascade_params cp;
    struct microstep ms;
    struct cascade cs;
    double t = 0.031, h = 1e-6, ip[2], im[2], y[5] = {0, 0, 0, 0, 0}, v[2], dx[4], want[2], s, c, id, iq, e_d, e_q;
    double did, diq;
    double x[4] = {0.3, -0.25, 7.5, 0.0123};
    int k;
    microstep_defaults(&mp);
    microstep_init(&ms, &mp);
    current_reference(t, y);
    CHECK(microstep_step(&ms, t, y, v) == CTRL_OK, "microstep step");
    motor_rhs(&MOTOR, y, v, 0, dx);
    current_reference(t + h, ip), current_reference(t - h, im);
    for (k = 0; k < 2; k++) {
        want[k] = (ip[k] - im[k]) / (2 * h);
        CHECK(fabs(dx[k] - want[k]) < 1e-6 * fabs(want[k]), "di%c/dt %.17g vs di*/dt %.17g", 'a' + k, dx[k], want[k]);
    }
    cascade_defaults(&cp);
    cascade_init(&cs, &cp);
    cs.integral[0] = 3, cs.integral[1] = 0.2, cs.integral[2] = -0.1;
    memcpy(y, x, sizeof x);
    CHECK(cascade_step(&cs, t, y, v) == CTRL_OK, "cascade step");
    motor_rhs(&MOTOR, x, v, 0, dx);
    s = sin(50 * x[3]), c = cos(50 * x[3]);
    id = x[0] * c + x[1] * s, iq = -x[0] * s + x[1] * c;
    e_d = -id;
    e_q = (cs.integral[2] - -0.1) / cs.ki_Ts;  // the step's q-current error, from its integral's increment
    want[0] = (cs.kp * e_d + 0.2 - 8.4 * id) / 0.010;
    want[1] = (cs.kp * e_q - 0.1 - 8.4 * iq) / 0.010;
    // i_dq' = (ia', ib') rotated by -Nr theta, plus Nr omega (iq, -id).
    did = dx[0] * c + dx[1] * s + 50 * x[2] * iq;
    diq = -dx[0] * s + dx[1] * c - 50 * x[2] * id;
    CHECK(fabs(did - want[0]) < 1e-9 * fabs(want[0]) && fabs(diq - want[1]) < 1e-9 * fabs(want[1]),
          "i_d' %.17g vs %.17g, i_q' %.17g vs %.17g", did, want[0], diq, want[1]);
    return 0;
}

// The closed loop of one test run: the plant (the nominal motor, no load) and the bound controller.
struct loop {
    struct controller c;
    double v[2];
};

// Returns 0; dx = motor_rhs at the held voltages.
static int loop_rhs(void *ctx, double t, const double *x, double *dx)
{
    (void)t;
    motor_rhs(&MOTOR, x, ((struct loop *)ctx)->v, 0, dx);
    return 0;
}

// Returns the largest |theta - theta*| over the run; runs c around the motor with RK4 from the plan's start
// equilibrium, the voltages held over each period Ts (4 RK4 steps), until t_end; writes the final state.
static double run(struct controller *c, double Ts, double t_end, double x[4])
{
    struct loop lp;
    double y[5], f[PLAN_FLAG_LEN], t = 0, worst = 0, e;
    int k, n = (int)(t_end / Ts + 0.5), j;
    lp.c = *c;
    x[0] = PLAN.rho1 * cos(50 * PLAN.theta1), x[1] = PLAN.rho1 * sin(50 * PLAN.theta1), x[2] = 0, x[3] = PLAN.theta1;
    c->reset(c->self);
    for (k = 0; k < n; k++) {
        t = k * Ts;
        memcpy(y, x, 4 * sizeof *x);
        y[4] = (motor_torque(&MOTOR, x) - MOTOR.B * x[2]) / MOTOR.J;
        CHECK((c->step(c->self, t, y, lp.v) & CTRL_FAULTS) == 0, "fault at t = %g", t);
        for (j = 0; j < 4; j++)
            ode_rk4_step(loop_rhs, &lp, 4, t + j * Ts / 4, Ts / 4, x);
        plan_eval(&PLAN, t + Ts, f);
        e = fabs(x[3] - f[PLAN_THETA]);
        worst = e > worst ? e : worst;
    }
    return worst;
}

// Returns 0; each controller moves the paper's motor 0 -> 20 mrad and tracks it (a wrong sign diverges); open-loop
// microstepping rings at sqrt(Km Nr rho / J) = 527 rad/s with only the motor's damping, hence its wider bound.
static int closed_loop_checks(void)
{
    struct microstep_params mp;
    struct cascade_params cp;
    struct exact_linearization_params ep;
    struct microstep ms;
    struct cascade cs;
    struct exact_linearization el;
    struct controller c;
    double x[4], worst;
    microstep_defaults(&mp);
    cascade_defaults(&cp);
    exlin_defaults(&ep);
    microstep_init(&ms, &mp);
    microstep_controller(&ms, &c);
    worst = run(&c, TS, 0.06, x);
    printf("  microstep: max |e| %.3g rad, theta(0.06) %.6f\n", worst, x[3]);
    CHECK(worst < 8e-3 && fabs(x[3] - 0.02) < 5e-3, "microstep tracks: %g, %g", worst, x[3]);
    cascade_init(&cs, &cp);
    cascade_controller(&cs, &c);
    worst = run(&c, TS, 0.06, x);
    printf("  cascade: max |e| %.3g rad, theta(0.06) %.6f\n", worst, x[3]);
    CHECK(worst < 1e-3 && fabs(x[3] - 0.02) < 1e-4, "cascade tracks: %g, %g", worst, x[3]);
    exact_linearization_init(&el, &ep);
    exact_linearization_controller(&el, &c);
    CHECK(c.stateless, "exact linearization is stateless");
    worst = run(&c, TS / 10, 0.06, x);
    printf("  exact linearization: max |e| %.3g rad, theta(0.06) %.6f\n", worst, x[3]);
    CHECK(worst < 1e-4 && fabs(x[3] - 0.02) < 1e-5, "exact linearization tracks: %g, %g", worst, x[3]);
    return 0;
}

// Returns 0; runs every check of the baseline controllers.
int test_baselines(void)
{
    init_checks();
    reset_checks();
    guard_checks();
    windup_checks();
    linearization_checks();
    feedforward_checks();
    closed_loop_checks();
    return 0;
}
