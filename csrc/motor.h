// Parameters of the two-phase PM stepper and the right-hand side of its a-b model, eq. (1).
#ifndef FS_MOTOR_H
#define FS_MOTOR_H

#include <stdbool.h>
#include "fs_real.h"

// cffi:begin

// State order everywhere: x = (ia, ib, omega, theta); inputs v = (va, vb).
struct motor_params {
    fs_real R;   // phase resistance [ohm], > 0
    fs_real L;   // phase inductance [H], > 0
    fs_real Km;  // torque / back-emf constant [N m/A], > 0
    fs_real J;   // inertia [kg m^2], > 0
    fs_real B;   // viscous friction [N m s/rad], >= 0
    int Nr;      // number of rotor teeth, >= 1
};

// Returns true when every parameter is finite and in range (R, L, Km, J > 0, B >= 0, Nr >= 1).
bool motor_params_valid(const struct motor_params *m);

// Returns the electromagnetic torque Km (ib cos Nr theta - ia sin Nr theta) [N m] at state x.
fs_real motor_torque(const struct motor_params *m, const fs_real x[4]);

// Returns the shaft acceleration (torque - B omega - load) / J [rad/s^2] at state x.
fs_real motor_acceleration(const struct motor_params *m, const fs_real x[4], fs_real load);

// Returns nothing; writes dx = f(x, v) of eq. (1) with a load torque on the shaft.
void motor_rhs(const struct motor_params *m, const fs_real x[4], const fs_real v[2], fs_real load, fs_real dx[4]);

// cffi:end
#endif
