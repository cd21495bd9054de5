// The time-optimal planner's phase plane: the speed-dependent envelope by Newton and the bang-bang move on it
// (flatstep.plan.envelope is the reference, operation for operation).
#include "time_optimal_stages.h"

#define TO_TOP_ACCEL FS_C(0.01)
#define TO_NEWTON_TOL (FS_REAL_EPSILON > FS_C(1e-12) ? 16 * FS_REAL_EPSILON : FS_C(1e-12))  // of i_max

// Returns the coefficients of h at speed w, floor f, cot k of the torque angle cap and squared bus v2.
struct to_hcoef to_hcoef(const struct motor_params *m, fs_real k, fs_real f, fs_real w, fs_real v2)
{
    struct to_hcoef hc;
    fs_real c = m->Km * w, e = (fs_real)m->Nr * w * m->L;
    hc.z = m->R * m->R + e * e, hc.opk = 1 + k * k, hc.kk = k * k, hc.f2 = f * f;
    hc.r2c = 2 * c * m->R, hc.ce2 = 2 * c * e, hc.cc = c * c, hc.v2 = v2;
    hc.dz = 2 * hc.z * hc.opk, hc.dr = hc.ce2 * k * k;
    return hc;
}

// Returns h(u) of the module's envelope (steady voltage squared less (gamma v_bus)^2); writes dh/du.
fs_real to_h(const struct to_hcoef *hc, fs_real u, fs_real *dh)
{
    fs_real root = fs_sqrt(hc->f2 + hc->kk * u * u);
    *dh = hc->dz * u + hc->r2c + hc->dr * u / root;
    return hc->z * (hc->opk * u * u + hc->f2) + hc->r2c * u + hc->ce2 * root + hc->cc - hc->v2;
}

// Returns the torque current bound on side sign (+1 or -1) of h (hc), the current cap cap and no torque within the
// bus: the cap, or Newton's root from outside, started at the previous grid point's root *prev when that lies
// outside (h > 0), else at the cap.
static fs_real newton_side(const struct to_limits *lim, const struct to_hcoef *hc, fs_real cap, fs_real sign,
                           fs_real *prev)
{
    fs_real dh, h, u = sign * cap, step, dh_prev, h_prev;
    int i;
    h = to_h(hc, u, &dh);
    if (!(h > 0))
        return *prev = u;
    if (sign * *prev < cap && sign * *prev > 0) {
        h_prev = to_h(hc, *prev, &dh_prev);
        if (h_prev > 0)
            u = *prev, h = h_prev, dh = dh_prev;
    }
    for (i = 0; i < 100; i++) {  // monotone: h is convex and the start lies outside its root
        step = h / dh;
        u -= step;
        if (!(fs_fabs(step) > TO_NEWTON_TOL * lim->i_max))
            break;
        h = to_h(hc, u, &dh);
    }
    return *prev = u;
}

// Returns nothing; writes the torque current bounds (iq_bounds) at speed w into *hi and *lo (with lo_too), both
// 0 where even no torque exceeds the bus; *hi and *lo come in as the previous grid point's roots (warm starts).
// trig holds sin, cos and cot of the torque angle cap.
static void iq_pair(const struct motor_params *m, const struct to_limits *lim, const fs_real trig[3], fs_real w,
                    fs_real v2, bool lo_too, fs_real *hi, fs_real *lo)
{
    fs_real f = to_floor_current(lim, w);
    fs_real room = lim->i_max * lim->i_max - f * f;
    fs_real cap = fs_sqrt(room > 0 ? room : 0) * trig[0];
    struct to_hcoef hc = to_hcoef(m, trig[2], f, w, v2);
    if (!(hc.z * hc.f2 + hc.ce2 * f + hc.cc - hc.v2 <= 0)) {  // h(0) as to_h rounds it: sqrt(f * f) is f
        *hi = *lo = 0;
        return;
    }
    newton_side(lim, &hc, cap, 1, hi);
    if (lo_too)
        newton_side(lim, &hc, cap, -1, lo);
}

