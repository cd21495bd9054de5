// The drive's parts: encoder and ADC readings, the delay ring, the observer, bus saturation, computation
// delay and PWM segments, and the sampled loop with ideal parts, a detent, switched PWM, and on a realistic
// 20 kHz drive.
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
    struct sensors_params p = {2 * PI / 16384, 0, 4.0 / 4096, 2.0, {0, 0}, 0, false};
    return p;
}

// Returns 0 after the encoder, ADC and delay-ring checks.
static int sensors_checks(void)
{
    struct sensors_params p = drive_sensors();
    struct sensors s;
    double q = p.angle_step, x[4] = {0, 0, 0, 0}, zero[2] = {0, 0}, noise[2] = {0.01, -0.3}, i[2],
           r[SENSORS_READING_LEN], edge[2];
    int k, delay;
    // the centre of the count, within half a count; exact without an encoder
    CHECK(sensors_angle(&p, 0.02) == q * 52 && fabs(sensors_angle(&p, 0.02) - 0.02) <= q / 2, "0.02 rad -> count 52");
    CHECK(sensors_angle(&p, -0.6 * q) == -q, "-0.6 count -> -1");
    // count edges moved by half a count; an exact tie rounds half to even, as NumPy's round
    p.encoder_offset = -0.5;
    CHECK(sensors_angle(&p, 0.0) == -0.5 * q && sensors_angle(&p, q) == 1.5 * q, "offset -0.5: ties to even");
    p.angle_step = 0;
    CHECK(sensors_angle(&p, 0.1234) == 0.1234, "exact angle");
    // steps so fine that theta / q overflows (fuzz/regressions/sampled/denormal-angle-step): the angle itself
    p.angle_step = 4.9406564584124654e-324, p.current_step = 1e-310;
    CHECK(sensors_angle(&p, 1.4839070901462678e-07) == 1.4839070901462678e-07, "denormal encoder step");
    x[0] = 0.4, x[1] = -3.0;
    sensors_currents(&p, x, zero, i);
    CHECK(i[0] == 0.4 && i[1] == -2.0, "denormal ADC step: %g %g", i[0], i[1]);
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
    CHECK(r[3] == 0 && r[4] == -1, "no edge timing: no edge (%g, %g)", r[3], r[4]);
    // edge timing: the edge behind the motion, its age from the speed; none at rest
    p = drive_sensors();
    p.edge_timing = true;
    sensors_edge(&p, 10.3 * q, 2.0, edge);
    CHECK(edge[0] == 10 * q - 0.5 * q && edge[1] == (10.3 * q - edge[0]) / 2.0, "edge forward: %.17g %.17g", edge[0],
          edge[1]);
    sensors_edge(&p, 10.3 * q, -2.0, edge);
    CHECK(edge[0] == 10 * q + 0.5 * q && edge[1] == (10.3 * q - edge[0]) / -2.0 && edge[1] > 0, "edge backward");
    sensors_edge(&p, 10.3 * q, 0.0, edge);
    CHECK(edge[0] == 0 && edge[1] == -1, "no edge at rest");
    CHECK(sensors_init(&s, &p) == 0, "edge timing accepted");
    x[2] = 2.0, x[3] = 10.3 * q;
    sensors_step(&s, x, zero, r);
    CHECK(r[3] == 10 * q - 0.5 * q && r[4] == (10.3 * q - r[3]) / 2.0, "the reading carries the edge");
    x[2] = 0;
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
    struct observer_params p = {2, {{1, 1e-3}, {0, 1}}, {0, 0}, {1, 1000}, {0, 0}};  // double integrator, deadbeat
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
    // the torque ramp: Bf times the torque's change since the last prediction (none on the first)
    p.Bf[0] = 0.01, p.Bf[1] = 0.1, p.Bf[2] = 0;
    observer_init(&o, &p);
    observer_correct(&o, 1.0);
    observer_predict(&o, 10);
    CHECK(o.x[0] == 1 + 1 && o.x[1] == 2, "first prediction holds the torque: %g %g", o.x[0], o.x[1]);
    observer_predict(&o, 14);
    CHECK(o.x[0] == 2 + 1e-3 * 2 + 0.1 * 14 + 0.01 * 4 && o.x[1] == 2 + 0.2 * 14 + 0.1 * 4, "ramp: %.17g %.17g", o.x[0],
          o.x[1]);
    // an edge 2 ms old: the innovation is against the estimate then, x0 - x1 age
    p.Bf[0] = p.Bf[1] = 0;
    observer_init(&o, &p);
    observer_correct_edge(&o, 0.25, 1e-3);
    CHECK(o.x[0] == 0.25 && o.x[1] == 0 && o.started, "first edge correction starts at rest at the edge");
    o.x[1] = 100;
    observer_correct_edge(&o, 0.1, 2e-3);
    CHECK(o.x[0] == 0.25 + (0.1 - (0.25 - 100 * 2e-3)) && o.x[1] == 100 + 1000 * (0.1 - (0.25 - 100 * 2e-3)),
          "edge correction: %.17g %.17g", o.x[0], o.x[1]);
    p.order = 2;
    observer_init(&o, &p);
    CHECK(observer_load(&o) == 0, "no load state: zero load");
    p.order = 5;
    CHECK(observer_init(&o, &p) == -1, "order 5 refused");
    p.order = 2;
    p.Lc[1] = NAN;
    CHECK(observer_init(&o, &p) == -1, "non-finite gain refused");
    p.Lc[1] = 1000;
    p.Bf[0] = INFINITY;
    CHECK(observer_init(&o, &p) == -1, "non-finite ramp refused");
    return 0;
}

