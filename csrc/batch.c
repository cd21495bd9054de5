// batch_sampled: many sampled scenarios through sampled_run, each summarised in one pass over its samples.
#include "batch.h"

// Returns the larger of a and |b|.
static fs_real max_abs(fs_real a, fs_real b)
{
    b = fs_fabs(b);
    return b > a ? b : a;
}

// Returns full_step, or half the last move through rest[0..n-1] if smaller (the rule in batch.h).
fs_real batch_arrival_error(fs_real full_step, const fs_real *rest, size_t n)
{
    fs_real big = 1, tol, half = 0;
    size_t k;
    for (k = 0; k < n; k++)
        big = max_abs(big, rest[k]);
    tol = (fs_real)BATCH_REST_TOLERANCE * big;
    for (k = n; k-- > 1;) {  // back from rest[n - 2] to the latest rest away from the end
        if (fs_fabs(rest[n - 1] - rest[k - 1]) > tol) {
            half = (fs_real)0.5 * fs_fabs(rest[n - 1] - rest[k - 1]);
            break;
        }
    }
    return half > 0 && half < full_step ? half : full_step;
}

// Returns nothing; writes the summary of a successful run from its states x and applied voltages v at the
// n + 1 instants k Ts against the plan, and whether and when the move was lost: |theta - theta*| first beyond
// the run's lost_error, or else beyond batch_arrival_error from some t_k to the end (lost at that t_k).
static void summarize(const struct plan_coef *plan, fs_real Ts, size_t n, const fs_real *x, const fs_real *v,
                      const struct batch_run *run, struct batch_summary *o)
{
    fs_real flag[PLAN_FLAG_LEN], t, err, away = -1;  // away: start of the excursion beyond arrival_error, or -1
    const fs_real rest[2] = {plan->p.theta1, plan->p.theta2};
    const fs_real arrival_error = batch_arrival_error(run->lost_error, rest, 2);
    size_t k;
    o->max_abs_theta_error = o->max_abs_rho_error = o->max_abs_va = o->max_abs_vb = 0;
    o->max_abs_theta_error_move = o->max_abs_theta_error_after = 0;
    o->n_move = o->n_after = 0;
    o->lost = false;
    o->lost_at = 0;
    for (k = 0; k <= n; k++) {
        t = (fs_real)k * Ts;
        plan_flag(plan, t, flag);
        err = x[4 * k + 3] - flag[PLAN_THETA];
        o->max_abs_theta_error = max_abs(o->max_abs_theta_error, err);
        if (!o->lost && fs_fabs(err) > run->lost_error) {
            o->lost = true;
            o->lost_at = t;
        }
        if (!(fs_fabs(err) > arrival_error))
            away = -1;
        else if (away < 0)
            away = t;
        o->max_abs_rho_error = max_abs(o->max_abs_rho_error, fs_hypot(x[4 * k], x[4 * k + 1]) - flag[PLAN_RHO]);
        o->max_abs_va = max_abs(o->max_abs_va, v[2 * k]);
        o->max_abs_vb = max_abs(o->max_abs_vb, v[2 * k + 1]);
        if (t >= plan->p.t0 && t <= plan->p.tf) {
            o->max_abs_theta_error_move = max_abs(o->max_abs_theta_error_move, err);
            o->n_move++;
        } else if (t > plan->p.tf) {
            o->max_abs_theta_error_after = max_abs(o->max_abs_theta_error_after, err);
            o->n_after++;
        }
        if (k == n)
            o->final_theta_error = err;
    }
    if (!o->lost && away >= 0) {  // it ends beyond arrival_error: lost from the start of that excursion
        o->lost = true;
        o->lost_at = away;
    }
    o->ia_final = x[4 * n];
    o->ib_final = x[4 * n + 1];
    o->omega_final = x[4 * n + 2];
    o->theta_final = x[4 * n + 3];
}

// Returns the number of runs whose status is not SIM_OK; runs the n scenarios one after another on sampled_run,
// using scratch (at least 6 (n_periods + 1) values for the longest run) for each run's states and voltages,
// and writes each run's summary into out[i].
size_t batch_sampled(const struct batch_run *runs, size_t n, fs_real *scratch, size_t scratch_len,
                     struct batch_summary *out)
{
    struct sampled loop;
    struct plan_coef plan;
    struct sim_stats st;
    size_t i, failed = 0, m;
    for (i = 0; i < n; i++) {
        m = runs[i].n_periods + 1;
        out[i].controller_status = 0;
        if (scratch_len < 6 || runs[i].n_periods > scratch_len / 6 - 1 || !plan_init(&plan, &runs[i].reference)
            || !(runs[i].lost_error > 0) || sampled_init(&loop, &runs[i].loop) != SIM_OK)
            out[i].status = SIM_EARGS;  // the scratch cannot hold this run, or its plan or loop is invalid
        else {
            out[i].status = sampled_run(&loop, &runs[i].ctrl, &runs[i].plant, runs[i].x0, runs[i].n_periods,
                                        runs[i].noise, scratch, scratch + 4 * m, NULL, NULL, &st);
            out[i].controller_status = st.controller_status;
            out[i].fault_periods = st.fault_periods;
            out[i].t_first_fault = st.t_first_fault;
            if (out[i].status == SIM_OK)
                summarize(&plan, runs[i].loop.Ts, runs[i].n_periods, scratch, scratch + 4 * m, &runs[i], &out[i]);
        }
        failed += out[i].status != SIM_OK;
    }
    return failed;
}
