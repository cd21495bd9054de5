// The field-weakening planner: feasible tables that end at the distance, field weakening at speed, the speed cap,
// mirrored moves and the error codes.
#include <math.h>
#include "check.h"
#include "time_optimal_dq.h"
#include "time_optimal_dq_cases.h"
#include "trajectory.h"

// The NEMA 17 preset of flatstep.model.motor.
static const struct motor_params NEMA17 = {4.10, 9.50e-3, 0.26870057685088805, 5.6e-6, 1e-4, 50};
static double work[60000];
static struct tod_result out, out2;

// Returns theta of row i of out at tau (Horner, highest power first).
static double theta_at(const struct tod_result *r, size_t i, double tau)
{
    double a = 0;
    int j;
    for (j = 0; j < TRAJ_NCOEF; j++)
        a = a * tau + r->theta[i * TRAJ_NCOEF + j];
    return a;
}

// Returns 0; each move is feasible, uses the bus, ends at the distance, weakens the field at speed and keeps under
// the cap.
static int feasible_checks(void)
{
    const double distances[] = {0.3, 1.0, 5.0};
    const double buses[] = {12.0, 24.0};
    size_t n = sizeof work / sizeof *work;
    int i, b;
    CHECK(time_optimal_dq_work_len() <= n, "workspace %zu", time_optimal_dq_work_len());
    for (b = 0; b < 2; b++)
        for (i = 0; i < 3; i++) {
            struct tod_limits l = {buses[b], 0.84, 1.0, 0, 20000};
            double cap = time_optimal_dq_speed_cap(&NEMA17, &l);
            int rc = time_optimal_dq_plan(&NEMA17, &l, distances[i], work, n, &out);
            CHECK(rc == TOD_OK, "rc %d at %g V, %g rad", rc, buses[b], distances[i]);
            if (rc != TOD_OK)
                continue;
            CHECK(out.margins.worst <= 0 && out.margins.voltage <= 1 && out.margins.current <= 1, "margins %g %g %g",
                  out.margins.worst, out.margins.voltage, out.margins.current);
            CHECK(out.margins.speed_peak <= cap, "peak %g over the cap %g", out.margins.speed_peak, cap);
            // the currents change at the bus's full rate (no share kept for the inductance), in one or two shots
            CHECK(out.margins.voltage >= 0.95 && out.tables >= 1 && out.tables <= 2, "voltage %g in %d shots",
                  out.margins.voltage, out.tables);
            CHECK(fabs(theta_at(&out, out.n - 1, 1.0) - distances[i]) < 1e-9, "ends at %g",
                  theta_at(&out, out.n - 1, 1.0));
            CHECK(out.knot_id[0] == 0 && fabs(out.knot_id[out.n]) < 1e-12, "rest d current %g %g", out.knot_id[0],
                  out.knot_id[out.n]);
            if (distances[i] >= 1.0)  // at speed the back EMF eats the bus: the d current goes negative
                CHECK(out.margins.i_d_min < -0.3, "i_d_min %g at %g V, %g rad", out.margins.i_d_min, buses[b],
                      distances[i]);
        }
    return 0;
}

// Returns 0; a negative move mirrors the positive one; the error codes.
static int mirror_and_errors(void)
{
    struct tod_limits l = {24, 0.84, 1.0, 0, 20000}, bad = l;
    size_t i, n = sizeof work / sizeof *work;
    int rc = time_optimal_dq_plan(&NEMA17, &l, 1.0, work, n, &out);
    int rc2 = time_optimal_dq_plan(&NEMA17, &l, -1.0, work, n, &out2);
    CHECK(rc == TOD_OK && rc2 == TOD_OK && out.n == out2.n, "rc %d %d", rc, rc2);
    for (i = 0; rc == TOD_OK && rc2 == TOD_OK && i < out.n * TRAJ_NCOEF; i++)
        CHECK(out.theta[i] == -out2.theta[i], "row %zu", i);
    CHECK(time_optimal_dq_plan(&NEMA17, &l, 0.0, work, n, &out) == TOD_EARGS && out.n == 0, "zero distance");
    CHECK(time_optimal_dq_plan(&NEMA17, &l, NAN, work, n, &out) == TOD_EARGS, "NaN distance");
    CHECK(time_optimal_dq_plan(&NEMA17, &l, 1.0, work, time_optimal_dq_work_len() - 1, &out) == TOD_EWORK, "work");
    bad.control_rate = 0;
    CHECK(time_optimal_dq_plan(&NEMA17, &bad, 1.0, work, n, &out) == TOD_EARGS, "control rate 0");
    bad = l, bad.v_use = 1.5;
    CHECK(time_optimal_dq_plan(&NEMA17, &bad, 1.0, work, n, &out) == TOD_EARGS, "v_use 1.5");
    bad = l, bad.speed_max = 40;  // the user's cap binds below the commutation cap
    rc = time_optimal_dq_plan(&NEMA17, &bad, 5.0, work, n, &out);
    CHECK(rc == TOD_OK && out.margins.speed_peak <= 40, "capped peak %g", out.margins.speed_peak);
    return 0;
}

// Returns 0; the double planner still gives the durations that the single-precision test holds its build to
// (time_optimal_dq_cases.h), within TOD_DOUBLE_TOL.
static int float_table_checks(void)
{
    size_t c, b, i, n = sizeof work / sizeof *work;
    int rc;
    double ms, want;
    for (c = 0; c < sizeof TOD_CASES / sizeof *TOD_CASES; c++)
        for (b = 0; b < 2; b++)
            for (i = 0; i < 5; i++) {
                const struct tod_limits lim = {TOD_CASE_BUS[b], 0.84, TOD_CASES[c].i_max, 0, 20000.0};
                rc = time_optimal_dq_plan(&TOD_CASES[c].m, &lim, TOD_CASE_DISTANCE[i], work, n, &out);
                ms = rc == TOD_OK ? 1e3 * out.breaks[out.n] : 0.0;
                want = TOD_CASES[c].ms[b][i];
                CHECK(rc == TOD_OK && rel_diff(ms, want) <= TOD_DOUBLE_TOL,
                      "%s %g V %g rad: rc %d, %.6f ms, time_optimal_dq_cases.h has %.6f ms", TOD_CASES[c].name,
                      TOD_CASE_BUS[b], TOD_CASE_DISTANCE[i], rc, ms, want);
            }
    return 0;
}

// Returns 0; a terminal ramp whose voltage overflows aims the next rate at 0, whose ramp has no voltage: that landing
// is kept (its voltage once divided the rate's share by 0), and the plan is a valid table within its limits.
static int ramp_voltage_overflow(void)
{
    const struct motor_params huge = {4.1, 1e156, 1e156, 1e156, 1e-4, 96};
    const struct tod_limits l = {1e156, 0.84, 1.0, 1e156, 20000};
    int rc = time_optimal_dq_plan(&huge, &l, 1.0, work, sizeof work / sizeof *work, &out);
    CHECK(rc == TOD_OK && out.margins.worst <= 0 && fabs(theta_at(&out, out.n - 1, 1.0) - 1.0) < 1e-9,
          "rc %d, worst %g, ends at %g", rc, out.margins.worst, rc == TOD_OK ? theta_at(&out, out.n - 1, 1.0) : 0.0);
    return 0;
}

int test_time_optimal_dq(void)
{
    float_table_checks();
    ramp_voltage_overflow();
    feasible_checks();
    mirror_and_errors();
    return 0;
}
