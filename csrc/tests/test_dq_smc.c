// The d-q flatness + sliding-mode law and the torque model: parameters, guards, sliding dynamics, closed loop.
#include <string.h>
#include "check.h"
#include "dq_smc.h"
#include "motor.h"
#include "ode.h"
#include "torque_model.h"

// A torque model with every term: detent of phase 0.3, Coulomb, a load changing over [0.01, 0.03] s.
static const struct torque_model TORQUES = {1e-3, 4, 0.3, 2e-4, 0.5, 1e-5, 3e-5, 0.01, 0.03};

// Returns 0; dq_smc_init rejects each invalid group and accepts the defaults.
static int init_checks(void)
{
    struct dq_smc_params p, q;
    struct dq_smc s;
    dq_smc_params_default(&p);
    CHECK(dq_smc_init(&s, &p) == DQ_SMC_PARAMS_OK, "defaults");
    CHECK(rel_diff(s.alpha1, 100) < 1e-15 && rel_diff(s.alpha2, 16) < 1e-15, "alpha %g %g", s.alpha1, s.alpha2);
    q = p, q.motor.Km = 0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EMOTOR, "Km = 0");
    q = p, q.plan.rho1 = NAN;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EPLAN, "rho1 = NaN");
    q = p, q.current.i_d2 = -0.1, q.current.tf = q.current.t0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EPLAN, "a d-current change of no duration");
    q = p, q.current.i_d1 = INFINITY;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EPLAN, "i_d1 infinite");
    q = p, q.gains.eps2 = 0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EGAINS, "eps2 = 0");
    q = p, q.gains.hold_damping = 0.7;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EGAINS, "hold_damping: not this law's");
    q = p, q.gains.wn = 1e200;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EGAINS, "wn^2 overflows");
    q = p, q.measurement = 2;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EMEASUREMENT, "measurement 2");
    q = p, q.v_limit = INFINITY;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_ELIMITS, "v_limit infinite");
    q = p, q.torques = TORQUES, q.torques.coulomb_speed = 0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_ETORQUES, "coulomb_speed = 0");
    q = p, q.torques = TORQUES, q.torques.load_tf = q.torques.load_t0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_ETORQUES, "a load change of no duration");
    q = p, q.torques = TORQUES;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK, "a full torque model");
    return 0;
}

// Returns 0; the torque model's rate is the time derivative of its torque along a motion (central differences).
static int torque_model_checks(void)
{
    const double h = 1e-7;
    double t = 0.017, th = 0.013, w = 3.0, a = 400.0, fd, rate;
    fd = (torque_model_torque(&TORQUES, 50, t + h, th + w * h + a * h * h / 2, w + a * h)
          - torque_model_torque(&TORQUES, 50, t - h, th - w * h + a * h * h / 2, w - a * h))
         / (2 * h);
    rate = torque_model_rate(&TORQUES, 50, t, th, w, a);
    CHECK(rel_diff(rate, fd) < 1e-6, "rate %.10g vs finite difference %.10g", rate, fd);
    CHECK(fabs(rate) > 1e-2, "every term contributes: %g", rate);
    struct torque_model none = {0, 4, 0, 0, 0.01, 0, 0, 0, 1};
    CHECK(torque_model_torque(&none, 50, t, th, w) == 0 && torque_model_rate(&none, 50, t, th, w, a) == 0,
          "no torque model, no torque");
    return 0;
}

