// The power stage of a sampled drive: bus saturation keeping the voltage direction, one-period computation delay.
#ifndef FS_DRIVE_H
#define FS_DRIVE_H

#include <stdbool.h>
#include "fs_real.h"

// cffi:begin

struct drive_params {
    fs_real v_bus;       // |va|, |vb| <= v_bus [V], > 0; infinity for an unlimited (ideal) bridge
    bool compute_delay;  // apply each command one period after it is computed
};

// Caller-owned state: the parameters and the command waiting for the next period.
struct drive {
    struct drive_params p;
    fs_real v_hold[2];
};

// Returns 0, or -1 when v_bus is not > 0 (d is then left unusable); the bridge starts by applying v_start.
int drive_init(struct drive *d, const struct drive_params *p, const fs_real v_start[2]);

// Returns nothing; the bridge applies v_start until the first delayed command arrives.
void drive_reset(struct drive *d, const fs_real v_start[2]);

// Returns nothing; writes v / max(1, max(|va|, |vb|) / v_bus): the command scaled into the bus, direction kept.
void drive_saturate(const struct drive_params *p, const fs_real v[2], fs_real out[2]);

// Returns nothing; saturates the command v_cmd and writes the voltage applied over the coming period (the
// saturated command, or with compute_delay the previous period's).
void drive_step(struct drive *d, const fs_real v_cmd[2], fs_real v_apply[2]);

// cffi:end
#endif
