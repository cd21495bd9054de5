// sampled_run: one period at a time in the order and arithmetic of flatstep.loop.reference.run_reference.
#include "sampled.h"
#include "ode.h"

// What the plant's right-hand side needs over a period: the plant and the held voltage.
struct held {
    const struct plant *plant;
    fs_real v[2];
};

// Returns 0; the plant under the voltage held over the period.
static int held_rhs(void *ctx, fs_real t, const fs_real *x, fs_real *dx)
{
    const struct held *h = ctx;
    (void)t;
    plant_rhs(h->plant, x, h->v, dx);
    return 0;
}

// Returns true when all four state components are finite.
static bool finite4(const fs_real x[4])
{
    return fs_isfinite(x[0]) && fs_isfinite(x[1]) && fs_isfinite(x[2]) && fs_isfinite(x[3]);
}

// Returns SIM_OK, or SIM_EARGS when a part's parameters are invalid (s is then left unusable).
int sampled_init(struct sampled *s, const struct sampled_params *p)
{
    const fs_real zero[2] = {0, 0};
    if (!(p->Ts > 0) || !fs_isfinite(p->Ts) || p->substeps < 1 || !motor_params_valid(&p->model)
        || !torque_model_valid(&p->torques))
        return SIM_EARGS;
    if (p->sensed && sensors_init(&s->sensors, &p->sensors) != 0)
        return SIM_EARGS;
    if (p->observed && observer_init(&s->observer, &p->observer) != 0)
        return SIM_EARGS;
    if (drive_init(&s->drive, &p->drive, zero) != 0)
        return SIM_EARGS;
    s->pwm_periods = p->drive.pwm == DRIVE_SWITCHED ? drive_pwm_periods(&p->drive, p->Ts) : 0;
    if (p->drive.pwm == DRIVE_SWITCHED && s->pwm_periods == 0)
        return SIM_EARGS;
    s->Ts = p->Ts;
    s->substeps = p->substeps;
    s->sensed = p->sensed;
    s->observed = p->observed;
    s->model = p->model;
    s->torques = p->torques;
    s->have_prev = false;
    s->theta_prev = 0;
    s->cancel = p->cancel;
    return SIM_OK;
}

// Returns nothing; writes what the controller sees at state x and time t, y = (ia, ib, omega, theta, theta''),
// and the torque of the measured currents at the estimated angle less the known torques (for the observer).
static void measure(struct sampled *s, const struct plant *plant, fs_real t, const fs_real x[4], const fs_real noise[2],
                    fs_real y[5], fs_real *torque)
{
    fs_real r[SENSORS_READING_LEN] = {x[3], x[0], x[1], 0, -1}, z[4];  // (theta_m, ia_m, ib_m, edge, age)
    if (s->sensed)
        sensors_step(&s->sensors, x, noise, r);
    y[0] = r[1];
    y[1] = r[2];
    if (s->observed) {
        if (s->observer.started && r[4] >= 0 && r[4] < s->Ts)  // an edge within the period: its angle, age ago
            observer_correct_edge(&s->observer, r[3], r[4]);
        else
            observer_correct(&s->observer, r[0]);
        z[0] = r[1], z[1] = r[2], z[2] = 0, z[3] = s->observer.x[0];
        *torque = motor_torque(&s->model, z)
                  - torque_model_torque(&s->torques, s->model.Nr, t, s->observer.x[0], s->observer.x[1]);
        y[2] = s->observer.x[1];
        y[3] = s->observer.x[0];
        y[4] = (*torque - s->model.B * s->observer.x[1] - observer_load(&s->observer)) / s->model.J;
    } else if (!s->sensed) {
        y[2] = x[2];
        y[3] = x[3];
        y[4] = plant_acceleration(plant, x);
    } else {
        y[2] = s->have_prev ? (r[0] - s->theta_prev) / s->Ts : 0;
        y[3] = r[0];
        y[4] = 0;
    }
    s->theta_prev = r[0];
    s->have_prev = true;
}

