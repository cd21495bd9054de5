// Array wrappers over time samples for host bindings and tests: one call per array, no loop in Python.
#ifndef FS_ARRAYS_H
#define FS_ARRAYS_H

#include <stddef.h>
#include <stdint.h>
#include "fs_real.h"
#include "flat.h"
#include "motor.h"
#include "plan.h"
#include "controller.h"
#include "plant.h"
#include "smc.h"

// cffi:begin
// Returns nothing; writes plan_eval at each of the n times t into flag (n x 6, row-major).
void arrays_plan_eval(const struct plan *p, const fs_real *t, size_t n, fs_real *flag);

// Returns the number of samples outside the flat maps' domain; plan_eval and flat_to_state in one pass: the
// flag (n x 6), state (n x 4) and voltages (n x 2) of the plan at the n times t for a known load.
size_t arrays_plan_flat(const struct plan *p, const struct motor_params *m, const fs_real *t, size_t n, fs_real load,
                        fs_real *flag, fs_real *x, fs_real *v);

// Columns of a closed-loop result row (arrays_result): the controller's voltages, the plant's acceleration,
// the polar current (rho, phi), the planned angle, speed and rho, the planned state's currents and the
// feedforward voltages, and the sliding variables.
enum {
    RES_VA,
    RES_VB,
    RES_ACC,
    RES_RHO,
    RES_PHI,
    RES_THETA_REF,
    RES_OMEGA_REF,
    RES_RHO_REF,
    RES_IA_REF,
    RES_IB_REF,
    RES_VA_REF,
    RES_VB_REF,
    RES_S1,
    RES_S2,
    RES_LEN
};

// Returns the number of samples where the plan leaves the flat maps' domain (their reference currents and
// voltages are 0); writes one RES_LEN row (out, n x RES_LEN) and the controller's status bits (status, may be
// NULL) for each of the n plant states x (n x 4) at times t: smc_step on (x, the plant's acceleration).
size_t arrays_result(struct smc *s, const struct plant *plant, const fs_real *t, const fs_real *x, size_t n,
                     fs_real *out, uint32_t *status);

// Returns the number of samples outside the maps' domain; flat_voltages on rows of
// args (n x 8: rho, drho, theta, dtheta, ddtheta, dddtheta, phi, A) into v (n x 2).
size_t arrays_flat_voltages(const struct motor_params *m, const fs_real *args, size_t n, fs_real *v);

// Returns the number of samples outside the maps' domain; flat_to_state on the n flags (n x 6) into
// x (n x 4) and v (n x 2).
size_t arrays_flat_to_state(const struct motor_params *m, const fs_real *flag, size_t n, fs_real load, fs_real *x,
                            fs_real *v);

// Returns the number of samples with ia = ib = 0; state_to_flat on x (n x 4), v (n x 2) into flag (n x 6).
size_t arrays_state_to_flat(const struct motor_params *m, const fs_real *x, const fs_real *v, size_t n, fs_real load,
                            fs_real *flag);

// Returns the OR of the status bits; smc_step at the n times t with measurements y (n x 5) into v (n x 2)
// and each step's status into status (may be NULL).
uint32_t arrays_smc_step(struct smc *s, const fs_real *t, const fs_real *y, size_t n, fs_real *v, uint32_t *status);

// Returns the OR of the status bits; any bound controller at the n times t with measurements y (n x 5) into
// v (n x 2) and each step's status into status (may be NULL).
uint32_t arrays_controller_step(const struct controller *c, const fs_real *t, const fs_real *y, size_t n, fs_real *v,
                                uint32_t *status);
// cffi:end

#endif
