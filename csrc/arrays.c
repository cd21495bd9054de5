// Loops of the single-sample core functions over row-major arrays.
#include "arrays.h"

// Returns nothing; writes plan_eval at each of the n times t into flag (n x 6, row-major).
void arrays_plan_eval(const struct plan *p, const fs_real *t, size_t n, fs_real *flag)
{
    struct plan_coef c;
    size_t i;
    plan_init(&c, p);
    for (i = 0; i < n; i++)
        plan_flag(&c, t[i], &flag[PLAN_FLAG_LEN * i]);
}

// Returns the number of samples outside the maps' domain; flat_voltages on rows of
// args (n x 8: rho, drho, theta, dtheta, ddtheta, dddtheta, phi, A) into v (n x 2).
size_t arrays_flat_voltages(const struct motor_params *m, const fs_real *args, size_t n, fs_real *v)
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
size_t arrays_flat_to_state(const struct motor_params *m, const fs_real *flag, size_t n, fs_real load, fs_real *x,
                            fs_real *v)
{
    size_t i, bad = 0;
    for (i = 0; i < n; i++)
        bad += flat_to_state(m, &flag[PLAN_FLAG_LEN * i], load, &x[4 * i], &v[2 * i]) != FLAT_OK;
    return bad;
}

// Returns the number of samples with ia = ib = 0; state_to_flat on x (n x 4), v (n x 2) into flag (n x 6).
size_t arrays_state_to_flat(const struct motor_params *m, const fs_real *x, const fs_real *v, size_t n, fs_real load,
                            fs_real *flag)
{
    size_t i, bad = 0;
    for (i = 0; i < n; i++)
        bad += state_to_flat(m, &x[4 * i], &v[2 * i], load, &flag[PLAN_FLAG_LEN * i]) != FLAT_OK;
    return bad;
}

// Returns the OR of the status bits; smc_step at the n times t with measurements y (n x 5) into v (n x 2)
// and each step's status into status (may be NULL).
uint32_t arrays_smc_step(struct smc *s, const fs_real *t, const fs_real *y, size_t n, fs_real *v, uint32_t *status)
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

// Returns the number of samples outside the flat maps' domain; plan_eval and flat_to_state in one pass: the
// flag (n x 6), state (n x 4) and voltages (n x 2) of the plan at the n times t for a known load.
size_t arrays_plan_flat(const struct plan *p, const struct motor_params *m, const fs_real *t, size_t n, fs_real load,
                        fs_real *flag, fs_real *x, fs_real *v)
{
    struct plan_coef c;
    size_t i, bad = 0;
    plan_init(&c, p);
    for (i = 0; i < n; i++) {
        plan_flag(&c, t[i], &flag[PLAN_FLAG_LEN * i]);
        bad += flat_to_state(m, &flag[PLAN_FLAG_LEN * i], load, &x[4 * i], &v[2 * i]) != FLAT_OK;
    }
    return bad;
}

// Returns nothing; writes the rest of a arrays_result row that smc_step_terms left unset (w->have): a step
// whose inputs were not finite or whose rho < rho_min computed neither the plan's flag nor the sliding variables.
static void result_fallback(struct smc *s, fs_real t, const fs_real y[5], struct smc_terms *w)
{
    if (!(w->have & SMC_HAVE_FLAG))
        plan_flag(&s->plan, t, w->flag);
    w->acc = s->p.measurement == SMC_IDEAL ? y[4] : motor_acceleration(&s->p.motor, y, 0);
    w->s2 = w->acc - w->flag[PLAN_DDTHETA] + s->alpha2 * (y[2] - w->flag[PLAN_DTHETA])
            + s->alpha1 * (y[3] - w->flag[PLAN_THETA]);
}

// Returns the number of samples where the plan leaves the flat maps' domain (their reference currents and
// voltages are 0); writes one RES_LEN row (out, n x RES_LEN) and the controller's status bits (status, may be
// NULL) for each of the n plant states x (n x 4) at times t: smc_step on (x, the plant's acceleration).
size_t arrays_result(struct smc *s, const struct plant *plant, const fs_real *t, const fs_real *x, size_t n,
                     fs_real *out, uint32_t *status)
{
    const struct motor_params *pm = &plant->motor;
    bool effects = plant_has_effects(plant);
    fs_real y[5], trig[2], prev[PLAN_FLAG_LEN], xr[4] = {0, 0, 0, 0}, vr[2] = {0, 0}, *row;
    struct smc_terms w;
    size_t i, bad = 0;
    uint32_t one;
    int k, ok = FLAT_OK, same, shared = pm->Nr == s->p.motor.Nr;
    for (i = 0; i < n; i++) {
        row = &out[RES_LEN * i];
        for (k = 0; k < 4; k++)
            y[k] = x[4 * i + k];
        // The plant's acceleration in motor_acceleration's operation order; its sin and cos of Nr theta are
        // the controller's too when the two motors have the same Nr.
        fs_sincos(pm->Nr * y[3], &trig[0], &trig[1]);
        y[4] = (pm->Km * (y[1] * trig[1] - y[0] * trig[0]) - pm->B * y[2] - plant->load) / pm->J;
        if (effects)  // plant_acceleration's sum
            y[4] = y[4] + plant_effects_torque(plant, y[2], y[3]) / pm->J;
        one = smc_step_terms(s, t[i], y, shared ? trig : NULL, &row[RES_VA], &w);
        if (status)
            status[i] = one;
        if (!(w.have & SMC_HAVE_LAW))
            result_fallback(s, t[i], y, &w);
        row[RES_ACC] = y[4];
        // hypot, not the step's sqrt(ia^2 + ib^2): rho and s1 equal NumPy's bit for bit.
        row[RES_RHO] = fs_hypot(y[0], y[1]);
        row[RES_PHI] = fs_atan2(y[0], y[1]);
        row[RES_THETA_REF] = w.flag[PLAN_THETA];
        row[RES_OMEGA_REF] = w.flag[PLAN_DTHETA];
        row[RES_RHO_REF] = w.flag[PLAN_RHO];
        // The reference state is the previous one while the flag holds still (before t0 and after tf).
        for (k = 0, same = i > 0; k < PLAN_FLAG_LEN && same; k++)
            same = w.flag[k] == prev[k];
        if (!same) {
            ok = flat_to_state(&s->p.motor, w.flag, 0, xr, vr);
            for (k = 0; k < PLAN_FLAG_LEN; k++)
                prev[k] = w.flag[k];
        }
        bad += ok != FLAT_OK;
        row[RES_IA_REF] = xr[0];
        row[RES_IB_REF] = xr[1];
        row[RES_VA_REF] = vr[0];
        row[RES_VB_REF] = vr[1];
        // The sliding variables of eq. (12), as smc_step and FlatnessSMC.sliding_variables form them.
        row[RES_S1] = row[RES_RHO] - w.flag[PLAN_RHO];
        row[RES_S2] = w.s2;
    }
    return bad;
}

// Returns the OR of the status bits; any bound controller at the n times t with measurements y (n x 5) into
// v (n x 2) and each step's status into status (may be NULL).
uint32_t arrays_controller_step(const struct controller *c, const fs_real *t, const fs_real *y, size_t n, fs_real *v,
                                uint32_t *status)
{
    uint32_t all = CTRL_OK, one;
    size_t i;
    for (i = 0; i < n; i++) {
        one = c->step(c->self, t[i], &y[CTRL_Y_LEN * i], &v[2 * i]);
        all |= one;
        if (status)
            status[i] = one;
    }
    return all;
}
