// A controller's model of the torques eq. (1) leaves out: detent, Coulomb friction, a known load (flatstep.model
// torque_model).
#ifndef FS_TORQUE_MODEL_H
#define FS_TORQUE_MODEL_H

#include <stdbool.h>
#include <stdint.h>
#include "fs_real.h"

// cffi:begin
// E = tau(t) + Td sin(h Nr theta + phase) + Tc tanh(omega / omega_s), tau(t) = load + load_step psi(t, load_t0,
// load_tf): the torque on the shaft beyond eq. (1), J theta'' = Km i_q - B omega - E. All zero: none.
struct torque_model {
    fs_real detent_torque;     // Td >= 0 [N m]
    uint32_t detent_harmonic;  // h >= 1; read only when Td > 0
    fs_real detent_phase;      // [rad]
    fs_real coulomb_torque;    // Tc >= 0 [N m]
    fs_real coulomb_speed;     // omega_s > 0 [rad/s]; read only when Tc > 0
    fs_real load;              // constant load [N m]
    fs_real load_step;         // load change along psi [N m]; 0: none
    fs_real load_t0, load_tf;  // the change's start and end [s], load_tf > load_t0 when load_step != 0
};

// Returns true when every field is finite and in range.
bool torque_model_valid(const struct torque_model *m);

// Returns true when E is the constant load alone (no load change, detent or Coulomb term): torque_model_torque
// then returns m->load and torque_model_rate 0, bit for bit.
bool torque_model_constant(const struct torque_model *m);

// Returns E [N m] at time t, angle theta and speed omega for a motor of Nr rotor teeth.
fs_real torque_model_torque(const struct torque_model *m, int Nr, fs_real t, fs_real theta, fs_real omega);

// Returns dE/dt [N m/s] along a motion with angle theta, speed omega and acceleration acc at time t.
fs_real torque_model_rate(const struct torque_model *m, int Nr, fs_real t, fs_real theta, fs_real omega, fs_real acc);
// cffi:end

#endif
