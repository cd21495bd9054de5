// The parts of the field-weakening shot (tod_shoot, time_optimal_dq_shoot.c): the model under the current-steering
// policy (time_optimal_dq_policy.c), its speeding-up and braking phases (time_optimal_dq_phases.c) and the terminal
// ramp (time_optimal_dq_ramp.c). Internal: not bound by Python.
#ifndef FS_TIME_OPTIMAL_DQ_SHOT_H
#define FS_TIME_OPTIMAL_DQ_SHOT_H

#include <stdbool.h>
#include <stddef.h>
#include "time_optimal_dq_stages.h"

// One shooting run's constants (time_optimal_dq_policy._Model).
struct tod_model {
    const struct motor_params *m;
    fs_real R, L, Km, J, B, Nr;
    fs_real v, i_max, h, inv_l, inv_j, lk, tc, rho, rate, end_rate, cap, hold, band, reactance;
};

// A state: theta, omega, i_d, i_q.
struct tod_state {
    fs_real th, w, id, iq;
};

// time_optimal_dq_policy.c
// Returns true when the run's constants are finite and positive and writes them (hostile limits can underflow or
// overflow them: every divisor is checked before it divides).
bool tod_model_init(struct tod_model *md, const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap,
                    fs_real h);
// Returns nothing; writes (di_d, di_q, dw) of the model under the policy towards the target (td, tq).
void tod_deriv(const struct tod_model *md, fs_real id, fs_real iq, fs_real w, fs_real td, fs_real tq, fs_real out[3]);
// Returns nothing; writes the target at speed w (braking: the bottom of the envelope with its bus disc scaled by
// 1 + 2 (rho - TOD_REACH_FROM) within [1, 1 + TOD_BRAKE_REACH], rho = R i_max / V; else its top, held to the cap's
// approach, which counts lead [rad/s] more for the current's lag, its d current the envelope's at w + ahead where
// that weakens more).
void tod_target(const struct tod_model *md, fs_real w, bool braking, fs_real lead, fs_real ahead, fs_real t[2]);
// Returns nothing; writes the target at the end of the step from s, at the speed predicted there (braking: pulled in
// where the current is beyond TOD_PULL_FROM i_max).
void tod_next_target(const struct tod_model *md, const struct tod_state *s, bool braking, fs_real t[2]);
// Returns nothing; writes the speeding-up target at the end of the step from s into t, its d part within TOD_D_SLEW
// h V / L of tg's.
void tod_next_speed_up(const struct tod_model *md, const struct tod_state *s, const fs_real tg[2], fs_real t[2]);
// Returns the state RK4 takes s to over f h, the target moving from t0 towards t1 (reached at a full step).
struct tod_state tod_step(const struct tod_model *md, const struct tod_state *s, const fs_real t0[2],
                          const fs_real t1[2], fs_real f);
// Returns the braking current beyond the terminal ramp's switching curve [A] (>= 0: ramp now).
fs_real tod_curve(const struct tod_model *md, const struct tod_state *s);

// time_optimal_dq_ramp.c
// Returns the bridge from s at t and the terminal ramp after it (time_optimal_dq_ramp.terminal_ramp).
struct tod_end tod_terminal_ramp(const struct tod_model *md, fs_real t, const struct tod_state *s, const fs_real tg[2]);
// Returns the largest voltage of the terminal ramp over the bus: at its start and at its end.
fs_real tod_ramp_voltage(const struct tod_model *md, const struct tod_end *e);

// time_optimal_dq_phases.c
// Returns true when the speeding-up phase fits TOD_MAX_STEPS steps; writes its samples and whether it settled.
bool tod_speed_up(const struct tod_model *md, fs_real d, const struct tod_phase *a, size_t *n, bool *cruise);
// Returns the speeding-up step that time t >= 0 lies in, at most n_acc - 1 (int(t / h) clipped, as the reference).
size_t tod_step_index(fs_real t, fs_real h, size_t n_acc);
// Returns true and writes the braking phase's end from the switch t_s (and its samples into out unless NULL);
// false when TOD_MAX_STEPS steps are too few (time_optimal_dq_phases._brake).
bool tod_brake(const struct tod_model *md, const struct tod_phase *a, size_t n_acc, bool cruise, fs_real t_s,
               const struct tod_phase *out, struct tod_end *end, size_t *n_b);

#endif
