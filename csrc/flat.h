// Flat outputs (rho, theta) <-> state and inputs: eqs. (7)-(10) as corrected in flatstep.flat.
#ifndef FS_FLAT_H
#define FS_FLAT_H

#include "fs_real.h"
#include "motor.h"
#include "plan.h"

// cffi:begin

// Domain errors of the flat maps (bit flags); the maps never divide by zero.
enum {
    FLAT_OK = 0,
    FLAT_ERHO = 1,   // rho <= 0, not a number, or so small that a product with it underflows
    FLAT_ESQRT = 2,  // Km^2 rho^2 - A^2 <= 0 (or NaN, or rho sqrt(.) underflows): demand out of reach
};

// Returns FLAT_OK, or a FLAT_E* flag with v = (0, 0); writes the voltages that give rho' = drho and
// theta''' = dddtheta at (rho, phi, theta, theta', theta'') for the torque demand A (eqs. 9 and 13).
int flat_voltages(const struct motor_params *m, fs_real rho, fs_real drho, fs_real theta, fs_real dtheta,
                  fs_real ddtheta, fs_real dddtheta, fs_real phi, fs_real A, fs_real v[2]);

// The angles flat_voltages_trig takes, by sine and cosine: the current vector's phase phi and delta = Nr theta
// + phi (a controller gets them from the measured currents without atan2, sin or cos of phi).
struct flat_angles {
    fs_real sphi, cphi;      // sin phi = ia / rho, cos phi = ib / rho
    fs_real sdelta, cdelta;  // sin and cos of Nr theta + phi
};

// Returns FLAT_OK, or a FLAT_E* flag with v = (0, 0); flat_voltages with the angles given as sines and cosines.
int flat_voltages_trig(const struct motor_params *m, fs_real rho, fs_real drho, fs_real dtheta, fs_real ddtheta,
                       fs_real dddtheta, const struct flat_angles *a, fs_real A, fs_real v[2]);

// Returns FLAT_OK, or a FLAT_E* flag with x and v zeroed; writes the state x and inputs v along the flat
// flag for a known load torque (eqs. 9-10).
int flat_to_state(const struct motor_params *m, const fs_real flag[PLAN_FLAG_LEN], fs_real load, fs_real x[4],
                  fs_real v[2]);

// Returns FLAT_OK, or FLAT_ERHO with the flag zeroed when ia = ib = 0 (rho L underflows); writes the flat flag
// (rho, rho', theta, theta', theta'', theta''') of state x under inputs v through eq. (8).
int state_to_flat(const struct motor_params *m, const fs_real x[4], const fs_real v[2], fs_real load,
                  fs_real flag[PLAN_FLAG_LEN]);

// cffi:end
#endif
