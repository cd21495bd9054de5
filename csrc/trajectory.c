// traj_flag: segment lookup by bisection, then Horner chains for each output and derivative.
#include "trajectory.h"

// Falling factorials p! / (p - k)! for the power p = 10 - j of coefficient j and k = 1..4 (row k - 1): the factor
// that the k-th tau-derivative puts on that coefficient. Integers, so exact in float and double.
static const fs_real traj_fall[4][TRAJ_NCOEF] = {
    {10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0},
    {90, 72, 56, 42, 30, 20, 12, 6, 2, 0, 0},
    {720, 504, 336, 210, 120, 60, 24, 6, 0, 0, 0},
    {5040, 3024, 1680, 840, 360, 120, 24, 0, 0, 0, 0},
};

// Returns true when n >= 1, the pointers are set, every break and coefficient is finite, the breaks increase,
// every segment's width h is finite (so t - breaks[i] cannot overflow inside it) and its (1 / h)^4 is finite (no
// derivative can overflow from the scaling alone).
bool traj_valid(const struct traj *tr)
{
    size_t i, j;
    fs_real ih;
    if (tr == NULL || tr->n < 1 || tr->breaks == NULL || tr->theta == NULL || tr->rho == NULL)
        return false;
    for (i = 0; i < tr->n; i++) {
        if (!(fs_isfinite(tr->breaks[i]) && fs_isfinite(tr->breaks[i + 1]) && tr->breaks[i + 1] > tr->breaks[i]))
            return false;
        ih = 1 / (tr->breaks[i + 1] - tr->breaks[i]);
        if (!(ih > 0) || !fs_isfinite(ih * ih * ih * ih))  // h overflowing: ih 0, and t - breaks[i] may overflow
            return false;
        for (j = 0; j < TRAJ_NCOEF; j++)
            if (!(fs_isfinite(tr->theta[i * TRAJ_NCOEF + j]) && fs_isfinite(tr->rho[i * TRAJ_NCOEF + j])))
                return false;
    }
    return true;
}

// Returns the segment i whose [breaks[i], breaks[i + 1]) holds t, clamped to 0 .. n - 1 (0 for a NaN t).
size_t traj_segment(const struct traj *tr, fs_real t)
{
    size_t lo = 0, hi = tr->n, mid;
    // Invariant: breaks[lo] <= t < breaks[hi] for t inside; a t outside (or NaN) ends at 0 or n - 1.
    while (hi - lo > 1) {
        mid = lo + (hi - lo) / 2;
        if (t < tr->breaks[mid])
            hi = mid;
        else
            lo = mid;
    }
    return t >= tr->breaks[0] ? lo : 0;
}

// Returns the polynomial of row c at tau (one Horner chain over the TRAJ_NCOEF coefficients).
static fs_real traj_value(const fs_real *c, fs_real tau)
{
    fs_real a = c[0];
    int j;
    for (j = 1; j < TRAJ_NCOEF; j++)
        a = a * tau + c[j];
    return a;
}

// Returns nothing; writes the flag at t inside segment i: six independent Horner chains, theta and its first three
// tau-derivatives, rho and its first, then the powers of 1 / h.
static void traj_eval(const struct traj *tr, size_t i, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    const fs_real *th = tr->theta + i * TRAJ_NCOEF, *rh = tr->rho + i * TRAJ_NCOEF;
    const fs_real *f1 = traj_fall[0], *f2 = traj_fall[1], *f3 = traj_fall[2];
    fs_real ih = 1 / (tr->breaks[i + 1] - tr->breaks[i]), tau = (t - tr->breaks[i]) * ih, ih2;
    fs_real a0, a1, a2, a3, r0, r1;
    int j;
    // The k-th derivative's chain reads the coefficients of powers >= k only (j <= 10 - k), each times its
    // falling factorial.
    a0 = th[0], a1 = th[0] * f1[0], a2 = th[0] * f2[0], a3 = th[0] * f3[0];
    r0 = rh[0], r1 = rh[0] * f1[0];
    for (j = 1; j < TRAJ_NCOEF - 3; j++) {
        a0 = a0 * tau + th[j];
        a1 = a1 * tau + th[j] * f1[j];
        a2 = a2 * tau + th[j] * f2[j];
        a3 = a3 * tau + th[j] * f3[j];
        r0 = r0 * tau + rh[j];
        r1 = r1 * tau + rh[j] * f1[j];
    }
    // j = 8: the third derivative's chain ended at j = 7
    a0 = a0 * tau + th[8], a1 = a1 * tau + th[8] * f1[8], a2 = a2 * tau + th[8] * f2[8];
    r0 = r0 * tau + rh[8], r1 = r1 * tau + rh[8] * f1[8];
    a0 = a0 * tau + th[9], a1 = a1 * tau + th[9] * f1[9];
    r0 = r0 * tau + rh[9], r1 = r1 * tau + rh[9] * f1[9];
    a0 = a0 * tau + th[10], r0 = r0 * tau + rh[10];
    ih2 = ih * ih;
    flag[PLAN_RHO] = r0;
    flag[PLAN_DRHO] = r1 * ih;
    flag[PLAN_THETA] = a0;
    flag[PLAN_DTHETA] = a1 * ih;
    flag[PLAN_DDTHETA] = a2 * ih2;
    flag[PLAN_DDDTHETA] = a3 * (ih2 * ih);
}

