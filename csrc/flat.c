// The flat maps of eqs. (7)-(10), in the operation order of flatstep.flat so that results agree to rounding.
#include "flat.h"

// Returns FLAT_OK, or a FLAT_E* flag with v = (0, 0); flat_voltages with the angles given as sines and cosines.
int flat_voltages_trig(const struct motor_params *m, fs_real rho, fs_real drho, fs_real dtheta, fs_real ddtheta,
                       fs_real dddtheta, const struct flat_angles *a, fs_real A, fs_real v[2])
{
    fs_real S2, S, dphi, X, Y;
    v[0] = v[1] = 0;
    if (!(rho > 0))
        return FLAT_ERHO;
    S2 = m->Km * m->Km * (rho * rho) - A * A;
    if (!(S2 > 0))
        return FLAT_ESQRT;
    S = fs_sqrt(S2);
    if (!(rho * S > 0))
        return FLAT_ESQRT;  // rho S underflowed: the division below would be by zero
    // phi' from the theta''' row of eq. (8) solved for phi'; the polar-frame voltages X, Y follow.
    dphi = -((m->J * dddtheta + m->B * ddtheta) * rho - A * drho) / (rho * S) - m->Nr * dtheta;
    X = m->L * drho + m->R * rho + m->Km * dtheta * a->cdelta;
    Y = m->L * rho * dphi - m->Km * dtheta * a->sdelta;
    v[0] = X * a->sphi + Y * a->cphi;
    v[1] = X * a->cphi - Y * a->sphi;
    return FLAT_OK;
}

// Returns FLAT_OK, or a FLAT_E* flag with v = (0, 0); writes the voltages that give rho' = drho and
// theta''' = dddtheta at (rho, phi, theta, theta', theta'') for the torque demand A (eqs. 9 and 13).
int flat_voltages(const struct motor_params *m, fs_real rho, fs_real drho, fs_real theta, fs_real dtheta,
                  fs_real ddtheta, fs_real dddtheta, fs_real phi, fs_real A, fs_real v[2])
{
    fs_real delta = m->Nr * theta + phi;
    struct flat_angles a;
    fs_sincos(phi, &a.sphi, &a.cphi);
    fs_sincos(delta, &a.sdelta, &a.cdelta);
    return flat_voltages_trig(m, rho, drho, dtheta, ddtheta, dddtheta, &a, A, v);
}

// Returns FLAT_OK, or a FLAT_E* flag with x and v zeroed; writes the state x and inputs v along the flat
// flag for a known load torque (eqs. 9-10).
int flat_to_state(const struct motor_params *m, const fs_real flag[PLAN_FLAG_LEN], fs_real load, fs_real x[4],
                  fs_real v[2])
{
    fs_real rho = flag[PLAN_RHO], A, c, phi;
    int k;
    for (k = 0; k < 4; k++)
        x[k] = 0;
    v[0] = v[1] = 0;
    if (!(rho > 0))
        return FLAT_ERHO;
    A = m->J * flag[PLAN_DDTHETA] + m->B * flag[PLAN_DTHETA] + load;
    if (!(m->Km * rho > 0))
        return FLAT_ERHO;
    c = A / (m->Km * rho);
    if (!(fs_fabs(c) < 1))
        return FLAT_ESQRT;
    phi = fs_acos(c) - m->Nr * flag[PLAN_THETA];
    fs_sincos(phi, &x[0], &x[1]);
    x[0] *= rho;
    x[1] *= rho;
    x[2] = flag[PLAN_DTHETA];
    x[3] = flag[PLAN_THETA];
    k = flat_voltages(m, rho, flag[PLAN_DRHO], flag[PLAN_THETA], flag[PLAN_DTHETA], flag[PLAN_DDTHETA],
                      flag[PLAN_DDDTHETA], phi, c * m->Km * rho, v);
    if (k != FLAT_OK)  // out of the voltages' domain (rho S underflows): x zeroed as well
        x[0] = x[1] = x[2] = x[3] = 0;
    return k;
}

// Returns FLAT_OK, or FLAT_ERHO with the flag zeroed when ia = ib = 0 (rho L underflows); writes the flat flag
// (rho, rho', theta, theta', theta'', theta''') of state x under inputs v through eq. (8).
int state_to_flat(const struct motor_params *m, const fs_real x[4], const fs_real v[2], fs_real load,
                  fs_real flag[PLAN_FLAG_LEN])
{
    fs_real rho = fs_hypot(x[0], x[1]), phi = fs_atan2(x[0], x[1]), omega = x[2], theta = x[3];
    fs_real delta, sp, cp, drho, dphi, ddtheta;
    int k;
    for (k = 0; k < PLAN_FLAG_LEN; k++)
        flag[k] = 0;
    if (!(m->L * rho > 0))
        return FLAT_ERHO;
    delta = m->Nr * theta + phi;
    sp = fs_sin(phi);
    cp = fs_cos(phi);
    drho = (-m->R * rho - m->Km * omega * fs_cos(delta) + v[1] * cp + v[0] * sp) / m->L;
    dphi = (m->Km * omega * fs_sin(delta) - v[1] * sp + v[0] * cp) / (m->L * rho);
    ddtheta = (m->Km * rho * fs_cos(delta) - m->B * omega - load) / m->J;
    flag[PLAN_RHO] = rho;
    flag[PLAN_DRHO] = drho;
    flag[PLAN_THETA] = theta;
    flag[PLAN_DTHETA] = omega;
    flag[PLAN_DDTHETA] = ddtheta;
    flag[PLAN_DDDTHETA] =
        (m->Km * drho * fs_cos(delta) - m->Km * rho * fs_sin(delta) * (m->Nr * omega + dphi) - m->B * ddtheta) / m->J;
    return FLAT_OK;
}
