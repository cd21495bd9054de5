// The time-optimal rest-to-rest planner: the smoothed envelope move of flatstep.plan.time_optimal, in C.
#ifndef FS_TIME_OPTIMAL_H
#define FS_TIME_OPTIMAL_H

#include <stddef.h>
#include "fs_real.h"
#include "motor.h"
#include "trajectory.h"

// cffi:begin

// Sizes of the algorithm (the constants of flatstep.plan.time_optimal, which must match).
enum {
    TO_GRID = 192,                   // speed-grid points of the phase plane
    TO_PROBE = 64,                   // speed-grid points of the probe for the top speed
    TO_FINE = 1000,                  // time samples of the smoothed profile, at least
    TO_FINE_MAX = 4000,              // time samples of the smoothed profile, at most (a long cruise is cut)
    TO_PER_PHASE = 16,               // samples over the shortest of speed-up, braking and smoothing width
    TO_KNOTS = 64,                   // segments of the table in speed-up and braking (4 more in a cruise)
    TO_CHECK = 8,                    // samples per segment of the margin check (tau = j / 8)
    TO_SEARCH = 6,                   // tables tried per smoothing width on gamma
    TO_MAX_WIDTHS = 8,               // smoothing widths a call may try
    TO_MAX_SEGMENTS = TO_KNOTS + 4,  // segments of a planned table, at most
    TO_MAX_SAMPLES = 2000000,        // time samples of a whole move at the full bus, at most (float: below 2^24)
};

// Return codes of time_optimal_plan.
enum {
    TO_OK = 0,
    TO_EARGS = -1,    // a motor parameter, a limit, the distance or a width is out of range or not finite (or
                      // v_use v_bus underflows to 0)
    TO_ESTART = -2,   // at rest the bus and the limits leave no torque: the motor cannot start (or its envelope is no
                      // number: an acceleration below 5e-312 rad/s^2 or beyond the largest double, J near 1e-318,
                      // or a top speed of 0, speed_max near 1e-323)
    TO_ENOPLAN = -3,  // no smoothing width and bus fraction give a table within the limits
    TO_EWORK = -4,    // the workspace is shorter than time_optimal_work_len()
    TO_ELONG = -5,    // the move would take more than TO_MAX_SAMPLES samples: split it into shorter moves
};

// The motor's limits on a plan (flatstep.plan.limits.MotorLimits): a cap of 0 is no cap.
struct to_limits {
    fs_real v_bus;             // bus voltage [V], > 0
    fs_real i_max;             // largest current magnitude rho [A], > i_hold
    fs_real i_hold;            // current across the torque axis at rest [A], > 0
    fs_real i_run;             // current across the torque axis at speed [A], in (0, i_hold]
    fs_real speed_corner;      // speed [rad/s] where the across-axis floor is halfway from i_hold to i_run, > 0
    fs_real torque_angle_max;  // largest torque angle [rad], in (0, pi/2)
    fs_real v_use;             // fraction of v_bus the plan's feedforward may use, in (0, 1], v_use v_bus > 0
    fs_real speed_max, accel_max, jerk_max;  // caps [rad/s, rad/s^2, rad/s^3], >= 0 (0: none)
};

// A plan's worst use of each limit: ratios (feasible at <= 1); worst is the search's measure, the voltage over
// 0.998 v_use and every other ratio over 1, the largest less 1 (<= 0: feasible).
struct to_margins {
    fs_real voltage, current, torque_angle, speed, acceleration, jerk, worst;
};

// The planned move: a segment table (struct traj layout) from theta = 0 at t = 0, and how it was found.
struct to_result {
    size_t n;                                     // segments
    fs_real breaks[TO_MAX_SEGMENTS + 1];          // n + 1 times [s]
    fs_real theta[TO_MAX_SEGMENTS * TRAJ_NCOEF];  // theta rows [rad], highest power first
    fs_real rho[TO_MAX_SEGMENTS * TRAJ_NCOEF];    // rho rows [A]
    fs_real gamma;                                // fraction of the bus of the envelope
    fs_real width;                                // smoothing width [s]
    struct to_margins margins;                    // on the table at TO_CHECK samples per segment
    int tables;                                   // tables built and checked
};

// Returns the number of fs_real the workspace of time_optimal_plan needs.
size_t time_optimal_work_len(void);

// Returns TO_OK and writes the shortest feasible table over distance [rad] (!= 0, either sign) into out, or a
// TO_E* code with out->n = 0. widths: n_widths smoothing widths [s] to try (> 0), or NULL and 0 for the default
// set (1/4, 1/2, 1, 2, 4 times L/R). work: time_optimal_work_len() fs_real of caller-owned scratch memory.
int time_optimal_plan(const struct motor_params *m, const struct to_limits *lim, fs_real distance,
                      const fs_real *widths, size_t n_widths, fs_real *work, size_t work_len, struct to_result *out);

// Returns the margins of a table (the search's check: tau = j / TO_CHECK on each segment, and the end); every ratio
// inf when the motor, the limits (time_optimal_plan's ranges) or the table (traj_valid) is invalid or the table's
// values overflow; voltage, torque angle and worst inf where the demand is out of reach. No ratio is NaN.
struct to_margins time_optimal_margins(const struct motor_params *m, const struct to_limits *lim,
                                       const struct traj *tr);

// cffi:end
#endif
