// Planner, flat maps and motor model: boundary values, finite-difference derivatives, round trips.
#include <float.h>
#include "check.h"
#include "flat.h"
#include "motor.h"
#include "plan.h"

static const struct motor_params PAPER = {8.4, 0.010, 0.05, 3.6e-6, 1e-4, 50};

// Returns 0; psi's boundary conditions and its derivatives against central differences.
static int psi_checks(void)
{
    const double t0 = 0.02, tf = 0.04, h = 1e-7;
    double t, fd;
    int k, i;
    CHECK(plan_psi(t0, t0, tf, 0) == 0.0, "psi(t0) = %g", plan_psi(t0, t0, tf, 0));
    CHECK(plan_psi(tf, t0, tf, 0) == 1.0, "psi(tf) = %g", plan_psi(tf, t0, tf, 0));
    CHECK(plan_psi(0.0, t0, tf, 0) == 0.0 && plan_psi(1.0, t0, tf, 0) == 1.0, "held outside");
    // psi is the regularized incomplete beta function I_tau(5, 6): I_1/2(5, 6) = 638 / 1024.
    CHECK(fabs(plan_psi(0.03, t0, tf, 0) - 638.0 / 1024) < 1e-15, "psi(mid) = %.17g", plan_psi(0.03, t0, tf, 0));
    for (k = 1; k <= 3; k++) {
        CHECK(plan_psi(t0, t0, tf, k) == 0.0 && plan_psi(tf, t0, tf, k) == 0.0, "order %d at the knots", k);
        CHECK(plan_psi(t0 - 1e-3, t0, tf, k) == 0.0 && plan_psi(tf + 1e-3, t0, tf, k) == 0.0, "order %d outside", k);
    }
    CHECK(plan_psi(0.03, t0, tf, 4) == 0.0 && plan_psi(0.03, t0, tf, -1) == 0.0, "orders out of range give 0");
    CHECK(plan_psi(0.03, tf, t0, 0) == 0.0, "tf <= t0 gives 0");
    // psi' = 1260 tau^4 (1 - tau)^5 / T, and each derivative is the central difference of the one below.
    CHECK(fabs(plan_psi(0.025, t0, tf, 1) - 1260 * pow(0.25, 4) * pow(0.75, 5) / 0.02) < 1e-12, "psi' closed form");
    for (i = 1; i < 20; i++) {
        t = t0 + (tf - t0) * i / 20.0;
        for (k = 1; k <= 3; k++) {
            fd = (plan_psi(t + h, t0, tf, k - 1) - plan_psi(t - h, t0, tf, k - 1)) / (2 * h);
            CHECK(fabs(fd - plan_psi(t, t0, tf, k)) <= 1e-5 * (1 + fabs(plan_psi(t, t0, tf, k))) * pow(50, k),
                  "order %d at t=%g: fd %.10g vs %.10g", k, t, fd, plan_psi(t, t0, tf, k));
        }
    }
    return 0;
}

// Returns 0; plan_init + plan_flag give plan_psi's values, and a NaN time a NaN angle with zero derivatives.
static int coef_checks(const struct plan *p)
{
    struct plan_coef c, tiny;
    struct plan bad = *p;
    double f[PLAN_FLAG_LEN], t;
    int i, k;
    CHECK(plan_init(&c, p), "plan_init accepts a valid plan");
    for (i = 0; i <= 40; i++) {
        t = 0.015 + 0.03 * i / 40.0;
        CHECK(plan_flag(&c, t, f) == (t > p->t0 && t < p->tf), "inside flag at t=%g", t);
        CHECK(f[PLAN_THETA] == p->theta1 + plan_psi(t, p->t0, p->tf, 0) * (p->theta2 - p->theta1), "theta at %g", t);
        for (k = 1; k <= 3; k++)
            CHECK(f[PLAN_THETA + k] == plan_psi(t, p->t0, p->tf, k) * (p->theta2 - p->theta1), "order %d at %g", k, t);
    }
    plan_flag(&c, NAN, f);
    CHECK(isnan(f[PLAN_THETA]) && f[PLAN_DTHETA] == 0 && f[PLAN_DDDTHETA] == 0, "NaN t: theta NaN, derivatives 0");
    bad.t0 = 0.0, bad.tf = 1e-200;  // the fuzzer's span: its cube underflows, so its derivatives must give 0
    CHECK(!plan_init(&tiny, &bad), "plan_init reports the invalid span");
    plan_flag(&tiny, 5e-201, f);
    CHECK(isfinite(f[PLAN_DTHETA]) && f[PLAN_DDDTHETA] == 0 && f[PLAN_DDTHETA] == 0, "tiny span: no division by 0");
    return 0;
}