// Returns 0; at a state off the plan the voltages give i_d' = Gamma1 and theta''' = Gamma2 through the model
// with the torques (the law's own terms recomputed here), and the guards hold.
static int law_checks(void)
{
    struct dq_smc_params p;
    struct dq_smc s;
    const struct motor_params *m;
    double y[5] = {0.05, 0.3, 2.0, 0.011, 0}, v[2], f[PLAN_FLAG_LEN], sn, cs, id, iq, vd, vq, did, diq, acc, jerk, e;
    double s1, s2, g1, g2, t = 0.027;
    uint32_t st;
    dq_smc_params_default(&p);
    p.gains = (struct smc_gains){70, 300, 0.01, 0.2, 0.7, 40, 0};
    p.torques = TORQUES;
    p.measurement = SMC_MODEL;
    CHECK(dq_smc_init(&s, &p) == DQ_SMC_PARAMS_OK, "init");
    m = &p.motor;
    st = dq_smc_step(&s, t, y, v);
    CHECK(st == CTRL_OK, "status %u", st);
    sn = sin(50 * y[3]), cs = cos(50 * y[3]);
    id = y[0] * cs + y[1] * sn, iq = -y[0] * sn + y[1] * cs;
    vd = v[0] * cs + v[1] * sn, vq = -v[0] * sn + v[1] * cs;
    acc = (m->Km * iq - m->B * y[2] - torque_model_torque(&TORQUES, 50, t, y[3], y[2])) / m->J;
    did = (vd - m->R * id + m->L * 50 * y[2] * iq) / m->L;
    diq = (vq - m->R * iq - m->L * 50 * y[2] * id - m->Km * y[2]) / m->L;
    jerk = (m->Km * diq - m->B * acc - torque_model_rate(&TORQUES, 50, t, y[3], y[2], acc)) / m->J;
    plan_eval(&p.plan, t, f);
    e = y[3] - f[PLAN_THETA];
    s1 = id;
    s2 = (acc - f[PLAN_DDTHETA]) + s.alpha2 * (y[2] - f[PLAN_DTHETA]) + s.alpha1 * e;
    g1 = -70 * s1 / (fabs(s1) + 0.01);
    g2 = f[PLAN_DDDTHETA] - s.alpha2 * (acc - f[PLAN_DDTHETA]) - s.alpha1 * (y[2] - f[PLAN_DTHETA])
         - 300 * s2 / (fabs(s2) + 0.2);
    CHECK(rel_diff(did, g1) < 1e-9, "i_d' %.12g vs Gamma1 %.12g", did, g1);
    CHECK(rel_diff(jerk, g2) < 1e-9, "theta''' %.12g vs Gamma2 %.12g", jerk, g2);

    y[2] = NAN;
    st = dq_smc_step(&s, t, y, v);
    CHECK(st == CTRL_NONFINITE && v[0] == 0 && v[1] == 0, "NaN speed: status %u, v (%g, %g)", st, v[0], v[1]);
    y[2] = 2.0, y[4] = NAN;
    CHECK(dq_smc_step(&s, t, y, v) == CTRL_OK, "y[4] is not read in model mode");
    p.measurement = SMC_IDEAL;
    p.v_limit = 0.5;
    dq_smc_init(&s, &p);
    CHECK(dq_smc_step(&s, t, y, v) == CTRL_NONFINITE, "y[4] = NaN is read in ideal mode");
    y[4] = 1e4;
    st = dq_smc_step(&s, t, y, v);
    CHECK(st == CTRL_SATURATED && rel_diff(hypot(v[0], v[1]), 0.5) < 1e-15, "scaled into v_limit: %u, |v| = %.17g", st,
          hypot(v[0], v[1]));
    y[4] = 1e307;
    st = dq_smc_step(&s, t, y, v);
    CHECK(st == CTRL_OVERFLOW && v[0] == 0 && v[1] == 0, "overflow: status %u", st);
    CHECK(s.status_seen == (CTRL_NONFINITE | CTRL_SATURATED | CTRL_OVERFLOW), "status seen %u", s.status_seen);
    dq_smc_reset(&s);
    CHECK(s.status_seen == CTRL_OK, "reset clears the status");
    return 0;
}

// The closed loop of the test: the nominal motor and the held voltages.
struct loop {
    const struct motor_params *m;
    double v[2];
};

