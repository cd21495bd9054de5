// The power stage of a sampled drive: bus saturation keeping the voltage direction, one-period computation
// delay, and switched (bipolar, centre-aligned) PWM with dead time.
#ifndef FS_DRIVE_H
#define FS_DRIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "fs_real.h"

// cffi:begin
enum drive_pwm { DRIVE_AVERAGED = 0, DRIVE_SWITCHED = 1 };

// The most segments of one PWM period: the start and the 8 other breakpoints of the two phases.
#define DRIVE_PWM_SEGMENTS 9

struct drive_params {
    fs_real v_bus;       // |va|, |vb| <= v_bus [V], > 0; infinity for an unlimited (ideal) averaged bridge
    bool compute_delay;  // apply each command one period after it is computed
    uint32_t pwm;        // enum drive_pwm: the bridge delivers the command (averaged) or chops it (switched)
    fs_real f_pwm;       // switched: PWM frequency [Hz], > 0 and finite
    fs_real dead_time;   // switched: per edge [s], 0 <= dead_time < 1 / (4 f_pwm)
};

// Caller-owned state: the parameters and the command waiting for the next period.
struct drive {
    struct drive_params p;
    fs_real v_hold[2];
};

// Returns 0, or -1 when v_bus is not > 0, pwm is not a drive_pwm, or (switched) v_bus, f_pwm or dead_time is
// out of range (d is then left unusable); the bridge starts by applying v_start.
int drive_init(struct drive *d, const struct drive_params *p, const fs_real v_start[2]);

// Returns nothing; the bridge applies v_start until the first delayed command arrives.
void drive_reset(struct drive *d, const fs_real v_start[2]);

// Returns nothing; writes v / max(1, max(|va|, |vb|) / v_bus): the command scaled into the bus, direction kept
// (v / max(|va|, |vb|) v_bus where that ratio overflows, on a bus below the command / DBL_MAX).
void drive_saturate(const struct drive_params *p, const fs_real v[2], fs_real out[2]);

// Returns nothing; saturates the command v_cmd and writes the voltage applied over the coming period (the
// saturated command, or with compute_delay the previous period's).
void drive_step(struct drive *d, const fs_real v_cmd[2], fs_real v_apply[2]);

// Returns the number n of PWM periods in a control period Ts, max(1, round(Ts / (1 / f_pwm))) with ties to
// even (each Ts / n long), or 0 when n would exceed 1e9.
uint32_t drive_pwm_periods(const struct drive_params *p, fs_real Ts);

// Returns the number of segments (1 to DRIVE_PWM_SEGMENTS) of one PWM period Tp under the command v (saturated
// here) with phase currents i; writes their durations dur (summing to Tp up to rounding) and the phase
// voltages lv, each -v_bus, +v_bus or during dead time the freewheeling -sign(i) v_bus (0 at i = 0). Each
// phase switches at offsets 0, on, on + td, off, off + td to -v_bus, free, +v_bus, free, -v_bus, with
// on = (1 - d) Tp / 2, off = (1 + d) Tp / 2, the duty d = (1 + v / v_bus) / 2 and td = min(dead_time, on,
// Tp - off); a segment starts at each distinct offset below Tp, and on it a phase has the level of its last
// offset (in that order) at or before the segment's start.
size_t drive_pwm_period(const struct drive_params *p, const fs_real v[2], const fs_real i[2], fs_real Tp,
                        fs_real dur[DRIVE_PWM_SEGMENTS], fs_real lv[DRIVE_PWM_SEGMENTS][2]);

// cffi:end
#endif
