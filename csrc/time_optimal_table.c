// The time-optimal planner's smoothed table: the bang-bang profile boxed twice, fitted by Hermite segments, and
// its margins (flatstep.plan.smoothing is the reference, operation for operation).
#include "time_optimal_stages.h"
#include <string.h>

// Returns the length of x after a box of n samples: x convolved with it through the running sum in s
// (smoothing._box; out may not alias x).
size_t to_box(const fs_real *x, size_t len, size_t n, fs_real *s, fs_real *out)
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

// Returns the central difference of x at i (one-sided at the ends) over dt (smoothing._gradient).
fs_real to_gradient(const fs_real *x, size_t len, size_t i, fs_real dt)
{
    if (i == 0)
        return (x[1] - x[0]) / dt;
    if (i == len - 1)
        return (x[len - 1] - x[len - 2]) / dt;
    return (x[i + 1] - x[i - 1]) / (2 * dt);
}

// Returns the second difference of x at i: the gradient of the gradient (smoothing._gradient twice).
static fs_real gradient2(const fs_real *x, size_t len, size_t i, fs_real dt)
{
    if (i == 0)
        return (to_gradient(x, len, 1, dt) - to_gradient(x, len, 0, dt)) / dt;
    if (i == len - 1)
        return (to_gradient(x, len, len - 1, dt) - to_gradient(x, len, len - 2, dt)) / dt;
    return (to_gradient(x, len, i + 1, dt) - to_gradient(x, len, i - 1, dt)) / (2 * dt);
}

// Returns the number of knots; writes their sample indices (smoothing._knots).
static size_t knots(size_t last, fs_real up, fs_real down, int cruise, fs_real *k)
{
    fs_real a = fs_min(fs_max(up, 0), (fs_real)last), b = fs_min(fs_max(down, 0), (fs_real)last), x;
    size_t i, n = 0, half = TO_KNOTS / 2;
    fs_real mid = (fs_real)last / 2;
    for (i = 0; i <= 2 * half + 4; i++) {
        if (cruise && b > a) {
            if (i <= half)
                x = to_linspace(0, a, half + 1, i);
            else if (i <= half + 4)
                x = to_linspace(a, b, 5, i - half);
            else
                x = to_linspace(b, (fs_real)last, half + 1, i - half - 4);
        } else {
            if (i > 2 * half)
                break;
            x = i <= half ? to_linspace(0, mid, half + 1, i) : to_linspace(mid, (fs_real)last, half + 1, i - half);
        }
        x = fs_rint(x);
        if (n == 0 || x != k[n - 1])
            k[n++] = x;
    }
    return n;
}

// (time_optimal_stages.h)
const fs_real TO_HERMITE[8][8] = {
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
            sum += TO_HERMITE[i][j] * rhs[j];
        row[3 + i] = sum;
    }
    for (i = 4; i < 8; i++)  // tau^3 .. tau^0: the start's own derivatives
        row[3 + i] = TO_HERMITE[i][7 - i] * rhs[7 - i];
}

// Returns the planned rho* at torque current iq and speed w (MotorLimits.rho); cot is cot(torque_angle_max).
static fs_real rho_star(const struct to_limits *lim, fs_real cot, fs_real iq, fs_real w)
{
    fs_real f = to_floor_current(lim, w), q = iq * cot;
    return fs_sqrt(iq * iq + (f * f + q * q));
}

// Returns rho* at sample i of the scaled speed profile v (len samples, step dt).
static fs_real rho_at(const struct motor_params *m, const struct to_limits *lim, fs_real cot, const fs_real *v,
                      size_t len, size_t i, fs_real dt)
{
    return rho_star(lim, cot, (m->J * to_gradient(v, len, i, dt) + m->B * v[i]) / m->Km, v[i]);
}

