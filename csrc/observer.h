// Discrete Luenberger observer of (theta, omega, load torque, load-torque rate) from the encoder angle.
#ifndef FS_OBSERVER_H
#define FS_OBSERVER_H

#include <stdbool.h>
#include <stdint.h>
#include "fs_real.h"

// cffi:begin

// Largest observer order: theta, omega, load torque, load-torque rate.
#define OBSERVER_MAX_ORDER 4

// The discretized model and gain of flatstep.observers.Observer.matrices (order 2, 3 or 4), row-major.
struct observer_params {
    uint32_t order;                                      // 2 + load states, in 2..4
    fs_real Ad[OBSERVER_MAX_ORDER][OBSERVER_MAX_ORDER];  // x_{k+1} = Ad x_k + Bd Te_k + Bf (Te_k - Te_{k-1})
    fs_real Bd[OBSERVER_MAX_ORDER];
    fs_real Lc[OBSERVER_MAX_ORDER];  // correction gain, current-estimator form
    fs_real Bf[OBSERVER_MAX_ORDER];  // the torque's ramp over the period, extrapolated from the last one (all 0:
                                     // the torque held, zero-order hold)
};

// Caller-owned state: the parameters and the estimate (theta, omega[, tau_load[, tau_load']]).
struct observer {
    struct observer_params p;
    fs_real x[OBSERVER_MAX_ORDER];
    bool started;         // false until the first correction sets the estimate from the first angle
    fs_real torque_prev;  // the torque of the last prediction [N m]
    bool predicted;       // false until the first prediction (which holds its torque: no ramp yet)
};

// Returns 0, or -1 when the order is not 2..4 or an entry is not finite (o is then left unusable).
int observer_init(struct observer *o, const struct observer_params *p);

// Returns nothing; forgets the estimate (the next correction starts from its angle at rest).
void observer_reset(struct observer *o);

// Returns nothing; corrects the estimate with the measured angle: x <- x + Lc (theta_m - x0), or, on the
// first call, x <- (theta_m, 0, ...).
void observer_correct(struct observer *o, fs_real theta_m);

// Returns nothing; corrects the estimate with a count edge crossed `age` seconds ago (age >= 0): the angle then,
// x0 - x1 age, was theta_edge: x <- x + Lc (theta_edge - (x0 - x1 age)); on the first call as observer_correct.
void observer_correct_edge(struct observer *o, fs_real theta_edge, fs_real age);

// Returns nothing; predicts the next period's estimate under the torque Te from the period's start, ramping by its
// last change: x <- Ad x + Bd Te + Bf (Te - Te_prev) (Te_prev = Te on the first prediction).
void observer_predict(struct observer *o, fs_real torque);

// Returns the estimated load torque [N m] (0 for a speed-only observer of order 2).
fs_real observer_load(const struct observer *o);

// cffi:end
#endif
