// The contract checks of sampled runs, drive saturation, PWM segments and sensor readings.
#include "sampled_check.h"
#include <stdio.h>
#include <stdlib.h>

// Returns true when a and b are the same value (both NaN counts as the same).
static bool same(double a, double b)
{
    return a == b || (isnan(a) && isnan(b));
}

// Returns the PWM periods per control period drive.h documents (sampled_check.h).
uint32_t fz_pwm_periods(const struct drive_params *d, double Ts)
{
    double n = rint(Ts / (1 / d->f_pwm));
    return !(n <= 1e9) ? 0 : (n < 1 ? 1 : (uint32_t)n);
}

// Returns nothing; decodes the start state and the sensor noise (sampled_check.h).
void fz_decode_run(struct fz_reader *r, uint32_t mask, struct fz_run *run)
{
    const struct plan *pl = &run->plan;
    double nominal[4] = {pl->rho1 * cos(run->plant.motor.Nr * pl->theta1),
                         pl->rho1 * sin(run->plant.motor.Nr * pl->theta1), 0, pl->theta1},
           scale, poison;
    uint64_t s;
    size_t k;
    int i;
    for (i = 0; i < 4; i++)
        run->x0[i] = mask & (1u << 17) ? fz_value(r, nominal[i]) : nominal[i];
    run->has_noise = mask & (1u << 18);
    if (!run->has_noise)
        return;
    scale = fz_value(r, 0.01), s = fz_u32(r, 1) | 1, k = fz_byte(r, 0), poison = fz_value(r, 0);
    for (i = 0; i < (int)(2 * (run->n + 1)); i++) {
        s ^= s << 13, s ^= s >> 7, s ^= s << 17;
        run->noise[i] = scale * ((double)(s >> 11) / 4503599627370496.0 - 1);
    }
    run->noise[k % (2 * (run->n + 1))] = poison;
}

// Returns nothing; aborts unless out is v scaled into the bus vb with its direction kept (drive_saturate).
static void check_saturated(const double v[2], const double out[2], double vb, size_t k)
{
    double peak = fmax(fabs(v[0]), fabs(v[1])), tiny = 4.9406564584124654e-324;
    int i;
    if (!(peak > vb)) {
        if (out[0] != v[0] || out[1] != v[1])
            FZ_FAIL("period %zu: a command %g %g within the bus %g was changed to %g %g", k, v[0], v[1], vb, out[0],
                    out[1]);
        return;
    }
    for (i = 0; i < 2; i++)
        if (!(fabs(out[i]) <= vb * (1 + 4 * DBL_EPSILON) + tiny) || fabs(out[i]) > fabs(v[i]) || out[i] * v[i] < 0)
            FZ_FAIL("period %zu: %.17g %.17g saturated to %.17g %.17g by the bus %.17g", k, v[0], v[1], out[0], out[1],
                    vb);
    if (!(fmax(fabs(out[0]), fabs(out[1])) >= vb * (1 - 4 * DBL_EPSILON) - tiny))
        FZ_FAIL("period %zu: %.17g %.17g saturated to %.17g %.17g, below the bus %.17g (direction lost)", k, v[0], v[1],
                out[0], out[1], vb);
}

// Returns nothing; aborts unless the readings of period k are what sensors.h promises for the plant states.
static void check_sensed(const struct sensors_params *sp, const struct fz_run *run, int pass, size_t k, double Ts)
{
    const double *y = &run->y[pass][CTRL_Y_LEN * k], *x = &run->x[pass][4 * (k >= sp->delay ? k - sp->delay : 0)];
    const double *nz = run->has_noise ? &run->noise[2 * (k >= sp->delay ? k - sp->delay : 0)] : NULL;
    double q = sp->angle_step, a;
    int i;
    if (y[CTRL_Y_ACC] != 0 || !same(y[CTRL_Y_OMEGA], k ? (y[CTRL_Y_THETA] - y[CTRL_Y_THETA - CTRL_Y_LEN]) / Ts : 0))
        FZ_FAIL("period %zu: encoder speed %g or acceleration %g is not the backward difference / 0", k,
                y[CTRL_Y_OMEGA], y[CTRL_Y_ACC]);
    if (q == 0 ? y[CTRL_Y_THETA] != x[3]
               : !(fabs(y[CTRL_Y_THETA] - x[3]) <= q * (0.5 + 1e-9) + 8 * DBL_EPSILON * fabs(x[3])))
        FZ_FAIL("period %zu: angle %.17g read as %.17g (step %g, delay %u)", k, x[3], y[CTRL_Y_THETA], q,
                (unsigned)sp->delay);
    for (i = 0; i < 2; i++) {
        a = x[i] + sp->current_offset[i] + (nz ? nz[i] : 0);
        if (sp->current_step == 0
                ? !same(y[i], a)
                : !isnan(a)
                      && (!(fabs(y[i]) <= sp->current_range)
                          || (fabs(a) + sp->current_step <= sp->current_range
                              && !(fabs(y[i] - a) <= sp->current_step * (0.5 + 1e-9) + 8 * DBL_EPSILON * fabs(a)))))
            FZ_FAIL("period %zu: current %.17g (with offset and noise) read as %.17g (step %g, range %g)", k, a, y[i],
                    sp->current_step, sp->current_range);
    }
}

