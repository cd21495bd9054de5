// One interface for every controller the run loops call: a step on caller-owned state, bound by function pointers.
#ifndef FS_CONTROLLER_H
#define FS_CONTROLLER_H

#include <stdbool.h>
#include <stdint.h>
#include "fs_real.h"

// cffi:begin
// What a controller measures, in this order: y = (ia, ib, omega, theta, theta''); each law reads what it needs.
enum { CTRL_Y_IA, CTRL_Y_IB, CTRL_Y_OMEGA, CTRL_Y_THETA, CTRL_Y_ACC, CTRL_Y_LEN };

// Status bits of a controller step. Any bit below CTRL_SATURATED is a fault: the step then outputs v = (0, 0),
// de-energising both phases, the safe state of a PM stepper.
enum ctrl_status {
    CTRL_OK = 0,
    CTRL_NONFINITE = 1,   // t or a used measurement is NaN or infinite, or the controller's state is
    CTRL_RHO = 2,         // current magnitude below the law's minimum: its angle is undefined
    CTRL_SQRT = 4,        // the torque demand is out of the law's reach
    CTRL_OVERFLOW = 8,    // the law overflowed to a non-finite voltage from finite inputs
    CTRL_SATURATED = 16,  // the command was scaled into the controller's own voltage limit (not a fault)
};
#define CTRL_FAULTS 15

// A bound controller: its state and its two entry points. The run loops call nothing else.
struct controller {
    void *self;                                                             // the law's state (struct smc, ...)
    uint32_t (*step)(void *self, fs_real t, const fs_real *y, fs_real *v);  // ctrl_status bits; finite v
    void (*reset)(void *self);                                              // back to the state after _init
    bool stateless;  // v depends on (t, y) alone: the continuous loop may evaluate it at trial stages
};
// cffi:end

#endif