// Returns false; writes the held flag before the start (or for a NaN t) or from the end on.
static bool traj_rest(const struct traj *tr, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    flag[PLAN_DRHO] = flag[PLAN_DTHETA] = flag[PLAN_DDTHETA] = flag[PLAN_DDDTHETA] = 0;
    if (t >= tr->breaks[tr->n]) {  // after the end: the last segment's value at tau = 1
        flag[PLAN_THETA] = traj_value(tr->theta + (tr->n - 1) * TRAJ_NCOEF, 1);
        flag[PLAN_RHO] = traj_value(tr->rho + (tr->n - 1) * TRAJ_NCOEF, 1);
    } else {  // before the start: the value at tau = 0, the constant term
        flag[PLAN_THETA] = tr->theta[TRAJ_NCOEF - 1];
        flag[PLAN_RHO] = tr->rho[TRAJ_NCOEF - 1];
    }
    return false;
}

// Returns true while breaks[0] < t < breaks[n]; writes the flag (rho, rho', theta, theta', theta'', theta''') at
// t in the layout of plan_flag, as flatstep.plan.piecewise.PiecewisePlan.flag does, operation for operation.
bool traj_flag(const struct traj *tr, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    if (!(t > tr->breaks[0] && t < tr->breaks[tr->n]))
        return traj_rest(tr, t, flag);
    traj_eval(tr, traj_segment(tr, t), t, flag);
    return true;
}

// Returns and writes what traj_flag does; *seg is the caller's guess of the segment (the last call's), checked,
// then its successor, then bisection; on return the segment of t.
bool traj_flag_seg(const struct traj *tr, fs_real t, size_t *seg, fs_real flag[PLAN_FLAG_LEN])
{
    size_t i = *seg;
    if (!(t > tr->breaks[0] && t < tr->breaks[tr->n]))
        return traj_rest(tr, t, flag);
    if (!(i < tr->n && tr->breaks[i] <= t && t < tr->breaks[i + 1])) {
        i = i + 1;
        if (!(i < tr->n && tr->breaks[i] <= t && t < tr->breaks[i + 1]))
            i = traj_segment(tr, t);
    }
    *seg = i;
    traj_eval(tr, i, t, flag);
    return true;
}

// Returns nothing; writes traj_flag at each of the n times t into flag (n x PLAN_FLAG_LEN, row-major).
void traj_flag_n(const struct traj *tr, const fs_real *t, size_t n, fs_real *flag)
{
    size_t k, seg = 0;
    for (k = 0; k < n; k++)
        traj_flag_seg(tr, t[k], &seg, flag + k * PLAN_FLAG_LEN);
}

// Returns the order-th time derivative (0..4) of theta at t (0 for an order out of range), for a caller that needs
// the snap theta'''' as well.
fs_real traj_theta(const struct traj *tr, fs_real t, int order)
{
    const fs_real *th, *f;
    fs_real tau, ih, a, scale = 1;
    size_t i;
    int j, k;
    if (order < 0 || order > 4)
        return 0;
    if (!(t > tr->breaks[0]) || t >= tr->breaks[tr->n]) {
        if (order > 0)
            return 0;
        return t >= tr->breaks[tr->n] ? traj_value(tr->theta + (tr->n - 1) * TRAJ_NCOEF, 1) : tr->theta[TRAJ_NCOEF - 1];
    }
    i = traj_segment(tr, t);
    th = tr->theta + i * TRAJ_NCOEF;
    ih = 1 / (tr->breaks[i + 1] - tr->breaks[i]);
    tau = (t - tr->breaks[i]) * ih;
    if (order == 0)
        return traj_value(th, tau);
    f = traj_fall[order - 1];
    a = th[0] * f[0];
    for (j = 1; j <= TRAJ_NCOEF - 1 - order; j++)
        a = a * tau + th[j] * f[j];
    for (k = 0; k < order; k++)
        scale = scale * ih;
    return a * scale;
}
