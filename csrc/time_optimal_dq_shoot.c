// The field-weakening move by shooting: the nominal d-q model under the bus-saturated current-steering policy,
// the switch time found by the Illinois variant of regula falsi (flatstep.plan.time_optimal_dq_shoot, operation
// for operation).
#include "time_optimal_dq_stages.h"

// One shooting run's constants (time_optimal_dq_shoot._Model).
struct model {
    const struct motor_params *m;
    fs_real R, L, Km, J, B, Nr;
    fs_real v, i_max, h, inv_l, inv_j, lk, tc, rho, rate, end_rate, cap, hold, band, reactance;
};

// A state: theta, omega, i_d, i_q.
struct state {
    fs_real th, w, id, iq;
};

// Returns true when the run's constants are finite and positive and writes them (hostile limits can underflow or
// overflow them: every divisor is checked before it divides).
static bool model_init(struct model *md, const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap, fs_real h)
{
    fs_real top, k, den = TOD_LAG * i_max;
    md->m = m, md->R = m->R, md->L = m->L, md->Km = m->Km, md->J = m->J, md->B = m->B, md->Nr = (fs_real)m->Nr;
    md->v = v, md->i_max = i_max, md->h = h, md->inv_l = 1 / m->L, md->inv_j = 1 / m->J;
    if (!(den > 0 && fs_isfinite(h) && h > 0))
        return false;
    md->lk = v / den;
    if (!(fs_isfinite(md->lk) && md->lk > 0))
        return false;
    md->tc = m->L / md->lk;
    md->rho = m->R * i_max / v;  // the resistive share of the bus
    md->rate = TOD_Q_RATE * v / m->L * (m->J / m->Km);
    md->end_rate = md->rate;
    top = tod_top_speed(m, v, i_max, cap);
    md->cap = top >= cap ? cap : TOD_TOP_SHARE * top;
    md->hold = m->B * md->cap / m->Km;
    md->reactance = m->R > 0 ? md->Nr * md->cap * m->L / m->R : (fs_real)INFINITY;  // N_r W L / R at the cap W
    den = 4 * h * m->Km;
    if (!(fs_isfinite(md->rate) && md->rate > 0 && fs_isfinite(md->cap) && md->cap > 0 && den > 0))
        return false;
    k = m->J / den;
    if (!(k * k > 0 && fs_isfinite(k * k)))
        return false;
    md->band = 2 * md->rate / (k * k);
    return fs_isfinite(md->band) && md->band > 0;
}

// Returns nothing; writes (di_d, di_q, dw) of the model under the policy towards the target (td, tq).
static void deriv(const struct model *md, fs_real id, fs_real iq, fs_real w, fs_real td, fs_real tq, fs_real out[3])
{
    fs_real x = md->Nr * w * md->L, ad, aq, vd, vq, n2, scale;
    ad = md->R * id - x * iq;
    aq = md->R * iq + x * id + md->Km * w;
    vd = ad + md->lk * (td - id);
    vq = aq + md->lk * (tq - iq);
    n2 = vd * vd + vq * vq;
    if (n2 > md->v * md->v) {
        scale = md->v / fs_sqrt(n2);
        vd = vd * scale, vq = vq * scale;
    }
    out[0] = (vd - ad) * md->inv_l;
    out[1] = (vq - aq) * md->inv_l;
    out[2] = (md->Km * iq - md->B * w) * md->inv_j;
}

