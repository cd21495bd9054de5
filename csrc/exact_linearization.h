// Zribi-Chiasson exact linearization in d-q with pole placement on theta and i_d (flatstep.control.exact_linearization).
#ifndef FS_EXACT_LINEARIZATION_H
#define FS_EXACT_LINEARIZATION_H

#include <stdbool.h>
#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "motor.h"
#include "plan.h"
#include "torque_model.h"

// cffi:begin
// Where theta'' comes from: y[4] (Python's "ideal" and "observer") or the zero-load model (Km iq - B omega) / J
// (Python's "model", Zribi and Chiasson's state feedback).
enum exact_linearization_measurement { EXACT_LINEARIZATION_MEASURED = 0, EXACT_LINEARIZATION_MODEL = 1 };

// Errors of exact_linearization_init: which group of parameters is invalid.
enum exact_linearization_param_error {
    EXACT_LINEARIZATION_PARAMS_OK = 0,
    EXACT_LINEARIZATION_EMOTOR,        // motor_params_valid fails, or L / Km overflows
    EXACT_LINEARIZATION_EPLAN,         // plan_valid fails
    EXACT_LINEARIZATION_EGAINS,        // wn, xi, p3, pd not finite and > 0, or k0, k1, k2 overflow
    EXACT_LINEARIZATION_EMEASUREMENT,  // not an exact_linearization_measurement
    EXACT_LINEARIZATION_ELIMITS,       // v_limit not > 0 (INFINITY is allowed: no limit)
    EXACT_LINEARIZATION_ETORQUES,      // torque_model_valid fails
};

// As flatstep.LinearizationGains: the angle error's poles (s + p3)(s^2 + 2 xi wn s + wn^2), the d current's s + pd.
struct exact_linearization_gains {
    fs_real wn;  // [rad/s], > 0
    fs_real xi;  // > 0
    fs_real p3;  // [rad/s], > 0
    fs_real pd;  // [rad/s], > 0
};

struct exact_linearization_params {
    struct motor_params motor;  // the controller's nominal model
    struct plan plan;           // the move, psi or a table (theta*, theta*', theta*'', theta*''')
    struct exact_linearization_gains gains;
    int measurement;              // enum exact_linearization_measurement
    fs_real v_limit;              // > 0, INFINITY: none; only sets CTRL_SATURATED (the law is static, no windup)
    struct torque_model torques;  // the known torques E (theta'' model: - E / J; vq: + L E' / Km); all zero: none
};

// Caller-owned state of the law: its parameters and constants, nothing that a step changes.
struct exact_linearization {
    struct exact_linearization_params p;
    struct plan_coef plan;  // p.plan ready to evaluate
    fs_real k0, k1, k2;     // s^3 + k2 s^2 + k1 s + k0 = (s + p3)(s^2 + 2 xi wn s + wn^2)
    fs_real L_Nr, L_Km;     // L Nr and L / Km
};

// Returns EXACT_LINEARIZATION_PARAMS_OK, or the exact_linearization_param_error naming the invalid group.
int exact_linearization_init(struct exact_linearization *s, const struct exact_linearization_params *p);

// Returns nothing; the law has no state (ExactLinearization.step passes its state through).
void exact_linearization_reset(struct exact_linearization *s);

// Returns ctrl_status bits; writes the law's voltages v = (va, vb) for time t and y = (ia, ib, omega, theta,
// theta'') (y[4] read in EXACT_LINEARIZATION_MEASURED mode only), as ExactLinearization.step. v is not limited:
// CTRL_SATURATED says max(|va|, |vb|) > v_limit. On a fault (CTRL_NONFINITE: t or a used y not finite;
// CTRL_OVERFLOW: v would not be finite) v = (0, 0).
uint32_t exact_linearization_step(struct exact_linearization *s, fs_real t, const fs_real *y, fs_real *v);

// Returns nothing; binds s into the run loops' interface (stateless: the continuous loop may evaluate it).
void exact_linearization_controller(struct exact_linearization *s, struct controller *c);
// cffi:end

#endif
