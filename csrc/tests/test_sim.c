// The closed-loop run loops on the paper's runs: tracking, sampled vs continuous, faults and bad arguments.
#include "check.h"
#include "continuous.h"
#include "sampled.h"
#include "smc.h"

#define N_OUT 601

static const double knots[2] = {0.02, 0.04};
static double t_out[N_OUT], x_out[4 * 6001], v_out[2 * 6001], xs_out[4 * 6001];

static struct controller ctrl;
static struct sampled loop;

// Returns nothing; sets up the paper's controller (W1 = W2 = w), bound into ctrl, its plant (load, no effects)
// and the start state.
static void paper(struct smc *s, struct plant *plant, double w, double load, double x0[4])
{
    struct smc_params p;
    const struct plant_effects none = {0, 0, 0, 0, 0};
    smc_params_default(&p);
    p.gains.W1 = p.gains.W2 = w;
    smc_init(s, &p);
    smc_controller(s, &ctrl);
    plant->motor = p.motor;
    plant->load = load;
    plant->effects = none;
    x0[0] = 0.4, x0[1] = 0, x0[2] = 0, x0[3] = 0;
}

// Returns sampled_run's status on an ideal loop (no sensors, observer or bus) with period Ts and RK4 substeps.
static volatile uint32_t cancel_flag;

static int run_ideal(struct smc *s, const struct plant *plant, const double x0[4], double Ts, uint32_t substeps,
                     size_t n, struct sim_stats *st)
{
    struct sampled_params p = {0};
    p.cancel = &cancel_flag;
    p.Ts = Ts;
    p.substeps = substeps;
    p.drive.v_bus = INFINITY;
    p.model = s->p.motor;
    if (sampled_init(&loop, &p) != SIM_OK)
        return SIM_EARGS;
    return sampled_run(&loop, &ctrl, plant, x0, n, NULL, xs_out, v_out, NULL, NULL, st);
}

// Returns the largest |theta - theta*| over the output samples of a run (t, x rows of 4).
static double max_theta_error(const struct smc *s, const double *t, const double *x, size_t n)
{
    double f[PLAN_FLAG_LEN], worst = 0;
    size_t i;
    for (i = 0; i < n; i++) {
        plan_eval(&s->p.plan, t[i], f);
        worst = fmax(worst, fabs(x[4 * i + 3] - f[PLAN_THETA]));
    }
    return worst;
}

// Returns 0 after the continuous-loop checks (paper Fig. 1 and Fig. 2, faults, arguments).
static int continuous_checks(void)
{
    struct continuous_params cp = {1e-10, 1e-12, 1.0, 1000000, CONTINUOUS_DOP853, knots, 2, NULL};
    struct plant plant;
    struct sim_stats st;
    struct smc s;
    double x0[4], err;
    int i, rc;
    for (i = 0; i < N_OUT; i++)
        t_out[i] = 0.06 * i / (N_OUT - 1);
    // Every integrator (DOP853 with Hermite output, DOPRI5, DOP853 with 7th-order dense output) tracks the plan.
    for (i = CONTINUOUS_DOP853; i <= CONTINUOUS_DOP853_DENSE; i++) {
        cp.method = (uint32_t)i;
        paper(&s, &plant, 100, 0, x0);
        rc = continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st);
        err = max_theta_error(&s, t_out, x_out, N_OUT);
        CHECK(rc == SIM_OK && err < 1e-8, "Fig. 1, method %d: rc %d max theta error %g", i, rc, err);
        CHECK(fabs(x_out[4 * (N_OUT - 1) + 3] - 0.02) < 1e-8 && x_out[0] == 0.4, "Fig. 1 ends at theta2, starts at x0");
        printf("  Fig. 1 continuous, method %d: %u steps, %u rejected, %u rhs calls, max |theta - theta*| %.3g rad\n",
               i, st.steps, st.rejected, st.rhs_evals, err);
    }
    cp.method = CONTINUOUS_DOP853_DENSE + 1;
    CHECK(continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st) == SIM_EARGS, "unknown method");
    cp.method = CONTINUOUS_DOP853;
    paper(&s, &plant, 300, 1e-5, x0);
    rc = continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st);
    err = 0.02 - x_out[4 * (N_OUT - 1) + 3];
    CHECK(rc == SIM_OK && err > 1e-4 && err < 1e-3, "Fig. 2: rc %d theta2 - theta(0.06) = %g", rc, err);
    // The plant runs on its own parameters: with R 20 % above the model's the move is lost (theta(0.06) =
    // -4.62e-4 rad; the scipy reference agrees, tests/test_core_sim.py).
    paper(&s, &plant, 300, 0, x0);
    plant.motor.R *= 1.2;
    rc = continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st);
    CHECK(rc == SIM_OK && fabs(x_out[4 * (N_OUT - 1) + 3] + 4.619e-4) < 1e-6, "R + 20 %%: theta(0.06) %.9g",
          x_out[4 * (N_OUT - 1) + 3]);
    // Zero currents are outside the law's domain at every stage: the run stops with SIM_ECONTROL.
    paper(&s, &plant, 100, 0, x0);
    x0[0] = 0;
    rc = continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st);
    CHECK(rc == SIM_ECONTROL && (st.controller_status & SMC_RHO) && st.t_fail == 0.0, "x0 = 0: rc %d status %u", rc,
          st.controller_status);
    x0[0] = 0.4;
    cp.max_steps = 10;
    cp.cancel = &cancel_flag;
    cancel_flag = 1;
    CHECK(continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st) == SIM_ECANCELLED, "cancelled");
    cancel_flag = 0;
    cp.cancel = NULL;
    CHECK(continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st) == SIM_EMAXSTEPS, "max_steps = 10");
    cp.max_steps = 1000000;
    t_out[5] = 1.0;
    CHECK(continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st) == SIM_EARGS, "decreasing t_out");
    t_out[5] = 0.06 * 5 / (N_OUT - 1);
    x0[2] = NAN;
    CHECK(continuous_run(&ctrl, &plant, x0, t_out, N_OUT, &cp, x_out, &st) == SIM_EARGS, "NaN in x0");
    return 0;
}

