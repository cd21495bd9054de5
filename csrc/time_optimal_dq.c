// The field-weakening planner: the move shot on the nominal d-q model (time_optimal_dq_shoot.c), its samples,
// knots and fit (theta degree-7 Hermite, i_d cubic Hermite), the margins of the fitted table, and the shots again
// at a smaller share where the fit crosses a limit (flatstep.plan.time_optimal_dq and
// flatstep.plan.time_optimal_dq_profile are the reference, operation for operation).
#include "time_optimal_dq_stages.h"
#include "time_optimal_stages.h"
#include <string.h>

#define TOD_ELECTRICAL_SHARE FS_C(0.035)  // the largest electrical frequency over the control rate
#define TOD_CAP_PLAN FS_C(0.995)          // of the speed cap, the share the move is shot at
#define TOD_CURRENT_PLAN FS_C(0.995)      // of i_max, the share the move is first shot at
#define TOD_V_MARGIN FS_C(0.995)          // of the bus, the voltage a table may reach at its samples
#define TOD_EXTRA FS_C(0.002)             // of the excess, the extra a share shrinks by
#define TOD_POWER FS_C(1.5)               // the power of the excess a share shrinks by
#define TOD_V_POWER FS_C(2.0)             // ... the bus's (the fitted table's peak voltage falls by less)
#define TOD_SHARE FS_C(0.98)              // of v_use v_bus, the bus the move is first shot at
#define TOD_TIME_WEIGHT FS_C(2.0)         // the measure's share of one rise time against a full change of a rate
#define TOD_CLOSE FS_C(0.25)              // of a step, samples closer than this to the one before are dropped
#define TOD_ANGLE_NOISE FS_C(16.0)        // roundings of the sampled angles that the angle steps may carry
#define TOD_PI FS_C(3.14159265358979323846)

// The samples of a shot (time_optimal_dq_profile.Samples), TOD_SAMPLES each.
struct samples {
    fs_real *t, *th, *w, *id, *iq, *did, *diq, *keep, *meas;
    size_t n;
};

size_t time_optimal_dq_work_len(void)
{
    return 12 * ((size_t)TOD_MAX_STEPS + 1) + 9 * (size_t)TOD_SAMPLES;
}

fs_real time_optimal_dq_speed_cap(const struct motor_params *m, const struct tod_limits *lim)
{
    fs_real cap = TOD_ELECTRICAL_SHARE * 2 * TOD_PI * lim->control_rate / (fs_real)m->Nr;
    return lim->speed_max > 0 ? fs_min(cap, lim->speed_max) : cap;
}

// Returns nothing; writes (di_d, di_q) of the model at the state under the shot's policy towards (td, tq)
// (time_optimal_dq_profile._rates).
static void rates(const struct motor_params *m, const struct tod_shot *sh, fs_real w, fs_real id, fs_real iq,
                  fs_real td, fs_real tq, fs_real *did, fs_real *diq)
{
    fs_real x = (fs_real)m->Nr * w * m->L, ad, aq, vd, vq, n2, scale, inv_l = 1 / m->L;
    ad = m->R * id - x * iq, aq = m->R * iq + x * id + m->Km * w;
    vd = ad + sh->gain * (td - id), vq = aq + sh->gain * (tq - iq);
    n2 = vd * vd + vq * vq;
    scale = n2 > sh->v * sh->v ? sh->v / fs_sqrt(n2 > 0 ? n2 : 1) : 1;
    *did = (vd * scale - ad) * inv_l, *diq = (vq * scale - aq) * inv_l;
}

// Returns nothing; appends a sample.
static void push(struct samples *s, fs_real t, fs_real th, fs_real w, fs_real id, fs_real iq, fs_real did, fs_real diq,
                 bool keep)
{
    size_t i = s->n++;
    s->t[i] = t, s->th[i] = th, s->w[i] = w, s->id[i] = id, s->iq[i] = iq, s->did[i] = did, s->diq[i] = diq;
    s->keep[i] = keep ? 1 : 0;
}

