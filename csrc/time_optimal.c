// The time-optimal planner: envelope by Newton, bang-bang phase plane, double box smoothing, Hermite table,
// regula falsi on the bus fraction (flatstep.plan.time_optimal is the reference, operation for operation).
#include "time_optimal.h"
#include <string.h>

#define TO_GAMMA_MIN FS_C(0.05)
#define TO_TOP_ACCEL FS_C(0.01)
#define TO_S_TOL FS_C(0.003)
#define TO_ANGLE_PLAN FS_C(0.98)
#define TO_CAP_PLAN FS_C(0.995)
#define TO_GAMMA_STEPS FS_C(65536.0)  // 2^16
#define TO_V_MARGIN FS_C(0.998)
#define TO_PEAK_OVER_STEADY FS_C(0.994)  // a table's peak voltage over the steady one at its peak speed
#define TO_NEWTON_TOL (FS_REAL_EPSILON > FS_C(1e-12) ? 16 * FS_REAL_EPSILON : FS_C(1e-12))  // of i_max
#define TO_FINE_LEN (TO_FINE_MAX + 2)

// Scratch arrays carved out of the caller's workspace.
struct to_work {
    fs_real *omega, *ap, *am, *tacc, *tdec, *dboth;  // TO_GRID each: the envelope and its integrals
    fs_real *a, *b, *c;                              // TO_FINE_LEN + 1 each: the sampled profile
    fs_real *knot;                                   // TO_MAX_SEGMENTS + 1 sample indices
    bool integrals;                                  // tacc, tdec and dboth hold the envelope's integrals
    struct traj tr;                                  // the candidate table over the arrays below
    fs_real *breaks, *theta, *rho;
};

// The bang-bang move of time_optimal.bang_bang and the sampling of time_optimal.timing.
struct to_move {
    fs_real t1, cruise, t2, w_peak, dt;
    size_t n_box, n;
    size_t r, k;  // the cut: k samples of the cruise from sample r on are not sampled
};

size_t time_optimal_work_len(void)
{
    return 6 * (size_t)TO_GRID + 3 * ((size_t)TO_FINE_LEN + 1) + (TO_MAX_SEGMENTS + 1) * 2
           + 2 * (size_t)TO_MAX_SEGMENTS * TRAJ_NCOEF;
}

// Returns the across-axis floor f(omega) (MotorLimits.floor).
static fs_real floor_current(const struct to_limits *lim, fs_real w)
{
    fs_real x = w / lim->speed_corner;
    return lim->i_run + (lim->i_hold - lim->i_run) / (1 + x * x);
}

// Returns element i of numpy.linspace(start, stop, num) as numpy computes it: i (stop - start) / (num - 1) + start,
// the last element stop itself (the knots are rounded from these: the same rounding gives the same knots).
static fs_real linspace(fs_real start, fs_real stop, size_t num, size_t i)
{
    return i == num - 1 ? stop : (fs_real)i * ((stop - start) / (fs_real)(num - 1)) + start;
}

// The envelope's h(u) at one speed: its products of the speed's terms, formed once (to_h then rounds as the
// reference's _h does, operation for operation).
struct to_hcoef {
    fs_real z, opk, kk, f2, r2c, ce2, cc, v2, dz, dr;
};

// Returns the coefficients of h at speed w, floor f, cot k of the torque angle cap and squared bus v2.
static struct to_hcoef to_hcoef(const struct motor_params *m, fs_real k, fs_real f, fs_real w, fs_real v2)
{
    struct to_hcoef hc;
    fs_real c = m->Km * w, e = (fs_real)m->Nr * w * m->L;
    hc.z = m->R * m->R + e * e, hc.opk = 1 + k * k, hc.kk = k * k, hc.f2 = f * f;
    hc.r2c = 2 * c * m->R, hc.ce2 = 2 * c * e, hc.cc = c * c, hc.v2 = v2;
    hc.dz = 2 * hc.z * hc.opk, hc.dr = hc.ce2 * k * k;
    return hc;
}

// Returns h(u) of the module's envelope (steady voltage squared less (gamma v_bus)^2); writes dh/du.
static fs_real to_h(const struct to_hcoef *hc, fs_real u, fs_real *dh)
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
    fs_real f = floor_current(lim, w);
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
// (time_optimal.envelope).
static size_t envelope(const struct motor_params *m, const struct to_limits *lim, fs_real gamma, struct to_work *w)
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
        x = linspace(0, w_max, TO_PROBE, i);
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
        fs_real x = linspace(0, top, TO_GRID, i);
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
    w->integrals = false;
    return TO_GRID;
}

