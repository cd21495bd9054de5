// The d-q law's online Km estimate: its guards, the plain law at Km^ = Km, one period of its gradient law, the
// projection, the holds and the binding.
#include "check.h"
#include "dq_smc.h"

// A torque model with a detent (phase 0.3) and Coulomb friction: the plan's regressor carries the detent's rate.
static const struct torque_model TORQUES = {1e-3, 4, 0.3, 2e-4, 0.5, 0, 0, 0, 1};

// Returns 0; dq_smc_init refuses each invalid adaptation and the binding is stateful with one.
static int guard_checks(void)
{
    struct dq_smc_params p, q;
    struct dq_smc s;
    struct controller c;
    const struct dq_smc_adaptation good = {1e3, 50, 0.3, 5e-5, 24};
    dq_smc_params_default(&p);
    q = p, q.adapt = good, q.adapt.rate = -1;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "rate < 0");
    q.adapt.rate = NAN;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "rate = NaN");
    q = p, q.adapt = good, q.adapt.phi0 = 0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "phi0 = 0");
    q = p, q.adapt = good, q.adapt.phi0 = 1e-170;  // found by the fuzzer: phi0^2 + phi^2 was 0 at rest, 0 / 0
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "phi0^2 underflows");
    q = p, q.adapt = good, q.adapt.range = 1;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "range = 1");
    q.adapt.range = 0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "range = 0");
    q = p, q.adapt = good, q.adapt.Ts = 0;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "Ts = 0");
    q = p, q.adapt = good, q.adapt.v_hold = INFINITY;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_EADAPT, "v_hold infinite");
    q = p, q.adapt = (struct dq_smc_adaptation){0, 0, 0, 0, 0};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK && s.km == p.motor.Km, "rate = 0 needs nothing else; Km^ = Km");
    dq_smc_controller(&s, &c);
    CHECK(c.stateless, "without the estimate the law is stateless");
    q.adapt = good;
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK, "a valid adaptation");
    dq_smc_controller(&s, &c);
    CHECK(!c.stateless, "with the estimate the law has state");
    return 0;
}

// Returns the plan's regressor phi at t (dq_smc.h) for the estimate km, computed apart from the law.
static double regressor(const struct dq_smc_params *p, double t, double km)
{
    double f[PLAN_FLAG_LEN], dE;
    plan_eval(&p->plan, t, f);
    dE = torque_model_rate(&p->torques, p->motor.Nr, t, f[PLAN_THETA], f[PLAN_DTHETA], f[PLAN_DDTHETA]);
    return (p->motor.J * f[PLAN_DDDTHETA] + p->motor.B * f[PLAN_DDTHETA] + dE) / km - km * f[PLAN_DTHETA] / p->motor.L;
}

// Returns 0; one period: the plain law's voltages at Km^ = Km, Km^ advanced by the gradient law, then projected,
// still at rest, held outside the boundary layer and above v_hold, back to Km by reset.
static int law_checks(void)
{
    struct dq_smc_params p, q;
    struct dq_smc s, r;
    double y[5] = {0.05, 0.3, 0.5, 0.011, 0}, v[2], w[2], f[PLAN_FLAG_LEN], s2, phi, km, t = 0.027;
    dq_smc_params_default(&p);
    p.gains = (struct smc_gains){70, 300, 0.01, 1e9, 0.7, 40, 0};
    p.torques = TORQUES;
    q = p, q.adapt = (struct dq_smc_adaptation){1e11, 5, 0.3, 5e-5, 1e3};
    CHECK(dq_smc_init(&s, &q) == DQ_SMC_PARAMS_OK && dq_smc_init(&r, &p) == DQ_SMC_PARAMS_OK, "init");
    dq_smc_step(&s, t, y, v);
    dq_smc_step(&r, t, y, w);
    CHECK(v[0] == w[0] && v[1] == w[1], "Km^ = Km: the plain law's voltages bit for bit");
    plan_eval(&p.plan, t, f);
    s2 = (y[4] - f[PLAN_DDTHETA]) + s.alpha2 * (y[2] - f[PLAN_DTHETA]) + s.alpha1 * (y[3] - f[PLAN_THETA]);
    phi = regressor(&p, t, p.motor.Km);
    km = p.motor.Km + 5e-5 * 1e11 * p.motor.J * 300 / 1e9 * s2 * phi / (25 + phi * phi);
    CHECK(rel_diff(s.km, km) < 1e-12 && fabs(s.km / p.motor.Km - 1) > 1e-3, "Km^ %.17g vs %.17g", s.km, km);
    dq_smc_step(&s, t, y, v);
    CHECK(rel_diff(-v[0] * sin(50 * y[3]) + v[1] * cos(50 * y[3]), -w[0] * sin(50 * y[3]) + w[1] * cos(50 * y[3]))
              > 1e-6,
          "the next step uses Km^");

    q.adapt.rate = 1e30;
    dq_smc_init(&s, &q);
    dq_smc_step(&s, t, y, v);
    CHECK(s.km == p.motor.Km * (1 - 0.3) || s.km == p.motor.Km * (1 + 0.3), "projected: %.17g", s.km);
    dq_smc_reset(&s);
    CHECK(s.km == p.motor.Km, "reset: Km^ = Km");
    dq_smc_step(&s, 0.01, y, v);
    CHECK(s.km == p.motor.Km && regressor(&p, 0.01, p.motor.Km) == 0, "still at rest (before t0): %.17g", s.km);

    q.gains.eps2 = fabs(s2) / 2;
    dq_smc_init(&s, &q);
    dq_smc_step(&s, t, y, v);
    CHECK(s.km == p.motor.Km, "held outside the boundary layer");
    q.gains.eps2 = 1e9;
    q.adapt.v_hold = hypot(w[0], w[1]) / 2;
    dq_smc_init(&s, &q);
    dq_smc_step(&s, t, y, v);
    CHECK(s.km == p.motor.Km, "held above v_hold");
    return 0;
}

// Returns 0 after running every check of the Km estimate.
int test_dq_smc_km(void)
{
    guard_checks();
    law_checks();
    return 0;
}