// Returns 0; dx = motor_rhs at the held voltages, no load.
static int loop_rhs(void *ctx, double t, const double *x, double *dx)
{
    const struct loop *lp = ctx;
    (void)t;
    motor_rhs(lp->m, x, lp->v, 0, dx);
    return 0;
}

// Returns 0; the law moves the paper's motor 0 -> 20 mrad at 10 kHz from the start equilibrium (i_d = 0.4 A),
// drives i_d to 0 and tracks the plan within 5e-5 rad.
static int closed_loop_checks(void)
{
    struct dq_smc_params p;
    struct dq_smc s;
    struct controller c;
    struct loop lp;
    double x[4] = {0.4, 0, 0, 0}, y[5], f[PLAN_FLAG_LEN], Ts = 1e-4, worst = 0, e;
    int k, j;
    dq_smc_params_default(&p);
    p.gains = (struct smc_gains){150, 3e5, 0.05, 100, 0.9, 750, 0};
    p.measurement = SMC_MODEL;
    CHECK(dq_smc_init(&s, &p) == DQ_SMC_PARAMS_OK, "init");
    dq_smc_controller(&s, &c);
    CHECK(c.stateless, "a static law");
    lp.m = &p.motor;
    c.reset(c.self);
    for (k = 0; k < 600; k++) {
        memcpy(y, x, sizeof x);
        y[4] = 0;
        CHECK((c.step(c.self, k * Ts, y, lp.v) & CTRL_FAULTS) == 0, "fault at step %d", k);
        for (j = 0; j < 4; j++)
            ode_rk4_step(loop_rhs, &lp, 4, k * Ts + j * Ts / 4, Ts / 4, x);
        plan_eval(&p.plan, (k + 1) * Ts, f);
        e = fabs(x[3] - f[PLAN_THETA]);
        worst = e > worst ? e : worst;
    }
    printf("  dq_smc: max |e| %.3g rad, theta(0.06) %.6f, i_d(0.06) %.3g A\n", worst, x[3],
           x[0] * cos(50 * x[3]) + x[1] * sin(50 * x[3]));
    CHECK(worst < 5e-5 && fabs(x[3] - 0.02) < 1e-5, "tracks: %g, %g", worst, x[3]);
    CHECK(fabs(x[0] * cos(50 * x[3]) + x[1] * sin(50 * x[3])) < 1e-3, "i_d -> 0");
    return 0;
}

// Returns 0; for every combination of extreme inputs (0, +-1e-300, +-1, +-1e10, +-1e300, NaN, infinity) the step
// returns finite voltages within v_limit, and 0 V exactly on a fault.
static int contract_checks(void)
{
    static const double values[] = {0, 1e-300, -1e-300, 1, -1, 1e10, -1e10, 1e300, -1e300, NAN, INFINITY};
    const int n = (int)(sizeof values / sizeof values[0]);
    struct dq_smc_params p;
    struct dq_smc s;
    double y[5], v[2], t;
    uint32_t st;
    int i, k, m, bad = 0, faults = 0;
    dq_smc_params_default(&p);
    p.torques = TORQUES;
    p.current = (struct dq_smc_current){
        .i_d1 = 0.1, .i_d2 = -0.2, .t0 = 0.01, .tf = 0.05, .weakening = 0.05, .weakening_speed = 0.8};
    for (m = 0; m < 2; m++) {
        p.measurement = m ? SMC_MODEL : SMC_IDEAL;
        dq_smc_init(&s, &p);
        for (i = 0; i < n * n * n; i++) {
            // t, and one input at a time set to each extreme over a nominal measurement
            t = i % 3 == 0 ? 0.03 : values[(i / 3) % n];
            y[0] = 0.1, y[1] = 0.3, y[2] = 1.0, y[3] = 0.01, y[4] = 100;
            k = i % 5;
            y[k] = values[(i / (3 * n)) % n];
            st = dq_smc_step(&s, t, y, v);
            faults += (st & CTRL_FAULTS) != 0;
            if (!(isfinite(v[0]) && isfinite(v[1]) && hypot(v[0], v[1]) <= p.v_limit * (1 + 1e-15))
                || ((st & CTRL_FAULTS) && (v[0] != 0 || v[1] != 0)))
                bad++;
        }
    }
    CHECK(bad == 0, "%d steps broke the contract", bad);
    CHECK(faults > 100, "the extremes do fault (%d steps)", faults);
    return 0;
}

