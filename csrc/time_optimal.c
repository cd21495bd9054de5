// The time-optimal planner: regula falsi on the bus fraction over the smoothing widths, each candidate built by
// the stages of time_optimal_stages.h (flatstep.plan.time_optimal is the reference, operation for operation).
#include "time_optimal_stages.h"
#include <string.h>

#define TO_GAMMA_MIN FS_C(0.05)
#define TO_S_TOL FS_C(0.003)
#define TO_ANGLE_PLAN FS_C(0.98)
#define TO_CAP_PLAN FS_C(0.995)
#define TO_GAMMA_STEPS FS_C(65536.0)     // 2^16
#define TO_PEAK_OVER_STEADY FS_C(0.994)  // a table's peak voltage over the steady one at its peak speed

size_t time_optimal_work_len(void)
{
    return 6 * (size_t)TO_GRID + 2 * ((size_t)TO_FINE_LEN + 1) + (size_t)TO_SUM_LEN + (TO_MAX_SEGMENTS + 1) * 2
           + 2 * (size_t)TO_MAX_SEGMENTS * TRAJ_NCOEF;
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
        if (!to_envelope(s->m, &s->plan, gamma, &s->w)) {
            s->env_gamma = -1;
            return (fs_real)INFINITY;
        }
    }
    if (!to_smoothed_table(s->m, &s->plan, s->d, width, 2, &s->w)) {
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
        if (!to_envelope(s->m, &s->plan, gamma, &s->w)) {
            s->env_gamma = -1;
            return 0;
        }
    }
    to_bang_bang(s->d, width, &s->w, &mv);
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
    hc = to_hcoef(m, k, to_floor_current(plan, mv->w_peak), mv->w_peak, 0);  // h at v2 = 0: the squared voltage
    acc[0] = to_interp(mv->w_peak, w->omega, w->ap, TO_GRID);
    acc[1] = to_interp(mv->w_peak, w->omega, w->am, TO_GRID);
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
    if (!motor_params_valid(m) || !to_limits_valid(lim) || !fs_isfinite(distance) || distance == 0 || nw < 1
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
    s.w.knot = s.w.c + TO_SUM_LEN;
    s.w.breaks = s.w.knot + TO_MAX_SEGMENTS + 1;
    s.w.theta = s.w.breaks + TO_MAX_SEGMENTS + 1;
    s.w.rho = s.w.theta + TO_MAX_SEGMENTS * TRAJ_NCOEF;
    s.w.tr.breaks = s.w.breaks, s.w.tr.theta = s.w.theta, s.w.tr.rho = s.w.rho;
    s.plan = *lim;
    s.plan.torque_angle_max *= TO_ANGLE_PLAN;
    s.plan.speed_max *= TO_CAP_PLAN;
    s.plan.accel_max *= TO_CAP_PLAN;
    s.env_gamma = 1;
    if (!to_envelope(m, &s.plan, 1, &s.w))
        return TO_ESTART;
    for (i = 0; i < nw; i++) {  // the full-bus durations: a width whose is not shorter than the best cannot win
        to_bang_bang(s.d, s.width[i], &s.w, &mv);
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
