// Integrators for the run loops: adaptive Dormand-Prince 5(4) and 8(5,3) with dense output, and a fixed RK4 step.
#ifndef FS_ODE_H
#define FS_ODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "fs_real.h"

// Largest state dimension the integrators hold (the plant has 4; room for observer states later).
#define ODE_MAX_DIM 8

// Right-hand side dx = f(t, x); returns 0, or nonzero when it cannot be evaluated at (t, x).
typedef int (*ode_rhs_fn)(void *ctx, fs_real t, const fs_real *x, fs_real *dx);

enum ode_status { ODE_OK = 0, ODE_EARGS, ODE_EHMIN, ODE_ERHS };

struct ode_params {
    fs_real rtol, atol;  // error control: |err_i| <= atol + rtol max(|x_i|, |x_new_i|), both > 0
    fs_real h_max;       // largest step [s], > 0 (use a large value for no bound)
};

// Caller-owned integrator state (no heap): the last accepted step [t_old, t] and its dense output.
struct ode_dopri5 {
    struct ode_params p;
    ode_rhs_fn f;
    void *ctx;
    size_t n;
    fs_real t, t_old, h;
    fs_real x[ODE_MAX_DIM];
    fs_real k[7][ODE_MAX_DIM];      // stages; k[0] = f(t, x) (first same as last)
    fs_real rcont[5][ODE_MAX_DIM];  // dense-output coefficients of the last step
    fs_real facold;
    uint32_t steps, rejected, rhs_evals;
};

// Returns ODE_OK, or ODE_EARGS for bad parameters, dimension or start time.
int ode_check_args(const struct ode_params *p, size_t n, fs_real t);

// Returns the first step size for a method of the given order by Hairer's heuristic (one Euler step from
// (t, x) with slope f0 = f(t, x) estimates the second derivative), -1 when f fails there, or 0 when the step
// underflows (a slope so large against the state's scale that no step size fits).
fs_real ode_first_step(const struct ode_params *p, size_t n, ode_rhs_fn f, void *ctx, fs_real t, const fs_real *x,
                       const fs_real *f0, int order);

// Returns ODE_OK, ODE_EARGS for bad parameters or dimension, ODE_ERHS when f fails at (t, x), or ODE_EHMIN when
// the first step size underflows to 0; starts an integration at (t, x) and picks the first step size (Hairer's
// heuristic).
int ode_dopri5_init(struct ode_dopri5 *s, const struct ode_params *p, size_t n, ode_rhs_fn f, void *ctx, fs_real t,
                    const fs_real *x);

// Returns ODE_OK after one accepted step that ends at t_end at the latest (exactly at t_end when it reaches
// it), ODE_EHMIN when the step size falls below rounding level, ODE_ERHS when f keeps failing.
int ode_dopri5_step(struct ode_dopri5 *s, fs_real t_end);

// Returns nothing; writes the 4th-order dense-output state at t in [t_old, t] of the last step.
void ode_dopri5_dense(const struct ode_dopri5 *s, fs_real t, fs_real *x);

// Caller-owned DOP853 state: the last accepted step [t_old, t], its stages (for the dense output, whose three
// extra stages are evaluated on the first request within a step) and its dense-output coefficients.
struct ode_dop853 {
    struct ode_params p;
    ode_rhs_fn f;
    void *ctx;
    size_t n;
    fs_real t, t_old, h;
    fs_real x[ODE_MAX_DIM];
    fs_real k[16][ODE_MAX_DIM];     // stages 1..12 of the last step, k[12] = f(t, x), k[13..15] dense stages
    fs_real rcont[8][ODE_MAX_DIM];  // dense-output coefficients (rcont[4..7] once dense_ready)
    bool dense_ready;
    uint32_t steps, rejected, rhs_evals;
};

// Returns ODE_OK, ODE_EARGS for bad parameters or dimension, ODE_ERHS when f fails at (t, x), or ODE_EHMIN when
// the first step size underflows to 0; starts a DOP853 integration at (t, x) and picks the first step size.
int ode_dop853_init(struct ode_dop853 *s, const struct ode_params *p, size_t n, ode_rhs_fn f, void *ctx, fs_real t,
                    const fs_real *x);

// Returns ODE_OK after one accepted step that ends at t_end at the latest (exactly at t_end when it reaches
// it), ODE_EHMIN when the step size falls below rounding level, ODE_ERHS when f keeps failing.
int ode_dop853_step(struct ode_dop853 *s, fs_real t_end);

// Returns ODE_OK, or ODE_ERHS when f fails at a dense-output stage; writes the 7th-order dense-output state
// at t in [t_old, t] of the last step (the first call within a step evaluates three more stages).
int ode_dop853_dense(struct ode_dop853 *s, fs_real t, fs_real *x);

// Returns nothing; writes the cubic Hermite interpolant of the last step at t in [t_old, t] (its end states
// and slopes, no evaluation of f; 4th order).
void ode_dop853_hermite(const struct ode_dop853 *s, fs_real t, fs_real *x);

// Returns 0, or the first nonzero value of f; advances x (dimension n <= ODE_MAX_DIM) by one classical
// RK4 step of size h from t.
int ode_rk4_step(ode_rhs_fn f, void *ctx, size_t n, fs_real t, fs_real h, fs_real *x);

#endif
