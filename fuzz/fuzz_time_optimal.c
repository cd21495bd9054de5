// libFuzzer harness for time_optimal_plan and time_optimal_margins: any motor, limits, distance, smoothing widths
// and workspace length give a documented code with out->n = 0 on error, or a valid table that starts at 0, ends at
// the distance, keeps its own margins and mirrors for -distance; the planner never writes past a workspace of
// exactly the advertised length (heap, so ASan sees it). time_optimal_margins on any table near the plan's gives
// ratios that are never NaN, and every ratio inf when the motor, the limits or the table is invalid.
//
// Input: a header byte (1 widths given, 2 the mirror check, 4 a short workspace, 8 margins on a decoded table),
// a 32-bit mask of the groups decoded hostile (bit 0 the motor, bits 1..10 each limit; the others take the NEMA 17
// preset at 24 V), then the distance (around 1 rad), the widths, the workspace shortfall, the motor, the limits
// and the table (fuzz/decode.h).
#include <stdio.h>
#include <stdlib.h>
#include "decode.h"
#include "laws.h"
#include "time_optimal.h"
#include "trajectory.h"

#define WIDTHS_MAX (TO_MAX_WIDTHS + 2)

// Returns true when time_optimal.h's documented ranges hold for the limits.
static bool limits_ok(const struct to_limits *l)
{
    return fz_positive(l->v_bus) && isfinite(l->i_max) && l->i_hold > 0 && l->i_hold < l->i_max && l->i_run > 0
           && l->i_run <= l->i_hold && fz_positive(l->speed_corner) && l->torque_angle_max > 0
           && l->torque_angle_max < 1.5707963267948966 && l->v_use > 0 && l->v_use <= 1
           && 0.998 * l->v_use * l->v_bus > 0 && isfinite(l->speed_max) && l->speed_max >= 0 && isfinite(l->accel_max)
           && l->accel_max >= 0 && isfinite(l->jerk_max) && l->jerk_max >= 0;
}

// Returns true when the motor's documented ranges hold (motor.h).
static bool motor_ok(const struct motor_params *m)
{
    return fz_positive(m->R) && fz_positive(m->L) && fz_positive(m->Km) && fz_positive(m->J) && isfinite(m->B)
           && m->B >= 0 && m->Nr >= 1;
}

// Returns nothing; decodes the limits field by field (bit k + 1 of mask: field k hostile, else 24 V, 1 A).
static void decode_limits(struct fz_reader *r, uint32_t mask, struct to_limits *l)
{
    double *f[10] = {&l->v_bus, &l->i_max,     &l->i_hold,    &l->i_run,   &l->speed_corner, &l->torque_angle_max,
                     &l->v_use, &l->speed_max, &l->accel_max, &l->jerk_max};
    const double nominal[10] = {24.0, 1.0, 0.3, 0.3, 10.0, 1.2, 0.9, 0, 0, 0};
    int k;
    for (k = 0; k < 10; k++)
        *f[k] = mask & (2u << k) ? fz_value(r, nominal[k]) : nominal[k];
}

// Returns nothing; aborts unless a margin ratio is a number and >= 0, and worst is their largest less 1 (or inf).
static void check_margins(const struct to_margins *g, const char *what)
{
    const double r[6] = {g->voltage, g->current, g->torque_angle, g->speed, g->acceleration, g->jerk};
    int k;
    for (k = 0; k < 6; k++)
        if (isnan(r[k]) || r[k] < 0)
            FZ_FAIL("%s: margin %d is %g", what, k, r[k]);
    if (isnan(g->worst) || g->worst < -1)
        FZ_FAIL("%s: worst margin %g", what, g->worst);
}

// Returns nothing; aborts unless the OK plan is a valid table from (0, 0) to (tf, distance) within its margins.
static void check_plan(const struct motor_params *m, const struct to_limits *l, double d, const double *widths,
                       size_t nw, const struct to_result *out)
{
    struct traj tr = {out->n, out->breaks, out->theta, out->rho};
    struct to_margins g;
    double f[PLAN_FLAG_LEN], end;
    size_t i;
    bool width_found = widths == NULL;
    if (out->n < 1 || out->n > TO_MAX_SEGMENTS || !traj_valid(&tr))
        FZ_FAIL("time_optimal_plan: TO_OK with an invalid table of %zu segments", out->n);
    if (out->breaks[0] != 0 || !(out->gamma >= 0.05 && out->gamma <= 1) || out->tables < 1)
        FZ_FAIL("time_optimal_plan: start %g, gamma %g, %d tables", out->breaks[0], out->gamma, out->tables);
    for (i = 0; i < nw && widths; i++)
        width_found |= widths[i] == out->width;
    if (!width_found || !(out->width > 0))
        FZ_FAIL("time_optimal_plan: width %g is not one tried", out->width);
    g = time_optimal_margins(m, l, &tr);
    if (memcmp(&g, &out->margins, sizeof g) != 0 || !(g.worst <= 0))
        FZ_FAIL("time_optimal_plan: margins %g, recomputed %g", out->margins.worst, g.worst);
    check_margins(&g, "time_optimal_plan");
    traj_flag(&tr, 0, f);
    if (fabs(f[PLAN_THETA]) > 1e-9 * fabs(d))
        FZ_FAIL("time_optimal_plan: starts at %.17g rad", f[PLAN_THETA]);
    end = traj_theta(&tr, out->breaks[out->n], 0);
    if (!(fabs(end - d) <= 1e-8 * fabs(d) + 1e-300))  // a denormal distance ends within its rounding
        FZ_FAIL("time_optimal_plan: ends at %.17g rad, not %.17g", end, d);
}

