#include "setpoints.h"

#include <math.h>

int setpoint_at(const struct setpoint_stream *s, double t, int mode, fs_real out[SETPOINT_LEN])
{
    if (!s || !out || !s->rows || s->n == 0 || !isfinite(s->rate) || !(s->rate > 0) || !isfinite(s->t0) || !isfinite(t)
        || (mode != SETPOINT_HOLD && mode != SETPOINT_LINEAR))
        return SETPOINT_EARGS;
    double position = (t - s->t0) * s->rate;  // in rows
    uint32_t last = s->n - 1;
    uint32_t k;
    double frac = 0.0;
    if (!(position > 0.0)) {
        k = 0;
    } else if (position >= (double)last) {
        k = last;
    } else {
        // a time a rounding below a row's own time still reads that row
        double nearest = floor(position + 0.5);
        double whole = fabs(position - nearest) <= 1e-9 * (nearest + 1.0) ? nearest : floor(position);
        k = (uint32_t)whole;
        frac = position > whole ? position - whole : 0.0;
    }
    const float *row = s->rows + (uint64_t)k * SETPOINT_LEN;
    if (mode == SETPOINT_LINEAR && frac > 0.0 && k < last) {
        const float *next = row + SETPOINT_LEN;
        for (int j = 0; j < SETPOINT_LEN; j++)
            out[j] = (fs_real)((double)row[j] + frac * ((double)next[j] - (double)row[j]));
    } else {
        for (int j = 0; j < SETPOINT_LEN; j++)
            out[j] = (fs_real)row[j];
    }
    return SETPOINT_OK;
}