// Returns nothing; aborts unless sensors_edge at the plant state x of period k keeps sensors.h's contract: (0, -1)
// without edge timing, an encoder or motion, else the count edge theta_m -+ q/2 behind the motion, which the rotor
// passed at most one count ago (up to the reading's rounding), and its age (theta - edge) / omega, never NaN.
static void check_edge(const struct sensors_params *sp, const double x[4], size_t k)
{
    double e[2], q = sp->angle_step, passed, tol = q * 1e-9 + 8 * DBL_EPSILON * fabs(x[3]);
    sensors_edge(sp, x[3], x[2], e);
    if (!sp->edge_timing || q == 0 || x[2] == 0) {
        if (e[0] != 0 || e[1] != -1)
            FZ_FAIL("period %zu: an edge %g aged %g without edge timing, an encoder or motion", k, e[0], e[1]);
        return;
    }
    passed = x[2] > 0 ? x[3] - e[0] : e[0] - x[3];
    if (e[0] != sensors_angle(sp, x[3]) - (x[2] > 0 ? 0.5 * q : -0.5 * q) || !same(e[1], (x[3] - e[0]) / x[2])
        || isnan(e[1]) || !(passed >= -tol && passed <= q + tol))
        FZ_FAIL("period %zu: angle %.17g at %.17g rad/s (step %g): edge %.17g aged %.17g, passed %.17g ago", k, x[3],
                x[2], q, e[0], e[1], passed);
}