// Returns the grid length (>= 2), or 0 when the motor cannot start; writes the envelope at gamma
// (envelope.envelope).
size_t to_envelope(const struct motor_params *m, const struct to_limits *lim, fs_real gamma, struct to_work *w)
{
    fs_real v2 = gamma * lim->v_bus * gamma * lim->v_bus, w_max = gamma * lim->v_bus / m->Km, top, hi = 0, lo = 0;
    fs_real acc, prev = 0, unused = 0, trig[3], thr = 0, x, x_prev = 0, a_prev = 0;
    size_t i;
    fs_sincos(lim->torque_angle_max, &trig[0], &trig[1]);
    trig[2] = trig[1] / trig[0];
    if (lim->speed_max > 0 && lim->speed_max < w_max)
        w_max = lim->speed_max;
    top = w_max;
    for (i = 0; i < TO_PROBE; i++) {  // the probe: where a+ first falls to TO_TOP_ACCEL of a+(0), interpolated
        x = to_linspace(0, w_max, TO_PROBE, i);
        iq_pair(m, lim, trig, x, v2, false, &prev, &unused);
        acc = (m->Km * prev - m->B * x) / m->J;
        if (i == 0) {
            if (!(acc > 0))
                return 0;
            thr = TO_TOP_ACCEL * acc;
        } else if (!(acc > thr)) {
            top = x_prev + (x - x_prev) * ((a_prev - thr) / (a_prev - acc));
            break;
        }
        x_prev = x, a_prev = acc;
    }
    for (i = 0; i < TO_GRID; i++) {
        fs_real x = to_linspace(0, top, TO_GRID, i);
        w->omega[i] = x;
        iq_pair(m, lim, trig, x, v2, true, &hi, &lo);
        w->ap[i] = (m->Km * hi - m->B * x) / m->J;
        w->am[i] = (m->Km * lo - m->B * x) / m->J;
        if (lim->accel_max > 0) {
            w->ap[i] = fs_min(w->ap[i], lim->accel_max);
            w->am[i] = fs_max(w->am[i], -lim->accel_max);
        }
    }
    w->ap[TO_GRID - 1] = fs_max(w->ap[TO_GRID - 1], FS_C(1e-12) * w->ap[0]);
    w->am[TO_GRID - 1] = fs_min(w->am[TO_GRID - 1], FS_C(1e-12) * w->am[0]);  // and left: braking at B = 0 is 0 there
    // the floor underflowed (a+(0) below 5e-312 rad/s^2), an acceleration is NaN, speed-up or braking is 0 inside
    // (a low bus fraction with little friction), or the top speed is 0 (a speed cap that underflowed): no envelope
    // to integrate (its times would divide by 0). A speed-up a little below 0 next to the top speed (the grid
    // straddling where it crosses 0) is integrated as the reference integrates it; a phase that runs backwards
    // is refused by to_bang_bang.
    for (i = 0; i < TO_GRID; i++)
        if (!(fs_isfinite(w->ap[i]) && fs_isfinite(w->am[i]) && w->ap[i] != 0 && w->am[i] != 0))
            return 0;
    if (!(w->omega[TO_GRID - 1] > 0))
        return 0;
    w->integrals = false;
    return TO_GRID;
}