// Returns 0 after the bus-saturation and computation-delay checks.
static int drive_checks(void)
{
    struct drive_params p = {24.0, false, DRIVE_AVERAGED, 0, 0};
    struct drive d;
    double start[2] = {3.36, 0}, v[2] = {30, -12}, inside[2] = {-23.9, 1e-3}, out[2];
    CHECK(drive_init(&d, &p, start) == 0, "drive accepted");
    drive_saturate(&p, v, out);
    CHECK(out[0] == 24 && fabs(out[1] + 9.6) < 1e-15 && out[0] * v[1] == out[1] * v[0], "direction kept: %g %g", out[0],
          out[1]);
    drive_saturate(&p, inside, out);
    CHECK(out[0] == inside[0] && out[1] == inside[1], "inside the bus: unchanged");
    p.v_bus = INFINITY;
    drive_saturate(&p, v, out);
    CHECK(out[0] == 30 && out[1] == -12, "no bus: unchanged");
    // a bus so small that peak / v_bus overflows (fuzz/regressions/sampled/denormal-v-bus): still scaled onto it
    p.v_bus = 3.4e-313;
    drive_saturate(&p, v, out);
    CHECK(out[0] == p.v_bus && fabs(out[1] + 0.4 * p.v_bus) <= 5e-324, "tiny bus: %g %g", out[0], out[1]);
    p.v_bus = 1e-3, v[0] = -1e308;
    drive_saturate(&p, v, out);
    CHECK(out[0] == -1e-3 && out[1] < 0 && out[1] == -12 / 1e308 * 1e-3, "huge command: %g %g", out[0], out[1]);
    v[0] = 30;
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

// Returns the mean phase voltages over one PWM period's m segments (into avg) and checks their durations sum
// to Tp and every level is -v_bus, +v_bus or the freewheeling level of the current i.
static int pwm_mean(const struct drive_params *p, const double v[2], const double i[2], double Tp, double avg[2])
{
    double dur[DRIVE_PWM_SEGMENTS], lv[DRIVE_PWM_SEGMENTS][2], sum = 0, free;
    size_t m = drive_pwm_period(p, v, i, Tp, dur, lv), j;
    int ph, ok = m >= 1 && m <= DRIVE_PWM_SEGMENTS;
    avg[0] = avg[1] = 0;
    for (j = 0; j < m; j++) {
        ok &= dur[j] > 0;
        sum += dur[j];
        for (ph = 0; ph < 2; ph++) {
            free = i[ph] > 0 ? -p->v_bus : (i[ph] < 0 ? p->v_bus : 0);
            ok &= lv[j][ph] == -p->v_bus || lv[j][ph] == p->v_bus || (p->dead_time > 0 && lv[j][ph] == free);
            avg[ph] += dur[j] * lv[j][ph];
        }
    }
    avg[0] /= sum, avg[1] /= sum;
    CHECK(ok && fabs(sum - Tp) <= 1e-20,
          "v (%g, %g), i (%g, %g): %zu segments summing to Tp %+.3g s, levels in {-v_bus, +v_bus, free}", v[0], v[1],
          i[0], i[1], m, sum - Tp);
    return 0;
}

// Returns 0 after the PWM checks: periods per control period, segments, duty and dead time, validation.
static int pwm_checks(void)
{
    struct drive_params p = {24.0, false, DRIVE_SWITCHED, 40e3, 0};
    struct drive d;
    const double v[][2] = {{3, -2}, {20, 23.9}, {-24, 0}, {24, -24}, {0, 0}, {30, -12}, {-0.01, 11.5}};
    const double vd[][2] = {{3, -2}, {0, 0}, {-12, 15}, {10, -20}};
    const double i[][2] = {{0.3, -0.2}, {-0.1, 0}, {0, 0.4}, {1, 1}};
    double Tp = 2.5e-5, td = 0.5e-6, avg[2], sat[2], shift, dur[DRIVE_PWM_SEGMENTS], lv[DRIVE_PWM_SEGMENTS][2];
    double q = 1.0 / 16384;  // a period of 2^-14 s: Ts / (1 / f_pwm) is exact
    size_t a, b, m, j;
    int ph, ok;
    p.f_pwm = 16384;
    CHECK(drive_pwm_periods(&p, 2 * q) == 2 && drive_pwm_periods(&p, 2.5 * q) == 2
              && drive_pwm_periods(&p, 3.5 * q) == 4 && drive_pwm_periods(&p, 0.2 * q) == 1
              && drive_pwm_periods(&p, 2e9 * q) == 0,
          "PWM periods: round half to even, at least 1, at most 1e9");
    p.f_pwm = 40e3;
    CHECK(drive_pwm_periods(&p, 5e-5) == 2, "20 kHz control, 40 kHz PWM: 2 periods");
    // without dead time each phase's mean is its saturated command, whatever the current
    for (a = 0; a < sizeof v / sizeof v[0]; a++)
        for (b = 0; b < sizeof i / sizeof i[0]; b++) {
            pwm_mean(&p, v[a], i[b], Tp, avg);
            drive_saturate(&p, v[a], sat);
            CHECK(fabs(avg[0] - sat[0]) < 1e-12 && fabs(avg[1] - sat[1]) < 1e-12,
                  "duty: mean (%.15g, %.15g), command (%.15g, %.15g)", avg[0], avg[1], sat[0], sat[1]);
        }
    // dead time: 2 td / Tp of the period freewheels at -sign(i) v_bus, shifting the mean against the current
    // (commands whose high and low pulses outlast the dead time)
    p.dead_time = td;
    for (a = 0; a < sizeof vd / sizeof vd[0]; a++)
        for (b = 0; b < sizeof i / sizeof i[0]; b++) {
            pwm_mean(&p, vd[a], i[b], Tp, avg);
            for (ph = 0; ph < 2; ph++) {
                shift = -2 * td / Tp * 24 * (i[b][ph] > 0 ? 1 : (i[b][ph] < 0 ? -1 : 0));
                CHECK(fabs(avg[ph] - (vd[a][ph] + shift)) < 1e-12, "dead time: v %g, i %g: mean %.15g, expected %.15g",
                      vd[a][ph], i[b][ph], avg[ph], vd[a][ph] + shift);
            }
        }
    CHECK(fabs(2 * td / Tp * 24 - 0.96) < 1e-12, "0.5 us at 40 kHz on 24 V: 0.96 V");
    // a high pulse shorter than the dead time vanishes: the phase freewheels from on to off + td
    {
        const double vs[2] = {-23.9, 0}, cur[2] = {0.5, -0.5};  // high for Tp / 480 = 52 ns < td
        m = drive_pwm_period(&p, vs, cur, Tp, dur, lv);
        for (j = 0, ok = 1; j < m; j++)
            ok &= lv[j][0] != 24;
        CHECK(ok && m <= DRIVE_PWM_SEGMENTS, "short pulse: no +v_bus on phase a in %zu segments", m);
    }
    // validation, as flatstep.loop.drive.Drive
    CHECK(drive_init(&d, &p, v[4]) == 0, "switched drive accepted");
    p.dead_time = 0.25 / p.f_pwm;
    CHECK(drive_init(&d, &p, v[4]) == -1, "dead time of a quarter period refused");
    p.dead_time = -1e-9;
    CHECK(drive_init(&d, &p, v[4]) == -1, "negative dead time refused");
    p.dead_time = 0, p.f_pwm = 0;
    CHECK(drive_init(&d, &p, v[4]) == -1, "zero PWM frequency refused");
    p.f_pwm = INFINITY;
    CHECK(drive_init(&d, &p, v[4]) == -1, "infinite PWM frequency refused");
    p.f_pwm = 40e3, p.v_bus = INFINITY;
    CHECK(drive_init(&d, &p, v[4]) == -1, "switched PWM on an unlimited bus refused");
    p.v_bus = 24, p.pwm = 2;
    CHECK(drive_init(&d, &p, v[4]) == -1, "unknown PWM mode refused");
    p.pwm = DRIVE_AVERAGED, p.f_pwm = 0, p.dead_time = -1;
    CHECK(drive_init(&d, &p, v[4]) == 0, "averaged: f_pwm and dead_time unread");
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
    struct sampled_params p = {5e-5,
                               4,
                               false,
                               false,
                               drive_sensors(),
                               {0},
                               {INFINITY, false, DRIVE_AVERAGED, 0, 0},
                               {0, 0, 0, 0, 0, 0},
                               NULL,
                               {0, 0, 0, 0, 0, 0, 0, 0, 0}};
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
    CHECK(rc == SIM_OK && err < count && st.controller_status == SMC_OK,
          "20 kHz drive: move error %.3g counts, status %u", err / count, st.controller_status);
    for (k = 0, same = 1; k <= N_PERIODS; k++)
        same &= fabs(va[2 * k]) <= 24 && fabs(va[2 * k + 1]) <= 24 && status[k] == SMC_OK;
    CHECK(same, "20 kHz drive: every voltage within the bus, no fault");
    printf("  20 kHz drive, 14-bit encoder, speed observer: max |theta - theta*| during the move %.3f counts\n",
           err / count);
    // switched PWM on the same drive: 40 kHz tracks as well; at 4 MHz (200 PWM periods a control period) the
    // plant nears the averaged run (ripple ~ 1 / f_pwm), while the recorded voltages stay the averaged commands
    p.drive.pwm = DRIVE_SWITCHED, p.drive.f_pwm = 40e3, p.drive.dead_time = 0;
    CHECK(sampled_init(&s, &p) == SIM_OK, "switched PWM loop accepted");
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xb, vb, NULL, NULL, &st);
    err = max_error(&c, xb, 400, 800);
    for (k = 0, same = 1; k <= N_PERIODS; k++)
        same &= fabs(vb[2 * k]) <= 24 && fabs(vb[2 * k + 1]) <= 24;
    CHECK(rc == SIM_OK && err < count && same && st.steps >= 2 * 3 * N_PERIODS && st.rhs_evals == 4 * st.steps,
          "40 kHz PWM: move error %.3g counts, %u RK4 steps", err / count, st.steps);
    printf("  the same with 40 kHz switched PWM: %.3f counts, %u RK4 steps (one per PWM segment)\n", err / count,
           st.steps);
    p.drive.f_pwm = 4e6;
    sampled_init(&s, &p);
    rc = sampled_run(&s, &cc, &plant, x0, N_PERIODS, NULL, xb, vb, NULL, NULL, &st);
    for (k = 0, err = 0; k <= N_PERIODS; k++)
        err = fmax(err, fabs(xb[4 * k + 3] - xa[4 * k + 3]));
    CHECK(rc == SIM_OK && err < 1e-2 * count, "4 MHz PWM against the averaged bridge: %.3g counts", err / count);
    printf("  4 MHz switched PWM against the averaged bridge: max |theta difference| %.2e counts\n", err / count);
    p.drive.pwm = DRIVE_AVERAGED;
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
    pwm_checks();
    loop_checks();
    return 0;
}