// Returns nothing; aborts unless the outputs of a finished or stopped run keep sampled.h's contract.
static void check_outputs(const struct sampled_params *p, const struct fz_law *law, const struct fz_run *run, int pass)
{
    const struct sim_stats *st = &run->st[pass];
    const double *x = run->x[pass], *v = run->v[pass], *y = run->y[pass];
    double start[2] = {p->model.R * run->x0[0], p->model.R * run->x0[1]}, t_first = 0;
    uint32_t calls = law->calls, status_or = 0, faults = 0, done, per;
    size_t k;
    int rc = run->rc[pass], m;
    if (calls == 0 || calls > run->n + 1 || calls > FZ_RECORD || (rc == SIM_OK && calls != run->n + 1))
        FZ_FAIL("%u controller calls for %zu periods (status %d)", (unsigned)calls, run->n, rc);
    if (memcmp(x, run->x0, sizeof run->x0) != 0)
        FZ_FAIL("the first state row is not x0");
    for (k = 0; k < calls; k++) {
        for (m = 0; m < 4; m++)
            if (!isfinite(x[4 * k + m]))
                FZ_FAIL("period %zu of %u: non-finite state x[%d] = %g (status %d)", k, (unsigned)calls, m,
                        x[4 * k + m], rc);
        // (SIM_ENONFINITE: the failing period's voltage may be what overflowed, R x0 under the delay)
        if ((rc != SIM_ENONFINITE || k + 1 < calls) && (!isfinite(v[2 * k]) || !isfinite(v[2 * k + 1])))
            FZ_FAIL("period %zu: non-finite applied voltage %g %g", k, v[2 * k], v[2 * k + 1]);
        if (memcmp(&y[CTRL_Y_LEN * k], law->y[k], sizeof law->y[k]) != 0 || run->status[pass][k] != law->status[k])
            FZ_FAIL("period %zu: y_out or status_out is not what the controller saw or returned", k);
        if (law->t[k] != (double)k * p->Ts)
            FZ_FAIL("period %zu: the controller ran at t = %.17g, not k Ts", k, law->t[k]);
        status_or |= law->status[k];
        if ((law->status[k] & CTRL_FAULTS) && faults++ == 0)
            t_first = law->t[k];
        if (p->drive.compute_delay && k == 0) {
            if (v[0] != start[0] || v[1] != start[1])
                FZ_FAIL("with the delay, the first period applies %g %g, not R x0 = %g %g", v[0], v[1], start[0],
                        start[1]);
        } else {
            check_saturated(law->v[p->drive.compute_delay ? k - 1 : k], &v[2 * k], p->drive.v_bus, k);
        }
        if (!p->sensed && !p->observed
            && (memcmp(&y[CTRL_Y_LEN * k], &x[4 * k], 4 * sizeof(double)) != 0
                || !same(y[CTRL_Y_LEN * k + CTRL_Y_ACC], plant_acceleration(&run->plant, &x[4 * k]))
                || !fz_acceleration_ok(&run->plant, &x[4 * k])))
            FZ_FAIL(
                "period %zu: without sensors the controller sees %.17g %.17g %.17g %.17g %.17g, not the plant's state "
                "%.17g %.17g %.17g %.17g and acceleration %.17g",
                k, y[CTRL_Y_LEN * k], y[CTRL_Y_LEN * k + 1], y[CTRL_Y_LEN * k + 2], y[CTRL_Y_LEN * k + 3],
                y[CTRL_Y_LEN * k + 4], x[4 * k], x[4 * k + 1], x[4 * k + 2], x[4 * k + 3],
                plant_acceleration(&run->plant, &x[4 * k]));
        if (p->sensed && !p->observed)
            check_sensed(&p->sensors, run, pass, k, p->Ts);
        if (p->sensed)
            check_edge(&p->sensors, &x[4 * k], k);
        if (p->observed && k == 0
            && (y[CTRL_Y_OMEGA] != 0 || (!p->sensed && y[CTRL_Y_THETA] != x[3])
                || (p->sensed
                    && !(fabs(y[CTRL_Y_THETA] - x[3])
                         <= p->sensors.angle_step * (0.5 + 1e-9) + 8 * DBL_EPSILON * fabs(x[3])))))
            FZ_FAIL("the observer does not start at rest at the first angle read: %g %g", y[CTRL_Y_OMEGA],
                    y[CTRL_Y_THETA]);
    }
    for (k = calls; k <= run->n; k++)
        if (!isnan(x[4 * k]) || !isnan(v[2 * k]) || run->status[pass][k] != 0xFFFFFFFFu)
            FZ_FAIL("period %zu was written, after the run stopped at %u", k, (unsigned)calls);
    if (st->controller_status != status_or || st->fault_periods != faults || st->t_first_fault != t_first)
        FZ_FAIL("sim_stats: status %u faults %u first %g, the controller returned %u %u %g",
                (unsigned)st->controller_status, (unsigned)st->fault_periods, st->t_first_fault, (unsigned)status_or,
                (unsigned)faults, t_first);
    done = rc == SIM_OK ? (uint32_t)run->n : (rc == SIM_ENONFINITE ? calls : calls - 1);
    per = p->drive.pwm == DRIVE_SWITCHED ? fz_pwm_periods(&p->drive, p->Ts) : p->substeps;
    // switched: each of the per PWM periods of a control period takes the same 1 to 9 segments
    if (st->rhs_evals != 4 * st->steps || st->steps < done * per || (per && st->steps % per != 0)
        || st->steps > done * per * (p->drive.pwm == DRIVE_SWITCHED ? DRIVE_PWM_SEGMENTS : 1))
        FZ_FAIL("sim_stats: %u steps %u evaluations for %u periods of %u", (unsigned)st->steps, (unsigned)st->rhs_evals,
                (unsigned)done, (unsigned)per);
}

