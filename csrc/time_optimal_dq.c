// The field-weakening planner: the search on the bus share over the smoothing widths, each candidate's theta from
// to_smoothed_table and its d current boxed and spread here (flatstep.plan.time_optimal_dq and
// flatstep.plan.time_optimal_dq_profile are the reference, operation for operation).
#include "time_optimal_dq_stages.h"
#include <string.h>

#define TOD_ELECTRICAL_SHARE FS_C(0.035)  // the largest electrical frequency over the control rate
#define TOD_CAP_PLAN FS_C(0.995)          // of the speed cap, the share the envelope is planned at
#define TOD_CURRENT_PLAN FS_C(0.97)       // of i_max, the share the envelope is planned at
#define TOD_V_MARGIN FS_C(0.995)          // of the bus, the voltage a table may reach at its samples
#define TOD_S_TOL FS_C(0.003)             // a feasible table within 0.3 % of the limit ends a width's search
#define TOD_PI FS_C(3.14159265358979323846)

// The scratch arrays and the search's state.
struct tod_search {
    const struct motor_params *m;
    const struct tod_limits *lim;
    struct to_limits any;  // valid limits for to_smoothed_table's rho rows, which this planner does not read
    fs_real d, cap;
    struct to_work w;
    fs_real *idp, *idm;  // TO_GRID each: the envelope's d currents
    fs_real *x, *y;      // TO_FINE_LEN + 1 each: the d current's samples
    fs_real *s;          // TO_SUM_LEN: running sums
    struct tod_result *out;
    bool found;
    fs_real start, width_tf, width_kappa;  // the next search's first kappa; the last width's best
    fs_real env_kappa;                     // the bus share of the envelope in w (NAN: none)
    int passes;                            // box filters of the candidates: 1 or 2
};

size_t time_optimal_dq_work_len(void)
{
    return time_optimal_work_len() + 2 * (size_t)TO_GRID + 2 * ((size_t)TO_FINE_LEN + 1) + (size_t)TO_SUM_LEN;
}

fs_real time_optimal_dq_speed_cap(const struct motor_params *m, const struct tod_limits *lim)
{
    fs_real cap = TOD_ELECTRICAL_SHARE * 2 * TOD_PI * lim->control_rate / (fs_real)m->Nr;
    return lim->speed_max > 0 ? fs_min(cap, lim->speed_max) : cap;
}

// Returns true and writes the d current's knots of the table in s->w.tr (time_optimal_dq_profile.dq_table).
static bool d_current(struct tod_search *s, fs_real width, fs_real *knot_id, fs_real *knot_did)
{
    struct to_move mv;
    struct to_work *w = &s->w;
    fs_real t, total, cruise, *x = s->x, *y = s->y;
    size_t i, len, half, at, r, k, nk = w->tr.n + 1, j_acc = 0, j_dec = TO_GRID - 2;
    to_bang_bang(s->d, width, w, &mv);
    total = mv.t1 + mv.cruise + mv.t2;
    cruise = to_interp(mv.w_peak, w->omega, s->idp, TO_GRID);
    // the d current of the side at the speed of the bang-bang move, read against time: the envelope's speed and d
    // current are both linear between the same grid points (the top while speeding up and cruising, the bottom
    // while braking)
    for (i = 0; i < mv.n - mv.k; i++) {  // sample i >= r at (i + k) dt
        t = (fs_real)(i < mv.r ? i : i + mv.k) * mv.dt;
        if (t <= mv.t1)
            x[i] = to_interp_walk(t, w->tacc, s->idp, TO_GRID, &j_acc);
        else if (t < mv.t1 + mv.cruise)
            x[i] = cruise;
        else
            x[i] = to_interp_walk(total - t, w->tdec, s->idm, TO_GRID, &j_dec);
    }
    x[mv.n - mv.k - 1] = 0;
    len = to_box(x, mv.n - mv.k, mv.n_box, s->s, y);
    if (s->passes == 2)
        len = to_box(y, len, mv.n_box, s->s, x);
    else
        memcpy(x, y, len * sizeof *x);
    s->s[0] = 0;  // the running mean of TOD_ID_SPREAD widths either side, narrowed at the ends
    for (i = 0; i < len; i++)
        s->s[i + 1] = s->s[i] + x[i];
    for (i = 0; i < len; i++) {
        half = i < len - 1 - i ? i : len - 1 - i;
        half = half < TOD_ID_SPREAD * mv.n_box ? half : TOD_ID_SPREAD * mv.n_box;
        y[i] = (s->s[i + half + 1] - s->s[i - half]) / (fs_real)(2 * half + 1);
    }
    r = mv.r < len - 1 ? mv.r : len - 1;
    for (i = 0; i < nk; i++) {
        k = (size_t)w->knot[i];
        at = k < r ? k : k >= r + mv.k ? k - mv.k : r;
        knot_id[i] = y[at];
        knot_did[i] = i == 0 || i == nk - 1 ? 0 : to_gradient(y, len, at, mv.dt);
    }
    return true;
}

