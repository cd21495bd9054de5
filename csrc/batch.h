// Many sampled runs (scenarios) in one call, each summarised as flatstep.engine.result.SimResult.summary does.
#ifndef FS_BATCH_H
#define FS_BATCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "plan.h"
#include "plant.h"
#include "sampled.h"
#include "sim.h"

// Two rest angles closer than this, relative to the largest |angle| (at least 1 rad), are one rest: a dwell's two
// ends differ by rounding (flatstep.engine.result.REST_TOLERANCE).
#define BATCH_REST_TOLERANCE 1e-12

// cffi:begin
// One sampled scenario: a bound controller (its state is the caller's), the plant, the loop, the plan the
// summary measures against, the horizon and the start.
struct batch_run {
    struct controller ctrl;
    struct plant plant;
    struct sampled_params loop;
    struct plan reference;  // the planned move (theta*, rho*) the errors are measured against
    size_t n_periods;       // periods from t = 0 (states at k Ts, k = 0..n_periods)
    fs_real x0[4];          // start state (ia, ib, omega, theta)
    const fs_real *noise;   // (n_periods + 1) x 2 current-noise samples, or NULL for none
    fs_real lost_error;     // |theta - theta*| [rad] beyond which the move is lost at any time (one full step), > 0
};  // at the end of the run the move is lost beyond batch_arrival_error(lost_error, {theta1, theta2}, 2)

// Summary of one run over the control instants t_k = k Ts, the values of SimResult.summary.
struct batch_summary {
    int status;                  // SIM_OK or a sim_status (SIM_EARGS: the loop refused the run)
    uint32_t controller_status;  // OR of the controller's status bits
    fs_real theta_final, ia_final, ib_final, omega_final, final_theta_error;
    fs_real max_abs_theta_error, max_abs_rho_error, max_abs_va, max_abs_vb;
    fs_real max_abs_theta_error_move;   // over t0 <= t_k <= tf (n_move samples)
    fs_real max_abs_theta_error_after;  // over t_k > tf (n_after samples)
    size_t n_move, n_after;
    bool lost;               // |theta - theta*| exceeded lost_error at some t_k
    fs_real lost_at;         // the first such t_k (0 when not lost)
    uint32_t fault_periods;  // periods whose controller step faulted (sim_stats)
    fs_real t_first_fault;   // the first of them (0 when none)
};

// Returns the error [rad] at the end of a run beyond which its move is lost: full_step, or half the plan's last
// move if that is smaller (full_step for a plan that never moves). rest[0..n-1] are the angles at which the plan
// rests, in order; the last move starts at the latest rest farther than BATCH_REST_TOLERANCE x max(1, max |rest|)
// from rest[n-1] (flatstep.engine.result.arrival_error, last_move).
fs_real batch_arrival_error(fs_real full_step, const fs_real *rest, size_t n);

// Returns the number of runs whose status is not SIM_OK; runs the n scenarios one after another on sampled_run,
// using scratch (at least 6 (n_periods + 1) values for the longest run) for each run's states and voltages,
// and writes each run's summary into out[i].
size_t batch_sampled(const struct batch_run *runs, size_t n, fs_real *scratch, size_t scratch_len,
                     struct batch_summary *out);
// cffi:end

#endif
