// The field-weakening planner's envelope: at each speed the largest and the smallest torque current over the
// d current, where the current disc meets the bus disc (flatstep.plan.time_optimal_dq_envelope, operation for
// operation).
#include "time_optimal_dq_stages.h"

// Returns true when the discs meet at speed w and writes (i_d+, i_q+, i_d-, i_q-) into c.
static bool best_currents(const struct motor_params *m, fs_real w, fs_real v, fs_real i_max, fs_real c[4])
{
    fs_real x = (fs_real)m->Nr * w * m->L, e = m->Km * w, z2, cd, cq, r, dist, a, h, ux, uy, p1[2], p2[2];
    const fs_real *hi, *lo;
    z2 = m->R * m->R + x * x;
    if (!(z2 > 0))  // R^2 + (Nr w L)^2 underflows: no impedance to divide by, no envelope
        return false;
    cd = -e * x / z2, cq = -e * m->R / z2, r = v / fs_sqrt(z2);
    dist = fs_hypot(cd, cq);
    if (!(dist <= i_max + r))
        return false;
    if (dist <= fs_fabs(i_max - r) || !(dist > 0)) {  // one disc inside the other (or the same disc)
        if (r <= i_max)
            c[0] = cd, c[1] = cq + r, c[2] = cd, c[3] = cq - r;
        else
            c[0] = 0, c[1] = i_max, c[2] = 0, c[3] = -i_max;
        return true;
    }
    // the circles cross at two points: a along the line of centres, h across it
    a = (i_max * i_max - r * r + dist * dist) / (2 * dist);
    h = fs_sqrt(fs_max(i_max * i_max - a * a, 0));
    ux = cd / dist, uy = cq / dist;
    p1[0] = a * ux - h * uy, p1[1] = a * uy + h * ux;
    p2[0] = a * ux + h * uy, p2[1] = a * uy - h * ux;
    hi = p2[1] > p1[1] ? p2 : p1;  // the first of equals, as Python's max and min
    lo = p2[1] < p1[1] ? p2 : p1;
    c[0] = hi[0], c[1] = hi[1], c[2] = lo[0], c[3] = lo[1];
    if ((cd - 0) * (cd - 0) + (cq - i_max) * (cq - i_max) <= r * r)  // the current's top inside the bus disc
        c[0] = 0, c[1] = i_max;
    else if (cd * cd + (cq + r) * (cq + r) <= i_max * i_max)  // the bus disc's top inside the current disc
        c[0] = cd, c[1] = cq + r;
    if (cd * cd + (cq + i_max) * (cq + i_max) <= r * r)
        c[2] = 0, c[3] = -i_max;
    else if (cd * cd + (cq - r) * (cq - r) <= i_max * i_max)
        c[2] = cd, c[3] = cq - r;
    return true;
}

// Returns the largest acceleration at speed w [rad/s^2] (-inf where the speed cannot be held).
static fs_real accel(const struct motor_params *m, fs_real w, fs_real v, fs_real i_max)
{
    fs_real c[4];
    if (!best_currents(m, w, v, i_max, c))
        return -(fs_real)INFINITY;
    return (m->Km * c[1] - m->B * w) / m->J;
}

bool tod_envelope(const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap, struct to_work *w, fs_real *idp,
                  fs_real *idm)
{
    fs_real top = cap, lo = 0, hi = cap, mid, c[4];
    size_t i;
    int k;
    if (!(accel(m, 0, v, i_max) > 0))
        return false;
    if (!(accel(m, cap, v, i_max) > 0)) {  // the speed where no torque is left, by bisection
        for (k = 0; k < TOD_PROBE; k++) {
            mid = FS_C(0.5) * (lo + hi);
            if (accel(m, mid, v, i_max) > 0)
                lo = mid;
            else
                hi = mid;
        }
        top = lo;
    }
    for (i = 0; i < TO_GRID; i++) {
        w->omega[i] = top * (fs_real)i / (fs_real)(TO_GRID - 1);
        if (!best_currents(m, w->omega[i], v, i_max, c))
            return false;
        idp[i] = c[0], idm[i] = c[2];
        w->ap[i] = (m->Km * c[1] - m->B * w->omega[i]) / m->J;
        w->am[i] = (m->Km * c[3] - m->B * w->omega[i]) / m->J;
    }
    w->ap[TO_GRID - 1] = fs_max(w->ap[TO_GRID - 1], FS_C(1e-12) * w->ap[0]);  // the top speed is reached
    w->am[TO_GRID - 1] = fs_min(w->am[TO_GRID - 1], FS_C(1e-12) * w->am[0]);  // and left in finite time
    for (i = 0; i < TO_GRID; i++)
        if (!(fs_isfinite(w->ap[i]) && fs_isfinite(w->am[i]) && w->ap[i] != 0 && w->am[i] != 0))
            return false;
    w->integrals = false;
    return w->omega[TO_GRID - 1] > 0;
}
