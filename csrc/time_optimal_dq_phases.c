// The field-weakening shot's phases: the speeding-up phase from rest, the state at a switch time and the braking
// phase from it to the terminal ramp, integrated under the policy (flatstep.plan.time_optimal_dq_phases, operation
// for operation).
#include "time_optimal_dq_shot.h"

bool tod_speed_up(const struct tod_model *md, fs_real d, const struct tod_phase *a, size_t *n, bool *cruise)
{
    struct tod_state s = {0, 0, 0, 0};
    fs_real tg[2], nxt[2];
    size_t k;
    tod_target(md, 0, false, 0, 0, tg);
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
            tod_next_speed_up(md, &s, tg, nxt);
            s = tod_step(md, &s, tg, nxt, 1);
            tg[0] = nxt[0], tg[1] = nxt[1];
        }
    }
    return false;
}

size_t tod_step_index(fs_real t, fs_real h, size_t n_acc)
{
    fs_real k = t / h;
    if (!(k > 0))
        return 0;
    return k < (fs_real)(n_acc - 1) ? (size_t)k : n_acc - 1;
}

// Returns the state at the switch t_s and writes the speeding-up target there (time_optimal_dq_phases.switch_state).
static struct tod_state switch_state(const struct tod_model *md, const struct tod_phase *a, size_t n_acc, bool cruise,
                                     fs_real t_s, fs_real tg[2])
{
    fs_real h = md->h, t0[2], t1[2], f;
    size_t k;
    struct tod_state s;
    if (cruise && t_s >= (fs_real)(n_acc - 1) * h) {
        k = n_acc - 1;
        s.th = a->theta[k] + a->omega[k] * (t_s - (fs_real)k * h), s.w = a->omega[k], s.id = a->i_d[k],
        s.iq = a->i_q[k];
        tg[0] = a->t_d[k], tg[1] = a->t_q[k];
        return s;
    }
    k = tod_step_index(t_s, h, n_acc);
    s.th = a->theta[k], s.w = a->omega[k], s.id = a->i_d[k], s.iq = a->i_q[k];
    t0[0] = a->t_d[k], t0[1] = a->t_q[k];
    if (!(t_s > (fs_real)k * h)) {
        tg[0] = t0[0], tg[1] = t0[1];
        return s;
    }
    if (k + 1 < n_acc)
        t1[0] = a->t_d[k + 1], t1[1] = a->t_q[k + 1];
    else
        tod_next_speed_up(md, &s, t0, t1);
    f = (t_s - (fs_real)k * h) / h;
    tg[0] = t0[0] + f * (t1[0] - t0[0]), tg[1] = t0[1] + f * (t1[1] - t0[1]);
    return tod_step(md, &s, t0, t1, f);
}

bool tod_brake(const struct tod_model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real t_s,
               const struct tod_phase *out, struct tod_end *end, size_t *n_b)
{
    fs_real tg[2], into[2], t1[2], at[2], g, g_next, f, lam, t_j, w_j, t_end;
    struct tod_state s = switch_state(md, a, n_acc, cruise, t_s, tg), nxt;
    size_t j;
    into[0] = tg[0], into[1] = tg[1];
    g = tod_curve(md, &s);
    *n_b = 0;
    if (g >= 0 || !(s.w > 0)) {
        *end = tod_terminal_ramp(md, t_s, &s, tg);
        return true;
    }
    for (j = 0; j < TOD_MAX_STEPS; j++) {
        if (out) {
            out->theta[j] = s.th, out->omega[j] = s.w, out->i_d[j] = s.id, out->i_q[j] = s.iq;
            out->t_d[j] = tg[0], out->t_q[j] = tg[1];
        }
        tod_next_target(md, &s, true, t1);
        if (j + 1 < TOD_SWITCH) {
            lam = ((fs_real)j + 1) / TOD_SWITCH;
            t1[0] = into[0] + lam * (t1[0] - into[0]), t1[1] = into[1] + lam * (t1[1] - into[1]);
        }
        t_j = tod_brake_time(t_s, md->h, j);
        w_j = (tod_brake_time(t_s, md->h, j + 1) - t_j) / md->h;  // the step the samples' times span (float: not 1)
        nxt = tod_step(md, &s, tg, t1, w_j);
        g_next = tod_curve(md, &nxt);
        if (g_next >= 0 || !(nxt.w > 0)) {
            f = w_j * (g_next >= 0 ? g / (g - g_next) : s.w / (s.w - nxt.w));
            t_end = t_j + f * md->h;
            f = (t_end - t_j) / md->h;  // (likewise)
            at[0] = tg[0] + f * (t1[0] - tg[0]), at[1] = tg[1] + f * (t1[1] - tg[1]);
            nxt = tod_step(md, &s, tg, t1, f);
            *end = tod_terminal_ramp(md, t_end, &nxt, at);
            *n_b = j + 1;
            return true;
        }
        s = nxt, g = g_next, tg[0] = t1[0], tg[1] = t1[1];
    }
    return false;
}
