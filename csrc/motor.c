// The a-b model of the PM stepper, eq. (1), evaluated in the same operation order as flatstep.motor.
#include "motor.h"

// Returns true when every parameter is finite and in range (R, L, Km, J > 0, B >= 0, Nr >= 1).
bool motor_params_valid(const struct motor_params *m)
{
    return fs_isfinite(m->R) && m->R > 0 && fs_isfinite(m->L) && m->L > 0 && fs_isfinite(m->Km) && m->Km > 0
           && fs_isfinite(m->J) && m->J > 0 && fs_isfinite(m->B) && m->B >= 0 && m->Nr >= 1;
}

// Returns the electromagnetic torque Km (ib cos Nr theta - ia sin Nr theta) [N m] at state x.
fs_real motor_torque(const struct motor_params *m, const fs_real x[4])
{
    fs_real s, c;
    fs_sincos(m->Nr * x[3], &s, &c);
    return m->Km * (x[1] * c - x[0] * s);
}

// Returns the shaft acceleration (torque - B omega - load) / J [rad/s^2] at state x.
fs_real motor_acceleration(const struct motor_params *m, const fs_real x[4], fs_real load)
{
    return (motor_torque(m, x) - m->B * x[2] - load) / m->J;
}

// Returns nothing; writes dx = f(x, v) of eq. (1) with a load torque on the shaft.
void motor_rhs(const struct motor_params *m, const fs_real x[4], const fs_real v[2], fs_real load, fs_real dx[4])
{
    fs_real s, c;
    fs_sincos(m->Nr * x[3], &s, &c);
    dx[0] = (v[0] - m->R * x[0] + m->Km * x[2] * s) / m->L;
    dx[1] = (v[1] - m->R * x[1] - m->Km * x[2] * c) / m->L;
    dx[2] = (m->Km * (x[1] * c - x[0] * s) - m->B * x[2] - load) / m->J;
    dx[3] = x[2];
}
