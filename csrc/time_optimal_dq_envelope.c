// The field-weakening planner's envelope: at a speed, the largest and the smallest torque current over the d
// current, where the current disc meets the bus disc (flatstep.plan.time_optimal_dq_envelope, operation for
// operation).
#include "time_optimal_dq_stages.h"

bool tod_best_currents(const struct motor_params *m, fs_real w, fs_real v, fs_real i_max, fs_real c[4])
{
    fs_real x = (fs_real)m->Nr * w * m->L, e = m->Km * w, z2, cd, cq, r, dist, a, h, ux, uy, p1[2], p2[2];
    const fs_real *hi, *lo;
    z2 = m->R * m->R + x * x;
    if (!(z2 > 0))  // R^2 + (Nr w L)^2 underflows: no impedance to divide by, no envelope
        return false;
    cd = -e * x / z2, cq = -e * m->R / z2, r = v / fs_sqrt(z2);
    dist = fs_sqrt(cd * cd + cq * cq);
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
    if (!tod_best_currents(m, w, v, i_max, c))
        return -(fs_real)INFINITY;
    return (m->Km * c[1] - m->B * w) / m->J;
}

fs_real tod_top_speed(const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap)
{
    fs_real lo = 0, hi = cap, mid;
    int k;
    if (accel(m, cap, v, i_max) > 0)
        return cap;
    for (k = 0; k < TOD_PROBE; k++) {
        mid = FS_C(0.5) * (lo + hi);
        if (accel(m, mid, v, i_max) > 0)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}
