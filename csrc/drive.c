// The drive's bridge: bus saturation, computation delay and PWM segments, in the arithmetic of flatstep.loop.drive.
#include "drive.h"

// Returns 0, or -1 when v_bus is not > 0, pwm is not a drive_pwm, or (switched) v_bus, f_pwm or dead_time is
// out of range (d is then left unusable); the bridge starts by applying v_start.
int drive_init(struct drive *d, const struct drive_params *p, const fs_real v_start[2])
{
    if (!(p->v_bus > 0) || (p->pwm != DRIVE_AVERAGED && p->pwm != DRIVE_SWITCHED))
        return -1;
    if (p->pwm == DRIVE_SWITCHED
        && (!fs_isfinite(p->v_bus) || !(p->f_pwm > 0) || !fs_isfinite(p->f_pwm)
            || !(p->dead_time >= 0 && p->dead_time < FS_C(0.25) / p->f_pwm)))
        return -1;
    d->p = *p;
    drive_reset(d, v_start);
    return 0;
}

// Returns nothing; the bridge applies v_start until the first delayed command arrives.
void drive_reset(struct drive *d, const fs_real v_start[2])
{
    d->v_hold[0] = v_start[0];
    d->v_hold[1] = v_start[1];
}

// Returns nothing; writes v / max(1, max(|va|, |vb|) / v_bus): the command scaled into the bus, direction kept
// (v / max(|va|, |vb|) v_bus where that ratio overflows, on a bus below the command / DBL_MAX).
void drive_saturate(const struct drive_params *p, const fs_real v[2], fs_real out[2])
{
    fs_real peak = fs_fabs(v[0]) > fs_fabs(v[1]) ? fs_fabs(v[0]) : fs_fabs(v[1]);
    fs_real scale = peak / p->v_bus;
    if (!(scale > 1))
        scale = 1;  // dividing by 1 leaves v exact, as NumPy's v / maximum(1, peak / v_bus)
    // peak / v_bus overflowed (a tiny bus): v / inf would lose the direction
    if (scale > FS_REAL_MAX) {
        out[0] = v[0] / peak * p->v_bus;
        out[1] = v[1] / peak * p->v_bus;
        return;
    }
    out[0] = v[0] / scale;
    out[1] = v[1] / scale;
}

// Returns nothing; saturates the command v_cmd and writes the voltage applied over the coming period (the
// saturated command, or with compute_delay the previous period's).
void drive_step(struct drive *d, const fs_real v_cmd[2], fs_real v_apply[2])
{
    fs_real v_new[2];
    drive_saturate(&d->p, v_cmd, v_new);
    if (d->p.compute_delay) {
        v_apply[0] = d->v_hold[0];
        v_apply[1] = d->v_hold[1];
    } else {
        v_apply[0] = v_new[0];
        v_apply[1] = v_new[1];
    }
    d->v_hold[0] = v_new[0];
    d->v_hold[1] = v_new[1];
}

// Returns the number n of PWM periods in a control period Ts, max(1, round(Ts / (1 / f_pwm))) with ties to
// even (each Ts / n long), or 0 when n would exceed 1e9.
uint32_t drive_pwm_periods(const struct drive_params *p, fs_real Ts)
{
    fs_real n = fs_rint(Ts / (1 / p->f_pwm));  // rint rounds ties to even, as Python's round
    if (!(n <= FS_C(1e9)))
        return 0;
    return n < 1 ? 1 : (uint32_t)n;
}

// Returns the number of segments of one PWM period Tp; writes their durations and phase voltages (drive.h).
size_t drive_pwm_period(const struct drive_params *p, const fs_real v[2], const fs_real i[2], fs_real Tp,
                        fs_real dur[DRIVE_PWM_SEGMENTS], fs_real lv[DRIVE_PWM_SEGMENTS][2])
{
    fs_real vs[2], at[2][5], level[2][5], d, on, off, td, free, t = 0, next;
    size_t m = 0;
    int ph, j;
    drive_saturate(p, v, vs);
    for (ph = 0; ph < 2; ph++) {
        d = FS_C(0.5) * (1 + vs[ph] / p->v_bus);  // fraction of the period at +v_bus
        on = FS_C(0.5) * (1 - d) * Tp;
        off = FS_C(0.5) * (1 + d) * Tp;
        free = i[ph] > 0 ? -p->v_bus : (i[ph] < 0 ? p->v_bus : 0);
        td = p->dead_time > 0 ? fs_min(fs_min(p->dead_time, on), Tp - off) : 0;
        at[ph][0] = 0, at[ph][1] = on, at[ph][2] = on + td, at[ph][3] = off, at[ph][4] = off + td;
        level[ph][0] = level[ph][4] = -p->v_bus;
        level[ph][1] = level[ph][3] = free;
        level[ph][2] = p->v_bus;
    }
    // merge: each segment runs from t to the nearest offset after it; offsets are not sorted when a high pulse
    // is shorter than the dead time (on + td > off), hence the scan
    while (t < Tp && m < DRIVE_PWM_SEGMENTS) {
        next = Tp;
        for (ph = 0; ph < 2; ph++)
            for (j = 1; j < 5; j++)
                if (at[ph][j] > t && at[ph][j] < next)
                    next = at[ph][j];
        for (ph = 0; ph < 2; ph++) {
            for (j = 4; j > 0 && !(at[ph][j] <= t); j--)
                ;
            lv[m][ph] = level[ph][j];
        }
        dur[m++] = next - t;
        t = next;
    }
    return m;
}