// Returns nothing; writes the target at speed w (braking: the bottom of the envelope with its bus disc scaled by
// 1 + 2 (rho - TOD_REACH_FROM) within [1, 1 + TOD_BRAKE_REACH], rho = R i_max / V; else its top, held to the cap's approach, which counts lead [rad/s] more for the current's lag,
// its d current the envelope's at w + ahead where that weakens more).
static void target(const struct model *md, fs_real w, bool braking, fs_real lead, fs_real ahead, fs_real t[2])
{
    fs_real c[4], c2[4], e, g,
        reach = braking ? 1 + fs_min(fs_max(2 * (md->rho - TOD_REACH_FROM), 0), TOD_BRAKE_REACH) : 1;
    if (!tod_best_currents(md->m, fs_min(fs_max(w, 0), md->cap), reach * md->v, md->i_max, c))
        c[0] = c[1] = c[2] = c[3] = 0;
    if (braking) {
        t[0] = c[2], t[1] = c[3];
        return;
    }
    e = md->cap - w - lead;
    g = e >= md->band ? fs_sqrt(2 * md->rate * e) : e * fs_sqrt(2 * md->rate / md->band);
    t[0] = c[0], t[1] = fs_min(c[1], md->hold + g);
    if (ahead > 0 && tod_best_currents(md->m, fs_min(fs_max(w + ahead, 0), md->cap), md->v, md->i_max, c2))
        t[0] = fs_min(t[0], c2[0]);
}

static void next_target(const struct model *md, const struct state *s, bool braking, fs_real t[2])
{
    fs_real alpha = (md->Km * s->iq - md->B * s->w) / md->J,
            share = fs_min(md->rho / TOD_RHO_FULL, 1)
                    * fs_min(fs_max((md->reactance - TOD_X_END) / (TOD_X_FULL - TOD_X_END), 0), 1),
            ahead = fs_min(fs_max((md->cap - s->w) / md->band, 0), 1) * TOD_AHEAD * share, n2, r2, q;
    target(md, s->w + md->h * alpha, braking, md->tc * alpha, ahead * md->tc * fs_max(alpha, 0), t);
    if (braking) {  // a current beyond TOD_PULL_FROM i_max pulls its target in
        n2 = s->id * s->id + s->iq * s->iq;
        r2 = (TOD_PULL_FROM * md->i_max) * (TOD_PULL_FROM * md->i_max);
        if (n2 > r2) {
            q = r2 / n2;
            t[0] = t[0] * q * q, t[1] = t[1] * q * q;
        }
    }
}

// Writes the speeding-up target at the end of the step from s into t, its d part within TOD_D_SLEW h V / L of tg's.
static void next_speed_up(const struct model *md, const struct state *s, const fs_real tg[2], fs_real t[2])
{
    fs_real slew = TOD_D_SLEW * md->h * md->v * md->inv_l;
    next_target(md, s, false, t);
    t[0] = fs_min(fs_max(t[0], tg[0] - slew), tg[0] + slew);
}

// Returns the state RK4 takes s to over f h, the target moving from t0 towards t1 (reached at a full step).
static struct state step(const struct model *md, const struct state *s, const fs_real t0[2], const fs_real t1[2],
                         fs_real f)
{
    fs_real h = f * md->h, dd = t1[0] - t0[0], dq = t1[1] - t0[1], k1[3], k2[3], k3[3], k4[3];
    struct state o;
    deriv(md, s->id, s->iq, s->w, t0[0], t0[1], k1);
    deriv(md, s->id + FS_C(0.5) * h * k1[0], s->iq + FS_C(0.5) * h * k1[1], s->w + FS_C(0.5) * h * k1[2],
          t0[0] + FS_C(0.5) * f * dd, t0[1] + FS_C(0.5) * f * dq, k2);
    deriv(md, s->id + FS_C(0.5) * h * k2[0], s->iq + FS_C(0.5) * h * k2[1], s->w + FS_C(0.5) * h * k2[2],
          t0[0] + FS_C(0.5) * f * dd, t0[1] + FS_C(0.5) * f * dq, k3);
    deriv(md, s->id + h * k3[0], s->iq + h * k3[1], s->w + h * k3[2], t0[0] + f * dd, t0[1] + f * dq, k4);
    o.th =
        s->th
        + h / 6 * (s->w + 2 * (s->w + FS_C(0.5) * h * k1[2]) + 2 * (s->w + FS_C(0.5) * h * k2[2]) + (s->w + h * k3[2]));
    o.w = s->w + h / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
    o.id = s->id + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
    o.iq = s->iq + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
    return o;
}