// Returns nothing; runs the loop twice and aborts unless both runs keep sampled.h's contract and agree (sampled_check.h).
void fz_check_run(struct sampled *loop, const struct sampled_params *p, struct fz_law *law, struct fz_run *run,
                  volatile uint32_t *cancel)
{
    bool bad_args = !(isfinite(run->x0[0]) && isfinite(run->x0[1]) && isfinite(run->x0[2]) && isfinite(run->x0[3]))
                    || !isfinite(p->model.R * run->x0[0]) || !isfinite(p->model.R * run->x0[1])
                    || !fz_plant_ok(&run->plant);
    int pass, rc;
    size_t i;
    for (pass = 0; pass < 2; pass++) {
        for (i = 0; i < 4 * (FZ_MAXN + 1); i++)
            run->x[pass][i] = NAN;
        for (i = 0; i < 2 * (FZ_MAXN + 1); i++)
            run->v[pass][i] = NAN;
        memset(run->status[pass], 0xFF, sizeof run->status[pass]);
        *cancel = 0;
        rc = run->rc[pass] =
            sampled_run(loop, &law->outer, &run->plant, run->x0, run->n, run->has_noise ? run->noise : NULL,
                        run->x[pass], run->v[pass], run->y[pass], run->status[pass], &run->st[pass]);
        if (rc != SIM_OK && rc != SIM_EARGS && rc != SIM_ENONFINITE && rc != SIM_ECANCELLED)
            FZ_FAIL("sampled_run returned %d, not a documented status", rc);
        if ((rc == SIM_EARGS) != bad_args)
            FZ_FAIL("sampled_run returned %d on %s start state and plant", rc, bad_args ? "an invalid" : "a valid");
        if (rc == SIM_EARGS)
            return;
        if (rc == SIM_ENONFINITE && run->st[pass].t_fail != (double)(law->calls - 1) * p->Ts + p->Ts)
            FZ_FAIL("SIM_ENONFINITE at t_fail %.17g after %u periods", run->st[pass].t_fail, (unsigned)law->calls);
        if ((rc == SIM_ECANCELLED) != (law->cancel && law->cancel_at <= run->n && law->calls >= law->cancel_at)
            || (rc == SIM_ECANCELLED && run->st[pass].t_fail != (double)(law->calls - 1) * p->Ts))
            FZ_FAIL("status %d: cancel at call %u of %zu periods, %u calls, t_fail %g", rc, (unsigned)law->cancel_at,
                    run->n, (unsigned)law->calls, run->st[pass].t_fail);
        if (pass == 0)
            check_outputs(p, law, run, 0);
#ifdef FZ_VERBOSE
        if (pass == 0)
            fprintf(stderr, "sampled: law %d status %d, %u periods, controller status %u, %u faulted, theta %g\n",
                    law->kind, rc, (unsigned)law->calls, (unsigned)run->st[0].controller_status,
                    (unsigned)run->st[0].fault_periods, run->x[0][4 * (law->calls - 1) + 3]);
#endif
    }
    if (run->rc[1] != run->rc[0] || memcmp(run->x[1], run->x[0], sizeof run->x[0]) != 0
        || memcmp(run->v[1], run->v[0], sizeof run->v[0]) != 0
        || memcmp(run->y[1], run->y[0], CTRL_Y_LEN * sizeof(double) * law->calls) != 0
        || memcmp(run->status[1], run->status[0], sizeof run->status[0]) != 0
        || memcmp(&run->st[1], &run->st[0], sizeof run->st[0]) != 0)
        FZ_FAIL("a second run from the same start differs: sampled_run's reset is incomplete");
}

// Returns the first period whose controller input the options of p may change (sampled.h): 2 with a torque ramp (the
// first prediction holds its torque), the period after the first reading (taken `delay` periods before) whose edge
// age lies in [0, Ts) with edge timing, with sensors and an observer; else FZ_MAXN + 2 (none).
static size_t first_changed(const struct sampled_params *p, const struct fz_run *run, uint32_t calls)
{
    const struct sensors_params *sp = &p->sensors;
    double e[2];
    size_t k, first = FZ_MAXN + 2;
    uint32_t i;
    for (i = 0; p->observed && i < p->observer.order; i++)
        if (p->observer.Bf[i] != 0)
            first = 2;
    for (k = 1; p->observed && p->sensed && k < calls && k < first; k++) {
        sensors_edge(sp, run->x[0][4 * (k >= sp->delay ? k - sp->delay : 0) + 3],
                     run->x[0][4 * (k >= sp->delay ? k - sp->delay : 0) + 2], e);
        if (e[1] >= 0 && e[1] < p->Ts)
            first = k;
    }
    return first;
}

