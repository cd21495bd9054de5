// libFuzzer harness for the rest-to-rest plan (plan.h), the flat maps (flat.h), the motor model (motor.h) and
// their array wrappers (arrays.h): plan_valid is its documented rule; a valid plan holds its ends, keeps psi in
// [0, 1] (to rounding) and returns true only inside (t0, tf); plan_flag, plan_eval and arrays_plan_eval agree bit for bit; the
// maps return a documented code with zeroed outputs on error and never divide by zero (UBSan); every arrays_*
// wrapper is its per-sample map bit for bit on arrays of exactly n rows (heap: ASan sees a write past them);
// motor_rhs is motor_acceleration and omega; near the paper's motor and move, flat_to_state then state_to_flat
// gives the flag back.
//
// Input: a header byte (the number of samples n = head % 17), a 32-bit mask of the groups decoded hostile (1 the
// motor, 2 the plan, 4 the load, 8 the times, 16 the maps' arguments, 32 the states and voltages; the others take
// the paper's motor and move, times every 4 ms to 64 ms), then the groups' values (fuzz/decode.h).
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include "arrays.h"
#include "flat.h"
#include "laws.h"

#define N_MAX 16

// Returns plan.h's rule for a valid plan, written from the header.
static bool plan_rule(const struct plan *p)
{
    return fabs(p->theta1) <= DBL_MAX / 4 && fabs(p->theta2) <= DBL_MAX / 4 && p->rho1 <= DBL_MAX / 4
           && p->rho2 <= DBL_MAX / 4 && fz_positive(p->rho1) && fz_positive(p->rho2) && isfinite(p->t0)
           && isfinite(p->tf) && p->tf > p->t0 && pow(p->tf - p->t0, 3) > 0;
}

// Returns nothing; aborts unless the valid plan's flag at the finite t keeps plan.h's guarantees.
static void check_plan_at(const struct plan *p, double t, const double f[PLAN_FLAG_LEN], bool in)
{
    const double start[PLAN_FLAG_LEN] = {p->rho1, 0, p->theta1, 0, 0, 0},
                 end[PLAN_FLAG_LEN] = {p->rho2, 0, p->theta2, 0, 0, 0};
    double psi = plan_psi(t, p->t0, p->tf, 0);
    int k;
    for (k = 0; k < PLAN_FLAG_LEN; k++)  // derivatives inside may overflow (a short span), values never
        if (!isfinite(f[k]) && (!in || k == PLAN_RHO || k == PLAN_THETA))
            FZ_FAIL("plan_flag: flag[%d] = %g at t = %.17g", k, f[k], t);
    if (in != (t > p->t0 && t < p->tf))
        FZ_FAIL("plan_flag returned %d at t = %.17g on (%.17g, %.17g)", in, t, p->t0, p->tf);
    for (k = 0; !in && k < PLAN_FLAG_LEN; k++)  // the end as theta1 + (theta2 - theta1): to rounding
        if (t <= p->t0 ? f[k] != start[k] : !(fabs(f[k] - end[k]) <= 4 * DBL_EPSILON * (fabs(start[k]) + fabs(end[k]))))
            FZ_FAIL("plan_flag: flag[%d] = %.17g at rest (t = %.17g), not the plan's end", k, f[k], t);
    if (!(psi >= -1e-11 && psi <= 1 + 1e-11) || (!in && psi != (t <= p->t0 ? 0 : 1)))  // Horner's rounding near 1
        FZ_FAIL("plan_psi = %.17g at t = %.17g", psi, t);
    for (k = 1; !in && k < 4; k++)
        if (plan_psi(t, p->t0, p->tf, k) != 0)
            FZ_FAIL("plan_psi: derivative %d is not 0 at rest (t = %.17g)", k, t);
    if (plan_psi(t, p->t0, p->tf, 4) != 0 || plan_psi(t, p->t0, p->tf, -1) != 0)
        FZ_FAIL("plan_psi: an order out of range is not 0");
}

// Returns nothing; aborts unless v (and x, when given) is all zeros.
static void check_zero(const char *what, int rc, const double *v, size_t n)
{
    size_t k;
    for (k = 0; k < n; k++)
        if (v[k] != 0)
            FZ_FAIL("%s returned %d with output %zu = %g, not 0", what, rc, k, v[k]);
}

