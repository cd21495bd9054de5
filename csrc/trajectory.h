// Piecewise-polynomial trajectories of the flat outputs (theta, rho): a segment table read by Horner's rule.
#ifndef FS_TRAJECTORY_H
#define FS_TRAJECTORY_H

#include <stdbool.h>
#include <stddef.h>
#include "fs_real.h"
#include "plan.h"

// cffi:begin

// Coefficients per segment and output: degree 10 at most (the paper's psi has degree 10).
enum { TRAJ_NCOEF = 11 };

// A segment table in caller-owned memory (const data in a firmware). On segment i, breaks[i] <= t < breaks[i + 1],
// with h = breaks[i + 1] - breaks[i] and the local time tau = (t - breaks[i]) (1 / h) in [0, 1):
//   theta(t) = sum_j theta[i TRAJ_NCOEF + j] tau^(10 - j)   (highest power first, as numpy.polyval),
// rho(t) likewise, and d^k/dt^k = (d^k/dtau^k) (1 / h)^k. Before breaks[0] the flag holds the first segment's
// value at tau = 0, from breaks[n] on the last segment's value at tau = 1, both with zero derivatives.
// flatstep.plan.piecewise.PiecewisePlan is the Python twin and builder.
struct traj {
    size_t n;               // number of segments, >= 1
    const fs_real *breaks;  // n + 1 increasing times [s]
    const fs_real *theta;   // n x TRAJ_NCOEF coefficients of theta [rad], row-major
    const fs_real *rho;     // n x TRAJ_NCOEF coefficients of the second flat output (rho [A]), row-major
};

// Returns true when n >= 1, the pointers are set, every break and coefficient is finite, the breaks increase,
// every segment's width h is finite (so t - breaks[i] cannot overflow inside it) and its (1 / h)^4 is finite (no
// derivative can overflow from the scaling alone).
bool traj_valid(const struct traj *tr);

// Returns the segment i whose [breaks[i], breaks[i + 1]) holds t, clamped to 0 .. n - 1 (0 for a NaN t).
size_t traj_segment(const struct traj *tr, fs_real t);

// Returns true while breaks[0] < t < breaks[n]; writes the flag (rho, rho', theta, theta', theta'', theta''') at
// t in the layout of plan_flag, as flatstep.plan.piecewise.PiecewisePlan.flag does, operation for operation.
// A NaN t holds the start, as any t <= breaks[0] does.
bool traj_flag(const struct traj *tr, fs_real t, fs_real flag[PLAN_FLAG_LEN]);

// Returns and writes what traj_flag does; *seg is the caller's guess of the segment (the last call's), checked,
// then its successor, then bisection; on return the segment of t. Times in order (a control loop's) so cost no
// search.
bool traj_flag_seg(const struct traj *tr, fs_real t, size_t *seg, fs_real flag[PLAN_FLAG_LEN]);

// Returns nothing; writes traj_flag at each of the n times t into flag (n x PLAN_FLAG_LEN, row-major).
void traj_flag_n(const struct traj *tr, const fs_real *t, size_t n, fs_real *flag);

// Returns the order-th time derivative (0..4) of theta at t (0 for an order out of range), for a caller that needs
// the snap theta'''' as well.
fs_real traj_theta(const struct traj *tr, fs_real t, int order);

// cffi:end
#endif