// Returns nothing; writes the shot's samples in time order, a sample closer than TOD_CLOSE h to the one before
// dropped (a kept one replaces one not kept, the end any; time_optimal_dq_profile.samples).
static void samples(const struct motor_params *m, const struct tod_shot *sh, fs_real d, struct samples *s)
{
    const struct tod_phase *a = &sh->acc, *b = &sh->brk;
    const struct tod_end *e = &sh->end;
    size_t i, na = sh->n_acc, nb = sh->n_brake, last;
    fs_real did, diq, alpha1, jerk, ramp_d, rest_d, t;
    s->n = 0;
    for (i = 0; i < na; i++) {
        rates(m, sh, a->omega[i], a->i_d[i], a->i_q[i], a->t_d[i], a->t_q[i], &did, &diq);
        push(s, (fs_real)i * sh->h, a->theta[i], a->omega[i], a->i_d[i], a->i_q[i], did, diq,
             i == 0 || (sh->cruise && i == na - 1));
    }
    for (i = 0; i < nb; i++) {
        rates(m, sh, b->omega[i], b->i_d[i], b->i_q[i], b->t_d[i], b->t_q[i], &did, &diq);
        push(s, tod_brake_time(sh->t_s, sh->h, i), b->theta[i], b->omega[i], b->i_d[i], b->i_q[i], did, diq,
             i == 0 || i == TOD_SWITCH);
    }
    rates(m, sh, e->omega, e->i_d, e->i_q, e->t_d, e->t_q, &did, &diq);
    push(s, e->t, e->theta, e->omega, e->i_d, e->i_q, did, diq, true);
    alpha1 = (m->Km * e->i_q1 - m->B * e->omega1) / m->J;
    jerk = e->tau > 0 ? -alpha1 / e->tau : 0;
    ramp_d = e->tau > 0 ? -e->d_share * e->i_d1 / e->tau : 0;
    rest_d = e->tau > 0 ? -(2 - e->d_share) * e->i_d1 / e->tau : 0;
    push(s, e->t + e->bridge, e->theta1, e->omega1, e->i_d1, e->i_q1, ramp_d, (m->J * jerk + m->B * alpha1) / m->Km,
         true);
    push(s, e->t + e->bridge + e->tau, d, 0, 0, 0, rest_d, m->J * jerk / m->Km, true);
    // drop the close ones in place
    for (last = 0, i = 1; i < s->n; i++) {
        t = s->t[last];
        if (s->t[i] - t >= TOD_CLOSE * sh->h
            || (s->keep[i] != 0 && s->keep[last] != 0 && s->t[i] > t * (1 + FS_C(1e-12))))
            last++;
        else if (!(s->keep[i] != 0 && (s->keep[last] == 0 || i == s->n - 1) && last > 0))
            continue;  // (the end at rest is never dropped: it replaces the one before it)
        s->t[last] = s->t[i], s->th[last] = s->th[i], s->w[last] = s->w[i], s->id[last] = s->id[i];
        s->iq[last] = s->iq[i], s->did[last] = s->did[i], s->diq[last] = s->diq[i], s->keep[last] = s->keep[i];
    }
    s->n = last + 1;
}

// Returns the first sample index at or above level q of TOD_KNOTS + 1 of the measure (numpy.searchsorted), n
// beyond the last level; *j walks up from the last call's.
static size_t chosen(const struct samples *s, size_t q, size_t *j)
{
    fs_real level;
    if (q > TOD_KNOTS)
        return s->n;
    level = s->meas[s->n - 1] * (fs_real)q / (TOD_KNOTS + 1);
    while (*j < s->n - 1 && s->meas[*j] < level)
        ++*j;
    return *j;
}

