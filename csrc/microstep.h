// Open-loop microstepping: the plan's sine/cosine current references tracked by a-b PI loops (flatstep.control.microstep).
#ifndef FS_MICROSTEP_H
#define FS_MICROSTEP_H

#include <stdbool.h>
#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "motor.h"
#include "plan.h"

// cffi:begin
// Errors of microstep_init: which group of parameters is invalid.
enum microstep_param_error {
    MICROSTEP_PARAMS_OK = 0,
    MICROSTEP_EMOTOR,   // motor_params_valid fails
    MICROSTEP_EPLAN,    // plan_valid fails, or the resting integrals R i*(t0 - 1) overflow
    MICROSTEP_EGAINS,   // current_bandwidth not finite and > 0, or kp = L wc, ki = R wc overflow
    MICROSTEP_EPERIOD,  // Ts not finite and > 0, or ki Ts overflows
    MICROSTEP_ELIMITS,  // v_limit not > 0 (INFINITY is allowed: no limit)
};

// As flatstep.MicrostepGains.
struct microstep_gains {
    fs_real current_bandwidth;  // wc [rad/s], > 0: PI gains kp = L wc, ki = R wc (pole-zero cancellation)
    bool feedforward;           // add R i* + L di*/dt to the PI output
    bool back_emf;              // add the back EMF at the plan's speed, Km theta*' (-sin Nr theta*, cos Nr theta*)
    bool load_angle;            // lead Nr theta* by asin((J theta*'' + B theta*') / (Km rho*)), clipped
};

struct microstep_params {
    struct motor_params motor;  // the driver's nominal model (R, L, Nr are used)
    struct plan plan;           // any plan: theta*(t) the commanded angle, rho*(t) the run current
    struct microstep_gains gains;
    fs_real Ts;       // control period [s] of the PI integrators, > 0
    fs_real v_limit;  // the bus its anti-windup knows [V], > 0; INFINITY: no limit
};

// Caller-owned state of the driver.
struct microstep {
    struct microstep_params p;
    struct plan_coef plan;  // p.plan ready to evaluate
    fs_real kp, ki_Ts;      // L wc and R wc Ts
    fs_real integral[2];    // the a and b PI integrals [V] (Python's state)
};

// Returns MICROSTEP_PARAMS_OK, or the microstep_param_error naming the invalid group (s is then unusable).
int microstep_init(struct microstep *s, const struct microstep_params *p);

// Returns nothing; sets the integrals to Microstepping.initial_state(): 0 with the feedforward, else
// R i*(t0 - 1), the resistive voltage of the start current.
void microstep_reset(struct microstep *s);

// Returns ctrl_status bits; writes the driver's command v = (va, vb) for time t and y = (ia, ib, ...) (only the
// currents are read) and advances the integrals by one period Ts, as Microstepping.step. v is not limited:
// CTRL_SATURATED says max(|va|, |vb|) > v_limit, and the integrals then hold (anti-windup). On a fault
// (CTRL_NONFINITE: t, ia, ib or an integral not finite; CTRL_OVERFLOW: v or an integral would not be finite)
// v = (0, 0) and the state is left unchanged.
uint32_t microstep_step(struct microstep *s, fs_real t, const fs_real *y, fs_real *v);

// Returns nothing; binds s into the run loops' interface (not stateless: the integrals advance each step).
void microstep_controller(struct microstep *s, struct controller *c);
// cffi:end

#endif
