// Segment tables: the paper's psi as one segment, held ends, finite differences, continuity, validation.
#include <stdint.h>
#include "check.h"
#include "plan.h"
#include "smc.h"
#include "trajectory.h"

// The paper's psi (highest power first) and its move of test_plan: theta 0 -> 0.02 rad on [0.02, 0.04] s.
static const double PSI[TRAJ_NCOEF] = {-126, 700, -1575, 1800, -1050, 252, 0, 0, 0, 0, 0};

// Returns 0; one psi segment gives plan_flag's flag within rounding, and the held values outside.
static int psi_segment_checks(void)
{
    const struct plan p = {0.1, 2.1, 0.4, 0.7, 0.02, 0.04, NULL};
    struct plan_coef pc;
    double breaks[2] = {0.02, 0.04}, th[TRAJ_NCOEF], rh[TRAJ_NCOEF], f[PLAN_FLAG_LEN], g[PLAN_FLAG_LEN], t;
    double peak[PLAN_FLAG_LEN] = {0};
    struct traj tr = {1, breaks, th, rh};
    int i, j;
    for (j = 0; j < TRAJ_NCOEF; j++)
        th[j] = PSI[j] * (p.theta2 - p.theta1), rh[j] = PSI[j] * (p.rho2 - p.rho1);
    th[TRAJ_NCOEF - 1] += p.theta1, rh[TRAJ_NCOEF - 1] += p.rho1;
    CHECK(traj_valid(&tr), "the psi table is valid");
    plan_init(&pc, &p);
    for (i = 0; i <= 200; i++) {  // each component's peak: the rounding of Horner's sum scales with it
        plan_flag(&pc, 0.02 + 0.02 * i / 200.0, g);
        for (j = 0; j < PLAN_FLAG_LEN; j++)
            peak[j] = fabs(g[j]) > peak[j] ? fabs(g[j]) : peak[j];
    }
    for (i = 0; i <= 60; i++) {
        t = 0.01 + 0.04 * i / 60.0;
        CHECK(traj_flag(&tr, t, f) == plan_flag(&pc, t, g), "inside flag at t=%g", t);
        for (j = 0; j < PLAN_FLAG_LEN; j++)
            CHECK(fabs(f[j] - g[j]) <= 1e-12 * peak[j], "flag[%d] at t=%g: %.17g vs %.17g", j, t, f[j], g[j]);
    }
    traj_flag(&tr, 0.0, f);
    CHECK(f[PLAN_THETA] == p.theta1 && f[PLAN_RHO] == p.rho1 && f[PLAN_DTHETA] == 0, "held start");
    traj_flag(&tr, 1.0, f);
    CHECK(fabs(f[PLAN_THETA] - p.theta2) < 1e-12 && fabs(f[PLAN_RHO] - p.rho2) < 1e-12 && f[PLAN_DDDTHETA] == 0,
          "held end %.17g %.17g %g", f[PLAN_THETA], f[PLAN_RHO], f[PLAN_DDDTHETA]);
    CHECK(!traj_flag(&tr, NAN, f) && f[PLAN_THETA] == p.theta1 && f[PLAN_DTHETA] == 0, "a NaN time holds the start");
    return 0;
}

// Returns 0; a three-segment table of cubics in tau: derivatives against central differences, segment lookup.
static int lookup_checks(void)
{
    // theta = tau^3 on [0, 1), 1 + 3 tau' on [1, 3) with tau' = (t - 1) / 2, ... any finite table will do.
    static const double breaks[4] = {0.0, 1.0, 3.0, 3.5};
    double th[3 * TRAJ_NCOEF] = {0}, rh[3 * TRAJ_NCOEF] = {0}, f[PLAN_FLAG_LEN], fp[PLAN_FLAG_LEN], fm[PLAN_FLAG_LEN],
                  t, h = 1e-6;
    struct traj tr = {3, breaks, th, rh};
    int i, k;
    for (i = 0; i < 3; i++) {
        th[i * TRAJ_NCOEF + 6] = 0.3 * (i + 1);  // tau^4
        th[i * TRAJ_NCOEF + 7] = 1.0 - i;        // tau^3
        th[i * TRAJ_NCOEF + 9] = 2.0;            // tau
        rh[i * TRAJ_NCOEF + 9] = 0.1 * (i + 1);  // rho's slope
        rh[i * TRAJ_NCOEF + 10] = 1.0;
    }
    CHECK(traj_valid(&tr), "valid");
    CHECK(traj_segment(&tr, -1) == 0 && traj_segment(&tr, 0.5) == 0 && traj_segment(&tr, 1.0) == 1, "lookup low");
    CHECK(traj_segment(&tr, 2.9) == 1 && traj_segment(&tr, 3.0) == 2 && traj_segment(&tr, 9) == 2, "lookup high");
    CHECK(traj_segment(&tr, NAN) == 0, "lookup NaN");
    for (i = 1; i < 35; i++) {
        t = 0.1 * i + 0.05;
        traj_flag(&tr, t, f);
        traj_flag(&tr, t + h, fp);
        traj_flag(&tr, t - h, fm);
        for (k = 0; k < 3; k++)
            CHECK(fabs((fp[PLAN_THETA + k] - fm[PLAN_THETA + k]) / (2 * h) - f[PLAN_THETA + k + 1]) < 1e-6,
                  "theta order %d at t=%g", k + 1, t);
        CHECK(fabs((fp[PLAN_RHO] - fm[PLAN_RHO]) / (2 * h) - f[PLAN_DRHO]) < 1e-8, "rho' at t=%g", t);
        CHECK(fabs((traj_theta(&tr, t + h, 3) - traj_theta(&tr, t - h, 3)) / (2 * h) - traj_theta(&tr, t, 4)) < 1e-5,
              "snap at t=%g", t);
        for (k = 0; k < 4; k++)
            CHECK(traj_theta(&tr, t, k) == f[PLAN_THETA + k], "traj_theta(%d) is the flag's at t=%g", k, t);
    }
    CHECK(traj_theta(&tr, 1.5, 5) == 0 && traj_theta(&tr, 1.5, -1) == 0, "orders out of range give 0");
    // traj_flag_seg: the same flag from any guess, and the segment of t on return.
    for (i = 0; i < 200; i++) {
        size_t seg = (size_t)(i * 7) % 5, want;  // guesses 0 .. 4, n = 3 included (out of range)
        t = -0.2 + 0.02 * ((i * 37) % 200);
        want = traj_segment(&tr, t);
        CHECK(traj_flag_seg(&tr, t, &seg, fp) == traj_flag(&tr, t, f), "inside at t=%g", t);
        for (k = 0; k < PLAN_FLAG_LEN; k++)
            CHECK(fp[k] == f[k], "flag[%d] from a guess at t=%g", k, t);
        CHECK(!(t > 0 && t < 3.5) || seg == want, "segment %zu of t=%g, want %zu", seg, t, want);
    }
    return 0;
}