// Returns 0; smc_init takes the loss-aware rho*(t) and refuses a margin out of [0, pi/2) or a negative hold, and
// its step tracks rho* = sqrt(rho_hold^2 + (A* / (Km cos margin))^2) (at rest with no torques: rho_hold).
static int loss_aware_checks(void)
{
    struct smc_params p, q;
    struct smc s;
    struct smc_terms w;
    double y[5] = {0.2, 0, 0, 0, 0}, v[2];
    smc_params_default(&p);
    p.loss_aware = (struct smc_loss_aware){0.7854, 0.2};
    CHECK(smc_init(&s, &p) == SMC_PARAMS_OK, "loss-aware rho*");
    q = p, q.loss_aware.margin = 1.5707963267948966;
    CHECK(smc_init(&s, &q) == SMC_EPLAN, "margin = pi/2");
    q = p, q.loss_aware.rho_hold = -1;
    CHECK(smc_init(&s, &q) == SMC_EPLAN, "rho_hold < 0");
    smc_init(&s, &p);
    CHECK(smc_step_terms(&s, 0.0, y, NULL, v, &w) == CTRL_OK, "step at rest");
    CHECK(w.flag[PLAN_RHO] == 0.2 && w.flag[PLAN_DRHO] == 0 && w.s1 == 0, "at rest rho* = rho_hold: %g %g %g",
          w.flag[PLAN_RHO], w.flag[PLAN_DRHO], w.s1);
    smc_step_terms(&s, 0.03, y, NULL, v, &w);
    CHECK(w.flag[PLAN_RHO] > 0.2 && w.flag[PLAN_DRHO] != 0, "in the move rho* rises: %g", w.flag[PLAN_RHO]);
    return 0;
}

