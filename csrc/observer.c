// The observer update of flatstep.sampled in the same operation order (no BLAS reordering, no FMA).
#include "observer.h"

// Returns 0, or -1 when the order is not 2..4 or an entry is not finite (o is then left unusable).
int observer_init(struct observer *o, const struct observer_params *p)
{
    uint32_t i, j;
    if (p->order < 2 || p->order > OBSERVER_MAX_ORDER)
        return -1;
    for (i = 0; i < p->order; i++) {
        if (!fs_isfinite(p->Bd[i]) || !fs_isfinite(p->Lc[i]) || !fs_isfinite(p->Bf[i]))
            return -1;
        for (j = 0; j < p->order; j++)
            if (!fs_isfinite(p->Ad[i][j]))
                return -1;
    }
    o->p = *p;
    observer_reset(o);
    return 0;
}

// Returns nothing; forgets the estimate (the next correction starts from its angle at rest).
void observer_reset(struct observer *o)
{
    uint32_t i;
    for (i = 0; i < OBSERVER_MAX_ORDER; i++)
        o->x[i] = 0;
    o->started = false;
    o->torque_prev = 0;
    o->predicted = false;
}

// Returns nothing; corrects the estimate with the measured angle: x <- x + Lc (theta_m - x0), or, on the
// first call, x <- (theta_m, 0, ...).
void observer_correct(struct observer *o, fs_real theta_m)
{
    fs_real innovation = theta_m - o->x[0];
    uint32_t i;
    if (!o->started) {
        o->x[0] = theta_m;
        o->started = true;
        return;
    }
    for (i = 0; i < o->p.order; i++)
        o->x[i] = o->x[i] + o->p.Lc[i] * innovation;
}

// Returns nothing; corrects the estimate with the count edge crossed age seconds ago (observer.h).
void observer_correct_edge(struct observer *o, fs_real theta_edge, fs_real age)
{
    fs_real innovation = theta_edge - (o->x[0] - o->x[1] * age);
    uint32_t i;
    if (!o->started) {
        observer_correct(o, theta_edge);
        return;
    }
    for (i = 0; i < o->p.order; i++)
        o->x[i] = o->x[i] + o->p.Lc[i] * innovation;
}

// Returns nothing; predicts the next period's estimate under the torque Te from the period's start, ramping by its
// last change: x <- Ad x + Bd Te + Bf (Te - Te_prev) (Te_prev = Te on the first prediction).
void observer_predict(struct observer *o, fs_real torque)
{
    fs_real next[OBSERVER_MAX_ORDER], acc, change = o->predicted ? torque - o->torque_prev : 0;
    uint32_t i, j, n = o->p.order;
    for (i = 0; i < n; i++) {
        // left to right over the columns, as flatstep.sampled sums them
        acc = o->p.Ad[i][0] * o->x[0];
        for (j = 1; j < n; j++)
            acc = acc + o->p.Ad[i][j] * o->x[j];
        next[i] = acc + o->p.Bd[i] * torque + o->p.Bf[i] * change;
    }
    for (i = 0; i < n; i++)
        o->x[i] = next[i];
    o->torque_prev = torque;
    o->predicted = true;
}

// Returns the estimated load torque [N m] (0 for a speed-only observer of order 2).
fs_real observer_load(const struct observer *o)
{
    return o->p.order > 2 ? o->x[2] : 0;
}
