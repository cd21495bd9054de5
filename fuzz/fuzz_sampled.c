// libFuzzer harness for sampled_init/sampled_run: the whole sampled loop (sensors, observer, every controller,
// the drive with switched PWM and dead time, the plant with its effects) either refuses its parameters with a
// documented status or runs to finite outputs, and keeps the contracts of sampled.h, drive.h and sensors.h.
//
// Input: a header byte (law, its options), a 32-bit mask of the groups decoded hostile (the others take the
// nominal: the paper's motor and move at Ts = 200 us), then the groups' values (fuzz/decode.h), and last an options
// byte (0 when exhausted, so shorter inputs run without the options): 1 the encoder's edge timing, 2 the observer's
// torque ramp (flatstep's Bf for the nominal observer), 4 Bf decoded around that (4 values after the byte).
// Each input runs at most FZ_WORK RK4 steps, twice (the second run must repeat the first bit for bit); with an
// option on, a third run without the options must agree with it up to the first period the options may change.
#include <stdio.h>
#include <stdlib.h>
#include "laws.h"
#include "sampled.h"
#include "sampled_check.h"

// Returns nothing; decodes the sensors (hostile, or a 4000-count encoder and a 12-bit +-2 A ADC).
static void decode_sensors(struct fz_reader *r, bool hostile, struct sensors_params *p)
{
    p->angle_step = 6.283185307179586 / 4000, p->encoder_offset = 0, p->current_step = 4.0 / 4096;
    p->current_range = 2, p->current_offset[0] = p->current_offset[1] = 0, p->delay = 0;
    if (!hostile)
        return;
    p->angle_step = fz_value(r, p->angle_step), p->encoder_offset = fz_value(r, 0);
    p->current_step = fz_value(r, p->current_step), p->current_range = fz_value(r, 2);
    p->current_offset[0] = fz_value(r, 0), p->current_offset[1] = fz_value(r, 0);
    p->delay = fz_byte(r, 1) % 12;
}

// Returns nothing; decodes the observer (hostile, or flatstep's matrices for bandwidth 1200 rad/s at 200 us).
static void decode_observer(struct fz_reader *r, bool hostile, struct observer_params *p)
{
    static const double Ad[4][4] = {{1.0, 0.00019944547182371698, -0.005545281762830317, -3.69856538108601e-07},
                                    {0.0, 0.9944598480048967, -55.40151995103249, -0.005545281762830316},
                                    {0.0, 0.0, 0.9999999999999998, 0.0002},
                                    {0.0, 0.0, 0.0, 1.0}};
    static const double Bd[4] = {0.005545281762830317, 55.40151995103249, 2.220446049250313e-16, 0.0};
    static const double Lc[4] = {0.8402977996510327, 2719.492770486277, -14.622084806633508, -8185.724045203784};
    int i, j;
    p->order = hostile ? fz_byte(r, 4) % 6 : 4;
    for (i = 0; i < OBSERVER_MAX_ORDER; i++) {
        p->Bd[i] = hostile ? fz_value(r, Bd[i]) : Bd[i];
        p->Lc[i] = hostile ? fz_value(r, Lc[i]) : Lc[i];
        for (j = 0; j < OBSERVER_MAX_ORDER; j++)
            p->Ad[i][j] = hostile ? fz_value(r, Ad[i][j]) : Ad[i][j];
    }
}

// Returns the options byte, decoded after everything else (0 when exhausted); sets the encoder's edge timing (1)
// and the observer's torque ramp (2: flatstep's Bf for the nominal observer, 4: Bf decoded around it).
static uint8_t decode_options(struct fz_reader *r, struct sampled_params *p)
{
    static const double Bf[4] = {0.0018492826905430052, 27.72640881415158, 1.3552527156068805e-16, 0.0};
    uint8_t opts = fz_byte(r, 0);
    int i;
    p->sensors.edge_timing = opts & 1;
    for (i = 0; i < OBSERVER_MAX_ORDER; i++)
        p->observer.Bf[i] = opts & 4 ? fz_value(r, Bf[i]) : (opts & 2 ? Bf[i] : 0);
    return opts;
}

// Returns nothing; decodes the drive: bus, PWM and dead time (mask bits: 1 delay, 2 switched, 4 hostile,
// 8 unlimited bus).
static void decode_drive(struct fz_reader *r, uint8_t bits, struct drive_params *p)
{
    p->v_bus = bits & 8 ? INFINITY : 48, p->compute_delay = bits & 1, p->pwm = bits & 2 ? DRIVE_SWITCHED : 0;
    p->f_pwm = 20e3, p->dead_time = bits & 2 ? 1e-6 : 0;
    if (!(bits & 4))
        return;
    p->v_bus = fz_value(r, p->v_bus), p->f_pwm = fz_value(r, p->f_pwm), p->dead_time = fz_value(r, 1e-6);
    if (fz_byte(r, 0) == 0xff)
        p->pwm = fz_u32(r, 2);  // mostly not a drive_pwm: drive_init must refuse it
}

