// smc_init / smc_reset / smc_step: parameter errors, the law on the reference, and the output guards.
#include <float.h>
#include <string.h>
#include "check.h"
#include "flat.h"
#include "smc.h"

// Returns true when v is finite and within the limit (one rounding of slack from the rescaling).
static int bounded(const double v[2], double limit)
{
    return isfinite(v[0]) && isfinite(v[1]) && hypot(v[0], v[1]) <= limit * (1 + 4 * DBL_EPSILON);
}

// Returns 0; smc_init rejects each invalid group and accepts the defaults.
static int init_checks(void)
{
    struct smc_params p, q;
    struct smc s;
    smc_params_default(&p);
    CHECK(smc_init(&s, &p) == SMC_PARAMS_OK, "defaults are valid");
    CHECK(s.alpha1 == 100.0 && fabs(s.alpha2 - 16.0) < 1e-14, "alpha1 %g alpha2 %g", s.alpha1, s.alpha2);
    q = p, q.motor.J = 0;
    CHECK(smc_init(&s, &q) == SMC_EMOTOR, "J = 0");
    q = p, q.plan.rho1 = -0.4;
    CHECK(smc_init(&s, &q) == SMC_EPLAN, "rho1 < 0");
    q = p, q.gains.eps2 = 0;
    CHECK(smc_init(&s, &q) == SMC_EGAINS, "eps2 = 0");
    q = p, q.gains.xi = NAN;
    CHECK(smc_init(&s, &q) == SMC_EGAINS, "xi = NaN");
    q = p, q.measurement = 7;
    CHECK(smc_init(&s, &q) == SMC_EMEASUREMENT, "measurement 7");
    q = p, q.v_limit = INFINITY;
    CHECK(smc_init(&s, &q) == SMC_ELIMITS, "v_limit = inf");
    q = p, q.v_limit = 1e-309;  // found by the fuzzer: a denormal limit cannot be met after rescaling
    CHECK(smc_init(&s, &q) == SMC_ELIMITS, "v_limit = 1e-309");
    q = p, q.rho_min = 0;
    CHECK(smc_init(&s, &q) == SMC_ELIMITS, "rho_min = 0");
    q = p, q.gains.hold_damping = -0.7;
    CHECK(smc_init(&s, &q) == SMC_EGAINS, "hold_damping < 0");
    q = p, q.gains.hold_damping = NAN;
    CHECK(smc_init(&s, &q) == SMC_EGAINS, "hold_damping = NaN");
    q = p, q.gains.hold_damping = 1e300, q.plan.rho2 = 1e-300;  // the hold's gain overflows
    CHECK(smc_init(&s, &q) == SMC_EGAINS, "hold gain = inf");
    return 0;
}

// Returns 0; on the planned trajectory s1 = s2 = 0 and the law gives the flat feedforward, in both modes.
static int law_checks(void)
{
    struct smc_params p;
    struct smc s;
    double f[PLAN_FLAG_LEN], x[4], vff[2], y[5], v[2], t;
    int i, mode;
    smc_params_default(&p);
    for (mode = SMC_IDEAL; mode <= SMC_MODEL; mode++) {
        p.measurement = mode;
        smc_init(&s, &p);
        for (i = 0; i <= 30; i++) {
            t = 0.015 + 0.001 * i;
            plan_eval(&p.plan, t, f);
            flat_to_state(&p.motor, f, 0, x, vff);
            y[0] = x[0], y[1] = x[1], y[2] = x[2], y[3] = x[3];
            y[4] = mode == SMC_IDEAL ? f[PLAN_DDTHETA] : NAN;  // model mode must not read y[4]
            CHECK(smc_step(&s, t, y, v) == SMC_OK, "mode %d t %g", mode, t);
            CHECK(fabs(v[0] - vff[0]) <= 1e-9 * (1 + fabs(vff[0])) && fabs(v[1] - vff[1]) <= 1e-9 * (1 + fabs(vff[1])),
                  "mode %d t %g: v (%.12g, %.12g) vs feedforward (%.12g, %.12g)", mode, t, v[0], v[1], vff[0], vff[1]);
        }
    }
    // Off the trajectory the law pushes rho back: too much current gives a voltage opposing the current.
    p.measurement = SMC_IDEAL;
    smc_init(&s, &p);
    y[0] = 0.5, y[1] = 0, y[2] = 0, y[3] = 0, y[4] = 0;
    smc_step(&s, 0.0, y, v);
    // s1 = 0.1, s2 = 0: va = R rho + L Gamma1 = 8.4 * 0.5 - 0.01 * 100 * 0.1 / (0.1 + 0.005), vb = 0.
    CHECK(fabs(v[0] - (4.2 - 0.1 / 0.105)) < 1e-12 && fabs(v[1]) < 1e-12, "rho above plan: v (%.17g, %.17g)", v[0],
          v[1]);
    return 0;
}

