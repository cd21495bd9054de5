// The plant's right-hand side: motor_rhs plus the effects' torque, in the operation order of flatstep.plant.
#include "plant.h"

// Returns true when x is finite and >= 0.
static bool nonnegative(fs_real x)
{
    return fs_isfinite(x) && x >= 0;
}

// Returns true when the motor, the load and every effect are finite and in range.
bool plant_valid(const struct plant *p)
{
    const struct plant_effects *e = &p->effects;
    return motor_params_valid(&p->motor) && fs_isfinite(p->load) && nonnegative(e->detent_torque)
           && (e->detent_torque == 0 || e->detent_harmonic >= 1) && nonnegative(e->coulomb_torque)
           && (e->coulomb_torque == 0 || (fs_isfinite(e->coulomb_speed) && e->coulomb_speed > 0))
           && nonnegative(e->magnetizing_resistance);
}

// Returns the torque the effects add to the rotor [N m] at speed omega and angle theta.
fs_real plant_effects_torque(const struct plant *p, fs_real omega, fs_real theta)
{
    const struct plant_effects *e = &p->effects;
    fs_real out = 0, s, c;
    if (e->detent_torque > 0) {
        fs_sincos((fs_real)e->detent_harmonic * (fs_real)p->motor.Nr * theta, &s, &c);
        out = -e->detent_torque * s;
    }
    if (e->coulomb_torque > 0)
        out = out - e->coulomb_torque * fs_tanh(omega / e->coulomb_speed);
    if (e->magnetizing_resistance > 0)
        out = out - p->motor.Km * p->motor.Km / e->magnetizing_resistance * omega;
    return out;
}

// Returns true when any effect is present (plant_rhs is then motor_rhs plus their torque).
bool plant_has_effects(const struct plant *p)
{
    const struct plant_effects *e = &p->effects;
    return e->detent_torque > 0 || e->coulomb_torque > 0 || e->magnetizing_resistance > 0;
}

// Returns the plant's true shaft acceleration theta'' [rad/s^2] at state x (what an ideal sensor reads).
fs_real plant_acceleration(const struct plant *p, const fs_real *x)
{
    fs_real acc = motor_acceleration(&p->motor, x, p->load);
    return plant_has_effects(p) ? acc + plant_effects_torque(p, x[2], x[3]) / p->motor.J : acc;
}

// Returns nothing; writes dx = f(x, v): eq. (1) with the load, plus the effects' torque over J.
void plant_rhs(const struct plant *p, const fs_real *x, const fs_real *v, fs_real *dx)
{
    motor_rhs(&p->motor, x, v, p->load, dx);
    if (plant_has_effects(p))
        dx[2] = dx[2] + plant_effects_torque(p, x[2], x[3]) / p->motor.J;
}