// Returns 0; the integral action: its guards, Gamma2 -= ki z, z += Ts s2 inside the boundary layer and below
// v_hold, held outside either, cleared by reset, and the binding stateful only with it.
static int integral_checks(void)
{
    struct dq_smc_params p, q;
    struct dq_smc s, r;
    struct controller c;
    double y[5] = {0.05, 0.3, 2.0, 0.011, 0}, v[2], w[2], f[PLAN_FLAG_LEN], sn, cs, vq, wq, s2, t = 0.027;
    dq_smc_params_default(&p);
    p.gains = (struct smc_gains){70, 300, 0.01, 1e9, 0.7, 40, 0};
    p.measurement = SMC_IDEAL;
    q = p;
    q.integral = (struct dq_smc_integral){-1, 5e-5, 24};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EINTEGRAL, "ki < 0");
    q.integral = (struct dq_smc_integral){NAN, 5e-5, 24};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EINTEGRAL, "ki = NaN");
    q.integral = (struct dq_smc_integral){1e5, 0, 24};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EINTEGRAL, "ki > 0, Ts = 0");
    q.integral = (struct dq_smc_integral){1e5, 5e-5, INFINITY};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EINTEGRAL, "v_hold infinite");
    q.integral = (struct dq_smc_integral){0, 0, 0};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK, "ki = 0 needs neither Ts nor v_hold");
    dq_smc_controller(&s, &c);
    CHECK(c.stateless, "without integral the law is stateless");

    q.integral = (struct dq_smc_integral){1e5, 5e-5, 1e3};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK && dq_smc_init(&r, &p) == DQ_SMC_PARAMS_OK, "init");
    dq_smc_controller(&s, &c);
    CHECK(!c.stateless, "with integral the law has state");
    dq_smc_step(&s, t, y, v);
    dq_smc_step(&r, t, y, w);
    CHECK(v[0] == w[0] && v[1] == w[1], "z = 0: the plain law's voltages bit for bit");
    plan_eval(&p.plan, t, f);
    s2 = (y[4] - f[PLAN_DDTHETA]) + s.alpha2 * (y[2] - f[PLAN_DTHETA]) + s.alpha1 * (y[3] - f[PLAN_THETA]);
    CHECK(rel_diff(s.z, 5e-5 * s2) < 1e-12 && s2 != 0, "z = Ts s2: %.17g vs %.17g", s.z, 5e-5 * s2);
    dq_smc_step(&s, t, y, v);
    dq_smc_step(&r, t, y, w);
    sn = sin(50 * y[3]), cs = cos(50 * y[3]);
    vq = -v[0] * sn + v[1] * cs, wq = -w[0] * sn + w[1] * cs;
    CHECK(rel_diff(vq - wq, -p.motor.L * p.motor.J * 1e5 * 5e-5 * s2 / p.motor.Km) < 1e-6,
          "v_q shifts by -L J ki z/Km: %.12g", vq - wq);
    CHECK(rel_diff(s.z, 2 * 5e-5 * s2) < 1e-12, "z advances again: %.17g", s.z);

    q.gains.eps2 = fabs(s2) / 2;
    dq_smc_init(&s, &q);
    dq_smc_step(&s, t, y, v);
    CHECK(s.z == 0, "held outside the boundary layer: %g", s.z);
    q.gains.eps2 = 1e9;
    q.integral.v_hold = hypot(w[0], w[1]) / 2;
    dq_smc_init(&s, &q);
    dq_smc_step(&s, t, y, v);
    CHECK(s.z == 0, "held above v_hold: %g", s.z);
    q.integral.v_hold = 1e3;
    dq_smc_init(&s, &q);
    dq_smc_step(&s, t, y, v);
    CHECK(s.z != 0, "advancing");
    dq_smc_reset(&s);
    CHECK(s.z == 0, "reset clears z");
    return 0;
}

// Returns 0; the angle advance: refused unless finite and >= 0, and the voltage turned by Nr omega advance with its
// norm kept (the same d-q voltage at the angle the rotor reaches advance later).
static int advance_checks(void)
{
    struct dq_smc_params p, q;
    struct dq_smc s;
    const double y[5] = {0.05, 0.3, 40.0, 0.011, 30.0}, ta = 2.5e-5, t = 0.025;
    double v0[2], v1[2], turn, c, sn;
    dq_smc_params_default(&p);
    q = p, q.advance = -1e-9;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADVANCE, "advance < 0");
    q.advance = NAN;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADVANCE, "advance = NaN");
    q.advance = INFINITY;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADVANCE, "advance infinite");
    dq_smc_init(&s, &p);
    dq_smc_step(&s, t, y, v0);
    q = p, q.advance = ta;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK, "advance = Ts/2");
    dq_smc_step(&s, t, y, v1);
    turn = p.motor.Nr * y[2] * ta, c = cos(turn), sn = sin(turn);
    CHECK(fabs(v1[0] - (v0[0] * c - v0[1] * sn)) < 1e-12 * hypot(v0[0], v0[1])
              && fabs(v1[1] - (v0[0] * sn + v0[1] * c)) < 1e-12 * hypot(v0[0], v0[1]) && turn > 0.01,
          "turned by %g: (%g, %g) from (%g, %g)", turn, v1[0], v1[1], v0[0], v0[1]);
    return 0;
}

// Returns 0 after running every check of the d-q law.
int test_dq_smc(void)
{
    init_checks();
    torque_model_checks();
    law_checks();
    closed_loop_checks();
    contract_checks();
    loss_aware_checks();
    integral_checks();
    advance_checks();
    test_dq_smc_km();
    return 0;
}
