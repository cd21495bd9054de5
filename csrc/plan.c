// The degree-10 interpolating polynomial psi of eq. (17) and the rest-to-rest flat flag built on it.
#include "plan.h"
#include "trajectory.h"

// Power-basis coefficients of psi(tau) and its first three tau-derivatives, row j holding the tau^j
// coefficient of each (so one Horner step reads one row); integers, so exact in float and double.
// psi = tau^5 (252 - 1050 tau + 1800 tau^2 - 1575 tau^3 + 700 tau^4 - 126 tau^5). The derivatives are padded
// with zero leading coefficients, which leave Horner's accumulator at exactly 0, so every chain rounds
// exactly as numpy.polyval on the unpadded polynomial.
static const fs_real psi_coef[11][4] = {
    {0, 0, 0, 0},
    {0, 0, 0, 0},
    {0, 0, 0, 15120},
    {0, 0, 5040, -126000},
    {0, 1260, -31500, 378000},
    {252, -6300, 75600, -529200},
    {-1050, 12600, -88200, 352800},
    {1800, -12600, 50400, -90720},
    {-1575, 6300, -11340, 0},
    {700, -1260, 0, 0},
    {-126, 0, 0, 0},
};

// Returns true when every field is finite, the angles and currents at most FS_REAL_MAX / 4 in magnitude, rho1,
// rho2 > 0 and tf > t0 with (tf - t0)^3 > 0, and a table, if set, is traj_valid.
bool plan_valid(const struct plan *p)
{
    // (tf - t0)^3 > 0 as well: a span whose cube underflows would make psi's third derivative divide by 0. Angles and
    // currents within FS_REAL_MAX / 4: theta1 + psi (theta2 - theta1) stays finite for psi up to 1.5 (Horner's
    // rounding takes psi a little past 1), and the held derivatives 0 (theta2 - theta1) are 0, not NaN.
    const fs_real big = FS_REAL_MAX / 4;
    return fs_fabs(p->theta1) <= big && fs_fabs(p->theta2) <= big && p->rho1 <= big && p->rho2 <= big
           && fs_isfinite(p->t0) && fs_isfinite(p->tf) && p->rho1 > 0 && p->rho2 > 0 && p->tf > p->t0
           && fs_pow(p->tf - p->t0, 3) > 0 && (p->traj == NULL || traj_valid(p->traj));
}

// Returns nothing; writes (tf - t0)^k, k = 0..3, as the reference's T**k (pow), or 0 when tf <= t0.
static void span_powers(fs_real t0, fs_real tf, fs_real Tk[4])
{
    fs_real T = tf - t0;
    int k;
    for (k = 0; k < 4; k++)
        Tk[k] = T > 0 ? fs_pow(T, (fs_real)k) : 0;
}

// Returns nothing; writes the four psi tau-polynomials at tau in one Horner pass (four independent chains).
static void psi_horner(fs_real tau, fs_real d[4])
{
    fs_real a0 = 0, a1 = 0, a2 = 0, a3 = 0;
    const fs_real *c;
    int j;
    for (j = 10; j >= 0; j--) {
        c = psi_coef[j];
        a0 = c[0] + a0 * tau;
        a1 = c[1] + a1 * tau;
        a2 = c[2] + a2 * tau;
        a3 = c[3] + a3 * tau;
    }
    d[0] = a0, d[1] = a1, d[2] = a2, d[3] = a3;
}

