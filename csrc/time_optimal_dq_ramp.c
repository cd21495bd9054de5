// The field-weakening shot's terminal ramp: the bridge from the braking phase, the ramp to rest, its d current's
// share and its voltage (flatstep.plan.time_optimal_dq_ramp, operation for operation).
#include "time_optimal_dq_shot.h"

// Returns nothing; writes the terminal ramp's voltage [V] at its start and at rest, from (w, id, iq) over tau, its
// d current's rate at the start c of -id / tau (time_optimal_dq_ramp.ramp_ends).
static void ramp_ends(const struct tod_model *md, fs_real w, fs_real id, fs_real iq, fs_real tau, fs_real c,
                      fs_real out[2])
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
// where the two are equal (bisection), or 0 (time_optimal_dq_ramp.ramp_share).
static fs_real ramp_share(const struct tod_model *md, fs_real w, fs_real id, fs_real iq, fs_real tau)
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

struct tod_end tod_terminal_ramp(const struct tod_model *md, fs_real t, const struct tod_state *s, const fs_real tg[2])
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
    tod_deriv(md, s->id, s->iq, s->w, tg[0], tg[1], r);
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

fs_real tod_ramp_voltage(const struct tod_model *md, const struct tod_end *e)
{
    fs_real v[2];
    if (!(e->tau > 0))
        return 0;
    ramp_ends(md, e->omega1, e->i_d1, e->i_q1, e->tau, e->d_share, v);
    return fs_max(v[0], v[1]) / md->v;
}
