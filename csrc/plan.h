// Plans of the flat outputs (rho, theta): the paper's rest-to-rest psi, eqs. (15)-(21), or a segment table.
#ifndef FS_PLAN_H
#define FS_PLAN_H

#include <stdbool.h>
#include "fs_real.h"

// cffi:begin

// Flat flag layout used by plan_eval and the flat maps.
enum { PLAN_RHO, PLAN_DRHO, PLAN_THETA, PLAN_DTHETA, PLAN_DDTHETA, PLAN_DDDTHETA, PLAN_FLAG_LEN };

// A piecewise-polynomial table of the flat outputs (trajectory.h).
struct traj;

// The one plan every controller tracks (flatstep.plan.protocol.Plan.c_plan). With traj NULL:
// theta*(t) = theta1 + psi(t) (theta2 - theta1), rho*(t) = rho1 + psi(t) (rho2 - rho1), eqs. (16), (18).
// With traj set, the flag is that table's (traj_flag) and the fields above it are its end points: where the move
// starts and ends (t0 = breaks[0], tf = breaks[n]) and the values held outside it (a hold's target).
struct plan {
    fs_real theta1, theta2;   // start and end angle [rad]
    fs_real rho1, rho2;       // start and end current magnitude [A], > 0
    fs_real t0, tf;           // start and end of the move [s], tf > t0
    const struct traj *traj;  // NULL: psi; else a table in caller-owned memory outliving every user of the plan
};

// A plan ready to evaluate: the plan and the constants plan_flag needs, filled once by plan_init (caller-owned).
struct plan_coef {
    struct plan p;
    const struct traj *traj;         // p.traj (plan_init): NULL for psi of p, else plan_flag evaluates this table
    fs_real Tk[4];                   // (tf - t0)^k, k = 0..3, by pow once here so that plan_flag calls no pow
    fs_real dtheta, drho;            // theta2 - theta1, rho2 - rho1
    fs_real rest[2][PLAN_FLAG_LEN];  // the flag held up to t0 and from tf on
};

// Returns true when every field is finite, the angles and currents at most FS_REAL_MAX / 4 in magnitude (the flag
// then stays finite), rho1, rho2 > 0 and tf > t0 with (tf - t0)^3 > 0, and a table, if set, is traj_valid.
bool plan_valid(const struct plan *p);

// Returns plan_valid(p); fills c from p either way (for tf <= t0 plan_flag then holds the start values, and
// a derivative whose (tf - t0)^k underflows evaluates to 0).
bool plan_init(struct plan_coef *c, const struct plan *p);

// Returns true while the move runs (t0 < t < tf); writes the flag (rho, rho', theta, theta', theta'',
// theta''') at time t, exactly as flatstep.plan.RestToRest.flag: one pass over the four psi polynomials.
// With a table (c->traj, from p.traj), returns and writes traj_flag(c->traj, t, flag) instead.
bool plan_flag(const struct plan_coef *c, fs_real t, fs_real flag[PLAN_FLAG_LEN]);

// Returns the order-th time derivative (0..3) of psi(t, t0, tf) of eq. (17): held at 0 before t0 and at 1
// after tf, derivatives 0 outside the open interval (t0, tf); 0 for an order out of range, for tf <= t0
// and for a span so short that (tf - t0)^order underflows.
fs_real plan_psi(fs_real t, fs_real t0, fs_real tf, int order);

// Returns plan_flag's value for a plan used once (plan_init on the stack, then plan_flag); writes the flag.
bool plan_eval(const struct plan *p, fs_real t, fs_real flag[PLAN_FLAG_LEN]);

// cffi:end
#endif