// Returns 0; plan validity, the flag at the knots and the moving flag.
static int plan_checks(void)
{
    struct plan p = {0.0, 0.02, 0.4, 0.3, 0.02, 0.04, NULL}, bad = p;
    double f[PLAN_FLAG_LEN];
    CHECK(plan_valid(&p), "paper-like plan is valid");
    bad.rho2 = 0;
    CHECK(!plan_valid(&bad), "rho2 = 0 is invalid");
    bad = p, bad.tf = bad.t0;
    CHECK(!plan_valid(&bad), "tf = t0 is invalid");
    bad = p, bad.t0 = 0.0, bad.tf = 1e-200;  // found by the fuzzer: (tf - t0)^3 underflows to 0
    CHECK(!plan_valid(&bad) && plan_psi(5e-201, 0.0, 1e-200, 3) == 0.0, "a span whose cube underflows is invalid");
    bad = p, bad.theta1 = NAN;
    CHECK(!plan_valid(&bad), "NaN theta1 is invalid");
    // found by the fuzzer: theta2 - theta1 overflowed, and the held flag's derivatives 0 inf were NaN; psi's
    // rounding past 1 took rho1 + psi (rho2 - rho1) to -inf
    bad = p, bad.theta1 = -1e308, bad.theta2 = 1e308;
    plan_eval(&bad, 0.05, f);
    CHECK(!plan_valid(&bad) && isnan(f[PLAN_DTHETA]), "a move whose span overflows is invalid");
    bad = p, bad.rho1 = DBL_MAX, bad.rho2 = 4.4e291, bad.t0 = 7.3e-304, bad.tf = 0.040000000000055637;
    plan_eval(&bad, 0.04, f);
    CHECK(!plan_valid(&bad) && isinf(f[PLAN_RHO]), "a current beyond DBL_MAX / 4 is invalid");
    bad = p, bad.theta2 = DBL_MAX / 4, bad.rho1 = DBL_MAX / 4;
    CHECK(plan_valid(&bad) && plan_eval(&bad, 0.039999, f) && isfinite(f[PLAN_THETA]) && isfinite(f[PLAN_RHO]),
          "within DBL_MAX / 4 the flag is finite");
    CHECK(!plan_eval(&p, 0.01, f) && f[PLAN_THETA] == 0.0 && f[PLAN_RHO] == 0.4, "held at the start");
    CHECK(!plan_eval(&p, 0.05, f) && f[PLAN_THETA] == 0.02 && f[PLAN_RHO] == 0.3 && f[PLAN_DDDTHETA] == 0.0,
          "held at the end");
    CHECK(plan_eval(&p, 0.03, f) && fabs(f[PLAN_THETA] - 0.02 * 638 / 1024) < 1e-15
              && fabs(f[PLAN_RHO] - (0.4 - 0.1 * 638 / 1024)) < 1e-15,
          "halfway: theta %.17g rho %.17g", f[PLAN_THETA], f[PLAN_RHO]);
    CHECK(f[PLAN_DRHO] < 0 && f[PLAN_DTHETA] > 0, "moving: rho' %g theta' %g", f[PLAN_DRHO], f[PLAN_DTHETA]);
    return coef_checks(&p);
}

