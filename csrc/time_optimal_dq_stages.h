// The stages of the field-weakening planner (csrc/time_optimal_dq.c): the envelope's best currents
// (time_optimal_dq_envelope.c, flatstep.plan.time_optimal_dq_envelope) and the shot move
// (time_optimal_dq_shoot.c and its parts, time_optimal_dq_shot.h; flatstep.plan.time_optimal_dq_shoot). Internal: not
// bound by Python.
#ifndef FS_TIME_OPTIMAL_DQ_STAGES_H
#define FS_TIME_OPTIMAL_DQ_STAGES_H

#include <stdbool.h>
#include <stddef.h>
#include "time_optimal_dq.h"

#define TOD_LAG FS_C(0.5)          // the current's time constant under the policy, in current rise times
#define TOD_Q_RATE FS_C(0.97)      // of V / L, the current's rate of the approach to the cap and the ramp
#define TOD_RAMP_SHARE FS_C(0.99)  // of the bus, the voltage the terminal ramp's rate aims at where it would leave it
#define TOD_RAMP_AIM FS_C(0.995)   // of the secant's ramp rate, the one tried
#define TOD_RAMP_LOW FS_C(0.97)    // of the bus, the ramp's voltage below which a fallen rate is raised once
#define TOD_TOP_SHARE FS_C(0.999)  // of the top speed, the cruise speed where that speed is below the cap
#define TOD_SETTLE                                  \
    (FS_C(1e-7) > 16 * FS_REAL_EPSILON ? FS_C(1e-7) \
                                       : 16 * FS_REAL_EPSILON)  // a cruise has settled this close, relatively
#define TOD_ROOT_TOL                   \
    (FS_C(1e-10) > 4 * FS_REAL_EPSILON \
         ? FS_C(1e-10)                 \
         : 4 * FS_REAL_EPSILON)  // the root finder stops this close to the distance, relatively
#define TOD_BRACKET_TOL                          \
    (FS_C(1e-15) > FS_REAL_EPSILON ? FS_C(1e-15) \
                                   : FS_REAL_EPSILON)  // the bracket on the switch time stops this narrow, relatively
#define TOD_LAND_TOL (FS_C(1e-6) > 64 * FS_REAL_EPSILON ? FS_C(1e-6) : 64 * FS_REAL_EPSILON)  // a shot lands this close
#define TOD_BRIDGE FS_C(0.05)      // of a step, the bridge from the braking rates to the ramp's
#define TOD_AHEAD FS_C(3.0)        // speeding up, the d target looks this many time constants T_c ahead
#define TOD_RHO_FULL FS_C(0.4)     // the resistive share R i_max / V from which the look-ahead is in full
#define TOD_X_END FS_C(3.0)        // ... where the reactance N_r W L at the cap W is above this many R (none below)
#define TOD_X_FULL FS_C(5.0)       // ... and in full from this many (linear between)
#define TOD_D_SLEW FS_C(2.0)       // speeding up, the d target moves by at most this many h V / L a step
#define TOD_PULL_FROM FS_C(0.995)  // braking, a current beyond this share of i_max pulls its target in by q^2,
                                   // q = (share i_max / |i|)^2
#define TOD_BRAKE_REACH FS_C(0.5)  // braking, the target's bus disc scaled by at most 1 + this
#define TOD_REACH_FROM FS_C(0.2)   // ... and by 1 + 2 (R i_max / V - this) below

// time_optimal_dq_envelope.c
// Returns true when the discs meet at speed w and writes (i_d+, i_q+, i_d-, i_q-) into c.
bool tod_best_currents(const struct motor_params *m, fs_real w, fs_real v, fs_real i_max, fs_real c[4]);
// Returns the least of cap and the speed where the largest acceleration falls to 0 (bisection).
fs_real tod_top_speed(const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap);

// Returns the time of the braking phase's sample j from the switch t_s at steps h (the shot integrates over these
// times' differences, which in single precision are not h, and the samples are taken at them).
static inline fs_real tod_brake_time(fs_real t_s, fs_real h, size_t j)
{
    return t_s + (fs_real)j * h;
}

// time_optimal_dq_shoot.c
// Samples of a phase at steps h: theta, omega, i_d, i_q and the target currents, TOD_MAX_STEPS + 1 each.
struct tod_phase {
    fs_real *theta, *omega, *i_d, *i_q, *t_d, *t_q;
};

// The end of the braking phase: the bridge's start (time, state, braking target), its length, the ramp's start,
// its duration and its d share (the d current's rate at the start, of -i_d1 / tau; at rest 2 - d_share of it).
struct tod_end {
    fs_real t, theta, omega, i_d, i_q, t_d, t_q, bridge, theta1, omega1, i_d1, i_q1, tau, d_share;
};

// The shot move (time_optimal_dq_shoot.Shot).
struct tod_shot {
    struct tod_phase acc, brk;
    size_t n_acc, n_brake;
    bool cruise;
    fs_real t_s, v, gain, h, ramp;  // ramp: the terminal ramp's rate, of TOD_Q_RATE V / L
    struct tod_end end;
};

// Returns true and writes the move over d > 0 at bus v, current i_max and speed cap into shot (its phases' arrays
// set by the caller), the terminal ramp's rate starting at ramp_rate of TOD_Q_RATE V / L and the root finder at
// switch_time where it and a probe one step from it bracket the distance (NAN: none); false when a phase needs
// too many steps at every step size.
bool tod_shoot(const struct motor_params *m, fs_real d, fs_real v, fs_real i_max, fs_real cap, fs_real ramp_rate,
               fs_real switch_time, struct tod_shot *shot);

#endif