// Returns nothing; aborts unless the flag of the state (flat_to_state then state_to_flat) is f, to rounding.
static void check_round_trip(const struct motor_params *m, const double f[PLAN_FLAG_LEN], const double x[4],
                             const double v[2], double load)
{
    const double scale[PLAN_FLAG_LEN] = {1, 100, 1, 10, 1e4, 1e7};  // rho [A], rho' [A/s], theta .. theta'''
    double g[PLAN_FLAG_LEN];
    int k;
    if (state_to_flat(m, x, v, load, g) != FLAT_OK)
        FZ_FAIL("state_to_flat refused the state flat_to_state gave");
    for (k = 0; k < PLAN_FLAG_LEN; k++)
        if (!(fabs(g[k] - f[k]) <= 1e-9 * (scale[k] + fabs(f[k]))))
            FZ_FAIL("round trip: flag[%d] %.17g came back as %.17g", k, f[k], g[k]);
}

// Returns 0 (libFuzzer's convention); aborts when a contract of plan.h, flat.h, motor.h or arrays.h is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct fz_reader r = {data, size};
    uint8_t head = fz_byte(&r, 8);
    uint32_t mask = fz_u32(&r, 0);
    size_t n = head % (N_MAX + 1), k, j, bad, bad2;
    struct motor_params m;
    struct plan p;
    struct plan_coef c;
    double load, t[N_MAX], f[PLAN_FLAG_LEN], g[PLAN_FLAG_LEN], x[4], v[2], dx[4], acc;
    double *flag = malloc((n ? n : 1) * PLAN_FLAG_LEN * sizeof *flag), *xs = malloc((n ? n : 1) * 4 * sizeof *xs);
    double *vs = malloc((n ? n : 1) * 2 * sizeof *vs), *args = malloc((n ? n : 1) * 8 * sizeof *args);
    double *out = malloc((n ? n : 1) * PLAN_FLAG_LEN * sizeof *out), *xo = malloc((n ? n : 1) * 4 * sizeof *xo);
    double *vo = malloc((n ? n : 1) * 2 * sizeof *vo);
    bool valid, in, nominal = !(mask & 0x3f);
    int rc;
    if (!flag || !xs || !vs || !args || !out || !xo || !vo)
        goto done;
    fz_motor(&r, mask & 1, &m);
    fz_plan(&r, mask & 2, 0.02, 0.04, &p);
    load = mask & 4 ? fz_value(&r, 5e-3) : 0;
    for (k = 0; k < n; k++)
        t[k] = mask & 8 ? fz_value(&r, 4e-3 * (double)k) : 4e-3 * (double)k;
    valid = plan_init(&c, &p);
    if (valid != plan_rule(&p) || plan_valid(&p) != valid)
        FZ_FAIL("plan_valid returned %d on (%g, %g, %g, %g, %g, %g)", valid, p.theta1, p.theta2, p.rho1, p.rho2, p.t0,
                p.tf);
    arrays_plan_eval(&p, t, n, flag);
    for (k = 0; k < n; k++) {
        in = plan_flag(&c, t[k], f);
        if (plan_eval(&p, t[k], g) != in || memcmp(f, g, sizeof f) != 0
            || memcmp(f, flag + k * PLAN_FLAG_LEN, sizeof f) != 0)
            FZ_FAIL("plan_flag, plan_eval and arrays_plan_eval differ at t = %.17g", t[k]);
        if (valid && isfinite(t[k]))
            check_plan_at(&p, t[k], f, in);
    }
    if (!motor_params_valid(&m))  // the maps and the model divide by L and J: a valid motor only (motor.h)
        goto done;
    // flat_to_state on the plan's flags, and its wrappers
    bad = arrays_plan_flat(&p, &m, t, n, load, out, xo, vo);
    for (k = 0, bad2 = 0; k < n; k++) {
        rc = flat_to_state(&m, flag + k * PLAN_FLAG_LEN, load, x, v);
        bad2 += rc != FLAT_OK;
        if (rc != FLAT_OK && rc != FLAT_ERHO && rc != FLAT_ESQRT)
            FZ_FAIL("flat_to_state returned %d", rc);
        if (rc != FLAT_OK)
            check_zero("flat_to_state", rc, x, 4), check_zero("flat_to_state", rc, v, 2);
        if (memcmp(x, xo + 4 * k, sizeof x) != 0 || memcmp(v, vo + 2 * k, sizeof v) != 0
            || memcmp(flag + k * PLAN_FLAG_LEN, out + k * PLAN_FLAG_LEN, sizeof f) != 0)
            FZ_FAIL("arrays_plan_flat differs from plan_eval and flat_to_state at sample %zu", k);
        if (rc == FLAT_OK && nominal)
            check_round_trip(&m, flag + k * PLAN_FLAG_LEN, x, v, load);
        for (j = 0; j < 4; j++)
            xs[4 * k + j] = mask & 32 ? fz_value(&r, x[j]) : x[j];
        vs[2 * k] = mask & 32 ? fz_value(&r, v[0]) : v[0], vs[2 * k + 1] = mask & 32 ? fz_value(&r, v[1]) : v[1];
    }
    if (bad != bad2 || arrays_flat_to_state(&m, flag, n, load, xo, vo) != bad2)
        FZ_FAIL("arrays_plan_flat / arrays_flat_to_state count %zu samples outside the maps' domain, not %zu", bad,
                bad2);
    // state_to_flat and the model on any states and voltages
    bad = arrays_state_to_flat(&m, xs, vs, n, load, out);
    for (k = 0, bad2 = 0; k < n; k++) {
        rc = state_to_flat(&m, xs + 4 * k, vs + 2 * k, load, f);
        bad2 += rc != FLAT_OK;
        if (rc != FLAT_OK && rc != FLAT_ERHO)
            FZ_FAIL("state_to_flat returned %d", rc);
        if (rc != FLAT_OK)
            check_zero("state_to_flat", rc, f, PLAN_FLAG_LEN);
        if (xs[4 * k] == 0 && xs[4 * k + 1] == 0 && rc != FLAT_ERHO)
            FZ_FAIL("state_to_flat accepted ia = ib = 0");
        if (memcmp(f, out + k * PLAN_FLAG_LEN, sizeof f) != 0)
            FZ_FAIL("arrays_state_to_flat differs from state_to_flat at sample %zu", k);
        motor_rhs(&m, xs + 4 * k, vs + 2 * k, load, dx);
        acc = motor_acceleration(&m, xs + 4 * k, load);
        if ((memcmp(&dx[2], &acc, sizeof acc) != 0 && !(isnan(dx[2]) && isnan(acc)))  // NaN payloads may differ
            || memcmp(&dx[3], &xs[4 * k + 2], sizeof acc) != 0)
            FZ_FAIL("motor_rhs: acceleration %.17g (motor_acceleration %.17g), dtheta %.17g", dx[2], acc, dx[3]);
        (void)motor_torque(&m, xs + 4 * k);
    }
    if (bad != bad2)
        FZ_FAIL("arrays_state_to_flat counts %zu samples with ia = ib = 0, not %zu", bad, bad2);
    // flat_voltages on arguments around the plan's (rho, rho', theta .. theta''', phi 0.3, the torque demand)
    for (k = 0; k < n; k++) {
        const double *fl = flag + k * PLAN_FLAG_LEN;
        double nominal_args[8] = {fl[0], fl[1], fl[2], fl[3], fl[4], fl[5], 0.3, m.J * fl[4] + m.B * fl[3] + load};
        for (j = 0; j < 8; j++)
            args[8 * k + j] = mask & 16 ? fz_value(&r, nominal_args[j]) : nominal_args[j];
    }
    bad = arrays_flat_voltages(&m, args, n, vo);
    for (k = 0, bad2 = 0; k < n; k++) {
        const double *a = args + 8 * k;
        struct flat_angles ang;
        rc = flat_voltages(&m, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], v);
        bad2 += rc != FLAT_OK;
        if (rc != FLAT_OK && rc != FLAT_ERHO && rc != FLAT_ESQRT)
            FZ_FAIL("flat_voltages returned %d", rc);
        if (rc != FLAT_OK)
            check_zero("flat_voltages", rc, v, 2);
        if (memcmp(v, vo + 2 * k, sizeof v) != 0)
            FZ_FAIL("arrays_flat_voltages differs from flat_voltages at sample %zu", k);
        ang.sphi = sin(a[6]), ang.cphi = cos(a[6]), ang.sdelta = sin(m.Nr * a[2] + a[6]);
        ang.cdelta = cos(m.Nr * a[2] + a[6]);
        rc = flat_voltages_trig(&m, a[0], a[1], a[3], a[4], a[5], &ang, a[7], g);
        if (rc != FLAT_OK && rc != FLAT_ERHO && rc != FLAT_ESQRT)
            FZ_FAIL("flat_voltages_trig returned %d", rc);
        if (rc != FLAT_OK)
            check_zero("flat_voltages_trig", rc, g, 2);
    }
    if (bad != bad2)
        FZ_FAIL("arrays_flat_voltages counts %zu samples outside the maps' domain, not %zu", bad, bad2);
done:
    free(flag), free(xs), free(vs), free(args), free(out), free(xo), free(vo);
    return 0;
}