// Returns the margins of the table (time_optimal_dq_profile.dq_margins): TO_CHECK samples per segment and the end.
// Per segment, theta's rate, acceleration and jerk rows are formed once in time (not tau) and the d current's
// cubic Hermite piece is the segment's own; the norms are compared squared and rooted once.
static struct tod_margins margins(const struct tod_search *s, const fs_real *kid, const fs_real *kdid)
{
    const struct motor_params *m = s->m;
    const struct traj *tr = &s->w.tr;
    struct tod_margins g = {0, 0, 0, 0, (fs_real)INFINITY, 0};
    fs_real v_limit = s->lim->v_use * s->lim->v_bus, h, tau, w, acc, jerk, id, did, iq, diq, x, vd, vq, v2 = 0, i2 = 0;
    fs_real r1[TRAJ_NCOEF - 1], r2[TRAJ_NCOEF - 2], r3[TRAJ_NCOEF - 3], p0, p1, m0, m1, h1, h2, h3, u;
    size_t i, j, n = tr->n, last;
    int k;
    for (i = 0; i < n; i++) {
        const fs_real *row = tr->theta + i * TRAJ_NCOEF;
        h = tr->breaks[i + 1] - tr->breaks[i];
        for (k = 0; k < TRAJ_NCOEF - 1; k++) {  // highest power first: row[k] multiplies tau^(7 - k)
            fs_real p = (fs_real)(TRAJ_NCOEF - 1 - k);
            r1[k] = row[k] * p;
            if (k < TRAJ_NCOEF - 2)
                r2[k] = row[k] * (p * (p - 1));
            if (k < TRAJ_NCOEF - 3)
                r3[k] = row[k] * (p * (p - 1) * (p - 2));
        }
        h1 = fs_pow(h, 1), h2 = fs_pow(h, 2), h3 = fs_pow(h, 3);
        p0 = kid[i], p1 = kid[i + 1], m0 = kdid[i] * h, m1 = kdid[i + 1] * h;
        last = i == n - 1 ? (size_t)TO_CHECK : (size_t)TO_CHECK - 1;
        for (j = 0; j <= last; j++) {
            tau = (fs_real)j / (fs_real)TO_CHECK;
            for (w = r1[0], k = 1; k < TRAJ_NCOEF - 1; k++)
                w = w * tau + r1[k];
            for (acc = r2[0], k = 1; k < TRAJ_NCOEF - 2; k++)
                acc = acc * tau + r2[k];
            for (jerk = r3[0], k = 1; k < TRAJ_NCOEF - 3; k++)
                jerk = jerk * tau + r3[k];
            w /= h1, acc /= h2, jerk /= h3;
            u = (fs_min(tr->breaks[i] + tau * h, tr->breaks[i + 1]) - tr->breaks[i]) / h;  // as hermite_cubic
            id = ((2 * u - 3) * u * u + 1) * p0 + ((u - 2) * u + 1) * u * m0 + (3 - 2 * u) * u * u * p1
                 + (u - 1) * u * u * m1;
            did = (i == 0 && j == 0) || (i == n - 1 && j == last)
                      ? 0
                      : (6 * (u - 1) * u * (p0 - p1) + ((3 * u - 4) * u + 1) * m0 + (3 * u - 2) * u * m1) / h;
            iq = (m->J * acc + m->B * w) / m->Km;
            diq = (m->J * jerk + m->B * acc) / m->Km;
            x = (fs_real)m->Nr * w * m->L;
            vd = m->R * id + m->L * did - x * iq;
            vq = m->R * iq + m->L * diq + x * id + m->Km * w;
            v2 = fs_max(v2, vd * vd + vq * vq);
            i2 = fs_max(i2, id * id + iq * iq);
            g.speed_peak = fs_max(g.speed_peak, fs_fabs(w));
            g.i_d_min = fs_min(g.i_d_min, id);
        }
    }
    g.voltage = fs_sqrt(v2) / v_limit, g.current = fs_sqrt(i2) / s->lim->i_max, g.speed = g.speed_peak / s->cap;
    g.worst = fs_max(fs_max(g.voltage / TOD_V_MARGIN, g.current), g.speed) - 1;
    if (!fs_isfinite(g.worst))
        g.worst = (fs_real)INFINITY;
    return g;
}

