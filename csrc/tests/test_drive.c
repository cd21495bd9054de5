// The drive's parts: encoder and ADC readings, the delay ring, the observer, bus saturation and computation
// delay, and the sampled loop with ideal parts, a detent, and on a realistic 20 kHz drive.
#include "check.h"
#include "sampled.h"
#include "smc.h"

#define PI 3.14159265358979323846
#define N_PERIODS 1200  // 60 ms at 20 kHz

static double xa[4 * (N_PERIODS + 1)], va[2 * (N_PERIODS + 1)], xb[4 * (N_PERIODS + 1)], vb[2 * (N_PERIODS + 1)];
static double ya[5 * (N_PERIODS + 1)];
static uint32_t status[N_PERIODS + 1];

// Returns a 14-bit encoder and 12-bit +-2 A ADC without offsets, noise or delay.
static struct sensors_params drive_sensors(void)
{
    struct sensors_params p = {2 * PI / 16384, 0, 4.0 / 4096, 2.0, {0, 0}, 0};
    return p;
}

// Returns 0 after the encoder, ADC and delay-ring checks.
static int sensors_checks(void)
{
    struct sensors_params p = drive_sensors();
    struct sensors s;
    double q = p.angle_step, x[4] = {0, 0, 0, 0}, zero[2] = {0, 0}, noise[2] = {0.01, -0.3}, i[2], r[3];
    int k, delay;
    // the centre of the count, within half a count; exact without an encoder
    CHECK(sensors_angle(&p, 0.02) == q * 52 && fabs(sensors_angle(&p, 0.02) - 0.02) <= q / 2, "0.02 rad -> count 52");
    CHECK(sensors_angle(&p, -0.6 * q) == -q, "-0.6 count -> -1");
    // count edges moved by half a count; an exact tie rounds half to even, as NumPy's round
    p.encoder_offset = -0.5;
    CHECK(sensors_angle(&p, 0.0) == -0.5 * q && sensors_angle(&p, q) == 1.5 * q, "offset -0.5: ties to even");
    p.angle_step = 0;
    CHECK(sensors_angle(&p, 0.1234) == 0.1234, "exact angle");
    // ADC: offset and noise before conversion, clipped to the range
    p = drive_sensors();
    p.current_offset[0] = 0.002;
    x[0] = 0.4, x[1] = 3.0;
    sensors_currents(&p, x, noise, i);
    CHECK(i[0] == 422 * p.current_step && i[1] == 2.0, "ADC: %.17g %.17g", i[0], i[1]);
    x[1] = -3.0;
    sensors_currents(&p, x, zero, i);
    CHECK(i[1] == -2.0, "ADC clips at -range: %g", i[1]);
    p.current_step = 0;
    sensors_currents(&p, x, noise, i);
    CHECK(i[0] == 0.4 + 0.002 + 0.01 && i[1] == -3.3, "exact currents keep offset and noise");
    // the delay ring: reading k - delay, or the first one while fewer were taken
    for (delay = 0; delay <= SENSORS_MAX_DELAY; delay++) {
        p = drive_sensors();
        p.delay = (uint32_t)delay;
        CHECK(sensors_init(&s, &p) == 0, "delay %d accepted", delay);
        for (k = 0; k < 3 * SENSORS_MAX_DELAY; k++) {
            x[3] = k * q;
            sensors_step(&s, x, zero, r);
            CHECK(r[0] == (k > delay ? k - delay : 0) * q, "delay %d, reading %d: got count %g", delay, k, r[0] / q);
        }
    }
    sensors_reset(&s);
    x[3] = 7 * q;
    sensors_step(&s, x, zero, r);
    CHECK(r[0] == 7 * q, "reset forgets the old readings");
    p = drive_sensors();
    p.delay = SENSORS_MAX_DELAY + 1;
    CHECK(sensors_init(&s, &p) == -1, "delay beyond the ring refused");
    p = drive_sensors();
    p.encoder_offset = 0.5;
    CHECK(sensors_init(&s, &p) == -1, "encoder offset 0.5 refused");
    p = drive_sensors();
    p.current_range = 0;
    CHECK(sensors_init(&s, &p) == -1, "zero ADC range refused");
    return 0;
}

// Returns nothing; fills p with the order-2 observer of a motor (J, B) at period Ts, poles at z = exp(-bw Ts)
// (double), Lc placed for the current-estimator form: (I - Lc C) Ad has z^2 - 2 z0 z + z0^2.
static void speed_observer(struct observer_params *p, double J, double B, double Ts, double bw)
{
    double a = B / J, e = exp(-a * Ts), z0 = exp(-bw * Ts), pr = (1 - e) / a;
    p->order = 2;
    p->Ad[0][0] = 1, p->Ad[0][1] = pr, p->Ad[1][0] = 0, p->Ad[1][1] = e;
    p->Bd[0] = (Ts - pr) / (a * J), p->Bd[1] = pr / J;
    // trace (1 - l1) + e - l2 pr = 2 z0, det (1 - l1) e = z0^2
    p->Lc[0] = 1 - z0 * z0 / e;
    p->Lc[1] = ((1 - p->Lc[0]) + e - 2 * z0) / pr;
}