// Returns nothing; runs the loop without the options and compares it with the run's first pass (sampled_check.h).
void fz_check_options(struct sampled *plain, const struct sampled_params *p, struct fz_law *law, struct fz_run *run,
                      volatile uint32_t *cancel)
{
    uint32_t calls = law->calls;
    size_t first, k, rows;
    int rc;
    if (run->rc[0] == SIM_EARGS)
        return;  // refused before any period: nothing to compare
    first = first_changed(p, run, calls);
    *cancel = 0;
    rc = sampled_run(plain, &law->outer, &run->plant, run->x0, run->n, run->has_noise ? run->noise : NULL, run->x[1],
                     run->v[1], run->y[1], run->status[1], &run->st[1]);
    rows = calls < law->calls ? calls : law->calls;
    rows = rows < first ? rows : first;
    for (k = 0; k < rows; k++)
        if (memcmp(&run->y[1][CTRL_Y_LEN * k], &run->y[0][CTRL_Y_LEN * k], CTRL_Y_LEN * sizeof(double)) != 0
            || memcmp(&run->v[1][2 * k], &run->v[0][2 * k], 2 * sizeof(double)) != 0
            || memcmp(&run->x[1][4 * k], &run->x[0][4 * k], 4 * sizeof(double)) != 0
            || run->status[1][k] != run->status[0][k])
            FZ_FAIL("period %zu: the edge timing or torque ramp changed the loop before period %zu (%u and %u calls)",
                    k, first, (unsigned)calls, (unsigned)law->calls);
    if (first >= calls
        && (rc != run->rc[0] || law->calls != calls || memcmp(&run->st[1], &run->st[0], sizeof run->st[0]) != 0))
        FZ_FAIL("the options never act, yet without them the run differs: status %d, not %d, %u calls, not %u", rc,
                run->rc[0], (unsigned)law->calls, (unsigned)calls);
}

// Returns nothing; aborts unless drive_pwm_period keeps drive.h's contract on a decoded command and currents:
// 1 to 9 segments of positive durations summing to Tp, levels -v_bus, 0 or +v_bus, and the mean voltage the
// saturated command, less the dead time's share (at most 4 v_bus dead_time / Tp).
void fz_check_pwm(struct fz_reader *r, const struct drive_params *d, double Tp)
{
    double v[2], i[2], vs[2], dur[DRIVE_PWM_SEGMENTS], lv[DRIVE_PWM_SEGMENTS][2], sum = 0, mean[2] = {0, 0}, tol;
    size_t m, j;
    int ph;
    v[0] = fz_value(r, 10), v[1] = fz_value(r, -30), i[0] = fz_value(r, 0.3), i[1] = fz_value(r, -0.2);
    if (!(isfinite(v[0]) && isfinite(v[1]) && isfinite(i[0]) && isfinite(i[1])))
        return;  // the loop calls it with finite commands and currents only
    m = drive_pwm_period(d, v, i, Tp, dur, lv);
    drive_saturate(d, v, vs);
    if (m < 1 || m > DRIVE_PWM_SEGMENTS)
        FZ_FAIL("drive_pwm_period: %zu segments", m);
    for (j = 0; j < m; j++) {
        if (!(dur[j] > 0) || !isfinite(dur[j]))
            FZ_FAIL("drive_pwm_period: segment %zu lasts %g", j, dur[j]);
        sum += dur[j];
        for (ph = 0; ph < 2; ph++) {
            if (lv[j][ph] != d->v_bus && lv[j][ph] != -d->v_bus && lv[j][ph] != 0)
                FZ_FAIL("drive_pwm_period: level %g on a bus of %g", lv[j][ph], d->v_bus);
            mean[ph] += lv[j][ph] / d->v_bus * (dur[j] / Tp);  // in units of the bus, as a fraction of Tp
        }
    }
    if (!(fabs(sum - Tp) <= 16 * DBL_EPSILON * Tp))
        FZ_FAIL("drive_pwm_period: segments sum to %.17g, not Tp = %.17g", sum, Tp);
    // rounding: of the offsets (relative, and absolute where Tp is denormal) and of the mean's sum
    tol = 4 * d->dead_time / Tp + 64 * DBL_EPSILON + 64 * 4.9406564584124654e-324 / Tp;
    for (ph = 0; ph < 2; ph++)
        if (!(fabs(mean[ph] - vs[ph] / d->v_bus) <= tol))
            FZ_FAIL("drive_pwm_period: phase %d averages %.17g V for a command of %.17g V (bus %g, dead %g, Tp %g)", ph,
                    mean[ph] * d->v_bus, vs[ph], d->v_bus, d->dead_time, Tp);
}