// Returns true and builds the envelope at kappa in s->w (kept while kappa does not change).
static bool envelope_at(struct tod_search *s, fs_real kappa)
{
    const struct tod_limits *l = s->lim;
    if (kappa == s->env_kappa)
        return true;
    s->env_kappa = (fs_real)NAN;
    if (!tod_envelope(s->m, kappa * l->v_use * l->v_bus, TOD_CURRENT_PLAN * l->i_max, TOD_CAP_PLAN * s->cap, &s->w,
                      s->idp, s->idm))
        return false;
    s->env_kappa = kappa;
    return true;
}

// Returns the duration [s] of the table at kappa and width without building it (inf when none is built;
// time_optimal_dq._duration).
static fs_real duration(struct tod_search *s, fs_real kappa, fs_real width)
{
    struct to_move mv;
    if (!envelope_at(s, kappa))
        return (fs_real)INFINITY;
    to_bang_bang(s->d, width, &s->w, &mv);
    return ((fs_real)(mv.n + (size_t)s->passes * (mv.n_box - 1)) - 1) * mv.dt;
}

// Returns the measure s of the table at kappa and width (inf when none is built) and writes its duration into
// tf_out (inf when none); a feasible table shorter than the best becomes the best (time_optimal_dq._try).
static fs_real try_table(struct tod_search *s, fs_real kappa, fs_real width, fs_real *tf_out)
{
    struct tod_result *out = s->out;
    struct tod_margins g;
    fs_real kid[TO_MAX_SEGMENTS + 1], kdid[TO_MAX_SEGMENTS + 1], tf;
    *tf_out = (fs_real)INFINITY;
    if (!envelope_at(s, kappa))
        return (fs_real)INFINITY;
    if (!to_smoothed_table(s->m, &s->any, s->d, width, s->passes, &s->w) || !d_current(s, width, kid, kdid))
        return (fs_real)INFINITY;
    out->tables++;
    g = margins(s, kid, kdid);
    tf = s->w.breaks[s->w.tr.n];
    *tf_out = tf;
    if (g.worst <= 0 && tf < s->width_tf)
        s->width_tf = tf, s->width_kappa = kappa;
    if (g.worst <= 0 && (!s->found || tf < out->breaks[out->n])) {
        s->found = true;
        out->n = s->w.tr.n;
        memcpy(out->breaks, s->w.breaks, (out->n + 1) * sizeof *out->breaks);
        memcpy(out->theta, s->w.theta, out->n * TRAJ_NCOEF * sizeof *out->theta);
        memcpy(out->knot_id, kid, (out->n + 1) * sizeof *kid);
        memcpy(out->knot_did, kdid, (out->n + 1) * sizeof *kdid);
        out->kappa = kappa, out->width = width, out->margins = g;
    }
    return g.worst;
}

// Returns the width's least duration (at kappa = 1); none of its tables is built when that is not shorter than the
// best; else the secant on kappa from s->start, then regula falsi once bracketed (time_optimal_dq.search_kappa);
// s->width_tf and
// s->width_kappa are the width's shortest feasible table's duration and bus share (inf and 0: none).
static fs_real search_kappa(struct tod_search *s, fs_real width)
{
    const fs_real nan = (fs_real)NAN, inf = (fs_real)INFINITY;
    fs_real lo = 0, hi = 1, s_lo = nan, s_hi = nan, k = s->start, k_prev = nan, s_prev = nan, x, aim, next, least, tf;
    int it;
    s->width_tf = inf, s->width_kappa = 0;
    least = duration(s, 1, width);
    if (!(least < (s->found ? s->out->breaks[s->out->n] : inf)))  // no table of this width could be shorter
        return least;
    for (it = 0; it < TOD_SEARCH; it++) {
        x = try_table(s, k, width, &tf);
        aim = x + FS_C(0.5) * TOD_S_TOL;
        if (x <= 0) {
            lo = k, s_lo = aim;
            if (k >= 1 || x > -TOD_S_TOL)
                break;
        } else {
            hi = k, s_hi = aim;
            if (s->found && tf >= s->out->breaks[s->out->n])  // every table below this bus share is longer
                break;
        }
        if (!isnan(s_lo) && fs_isfinite(s_hi)) {
            next = lo + (hi - lo) * s_lo / (s_lo - s_hi);
            next = fs_min(fs_max(next, lo + FS_C(0.02) * (hi - lo)), hi - FS_C(0.02) * (hi - lo));
        } else if (fs_isfinite(aim) && fs_isfinite(s_prev) && aim != s_prev) {
            next = k - aim * (k - k_prev) / (aim - s_prev);
            next = fs_min(fs_max(next, FS_C(0.5) * k), FS_C(1.5) * k);
        } else if (fs_isfinite(aim))
            next = k / (1 + aim);
        else
            next = FS_C(0.5) * (lo + hi);
        k_prev = k, s_prev = aim, k = fs_min(next, 1);
        if (k < FS_C(0.05) || hi - lo < FS_C(1e-4))
            break;
    }
    return least;
}

