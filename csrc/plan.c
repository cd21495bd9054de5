// The degree-10 interpolating polynomial psi of eq. (17) and the rest-to-rest flat flag built on it.
#include "plan.h"

// Power-basis coefficients (lowest first) of psi(tau) and its first three tau-derivatives; integers, so
// exact in float and double. psi = tau^5 (252 - 1050 tau + 1800 tau^2 - 1575 tau^3 + 700 tau^4 - 126 tau^5).
static const fs_real psi_coef[4][11] = {
    {0, 0, 0, 0, 0, 252, -1050, 1800, -1575, 700, -126},
    {0, 0, 0, 0, 1260, -6300, 12600, -12600, 6300, -1260},
    {0, 0, 0, 5040, -31500, 75600, -88200, 50400, -11340},
    {0, 0, 15120, -126000, 378000, -529200, 352800, -90720},
};

// Returns true when every field is finite, rho1, rho2 > 0 and tf > t0 with (tf - t0)^3 > 0.
bool plan_valid(const struct plan *p)
{
    // (tf - t0)^3 > 0 as well: a span whose cube underflows would make psi's third derivative divide by 0.
    return fs_isfinite(p->theta1) && fs_isfinite(p->theta2) && fs_isfinite(p->rho1) && fs_isfinite(p->rho2)
        && fs_isfinite(p->t0) && fs_isfinite(p->tf) && p->rho1 > 0 && p->rho2 > 0 && p->tf > p->t0
        && fs_pow(p->tf - p->t0, 3) > 0;
}

// Returns the Horner value of the order-th derivative polynomial of psi at tau (the numpy polyval order).
static fs_real psi_horner(int order, fs_real tau)
{
    const fs_real *c = psi_coef[order];
    int j = 10 - order;
    fs_real acc = c[j];
    while (j-- > 0)
        acc = c[j] + acc * tau;
    return acc;
}

// Returns the order-th time derivative (0..3) of psi(t, t0, tf) of eq. (17): held at 0 before t0 and at 1
// after tf, derivatives 0 outside the open interval (t0, tf); 0 for an order out of range, for tf <= t0
// and for a span so short that (tf - t0)^order underflows.
fs_real plan_psi(fs_real t, fs_real t0, fs_real tf, int order)
{
    fs_real T = tf - t0, Tk, tau;
    if (order < 0 || order > 3 || !(T > 0))
        return 0;
    Tk = fs_pow(T, (fs_real)order);
    if (!(Tk > 0) || (order > 0 && !(t > t0 && t < tf)))
        return 0;
    tau = (t - t0) / T;
    tau = tau < 0 ? 0 : (tau > 1 ? 1 : tau);
    return psi_horner(order, tau) / Tk;
}

// Returns true while the move runs (t0 < t < tf); writes the flag (rho, rho', theta, theta', theta'',
// theta''') at time t, exactly as flatstep.plan.RestToRest.flag.
bool plan_eval(const struct plan *p, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    fs_real dth = p->theta2 - p->theta1, drho = p->rho2 - p->rho1;
    fs_real p0 = plan_psi(t, p->t0, p->tf, 0), p1 = plan_psi(t, p->t0, p->tf, 1);
    fs_real p2 = plan_psi(t, p->t0, p->tf, 2), p3 = plan_psi(t, p->t0, p->tf, 3);
    flag[PLAN_RHO] = p->rho1 + p0 * drho;
    flag[PLAN_DRHO] = p1 * drho;
    flag[PLAN_THETA] = p->theta1 + p0 * dth;
    flag[PLAN_DTHETA] = p1 * dth;
    flag[PLAN_DDTHETA] = p2 * dth;
    flag[PLAN_DDDTHETA] = p3 * dth;
    return t > p->t0 && t < p->tf;
}
