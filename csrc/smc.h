// The paper's flatness + sliding-mode controller, eqs. (12)-(14), with a boundary layer and output guards.
#ifndef FS_SMC_H
#define FS_SMC_H

#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "motor.h"
#include "plan.h"
#include "torque_model.h"
#include "trajectory.h"

// cffi:begin

// Where theta'' comes from: the measurement y[4] (the paper's assumption) or the zero-load model.
enum smc_measurement { SMC_IDEAL = 0, SMC_MODEL = 1 };

// Status bits returned by smc_step. Any bit below SMC_SATURATED is a fault: the step then outputs
// v = (0, 0), i.e. de-energises both phases, which is the safe state of a PM stepper (no current can run
// away; the detent torque and friction hold the rotor) until the caller decides to re-energise.
// The bits are the controller interface's (controller.h), named for this law.
enum smc_status {
    SMC_OK = CTRL_OK,
    SMC_NONFINITE = CTRL_NONFINITE,  // t or a used measurement is NaN or infinite
    SMC_RHO = CTRL_RHO,              // current magnitude rho < rho_min: phi is undefined
    SMC_SQRT = CTRL_SQRT,            // Km^2 rho^2 - (J theta'' + B theta')^2 <= 0: the torque demand is out of reach
    SMC_OVERFLOW = CTRL_OVERFLOW,    // the law overflowed to a non-finite voltage from finite inputs
    SMC_SATURATED = CTRL_SATURATED,  // |v| > v_limit: v scaled to |v| = v_limit keeping its direction (not a fault)
};

// Errors of smc_init: which group of parameters is invalid.
enum smc_param_error {
    SMC_PARAMS_OK = 0,
    SMC_EMOTOR,
    SMC_EPLAN,
    SMC_EGAINS,
    SMC_EMEASUREMENT,
    SMC_ELIMITS,
    SMC_ETORQUES,  // torque_model_valid fails
};

// Design constants; the paper's are W1 = W2 = 100, eps1 = eps2 = 0.005, xi = 0.8, wn = 10.
struct smc_gains {
    fs_real W1, W2;        // reaching gains [A/s], [rad/s^3], > 0
    fs_real eps1, eps2;    // boundary-layer widths of s/(|s| + eps), > 0
    fs_real xi, wn;        // alpha1 = wn^2, alpha2 = 2 xi wn, > 0
    fs_real hold_damping;  // 0: track the plan to the end; > 0: from tf on, hold the detent of theta2 with this
                           // damping ratio (smc_step)
};

// The loss-aware rho*(t) = sqrt(rho_hold^2 + (A* / (Km cos margin))^2), A* = J theta*'' + B theta*' + E at the
// planned angle (flatstep.plan.loss_aware); rho_hold = 0: the plan's rho.
struct smc_loss_aware {
    fs_real margin;    // [rad], in [0, pi/2)
    fs_real rho_hold;  // [A], >= 0
};

struct smc_params {
    struct motor_params motor;  // the controller's model of the motor
    struct plan plan;           // the planned flat outputs: psi, or a table (plan.traj) with its end points
    struct smc_gains gains;
    int measurement;                   // enum smc_measurement
    fs_real v_limit;                   // bound on |v| = hypot(va, vb) [V], finite and >= 1e-3 (no denormal scaling)
    fs_real rho_min;                   // smallest current magnitude the law acts on [A], > 0
    struct torque_model torques;       // torques the law knows beyond eq. (1); all zero: the paper's law bit for bit
    struct smc_loss_aware loss_aware;  // rho_hold > 0: track the loss-aware rho*(t) instead of the plan's rho
};

struct smc {
    struct smc_params p;
    struct plan_coef plan;     // p.plan ready to evaluate (plan_init)
    fs_real alpha1, alpha2;    // wn^2, 2 xi wn
    fs_real v_limit2_below;    // just below v_limit^2: va^2 + vb^2 under it needs no hypot
    fs_real hold_gain;         // 2 hold_damping sqrt(J Nr / (Km rho2)): sin of the hold's torque angle per rad/s
    fs_real hold_s2, hold_c2;  // sin and cos of Nr theta2
    fs_real hold_lambda;       // W1 / eps1: the rate of the hold's current loop [1/s]
    bool torques_constant;     // torque_model_constant(&p.torques): E = load, E' = 0 without the model's calls
    bool loss_aware;           // p.loss_aware.rho_hold > 0: the plan's rho replaced by rho*(t)
    bool hold;                 // p.gains.hold_damping > 0: the detent hold from tf on
    bool hold_torques;         // hold and a known torque: the hold turns by its load angle on theta2
    uint32_t status_seen;      // OR of every status since the last reset
};

// Which fields of struct smc_terms a step wrote (bits of smc_terms.have).
enum smc_terms_have {
    SMC_HAVE_FLAG = 1,  // flag: the inputs were finite
    SMC_HAVE_LAW = 2,   // rho .. s2: rho >= rho_min as well (the law ran to its voltages)
};

// The intermediate values of one step (smc_step_terms), for a caller that reports them beside the voltages.
struct smc_terms {
    fs_real flag[PLAN_FLAG_LEN];  // the plan's flat flag at t (plan_flag)
    fs_real rho;                  // sqrt(ia^2 + ib^2) (hypot where the squares would over- or underflow)
    fs_real sphi, cphi;           // sin phi = ia / rho, cos phi = ib / rho (phi = atan2(ia, ib))
    fs_real snr, cnr;             // sin and cos of Nr theta
    fs_real acc;                  // the theta'' the law used: y[4], or the model's under the known torques
    fs_real s1, s2;               // the sliding variables of eq. (12)
    uint32_t have;                // SMC_HAVE_* bits; the other fields are unset
};

// Returns nothing; fills p with the paper's motor, move (Section 3) and gains, ideal measurement,
// v_limit = 1e3 V, rho_min = 1e-6 A, no torque model and no table.
void smc_params_default(struct smc_params *p);

// Returns SMC_PARAMS_OK, or the smc_param_error naming the invalid group (s is then left unusable).
int smc_init(struct smc *s, const struct smc_params *p);

// Returns nothing; clears the accumulated status of a controller set up by smc_init.
void smc_reset(struct smc *s);

// Returns the smc_status bits of this step; writes finite phase voltages v with hypot(v) <= v_limit for any
// time t and measurement y = (ia, ib, omega, theta, theta'') (y[4] read in SMC_IDEAL mode only).
// With gains.hold_damping = zeta > 0 and t >= tf, the voltages are the detent hold's instead of the law's:
// i* = rho2 (cos p, sin p), p = Nr theta2 + asin(clip(E(t, theta2, 0) / (Km rho2), +-1))
// + asin(clip(-2 zeta sqrt(J Nr / (Km rho2)) omega, +-1)) with E the known torque (0 without torques),
// v = R i* + L (W1 / eps1) (i* - i) + Km omega (-sin Nr theta, cos Nr theta) (flatstep.control.smc).
uint32_t smc_step(struct smc *s, fs_real t, const fs_real y[5], fs_real v[2]);

// Returns smc_step's status and writes its voltages v, bit for bit; also writes the step's intermediate values
// into w (w->have says which). nr_trig: NULL, or sin and cos of Nr y[3] already computed by the caller (the
// controller's Nr), which the step then uses instead of computing them.
uint32_t smc_step_terms(struct smc *s, fs_real t, const fs_real y[5], const fs_real *nr_trig, fs_real v[2],
                        struct smc_terms *w);

// Returns nothing; binds s into the run loops' interface (a stateless law: the continuous loop may run it).
void smc_controller(struct smc *s, struct controller *c);

// cffi:end
#endif
