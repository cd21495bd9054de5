// Cascaded field-oriented control: a P-PI position-velocity loop over d-q PI current loops (flatstep.control.cascade).
#ifndef FS_CASCADE_H
#define FS_CASCADE_H

#include <stdbool.h>
#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "motor.h"
#include "plan.h"
#include "torque_model.h"

// cffi:begin
// Errors of cascade_init: which group of parameters is invalid.
enum cascade_param_error {
    CASCADE_PARAMS_OK = 0,
    CASCADE_EMOTOR,    // motor_params_valid fails
    CASCADE_EPLAN,     // plan_valid fails
    CASCADE_EGAINS,    // wc, k_theta, k_omega not finite and > 0, ki_omega or d_hold finite >= 0, or L wc overflows
    CASCADE_EPERIOD,   // Ts not finite and > 0, or ki Ts overflows
    CASCADE_ELIMITS,   // v_limit not > 0 (INFINITY is allowed: no limit)
    CASCADE_ETORQUES,  // torque_model_valid fails
};

// As flatstep.CascadeGains: the current PIs' bandwidth and the P-PI loop's gains (the rule's w / 3, 2.25 w,
// 0.75 w^2 for a bandwidth w, or any others).
struct cascade_gains {
    fs_real current_bandwidth;  // wc [rad/s], > 0: current PIs kp = L wc, ki = R wc
    fs_real k_theta;            // position gain [1/s], > 0
    fs_real k_omega;            // velocity gain [1/s], > 0
    fs_real ki_omega;           // velocity integral gain [1/s^2], >= 0
    bool decoupling;            // add -L Nr omega iq to vd and L Nr omega id + Km omega to vq
    bool voltage_feedforward;   // add R iq_ff + L iq_ff' to vq, iq_ff = (J theta*'' + B theta*' + E*) / Km on the plan
                                // (and R id* + L id*' to vd with plan_frame)
    bool plan_frame;            // the current loops in the plan's frame (Park by Nr theta*) with id* = d_hold rho*(t)
    fs_real d_hold;             // with plan_frame: the share of the plan's rho* held on d, finite and >= 0
};

struct cascade_params {
    struct motor_params motor;  // the controller's nominal model
    struct plan plan;           // the move: psi, or a table (plan.traj)
    struct cascade_gains gains;
    fs_real Ts;                   // control period [s] of the integrators, > 0
    fs_real v_limit;              // the bus its anti-windup knows [V], > 0; INFINITY: no limit
    struct torque_model torques;  // anti-cogging: the known torques E join iq* as E / Km (all zero: none)
};

// Caller-owned state of the cascade.
struct cascade {
    struct cascade_params p;
    struct plan_coef plan;  // p.plan ready to evaluate
    fs_real ki_omega_Ts;    // ki_omega Ts
    fs_real kp, ki_Ts;      // L wc and R wc Ts of the current loops
    fs_real L_Nr;           // L Nr, the decoupling's factor
    fs_real integral[3];    // velocity loop [rad/s^2], d and q current loops [V] (Python's state)
};

// Returns CASCADE_PARAMS_OK, or the cascade_param_error naming the invalid group (s is then unusable).
int cascade_init(struct cascade *s, const struct cascade_params *p);

// Returns nothing; sets the three integrals to 0 (CascadeFOC.initial_state()).
void cascade_reset(struct cascade *s);

// Returns ctrl_status bits; writes the cascade's command v = (va, vb) for time t and y = (ia, ib, omega, theta,
// theta'') (y[4] is not read; iq* carries E(t, theta, omega) / Km of the torque model; with voltage_feedforward vq
// carries R iq_ff + L iq_ff' with E and E' along the plan; with plan_frame the currents are regulated in the plan's
// frame, id* = d_hold rho*, the decoupling at the plan's speed and the back EMF at the measured angle) and advances
// the integrals by one period Ts, as CascadeFOC.step. v is not limited:
// CTRL_SATURATED says max(|va|, |vb|) > v_limit, and the integrals then hold (anti-windup). On a fault
// (CTRL_NONFINITE: t, y[0..3] or an integral not finite; CTRL_OVERFLOW: v or an integral would not be finite)
// v = (0, 0) and the state is left unchanged.
uint32_t cascade_step(struct cascade *s, fs_real t, const fs_real *y, fs_real *v);

// Returns nothing; binds s into the run loops' interface (not stateless: the integrals advance each step).
void cascade_controller(struct cascade *s, struct controller *c);
// cffi:end

#endif
