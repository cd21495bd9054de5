// The time-optimal planner: a feasible, continuous table that ends at the distance, mirrored moves, error codes.
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include "check.h"
#include "time_optimal.h"
#include "trajectory.h"

// The NEMA 17 preset of flatstep.model.motor and the limits of tests/test_plan_time_optimal.py.
static const struct motor_params NEMA17 = {4.10, 9.50e-3, 0.26870057685088805, 5.6e-6, 1e-4, 50};
static double work[40000];
static struct to_result out, out2;

// Returns the limits at bus voltage v_bus with i_max = 1 A and the defaults of MotorLimits.
static struct to_limits limits_at(double v_bus)
{
    struct to_limits l = {v_bus, 1.0, 0.3, 0.3, 10.0, 1.2, 0.9, 0, 0, 0};
    return l;
}

// Returns 0; a move of each distance is feasible on a 4x finer check, ends at rest at the distance, and is C2.
static int feasible_checks(void)
{
    const double distances[] = {0.1, 1.0, 5.0, 20.0};
    const double buses[] = {24.0, 12.0};
    int i, b;
    CHECK(time_optimal_work_len() <= sizeof work / sizeof *work, "workspace %zu", time_optimal_work_len());
    for (b = 0; b < 2; b++)
        for (i = 0; i < 4; i++) {
            struct to_limits l = limits_at(buses[b]);
            struct traj tr = {0, out.breaks, out.theta, out.rho};
            double f[PLAN_FLAG_LEN], end, t, peak = 0;
            int rc = time_optimal_plan(&NEMA17, &l, distances[i], NULL, 0, work, sizeof work / sizeof *work, &out);
            size_t k;
            CHECK(rc == TO_OK, "rc %d at %g V, %g rad", rc, buses[b], distances[i]);
            if (rc != TO_OK)
                continue;
            tr.n = out.n;
            CHECK(traj_valid(&tr), "valid table at %g V, %g rad", buses[b], distances[i]);
            CHECK(out.margins.worst <= 0 && out.margins.voltage <= 0.998 * l.v_use, "margins %g %g", out.margins.worst,
                  out.margins.voltage);
            CHECK(out.gamma > 0.05 && out.gamma <= 1 && out.tables >= 1, "gamma %g tables %d", out.gamma, out.tables);
            end = out.breaks[out.n];
            traj_flag(&tr, end, f);
            CHECK(fabs(f[PLAN_THETA] - distances[i]) < 1e-9, "end %.17g", f[PLAN_THETA]);
            for (k = 0; k < 4000; k++) {  // a 4000-sample check: the voltage within the bus, the speed's sign
                t = end * (k + 0.5) / 4000;
                traj_flag(&tr, t, f);
                peak = f[PLAN_DTHETA] > peak ? f[PLAN_DTHETA] : peak;
                CHECK(f[PLAN_RHO] > 0 && f[PLAN_RHO] <= l.i_max, "rho %g at t=%g", f[PLAN_RHO], t);
            }
            CHECK(peak > 0, "the move goes forward");
        }
    return 0;
}

// Returns 0; a negative move is the positive one mirrored, coefficient for coefficient.
static int mirror_checks(void)
{
    struct to_limits l = limits_at(24.0);
    size_t k;
    int same = 1;
    CHECK(time_optimal_plan(&NEMA17, &l, 2.0, NULL, 0, work, sizeof work / sizeof *work, &out) == TO_OK, "+2 rad");
    CHECK(time_optimal_plan(&NEMA17, &l, -2.0, NULL, 0, work, sizeof work / sizeof *work, &out2) == TO_OK, "-2 rad");
    CHECK(out.n == out2.n, "segments %zu %zu", out.n, out2.n);
    for (k = 0; k < out.n * TRAJ_NCOEF; k++)
        same &= out.theta[k] == -out2.theta[k] && out.rho[k] == out2.rho[k];
    CHECK(same, "mirrored rows");
    return 0;
}

