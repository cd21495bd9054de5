// The continuous closed loop: any stateless controller evaluated inside the plant's right-hand side (DOP853).
//
// Why an adaptive integrator here. The law is evaluated at every stage, so the closed loop is one smooth ODE
// between the plan's knots (where the reference's higher derivatives start and stop); an embedded pair with
// error control meets a requested rtol/atol at few evaluations, and interpolating each step samples any output
// grid without shortening steps. The 8th-order DOP853 takes about 2.7x fewer evaluations than the 5(4) DOPRI5
// at equal accuracy on the paper's runs (docs/c-core.md). The loop is only mildly stiff (W/eps = 2e4 1/s with
// the paper's gains, R/L = 840 1/s): an explicit method's stability bound stays near the step rtol 1e-7 needs.
// Why only stateless controllers. A law with state (the PI integrators of the microstepping driver and of the
// cascade) is a discrete-time law, defined by its update once per control period; evaluated at an adaptive
// integrator's trial stages, it would update its state on stages that are later rejected. Those laws run on
// the sampled loop (sampled.h), which is how a drive runs them.
#ifndef FS_CONTINUOUS_H
#define FS_CONTINUOUS_H

#include <stddef.h>
#include <stdint.h>
#include "controller.h"
#include "fs_real.h"
#include "plant.h"
#include "sim.h"

// cffi:begin
// Integrator and how it writes the state between steps: DOP853 with the step's cubic Hermite interpolant (the
// default, 0: no extra evaluation), DOPRI5 with its 4th-order dense output, or DOP853 with its 7th-order dense
// output (three more evaluations in each step that holds an output time).
enum continuous_method { CONTINUOUS_DOP853 = 0, CONTINUOUS_DOPRI5, CONTINUOUS_DOP853_DENSE };

struct continuous_params {
    fs_real rtol, atol;               // error control, > 0
    fs_real h_max;                    // largest step [s], > 0
    uint32_t max_steps;               // bound on accepted steps over the whole run
    uint32_t method;                  // enum continuous_method
    const fs_real *knots;             // times where the reference's derivatives jump (the plan's t0, tf), nondecreasing
    size_t n_knots;                   // how many (knots may be NULL when 0)
    const volatile uint32_t *cancel;  // NULL, or a flag another thread sets to stop the run (SIM_ECANCELLED)
};

// Returns SIM_OK or an error sim_status; runs the closed loop from x0 at t_out[0] with ideal sensors (the state
// and the plant's true acceleration), the controller evaluated at every stage (a fault rejects the stage),
// integration restarted at each knot inside the run, and writes the state at each of the n_out
// nondecreasing times t_out into x_out (n_out x 4, row-major). SIM_EARGS for a controller with state.
int continuous_run(const struct controller *ctrl, const struct plant *plant, const fs_real *x0, const fs_real *t_out,
                   size_t n_out, const struct continuous_params *p, fs_real *x_out, struct sim_stats *st);
// cffi:end

#endif