// Returns nothing; writes psi and its first three time derivatives at t (see plan_psi) from the span powers.
static void psi_all(fs_real t, fs_real t0, fs_real tf, const fs_real Tk[4], fs_real d[4])
{
    bool inside = t > t0 && t < tf;
    fs_real tau;
    int k;
    if (!(tf > t0) || (!inside && (t <= t0 || t >= tf))) {
        // tf <= t0: all 0. At rest: psi(0) = 0 and psi(1) = 1 exactly (its coefficients sum to 1), derivatives
        // 0. Only a NaN t goes on: psi is then NaN and its derivatives 0, as in the reference.
        d[0] = tf > t0 && t >= tf ? 1 : 0;
        d[1] = d[2] = d[3] = 0;
        return;
    }
    tau = (t - t0) / (tf - t0);
    tau = tau < 0 ? 0 : (tau > 1 ? 1 : tau);
    psi_horner(tau, d);
    for (k = 1; k < 4; k++)
        d[k] = inside && Tk[k] > 0 ? d[k] / Tk[k] : 0;  // the reference divides by T**k; an underflowed power: 0
}

// Returns nothing; writes the flag for psi and its time derivatives d.
static void flag_of_psi(const struct plan_coef *c, const fs_real d[4], fs_real flag[PLAN_FLAG_LEN])
{
    flag[PLAN_RHO] = c->p.rho1 + d[0] * c->drho;
    flag[PLAN_DRHO] = d[1] * c->drho;
    flag[PLAN_THETA] = c->p.theta1 + d[0] * c->dtheta;
    flag[PLAN_DTHETA] = d[1] * c->dtheta;
    flag[PLAN_DDTHETA] = d[2] * c->dtheta;
    flag[PLAN_DDDTHETA] = d[3] * c->dtheta;
}

// Returns plan_valid(p); fills c from p either way (for tf <= t0 plan_flag then holds the start values, and
// a derivative whose (tf - t0)^k underflows evaluates to 0).
bool plan_init(struct plan_coef *c, const struct plan *p)
{
    fs_real d[4];
    c->p = *p;
    c->traj = p->traj;
    span_powers(p->t0, p->tf, c->Tk);
    c->dtheta = p->theta2 - p->theta1;
    c->drho = p->rho2 - p->rho1;
    psi_all(p->t0, p->t0, p->tf, c->Tk, d);
    flag_of_psi(c, d, c->rest[0]);
    psi_all(p->tf, p->t0, p->tf, c->Tk, d);
    flag_of_psi(c, d, c->rest[1]);
    return plan_valid(p);
}

// Returns true while the move runs (t0 < t < tf); writes the flag (rho, rho', theta, theta', theta'',
// theta''') at time t, exactly as flatstep.plan.RestToRest.flag: one pass over the four psi polynomials.
// With c->traj set, returns and writes traj_flag(c->traj, t, flag) instead.
bool plan_flag(const struct plan_coef *c, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    const fs_real *rest;
    fs_real d[4];
    if (c->traj)
        return traj_flag(c->traj, t, flag);
    if (t <= c->p.t0 || t >= c->p.tf) {  // at rest: the flag held since t0 or from tf on
        rest = c->rest[t >= c->p.tf];
        flag[0] = rest[0], flag[1] = rest[1], flag[2] = rest[2];
        flag[3] = rest[3], flag[4] = rest[4], flag[5] = rest[5];
        return false;
    }
    psi_all(t, c->p.t0, c->p.tf, c->Tk, d);
    flag_of_psi(c, d, flag);
    return t > c->p.t0 && t < c->p.tf;
}

// Returns the order-th time derivative (0..3) of psi(t, t0, tf) of eq. (17): held at 0 before t0 and at 1
// after tf, derivatives 0 outside the open interval (t0, tf); 0 for an order out of range, for tf <= t0
// and for a span so short that (tf - t0)^order underflows.
fs_real plan_psi(fs_real t, fs_real t0, fs_real tf, int order)
{
    fs_real Tk[4], d[4];
    if (order < 0 || order > 3)
        return 0;
    span_powers(t0, tf, Tk);
    psi_all(t, t0, tf, Tk, d);
    return d[order];
}

// Returns plan_flag's value for a plan used once (plan_init on the stack, then plan_flag); writes the flag.
bool plan_eval(const struct plan *p, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    struct plan_coef c;
    plan_init(&c, p);
    return plan_flag(&c, t, flag);
}
