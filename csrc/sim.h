// Closed-loop run loops: continuous-time control (adaptive DOP853) and sampled control (ZOH + RK4 substeps).
//
// Why two integrators. In the continuous loop the law is evaluated inside the right-hand side at every
// stage, so the closed loop is one smooth ODE between the plan's knots t0 and tf (where the reference's
// higher derivatives start and stop); an embedded pair with error control meets a requested rtol/atol at
// few evaluations, and interpolating each step samples any output grid without shortening steps. The 8th-
// order DOP853 takes about 2.7x fewer evaluations than the 5(4) DOPRI5 at equal accuracy on the paper's
// runs (docs/c-core.md). The loop is only mildly stiff (W/eps = 2e4 1/s with the paper's gains, R/L =
// 840 1/s): an explicit method's stability bound stays near the step that rtol 1e-7 needs.
// In the sampled loop the controller fires at fixed instants k Ts and its voltage is held in between, so
// the input is discontinuous exactly at the sample instants and smooth inside each period. Fixed RK4
// substeps aligned with the period resolve every period exactly, cost the same every period (no
// rejections, no step-size state), and are what a firmware-in-the-loop test bench would run.
#ifndef FS_SIM_H
#define FS_SIM_H

#include <stddef.h>
#include <stdint.h>
#include "fs_real.h"
#include "motor.h"
#include "smc.h"

enum sim_status {
    SIM_OK = 0,
    SIM_EARGS,       // invalid parameters, output times or initial state
    SIM_ECONTROL,    // continuous loop: the controller faulted (outside the law's domain) and steps could not avoid it
    SIM_EHMIN,       // continuous loop: the step size fell below rounding level
    SIM_EMAXSTEPS,   // continuous loop: more than max_steps accepted steps
    SIM_ENONFINITE,  // sampled loop: the plant state became NaN or infinite
};

// The plant: its own motor parameters (may differ from the controller's model) and a constant load torque.
struct sim_plant {
    struct motor_params motor;
    fs_real load;  // [N m]
};

// Integrator of the continuous loop and how it writes the state between steps: DOP853 with the step's cubic
// Hermite interpolant (the default, 0: no extra evaluation), DOPRI5 with its 4th-order dense output, or
// DOP853 with its 7th-order dense output (three more evaluations in each step that holds an output time).
enum sim_method { SIM_DOP853 = 0, SIM_DOPRI5, SIM_DOP853_DENSE };

struct sim_continuous_params {
    fs_real rtol, atol;  // error control, > 0
    fs_real h_max;       // largest step [s], > 0
    uint32_t max_steps;  // bound on accepted steps over the whole run
    uint32_t method;     // enum sim_method
};

struct sim_sampled_params {
    fs_real Ts;         // control period [s], > 0
    uint32_t substeps;  // RK4 steps per period, >= 1
};

struct sim_stats {
    uint32_t steps, rejected, rhs_evals;  // integrator work
    uint32_t smc_status;                  // OR of the smc_status bits of every controller call
    fs_real t_fail;                       // time of the failure when the run returns an error
};

// Returns SIM_OK or an error sim_status; runs the continuous closed loop from x0 at t_out[0], the law
// evaluated at every stage, integration restarted at the plan's knots t0 and tf, and writes the state at
// each of the n_out nondecreasing times t_out into x_out (n_out x 4, row-major).
int sim_continuous(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], const fs_real *t_out,
                   size_t n_out, const struct sim_continuous_params *p, fs_real *x_out, struct sim_stats *st);

// Returns SIM_OK or an error sim_status; runs the sampled loop from x0 at t_start for n_periods periods
// (controller at t_k = t_start + k Ts, voltage held, plant by RK4 substeps) and writes the state at every
// t_k, k = 0..n_periods, into x_out ((n_periods + 1) x 4) and the voltage applied from t_k into v_out
// ((n_periods + 1) x 2). Controller faults do not stop the run: the controller then applies 0 V.
int sim_sampled(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], fs_real t_start,
                size_t n_periods, const struct sim_sampled_params *p, fs_real *x_out, fs_real *v_out,
                struct sim_stats *st);

#endif