// Returns true and builds the candidate table w->tr of the move over d > 0 at width (smoothing.smoothed_table);
// false when the profile would not fit the workspace.
bool to_smoothed_table(const struct motor_params *m, const struct to_limits *lim, fs_real d, fs_real width, int passes,
                       struct to_work *w)
{
    struct to_move mv;
    fs_real total, t, *speed = w->a, *inc = w->c, scale, cruise, sum, angle = 0, step, s0[4], s1[4], r0[4], r1[4], h;
    size_t i, j, len, nk, last, at, at0 = 0, r, j_acc = 0, j_dec = TO_GRID - 2;
    fs_real cot = fs_cos(lim->torque_angle_max) / fs_sin(lim->torque_angle_max);
    to_bang_bang(d, width, w, &mv);
    total = mv.t1 + mv.cruise + mv.t2;
    // the profile after both boxes (in a) and the second box's running sum (in c) must fit their arrays
    if (mv.n > TO_MAX_SAMPLES || mv.n - mv.k + 2 * (mv.n_box - 1) > TO_FINE_LEN
        || mv.n - mv.k + 3 * mv.n_box - 2 > TO_SUM_LEN)
        return false;
    for (i = 0; i < mv.n - mv.k; i++) {  // sample i >= r at (i + k) dt: the cut is not sampled
        t = (fs_real)(i < mv.r ? i : i + mv.k) * mv.dt;
        if (t <= mv.t1)
            speed[i] = to_interp_walk(t, w->tacc, w->omega, TO_GRID, &j_acc);
        else if (t < mv.t1 + mv.cruise)
            speed[i] = mv.w_peak;
        else
            speed[i] = to_interp_walk(total - t, w->tdec, w->omega, TO_GRID, &j_dec);
    }
    speed[mv.n - mv.k - 1] = 0;
    len = to_box(speed, mv.n - mv.k, mv.n_box, w->c, w->b);
    if (passes == 2)
        len = to_box(w->b, len, mv.n_box, w->c, speed);
    else
        memcpy(speed, w->b, len * sizeof *speed);
    sum = 0;
    for (i = 0; i + 1 < len; i++) {  // the trapezoids of the angle
        inc[i] = FS_C(0.5) * (speed[i + 1] + speed[i]) * mv.dt;
        sum += inc[i];
    }
    r = mv.r < len - 1 ? mv.r : len - 1;  // no cut (k = 0): r only has to index the profile
    cruise = mv.k ? speed[r] : 0;
    scale = sum + (fs_real)mv.k * mv.dt * cruise;
    if (!(scale > 0 && fs_isfinite(scale)))  // a width so long that the profile vanishes: no table
        return false;
    scale = d / scale;
    for (i = 0; i < len; i++)
        speed[i] *= scale;
    last = len - 1;
    // the cruise's knots 4 samples inside it (smoothing.smoothed_table)
    nk = knots(last + mv.k, (mv.t1 + (fs_real)passes * width) / mv.dt + 4, (mv.t1 + mv.cruise) / mv.dt - 4,
               mv.cruise > 0, w->knot);
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
        s1[2] = to_gradient(speed, len, at, mv.dt);
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

// Returns true when every limit is finite and in range, and the usable voltage TO_V_MARGIN v_use v_bus does not
// underflow (the planner divides by it).
bool to_limits_valid(const struct to_limits *l)
{
    const fs_real half_pi = FS_C(1.5707963267948966);
    return fs_isfinite(l->v_bus) && l->v_bus > 0 && fs_isfinite(l->i_max) && l->i_hold > 0 && l->i_hold < l->i_max
           && l->i_run > 0 && l->i_run <= l->i_hold && fs_isfinite(l->speed_corner) && l->speed_corner > 0
           && l->torque_angle_max > 0 && l->torque_angle_max < half_pi && l->v_use > 0 && l->v_use <= 1
           && TO_V_MARGIN * l->v_use * l->v_bus > 0 && fs_isfinite(l->speed_max) && l->speed_max >= 0
           && fs_isfinite(l->accel_max) && l->accel_max >= 0 && fs_isfinite(l->jerk_max) && l->jerk_max >= 0;
}

// Returns margins of inf: nothing can be measured (invalid arguments, or a table whose values are not numbers).
static struct to_margins margins_inf(void)
{
    const fs_real inf = (fs_real)INFINITY;
    struct to_margins out = {inf, inf, inf, inf, inf, inf, inf};
    return out;
}

struct to_margins time_optimal_margins(const struct motor_params *m, const struct to_limits *lim, const struct traj *tr)
{
    struct to_margins out = {0, 0, 0, 0, 0, 0, 0};
    fs_real rho_max = 0, w_max = 0, a_max = 0, j_max = 0, c_max = 0, v2_max = 0, kr, inv_kr, a, s, dphi, x, y;
    fs_real sin_max;
    bool bad = false;
    size_t i;
    int j;
    if (!motor_params_valid(m) || !to_limits_valid(lim) || !traj_valid(tr))  // nothing to divide by
        return margins_inf();
    sin_max = fs_sin(lim->torque_angle_max);
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
            if (!(fs_isfinite(w) && fs_isfinite(acc) && fs_isfinite(jerk) && fs_isfinite(rho) && fs_isfinite(drho)))
                return margins_inf();  // the table's values overflow: no ratio is a number
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
            if (!(rho * s > 0 && fs_isfinite(inv_kr))) {  // rho s or kr underflowed: no division by zero
                bad = true;
                continue;
            }
            c_max = fs_max(c_max, fs_fabs(a) * inv_kr);
            dphi = -((m->J * jerk + m->B * acc) * rho - a * drho) / (rho * s) - (fs_real)m->Nr * w;
            x = m->L * drho + m->R * rho + m->Km * w * (a * inv_kr);
            y = m->L * rho * dphi - m->Km * w * (s * inv_kr);
            if (isnan(x * x + y * y)) {  // inf - inf inside: a voltage beyond any bus
                bad = true;
                continue;
            }
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
