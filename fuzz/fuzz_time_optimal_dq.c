// libFuzzer harness for time_optimal_dq_plan: any motor, limits, distance and workspace length give a documented
// code with out->n = 0 on error, or a valid table that starts at 0, ends at the distance, keeps its own margins and
// a finite d current that rests at both ends; the planner never writes past a workspace of exactly the advertised
// length (heap, so ASan sees it).
//
// Input: a header byte (4 a short workspace), an 8-bit mask of the groups decoded hostile (bit 0 the motor, bits
// 1..5 each limit; the others take the NEMA 17 preset at 24 V, 1 A, 20 kHz), then the distance (around 1 rad), the
// workspace shortfall, the motor and the limits (fuzz/decode.h).
#include <stdio.h>
#include <stdlib.h>
#include "decode.h"
#include "laws.h"
#include "time_optimal_dq.h"
#include "trajectory.h"

// Returns theta of the last row at tau = 1 (the sum of its coefficients).
static double end_angle(const struct tod_result *out)
{
    double a = 0;
    int j;
    for (j = 0; j < TRAJ_NCOEF; j++)
        a += out->theta[(out->n - 1) * TRAJ_NCOEF + j];
    return a;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct tod_result out;
    const struct motor_params nema17 = {4.10, 9.50e-3, 0.26870057685088805, 5.6e-6, 1e-4, 50};
    struct fz_reader r = {data, size};
    struct motor_params m = nema17;
    struct tod_limits l = {24.0, 0.84, 1.0, 0, 20000.0};
    double d, *f[5] = {&l.v_bus, &l.v_use, &l.i_max, &l.speed_max, &l.control_rate}, *work;
    uint8_t head = fz_byte(&r, 0), mask = fz_byte(&r, 0);
    size_t len = time_optimal_dq_work_len(), i;
    int rc, k;
    d = fz_value(&r, 1.0);
    if (head & 4)
        len -= 1 + fz_byte(&r, 0);
    if (mask & 1)
        fz_motor_fields(&r, false, &m);  // Nr 0..255
    for (k = 0; k < 5; k++)
        if (mask & (2u << k))
            *f[k] = fz_value(&r, *f[k]);
    work = malloc(len * sizeof *work);
    if (!work)
        return 0;
    rc = time_optimal_dq_plan(&m, &l, d, work, len, &out);
    free(work);
    if (rc != TOD_OK) {
        if (rc != TOD_EARGS && rc != TOD_ESTART && rc != TOD_ENOPLAN && rc != TOD_EWORK)
            FZ_FAIL("time_optimal_dq_plan: undocumented code %d", rc);
        if (out.n != 0)
            FZ_FAIL("time_optimal_dq_plan: code %d with %zu segments", rc, out.n);
        return 0;
    }
    if (len < time_optimal_dq_work_len())
        FZ_FAIL("time_optimal_dq_plan: TOD_OK on a short workspace");
    {
        struct traj tr = {out.n, out.breaks, out.theta, out.theta};
        if (out.n < 1 || out.n > TO_MAX_SEGMENTS || !traj_valid(&tr) || out.breaks[0] != 0)
            FZ_FAIL("time_optimal_dq_plan: TOD_OK with an invalid table of %zu segments", out.n);
    }
    if (!(out.margins.worst <= 0) || fabs(end_angle(&out) - d) > 1e-6 * (1 + fabs(d)))
        FZ_FAIL("time_optimal_dq_plan: worst %g, ends at %g for %g", out.margins.worst, end_angle(&out), d);
    for (i = 0; i <= out.n; i++)
        if (!(isfinite(out.knot_id[i]) && isfinite(out.knot_did[i])))
            FZ_FAIL("time_optimal_dq_plan: d current %g, %g at knot %zu", out.knot_id[i], out.knot_did[i], i);
    if (out.knot_id[0] != 0 || fabs(out.knot_id[out.n]) > 1e-9 * l.i_max)
        FZ_FAIL("time_optimal_dq_plan: d current %g, %g at rest", out.knot_id[0], out.knot_id[out.n]);
    return 0;
}