// Returns 0 after the sampled-loop checks: convergence to the continuous loop as Ts -> 0, faults, arguments.
static int sampled_checks(void)
{
    struct continuous_params cp = {1e-10, 1e-12, 1.0, 1000000, CONTINUOUS_DOP853, knots, 2, NULL};
    struct plant plant;
    struct sim_stats st;
    struct smc s;
    double x0[4], ts[6001], diff[3];
    size_t n, i, k;
    int rc, j;
    const double periods[3] = {4e-5, 2e-5, 1e-5};
    paper(&s, &plant, 100, 0, x0);
    for (j = 0; j < 3; j++) {
        n = (size_t)(0.06 / periods[j] + 0.5);
        rc = run_ideal(&s, &plant, x0, periods[j], 4, n, &st);
        for (i = 0; i <= n; i++)
            ts[i] = i * periods[j];
        CHECK(rc == SIM_OK, "Ts %g: rc %d", periods[j], rc);
        CHECK(continuous_run(&ctrl, &plant, x0, ts, n + 1, &cp, x_out, &st) == SIM_OK, "continuous on the same grid");
        diff[j] = 0;
        for (k = 0; k <= n; k++)
            diff[j] = fmax(diff[j], fabs(xs_out[4 * k + 3] - x_out[4 * k + 3]));
        printf("  sampled Ts = %g s, 4 RK4 substeps: max |theta_sampled - theta_continuous| %.3g rad\n", periods[j],
               diff[j]);
    }
    // The ZOH error of the paper's law is large (8.4e-3 rad at Ts = 10 us; docs/c-core.md) but shrinks with Ts.
    CHECK(diff[2] < diff[1] && diff[1] < diff[0] && diff[2] < 1e-2, "ZOH error shrinks with Ts: %g %g %g", diff[0],
          diff[1], diff[2]);
    // Zero currents: the controller faults and applies 0 V every period; the run goes on and nothing moves.
    x0[0] = 0;
    rc = run_ideal(&s, &plant, x0, 1e-4, 4, 600, &st);
    CHECK(rc == SIM_OK && st.controller_status == SMC_RHO && v_out[2 * 600] == 0 && xs_out[4 * 600 + 3] == 0,
          "x0 = 0: rc %d status %u", rc, st.controller_status);
    x0[0] = 0.4;
    CHECK(run_ideal(&s, &plant, x0, 1e-4, 0, 600, &st) == SIM_EARGS, "substeps = 0");
    cancel_flag = 1;  // as another thread would set it: the run stops after the current period
    rc = run_ideal(&s, &plant, x0, 1e-4, 4, 600, &st);
    CHECK(rc == SIM_ECANCELLED && st.t_fail == 0 && st.steps == 0, "cancelled sampled run: rc %d", rc);
    cancel_flag = 0;
    CHECK(run_ideal(&s, &plant, x0, -1e-4, 4, 600, &st) == SIM_EARGS, "Ts < 0");
    // a finite x0 whose start voltage R x0 overflows (fuzz/regressions/sampled/start-voltage-overflow)
    x0[0] = 1.7e308;
    CHECK(run_ideal(&s, &plant, x0, 1e-4, 4, 0, &st) == SIM_EARGS, "R x0 overflows");
    x0[0] = 0.4;
    plant.effects.detent_torque = -1;
    CHECK(run_ideal(&s, &plant, x0, 1e-4, 4, 600, &st) == SIM_EARGS, "negative detent torque");
    plant.effects.detent_torque = 0;
    // A plant that blows up (huge period, unstable ZOH loop) stops with SIM_ENONFINITE, never NaN silently.
    plant.load = 1e3;
    rc = run_ideal(&s, &plant, x0, 1e-2, 1, 600, &st);
    printf("  unstable loop: rc %d, t_fail %g, status %u\n", rc, st.t_fail, st.controller_status);
    CHECK(rc == SIM_ENONFINITE, "unstable loop: rc %d", rc);
    return 0;
}

// Returns 0 after running the run-loop checks.
int test_sim(void)
{
    continuous_checks();
    sampled_checks();
    return 0;
}
