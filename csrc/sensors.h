// Drive sensors: a quantized encoder, offset/noisy/quantized ADC phase currents, a measurement delay ring.
#ifndef FS_SENSORS_H
#define FS_SENSORS_H

#include <stdbool.h>
#include <stdint.h>
#include "fs_real.h"

// cffi:begin

// Longest measurement delay the ring holds [control periods].
#define SENSORS_MAX_DELAY 8

// What the sensors do; the same fields as flatstep.sensors.Sensors, with the steps precomputed.
struct sensors_params {
    fs_real angle_step;         // one encoder count [rad] (2 pi / counts), or 0 for the exact angle
    fs_real encoder_offset;     // where the count edges sit, in counts, in [-0.5, 0.5)
    fs_real current_step;       // one ADC step [A] (2 range / 2^bits), or 0 for exact currents
    fs_real current_range;      // ADC full scale [A], > 0: readings are clipped to +-current_range
    fs_real current_offset[2];  // offsets added to (ia, ib) before conversion [A]
    uint32_t delay;             // the controller sees the reading of `delay` periods ago, <= SENSORS_MAX_DELAY
    bool edge_timing;           // the encoder also latches its last edge: the angle of that edge and its age
};

// Length of a reading: (theta_m, ia_m, ib_m, theta_edge, edge_age).
#define SENSORS_READING_LEN 5

// Caller-owned state: the parameters and the last delay + 1 readings.
struct sensors {
    struct sensors_params p;
    fs_real ring[SENSORS_MAX_DELAY + 1][SENSORS_READING_LEN];
    uint32_t head;   // slot of the newest reading
    uint32_t taken;  // readings taken since the last reset, saturating at SENSORS_MAX_DELAY + 1
};

// Returns true when every parameter is finite and in range.
bool sensors_params_valid(const struct sensors_params *p);

// Returns 0, or -1 when p is invalid (s is then left unusable); copies p and resets s.
int sensors_init(struct sensors *s, const struct sensors_params *p);

// Returns nothing; forgets the readings taken so far.
void sensors_reset(struct sensors *s);

// Returns the encoder reading q (round(theta / q - offset) + offset) of the true angle theta (rounding half to
// even, as NumPy; theta itself when angle_step is 0 or |theta / q| >= 1 / epsilon, where counts are integers).
fs_real sensors_angle(const struct sensors_params *p, fs_real theta);

// Returns nothing; writes the ADC readings of the phase currents i with the noise sample added:
// clip(q round((i + offset + noise) / q), +-range), or i + offset + noise when current_step is 0 (and, clipped,
// when |(i + offset + noise) / q| >= 1 / epsilon, where steps are integers).
void sensors_currents(const struct sensors_params *p, const fs_real i[2], const fs_real noise[2], fs_real out[2]);

// Returns nothing; writes the last count edge the rotor crossed, edge[0] = theta_m -+ q/2 behind the motion, and
// its age edge[1] = (theta - edge[0]) / omega [s] from the speed at the sample; edge = (0, -1) (none) without
// edge_timing, an encoder, or motion (omega = 0) (flatstep.loop.sensors.Sensors.read_edge).
void sensors_edge(const struct sensors_params *p, fs_real theta, fs_real omega, fs_real edge[2]);

// Returns nothing; reads the plant state x = (ia, ib, omega, theta) with the noise sample, stores the reading,
// and writes the one of `delay` periods ago (the first one while fewer have been taken) as
// (theta_m, ia_m, ib_m, theta_edge, edge_age) (sensors_edge).
void sensors_step(struct sensors *s, const fs_real x[4], const fs_real noise[2], fs_real reading[SENSORS_READING_LEN]);

// cffi:end
#endif