// Returns the braking current beyond the terminal ramp's switching curve [A] (>= 0: ramp now).
static fs_real curve(const struct model *md, const struct state *s)
{
    return -s->iq - fs_sqrt(2 * md->end_rate * fs_max(s->w, 0));
}

// Returns true when the speeding-up phase fits TOD_MAX_STEPS steps; writes its samples and whether it settled.
static bool speed_up(const struct model *md, fs_real d, const struct tod_phase *a, size_t *n, bool *cruise)
{
    struct state s = {0, 0, 0, 0};
    fs_real tg[2], nxt[2];
    size_t k;
    target(md, 0, false, 0, 0, tg);
    for (k = 0; k <= TOD_MAX_STEPS; k++) {
        a->theta[k] = s.th, a->omega[k] = s.w, a->i_d[k] = s.id, a->i_q[k] = s.iq, a->t_d[k] = tg[0], a->t_q[k] = tg[1];
        if (s.th >= d) {
            *n = k + 1, *cruise = false;
            return true;
        }
        if (fs_fabs(md->cap - s.w) <= TOD_SETTLE * md->cap && fs_fabs(tg[0] - s.id) <= TOD_SETTLE * md->i_max
            && fs_fabs(tg[1] - s.iq) <= TOD_SETTLE * md->i_max) {
            a->omega[k] = md->cap, a->i_d[k] = tg[0], a->i_q[k] = tg[1];  // settled: the cruise's steady state
            *n = k + 1, *cruise = true;
            return true;
        }
        if (k < TOD_MAX_STEPS) {
            next_speed_up(md, &s, tg, nxt);
            s = step(md, &s, tg, nxt, 1);
            tg[0] = nxt[0], tg[1] = nxt[1];
        }
    }
    return false;
}

// Returns nothing; writes the terminal ramp's voltage [V] at its start and at rest, from (w, id, iq) over tau, its
// d current's rate at the start c of -id / tau (time_optimal_dq_shoot.ramp_ends).
static void ramp_ends(const struct model *md, fs_real w, fs_real id, fs_real iq, fs_real tau, fs_real c, fs_real out[2])
{
    fs_real a = (md->Km * iq - md->B * w) / md->J, jerk = -a / tau, diq, x, vd, vq, end_d, end_q;
    diq = (md->J * jerk + md->B * a) / md->Km;
    x = md->Nr * w * md->L;
    vd = md->R * id - x * iq - md->L * c * id / tau;
    vq = md->R * iq + x * id + md->Km * w + md->L * diq;
    end_d = (2 - c) * id / tau, end_q = md->J * jerk / md->Km;
    out[0] = fs_sqrt(vd * vd + vq * vq), out[1] = md->L * fs_sqrt(end_d * end_d + end_q * end_q);
}

