// Dormand-Prince 5(4) (Hairer's DOPRI5: FSAL, PI step control, 4th-order dense output), the first-step
// heuristic both adaptive integrators share, and classical RK4.
#include "ode.h"

// Butcher tableau of DOPRI5 (a[i][j] for stage i+1), the error weights e and the dense-output weights d.
static const fs_real c_[7] = {0, FS_C(0.2), FS_C(0.3), FS_C(0.8), FS_C(8.0) / 9, 1, 1};
static const fs_real a_[7][6] = {
    {0},
    {FS_C(0.2)},
    {FS_C(3.0) / 40, FS_C(9.0) / 40},
    {FS_C(44.0) / 45, FS_C(-56.0) / 15, FS_C(32.0) / 9},
    {FS_C(19372.0) / 6561, FS_C(-25360.0) / 2187, FS_C(64448.0) / 6561, FS_C(-212.0) / 729},
    {FS_C(9017.0) / 3168, FS_C(-355.0) / 33, FS_C(46732.0) / 5247, FS_C(49.0) / 176, FS_C(-5103.0) / 18656},
    {FS_C(35.0) / 384, 0, FS_C(500.0) / 1113, FS_C(125.0) / 192, FS_C(-2187.0) / 6784, FS_C(11.0) / 84},
};
static const fs_real e_[7] = {
    FS_C(71.0) / 57600, 0, FS_C(-71.0) / 16695, FS_C(71.0) / 1920, FS_C(-17253.0) / 339200, FS_C(22.0) / 525,
    FS_C(-1.0) / 40};
static const fs_real d_[7] = {FS_C(-12715105075.0) / FS_C(11282082432.0),  0,
                              FS_C(87487479700.0) / FS_C(32700410799.0),   FS_C(-10690763975.0) / FS_C(1880347072.0),
                              FS_C(701980252875.0) / FS_C(199316789632.0), FS_C(-1453857185.0) / FS_C(822651844.0),
                              FS_C(69997945.0) / FS_C(29380423.0)};

// Step-size control constants of Hairer's code: safety factor, PI exponent beta, step ratio bounds.
#define SAFE FS_C(0.9)
#define BETA FS_C(0.04)
#define FAC_MIN FS_C(0.2)
#define FAC_MAX FS_C(10.0)
#define EPS_T FS_C(1e-14)

// Returns the calls' result of f, counting the evaluation.
static int eval(struct ode_dopri5 *s, fs_real t, const fs_real *x, fs_real *dx)
{
    s->rhs_evals++;
    return s->f(s->ctx, t, x, dx);
}

// Returns ODE_OK, or ODE_EARGS for bad parameters, dimension or start time.
int ode_check_args(const struct ode_params *p, size_t n, fs_real t)
{
    bool ok = n > 0 && n <= ODE_MAX_DIM && p->rtol > 0 && p->atol > 0 && p->h_max > 0 && fs_isfinite(t);
    return ok ? ODE_OK : ODE_EARGS;
}

// Returns the first step size for a method of the given order by Hairer's heuristic (one Euler step from
// (t, x) with slope f0 = f(t, x) estimates the second derivative), -1 when f fails there, or 0 when the step
// underflows (a slope so large against the state's scale that no step size fits).
fs_real ode_first_step(const struct ode_params *p, size_t n, ode_rhs_fn f, void *ctx, fs_real t, const fs_real *x,
                       const fs_real *f0, int order)
{
    fs_real dnf = 0, dny = 0, der2 = 0, sk, h, h1, der12, x1[ODE_MAX_DIM] = {0}, f1[ODE_MAX_DIM] = {0};
    size_t i;
    for (i = 0; i < n; i++) {
        sk = p->atol + p->rtol * fs_fabs(x[i]);
        dnf += (f0[i] / sk) * (f0[i] / sk);
        dny += (x[i] / sk) * (x[i] / sk);
    }
    h = (dnf <= FS_C(1e-10) || dny <= FS_C(1e-10)) ? FS_C(1e-6) : fs_sqrt(dny / dnf) * FS_C(0.01);
    h = fs_min(h, p->h_max);
    if (!(h > 0))
        return 0;  // dny / dnf underflowed: the slope dwarfs the state's scale, no step size fits
    for (i = 0; i < n; i++)
        x1[i] = x[i] + h * f0[i];
    if (f(ctx, t + h, x1, f1))
        return -1;
    for (i = 0; i < n; i++) {
        sk = p->atol + p->rtol * fs_fabs(x[i]);
        der2 += ((f1[i] - f0[i]) / sk) * ((f1[i] - f0[i]) / sk);
    }
    der12 = fs_max(fs_sqrt(der2) / h, fs_sqrt(dnf));
    h1 = der12 <= FS_C(1e-15) ? fs_max(FS_C(1e-6), h * FS_C(1e-3)) : fs_pow(FS_C(0.01) / der12, FS_C(1.0) / order);
    return fs_min(fs_min(100 * h, h1), p->h_max);
}

