// The a-b model of the PM stepper, eq. (1), evaluated in the same operation order as flatstep.motor.
#include "motor.h"

#ifndef FS_SINGLE
// fdlibm's minimax coefficients for sin and cos on [-pi/4, pi/4] (__kernel_sin, __kernel_cos), and pi/2 in
// three parts whose first two have trailing zero bits, so n * part is exact for |n| < 2^16 (Cody-Waite).
static const double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                    S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                    S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
static const double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                    C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                    C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
static const double INV_PIO2 = 6.36619772367581382433e-01, PIO2_1 = 1.57079632673412561417e+00,
                    PIO2_2 = 6.07710050630396597660e-11, PIO2_3 = 2.02226624871116645580e-21;
#endif

// Returns nothing; writes sin x and cos x (within 2 ulp of libm's; libm itself beyond |x| = 1e5 and in float).
void motor_sincos(fs_real x, fs_real *s, fs_real *c)
{
#ifndef FS_SINGLE
    long n;
    fs_real r, z, hz, w, sr, cr;
    if (fs_fabs(x) < 1e5) {
        // x = n pi/2 + r with |r| <= pi/4; then the quadrant n mod 4 permutes and negates sin r, cos r.
        n = (long)(x * INV_PIO2 + (x >= 0 ? 0.5 : -0.5));
        r = ((x - (fs_real)n * PIO2_1) - (fs_real)n * PIO2_2) - (fs_real)n * PIO2_3;
        z = r * r;
        sr = r + z * r * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
        hz = 0.5 * z;
        w = 1 - hz;
        cr = w + (((1 - w) - hz) + z * z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6))))));
        switch (n & 3) {
        case 0: *s = sr, *c = cr; return;
        case 1: *s = cr, *c = -sr; return;
        case 2: *s = -sr, *c = -cr; return;
        default: *s = -cr, *c = sr; return;
        }
    }
#endif
    *s = fs_sin(x);
    *c = fs_cos(x);
}

// Returns true when every parameter is finite and in range (R, L, Km, J > 0, B >= 0, Nr >= 1).
bool motor_params_valid(const struct motor_params *m)
{
    return fs_isfinite(m->R) && m->R > 0 && fs_isfinite(m->L) && m->L > 0 && fs_isfinite(m->Km)
        && m->Km > 0 && fs_isfinite(m->J) && m->J > 0 && fs_isfinite(m->B) && m->B >= 0 && m->Nr >= 1;
}

// Returns the electromagnetic torque Km (ib cos Nr theta - ia sin Nr theta) [N m] at state x.
fs_real motor_torque(const struct motor_params *m, const fs_real x[4])
{
    fs_real s, c;
    motor_sincos(m->Nr * x[3], &s, &c);
    return m->Km * (x[1] * c - x[0] * s);
}

// Returns the shaft acceleration (torque - B omega - load) / J [rad/s^2] at state x.
fs_real motor_acceleration(const struct motor_params *m, const fs_real x[4], fs_real load)
{
    return (motor_torque(m, x) - m->B * x[2] - load) / m->J;
}

// Returns nothing; writes dx = f(x, v) of eq. (1) with a load torque on the shaft.
void motor_rhs(const struct motor_params *m, const fs_real x[4], const fs_real v[2], fs_real load,
               fs_real dx[4])
{
    fs_real s, c;
    motor_sincos(m->Nr * x[3], &s, &c);
    dx[0] = (v[0] - m->R * x[0] + m->Km * x[2] * s) / m->L;
    dx[1] = (v[1] - m->R * x[1] - m->Km * x[2] * c) / m->L;
    dx[2] = (m->Km * (x[1] * c - x[0] * s) - m->B * x[2] - load) / m->J;
    dx[3] = x[2];
}