// Returns the number of knots; writes their sample indices: the kept samples and TOD_KNOTS more at equal steps of
// the measure (time_optimal_dq_profile.pick_knots).
static size_t pick_knots(const struct samples *s, fs_real rise, fs_real rate, size_t *k)
{
    size_t n = s->n, i, j = 0, q = 1, c, nk = 0;
    fs_real dt, change;
    bool sel;
    if (n <= TOD_KNOTS + 6) {
        for (i = 0; i < n; i++)
            k[i] = i;
        return n;
    }
    s->meas[0] = 0;
    for (i = 0; i + 1 < n; i++) {
        dt = s->t[i + 1] - s->t[i];
        change = (fs_fabs(s->diq[i + 1] - s->diq[i]) + fs_fabs(s->did[i + 1] - s->did[i])) / rate;
        if (s->w[i + 1] - s->w[i] == 0 && s->iq[i + 1] - s->iq[i] == 0 && s->id[i + 1] - s->id[i] == 0)
            s->meas[i + 1] = s->meas[i] + 0;  // settled: only theta moves
        else
            s->meas[i + 1] = s->meas[i] + (TOD_TIME_WEIGHT * dt / rise + change);
    }
    c = chosen(s, q, &j);
    for (i = 0; i < n; i++) {
        sel = s->keep[i] != 0;
        while (c == i) {
            sel = true;
            c = chosen(s, ++q, &j);
        }
        if (sel)
            k[nk++] = i;
    }
    return nk;
}

// Returns the angle step's part beyond the trapezoid h (w0 + w1) / 2 over the segment from s0 to s1 [rad]: the
// samples' where it differs from the two-point Hermite quadrature of omega's (exact for omega of degree 5) by more
// than TOD_ANGLE_NOISE roundings of their angles, else the quadrature's. (In single precision the sampled angles
// carry rounding of eps theta, far above this residual on short segments, where the fit's jerk multiplies it by
// about 4000 / h^3; in double the samples' is taken but where the two agree to rounding.)
static fs_real step_residual(const fs_real s0[4], const fs_real s1[4], fs_real h)
{
    fs_real sampled = (s1[0] - s0[0]) - h * FS_C(0.5) * (s0[1] + s1[1]);
    fs_real quad = h * h * ((s0[2] - s1[2]) / 10 + h * (s0[3] + s1[3]) / 120);
    fs_real noise = TOD_ANGLE_NOISE * FS_REAL_EPSILON * (fs_fabs(s0[0]) + fs_fabs(s1[0]));
    return fs_fabs(sampled - quad) <= noise ? quad : sampled;
}

// Returns nothing; writes the row as hermite_row would for the segment from s0 to s1 over h, the angle step given
// as its residual q beyond the trapezoid and the row's start angle as th0: the tau^7 .. tau^4 coefficients formed
// from q and the change of the rate, so that no term of size omega h cancels in them (in single precision that
// cancellation leaves errors of eps omega h, which the jerk multiplies by about 4000 / h^3).
static void hermite_row_step(const fs_real s0[4], const fs_real s1[4], fs_real h, fs_real q, fs_real th0, fs_real *row)
{
    static const fs_real dw[4] = {0, 1, -3, FS_C(2.5)};  // of (w1 - w0) h: H[i][5] + H[i][4] / 2
    fs_real rhs[8], p = 1, sum;
    int i, j;
    for (j = 0; j < 4; j++, p *= h)
        rhs[j] = s0[j] * p, rhs[4 + j] = s1[j] * p;
    for (i = 0; i < TRAJ_NCOEF - 8; i++)
        row[i] = 0;
    for (i = 0; i < 4; i++) {
        sum = TO_HERMITE[i][4] * q + dw[i] * ((s1[1] - s0[1]) * h);
        for (j = 2; j < 4; j++)
            sum += TO_HERMITE[i][j] * rhs[j] + TO_HERMITE[i][4 + j] * rhs[4 + j];
        row[TRAJ_NCOEF - 8 + i] = sum;
    }
    for (i = 4; i < 7; i++)
        row[TRAJ_NCOEF - 8 + i] = TO_HERMITE[i][7 - i] * rhs[7 - i];
    row[TRAJ_NCOEF - 1] = th0;
}

