// The field-weakening move by shooting: the switch time that lands the braking phase on the distance, found by the
// Illinois variant of regula falsi, and the terminal ramp's rate, kept within the bus (the model under the policy,
// its phases and the ramp: time_optimal_dq_shot.h; flatstep.plan.time_optimal_dq_shoot, operation for operation).
#include "time_optimal_dq_shot.h"

// The root finder's bracket on the switch time: its ends, their misses of the distance, and the time last
// evaluated with its miss (its end in the caller's tod_end).
struct bracket {
    fs_real lo, f_lo, hi, f_hi, t_s, f;
};

// Returns true and writes a bracket from the guessed switch time and a probe one step from it towards the distance
// (false: it does not bracket; time_optimal_dq_shoot._guess).
static bool guess_bracket(const struct tod_model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real d,
                          fs_real guess, fs_real top, const struct tod_phase *out, struct tod_end *end, size_t *n_b,
                          struct bracket *b)
{
    fs_real f_g, probe, f;
    if (!(guess > 0 && guess < top))
        return false;
    if (!tod_brake(md, a, n_acc, cruise, guess, out, end, n_b))
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
    if (!tod_brake(md, a, n_acc, cruise, probe, out, end, n_b))
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
static fs_real estimate(const struct tod_model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real d,
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
static bool land(const struct tod_model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real d,
                 fs_real guess, const struct tod_phase *out, fs_real *t_s_out, struct tod_end *end, size_t *n_b)
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
        if (!tod_brake(md, a, n_acc, cruise, hi, out, end, n_b))
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
        if (!tod_brake(md, a, n_acc, cruise, t_s, out, end, n_b))
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
    struct tod_model md;
    fs_real h = m->L * i_max / v / TOD_STEPS, t_s = 0, excess, rate, prev, e_prev, nxt, guess, kept_rate = 0,
            kept_switch = 0;
    size_t n_acc = 0, n_b, k;
    bool cruise = false, landed, kept;
    int dbl, tries;
    for (dbl = 0; dbl <= TOD_DOUBLINGS; dbl++, h *= 2) {
        if (!tod_model_init(&md, m, v, i_max, cap, h))
            return false;
        md.end_rate = ramp_rate * md.rate;
        landed = kept = false;
        prev = e_prev = excess = (fs_real)NAN, guess = switch_time;
        if (tod_speed_up(&md, d, &shot->acc, &n_acc, &cruise)) {
            for (tries = 0; tries <= TOD_RAMP_TRIES; tries++) {
                landed = land(&md, &shot->acc, n_acc, cruise, d, guess, &shot->brk, &t_s, &shot->end, &n_b);
                if (!landed)
                    break;
                guess = t_s;
                excess = tod_ramp_voltage(&md, &shot->end);
                // (no ramp voltage, excess 0, leaves nothing to aim the rate from: kept as it is)
                if (excess <= 1 && (excess >= TOD_RAMP_LOW || !(e_prev > 1) || kept || excess == 0))
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
        k = tod_step_index(t_s, h, n_acc);
        shot->n_acc = shot->cruise ? n_acc : k + 1;
        shot->n_brake = n_b, shot->t_s = t_s, shot->v = v, shot->gain = md.lk, shot->h = h;
        shot->ramp = md.end_rate / md.rate;
        return true;
    }
    return false;
}