// Returns nothing; integrates the plant state x over one period from t under the applied voltage v: RK4
// substeps, or with switched PWM one RK4 step per segment of each PWM period (currents at t, as the reference).
static void integrate(struct sampled *s, struct held *c, const fs_real v[2], fs_real t, fs_real x[4],
                      struct sim_stats *st)
{
    fs_real dur[DRIVE_PWM_SEGMENTS], lv[DRIVE_PWM_SEGMENTS][2], h = s->Ts / (fs_real)s->substeps;
    size_t m, j;
    uint32_t k;
    if (s->drive.p.pwm != DRIVE_SWITCHED) {
        c->v[0] = v[0], c->v[1] = v[1];
        for (k = 0; k < s->substeps; k++)
            ode_rk4_step(held_rhs, c, 4, t + (fs_real)k * h, h, x);
        st->steps += s->substeps;
        st->rhs_evals += 4 * s->substeps;
        return;
    }
    m = drive_pwm_period(&s->drive.p, v, x, s->Ts / (fs_real)s->pwm_periods, dur, lv);
    for (k = 0; k < s->pwm_periods; k++)
        for (j = 0; j < m; j++) {
            c->v[0] = lv[j][0], c->v[1] = lv[j][1];
            ode_rk4_step(held_rhs, c, 4, t, dur[j], x);
            t += dur[j];
        }
    st->steps += s->pwm_periods * (uint32_t)m;
    st->rhs_evals += 4 * s->pwm_periods * (uint32_t)m;
}

// Returns SIM_OK or an error sim_status; resets the parts and the controller and runs n_periods periods from
// x0 at t_k = k Ts (sampled.h).
int sampled_run(struct sampled *s, const struct controller *ctrl, const struct plant *plant, const fs_real *x0,
                size_t n_periods, const fs_real *noise, fs_real *x_out, fs_real *v_out, fs_real *y_out,
                uint32_t *status_out, struct sim_stats *st)
{
    const fs_real quiet[2] = {0, 0};
    struct held c;
    fs_real x[4], y[CTRL_Y_LEN], v[2], v_apply[2], t, torque = 0;
    fs_real v_start[2] = {s->model.R * x0[0], s->model.R * x0[1]};  // the start equilibrium, until a command
    uint32_t status;
    size_t k;
    int m;
    st->steps = st->rejected = st->rhs_evals = st->fault_periods = 0;
    st->controller_status = CTRL_OK;
    st->t_fail = st->t_first_fault = 0;
    if (!finite4(x0) || !fs_isfinite(v_start[0]) || !fs_isfinite(v_start[1]) || !plant_valid(plant))
        return SIM_EARGS;
    if (s->sensed)
        sensors_reset(&s->sensors);
    if (s->observed)
        observer_reset(&s->observer);
    drive_reset(&s->drive, v_start);
    ctrl->reset(ctrl->self);
    s->have_prev = false;
    c.plant = plant;
    for (m = 0; m < 4; m++)
        x[m] = x0[m];
    for (k = 0;; k++) {
        t = (fs_real)k * s->Ts;
        for (m = 0; m < 4; m++)
            x_out[4 * k + m] = x[m];
        measure(s, plant, t, x, noise ? &noise[2 * k] : quiet, y, &torque);
        status = ctrl->step(ctrl->self, t, y, v);  // 0 V on a fault: the drive de-energises for this period
        st->controller_status |= status;
        if (status & CTRL_FAULTS && st->fault_periods++ == 0)
            st->t_first_fault = t;
        drive_step(&s->drive, v, v_apply);
        v_out[2 * k] = v_apply[0];  // the averaged command, also under switched PWM
        v_out[2 * k + 1] = v_apply[1];
        if (y_out)
            for (m = 0; m < CTRL_Y_LEN; m++)
                y_out[CTRL_Y_LEN * k + m] = y[m];
        if (status_out)
            status_out[k] = status;
        if (k == n_periods)
            break;
        if (s->cancel && *s->cancel) {
            st->t_fail = t;
            return SIM_ECANCELLED;
        }
        integrate(s, &c, v_apply, t, x, st);
        if (!finite4(x)) {
            st->t_fail = t + s->Ts;
            return SIM_ENONFINITE;
        }
        if (s->observed)
            observer_predict(&s->observer, torque);
    }
    return SIM_OK;
}