// Returns nothing; writes the table of the knots k[0..nk) of the samples into out (time_optimal_dq_profile.dq_fit).
static void fit(const struct motor_params *m, const struct samples *s, const size_t *k, size_t nk,
                struct tod_result *out)
{
    fs_real prev[4] = {0, 0, 0, 0}, cur[4], alpha, h, q;
    size_t i;
    out->n = nk - 1;
    for (i = 0; i < nk; i++) {
        alpha = (m->Km * s->iq[k[i]] - m->B * s->w[k[i]]) / m->J;
        cur[0] = s->th[k[i]], cur[1] = s->w[k[i]], cur[2] = alpha,
        cur[3] = (m->Km * s->diq[k[i]] - m->B * alpha) / m->J;
        out->breaks[i] = s->t[k[i]] - s->t[k[0]];
        out->knot_id[i] = i == nk - 1 ? 0 : s->id[k[i]];
        out->knot_did[i] = i == 0 ? 0 : s->did[k[i]];
        if (i > 0) {
            h = s->t[k[i]] - s->t[k[i - 1]];
            q = step_residual(prev, cur, h);
            hermite_row_step(prev, cur, h, q, prev[0], out->theta + (i - 1) * TRAJ_NCOEF);
        }
        memcpy(prev, cur, sizeof prev);
    }
}