// Returns nothing; margins on a table decoded around the plan's (or a constant 0.3 A hold when no plan); aborts
// when a ratio is NaN for valid motor, limits and table.
static void fuzz_margins(struct fz_reader *r, const struct motor_params *m, const struct to_limits *l,
                         const struct to_result *out)
{
    static double breaks[TO_MAX_SEGMENTS + 1], theta[TO_MAX_SEGMENTS * TRAJ_NCOEF], rho[TO_MAX_SEGMENTS * TRAJ_NCOEF];
    struct traj tr = {0, breaks, theta, rho};
    struct to_margins g;
    size_t i, k;
    tr.n = out->n ? out->n : 1 + (size_t)(fz_byte(r, 0) % 4);
    for (i = 0; i <= tr.n; i++)
        breaks[i] = out->n ? fz_value(r, out->breaks[i]) : (i ? breaks[i - 1] + fz_value(r, 0.01) : fz_value(r, 0));
    for (k = 0; k < tr.n * TRAJ_NCOEF; k++) {
        theta[k] = fz_value(r, out->n ? out->theta[k] : 0);
        rho[k] = fz_value(r, out->n ? out->rho[k] : (k % TRAJ_NCOEF == TRAJ_NCOEF - 1 ? 0.3 : 0));
    }
    g = time_optimal_margins(m, l, &tr);
    if (motor_ok(m) && limits_ok(l) && traj_valid(&tr))
        check_margins(&g, "time_optimal_margins");
    else if (!(isinf(g.voltage) && isinf(g.current) && isinf(g.torque_angle) && isinf(g.speed) && isinf(g.acceleration)
               && isinf(g.jerk) && isinf(g.worst)))
        FZ_FAIL("time_optimal_margins: a finite margin %g on an invalid motor, limits or table", g.worst);
}

// Returns 0 (libFuzzer's convention); aborts when a contract of the time-optimal planner is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct to_result out, out2;
    const struct motor_params nema17 = {4.10, 9.50e-3, 0.26870057685088805, 5.6e-6, 1e-4, 50};
    struct fz_reader r = {data, size};
    struct motor_params m = nema17;
    struct to_limits l;
    double d, widths[WIDTHS_MAX], *work;
    uint8_t head = fz_byte(&r, 0);
    uint32_t mask = fz_u32(&r, 0);
    size_t nw = 0, len = time_optimal_work_len(), i, k;
    bool args_ok;
    int rc, rc2;
    d = fz_value(&r, 1.0);
    if (head & 1) {
        nw = fz_byte(&r, 5) % (WIDTHS_MAX + 1);  // 0 and more than TO_MAX_WIDTHS: refused
        for (i = 0; i < nw; i++)
            widths[i] = fz_value(&r, (m.L / m.R) * ldexp(1, (int)i - 2));
    }
    if (head & 4)
        len -= 1 + fz_byte(&r, 0);
    if (mask & 1)
        fz_motor_fields(&r, true, &m);
    decode_limits(&r, mask, &l);
    args_ok =
        motor_ok(&m) && limits_ok(&l) && isfinite(d) && d != 0 && (!(head & 1) || (nw >= 1 && nw <= TO_MAX_WIDTHS));
    for (i = 0; i < nw && (head & 1); i++)
        args_ok &= fz_positive(widths[i]);
    for (i = 0; args_ok && !(head & 1) && i < 5; i++)  // the default widths: 1/4 .. 4 times L/R
        args_ok &= fz_positive((i == 0 ? 0.25 : i == 1 ? 0.5 : (double)(1 << (i - 2))) * (m.L / m.R));
    work = malloc(len * sizeof *work);  // exactly the length passed: ASan sees a write past it
    if (!work)
        return 0;
    out.n = 99;
    rc = time_optimal_plan(&m, &l, d, head & 1 ? widths : NULL, nw, work, len, &out);
    if (rc != TO_OK && rc != TO_EARGS && rc != TO_ESTART && rc != TO_ENOPLAN && rc != TO_EWORK && rc != TO_ELONG)
        FZ_FAIL("time_optimal_plan returned %d, not a documented code", rc);
    if ((rc == TO_EARGS) != !args_ok)
        FZ_FAIL("time_optimal_plan returned %d on %s arguments", rc, args_ok ? "valid" : "invalid");
    if (args_ok && (rc == TO_EWORK) != (len < time_optimal_work_len()))
        FZ_FAIL("time_optimal_plan returned %d on a workspace of %zu (%zu needed)", rc, len, time_optimal_work_len());
    if (rc != TO_OK && out.n != 0)
        FZ_FAIL("time_optimal_plan returned %d with %zu segments", rc, out.n);
    if (rc == TO_OK)
        check_plan(&m, &l, d, head & 1 ? widths : NULL, nw, &out);
    if (head & 2) {  // -distance: the same table mirrored, coefficient for coefficient
        rc2 = time_optimal_plan(&m, &l, -d, head & 1 ? widths : NULL, nw, work, len, &out2);
        if (rc2 != rc || out2.n != out.n)
            FZ_FAIL("time_optimal_plan: %d and %zu segments for -d, %d and %zu for d", rc2, out2.n, rc, out.n);
        for (k = 0; k < out.n * TRAJ_NCOEF; k++)
            if (out2.theta[k] != -out.theta[k] || memcmp(&out2.rho[k], &out.rho[k], sizeof out.rho[k]) != 0)
                FZ_FAIL("time_optimal_plan: -d is not the mirror of d at coefficient %zu", k);
    }
    free(work);
    if (head & 8)
        fuzz_margins(&r, &m, &l, &out);
    return 0;
}
