// Array wrappers over time samples for host bindings and tests: one call per array, no loop in Python.
#ifndef FS_BATCH_H
#define FS_BATCH_H

#include <stddef.h>
#include <stdint.h>
#include "fs_real.h"
#include "flat.h"
#include "motor.h"
#include "plan.h"
#include "smc.h"

// Returns nothing; writes plan_eval at each of the n times t into flag (n x 6, row-major).
void batch_plan_eval(const struct plan *p, const fs_real *t, size_t n, fs_real *flag);

// Returns the number of samples outside the maps' domain; flat_voltages on rows of
// args (n x 8: rho, drho, theta, dtheta, ddtheta, dddtheta, phi, A) into v (n x 2).
size_t batch_flat_voltages(const struct motor_params *m, const fs_real *args, size_t n, fs_real *v);

// Returns the number of samples outside the maps' domain; flat_to_state on the n flags (n x 6) into
// x (n x 4) and v (n x 2).
size_t batch_flat_to_state(const struct motor_params *m, const fs_real *flag, size_t n, fs_real load, fs_real *x,
                           fs_real *v);

// Returns the number of samples with ia = ib = 0; state_to_flat on x (n x 4), v (n x 2) into flag (n x 6).
size_t batch_state_to_flat(const struct motor_params *m, const fs_real *x, const fs_real *v, size_t n,
                           fs_real load, fs_real *flag);

// Returns the OR of the status bits; smc_step at the n times t with measurements y (n x 5) into v (n x 2)
// and each step's status into status (may be NULL).
uint32_t batch_smc_step(struct smc *s, const fs_real *t, const fs_real *y, size_t n, fs_real *v,
                        uint32_t *status);

#endif
