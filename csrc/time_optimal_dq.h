// The field-weakening time-optimal planner in the d-q flat outputs (theta, i_d): flatstep.plan.time_optimal_dq in C.
#ifndef FS_TIME_OPTIMAL_DQ_H
#define FS_TIME_OPTIMAL_DQ_H

#include <stddef.h>
#include "fs_real.h"
#include "motor.h"
#include "time_optimal.h"
#include "trajectory.h"

// cffi:begin

// Sizes of the algorithm (the constants of flatstep.plan.time_optimal_dq*, which must match).
enum {
    TOD_PROBE = 48,                       // bisection halvings for the speed where no torque is left
    TOD_STEPS = 10,                       // integration steps per current rise time L i_max / V
    TOD_MAX_STEPS = 512,                  // steps of one phase, at most (more double the step)
    TOD_DOUBLINGS = 8,                    // doublings of the step, at most
    TOD_ROOT = 48,                        // braking phases tried by the root finder on the switch time, at most
    TOD_SWITCH = 4,                       // steps over which the target passes from speeding up to braking
    TOD_SHARE_HALVINGS = 24,              // halvings of the bisection on the terminal ramp's d share
    TOD_RAMP_TRIES = 4,                   // times the terminal ramp's rate may fall
    TOD_SHRINKS = 6,                      // shots after the first, at most
    TOD_KNOTS = 62,                       // knots picked by the measure (besides the kept ones)
    TOD_SAMPLES = 2 * TOD_MAX_STEPS + 6,  // samples of a shot, at most
};

// Return codes of time_optimal_dq_plan.
enum {
    TOD_OK = 0,
    TOD_EARGS = -1,    // a motor parameter, a limit or the distance is out of range or not finite
    TOD_ESTART = -2,   // at rest the bus and i_max leave no torque
    TOD_ENOPLAN = -3,  // no shot's table keeps the limits (or a phase needs too many steps)
    TOD_EWORK = -4,    // the workspace is shorter than time_optimal_dq_work_len()
};

// The limits of a field-weakening plan (flatstep.plan.limits.MotorLimits' fields that it reads).
struct tod_limits {
    fs_real v_bus;         // bus voltage [V], > 0
    fs_real v_use;         // fraction of v_bus the plan may use, in (0, 1]
    fs_real i_max;         // largest current magnitude [A], > 0
    fs_real speed_max;     // user's speed cap [rad/s], >= 0 (0: none)
    fs_real control_rate;  // the drive's control rate [Hz], > 0: the commutation cap
};

// A table's worst use of each limit (ratios, feasible at <= 1), the peak speed and the least d current.
struct tod_margins {
    fs_real voltage, current, speed, worst, i_d_min, speed_peak;
};

// The planned move from theta = 0 at t = 0: theta's segment table (struct traj layout) and the d current's cubic
// Hermite knots at the breaks.
struct tod_result {
    size_t n;                                     // segments
    fs_real breaks[TO_MAX_SEGMENTS + 1];          // n + 1 times [s]
    fs_real theta[TO_MAX_SEGMENTS * TRAJ_NCOEF];  // theta rows [rad], highest power first
    fs_real knot_id[TO_MAX_SEGMENTS + 1];         // the d current at the breaks [A]
    fs_real knot_did[TO_MAX_SEGMENTS + 1];        // its rate there [A/s]
    fs_real kappa;                                // the bus share the move was shot at (of v_use v_bus)
    fs_real width;                                // the integration step [s]
    struct tod_margins margins;                   // on the table at TO_CHECK samples per segment
    int tables;                                   // shots fitted and checked
};

// Returns the number of fs_real the workspace of time_optimal_dq_plan needs.
size_t time_optimal_dq_work_len(void);

// Returns the speed cap [rad/s]: 0.035 of the control rate in electrical frequency (about 29 control periods per
// electrical turn), and the user's cap.
fs_real time_optimal_dq_speed_cap(const struct motor_params *m, const struct tod_limits *lim);

// Returns TOD_OK and writes the field-weakening table over distance [rad] (!= 0, either sign) into out, or a TOD_E*
// code with out->n = 0: the move shot on the nominal d-q model at the bus's full rate, fitted, checked, shot again
// at a smaller share where the fit crosses a limit. work: time_optimal_dq_work_len() fs_real of caller-owned
// scratch.
int time_optimal_dq_plan(const struct motor_params *m, const struct tod_limits *lim, fs_real distance, fs_real *work,
                         size_t work_len, struct tod_result *out);

// cffi:end
#endif