// Returns 0; every hostile input gives a finite, bounded voltage and the right status bit.
static int guard_checks(void)
{
    struct smc_params p;
    struct smc s;
    const double big = DBL_MAX, inf = INFINITY, nan = NAN;
    double y[5], v[2], v2[2];
    const double cases[][6] = {
        // t, ia, ib, omega, theta, ddtheta -> expected status
        {nan, 0.4, 0, 0, 0, 0}, {0, nan, 0, 0, 0, 0},   {0, 0.4, inf, 0, 0, 0}, {0, 0.4, 0, -inf, 0, 0},
        {0, 0.4, 0, 0, nan, 0}, {0, 0.4, 0, 0, 0, inf}, {inf, 0.4, 0, 0, 0, 0},
    };
    uint32_t st;
    size_t i;
    smc_params_default(&p);
    smc_init(&s, &p);
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        y[0] = cases[i][1], y[1] = cases[i][2], y[2] = cases[i][3], y[3] = cases[i][4], y[4] = cases[i][5];
        v[0] = v[1] = 123;
        st = smc_step(&s, cases[i][0], y, v);
        CHECK(st == SMC_NONFINITE && v[0] == 0 && v[1] == 0, "case %zu: status %u v (%g, %g)", i, st, v[0], v[1]);
    }
    CHECK(s.status_seen == SMC_NONFINITE, "status_seen accumulates: %u", s.status_seen);
    smc_reset(&s);
    CHECK(s.status_seen == SMC_OK, "reset clears status_seen");
    y[0] = 0, y[1] = 0, y[2] = 0, y[3] = 0, y[4] = 0;
    CHECK(smc_step(&s, 0.03, y, v) == SMC_RHO && v[0] == 0 && v[1] == 0, "zero currents -> SMC_RHO, 0 V");
    y[0] = 5e-7;
    CHECK(smc_step(&s, 0.03, y, v) == SMC_RHO, "rho below rho_min -> SMC_RHO");
    y[0] = 0.4, y[4] = 1e5;  // J theta'' = 0.36 N m > Km rho = 0.02 N m
    CHECK(smc_step(&s, 0.03, y, v) == SMC_SQRT && v[0] == 0 && v[1] == 0, "out-of-reach torque -> SMC_SQRT, 0 V");
    y[0] = 200, y[4] = 0;  // 200 A: R rho alone is 1680 V
    st = smc_step(&s, 0.03, y, v);
    CHECK(st == SMC_SATURATED && bounded(v, 1e3) && fabs(hypot(v[0], v[1]) - 1e3) < 1e-9, "saturated: %u |v| %.17g", st,
          hypot(v[0], v[1]));
    p.v_limit = 1e300;  // the same step unsaturated keeps the direction of the saturated one
    smc_init(&s, &p);
    CHECK(smc_step(&s, 0.03, y, v2) == SMC_OK, "unsaturated with a huge limit");
    CHECK(fabs(v[0] / 1e3 - v2[0] / hypot(v2[0], v2[1])) < 1e-12
              && fabs(v[1] / 1e3 - v2[1] / hypot(v2[0], v2[1])) < 1e-12,
          "saturation keeps the direction");
    // Huge finite inputs: overflow inside the law is caught, never passed on.
    smc_params_default(&p);
    smc_init(&s, &p);
    for (i = 0; i < 32; i++) {
        y[0] = (i & 1) ? big : 0.4, y[1] = (i & 2) ? -big : 0.1, y[2] = (i & 4) ? big : 1;
        y[3] = (i & 8) ? big : 0.01, y[4] = (i & 16) ? -big : 3;
        st = smc_step(&s, (i & 1) ? -big : 0.03, y, v);
        CHECK(bounded(v, 1e3), "huge case %zu: v (%g, %g)", i, v[0], v[1]);
        CHECK((st & ~(uint32_t)SMC_SATURATED) == 0 || (v[0] == 0 && v[1] == 0), "huge case %zu: fault %u gives 0 V", i,
              st);
    }
    return 0;
}

