// The drive's sensors in the operation order of flatstep.sensors, so that they round as the reference does.
#include "sensors.h"

// Returns true when every parameter is finite and in range.
bool sensors_params_valid(const struct sensors_params *p)
{
    return fs_isfinite(p->angle_step) && p->angle_step >= 0 && fs_isfinite(p->encoder_offset)
           && p->encoder_offset >= FS_C(-0.5) && p->encoder_offset < FS_C(0.5) && fs_isfinite(p->current_step)
           && p->current_step >= 0 && fs_isfinite(p->current_range) && p->current_range > 0
           && fs_isfinite(p->current_offset[0]) && fs_isfinite(p->current_offset[1]) && p->delay <= SENSORS_MAX_DELAY;
}

// Returns 0, or -1 when p is invalid (s is then left unusable); copies p and resets s.
int sensors_init(struct sensors *s, const struct sensors_params *p)
{
    if (!sensors_params_valid(p))
        return -1;
    s->p = *p;
    sensors_reset(s);
    return 0;
}

// Returns nothing; forgets the readings taken so far.
void sensors_reset(struct sensors *s)
{
    s->head = SENSORS_MAX_DELAY;
    s->taken = 0;
}

// Returns the encoder reading q (round(theta / q - offset) + offset) of the true angle theta (rounding half to
// even, as NumPy; theta itself when angle_step is 0 or |theta / q| >= 1 / epsilon, where counts are integers).
fs_real sensors_angle(const struct sensors_params *p, fs_real theta)
{
    fs_real q = p->angle_step, counts = q != 0 ? theta / q : 0;
    // beyond 1 / epsilon counts (or an overflow to inf) every count is an integer: the angle is its own reading
    if (q == 0 || !(fs_fabs(counts) < 1 / FS_REAL_EPSILON))
        return theta;
    return q * (fs_rint(counts - p->encoder_offset) + p->encoder_offset);
}

// Returns nothing; writes the ADC readings of the phase currents i with the noise sample added:
// clip(q round((i + offset + noise) / q), +-range), or i + offset + noise when current_step is 0 (and, clipped,
// when |(i + offset + noise) / q| >= 1 / epsilon, where steps are integers).
void sensors_currents(const struct sensors_params *p, const fs_real i[2], const fs_real noise[2], fs_real out[2])
{
    fs_real q = p->current_step, r = p->current_range, a;
    int k;
    for (k = 0; k < 2; k++) {
        a = i[k] + p->current_offset[k] + noise[k];
        if (q != 0) {
            if (fs_fabs(a / q) < 1 / FS_REAL_EPSILON)  // else a is a whole number of steps (or a / q overflowed)
                a = q * fs_rint(a / q);
            a = a < -r ? -r : (a > r ? r : a);
        }
        out[k] = a;
    }
}

// Returns nothing; writes the last count edge crossed and its age, or (0, -1) (sensors.h).
void sensors_edge(const struct sensors_params *p, fs_real theta, fs_real omega, fs_real edge[2])
{
    fs_real q = p->angle_step;
    edge[0] = 0;
    edge[1] = -1;
    if (!p->edge_timing || q == 0 || omega == 0)
        return;
    edge[0] = sensors_angle(p, theta) - (omega > 0 ? FS_C(0.5) * q : FS_C(-0.5) * q);
    edge[1] = (theta - edge[0]) / omega;
}

// Returns nothing; reads the plant state x = (ia, ib, omega, theta) with the noise sample, stores the reading,
// and writes the one of `delay` periods ago (the first one while fewer have been taken) as
// (theta_m, ia_m, ib_m, theta_edge, edge_age).
void sensors_step(struct sensors *s, const fs_real x[4], const fs_real noise[2], fs_real reading[SENSORS_READING_LEN])
{
    // The ring holds the last MAX + 1 readings; while at most `delay` were taken none has been overwritten
    // and the first one, in slot 0, is the delayed reading, as in flatstep.sampled.
    const uint32_t slots = SENSORS_MAX_DELAY + 1;
    fs_real i_m[2], *slot;
    uint32_t back;
    int m;
    s->head = (s->head + 1) % slots;
    if (s->taken < slots)
        s->taken++;
    slot = s->ring[s->head];
    sensors_currents(&s->p, x, noise, i_m);
    slot[0] = sensors_angle(&s->p, x[3]);
    slot[1] = i_m[0];
    slot[2] = i_m[1];
    sensors_edge(&s->p, x[3], x[2], &slot[3]);
    back = s->taken > s->p.delay ? (s->head + slots - s->p.delay) % slots : 0;
    for (m = 0; m < SENSORS_READING_LEN; m++)
        reading[m] = s->ring[back][m];
}