// Returns y at x by linear interpolation in the increasing xs (numpy.interp, ends held).
fs_real to_interp(fs_real x, const fs_real *xs, const fs_real *ys, size_t n)
{
    size_t lo = 0, hi = n - 1, mid;
    if (x <= xs[0])
        return ys[0];
    if (x >= xs[n - 1])
        return ys[n - 1];
    while (hi - lo > 1) {
        mid = (lo + hi) / 2;
        if (xs[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return xs[hi] == xs[lo] ? ys[lo] : (ys[hi] - ys[lo]) / (xs[hi] - xs[lo]) * (x - xs[lo]) + ys[lo];
}

// Returns nothing; writes the running trapezoidal integral out[i] of y over the uniform or given x.
static void cumtrapz(const fs_real *y, const fs_real *x, fs_real dx, size_t n, fs_real *out)
{
    size_t i;
    out[0] = 0;
    for (i = 1; i < n; i++)
        out[i] = out[i - 1] + FS_C(0.5) * (y[i] + y[i - 1]) * (x ? x[i] - x[i - 1] : dx);
}

// Returns nothing; writes the bang-bang move over distance d > 0 on the envelope and its sampling at width
// (envelope.bang_bang and smoothing.timing).
void to_bang_bang(fs_real d, fs_real width, struct to_work *w, struct to_move *mv)
{
    size_t i, g = TO_GRID;
    long keep, first, last;
    fs_real total, dt, core, x;
    // the integrands, then their running integrals in place, once per envelope (every width and distance reads them)
    for (i = 0; i < g && !w->integrals; i++) {
        w->tacc[i] = 1 / w->ap[i];
        w->tdec[i] = 1 / -w->am[i];
        w->dboth[i] = w->omega[i] / w->ap[i] + w->omega[i] / -w->am[i];
    }
    if (!w->integrals) {
        cumtrapz(w->tacc, w->omega, 0, g, w->a);
        cumtrapz(w->tdec, w->omega, 0, g, w->b);
        cumtrapz(w->dboth, w->omega, 0, g, w->c);
        for (i = 0; i < g; i++)
            w->tacc[i] = w->a[i], w->tdec[i] = w->b[i], w->dboth[i] = w->c[i];
        w->integrals = true;
    }
    if (d >= w->dboth[g - 1]) {
        mv->w_peak = w->omega[g - 1];
        mv->cruise = (d - w->dboth[g - 1]) / w->omega[g - 1];
    } else {
        mv->w_peak = to_interp(d, w->dboth, w->omega, g);
        mv->cruise = 0;
    }
    mv->t1 = to_interp(mv->w_peak, w->omega, w->tacc, g);
    mv->t2 = to_interp(mv->w_peak, w->omega, w->tdec, g);
    total = mv->t1 + mv->cruise + mv->t2;
    core = mv->t1 + mv->t2 + fs_min(mv->cruise, 4 * width) + 2 * width;
    dt = fs_min(core / TO_FINE, fs_min(fs_min(mv->t1, mv->t2), width) / TO_PER_PHASE);
    mv->dt = dt = fs_max(dt, core / TO_FINE_MAX);
    if (!(dt > 0)) {  // nothing to sample (denormal widths and speeds, or NaN): refused by the caller
        mv->n_box = 1, mv->n = (size_t)TO_MAX_SAMPLES + 1, mv->r = mv->k = 0;
        return;
    }
    x = fs_rint(width / dt);  // numpy's round: half to even, as rint in the default rounding mode
    mv->n_box = x >= 1 ? (size_t)fs_min(x, TO_MAX_SAMPLES) : 1;  // 1 for a NaN x (no cast): refused below
    x = total / dt;
    // too long to sample (and to cast), NaN, or a phase of negative duration (an envelope whose acceleration is
    // not > 0 inside, at a low bus fraction with little friction): refused by the caller
    if (!(x >= 0 && x < TO_MAX_SAMPLES && mv->t1 >= 0 && mv->t2 >= 0)) {
        mv->n = (size_t)TO_MAX_SAMPLES + 1, mv->r = mv->k = 0;
        return;
    }
    mv->n = (size_t)x + (x > (fs_real)(size_t)x) + 1;  // ceil(total / dt) + 1
    // the cut: inside the raw cruise (from ceil(t1 / dt) + 1 to floor((t1 + cruise) / dt) - 1), 2 n_box + 4
    // samples kept at each end
    keep = 2 * (long)mv->n_box + 4;
    x = mv->t1 / dt;
    first = (long)x + (x > (fs_real)(long)x) + 1;
    last = (long)((mv->t1 + mv->cruise) / dt) - 1;
    mv->r = (size_t)(first + keep);
    mv->k = last - keep - (first + keep) > 0 ? (size_t)(last - keep - (first + keep)) : 0;
}