// Returns 0; smc_step_terms gives smc_step's bits and the step's intermediate values, with and without the
// caller's sin and cos of Nr theta, on the law's path and on the faults that stop it early.
static int terms_checks(void)
{
    struct smc_params p;
    struct smc s;
    struct smc_terms w;
    double f[PLAN_FLAG_LEN], y[5] = {0.3, 0.2, 5.0, 0.01, 40.0}, v[2], vt[2], trig[2], rho, acc, s2;
    double faults[3][5] = {{NAN, 0.2, 5.0, 0.01, 40.0}, {0, 0, 5.0, 0.01, 40.0}, {1e-7, 0, 5.0, 0.01, 40.0}};
    uint32_t st, stt;
    int mode, k, given;
    smc_params_default(&p);
    for (mode = SMC_IDEAL; mode <= SMC_MODEL; mode++) {
        p.measurement = mode;
        smc_init(&s, &p);
        trig[0] = sin(p.motor.Nr * y[3]), trig[1] = cos(p.motor.Nr * y[3]);
        for (given = 0; given < 2; given++) {
            st = smc_step(&s, 0.03, y, v);
            stt = smc_step_terms(&s, 0.03, y, given ? trig : NULL, vt, &w);
            CHECK(st == stt && v[0] == vt[0] && v[1] == vt[1], "mode %d trig %d: terms step differs (%.17g %.17g)",
                  mode, given, vt[0] - v[0], vt[1] - v[1]);
            CHECK(w.have == (SMC_HAVE_FLAG | SMC_HAVE_LAW), "mode %d: have %u", mode, w.have);
            plan_eval(&p.plan, 0.03, f);
            rho = hypot(y[0], y[1]);
            acc = mode == SMC_IDEAL ? y[4] : motor_acceleration(&p.motor, y, 0);
            s2 = acc - f[PLAN_DDTHETA] + s.alpha2 * (y[2] - f[PLAN_DTHETA]) + s.alpha1 * (y[3] - f[PLAN_THETA]);
            for (k = 0; k < PLAN_FLAG_LEN; k++)
                CHECK(fabs(w.flag[k] - f[k]) <= 1e-15 * fabs(f[k]), "flag[%d] %.17g vs %.17g", k, w.flag[k], f[k]);
            CHECK(fabs(w.rho - rho) <= 2e-16 * rho && fabs(w.s1 - (rho - f[PLAN_RHO])) <= 1e-15 * rho
                      && fabs(w.sphi - y[0] / rho) <= 1e-15 && fabs(w.cphi - y[1] / rho) <= 1e-15
                      && fabs(w.snr - trig[0]) <= 1e-15 && fabs(w.cnr - trig[1]) <= 1e-15
                      && fabs(w.acc - acc) <= 1e-12 * fabs(acc) && fabs(w.s2 - s2) <= 1e-12 * fabs(s2),
                  "mode %d trig %d: terms rho %.17g s1 %.17g acc %.17g s2 %.17g", mode, given, w.rho, w.s1, w.acc,
                  w.s2);
        }
    }
    // Faults before the law: no flag for a non-finite input, the flag only when rho < rho_min.
    for (k = 0; k < 3; k++) {
        st = smc_step(&s, 0.03, faults[k], v);
        stt = smc_step_terms(&s, 0.03, faults[k], NULL, vt, &w);
        CHECK(st == stt && vt[0] == 0 && vt[1] == 0, "fault case %d: status %u vs %u", k, stt, st);
        CHECK(w.have == (k == 0 ? 0u : (uint32_t)SMC_HAVE_FLAG), "fault case %d: have %u", k, w.have);
    }
    return 0;
}