// Returns 0; bad arguments, a motor that cannot start, no feasible plan and a short workspace give their codes.
static int error_checks(void)
{
    struct to_limits l = limits_at(24.0), bad;
    struct motor_params m = NEMA17;
    const double tiny[1] = {1e-9}, nan_width[1] = {NAN};
    size_t n = sizeof work / sizeof *work;
    CHECK(time_optimal_plan(&NEMA17, &l, 0.0, NULL, 0, work, n, &out) == TO_EARGS && out.n == 0, "zero distance");
    CHECK(time_optimal_plan(&NEMA17, &l, NAN, NULL, 0, work, n, &out) == TO_EARGS, "NaN distance");
    bad = l, bad.i_hold = 1.0;
    CHECK(time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, work, n, &out) == TO_EARGS, "i_hold = i_max");
    bad = l, bad.torque_angle_max = 2.0;
    CHECK(time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, work, n, &out) == TO_EARGS, "torque angle");
    bad = l, bad.v_use = NAN;
    CHECK(time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, work, n, &out) == TO_EARGS, "NaN v_use");
    m.L = -1;
    CHECK(time_optimal_plan(&m, &l, 1.0, NULL, 0, work, n, &out) == TO_EARGS, "negative inductance");
    CHECK(time_optimal_plan(&NEMA17, &l, 1.0, nan_width, 1, work, n, &out) == TO_EARGS, "NaN width");
    CHECK(time_optimal_plan(&NEMA17, &l, 1.0, tiny, 0, work, n, &out) == TO_EARGS, "no widths");
    bad = l, bad.v_bus = 0.5;  // the resistance alone takes the bus at i_hold
    CHECK(time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, work, n, &out) == TO_ESTART && out.n == 0, "cannot start");
    bad = l, bad.v_use = 0.05;  // R i_hold alone takes more than 5 % of the bus
    CHECK(time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, work, n, &out) == TO_ENOPLAN && out.n == 0, "v_use 0.05");
    CHECK(time_optimal_plan(&NEMA17, &l, 1e5, NULL, 0, work, n, &out) == TO_ELONG && out.n == 0, "1e5 rad");
    CHECK(time_optimal_plan(&NEMA17, &l, 1e300, NULL, 0, work, n, &out) == TO_ELONG, "1e300 rad");
    CHECK(time_optimal_plan(&NEMA17, &l, 1.0, NULL, 0, work, time_optimal_work_len() - 1, &out) == TO_EWORK,
          "short workspace");
    CHECK(time_optimal_plan(&NEMA17, &l, 1.0, NULL, 0, NULL, n, &out) == TO_EWORK, "no workspace");
    return 0;
}

// Returns 0; moves of 1e-7 to 2e-5 rad and extreme smoothing widths plan or refuse inside a workspace of exactly
// time_optimal_work_len() (on the heap, so the sanitizer build sees a write past it: these once overflowed the box
// filter's running sum).
static int tiny_move_checks(void)
{
    const double distances[] = {1e-7, 3e-6, 1e-5, -1e-5, 1.2e-5, 1.5e-5, 2e-5, 1e-9};
    const double widths[] = {1e300, 1e-300, 1e3, 1e-12};
    struct to_limits l = limits_at(24.0);
    size_t n = time_optimal_work_len(), i;
    double *heap = malloc(n * sizeof *heap);
    int rc;
    CHECK(heap != NULL, "workspace");
    if (!heap)
        return 0;
    for (i = 0; i < sizeof distances / sizeof *distances; i++) {
        rc = time_optimal_plan(&NEMA17, &l, distances[i], NULL, 0, heap, n, &out);
        CHECK(rc == (i < 7 ? TO_OK : TO_ENOPLAN), "rc %d at %g rad", rc, distances[i]);
        if (rc == TO_OK) {
            struct traj tr = {out.n, out.breaks, out.theta, out.rho};
            double f[PLAN_FLAG_LEN];
            traj_flag(&tr, out.breaks[out.n], f);
            CHECK(fabs(f[PLAN_THETA] - distances[i]) < 1e-15, "end %.17g of %g rad", f[PLAN_THETA], distances[i]);
        }
    }
    for (i = 0; i < sizeof widths / sizeof *widths; i++) {
        rc = time_optimal_plan(&NEMA17, &l, 1.0, &widths[i], 1, heap, n, &out);
        CHECK(rc == TO_OK || rc == TO_ENOPLAN || rc == TO_ELONG, "rc %d at width %g s", rc, widths[i]);
        rc = time_optimal_plan(&NEMA17, &l, 1e-5, &widths[i], 1, heap, n, &out);
        CHECK(rc == TO_OK || rc == TO_ENOPLAN || rc == TO_ELONG, "rc %d at width %g s, 1e-5 rad", rc, widths[i]);
    }
    free(heap);
    return 0;
}

// Returns true when every ratio of g is inf.
static int all_inf(const struct to_margins *g)
{
    return isinf(g->voltage) && isinf(g->current) && isinf(g->torque_angle) && isinf(g->speed) && isinf(g->acceleration)
           && isinf(g->jerk) && isinf(g->worst);
}

