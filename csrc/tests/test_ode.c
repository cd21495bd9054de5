// The integrators on problems with known solutions: accuracy, dense output, order, landing on t_end.
#include "check.h"
#include "ode.h"

// Returns 0; x' = A x for the harmonic oscillator x = (cos t, -sin t) and decay x3' = -2 x3.
static int osc(void *ctx, double t, const double *x, double *dx)
{
    (void)ctx, (void)t;
    dx[0] = x[1];
    dx[1] = -x[0];
    dx[2] = -2 * x[2];
    return 0;
}

// Returns 1 (a failing right-hand side) beyond t = 0.5, 0 before.
static int wall(void *ctx, double t, const double *x, double *dx)
{
    (void)ctx;
    dx[0] = x[0];
    return t > 0.5;
}

// Returns 0; a slope of 1e300 (fuzz/regressions/continuous/first-step-underflow): (f0 / sk)^2 overflows.
static int steep(void *ctx, double t, const double *x, double *dx)
{
    (void)ctx, (void)t, (void)x;
    dx[0] = 1e300;
    return 0;
}

// Returns the largest error of the oscillator state at t against the exact solution.
static double osc_error(const double *x, double t)
{
    double e0 = fabs(x[0] - cos(t)), e1 = fabs(x[1] + sin(t)), e2 = fabs(x[2] - exp(-2 * t));
    return fmax(e0, fmax(e1, e2));
}

// Returns nothing; integrates the oscillator from 0 to 2 with DOP853 at the fixed step 2/n (tolerances too
// loose to reject or change it) and writes the end error and the worst dense and Hermite errors at midsteps.
static void dop853_fixed(int n, double *e_end, double *e_dense, double *e_hermite)
{
    struct ode_params p = {1e10, 1e10, 2.0 / n};
    struct ode_dop853 s;
    double x0[3] = {1, 0, 1}, x[3], tm;
    ode_dop853_init(&s, &p, 3, osc, NULL, 0.0, x0);
    s.h = 2.0 / n;
    *e_dense = *e_hermite = 0;
    while (s.t < 2.0 && ode_dop853_step(&s, 2.0) == ODE_OK) {
        tm = 0.5 * (s.t_old + s.t);
        ode_dop853_dense(&s, tm, x);
        *e_dense = fmax(*e_dense, osc_error(x, tm));
        ode_dop853_hermite(&s, tm, x);
        *e_hermite = fmax(*e_hermite, osc_error(x, tm));
    }
    *e_end = osc_error(s.x, 2.0);
}

// Returns 0 after checking DOP853: accuracy, order 8 of the steps, orders of the two interpolants, failures.
static int test_dop853(void)
{
    struct ode_params p = {1e-10, 1e-12, 1.0};
    struct ode_dop853 s;
    double x0[3] = {1, 0, 1}, x[3], worst_dense = 0, t, e[2], d[2], h[2];
    int rc = ODE_OK, k;
    CHECK(ode_dop853_init(&s, &p, 3, osc, NULL, 0.0, x0) == ODE_OK, "dop853 init");
    while (rc == ODE_OK && s.t < 10.0) {
        rc = ode_dop853_step(&s, 10.0);
        for (t = s.t_old; t < s.t; t += (s.t - s.t_old) / 7) {
            CHECK(ode_dop853_dense(&s, t, x) == ODE_OK, "dense");
            worst_dense = fmax(worst_dense, osc_error(x, t));
        }
    }
    CHECK(rc == ODE_OK && s.t == 10.0, "dop853 landed on t_end exactly: rc %d t %.17g", rc, s.t);
    CHECK(osc_error(s.x, 10.0) < 1e-9, "DOP853 error at t = 10: %g", osc_error(s.x, 10.0));
    CHECK(worst_dense < 1e-9, "DOP853 dense output error %g", worst_dense);
    CHECK(s.rhs_evals == 12 * s.steps + 2 + 11 * s.rejected + 3 * s.steps, "%u evals for %u steps", s.rhs_evals,
          s.steps);
    printf("  dop853 oscillator to t=10: %u steps, %u rejected, error %.2g, dense error %.2g\n", s.steps, s.rejected,
           osc_error(s.x, 10.0), worst_dense);
    // Orders at fixed steps h = 0.2 and 0.1: the steps are 8th order (error ratio ~2^8), the dense output
    // 7th order or better, the Hermite interpolant 4th order (ratio ~2^4).
    for (k = 0; k < 2; k++)
        dop853_fixed(10 << k, &e[k], &d[k], &h[k]);
    printf("  dop853 fixed h 0.2 -> 0.1: end error %.3g -> %.3g, dense %.3g -> %.3g, hermite %.3g -> %.3g\n", e[0],
           e[1], d[0], d[1], h[0], h[1]);
    CHECK(e[0] / e[1] > 200 && e[0] / e[1] < 320, "DOP853 order: error ratio %g", e[0] / e[1]);
    CHECK(d[0] / d[1] > 100 && d[0] / d[1] < 320, "dense output order: error ratio %g", d[0] / d[1]);
    CHECK(h[0] / h[1] > 12 && h[0] / h[1] < 20, "Hermite order: error ratio %g", h[0] / h[1]);
    // A right-hand side that fails beyond t = 0.5 stops the integration with ODE_ERHS before t = 0.5.
    p.rtol = 1e-5, p.atol = 1e-7;
    ode_dop853_init(&s, &p, 1, wall, NULL, 0.0, x0);
    rc = ODE_OK;
    while (rc == ODE_OK && s.t < 1.0)
        rc = ode_dop853_step(&s, 1.0);
    CHECK(rc == ODE_ERHS && s.t <= 0.5, "dop853 failing rhs: rc %d at t %g", rc, s.t);
    CHECK(ode_dop853_init(&s, &p, ODE_MAX_DIM + 1, osc, NULL, 0.0, x0) == ODE_EARGS, "n too large");
    p.atol = 0;
    CHECK(ode_dop853_init(&s, &p, 3, osc, NULL, 0.0, x0) == ODE_EARGS, "atol = 0");
    return 0;
}