// Returns y at x by linear interpolation in the increasing xs (numpy.interp, ends held).
static fs_real interp(fs_real x, const fs_real *xs, const fs_real *ys, size_t n)
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

// Returns y at x as interp does, for x rising (dir 1) or falling (dir -1) between calls: *j walks to the bracket.
static fs_real interp_walk(fs_real x, const fs_real *xs, const fs_real *ys, size_t n, size_t *j)
{
    if (x <= xs[0])
        return ys[0];
    if (x >= xs[n - 1])
        return ys[n - 1];
    while (*j + 1 < n - 1 && xs[*j + 1] <= x)
        ++*j;
    while (*j > 0 && xs[*j] > x)
        --*j;
    return (ys[*j + 1] - ys[*j]) / (xs[*j + 1] - xs[*j]) * (x - xs[*j]) + ys[*j];
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
// (time_optimal.bang_bang and time_optimal.timing).
static void bang_bang(fs_real d, fs_real width, struct to_work *w, struct to_move *mv)
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
        mv->w_peak = interp(d, w->dboth, w->omega, g);
        mv->cruise = 0;
    }
    mv->t1 = interp(mv->w_peak, w->omega, w->tacc, g);
    mv->t2 = interp(mv->w_peak, w->omega, w->tdec, g);
    total = mv->t1 + mv->cruise + mv->t2;
    core = mv->t1 + mv->t2 + fs_min(mv->cruise, 4 * width) + 2 * width;
    dt = fs_min(core / TO_FINE, fs_min(fs_min(mv->t1, mv->t2), width) / TO_PER_PHASE);
    mv->dt = dt = fs_max(dt, core / TO_FINE_MAX);
    x = fs_rint(width / dt);  // numpy's round: half to even, as rint in the default rounding mode
    mv->n_box = x < 1 ? 1 : (size_t)x;
    x = total / dt;
    if (!(x < TO_MAX_SAMPLES)) {  // too long to sample (and to cast): refused by the caller
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

// Returns the length of x after a box of n samples: x convolved with it through the running sum in s
// (time_optimal._box; out may not alias x).
static size_t box(const fs_real *x, size_t len, size_t n, fs_real *s, fs_real *out)
{
    size_t i, out_len = len + n - 1;
    fs_real unit = 1 / (fs_real)n;  // the box's height (unit area)
    for (i = 0; i < n; i++)         // the running sum of x padded by n - 1 zeros at each end
        s[i] = 0;
    for (i = 0; i < len; i++)
        s[n + i] = s[n - 1 + i] + x[i];
    for (i = n + len; i < len + 2 * n - 1; i++)
        s[i] = s[i - 1];
    for (i = 0; i < out_len; i++)
        out[i] = (s[i + n] - s[i]) * unit;
    return out_len;
}

// Returns the central difference of x at i (one-sided at the ends) over dt (time_optimal._gradient).
static fs_real gradient(const fs_real *x, size_t len, size_t i, fs_real dt)
{
    if (i == 0)
        return (x[1] - x[0]) / dt;
    if (i == len - 1)
        return (x[len - 1] - x[len - 2]) / dt;
    return (x[i + 1] - x[i - 1]) / (2 * dt);
}

// Returns the second difference of x at i: the gradient of the gradient (time_optimal._gradient twice).
static fs_real gradient2(const fs_real *x, size_t len, size_t i, fs_real dt)
{
    if (i == 0)
        return (gradient(x, len, 1, dt) - gradient(x, len, 0, dt)) / dt;
    if (i == len - 1)
        return (gradient(x, len, len - 1, dt) - gradient(x, len, len - 2, dt)) / dt;
    return (gradient(x, len, i + 1, dt) - gradient(x, len, i - 1, dt)) / (2 * dt);
}

// Returns the number of knots; writes their sample indices (time_optimal._knots).
static size_t knots(size_t last, fs_real up, fs_real down, int cruise, fs_real *k)
{
    fs_real a = fs_min(fs_max(up, 0), (fs_real)last), b = fs_min(fs_max(down, 0), (fs_real)last), x;
    size_t i, n = 0, half = TO_KNOTS / 2;
    fs_real mid = (fs_real)last / 2;
    for (i = 0; i <= 2 * half + 4; i++) {
        if (cruise && b > a) {
            if (i <= half)
                x = linspace(0, a, half + 1, i);
            else if (i <= half + 4)
                x = linspace(a, b, 5, i - half);
            else
                x = linspace(b, (fs_real)last, half + 1, i - half - 4);
        } else {
            if (i > 2 * half)
                break;
            x = i <= half ? linspace(0, mid, half + 1, i) : linspace(mid, (fs_real)last, half + 1, i - half);
        }
        x = fs_rint(x);
        if (n == 0 || x != k[n - 1])
            k[n++] = x;
    }
    return n;
}

// The inverse of the degree-7 Hermite system of segments.hermite_rows: coefficients (tau^7 .. tau^0) from the
// ends' (theta, theta' h, theta'' h^2, theta''' h^3).
static const fs_real HERMITE[8][8] = {
    {20, 10, 2, FS_C(1.0) / 6, -20, 10, -2, FS_C(1.0) / 6},
    {-70, -36, FS_C(-7.5), FS_C(-2.0) / 3, 70, -34, FS_C(6.5), FS_C(-0.5)},
    {84, 45, 10, 1, -84, 39, -7, FS_C(0.5)},
    {-35, -20, -5, FS_C(-2.0) / 3, 35, -15, FS_C(2.5), FS_C(-1.0) / 6},
    {0, 0, 0, FS_C(1.0) / 6, 0, 0, 0, 0},
    {0, 0, FS_C(0.5), 0, 0, 0, 0, 0},
    {0, 1, 0, 0, 0, 0, 0, 0},
    {1, 0, 0, 0, 0, 0, 0, 0},
};

// Returns nothing; writes the row (TRAJ_NCOEF, three leading zeros) of the segment from s0 to s1 over h.
static void hermite_row(const fs_real s0[4], const fs_real s1[4], fs_real h, fs_real *row)
{
    fs_real rhs[8], p = 1;
    int i, j;
    for (j = 0; j < 4; j++, p *= h)
        rhs[j] = s0[j] * p, rhs[4 + j] = s1[j] * p;
    for (i = 0; i < 3; i++)
        row[i] = 0;
    for (i = 0; i < 4; i++) {  // tau^7 .. tau^4 from both ends
        fs_real sum = 0;
        for (j = 0; j < 8; j++)
            sum += HERMITE[i][j] * rhs[j];
        row[3 + i] = sum;
    }
    for (i = 4; i < 8; i++)  // tau^3 .. tau^0: the start's own derivatives
        row[3 + i] = HERMITE[i][7 - i] * rhs[7 - i];
}

// Returns the planned rho* at torque current iq and speed w (MotorLimits.rho); cot is cot(torque_angle_max).
static fs_real rho_star(const struct to_limits *lim, fs_real cot, fs_real iq, fs_real w)
{
    fs_real f = floor_current(lim, w), q = iq * cot;
    return fs_sqrt(iq * iq + (f * f + q * q));
}

// Returns rho* at sample i of the scaled speed profile v (len samples, step dt).
static fs_real rho_at(const struct motor_params *m, const struct to_limits *lim, fs_real cot, const fs_real *v,
                      size_t len, size_t i, fs_real dt)
{
    return rho_star(lim, cot, (m->J * gradient(v, len, i, dt) + m->B * v[i]) / m->Km, v[i]);
}

// Returns true and builds the candidate table w->tr of the move over d > 0 at width (time_optimal.smoothed_table);
// false when the profile would not fit the workspace.
static bool smoothed_table(const struct motor_params *m, const struct to_limits *lim, fs_real d, fs_real width,
                           struct to_work *w)
{
    struct to_move mv;
    fs_real total, t, *speed = w->a, *inc = w->c, scale, cruise, sum, angle = 0, step, s0[4], s1[4], r0[4], r1[4], h;
    size_t i, j, len, nk, last, at, at0 = 0, r, j_acc = 0, j_dec = TO_GRID - 2;
    fs_real cot = fs_cos(lim->torque_angle_max) / fs_sin(lim->torque_angle_max);
    bang_bang(d, width, w, &mv);
    total = mv.t1 + mv.cruise + mv.t2;
    if (mv.n > TO_MAX_SAMPLES || mv.n - mv.k + 2 * (mv.n_box - 1) > TO_FINE_LEN)
        return false;
    for (i = 0; i < mv.n - mv.k; i++) {  // sample i >= r at (i + k) dt: the cut is not sampled
        t = (fs_real)(i < mv.r ? i : i + mv.k) * mv.dt;
        if (t <= mv.t1)
            speed[i] = interp_walk(t, w->tacc, w->omega, TO_GRID, &j_acc);
        else if (t < mv.t1 + mv.cruise)
            speed[i] = mv.w_peak;
        else
            speed[i] = interp_walk(total - t, w->tdec, w->omega, TO_GRID, &j_dec);
    }
    speed[mv.n - mv.k - 1] = 0;
    len = box(speed, mv.n - mv.k, mv.n_box, w->c, w->b);
    len = box(w->b, len, mv.n_box, w->c, speed);
    sum = 0;
    for (i = 0; i + 1 < len; i++) {  // the trapezoids of the angle
        inc[i] = FS_C(0.5) * (speed[i + 1] + speed[i]) * mv.dt;
        sum += inc[i];
    }
    r = mv.r < len - 1 ? mv.r : len - 1;  // no cut (k = 0): r only has to index the profile
    cruise = mv.k ? speed[r] : 0;
    scale = d / (sum + (fs_real)mv.k * mv.dt * cruise);
    for (i = 0; i < len; i++)
        speed[i] *= scale;
    last = len - 1;
    // the cruise's knots 4 samples inside it (time_optimal.smoothed_table)
    nk = knots(last + mv.k, (mv.t1 + 2 * width) / mv.dt + 4, (mv.t1 + mv.cruise) / mv.dt - 4, mv.cruise > 0, w->knot);
    if (nk < 2)
        return false;
    w->tr.n = nk - 1;
    w->breaks[0] = 0;
    for (i = 0; i < nk; i++) {
        size_t k = (size_t)w->knot[i];
        // the sample the knot reads: itself before the cut, the constant cruise in it, k earlier after it
        at = k < r ? k : k >= r + mv.k ? k - mv.k : r;
        s1[0] = 0;
        s1[1] = speed[at];
        s1[2] = gradient(speed, len, at, mv.dt);
        s1[3] = gradient2(speed, len, at, mv.dt);
        r1[0] = rho_at(m, lim, cot, speed, len, at, mv.dt);
        r1[1] = at == 0 ? (rho_at(m, lim, cot, speed, len, 1, mv.dt) - r1[0]) / mv.dt
                : at == last
                    ? (r1[0] - rho_at(m, lim, cot, speed, len, last - 1, mv.dt)) / mv.dt
                    : (rho_at(m, lim, cot, speed, len, at + 1, mv.dt) - rho_at(m, lim, cot, speed, len, at - 1, mv.dt))
                          / (2 * mv.dt);
        r1[2] = r1[3] = 0;
        if (i == 0 || i == nk - 1)
            s1[1] = s1[2] = s1[3] = 0;
        if (i > 0) {
            size_t k0 = (size_t)w->knot[i - 1], c0 = k0 < r ? r : k0 > r + mv.k ? r + mv.k : k0;
            size_t c1 = k < r ? r : k > r + mv.k ? r + mv.k : k;
            // the angle from the last knot: the trapezoids between their samples and the cut's samples between them
            sum = 0;
            for (j = at0; j < at; j++)
                sum += inc[j];
            step = (sum + (fs_real)(c1 - c0) * mv.dt * cruise) * scale;
            if (i == nk - 1)
                step = d - angle;  // the move ends at the distance
            h = (w->knot[i] - w->knot[i - 1]) * mv.dt;
            w->breaks[i] = w->breaks[i - 1] + h;
            s1[0] = step;  // each segment from 0 to its step, its start angle added after (module docstring)
            hermite_row(s0, s1, h, w->theta + (i - 1) * TRAJ_NCOEF);
            w->theta[(i - 1) * TRAJ_NCOEF + TRAJ_NCOEF - 1] += angle;
            hermite_row(r0, r1, h, w->rho + (i - 1) * TRAJ_NCOEF);
            angle += step;
        }
        at0 = at;
        memcpy(s0, s1, sizeof s0);
        s0[0] = 0;
        memcpy(r0, r1, sizeof r0);
    }
    return true;
}

// Returns p(tau) of the coefficients c[0..deg] (highest power first) by Horner's rule.
static fs_real horner(const fs_real *c, int deg, fs_real tau)
{
    fs_real out = c[0];
    int j;
    for (j = 1; j <= deg; j++)
        out = out * tau + c[j];
    return out;
}

// Horner's rule on 5 to 8 coefficients (highest power first), unrolled: what horner does for those degrees.
#define HORNER5(c, t) ((((c[0] * (t) + c[1]) * (t) + c[2]) * (t) + c[3]) * (t) + c[4])
#define HORNER6(c, t) (HORNER5(c, t) * (t) + c[5])
#define HORNER7(c, t) (HORNER6(c, t) * (t) + c[6])
#define HORNER8(c, t) (HORNER7(c, t) * (t) + c[7])

// Returns the degree of the k-th time derivative; writes its coefficients in tau from the row over h (the
// reference's deriv: the tau-derivative over h^k).
static int deriv_row(const fs_real *row, int k, fs_real h, fs_real *out)
{
    // FALL[k][p] = p! / (p - k)!: the factor of tau^p's k-th derivative
    static const fs_real FALL[4][TRAJ_NCOEF] = {{1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
                                                {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10},
                                                {0, 0, 2, 6, 12, 20, 30, 42, 56, 72, 90},
                                                {0, 0, 0, 6, 24, 60, 120, 210, 336, 504, 720}};
    fs_real p = 1;
    int j, q, lead = 0, deg;
    while (lead < TRAJ_NCOEF - 1 - k && row[lead] == 0)  // leading zeros: a lower degree
        lead++;
    deg = TRAJ_NCOEF - 1 - k - lead;
    for (q = 0; q < k; q++)
        p *= h;
    p = 1 / p;  // one division per row, not per coefficient
    for (j = 0; j <= deg; j++)
        out[j] = row[j + lead] * FALL[k][TRAJ_NCOEF - 1 - (j + lead)] * p;
    return deg;
}

struct to_margins time_optimal_margins(const struct motor_params *m, const struct to_limits *lim, const struct traj *tr)
{
    struct to_margins out = {0, 0, 0, 0, 0, 0, 0};
    fs_real rho_max = 0, w_max = 0, a_max = 0, j_max = 0, c_max = 0, v2_max = 0, kr, inv_kr, a, s, dphi, x, y;
    fs_real sin_max = fs_sin(lim->torque_angle_max);
    bool bad = false;
    size_t i;
    int j;
    for (i = 0; i < tr->n; i++) {
        fs_real h = tr->breaks[i + 1] - tr->breaks[i];
        const fs_real *th = tr->theta + i * TRAJ_NCOEF, *rh = tr->rho + i * TRAJ_NCOEF;
        fs_real c0[TRAJ_NCOEF], c1[TRAJ_NCOEF], c2[TRAJ_NCOEF], c3[TRAJ_NCOEF], c4[TRAJ_NCOEF];
        int g1 = deriv_row(th, 1, h, c1), g2 = deriv_row(th, 2, h, c2), g3 = deriv_row(th, 3, h, c3);
        int g4 = deriv_row(rh, 1, h, c4), g0 = deriv_row(rh, 0, h, c0);
        for (j = 0; j < TO_CHECK + (i == tr->n - 1); j++) {
            fs_real tau = (fs_real)j / TO_CHECK;  // j = TO_CHECK on the last segment: its end
            fs_real w, acc, jerk, rho, drho;
            if (g0 == 7 && g1 == 6) {  // the planner's own degree-7 rows: Horner unrolled
                w = HORNER7(c1, tau), acc = HORNER6(c2, tau), jerk = HORNER5(c3, tau);
                rho = HORNER8(c0, tau), drho = HORNER7(c4, tau);
            } else {
                w = horner(c1, g1, tau), acc = horner(c2, g2, tau), jerk = horner(c3, g3, tau);
                rho = horner(c0, g0, tau), drho = horner(c4, g4, tau);
            }
            rho_max = fs_max(rho_max, rho);
            w_max = fs_max(w_max, fs_fabs(w));
            a_max = fs_max(a_max, fs_fabs(acc));
            j_max = fs_max(j_max, fs_fabs(jerk));
            a = m->J * acc + m->B * w;
            kr = m->Km * rho;
            if (!(rho > 0 && fs_fabs(a) - kr < 0)) {
                bad = true;
                continue;
            }
            s = fs_sqrt(kr * kr - a * a);
            inv_kr = 1 / kr;
            c_max = fs_max(c_max, fs_fabs(a) * inv_kr);
            dphi = -((m->J * jerk + m->B * acc) * rho - a * drho) / (rho * s) - (fs_real)m->Nr * w;
            x = m->L * drho + m->R * rho + m->Km * w * (a * inv_kr);
            y = m->L * rho * dphi - m->Km * w * (s * inv_kr);
            v2_max = fs_max(v2_max, x * x + y * y);
        }
    }
    out.current = rho_max / lim->i_max;
    out.speed = lim->speed_max > 0 ? w_max / lim->speed_max : 0;
    out.acceleration = lim->accel_max > 0 ? a_max / lim->accel_max : 0;
    out.jerk = lim->jerk_max > 0 ? j_max / lim->jerk_max : 0;
    if (bad) {
        out.voltage = out.torque_angle = out.worst = (fs_real)INFINITY;
        return out;
    }
    out.torque_angle = c_max / sin_max;
    out.voltage = fs_sqrt(v2_max) / lim->v_bus;
    out.worst = fs_max(fs_max(out.voltage / (TO_V_MARGIN * lim->v_use), out.current),
                       fs_max(out.torque_angle, fs_max(out.speed, fs_max(out.acceleration, out.jerk))))
                - 1;
    return out;
}

// The search's state: the workspace, the envelope's gamma in it, the best table so far (in out), the tables built.
struct to_search {
    const struct motor_params *m;
    const struct to_limits *lim;
    struct to_limits plan;  // the limits planned with: the torque angle cap TO_ANGLE_PLAN times lim's, the speed
                            // and acceleration caps TO_CAP_PLAN times
    fs_real d, env_gamma;
    struct to_work w;
    struct to_result *out;
    bool found, overflow;
    fs_real width[TO_MAX_WIDTHS], full[TO_MAX_WIDTHS];  // the widths, sorted, and their full-bus durations
    size_t nw;
    fs_real start, width_tf, width_gamma;  // the next search's first gamma; the last width's best
};

// Returns the measure s of the table at gamma and width (inf when the motor cannot start or the profile does not
// fit); a feasible table shorter than the best becomes the best (time_optimal._try and search_width).
static fs_real try_table(struct to_search *s, fs_real gamma, fs_real width)
{
    struct to_margins mg;
    struct to_result *out = s->out;
    if (s->env_gamma != gamma) {
        s->env_gamma = gamma;
        if (!envelope(s->m, &s->plan, gamma, &s->w)) {
            s->env_gamma = -1;
            return (fs_real)INFINITY;
        }
    }
    if (!smoothed_table(s->m, &s->plan, s->d, width, &s->w)) {
        s->overflow = true;
        return (fs_real)INFINITY;
    }
    out->tables++;
    mg = time_optimal_margins(s->m, s->lim, &s->w.tr);
#ifdef TO_DEBUG
    printf("C g=%.17g w=%.6g s=%.17g tf=%.17g\n", gamma, width, mg.worst, s->w.breaks[s->w.tr.n]);
#endif
    if (mg.worst <= 0 && s->w.breaks[s->w.tr.n] < s->width_tf) {
        s->width_tf = s->w.breaks[s->w.tr.n];
        s->width_gamma = gamma;
    }
    if (mg.worst <= 0 && (!s->found || s->w.breaks[s->w.tr.n] < out->breaks[out->n])) {
        s->found = true;
        out->n = s->w.tr.n;
        memcpy(out->breaks, s->w.breaks, (out->n + 1) * sizeof *out->breaks);
        memcpy(out->theta, s->w.theta, out->n * TRAJ_NCOEF * sizeof *out->theta);
        memcpy(out->rho, s->w.rho, out->n * TRAJ_NCOEF * sizeof *out->rho);
        out->gamma = gamma;
        out->width = width;
        out->margins = mg;
    }
    return mg.worst;
}

// Returns the duration of the table at gamma and width from its timing alone, before the table is built
// (time_optimal._duration): 0 when the table would not be built (the motor cannot start, or too many samples).
static fs_real duration(struct to_search *s, fs_real gamma, fs_real width)
{
    struct to_move mv;
    if (s->env_gamma != gamma) {
        s->env_gamma = gamma;
        if (!envelope(s->m, &s->plan, gamma, &s->w)) {
            s->env_gamma = -1;
            return 0;
        }
    }
    bang_bang(s->d, width, &s->w, &mv);
    return mv.n > TO_MAX_SAMPLES ? 0 : (fs_real)(mv.n + 2 * (mv.n_box - 1) - 1) * mv.dt;
}

// Returns nothing; the search on gamma at one width from start (time_optimal.search_width): regula falsi in a
// measured bracket, else the secant through the last two tables, else the proportional guess; s->width_tf and
// s->width_gamma are the width's shortest feasible table's duration and gamma (inf and 0 when none).
static void search_width(struct to_search *s, fs_real width, fs_real start)
{
    const fs_real nan = (fs_real)NAN;
    fs_real lo = 0, hi = 1, s_lo = nan, s_hi = nan, g = start, x, aim, g_last = nan, s_last = nan, g_prev, s_prev;
    int side = 0, it;
    s->width_tf = (fs_real)INFINITY;
    s->width_gamma = 0;
    for (it = 0; it < TO_SEARCH; it++) {
        g = fs_rint(g * TO_GAMMA_STEPS) / TO_GAMMA_STEPS;  // on a grid: both planners try the same gamma
        if (g < TO_GAMMA_MIN)
            break;
        if (side == 1 && s->found && duration(s, g, width) >= s->out->breaks[s->out->n])
            break;  // below an infeasible gamma, the guess of the bus target is no faster than the best: no table
        x = try_table(s, g, width);
        aim = x + FS_C(0.5) * TO_S_TOL;  // the guesses aim at the middle of the accepted band (-TO_S_TOL, 0]
        g_prev = g_last, s_prev = s_last, g_last = g, s_last = aim;
        if (x <= 0) {
            lo = g, s_lo = aim;
            if (g >= 1 || x > -TO_S_TOL)
                break;
            if (side == -1 && !isnan(s_hi))
                s_hi *= FS_C(0.5);  // Illinois: the end kept twice in a row counts half
            side = -1;
        } else {
            if (s->found && s->w.breaks[s->w.tr.n] >= s->out->breaks[s->out->n] && s->env_gamma == g)
                break;  // every feasible gamma of this width lies below g, and is slower still
            hi = g, s_hi = aim;
            if (side == 1 && !isnan(s_lo))
                s_lo *= FS_C(0.5);
            side = 1;
        }
        if (hi - lo < FS_C(1e-4))
            break;
        if (!isnan(s_lo) && fs_isfinite(s_hi))
            g = lo + (hi - lo) * s_lo / (s_lo - s_hi);
        else if (fs_isfinite(s_last) && fs_isfinite(s_prev) && s_last != s_prev) {
            g = g_last - s_last * (g_last - g_prev) / (s_last - s_prev);
            g = fs_min(fs_max(g, FS_C(0.5) * g_last), FS_C(1.5) * g_last);
        } else if (fs_isfinite(s_last))
            g = g_last / (1 + s_last);
        else
            g = FS_C(0.5) * (lo + hi);
        if (!isnan(s_hi))  // inside a measured bracket
            g = fs_min(fs_max(g, lo + FS_C(0.02) * (hi - lo)), hi - FS_C(0.02) * (hi - lo));
        g = fs_min(g, 1);
    }
}

// Returns the first gamma the search tries (time_optimal.first_gamma): for a move that cruises, predicted from the
// steady voltage at the full-bus move mv's peak speed (w holds the envelope at gamma = 1), else 1.
static fs_real first_gamma(const struct motor_params *m, const struct to_limits *plan, const struct to_work *w,
                           const struct to_move *mv)
{
    fs_real k = fs_cos(plan->torque_angle_max) / fs_sin(plan->torque_angle_max), v2 = 0, u, x, dh, s;
    fs_real acc[2];
    struct to_hcoef hc;
    int i;
    if (!(mv->cruise > 0))
        return 1;
    hc = to_hcoef(m, k, floor_current(plan, mv->w_peak), mv->w_peak, 0);  // h at v2 = 0: the squared voltage
    acc[0] = interp(mv->w_peak, w->omega, w->ap, TO_GRID);
    acc[1] = interp(mv->w_peak, w->omega, w->am, TO_GRID);
    for (i = 0; i < 2; i++) {
        u = (m->J * acc[i] + m->B * mv->w_peak) / m->Km;
        x = to_h(&hc, u, &dh);
        v2 = fs_max(v2, x);
    }
    s = TO_PEAK_OVER_STEADY * fs_sqrt(v2) / (TO_V_MARGIN * plan->v_use * plan->v_bus) - 1;
    return fs_min(1, 1 / (1 + s + FS_C(0.5) * TO_S_TOL));
}

// Returns the duration of width i's shortest feasible table (inf when none, or when its full-bus duration cannot
// beat the best); the next width's search starts at its gamma (time_optimal.plan_move's run).
static fs_real run_width(struct to_search *s, size_t i)
{
    if (s->found && s->full[i] >= s->out->breaks[s->out->n])
        return (fs_real)INFINITY;
    search_width(s, s->width[i], s->start);
    if (s->width_tf < (fs_real)INFINITY)
        s->start = s->width_gamma;
    return s->width_tf;
}

// Returns true when a width beyond the one before i was shorter; walks by step while the duration falls
// (time_optimal.plan_move's walk).
static bool walk(struct to_search *s, long i, long step, fs_real f)
{
    bool better = false;
    fs_real fi;
    for (; i >= 0 && i < (long)s->nw; i += step) {
        fi = run_width(s, (size_t)i);
        if (fi < f)
            better = true, f = fi;
        else if (f < (fs_real)INFINITY)
            break;
    }
    return better;
}

// Returns true when every limit is finite and in range.
static bool limits_valid(const struct to_limits *l)
{
    const fs_real half_pi = FS_C(1.5707963267948966);
    return fs_isfinite(l->v_bus) && l->v_bus > 0 && fs_isfinite(l->i_max) && l->i_hold > 0 && l->i_hold < l->i_max
           && l->i_run > 0 && l->i_run <= l->i_hold && fs_isfinite(l->speed_corner) && l->speed_corner > 0
           && l->torque_angle_max > 0 && l->torque_angle_max < half_pi && l->v_use > 0 && l->v_use <= 1
           && fs_isfinite(l->speed_max) && l->speed_max >= 0 && fs_isfinite(l->accel_max) && l->accel_max >= 0
           && fs_isfinite(l->jerk_max) && l->jerk_max >= 0;
}

int time_optimal_plan(const struct motor_params *m, const struct to_limits *lim, fs_real distance,
                      const fs_real *widths, size_t n_widths, fs_real *work, size_t work_len, struct to_result *out)
{
    static const fs_real DEFAULT_WIDTHS[] = {FS_C(0.25), FS_C(0.5), 1, 2, 4};
    struct to_search s;
    struct to_move mv;
    fs_real sign = distance < 0 ? -1 : 1, f0, x;
    size_t i, j, k, nw = widths ? n_widths : sizeof DEFAULT_WIDTHS / sizeof *DEFAULT_WIDTHS;
    out->n = 0;
    out->tables = 0;
    if (!motor_params_valid(m) || !limits_valid(lim) || !fs_isfinite(distance) || distance == 0 || nw < 1
        || nw > TO_MAX_WIDTHS)
        return TO_EARGS;
    for (i = 0; i < nw; i++) {  // insertion into the sorted widths
        x = widths ? widths[i] : DEFAULT_WIDTHS[i] * (m->L / m->R);
        if (!(fs_isfinite(x) && x > 0))
            return TO_EARGS;
        for (j = i; j > 0 && s.width[j - 1] > x; j--)
            s.width[j] = s.width[j - 1];
        s.width[j] = x;
    }
    if (!work || work_len < time_optimal_work_len())
        return TO_EWORK;
    s.m = m, s.lim = lim, s.d = fs_fabs(distance), s.out = out, s.found = s.overflow = false, s.nw = nw, s.start = 1;
    s.w.omega = work, s.w.ap = work + TO_GRID, s.w.am = work + 2 * TO_GRID, s.w.tacc = work + 3 * TO_GRID;
    s.w.tdec = work + 4 * TO_GRID, s.w.dboth = work + 5 * TO_GRID;
    s.w.a = work + 6 * TO_GRID, s.w.b = s.w.a + TO_FINE_LEN + 1, s.w.c = s.w.b + TO_FINE_LEN + 1;
    s.w.knot = s.w.c + TO_FINE_LEN + 1;
    s.w.breaks = s.w.knot + TO_MAX_SEGMENTS + 1;
    s.w.theta = s.w.breaks + TO_MAX_SEGMENTS + 1;
    s.w.rho = s.w.theta + TO_MAX_SEGMENTS * TRAJ_NCOEF;
    s.w.tr.breaks = s.w.breaks, s.w.tr.theta = s.w.theta, s.w.tr.rho = s.w.rho;
    s.plan = *lim;
    s.plan.torque_angle_max *= TO_ANGLE_PLAN;
    s.plan.speed_max *= TO_CAP_PLAN;
    s.plan.accel_max *= TO_CAP_PLAN;
    s.env_gamma = 1;
    if (!envelope(m, &s.plan, 1, &s.w))
        return TO_ESTART;
    for (i = 0; i < nw; i++) {  // the full-bus durations: a width whose is not shorter than the best cannot win
        bang_bang(s.d, s.width[i], &s.w, &mv);
        if (mv.n > TO_MAX_SAMPLES)
            return TO_ELONG;
        s.full[i] = (fs_real)(mv.n + 2 * (mv.n_box - 1) - 1) * mv.dt;
    }
    s.start = first_gamma(m, &s.plan, &s.w, &mv);
    // from the middle width down while the duration falls, then up unless down found a shorter table (both ways
    // from an infeasible middle width)
    f0 = run_width(&s, nw / 2);
    if (!walk(&s, (long)(nw / 2) - 1, -1, f0) || !(f0 < (fs_real)INFINITY))
        walk(&s, (long)(nw / 2) + 1, 1, f0);
    if (!s.found) {
        out->n = 0;
        return TO_ENOPLAN;
    }
    for (i = 0; i < out->n; i++)  // a negative move mirrors the positive one
        for (k = 0; k < TRAJ_NCOEF; k++)
            out->theta[i * TRAJ_NCOEF + k] *= sign;
    return TO_OK;
}