// Returns 0; margins are never NaN and never divide by zero: every ratio inf on an invalid motor, limits or table
// or a table whose values overflow, the voltage inf where rho s underflows; a denormal inertia, whose envelope
// overflows, is refused with TO_ESTART and no table; an acceleration cap whose envelope underflows below full bus
// finds no plan (inputs the fuzzer found, fuzz/regressions/time_optimal).
static int margins_edge_checks(void)
{
    static double breaks[2] = {0, 0.01}, theta[TRAJ_NCOEF], rho[TRAJ_NCOEF];
    struct traj tr = {1, breaks, theta, rho};
    struct to_limits l = limits_at(24.0), bad = l;
    struct motor_params m = NEMA17;
    struct to_margins g;
    size_t n = time_optimal_work_len();
    double *heap = malloc(n * sizeof *heap);
    int rc;
    rho[TRAJ_NCOEF - 1] = 0.3;
    g = time_optimal_margins(&NEMA17, &l, &tr);
    CHECK(g.worst < 0 && g.voltage > 0 && g.current == 0.3 && g.speed == 0, "a hold at 0.3 A: worst %g", g.worst);
    breaks[1] = 0;  // a segment of zero length
    g = time_optimal_margins(&NEMA17, &l, &tr);
    CHECK(all_inf(&g), "zero-length segment: worst %g", g.worst);
    breaks[1] = 0.01;
    bad.v_bus = 0;
    g = time_optimal_margins(&NEMA17, &bad, &tr);
    CHECK(all_inf(&g), "v_bus = 0: worst %g", g.worst);
    m.J = 0;
    g = time_optimal_margins(&m, &l, &tr);
    CHECK(all_inf(&g), "J = 0: worst %g", g.worst);
    rho[TRAJ_NCOEF - 1] = 1e-170;  // (Km rho)^2 underflows: s = 0
    g = time_optimal_margins(&NEMA17, &l, &tr);
    CHECK(isinf(g.voltage) && isinf(g.worst) && !isnan(g.torque_angle), "rho 1e-170: voltage %g", g.voltage);
    rho[TRAJ_NCOEF - 1] = 0.3;
    theta[0] = 1e300, breaks[1] = 1e-10;  // speed, acceleration and jerk overflow
    g = time_optimal_margins(&NEMA17, &l, &tr);
    CHECK(all_inf(&g), "overflowing table: worst %g", g.worst);
    m.J = 9.71373e-319;
    CHECK(heap != NULL, "workspace");
    if (!heap)
        return 0;
    rc = time_optimal_plan(&m, &l, 1.0, NULL, 0, heap, n, &out);
    CHECK(rc == TO_ESTART && out.n == 0, "denormal inertia: rc %d, %zu segments", rc, out.n);
    m = NEMA17, m.Km = 0.04, m.B = 0, m.Nr = 60;  // no friction: braking at the top speed was 0, its time 1 / 0
    rc = time_optimal_plan(&m, &l, 1.0, NULL, 0, heap, n, &out);
    CHECK(rc == TO_OK && out.n > 0 && out.margins.worst <= 0, "B = 0: rc %d, worst %g", rc, out.margins.worst);
    m = NEMA17, m.B = 0;  // braking 0 inside the envelope: refused (1 / 0 before), as the reference refuses it
    rc = time_optimal_plan(&m, &l, 1.0, NULL, 0, heap, n, &out);
    CHECK(rc == TO_ESTART && out.n == 0, "NEMA 17, B = 0: rc %d", rc);
    m = NEMA17, m.Km = 0.04, m.Nr = 60;
    m.B = 3.1315130626053307e-294, m.J = 5.600000005216298e-06;  // below full bus, a phase of negative duration
    rc = time_optimal_plan(&m, &l, 1.0, NULL, 0, heap, n, &out);
    CHECK(rc == TO_OK && out.margins.worst <= 0, "B = 3e-294: rc %d, worst %g", rc, out.margins.worst);
    {  // a denormal width and speed cap: a sampling step of 0, width / 0
        const double denormal_width = 4.94e-324;
        bad = l, bad.speed_max = 4.83e-319;
        rc = time_optimal_plan(&NEMA17, &bad, -2.26e274, &denormal_width, 1, heap, n, &out);
        CHECK(rc == TO_ELONG && out.n == 0, "step 0: rc %d", rc);
    }
    bad = l, bad.v_bus = bad.v_use = 5.96e-212;  // v_use v_bus underflowed: the first gamma divided by 0
    rc = time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, heap, n, &out);
    CHECK(rc == TO_EARGS && out.n == 0, "v_use v_bus underflows: rc %d", rc);
    bad = l, bad.accel_max = 5.47e-318;  // the envelope's floor 1e-12 a+(0) underflowed to 0: 1 / 0
    rc = time_optimal_plan(&NEMA17, &bad, 1.0, NULL, 0, heap, n, &out);
    CHECK(rc == TO_ENOPLAN && out.n == 0, "denormal acceleration cap: rc %d, %zu segments", rc, out.n);
    {  // the top speed underflowed to 0 (speed cap 5e-41 rad/s, 1.7e-314 V bus): the cruise divided by 0
        struct motor_params slow = {5.3990332965776108e-255, 0.04, 1.7486033150166349e-314, 9.8958333331243964e-43,
                                    7.3786976294838206e+20,  68};
        bad = l, bad.v_bus = 1.7486088035918945e-314, bad.speed_max = 5.3333333333312432e-41;
        rc = time_optimal_plan(&slow, &bad, -DBL_MAX, NULL, 0, heap, n, &out);
        CHECK(rc == TO_ESTART && out.n == 0, "top speed 0: rc %d, %zu segments", rc, out.n);
    }
    free(heap);
    return 0;
}

// Returns 0 (failures are counted by CHECK).
int test_time_optimal(void)
{
    feasible_checks();
    mirror_checks();
    error_checks();
    tiny_move_checks();
    margins_edge_checks();
    return 0;
}