// Returns the terminal ramp's d share in [0, 1]: 1 unless its start's voltage is above its end's, then the share
// where the two are equal (bisection), or 0 (time_optimal_dq_shoot.ramp_share).
static fs_real ramp_share(const struct model *md, fs_real w, fs_real id, fs_real iq, fs_real tau)
{
    fs_real v[2], lo = 0, hi = 1, mid;
    int k;
    ramp_ends(md, w, id, iq, tau, 1, v);
    if (v[0] <= v[1])
        return 1;
    ramp_ends(md, w, id, iq, tau, 0, v);
    if (v[0] >= v[1])
        return 0;
    for (k = 0; k < TOD_SHARE_HALVINGS; k++) {
        mid = FS_C(0.5) * (lo + hi);
        ramp_ends(md, w, id, iq, tau, mid, v);
        if (v[0] < v[1])
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

// Returns the bridge from s at t and the terminal ramp after it (time_optimal_dq_shoot._ramp).
static struct tod_end ramp(const struct model *md, fs_real t, const struct state *s, const fs_real tg[2])
{
    struct tod_end e = {t, s->th, fs_max(s->w, 0), s->id, s->iq, tg[0], tg[1],
                        0, s->th, fs_max(s->w, 0), s->id, s->iq, 0,     1};
    fs_real a0 = (md->Km * s->iq - md->B * s->w) / md->J, tau0, dt, r[3], j_l, j_r, a1, w1, c;
    if (!(a0 < 0 && s->w > 0))
        return e;
    tau0 = -2 * s->w / a0;
    if (!(tau0 > 0))
        return e;
    dt = fs_min(TOD_BRIDGE * md->h, FS_C(0.5) * tau0);
    dt = (t + dt) - t;  // the bridge the samples' times t, t + dt will span (in single precision not dt itself)
    deriv(md, s->id, s->iq, s->w, tg[0], tg[1], r);
    j_l = (md->Km * r[1] - md->B * a0) / md->J;
    j_r = -a0 / tau0;
    a1 = a0 + FS_C(0.5) * (j_l + j_r) * dt;
    w1 = s->w + a0 * dt + (j_l / 3 + j_r / 6) * dt * dt;
    e.omega = s->w;
    e.bridge = dt;
    e.theta1 = s->th + s->w * dt + a0 * dt * dt / 2 + (j_l / 8 + j_r / 24) * (dt * dt * dt);
    e.omega1 = fs_max(w1, 0);
    c = ramp_share(md, s->w, s->id, s->iq, tau0);
    e.d_share = c;
    e.i_d1 = s->id + FS_C(0.5) * (r[0] - c * s->id / tau0) * dt;
    e.i_q1 = (md->J * a1 + md->B * w1) / md->Km;
    e.tau = a1 < 0 && w1 > 0 ? -2 * w1 / a1 : 0;
    return e;
}

// Returns the speeding-up step that time t >= 0 lies in, at most n_acc - 1 (int(t / h) clipped, as the reference).
static size_t step_index(fs_real t, fs_real h, size_t n_acc)
{
    fs_real k = t / h;
    if (!(k > 0))
        return 0;
    return k < (fs_real)(n_acc - 1) ? (size_t)k : n_acc - 1;
}

// Returns the state at the switch t_s and writes the speeding-up target there (time_optimal_dq_shoot.switch_state).
static struct state switch_state(const struct model *md, const struct tod_phase *a, size_t n_acc, bool cruise,
                                 fs_real t_s, fs_real tg[2])
{
    fs_real h = md->h, t0[2], t1[2], f;
    size_t k;
    struct state s;
    if (cruise && t_s >= (fs_real)(n_acc - 1) * h) {
        k = n_acc - 1;
        s.th = a->theta[k] + a->omega[k] * (t_s - (fs_real)k * h), s.w = a->omega[k], s.id = a->i_d[k],
        s.iq = a->i_q[k];
        tg[0] = a->t_d[k], tg[1] = a->t_q[k];
        return s;
    }
    k = step_index(t_s, h, n_acc);
    s.th = a->theta[k], s.w = a->omega[k], s.id = a->i_d[k], s.iq = a->i_q[k];
    t0[0] = a->t_d[k], t0[1] = a->t_q[k];
    if (!(t_s > (fs_real)k * h)) {
        tg[0] = t0[0], tg[1] = t0[1];
        return s;
    }
    if (k + 1 < n_acc)
        t1[0] = a->t_d[k + 1], t1[1] = a->t_q[k + 1];
    else
        next_speed_up(md, &s, t0, t1);
    f = (t_s - (fs_real)k * h) / h;
    tg[0] = t0[0] + f * (t1[0] - t0[0]), tg[1] = t0[1] + f * (t1[1] - t0[1]);
    return step(md, &s, t0, t1, f);
}

// Returns true and writes the braking phase's end from the switch t_s (and its samples into out unless NULL);
// false when TOD_MAX_STEPS steps are too few (time_optimal_dq_shoot._brake).
static bool brake(const struct model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real t_s,
                  const struct tod_phase *out, struct tod_end *end, size_t *n_b)
{
    fs_real tg[2], into[2], t1[2], at[2], g, g_next, f, lam, t_j, w_j, t_end;
    struct state s = switch_state(md, a, n_acc, cruise, t_s, tg), nxt;
    size_t j;
    into[0] = tg[0], into[1] = tg[1];
    g = curve(md, &s);
    *n_b = 0;
    if (g >= 0 || !(s.w > 0)) {
        *end = ramp(md, t_s, &s, tg);
        return true;
    }
    for (j = 0; j < TOD_MAX_STEPS; j++) {
        if (out) {
            out->theta[j] = s.th, out->omega[j] = s.w, out->i_d[j] = s.id, out->i_q[j] = s.iq;
            out->t_d[j] = tg[0], out->t_q[j] = tg[1];
        }
        next_target(md, &s, true, t1);
        if (j + 1 < TOD_SWITCH) {
            lam = ((fs_real)j + 1) / TOD_SWITCH;
            t1[0] = into[0] + lam * (t1[0] - into[0]), t1[1] = into[1] + lam * (t1[1] - into[1]);
        }
        t_j = tod_brake_time(t_s, md->h, j);
        w_j = (tod_brake_time(t_s, md->h, j + 1) - t_j) / md->h;  // the step the samples' times span (float: not 1)
        nxt = step(md, &s, tg, t1, w_j);
        g_next = curve(md, &nxt);
        if (g_next >= 0 || !(nxt.w > 0)) {
            f = w_j * (g_next >= 0 ? g / (g - g_next) : s.w / (s.w - nxt.w));
            t_end = t_j + f * md->h;
            f = (t_end - t_j) / md->h;  // (likewise)
            at[0] = tg[0] + f * (t1[0] - tg[0]), at[1] = tg[1] + f * (t1[1] - tg[1]);
            nxt = step(md, &s, tg, t1, f);
            *end = ramp(md, t_end, &nxt, at);
            *n_b = j + 1;
            return true;
        }
        s = nxt, g = g_next, tg[0] = t1[0], tg[1] = t1[1];
    }
    return false;
}

// Returns the largest voltage of the terminal ramp over the bus: at its start and at its end.
static fs_real ramp_voltage(const struct model *md, const struct tod_end *e)
{
    fs_real v[2];
    if (!(e->tau > 0))
        return 0;
    ramp_ends(md, e->omega1, e->i_d1, e->i_q1, e->tau, e->d_share, v);
    return fs_max(v[0], v[1]) / md->v;
}

// The root finder's bracket on the switch time: its ends, their misses of the distance, and the time last
// evaluated with its miss (its end in the caller's tod_end).
struct bracket {
    fs_real lo, f_lo, hi, f_hi, t_s, f;
};

// Returns true and writes a bracket from the guessed switch time and a probe one step from it towards the distance
// (false: it does not bracket; time_optimal_dq_shoot._guess).
static bool guess_bracket(const struct model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real d,
                          fs_real guess, fs_real top, const struct tod_phase *out, struct tod_end *end, size_t *n_b,
                          struct bracket *b)
{
    fs_real f_g, probe, f;
    if (!(guess > 0 && guess < top))
        return false;
    if (!brake(md, a, n_acc, cruise, guess, out, end, n_b))
        return false;
    f_g = end->theta1 + end->omega1 * end->tau / 3 - d;
    if (!fs_isfinite(f_g))
        return false;
    if (fs_fabs(f_g) <= TOD_ROOT_TOL * d) {
        b->lo = b->hi = b->t_s = guess, b->f_lo = b->f_hi = b->f = f_g;
        return true;
    }
    probe = f_g < 0 ? guess + md->h : guess - md->h;
    if (!(probe > 0 && probe < top))
        return false;
    if (!brake(md, a, n_acc, cruise, probe, out, end, n_b))
        return false;
    f = end->theta1 + end->omega1 * end->tau / 3 - d;
    if (!fs_isfinite(f) || (f < 0) == (f_g < 0))
        return false;
    b->t_s = probe, b->f = f;
    if (f_g < 0)
        b->lo = guess, b->f_lo = f_g, b->hi = probe, b->f_hi = f;
    else
        b->lo = probe, b->f_lo = f, b->hi = guess, b->f_hi = f_g;
    return true;
}

// Returns a first switch time: where the braking distance from top (over beyond d), scaled by the square of the
// speed, lands on d (NAN: none); from a cruise, exact (the braking from any switch on it is the same, shifted).
static fs_real estimate(const struct model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real d,
                        fs_real top, fs_real over)
{
    size_t k = n_acc - 1, j;
    fs_real t, b, c, g, g0 = -d;
    if (!(a->omega[k] > 0))
        return (fs_real)NAN;
    if (cruise) {
        t = top - over / a->omega[k];
        if (t >= (fs_real)k * md->h)
            return t;
        b = over;
    } else {
        b = over + d - a->theta[k];
    }
    c = a->omega[k] * a->omega[k];
    if (!(c > 0))  // the speed's square underflows: no estimate
        return (fs_real)NAN;
    c = b / c;
    if (!(fs_isfinite(c) && c > 0))
        return (fs_real)NAN;
    for (j = 1; j < n_acc; j++) {
        g = a->theta[j] + c * a->omega[j] * a->omega[j] - d;
        if (g >= 0)
            return ((fs_real)(j - 1) + g0 / (g0 - g)) * md->h;
        g0 = g;
    }
    return (fs_real)NAN;
}

// Returns true and writes the switch time that lands the move on d and its end, the root finder started from the
// bracket of guess where it brackets (guess not finite: none; time_optimal_dq_shoot._land); every braking phase
// it tries writes its samples into out and their count into n_b, so the last (at the switch time) is the shot's.
static bool land(const struct model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real d, fs_real guess,
                 const struct tod_phase *out, fs_real *t_s_out, struct tod_end *end, size_t *n_b)
{
    fs_real last = (fs_real)(n_acc - 1) * md->h, top, t_s, hi, lo, f_lo, f_hi, f, est = (fs_real)NAN;
    struct bracket b;
    int it, side = 0;
    if (cruise && !(a->omega[n_acc - 1] > 0))  // a cruise at no speed: the cap is 0 in fs_real
        return false;
    top = cruise ? last + (d - a->theta[n_acc - 1]) / a->omega[n_acc - 1] : last;
    if (fs_isfinite(guess) && guess_bracket(md, a, n_acc, cruise, d, guess, top, out, end, n_b, &b)) {
        lo = b.lo, f_lo = b.f_lo, hi = b.hi, f_hi = b.f_hi, t_s = b.t_s, f = b.f;
    } else {
        t_s = hi = top, lo = 0, f_lo = -d;
        if (!brake(md, a, n_acc, cruise, hi, out, end, n_b))
            return false;
        f_hi = f = end->theta1 + end->omega1 * end->tau / 3 - d;
        if (!fs_isfinite(f) || !(t_s >= 0) || f < 0)  // the bracket's top must not fall short
            return false;
        est = estimate(md, a, n_acc, cruise, d, top, f);
    }
    for (it = 0; it < TOD_ROOT; it++) {
        if (fs_fabs(f) <= TOD_ROOT_TOL * d || !(hi - lo > TOD_BRACKET_TOL * hi))
            break;
        if (!(f_hi - f_lo > 0))
            break;
        t_s = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if (lo < est && est < hi)  // the first try: the estimate from the top's braking distance
            t_s = est;
        est = (fs_real)NAN;
        if (!brake(md, a, n_acc, cruise, t_s, out, end, n_b))
            return false;
        f = end->theta1 + end->omega1 * end->tau / 3 - d;
        if (!fs_isfinite(f))
            return false;
        if (f < 0) {
            lo = t_s, f_lo = f;
            if (side == -1)
                f_hi *= FS_C(0.5);
            side = -1;
        } else {
            hi = t_s, f_hi = f;
            if (side == 1)
                f_lo *= FS_C(0.5);
            side = 1;
        }
    }
    *t_s_out = t_s;
    return true;
}

bool tod_shoot(const struct motor_params *m, fs_real d, fs_real v, fs_real i_max, fs_real cap, fs_real ramp_rate,
               fs_real switch_time, struct tod_shot *shot)
{
    struct model md;
    fs_real h = m->L * i_max / v / TOD_STEPS, t_s = 0, excess, rate, prev, e_prev, nxt, guess, kept_rate = 0,
            kept_switch = 0;
    size_t n_acc = 0, n_b, k;
    bool cruise = false, landed, kept;
    int dbl, tries;
    for (dbl = 0; dbl <= TOD_DOUBLINGS; dbl++, h *= 2) {
        if (!model_init(&md, m, v, i_max, cap, h))
            return false;
        md.end_rate = ramp_rate * md.rate;
        landed = kept = false;
        prev = e_prev = excess = (fs_real)NAN, guess = switch_time;
        if (speed_up(&md, d, &shot->acc, &n_acc, &cruise)) {
            for (tries = 0; tries <= TOD_RAMP_TRIES; tries++) {
                landed = land(&md, &shot->acc, n_acc, cruise, d, guess, &shot->brk, &t_s, &shot->end, &n_b);
                if (!landed)
                    break;
                guess = t_s;
                excess = ramp_voltage(&md, &shot->end);
                if (excess <= 1 && (excess >= TOD_RAMP_LOW || !(e_prev > 1) || kept))
                    break;
                rate = md.end_rate;
                if (excess <= 1)  // well within the bus after a fall: raised once, between the two
                    kept = true, kept_rate = rate, kept_switch = guess;
                if (fs_isfinite(e_prev) && excess != e_prev) {
                    nxt = rate + (TOD_RAMP_SHARE - excess) * (rate - prev) / (excess - e_prev);
                    nxt = fs_min(fs_max(nxt, FS_C(0.25) * rate), fs_max(rate, prev));
                } else
                    nxt = rate * ((TOD_RAMP_SHARE / excess) * (TOD_RAMP_SHARE / excess));
                prev = rate, e_prev = excess, md.end_rate = TOD_RAMP_AIM * nxt;
            }
            if (kept && (!landed || !(excess <= 1))) {
                md.end_rate = kept_rate;  // the raise left the bus: back to the rate within it
                landed = land(&md, &shot->acc, n_acc, cruise, d, kept_switch, &shot->brk, &t_s, &shot->end, &n_b);
            }
        }
        if (!landed)  // (the landing's last braking phase is at t_s: its samples are the shot's)
            continue;
        excess = shot->end.theta1 + shot->end.omega1 * shot->end.tau / 3 - d;
        if (!(fs_fabs(excess) <= TOD_LAND_TOL * d))  // the root finder stopped short of the distance
            return false;
        shot->cruise = cruise && t_s >= (fs_real)(n_acc - 1) * h;
        k = step_index(t_s, h, n_acc);
        shot->n_acc = shot->cruise ? n_acc : k + 1;
        shot->n_brake = n_b, shot->t_s = t_s, shot->v = v, shot->gain = md.lk, shot->h = h;
        shot->ramp = md.end_rate / md.rate;
        return true;
    }
    return false;
}