// Returns true when sampled.h's documented requirements hold (the oracle for sampled_init).
static bool params_ok(const struct sampled_params *p, uint32_t pwm_periods)
{
    const struct drive_params *d = &p->drive;
    const struct sensors_params *s = &p->sensors;
    const struct observer_params *o = &p->observer;
    bool drive = d->v_bus > 0 && (d->pwm == DRIVE_AVERAGED || d->pwm == DRIVE_SWITCHED);
    uint32_t i, j;
    if (d->pwm == DRIVE_SWITCHED)
        drive = drive && isfinite(d->v_bus) && fz_positive(d->f_pwm) && d->dead_time >= 0
                && d->dead_time < 0.25 / d->f_pwm && pwm_periods >= 1;
    if (p->observed && (o->order < 2 || o->order > OBSERVER_MAX_ORDER))
        return false;
    for (i = 0; p->observed && i < o->order; i++) {
        if (!isfinite(o->Bd[i]) || !isfinite(o->Lc[i]) || !isfinite(o->Bf[i]))
            return false;
        for (j = 0; j < o->order; j++)
            if (!isfinite(o->Ad[i][j]))
                return false;
    }
    if (p->sensed
        && !(isfinite(s->angle_step) && s->angle_step >= 0 && isfinite(s->encoder_offset) && s->encoder_offset >= -0.5
             && s->encoder_offset < 0.5 && isfinite(s->current_step) && s->current_step >= 0
             && fz_positive(s->current_range) && isfinite(s->current_offset[0]) && isfinite(s->current_offset[1])
             && s->delay <= SENSORS_MAX_DELAY))
        return false;
    return fz_positive(p->Ts) && p->substeps >= 1 && p->model.Nr >= 1 && fz_positive(p->model.R)
           && fz_positive(p->model.L) && fz_positive(p->model.Km) && fz_positive(p->model.J) && isfinite(p->model.B)
           && p->model.B >= 0 && drive;
}

// Returns 0 (libFuzzer's convention); aborts when a contract of the sampled loop is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct fz_law law;
    static struct fz_run run;
    static struct sampled loop, plain;
    struct fz_reader r = {data, size};
    struct sampled_params p = {0};
    uint8_t head = fz_byte(&r, 0);
    uint32_t mask = fz_u32(&r, 0), periods;
    double work;
    volatile uint32_t cancel = 0;
    int rc;
    fz_motor(&r, mask & 1, &p.model);
    fz_plan(&r, mask & (1u << 15), 0.02, 0.04, &run.plan);
    fz_plant(&r, (uint8_t)((mask >> 1) & 31), &p.model, &run.plant);
    p.sensed = mask & (1u << 6);
    decode_sensors(&r, mask & (1u << 7), &p.sensors);
    p.observed = mask & (1u << 8);
    decode_observer(&r, mask & (1u << 9), &p.observer);
    decode_drive(&r, (uint8_t)((mask >> 10) & 15), &p.drive);
    p.Ts = mask & (1u << 14) ? fz_value(&r, 2e-4) : 2e-4;
    p.substeps = mask & (1u << 14) ? fz_byte(&r, 4) : 4;
    run.n = fz_byte(&r, 250);
    periods = p.drive.pwm == DRIVE_SWITCHED && fz_positive(p.drive.f_pwm) ? fz_pwm_periods(&p.drive, p.Ts) : 0;
    p.cancel = &cancel;
    rc = sampled_init(&loop, &p);
    if ((rc == SIM_OK) != params_ok(&p, periods) || (rc != SIM_OK && rc != SIM_EARGS))
        FZ_FAIL("sampled_init returned %d on %s parameters", rc, params_ok(&p, periods) ? "valid" : "invalid");
    if (rc != SIM_OK)
        return 0;
    if (p.drive.pwm == DRIVE_SWITCHED)
        fz_check_pwm(&r, &p.drive, p.Ts / (double)periods);
    if (fz_law_init(&law, head & 3, &r, mask & (1u << 16), (uint8_t)(head >> 2), &p.model, &run.plan, p.Ts,
                    p.drive.v_bus)
        != 0)
        return 0;
    work = p.drive.pwm == DRIVE_SWITCHED ? (double)periods * DRIVE_PWM_SEGMENTS : (double)p.substeps;
    if (work * (double)run.n > FZ_WORK)
        return 0;  // a valid run, too long for a fuzz input
    fz_decode_run(&r, mask, &run);
    if (mask & (1u << 19)) {
        law.cancel = &cancel;
        law.cancel_at = 1 + fz_byte(&r, 100);
    }
    if (!(decode_options(&r, &p) & 7)) {
        fz_check_run(&loop, &p, &law, &run, &cancel);
        return 0;
    }
    plain = loop;  // initialised without the options
    rc = sampled_init(&loop, &p);
    if ((rc == SIM_OK) != params_ok(&p, periods) || (rc != SIM_OK && rc != SIM_EARGS))
        FZ_FAIL("sampled_init with the options returned %d on %s parameters", rc,
                params_ok(&p, periods) ? "valid" : "invalid");
    if (rc != SIM_OK)
        return 0;
    fz_check_run(&loop, &p, &law, &run, &cancel);
    fz_check_options(&plain, &p, &law, &run, &cancel);
    return 0;
}