// Returns the duration of width i's shortest feasible table (inf when none); the next width's search starts at its
// kappa (time_optimal_dq.plan_dq_move's run).
static fs_real run_width(struct tod_search *s, const fs_real *widths, long i)
{
    search_kappa(s, widths[i]);
    if (s->width_tf < (fs_real)INFINITY)
        s->start = s->width_kappa;
    return s->width_tf;
}

// Returns true when a width beyond the one before i was shorter; walks by step while the duration falls.
static bool walk(struct tod_search *s, const fs_real *widths, long i, long step, fs_real f)
{
    bool better = false;
    fs_real fi;
    for (; i >= 0 && i < TOD_WIDTHS; i += step) {
        fi = run_width(s, widths, i);
        if (fi < f)
            better = true, f = fi;
        else if (f < (fs_real)INFINITY)
            break;
    }
    return better;
}

int time_optimal_dq_plan(const struct motor_params *m, const struct tod_limits *lim, fs_real distance, fs_real *work,
                         size_t work_len, struct tod_result *out)
{
    static const fs_real WIDTHS[TOD_WIDTHS] = {FS_C(0.75), 1, FS_C(1.5), 2, 3};
    struct tod_search s;
    struct to_limits any = {24, 1, FS_C(0.3), FS_C(0.3), 10, FS_C(1.2), FS_C(0.9), 0, 0, 0};
    fs_real sign = distance < 0 ? -1 : 1, rise, widths[TOD_WIDTHS], f0;
    size_t i, k;
    out->n = 0, out->tables = 0;
    if (!motor_params_valid(m) || !fs_isfinite(distance) || distance == 0
        || !(fs_isfinite(lim->v_bus) && lim->v_bus > 0 && fs_isfinite(lim->v_use) && lim->v_use > 0 && lim->v_use <= 1
             && fs_isfinite(lim->i_max) && lim->i_max > 0 && fs_isfinite(lim->speed_max) && lim->speed_max >= 0
             && fs_isfinite(lim->control_rate) && lim->control_rate > 0))
        return TOD_EARGS;
    if (!work || work_len < time_optimal_dq_work_len())
        return TOD_EWORK;
    s.m = m, s.lim = lim, s.any = any, s.d = fs_fabs(distance), s.out = out, s.found = false;
    s.env_kappa = (fs_real)NAN;
    s.cap = time_optimal_dq_speed_cap(m, lim);
    s.w.omega = work, s.w.ap = work + TO_GRID, s.w.am = work + 2 * TO_GRID, s.w.tacc = work + 3 * TO_GRID;
    s.w.tdec = work + 4 * TO_GRID, s.w.dboth = work + 5 * TO_GRID;
    s.w.a = work + 6 * TO_GRID, s.w.b = s.w.a + TO_FINE_LEN + 1, s.w.c = s.w.b + TO_FINE_LEN + 1;
    s.w.knot = s.w.c + TO_SUM_LEN;
    s.w.breaks = s.w.knot + TO_MAX_SEGMENTS + 1;
    s.w.theta = s.w.breaks + TO_MAX_SEGMENTS + 1;
    s.w.rho = s.w.theta + TO_MAX_SEGMENTS * TRAJ_NCOEF;
    s.w.tr.breaks = s.w.breaks, s.w.tr.theta = s.w.theta, s.w.tr.rho = s.w.rho;
    s.idp = work + time_optimal_work_len(), s.idm = s.idp + TO_GRID;
    s.x = s.idm + TO_GRID, s.y = s.x + TO_FINE_LEN + 1, s.s = s.y + TO_FINE_LEN + 1;
    if (!envelope_at(&s, 1))
        return TOD_ESTART;
    rise = m->L * lim->i_max / (lim->v_use * lim->v_bus);
    for (i = 0; i < TOD_WIDTHS; i++)
        widths[i] = WIDTHS[i] * rise;
    // from the middle width down while the duration falls, then up unless down found a shorter table
    for (s.passes = 1; s.passes <= 2; s.passes++) {  // the box once (the jerk jumps, the law takes it), twice
        s.start = 1;
        f0 = run_width(&s, widths, TOD_WIDTHS / 2);
        if (!walk(&s, widths, TOD_WIDTHS / 2 - 1, -1, f0) || !(f0 < (fs_real)INFINITY))
            walk(&s, widths, TOD_WIDTHS / 2 + 1, 1, f0);
    }
    if (!s.found) {
        out->n = 0;
        return TOD_ENOPLAN;
    }
    for (i = 0; i < out->n; i++)  // a negative move mirrors the positive one
        for (k = 0; k < TRAJ_NCOEF; k++)
            out->theta[i * TRAJ_NCOEF + k] *= sign;
    return TOD_OK;
}