// Returns 0 after the observer checks.
static int observer_checks(void)
{
    struct observer_params p = {2, {{1, 1e-3}, {0, 1}}, {0, 0}, {1, 1000}};  // double integrator, deadbeat
    struct observer o;
    double w = 3.0, Ts = 1e-3;
    int k;
    CHECK(observer_init(&o, &p) == 0, "order 2 accepted");
    observer_correct(&o, 0.5);
    CHECK(o.x[0] == 0.5 && o.x[1] == 0 && o.started, "first correction starts at rest at the angle");
    for (k = 1; k <= 3; k++) {
        observer_predict(&o, 0);
        observer_correct(&o, 0.5 + w * k * Ts);
    }
    CHECK(fabs(o.x[1] - w) < 1e-12 && fabs(o.x[0] - (0.5 + 3 * w * Ts)) < 1e-15, "deadbeat: speed %.17g", o.x[1]);
    // x <- x + Lc (theta_m - x0), then x <- Ad x + Bd Te, by hand
    p.order = 3;
    p.Ad[0][2] = 0.25, p.Ad[1][2] = -0.5, p.Ad[2][0] = 0, p.Ad[2][1] = 0, p.Ad[2][2] = 1;
    p.Bd[0] = 0.1, p.Bd[1] = 0.2, p.Bd[2] = 0;
    p.Lc[2] = -4;
    observer_init(&o, &p);
    observer_correct(&o, 1.0);
    observer_correct(&o, 1.5);
    CHECK(o.x[0] == 1.5 && o.x[1] == 500 && o.x[2] == -2 && observer_load(&o) == -2, "correction");
    observer_predict(&o, 10);
    CHECK(o.x[0] == 1.5 + 0.5 - 0.5 + 1 && o.x[1] == 500 + 1 + 2 && o.x[2] == -2, "prediction: %g %g %g", o.x[0],
          o.x[1], o.x[2]);
    p.order = 2;
    observer_init(&o, &p);
    CHECK(observer_load(&o) == 0, "no load state: zero load");
    p.order = 5;
    CHECK(observer_init(&o, &p) == -1, "order 5 refused");
    p.order = 2;
    p.Lc[1] = NAN;
    CHECK(observer_init(&o, &p) == -1, "non-finite gain refused");
    return 0;
}

// Returns 0 after the bus-saturation and computation-delay checks.
static int drive_checks(void)
{
    struct drive_params p = {24.0, false};
    struct drive d;
    double start[2] = {3.36, 0}, v[2] = {30, -12}, inside[2] = {-23.9, 1e-3}, out[2];
    CHECK(drive_init(&d, &p, start) == 0, "drive accepted");
    drive_saturate(&p, v, out);
    CHECK(out[0] == 24 && fabs(out[1] + 9.6) < 1e-15 && out[0] * v[1] == out[1] * v[0], "direction kept: %g %g",
          out[0], out[1]);
    drive_saturate(&p, inside, out);
    CHECK(out[0] == inside[0] && out[1] == inside[1], "inside the bus: unchanged");
    p.v_bus = INFINITY;
    drive_saturate(&p, v, out);
    CHECK(out[0] == 30 && out[1] == -12, "no bus: unchanged");
    p.v_bus = 24.0;
    p.compute_delay = true;
    drive_init(&d, &p, start);
    drive_step(&d, v, out);
    CHECK(out[0] == 3.36 && out[1] == 0, "delay: the start voltage first");
    drive_step(&d, inside, out);
    CHECK(out[0] == 24 && fabs(out[1] + 9.6) < 1e-15, "delay: then the previous command, saturated");
    p.compute_delay = false;
    drive_init(&d, &p, start);
    drive_step(&d, inside, out);
    CHECK(out[0] == inside[0], "no delay: the command now");
    p.v_bus = 0;
    CHECK(drive_init(&d, &p, start) == -1, "zero bus refused");
    return 0;
}

// Returns nothing; the paper's motor and move with the 20 kHz designed gains (model or ideal measurement).
static void designed(struct smc *s, struct plant *plant, int measurement, double x0[4])
{
    struct smc_params p;
    smc_params_default(&p);
    p.gains.W1 = 150, p.gains.W2 = 3e5, p.gains.eps1 = 0.025, p.gains.eps2 = 50, p.gains.xi = 0.9;
    p.gains.wn = 1500;
    p.measurement = measurement;
    smc_init(s, &p);
    plant->motor = p.motor;
    plant->load = 1e-5;
    plant->effects = (struct plant_effects){0, 0, 0, 0, 0};
    x0[0] = 0.4, x0[1] = 0, x0[2] = 0, x0[3] = 0;
}