// Returns 0; the detent hold: the law's voltages until tf, then v = R i* on the detent of theta2 at rest, and a
// damping torque -2 zeta sqrt(K J) omega (K = Km rho2 Nr) from the hold's current vector when the rotor moves.
static int hold_checks(void)
{
    struct smc_params p;
    struct smc plain, hold;
    const struct motor_params *m = &p.motor;
    double y[5], v[2], vp[2], ia, ib, K, te, istar[2], omega = 2e-3, lam, E;
    smc_params_default(&p);
    p.measurement = SMC_MODEL;
    smc_init(&plain, &p);
    p.gains.hold_damping = 0.7;
    CHECK(smc_init(&hold, &p) == SMC_PARAMS_OK, "hold_damping = 0.7 is valid");
    y[0] = 0.1, y[1] = -0.3, y[2] = 0.5, y[3] = p.plan.theta2 + 1e-3, y[4] = NAN;
    smc_step(&plain, 0.039, y, vp);
    smc_step(&hold, 0.039, y, v);
    CHECK(v[0] == vp[0] && v[1] == vp[1], "before tf the hold is the law");
    // at rest on theta2 with the currents on the detent (ia, ib) = rho2 (cos Nr theta2, sin Nr theta2): v = R i
    istar[0] = p.plan.rho2 * cos(m->Nr * p.plan.theta2), istar[1] = p.plan.rho2 * sin(m->Nr * p.plan.theta2);
    y[0] = istar[0], y[1] = istar[1], y[2] = 0, y[3] = p.plan.theta2;
    CHECK(smc_step(&hold, p.plan.tf, y, v) == SMC_OK, "hold at rest");
    CHECK(fabs(v[0] - m->R * istar[0]) < 1e-12 && fabs(v[1] - m->R * istar[1]) < 1e-12, "v (%g, %g) vs R i* (%g, %g)",
          v[0], v[1], m->R * istar[0], m->R * istar[1]);
    // moving: the currents the hold drives to, from v = R i* + L lam (i* - i) + emf at i = the rest currents
    y[2] = omega;
    CHECK(smc_step(&hold, 0.05, y, v) == SMC_OK, "hold moving");
    lam = p.gains.W1 / p.gains.eps1;
    ia = (v[0] + m->Km * omega * sin(m->Nr * y[3]) + m->L * lam * istar[0]) / (m->R + m->L * lam);
    ib = (v[1] - m->Km * omega * cos(m->Nr * y[3]) + m->L * lam * istar[1]) / (m->R + m->L * lam);
    K = m->Km * p.plan.rho2 * m->Nr;
    te = m->Km * (ib * cos(m->Nr * y[3]) - ia * sin(m->Nr * y[3]));
    CHECK(rel_diff(te, -2 * 0.7 * sqrt(K * m->J) * omega) < 1e-6, "damping torque %g vs %g", te,
          -2 * 0.7 * sqrt(K * m->J) * omega);
    // known torques: at rest the hold's currents balance E on theta2 (detent there and load, no Coulomb at rest)
    p.torques.detent_torque = 1e-3, p.torques.coulomb_torque = 2e-4, p.torques.load = 1e-5;
    CHECK(smc_init(&hold, &p) == SMC_PARAMS_OK && hold.hold_torques, "hold with known torques");
    y[0] = 0.1, y[1] = -0.3, y[2] = 0, y[3] = p.plan.theta2 + 1e-4;
    CHECK(smc_step(&hold, p.plan.tf, y, v) == SMC_OK, "hold with torques at rest");
    ia = (v[0] + m->L * lam * y[0]) / (m->R + m->L * lam);
    ib = (v[1] + m->L * lam * y[1]) / (m->R + m->L * lam);
    te = m->Km * (ib * cos(m->Nr * p.plan.theta2) - ia * sin(m->Nr * p.plan.theta2));
    E = torque_model_torque(&p.torques, m->Nr, p.plan.tf, p.plan.theta2, 0);
    CHECK(fabs(E) > 5e-4 && rel_diff(te, E) < 1e-9, "hold torque %g vs E %g", te, E);
    CHECK(rel_diff(hypot(ia, ib), p.plan.rho2) < 1e-12, "hold current %g vs rho2", hypot(ia, ib));
    return 0;
}

// Returns 0 after running the controller checks.
// Returns 0; a constant known torque (the load alone) skips the torque model's calls and gives, bit for bit, what
// the calls give, in both measurement modes, on and off the plan, at rest and in the move, with rho*(t) as well.
static int constant_torque_checks(void)
{
    struct smc_params p;
    struct smc fast, called;
    double y[5], v[2], w[2], t;
    int i, mode, la, same = 0, ok = 0;
    smc_params_default(&p);
    p.torques.load = 1e-5;
    p.torques.coulomb_speed = 0.3;  // read only with a Coulomb amplitude
    for (la = 0; la <= 1; la++) {
        p.loss_aware.rho_hold = la ? 0.2 : 0;
        p.loss_aware.margin = la ? 0.7 : 0;
        for (mode = SMC_IDEAL; mode <= SMC_MODEL; mode++) {
            p.measurement = mode;
            CHECK(smc_init(&fast, &p) == SMC_PARAMS_OK && smc_init(&called, &p) == SMC_PARAMS_OK, "init");
            CHECK(fast.torques_constant, "the load alone is constant");
            called.torques_constant = false;
            for (i = 0; i < 64; i++) {
                t = 0.001 * i;
                y[0] = 0.4 * sin(3.1 * i), y[1] = 0.4 * cos(1.7 * i) + 0.1, y[2] = sin(0.7 * i);
                y[3] = 0.02 * sin(0.3 * i), y[4] = 100 * cos(0.9 * i);
                ok += smc_step(&fast, t, y, v) == SMC_OK;
                smc_step(&called, t, y, w);
                same += memcmp(v, w, sizeof v) == 0;
            }
        }
    }
    CHECK(same == 4 * 64 && ok > 2 * 64, "%d of %d steps bit for bit, %d without a status bit", same, 4 * 64, ok);
    p.torques.detent_torque = 1e-3;
    smc_init(&fast, &p);
    CHECK(!fast.torques_constant, "a detent term is not constant");
    return 0;
}

int test_smc(void)
{
    init_checks();
    law_checks();
    guard_checks();
    terms_checks();
    hold_checks();
    constant_torque_checks();
    return 0;
}
