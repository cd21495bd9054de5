// What the two run loops share: their status codes and their work counters.
#ifndef FS_SIM_H
#define FS_SIM_H

#include <stdint.h>
#include "fs_real.h"

// cffi:begin
enum sim_status {
    SIM_OK = 0,
    SIM_EARGS,       // invalid parameters, output times, initial state or controller
    SIM_ECONTROL,    // continuous loop: the controller faulted (outside the law's domain) and steps could not avoid it
    SIM_EHMIN,       // continuous loop: the step size fell below rounding level
    SIM_EMAXSTEPS,   // continuous loop: more than max_steps accepted steps
    SIM_ENONFINITE,  // sampled loop: the plant state became NaN or infinite
    SIM_ECANCELLED,  // the caller's cancel flag was set (another thread asked the run to stop)
};

struct sim_stats {
    uint32_t steps, rejected, rhs_evals;  // integrator work
    uint32_t controller_status;           // OR of the ctrl_status bits of every controller call
    uint32_t fault_periods;               // sampled loop: periods whose step faulted (0 V applied)
    fs_real t_first_fault;                // sampled loop: time of the first of them (0 when none)
    fs_real t_fail;                       // time of the failure when the run returns an error
};
// cffi:end

#endif
