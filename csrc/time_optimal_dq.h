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
    TOD_PROBE = 48,     // bisection halvings for the speed where no torque is left
    TOD_SEARCH = 7,     // tables tried per smoothing width on the bus share kappa
    TOD_WIDTHS = 5,     // smoothing widths tried (DEFAULT_WIDTHS)
    TOD_ID_SPREAD = 4,  // the d current's running mean, in smoothing widths either side
};

// Return codes of time_optimal_dq_plan.
enum {
    TOD_OK = 0,
    TOD_EARGS = -1,    // a motor parameter, a limit or the distance is out of range or not finite
    TOD_ESTART = -2,   // at rest the bus and i_max leave no torque
    TOD_ENOPLAN = -3,  // no smoothing width and bus share give a table within the limits
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
    fs_real kappa;                                // the bus share of the envelope
    fs_real width;                                // smoothing width [s]
    struct tod_margins margins;                   // on the table at TO_CHECK samples per segment
    int tables;                                   // tables built and checked
};

// Returns the number of fs_real the workspace of time_optimal_dq_plan needs.
size_t time_optimal_dq_work_len(void);

// Returns the speed cap [rad/s]: 0.035 of the control rate in electrical frequency (about 29 control periods per
// electrical turn), and the user's cap.
fs_real time_optimal_dq_speed_cap(const struct motor_params *m, const struct tod_limits *lim);

// Returns TOD_OK and writes the shortest feasible field-weakening table over distance [rad] (!= 0, either sign)
// into out, or a TOD_E* code with out->n = 0. work: time_optimal_dq_work_len() fs_real of caller-owned scratch.
int time_optimal_dq_plan(const struct motor_params *m, const struct tod_limits *lim, fs_real distance, fs_real *work,
                         size_t work_len, struct tod_result *out);

// cffi:end
#endif