// Returns ODE_OK, ODE_EARGS for bad parameters or dimension, ODE_ERHS when f fails at (t, x), or ODE_EHMIN when
// the first step size underflows to 0; starts an integration at (t, x) and picks the first step size (Hairer's
// heuristic).
int ode_dopri5_init(struct ode_dopri5 *s, const struct ode_params *p, size_t n, ode_rhs_fn f, void *ctx, fs_real t,
                    const fs_real *x)
{
    size_t i;
    if (ode_check_args(p, n, t) != ODE_OK)
        return ODE_EARGS;
    s->p = *p;
    s->f = f;
    s->ctx = ctx;
    s->n = n;
    s->t = s->t_old = t;
    s->facold = FS_C(1e-4);
    s->steps = s->rejected = s->rhs_evals = 0;
    for (i = 0; i < n; i++)
        s->x[i] = x[i];
    if (eval(s, t, s->x, s->k[0]))
        return ODE_ERHS;
    s->rhs_evals++;
    s->h = ode_first_step(p, n, f, ctx, t, s->x, s->k[0], 5);
    return s->h > 0 ? ODE_OK : (s->h < 0 ? ODE_ERHS : ODE_EHMIN);
}

// Returns the scaled RMS error of a trial step from (x, k) to xn, or -1 when it is not finite.
static fs_real trial_error(const struct ode_dopri5 *s, const fs_real *xn, fs_real h)
{
    fs_real err = 0, sk, ei;
    size_t i;
    int j;
    for (i = 0; i < s->n; i++) {
        ei = 0;
        for (j = 0; j < 7; j++)
            ei += e_[j] * s->k[j][i];
        sk = s->p.atol + s->p.rtol * fs_max(fs_fabs(s->x[i]), fs_fabs(xn[i]));
        err += (h * ei / sk) * (h * ei / sk);
    }
    err = fs_sqrt(err / (fs_real)s->n);
    return fs_isfinite(err) ? err : -1;
}

// Returns 0, or nonzero when f failed; computes stages 2..7 and the 5th-order solution xn of a step h.
static int trial_step(struct ode_dopri5 *s, fs_real h, fs_real *xn)
{
    fs_real xs[ODE_MAX_DIM];
    size_t i;
    int j, m;
    for (j = 1; j < 7; j++) {
        for (i = 0; i < s->n; i++) {
            xs[i] = s->x[i];
            for (m = 0; m < j; m++)
                xs[i] += h * a_[j][m] * s->k[m][i];
        }
        if (j == 6)
            for (i = 0; i < s->n; i++)
                xn[i] = xs[i];
        if (eval(s, s->t + c_[j] * h, xs, s->k[j]))
            return 1;
    }
    return 0;
}

