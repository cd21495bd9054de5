// The simulated plant: the a-b model of eq. (1) with a load torque and the effects the paper leaves out.
#ifndef FS_PLANT_H
#define FS_PLANT_H

#include <stdbool.h>
#include <stdint.h>
#include "fs_real.h"
#include "motor.h"

// cffi:begin
// Torques on the rotor beyond eq. (1), as flatstep.plant.PlantEffects (all zero: none):
// -T_d sin(h Nr theta) - T_c tanh(omega / omega_s) - (Km^2 / R_m) omega.
struct plant_effects {
    fs_real detent_torque;           // T_d >= 0 [N m]
    uint32_t detent_harmonic;        // h >= 1 (4 for a two-phase hybrid); read only when T_d > 0
    fs_real coulomb_torque;          // T_c >= 0 [N m]
    fs_real coulomb_speed;           // omega_s > 0 [rad/s]; read only when T_c > 0
    fs_real magnetizing_resistance;  // R_m > 0 [ohm], or 0 for no iron loss
};

// The plant of a run: its own motor (may differ from any controller's model), a constant load, its effects.
struct plant {
    struct motor_params motor;
    fs_real load;  // [N m]
    struct plant_effects effects;
};

// Returns true when the motor, the load and every effect are finite and in range.
bool plant_valid(const struct plant *p);

// Returns true when any effect is present (plant_rhs is then motor_rhs plus their torque).
bool plant_has_effects(const struct plant *p);

// Returns the torque the effects add to the rotor [N m] at speed omega and angle theta.
fs_real plant_effects_torque(const struct plant *p, fs_real omega, fs_real theta);

// Returns the plant's true shaft acceleration theta'' [rad/s^2] at state x (what an ideal sensor reads).
fs_real plant_acceleration(const struct plant *p, const fs_real *x);

// Returns nothing; writes dx = f(x, v): eq. (1) with the load, plus the effects' torque over J.
void plant_rhs(const struct plant *p, const fs_real *x, const fs_real *v, fs_real *dx);
// cffi:end

#endif