// Returns the largest |theta - theta*| over periods [k0, k1] of a run at 20 kHz.
static double max_error(const struct smc *s, const double *x, int k0, int k1)
{
    double f[PLAN_FLAG_LEN], worst = 0;
    int k;
    for (k = k0; k <= k1; k++) {
        plan_eval(&s->p.plan, k * 5e-5, f);
        worst = fmax(worst, fabs(x[4 * k + 3] - f[PLAN_THETA]));
    }
    return worst;
}

// Returns 0 after the sampled-loop checks.
static int loop_checks(void)
{
    struct sampled_params p = {5e-5, 4, false, false, drive_sensors(), {0}, {INFINITY, false}, {0, 0, 0, 0, 0, 0}};
    struct plant plant;
    struct sim_stats st;
    struct sampled s;
    struct smc c;
    struct controller cc;
    double x0[4], count = 2 * PI / 16384, err, acc;
    int rc, k, same = 1;
    // ideal parts: the controller sees the plant's state and its true acceleration, effects included
    designed(&c, &plant, SMC_IDEAL, x0);
    smc_controller(&c, &cc);
    p.model = c.p.motor;
    CHECK(sampled_init(&s, &p) == SIM_OK, "ideal loop accepted");
    plant.effects.detent_torque = 1e-3, plant.effects.detent_harmonic = 4;
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xa, va, ya, status, &st);
    acc = plant_acceleration(&plant, &xa[4 * 7]);
    CHECK(rc == SIM_OK && st.rhs_evals == 4 * 4 * N_PERIODS, "ideal parts: rc %d", rc);
    CHECK(ya[5 * 7 + 3] == xa[4 * 7 + 3] && ya[5 * 7 + 2] == xa[4 * 7 + 2] && ya[5 * 7 + 4] == acc
          && acc != motor_acceleration(&plant.motor, &xa[4 * 7], plant.load),
          "ideal parts: the controller sees x and the acceleration with the detent");
    plant.effects.detent_torque = 0;
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xb, vb, NULL, NULL, &st);
    for (k = 0, same = 0; k < 4 * (N_PERIODS + 1); k++)
        same |= xa[k] != xb[k];
    CHECK(rc == SIM_OK && same, "the detent changes the run");
    // the realistic drive: 14-bit encoder, 12-bit ADC, speed observer at 1500 rad/s, 24 V bus
    p.sensed = p.observed = true;
    p.drive.v_bus = 24;
    speed_observer(&p.observer, c.p.motor.J, c.p.motor.B, p.Ts, 1500);
    CHECK(sampled_init(&s, &p) == SIM_OK, "drive loop accepted");
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xa, va, ya, status, &st);
    err = max_error(&c, xa, 400, 800);
    CHECK(rc == SIM_OK && err < count && st.controller_status == SMC_OK, "20 kHz drive: move error %.3g counts, status %u",
          err / count, st.controller_status);
    for (k = 0, same = 1; k <= N_PERIODS; k++)
        same &= fabs(va[2 * k]) <= 24 && fabs(va[2 * k + 1]) <= 24 && status[k] == SMC_OK;
    CHECK(same, "20 kHz drive: every voltage within the bus, no fault");
    printf("  20 kHz drive, 14-bit encoder, speed observer: max |theta - theta*| during the move %.3f counts\n",
           err / count);
    // encoder-difference speed and the controller's model acceleration, with a delay and a compute delay
    designed(&c, &plant, SMC_MODEL, x0);
    smc_controller(&c, &cc);
    p.observed = false;
    p.sensors.delay = 1;
    p.drive.compute_delay = true;
    sampled_init(&s, &p);
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xa, va, ya, status, &st);
    CHECK(rc == SIM_OK && ya[5 * 0 + 2] == 0 && ya[5 * 500 + 2] == (ya[5 * 500 + 3] - ya[5 * 499 + 3]) / 5e-5,
          "backward difference of the encoder");
    CHECK(va[0] == c.p.motor.R * 0.4 && va[1] == 0, "compute delay: the start equilibrium first");
    // bad parts and a diverging plant
    p.sensors.delay = SENSORS_MAX_DELAY + 1;
    CHECK(sampled_init(&s, &p) == SIM_EARGS, "delay beyond the ring refused");
    p.sensors.delay = 0;
    p.Ts = 0;
    CHECK(sampled_init(&s, &p) == SIM_EARGS, "zero period refused");
    p.Ts = 5e-5;
    p.model.J = 0;
    CHECK(sampled_init(&s, &p) == SIM_EARGS, "invalid model refused");
    p.model = c.p.motor;
    p.Ts = 5e-5;
    sampled_init(&s, &p);
    plant.load = 1e308;  // theta'' = -load / J overflows
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xa, va, NULL, NULL, &st);
    CHECK(rc == SIM_ENONFINITE && st.t_fail > 0, "a non-finite plant stops the run: rc %d", rc);
    return 0;
}

// Returns 0 after every check of the drive's parts and loop.
int test_drive(void)
{
    sensors_checks();
    observer_checks();
    drive_checks();
    loop_checks();
    return 0;
}