// Returns 0; traj_valid refuses every kind of broken table.
static int valid_checks(void)
{
    double breaks[3] = {0.0, 1.0, 2.0}, th[2 * TRAJ_NCOEF] = {0}, rh[2 * TRAJ_NCOEF] = {0};
    struct traj tr = {2, breaks, th, rh}, bad;
    CHECK(traj_valid(&tr), "valid");
    bad = tr, bad.n = 0;
    CHECK(!traj_valid(&bad) && !traj_valid(NULL), "no segment");
    bad = tr, bad.rho = NULL;
    CHECK(!traj_valid(&bad), "no rho table");
    breaks[1] = 2.0;
    CHECK(!traj_valid(&tr), "breaks not increasing");
    breaks[1] = 1e-100;
    CHECK(!traj_valid(&tr), "(1/h)^4 overflows");
    breaks[1] = 1.0, th[13] = NAN;
    CHECK(!traj_valid(&tr), "a NaN coefficient");
    th[13] = 0, breaks[2] = INFINITY;
    CHECK(!traj_valid(&tr), "an infinite break");
    return 0;
}

// Returns 0; smc tracks a table given in its params: the step's reference is traj_flag's, and a broken table is
// refused.
static int smc_checks(void)
{
    static const double breaks[3] = {0.01, 0.03, 0.05};
    double th[2 * TRAJ_NCOEF] = {0}, rh[2 * TRAJ_NCOEF] = {0}, f[PLAN_FLAG_LEN], v[2], t;
    double y[5] = {0.1, 0.3, 0.5, 0.01, 2.0};
    struct traj tr = {2, breaks, th, rh}, bad = {0, breaks, th, rh};
    struct smc_params p;
    struct smc s;
    struct smc_terms w;
    int i, j;
    for (j = 0; j < TRAJ_NCOEF; j++)
        th[j] = PSI[j] * 0.02, th[TRAJ_NCOEF + j] = -PSI[j] * 0.01;
    th[2 * TRAJ_NCOEF - 1] += 0.02;
    rh[TRAJ_NCOEF - 1] = rh[2 * TRAJ_NCOEF - 1] = 0.4;
    smc_params_default(&p);
    CHECK(p.plan.traj == NULL, "no table by default");
    p.plan.traj = &bad;
    CHECK(!plan_valid(&p.plan), "plan_valid refuses a broken table");
    CHECK(smc_init(&s, &p) == SMC_EPLAN, "a broken table is refused");
    p.plan.traj = &tr;
    CHECK(smc_init(&s, &p) == SMC_PARAMS_OK, "a valid table is taken");
    for (i = 0; i <= 30; i++) {
        t = 0.002 * i;
        smc_step_terms(&s, t, y, NULL, v, &w);
        traj_flag(&tr, t, f);
        for (j = 0; j < PLAN_FLAG_LEN; j++)
            CHECK(w.flag[j] == f[j], "flag[%d] at t=%g", j, t);
        CHECK(isfinite(v[0]) && isfinite(v[1]), "finite voltages at t=%g", t);
    }
    return 0;
}

// Returns the number of failed checks of the trajectory suite.
int test_trajectory(void)
{
    psi_segment_checks();
    lookup_checks();
    valid_checks();
    smc_checks();
    return check_failures;
}