// Returns 0 after checking DOPRI5, DOP853 and RK4.
int test_ode(void)
{
    struct ode_params p = {1e-10, 1e-12, 1.0};
    struct ode_dopri5 s;
    struct ode_dop853 s853;
    double x0[3] = {1, 0, 1}, x[3], worst_dense = 0, e1, e2, t;
    int rc = ODE_OK, k, n;
    CHECK(ode_dopri5_init(&s, &p, 3, osc, NULL, 0.0, x0) == ODE_OK, "init");
    while (rc == ODE_OK && s.t < 10.0) {
        rc = ode_dopri5_step(&s, 10.0);
        for (t = s.t_old; t < s.t; t += (s.t - s.t_old) / 7) {
            ode_dopri5_dense(&s, t, x);
            worst_dense = fmax(worst_dense, osc_error(x, t));
        }
    }
    CHECK(rc == ODE_OK && s.t == 10.0, "landed on t_end exactly: rc %d t %.17g", rc, s.t);
    CHECK(osc_error(s.x, 10.0) < 1e-8, "DOPRI5 error at t = 10: %g", osc_error(s.x, 10.0));
    CHECK(worst_dense < 1e-8, "dense output error %g", worst_dense);
    CHECK(s.steps > 20 && s.steps < 2000, "%u steps", s.steps);
    printf("  dopri5 oscillator to t=10: %u steps, %u rejected, error %.2g, dense error %.2g\n", s.steps, s.rejected,
           osc_error(s.x, 10.0), worst_dense);
    // A looser tolerance takes fewer steps and is less accurate: the error control is live.
    p.rtol = 1e-5, p.atol = 1e-7;
    ode_dopri5_init(&s, &p, 3, osc, NULL, 0.0, x0);
    k = s.steps;
    while (s.t < 10.0 && ode_dopri5_step(&s, 10.0) == ODE_OK)
        k++;
    CHECK(k < 200 && osc_error(s.x, 10.0) > 1e-9 && osc_error(s.x, 10.0) < 1e-3, "loose: %d steps error %g", k,
          osc_error(s.x, 10.0));
    // A right-hand side that fails beyond t = 0.5 stops the integration with ODE_ERHS before t = 0.5.
    ode_dopri5_init(&s, &p, 1, wall, NULL, 0.0, x0);
    rc = ODE_OK;
    while (rc == ODE_OK && s.t < 1.0)
        rc = ode_dopri5_step(&s, 1.0);
    CHECK(rc == ODE_ERHS && s.t <= 0.5, "failing rhs: rc %d at t %g", rc, s.t);
    CHECK(ode_dopri5_init(&s, &p, 0, osc, NULL, 0.0, x0) == ODE_EARGS, "n = 0");
    // a slope that dwarfs the state's scale: no first step fits, ODE_EHMIN (not a failing right-hand side)
    CHECK(ode_dopri5_init(&s, &p, 1, steep, NULL, 0.0, x0) == ODE_EHMIN && s.h == 0, "steep: h %g", s.h);
    CHECK(ode_dop853_init(&s853, &p, 1, steep, NULL, 0.0, x0) == ODE_EHMIN && s853.h == 0, "steep 853: h %g", s853.h);
    p.rtol = 0;
    CHECK(ode_dopri5_init(&s, &p, 3, osc, NULL, 0.0, x0) == ODE_EARGS, "rtol = 0");
    // RK4 is 4th order: halving the step divides the error by ~16.
    for (k = 0, e1 = e2 = 0; k < 2; k++) {
        n = 100 << k;
        x[0] = 1, x[1] = 0, x[2] = 1;
        for (int j = 0; j < n; j++)
            ode_rk4_step(osc, NULL, 3, j * (2.0 / n), 2.0 / n, x);
        if (k == 0)
            e1 = osc_error(x, 2.0);
        else
            e2 = osc_error(x, 2.0);
    }
    CHECK(e1 / e2 > 14 && e1 / e2 < 18, "RK4 error ratio %g (errors %g, %g)", e1 / e2, e1, e2);
    CHECK(ode_rk4_step(wall, NULL, 1, 0.6, 0.1, x) == 1, "RK4 passes on the rhs failure");
    return test_dop853();
}
