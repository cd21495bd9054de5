// Flatness + sliding-mode control on the d-q flat outputs (theta, i_d) (flatstep.control.dq_smc).
#ifndef FS_DQ_SMC_H
#define FS_DQ_SMC_H

#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "motor.h"
#include "plan.h"
#include "smc.h"
#include "torque_model.h"

// cffi:begin
// Errors of dq_smc_init: which group of parameters is invalid.
enum dq_smc_param_error {
    DQ_SMC_PARAMS_OK = 0,
    DQ_SMC_EMOTOR,        // motor_params_valid fails
    DQ_SMC_EPLAN,         // plan_valid fails, or the d-current plan is not finite (or tf <= t0 with i_d1 != i_d2, or
                          // its table's knots are not rising)
    DQ_SMC_EGAINS,        // a gain not finite and > 0, or hold_damping != 0 (this law has no detent hold)
    DQ_SMC_EMEASUREMENT,  // not SMC_IDEAL or SMC_MODEL
    DQ_SMC_ELIMITS,       // v_limit not finite and >= 1e-3
    DQ_SMC_ETORQUES,      // torque_model_valid fails
    DQ_SMC_EINTEGRAL,     // ki not finite and >= 0, or with ki > 0: Ts or v_hold not finite and > 0
    DQ_SMC_EADAPT,        // rate not finite and >= 0, or with rate > 0: Ts, v_hold, phi0 not finite and > 0, phi0^2
                          // underflows to 0, or range not in (0, 1)
    DQ_SMC_EADVANCE,      // advance not finite and >= 0
};

// Integral action on s2 (off with ki = 0): Gamma2 -= ki z, z += Ts s2 after each step, held (anti-windup) while
// |s2| > eps2 (outside the boundary layer), while hypot(v) > v_hold (the bus) and on a step that faults.
struct dq_smc_integral {
    fs_real ki;      // >= 0 [1/s^2]
    fs_real Ts;      // the control period [s]
    fs_real v_hold;  // the bus voltage the anti-windup knows [V]
};

// Online estimate Km^ of the torque constant (off with rate = 0: Km^ = motor.Km, today's law): Km^ replaces Km in
// the law and, after each step, Km^ += Ts rate (J lambda) s2 phi / (phi0^2 + phi^2), lambda = W2/eps2, along the
// plan's regressor phi = (J theta*''' + B theta*'' + E'(t, theta*, theta*', theta*''))/Km^ - Km^ theta*'/L [A/s]
// (0 at rest), projected into motor.Km (1 +- range); held as the integral is (|s2| > eps2, hypot(v) > v_hold,
// a fault).
struct dq_smc_adaptation {
    fs_real rate;    // >= 0 [1/s]: the estimate's convergence rate at full excitation (|phi| >> phi0)
    fs_real phi0;    // the regressor below which the estimate slows down (no excitation at rest) [A/s]
    fs_real range;   // in (0, 1): the projection's relative half-width around motor.Km
    fs_real Ts;      // the control period [s]
    fs_real v_hold;  // the bus voltage the estimate's hold knows [V]
};

// Knots of a planned d-current table, at most.
enum { DQ_SMC_ID_KNOTS = 72 };

// The planned d current i_d*(t) = i_d1 + psi(t, t0, tf) (i_d2 - i_d1) - weakening max(|theta*'| - weakening_speed, 0),
// with the paper's psi of eq. (17) and the planned speed theta*' (flatstep.plan.d_current); with n_knots >= 2 the
// cubic Hermite table through (knot_id, knot_did) at the times knot_t (held outside) replaces the psi term.
struct dq_smc_current {
    fs_real i_d1, i_d2;                 // start and end d current [A]
    fs_real t0, tf;                     // start and end of the change [s]; read only when i_d2 != i_d1
    fs_real weakening;                  // k_w >= 0 [A s/rad]: field weakening per rad/s above weakening_speed
    fs_real weakening_speed;            // >= 0 [rad/s]
    uint32_t n_knots;                   // 0 (no table) or 2..DQ_SMC_ID_KNOTS
    fs_real knot_t[DQ_SMC_ID_KNOTS];    // rising times [s]
    fs_real knot_id[DQ_SMC_ID_KNOTS];   // d current at the knots [A]
    fs_real knot_did[DQ_SMC_ID_KNOTS];  // its rate at the knots [A/s]
};

struct dq_smc_params {
    struct motor_params motor;        // the controller's model of the motor
    struct plan plan;                 // the planned angle, psi or a table (its rho channel is not read)
    struct dq_smc_current current;    // the planned d current
    struct smc_gains gains;           // W1, eps1 act on s1 = i_d - i_d*; W2, eps2, xi, wn on s2 as in smc
    struct torque_model torques;      // the torques the law knows beyond eq. (1)
    int measurement;                  // enum smc_measurement: theta'' from y[4] or from the model with E
    fs_real v_limit;                  // bound on |v| = hypot(va, vb) [V], finite and >= 1e-3
    struct dq_smc_integral integral;  // integral action on s2 (ki = 0: none, a stateless law)
    struct dq_smc_adaptation adapt;   // the online Km^ (rate = 0: none)
    fs_real advance;                  // >= 0 [s]: the inverse Park at Nr (theta + omega advance) (0: none)
};

// Caller-owned state of the law (stateless between steps but for the accumulated status).
struct dq_smc {
    struct dq_smc_params p;
    struct plan_coef plan;   // p.plan ready to evaluate
    fs_real alpha1, alpha2;  // wn^2, 2 xi wn
    fs_real z;               // the integral of s2 [rad/s]
    fs_real km;              // the estimate Km^ [N m/A] (motor.Km without adaptation)
    uint32_t status_seen;    // OR of every status since the last reset
};

// Returns nothing; fills p with the paper's motor, move and gains, i_d* = 0, no torque model, ideal measurement
// and v_limit = 1e3 V.
void dq_smc_params_default(struct dq_smc_params *p);

// Returns DQ_SMC_PARAMS_OK, or the dq_smc_param_error naming the invalid group (s is then left unusable).
int dq_smc_init(struct dq_smc *s, const struct dq_smc_params *p);

// Returns nothing; clears the accumulated status and the integral, and sets Km^ = motor.Km.
void dq_smc_reset(struct dq_smc *s);

// Returns ctrl_status bits; writes finite voltages v with hypot(v) <= v_limit for any t and y = (ia, ib, omega,
// theta, theta'') (y[4] read in SMC_IDEAL mode only): s1 = i_d - i_d*, s2 = e'' + a2 e' + a1 e (e = theta -
// theta*), Gamma1 = i_d*' - W1 s1/(|s1| + eps1), Gamma2 = theta*''' - a2 e'' - a1 e' - W2 s2/(|s2| + eps2) - ki z, and
// v = inverse Park of (L Gamma1 + R i_d - L Nr omega i_q, L (J Gamma2 + B theta'' + E')/Km + R i_q + L Nr omega
// i_d + Km omega), with Km^ for Km (also in SMC_MODEL's theta''); then z and Km^ advance (struct dq_smc_integral,
// struct dq_smc_adaptation). CTRL_NONFINITE: a used input is not finite; CTRL_OVERFLOW: v would not be; both give
// v = 0.
uint32_t dq_smc_step(struct dq_smc *s, fs_real t, const fs_real y[5], fs_real v[2]);

// Returns nothing; binds s into the run loops' interface (stateless without integral action or adaptation: the
// continuous loop may run it).
void dq_smc_controller(struct dq_smc *s, struct controller *c);
// cffi:end

#endif
