// The checks of a sampled run (sampled.h, drive.h, sensors.h) for the sampled-loop fuzz harness.
#ifndef FUZZ_SAMPLED_CHECK_H
#define FUZZ_SAMPLED_CHECK_H

#include <stdint.h>
#include "laws.h"
#include "sampled.h"

// Longest run a fuzz input asks for [periods], and the most RK4 steps one run may take.
#define FZ_MAXN 255
#define FZ_WORK 20000.0

// One run's inputs and, for each of its two passes, its outputs.
struct fz_run {
    struct plan plan;
    struct plant plant;
    double x0[4];
    size_t n;
    bool has_noise;
    double noise[2 * (FZ_MAXN + 1)];
    double x[2][4 * (FZ_MAXN + 1)], v[2][2 * (FZ_MAXN + 1)], y[2][CTRL_Y_LEN * (FZ_MAXN + 1)];
    uint32_t status[2][FZ_MAXN + 1];
    struct sim_stats st[2];
    int rc[2];
};

// Returns the PWM periods per control period drive.h documents: max(1, round(Ts f_pwm)), ties to even, or 0
// beyond 1e9.
uint32_t fz_pwm_periods(const struct drive_params *d, double Ts);

// Returns nothing; decodes the start state (mask bit 17: hostile, else the plan's start equilibrium) and the
// sensor noise (bit 18: a scaled uniform sequence with one poisoned sample).
void fz_decode_run(struct fz_reader *r, uint32_t mask, struct fz_run *run);

// Returns nothing; runs the loop twice and aborts unless both runs keep sampled.h's contract and agree bit for bit.
void fz_check_run(struct sampled *loop, const struct sampled_params *p, struct fz_law *law, struct fz_run *run,
                  volatile uint32_t *cancel);

// Returns nothing; runs plain (the loop initialised without p's edge timing and torque ramp) once and aborts unless
// it agrees with the run's first pass up to the first period the options may change (sampled.h): the torque ramp
// from the second prediction on, the edge timing from the first reading after the first whose edge age lies in
// [0, Ts), and only with sensors and an observer.
void fz_check_options(struct sampled *plain, const struct sampled_params *p, struct fz_law *law, struct fz_run *run,
                      volatile uint32_t *cancel);

// Returns nothing; aborts unless drive_pwm_period keeps drive.h's contract on a decoded command and currents.
void fz_check_pwm(struct fz_reader *r, const struct drive_params *d, double Tp);

#endif
