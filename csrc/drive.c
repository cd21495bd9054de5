// The drive's averaged bridge: bus saturation and computation delay, in the operation order of flatstep.drive.
#include "drive.h"

// Returns 0, or -1 when v_bus is not > 0 (d is then left unusable); the bridge starts by applying v_start.
int drive_init(struct drive *d, const struct drive_params *p, const fs_real v_start[2])
{
    if (!(p->v_bus > 0))
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

// Returns nothing; writes v / max(1, max(|va|, |vb|) / v_bus): the command scaled into the bus, direction kept.
void drive_saturate(const struct drive_params *p, const fs_real v[2], fs_real out[2])
{
    fs_real peak = fs_fabs(v[0]) > fs_fabs(v[1]) ? fs_fabs(v[0]) : fs_fabs(v[1]);
    fs_real scale = peak / p->v_bus;
    if (!(scale > 1))
        scale = 1;  // dividing by 1 leaves v exact, as NumPy's v / maximum(1, peak / v_bus)
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
