// The stages the time-optimal planner's search calls (csrc/time_optimal.c): the envelope and the bang-bang move
// (time_optimal_envelope.c, flatstep.plan.envelope), the smoothed table (time_optimal_table.c,
// flatstep.plan.smoothing). Internal to the planner: not part of the C API and not bound by Python.
#ifndef FS_TIME_OPTIMAL_STAGES_H
#define FS_TIME_OPTIMAL_STAGES_H

#include <stdbool.h>
#include <stddef.h>
#include "time_optimal.h"

#define TO_V_MARGIN FS_C(0.998)  // of v_use: the sampled check may miss the peak between its samples by this much
#define TO_FINE_LEN (TO_FINE_MAX + 2)
// The box filter's running sum: a profile of up to TO_FINE_LEN samples padded by n_box - 1 zeros at each end, with
// n_box <= TO_FINE_MAX / 2 (a smoothing width is at most half the sampled core, whose step is >= core / TO_FINE_MAX).
#define TO_SUM_LEN (TO_FINE_LEN + TO_FINE_MAX / 2 + 2)

// Scratch arrays carved out of the caller's workspace.
struct to_work {
    fs_real *omega, *ap, *am, *tacc, *tdec, *dboth;  // TO_GRID each: the envelope and its integrals
    fs_real *a, *b;                                  // TO_FINE_LEN + 1 each: the sampled profile
    fs_real *c;                                      // TO_SUM_LEN: the box filter's running sum
    fs_real *knot;                                   // TO_MAX_SEGMENTS + 1 sample indices
    bool integrals;                                  // tacc, tdec and dboth hold the envelope's integrals
    struct traj tr;                                  // the candidate table over the arrays below
    fs_real *breaks, *theta, *rho;
};

// The bang-bang move of envelope.bang_bang and the sampling of smoothing.timing.
struct to_move {
    fs_real t1, cruise, t2, w_peak, dt;
    size_t n_box, n;
    size_t r, k;  // the cut: k samples of the cruise from sample r on are not sampled
};

// The envelope's h(u) at one speed: its products of the speed's terms, formed once (to_h then rounds as the
// reference's voltage_excess does, operation for operation).
struct to_hcoef {
    fs_real z, opk, kk, f2, r2c, ce2, cc, v2, dz, dr;
};

// time_optimal_envelope.c
// Returns the across-axis floor f(omega) (MotorLimits.floor).
static inline fs_real to_floor_current(const struct to_limits *lim, fs_real w)
{
    fs_real x = w / lim->speed_corner;
    return lim->i_run + (lim->i_hold - lim->i_run) / (1 + x * x);
}

// Returns element i of numpy.linspace(start, stop, num) as numpy computes it: i (stop - start) / (num - 1) + start,
// the last element stop itself (the knots are rounded from these: the same rounding gives the same knots).
static inline fs_real to_linspace(fs_real start, fs_real stop, size_t num, size_t i)
{
    return i == num - 1 ? stop : (fs_real)i * ((stop - start) / (fs_real)(num - 1)) + start;
}

struct to_hcoef to_hcoef(const struct motor_params *m, fs_real k, fs_real f, fs_real w, fs_real v2);
fs_real to_h(const struct to_hcoef *hc, fs_real u, fs_real *dh);
size_t to_envelope(const struct motor_params *m, const struct to_limits *lim, fs_real gamma, struct to_work *w);
fs_real to_interp(fs_real x, const fs_real *xs, const fs_real *ys, size_t n);

// Returns the length of x after a box of n samples: x convolved with it through the running sum in s, which holds
// len + 2 n - 1 values (smoothing._box; out may not alias x).
size_t to_box(const fs_real *x, size_t len, size_t n, fs_real *s, fs_real *out);

// Returns the central difference of x at i (one-sided at the ends) over dt (smoothing._gradient).
fs_real to_gradient(const fs_real *x, size_t len, size_t i, fs_real dt);

// The inverse of the degree-7 Hermite system of segments.hermite_rows: coefficients (tau^7 .. tau^0) from the
// ends' (theta, theta' h, theta'' h^2, theta''' h^3); both time-optimal planners fit their tables with it.
extern const fs_real TO_HERMITE[8][8];
// Returns y at x as to_interp does, for x rising (dir 1) or falling (dir -1) between calls: *j walks to the bracket.
static inline fs_real to_interp_walk(fs_real x, const fs_real *xs, const fs_real *ys, size_t n, size_t *j)
{
    if (x <= xs[0])
        return ys[0];
    if (x >= xs[n - 1])
        return ys[n - 1];
    while (*j + 1 < n - 1 && xs[*j + 1] <= x)
        ++*j;
    while (*j > 0 && xs[*j] > x)
        --*j;
    return (ys[*j + 1] - ys[*j]) / (xs[*j + 1] - xs[*j]) * (x - xs[*j]) + ys[*j];
}

void to_bang_bang(fs_real d, fs_real width, struct to_work *w, struct to_move *mv);

// time_optimal_table.c
// Returns true when every limit is finite and in range (time_optimal.h's struct to_limits).
bool to_limits_valid(const struct to_limits *l);
// passes: the box filters (2; 1 for the field-weakening planner, whose law takes a jerk that jumps).
bool to_smoothed_table(const struct motor_params *m, const struct to_limits *lim, fs_real d, fs_real width, int passes,
                       struct to_work *w);

#endif