// Returns the margins of the table (time_optimal_dq_profile.dq_margins): TO_CHECK samples per segment and the end.
// Per segment, theta's rate, acceleration and jerk rows are formed once in time (not tau) and the d current's
// cubic Hermite piece is the segment's own; the norms are compared squared and rooted once.
static struct tod_margins margins(const struct motor_params *m, const struct tod_limits *lim, fs_real cap,
                                  const struct tod_result *tr)
{
    struct tod_margins g = {0, 0, 0, 0, (fs_real)INFINITY, 0};
    fs_real v_limit = lim->v_use * lim->v_bus, h, tau, w, acc, jerk, id, did, iq, diq, x, vd, vq, v2 = 0, i2 = 0;
    fs_real r1[TRAJ_NCOEF - 1], r2[TRAJ_NCOEF - 2], r3[TRAJ_NCOEF - 3], p0, p1, m0, m1, h1, h2, h3, u;
    const fs_real *kid = tr->knot_id, *kdid = tr->knot_did;
    size_t i, j, n = tr->n, last;
    int k;
    for (i = 0; i < n; i++) {
        const fs_real *row = tr->theta + i * TRAJ_NCOEF;
        h = tr->breaks[i + 1] - tr->breaks[i];
        for (k = 0; k < TRAJ_NCOEF - 1; k++) {  // highest power first: row[k] multiplies tau^(10 - k)
            fs_real p = (fs_real)(TRAJ_NCOEF - 1 - k);
            r1[k] = row[k] * p;
            if (k < TRAJ_NCOEF - 2)
                r2[k] = row[k] * (p * (p - 1));
            if (k < TRAJ_NCOEF - 3)
                r3[k] = row[k] * (p * (p - 1) * (p - 2));
        }
        h1 = h, h2 = h * h, h3 = h * h * h;
        u = 1 / h;
        if (!fs_isfinite(u * u * u * u)) {  // a segment too short for a table (traj_valid): none
            g.worst = (fs_real)INFINITY;
            return g;
        }
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
    g.voltage = fs_sqrt(v2) / v_limit, g.current = fs_sqrt(i2) / lim->i_max, g.speed = g.speed_peak / cap;
    g.worst = fs_max(fs_max(g.voltage / TOD_V_MARGIN, g.current), g.speed) - 1;
    if (!fs_isfinite(g.worst))
        g.worst = (fs_real)INFINITY;
    return g;
}

int time_optimal_dq_plan(const struct motor_params *m, const struct tod_limits *lim, fs_real distance, fs_real *work,
                         size_t work_len, struct tod_result *out)
{
    struct tod_shot sh;
    struct samples s;
    struct tod_margins g;
    fs_real sign = distance < 0 ? -1 : 1, d = fs_fabs(distance), cap, v_bus, share = TOD_SHARE,
            current = TOD_CURRENT_PLAN;
    fs_real speed = TOD_CAP_PLAN, ramp = 1, switch_time = (fs_real)NAN, v, i_max, c[4], end, *p = work;
    fs_real **arrays[12] = {&sh.acc.theta, &sh.acc.omega, &sh.acc.i_d, &sh.acc.i_q, &sh.acc.t_d, &sh.acc.t_q,
                            &sh.brk.theta, &sh.brk.omega, &sh.brk.i_d, &sh.brk.i_q, &sh.brk.t_d, &sh.brk.t_q};
    fs_real **sarrays[9] = {&s.t, &s.th, &s.w, &s.id, &s.iq, &s.did, &s.diq, &s.keep, &s.meas};
    size_t knots[TO_MAX_SEGMENTS + 1], nk, i, k;
    int attempt;
    out->n = 0, out->tables = 0;
    if (!motor_params_valid(m) || !fs_isfinite(distance) || distance == 0
        || !(fs_isfinite(lim->v_bus) && lim->v_bus > 0 && fs_isfinite(lim->v_use) && lim->v_use > 0 && lim->v_use <= 1
             && fs_isfinite(lim->i_max) && lim->i_max > 0 && fs_isfinite(lim->speed_max) && lim->speed_max >= 0
             && fs_isfinite(lim->control_rate) && lim->control_rate > 0))
        return TOD_EARGS;
    if (!work || work_len < time_optimal_dq_work_len())
        return TOD_EWORK;
    for (i = 0; i < 12; i++, p += TOD_MAX_STEPS + 1)
        *arrays[i] = p;
    for (i = 0; i < 9; i++, p += TOD_SAMPLES)
        *sarrays[i] = p;
    cap = time_optimal_dq_speed_cap(m, lim);
    v_bus = lim->v_use * lim->v_bus;
    if (!tod_best_currents(m, 0, share * v_bus, current * lim->i_max, c) || !(c[1] > 0))
        return TOD_ESTART;
    for (attempt = 0; attempt <= TOD_SHRINKS; attempt++) {
        v = share * v_bus, i_max = current * lim->i_max;
        if (!(v > 0 && i_max > 0 && cap > 0 && m->L * i_max / v > 0))
            break;
        if (!tod_shoot(m, d, v, i_max, speed * cap, ramp, switch_time, &sh))
            break;
        ramp = sh.ramp, switch_time = sh.t_s;
        samples(m, &sh, d, &s);
        nk = pick_knots(&s, m->L * i_max / v, v / m->L, knots);
        if (nk < 2 || nk > TO_MAX_SEGMENTS + 1)
            break;
        fit(m, &s, knots, nk, out);
        out->tables++;
        for (end = 0, k = 0; k < TRAJ_NCOEF; k++)  // the last row at tau = 1: the fit must end on the distance
            end += out->theta[(out->n - 1) * TRAJ_NCOEF + k];
        if (!(fs_fabs(end - d) <= TOD_LAND_TOL * (1 + d)))  // (segments so long that the fit loses the angle)
            break;
        g = margins(m, lim, cap, out);
        if (!fs_isfinite(g.worst))
            break;
        if (g.worst <= 0) {
            out->kappa = share, out->width = sh.h, out->margins = g;
            for (i = 0; i < out->n; i++)  // a negative move mirrors the positive one
                for (k = 0; k < TRAJ_NCOEF; k++)
                    out->theta[i * TRAJ_NCOEF + k] *= sign;
            return TOD_OK;
        }
        if (g.voltage / TOD_V_MARGIN - 1 > 0)
            share /= fs_pow(g.voltage / TOD_V_MARGIN + TOD_EXTRA, TOD_V_POWER);
        if (g.current > 1)
            current /= fs_pow(g.current + TOD_EXTRA, TOD_POWER);
        if (g.speed > 1)
            speed /= fs_pow(g.speed + TOD_EXTRA, TOD_POWER);
        if (!fs_isfinite(share) || !fs_isfinite(current) || !fs_isfinite(speed))
            break;
    }
    out->n = 0;
    return TOD_ENOPLAN;
}