// Returns ODE_OK after one accepted step that ends at t_end at the latest (exactly at t_end when it reaches
// it), ODE_EHMIN when the step size falls below rounding level, ODE_ERHS when f keeps failing.
int ode_dopri5_step(struct ode_dopri5 *s, fs_real t_end)
{
    fs_real xn[ODE_MAX_DIM], h, err, fac11, fac, expo1 = FS_C(0.2) - BETA * FS_C(0.75);
    bool rejected = false, last, failed;
    size_t i;
    int j;
    for (;;) {
        h = fs_min(s->h, s->p.h_max);
        last = s->t + FS_C(1.01) * h >= t_end;
        if (last)
            h = t_end - s->t;
        if (!(h > EPS_T * fs_max(fs_fabs(s->t), 1)))
            return last && h == 0 ? ODE_OK : ODE_EHMIN;
        failed = trial_step(s, h, xn) != 0;
        err = failed ? -1 : trial_error(s, xn, h);
        if (err < 0 || err > 1) {
            // Reject: shrink by the error estimate, or tenfold when f failed or the trial was not finite.
            fac11 = err < 0 ? 0 : fs_pow(err, expo1);
            s->h = err < 0 ? h * FS_C(0.1) : h / fs_min(1 / FAC_MIN, fac11 / SAFE);
            s->rejected++;
            rejected = true;
            if (failed && !(s->h > EPS_T * fs_max(fs_fabs(s->t), 1)))
                return ODE_ERHS;
            continue;
        }
        fac11 = fs_pow(err, expo1);
        fac = fs_max(1 / FAC_MAX, fs_min(1 / FAC_MIN, fac11 / fs_pow(s->facold, BETA) / SAFE));
        s->facold = fs_max(err, FS_C(1e-4));
        for (i = 0; i < s->n; i++) {
            s->rcont[0][i] = s->x[i];
            s->rcont[1][i] = xn[i] - s->x[i];
            s->rcont[2][i] = h * s->k[0][i] - s->rcont[1][i];
            s->rcont[3][i] = s->rcont[1][i] - h * s->k[6][i] - s->rcont[2][i];
            s->rcont[4][i] = 0;
            for (j = 0; j < 7; j++)
                s->rcont[4][i] += h * d_[j] * s->k[j][i];
            s->x[i] = xn[i];
            s->k[0][i] = s->k[6][i];
        }
        s->t_old = s->t;
        s->t = last ? t_end : s->t + h;
        s->h = rejected ? fs_min(h / fac, h) : h / fac;
        s->steps++;
        return ODE_OK;
    }
}

// Returns nothing; writes the 4th-order dense-output state at t in [t_old, t] of the last step.
void ode_dopri5_dense(const struct ode_dopri5 *s, fs_real t, fs_real *x)
{
    fs_real h = s->t - s->t_old, th = h > 0 ? (t - s->t_old) / h : 1, th1 = 1 - th;
    size_t i;
    for (i = 0; i < s->n; i++)
        x[i] = s->rcont[0][i]
               + th * (s->rcont[1][i] + th1 * (s->rcont[2][i] + th * (s->rcont[3][i] + th1 * s->rcont[4][i])));
}

// Returns 0, or the first nonzero value of f; advances x (dimension n <= ODE_MAX_DIM) by one classical
// RK4 step of size h from t.
int ode_rk4_step(ode_rhs_fn f, void *ctx, size_t n, fs_real t, fs_real h, fs_real *x)
{
    fs_real k1[ODE_MAX_DIM], k2[ODE_MAX_DIM], k3[ODE_MAX_DIM], k4[ODE_MAX_DIM], xs[ODE_MAX_DIM];
    size_t i;
    int rc;
    if (n > ODE_MAX_DIM)
        return -1;
    if ((rc = f(ctx, t, x, k1)) != 0)
        return rc;
    for (i = 0; i < n; i++)
        xs[i] = x[i] + h / 2 * k1[i];
    if ((rc = f(ctx, t + h / 2, xs, k2)) != 0)
        return rc;
    for (i = 0; i < n; i++)
        xs[i] = x[i] + h / 2 * k2[i];
    if ((rc = f(ctx, t + h / 2, xs, k3)) != 0)
        return rc;
    for (i = 0; i < n; i++)
        xs[i] = x[i] + h * k3[i];
    if ((rc = f(ctx, t + h, xs, k4)) != 0)
        return rc;
    for (i = 0; i < n; i++)
        x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    return 0;
}
