// Loops of the single-sample core functions over row-major arrays.
#include "batch.h"

// Returns nothing; writes plan_eval at each of the n times t into flag (n x 6, row-major).
void batch_plan_eval(const struct plan *p, const fs_real *t, size_t n, fs_real *flag)
{
    struct plan_coef c;
    size_t i;
    plan_init(&c, p);
    for (i = 0; i < n; i++)
        plan_flag(&c, t[i], &flag[PLAN_FLAG_LEN * i]);
}

// Returns the number of samples outside the maps' domain; flat_voltages on rows of
// args (n x 8: rho, drho, theta, dtheta, ddtheta, dddtheta, phi, A) into v (n x 2).
size_t batch_flat_voltages(const struct motor_params *m, const fs_real *args, size_t n, fs_real *v)
{
    size_t i, bad = 0;
    const fs_real *a;
    for (i = 0; i < n; i++) {
        a = &args[8 * i];
        bad += flat_voltages(m, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], &v[2 * i]) != FLAT_OK;
    }
    return bad;
}

// Returns the number of samples outside the maps' domain; flat_to_state on the n flags (n x 6) into
// x (n x 4) and v (n x 2).
size_t batch_flat_to_state(const struct motor_params *m, const fs_real *flag, size_t n, fs_real load, fs_real *x,
                           fs_real *v)
{
    size_t i, bad = 0;
    for (i = 0; i < n; i++)
        bad += flat_to_state(m, &flag[PLAN_FLAG_LEN * i], load, &x[4 * i], &v[2 * i]) != FLAT_OK;
    return bad;
}

// Returns the number of samples with ia = ib = 0; state_to_flat on x (n x 4), v (n x 2) into flag (n x 6).
size_t batch_state_to_flat(const struct motor_params *m, const fs_real *x, const fs_real *v, size_t n,
                           fs_real load, fs_real *flag)
{
    size_t i, bad = 0;
    for (i = 0; i < n; i++)
        bad += state_to_flat(m, &x[4 * i], &v[2 * i], load, &flag[PLAN_FLAG_LEN * i]) != FLAT_OK;
    return bad;
}

// Returns the OR of the status bits; smc_step at the n times t with measurements y (n x 5) into v (n x 2)
// and each step's status into status (may be NULL).
uint32_t batch_smc_step(struct smc *s, const fs_real *t, const fs_real *y, size_t n, fs_real *v,
                        uint32_t *status)
{
    uint32_t all = SMC_OK, one;
    size_t i;
    for (i = 0; i < n; i++) {
        one = smc_step(s, t[i], &y[5 * i], &v[2 * i]);
        all |= one;
        if (status)
            status[i] = one;
    }
    return all;
}
