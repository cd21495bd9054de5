// The field-weakening shot's model under the bus-saturated current-steering policy: the run's constants, the
// targets the policy steers the current to, the model's rates under it and one RK4 step
// (flatstep.plan.time_optimal_dq_policy, operation for operation).
#include "time_optimal_dq_shot.h"

bool tod_model_init(struct tod_model *md, const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap,
                    fs_real h)
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

void tod_deriv(const struct tod_model *md, fs_real id, fs_real iq, fs_real w, fs_real td, fs_real tq, fs_real out[3])
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

void tod_target(const struct tod_model *md, fs_real w, bool braking, fs_real lead, fs_real ahead, fs_real t[2])
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

void tod_next_target(const struct tod_model *md, const struct tod_state *s, bool braking, fs_real t[2])
{
    fs_real alpha = (md->Km * s->iq - md->B * s->w) / md->J,
            share = fs_min(md->rho / TOD_RHO_FULL, 1)
                    * fs_min(fs_max((md->reactance - TOD_X_END) / (TOD_X_FULL - TOD_X_END), 0), 1),
            ahead = fs_min(fs_max((md->cap - s->w) / md->band, 0), 1) * TOD_AHEAD * share, n2, r2, q;
    tod_target(md, s->w + md->h * alpha, braking, md->tc * alpha, ahead * md->tc * fs_max(alpha, 0), t);
    if (braking) {  // a current beyond TOD_PULL_FROM i_max pulls its target in
        n2 = s->id * s->id + s->iq * s->iq;
        r2 = (TOD_PULL_FROM * md->i_max) * (TOD_PULL_FROM * md->i_max);
        if (n2 > r2) {
            q = r2 / n2;
            t[0] = t[0] * q * q, t[1] = t[1] * q * q;
        }
    }
}

void tod_next_speed_up(const struct tod_model *md, const struct tod_state *s, const fs_real tg[2], fs_real t[2])
{
    fs_real slew = TOD_D_SLEW * md->h * md->v * md->inv_l;
    tod_next_target(md, s, false, t);
    t[0] = fs_min(fs_max(t[0], tg[0] - slew), tg[0] + slew);
}

struct tod_state tod_step(const struct tod_model *md, const struct tod_state *s, const fs_real t0[2],
                          const fs_real t1[2], fs_real f)
{
    fs_real h = f * md->h, dd = t1[0] - t0[0], dq = t1[1] - t0[1], k1[3], k2[3], k3[3], k4[3];
    struct tod_state o;
    tod_deriv(md, s->id, s->iq, s->w, t0[0], t0[1], k1);
    tod_deriv(md, s->id + FS_C(0.5) * h * k1[0], s->iq + FS_C(0.5) * h * k1[1], s->w + FS_C(0.5) * h * k1[2],
              t0[0] + FS_C(0.5) * f * dd, t0[1] + FS_C(0.5) * f * dq, k2);
    tod_deriv(md, s->id + FS_C(0.5) * h * k2[0], s->iq + FS_C(0.5) * h * k2[1], s->w + FS_C(0.5) * h * k2[2],
              t0[0] + FS_C(0.5) * f * dd, t0[1] + FS_C(0.5) * f * dq, k3);
    tod_deriv(md, s->id + h * k3[0], s->iq + h * k3[1], s->w + h * k3[2], t0[0] + f * dd, t0[1] + f * dq, k4);
    o.th =
        s->th
        + h / 6 * (s->w + 2 * (s->w + FS_C(0.5) * h * k1[2]) + 2 * (s->w + FS_C(0.5) * h * k2[2]) + (s->w + h * k3[2]));
    o.w = s->w + h / 6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
    o.id = s->id + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
    o.iq = s->iq + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
    return o;
}

fs_real tod_curve(const struct tod_model *md, const struct tod_state *s)
{
    return -s->iq - fs_sqrt(2 * md->end_rate * fs_max(s->w, 0));
}
