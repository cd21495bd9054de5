// The one sampled loop, as flatstep.loop.reference: sensors -> observer -> controller -> drive -> plant, per period.
#ifndef FS_SAMPLED_H
#define FS_SAMPLED_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "controller.h"
#include "drive.h"
#include "fs_real.h"
#include "motor.h"
#include "observer.h"
#include "plant.h"
#include "sensors.h"
#include "torque_model.h"
#include "sim.h"

// cffi:begin
// The drive around the controller. Without sensors the controller reads the plant state exactly (and, without
// an observer, the plant's true acceleration); with sensors and no observer the speed is the encoder's
// backward difference and the acceleration is left to the controller's model (measurement "model").
struct sampled_params {
    fs_real Ts;                       // control period [s], > 0
    uint32_t substeps;                // RK4 steps per period, >= 1
    bool sensed;                      // read the plant through `sensors`
    bool observed;                    // estimate angle, speed and load with `observer`
    struct sensors_params sensors;    // used when sensed
    struct observer_params observer;  // used when observed
    struct drive_params drive;        // bus saturation (v_bus = infinity: none), computation delay, PWM
    struct motor_params model;        // the controller's nominal model: the observer's torque, the bridge's
                                      // start voltage R x0 (the start equilibrium)
    const volatile uint32_t *cancel;  // NULL, or a flag another thread sets to stop the run (SIM_ECANCELLED)
    struct torque_model torques;      // the torques the controller knows beyond eq. (1); the observer predicts
                                      // with the motor torque less them (all zero: none)
};

// Caller-owned state of a run: the parts' states and the previous encoder angle.
struct sampled {
    fs_real Ts;
    uint32_t substeps;
    uint32_t pwm_periods;  // switched PWM: PWM periods per control period
    bool sensed, observed;
    struct sensors sensors;
    struct observer observer;
    struct drive drive;
    struct motor_params model;
    struct torque_model torques;
    fs_real theta_prev;  // last angle the controller saw (backward difference)
    bool have_prev;
    const volatile uint32_t *cancel;
};

// Returns SIM_OK, or SIM_EARGS when a part's parameters are invalid (s is then left unusable).
int sampled_init(struct sampled *s, const struct sampled_params *p);

// Returns SIM_OK or an error sim_status (SIM_EARGS for a non-finite x0 or start voltage R x0, or an invalid plant);
// resets the parts and the controller and runs n_periods periods from x0 at t_k = k Ts. Period k: read the sensors
// with noise sample k (noise: (n_periods + 1) x 2, or NULL for none), correct the observer (by the edge the reading
// carries where its age is within [0, Ts), else by the count; its acceleration and
// prediction use the motor torque less the known torques), step the controller (0 V on a fault), saturate and delay
// in the drive, integrate the plant (plant_rhs: eq. (1), load and effects) by RK4 substeps under the applied voltage
// (switched PWM: one RK4 step per PWM segment, drive_pwm_period of the applied voltage and the currents at t_k,
// repeated for each PWM period), predict the observer. Writes, at every t_k, k = 0..n_periods, the plant state into
// x_out ((n_periods + 1) x 4), the voltage applied from t_k into v_out ((n_periods + 1) x 2), and, unless NULL, what
// the controller saw into y_out ((n_periods + 1) x 5) and its status into status_out.
int sampled_run(struct sampled *s, const struct controller *ctrl, const struct plant *plant, const fs_real *x0,
                size_t n_periods, const fs_real *noise, fs_real *x_out, fs_real *v_out, fs_real *y_out,
                uint32_t *status_out, struct sim_stats *st);
// cffi:end

#endif