// Returns 0; the motor model and the flat maps against each other.
static int flat_checks(void)
{
    struct plan p = {0.0, 0.02, 0.4, 0.3, 0.02, 0.04, NULL};
    double f[PLAN_FLAG_LEN], g[PLAN_FLAG_LEN], x[4], v[2], dx[4], load = 1e-5;
    struct motor_params m = PAPER;
    int i, k;
    CHECK(motor_params_valid(&m), "paper motor is valid");
    m.Nr = 0;
    CHECK(!motor_params_valid(&m), "Nr = 0 is invalid");
    m = PAPER, m.B = -1e-9;
    CHECK(!motor_params_valid(&m), "B < 0 is invalid");
    m = PAPER, m.L = INFINITY;
    CHECK(!motor_params_valid(&m), "L = inf is invalid");
    for (i = 0; i <= 24; i++) {
        plan_eval(&p, 0.018 + 0.001 * i, f);
        CHECK(flat_to_state(&PAPER, f, load, x, v) == FLAT_OK, "f2s at sample %d", i);
        CHECK(state_to_flat(&PAPER, x, v, load, g) == FLAT_OK, "s2f at sample %d", i);
        for (k = 0; k < PLAN_FLAG_LEN; k++)
            CHECK(fabs(g[k] - f[k]) <= 1e-9 * (1 + fabs(f[k])), "round trip sample %d component %d: %.17g vs %.17g", i,
                  k, g[k], f[k]);
        // The model under the flat voltages moves exactly as planned: omega' = theta'', theta' = omega.
        motor_rhs(&PAPER, x, v, load, dx);
        CHECK(fabs(dx[2] - f[PLAN_DDTHETA]) <= 1e-9 * (1 + fabs(f[PLAN_DDTHETA])), "omega' %.17g vs %.17g", dx[2],
              f[PLAN_DDTHETA]);
        CHECK(dx[3] == x[2], "theta' = omega");
    }
    f[PLAN_RHO] = 0;
    CHECK(flat_to_state(&PAPER, f, 0, x, v) == FLAT_ERHO && v[0] == 0 && x[0] == 0, "rho = 0 is outside the domain");
    f[PLAN_RHO] = 0.4, f[PLAN_DDTHETA] = 1e5;
    CHECK(flat_to_state(&PAPER, f, 0, x, v) == FLAT_ESQRT && v[1] == 0, "|A| >= Km rho is outside the domain");
    CHECK(flat_voltages(&PAPER, 1e-300, 0, 0, 0, 0, 0, 0, 0, v) == FLAT_ESQRT, "rho sqrt underflow is caught");
    for (k = 0; k < PLAN_FLAG_LEN; k++)  // found by the fuzzer: the state was left set when the voltages failed
        f[k] = k == PLAN_RHO ? 1e-300 : 0;
    x[0] = x[1] = 1;
    CHECK(flat_to_state(&PAPER, f, 0, x, v) == FLAT_ESQRT && x[0] == 0 && x[1] == 0, "the state zeroed on FLAT_ESQRT");
    x[0] = x[1] = 0;
    CHECK(state_to_flat(&PAPER, x, v, 0, g) == FLAT_ERHO && g[PLAN_DDDTHETA] == 0, "ia = ib = 0 is caught");
    x[0] = 0.4, x[1] = 0, x[2] = 0, x[3] = 0;
    CHECK(fabs(motor_torque(&PAPER, x)) < 1e-18, "no torque at the start equilibrium");
    CHECK(motor_acceleration(&PAPER, x, 1e-5) == -1e-5 / 3.6e-6, "the load alone accelerates the rotor");
    return 0;
}

// Returns 0 after running the planner and flat-map checks.
int test_plan(void)
{
    psi_checks();
    plan_checks();
    flat_checks();
    return 0;
}
