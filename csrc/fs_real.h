// Precision typedef and math wrappers shared by every module (double by default, float with -DFS_SINGLE).
#ifndef FS_REAL_H
#define FS_REAL_H

#include <math.h>

#ifdef FS_SINGLE
typedef float fs_real;
#define FS_C(x) x##f
#define fs_sin sinf
#define fs_cos cosf
#define fs_sqrt sqrtf
#define fs_atan2 atan2f
#define fs_acos acosf
#define fs_hypot hypotf
#define fs_fabs fabsf
#define fs_pow powf
#define fs_rint rintf
#define fs_tanh tanhf
#define FS_REAL_MAX 3.402823466e+38f
#define FS_REAL_EPSILON 1.1920928955078125e-07f
#else
typedef double fs_real;
#define FS_C(x) x
#define fs_sin sin
#define fs_cos cos
#define fs_sqrt sqrt
#define fs_atan2 atan2
#define fs_acos acos
#define fs_hypot hypot
#define fs_fabs fabs
#define fs_pow pow
#define fs_rint rint
#define fs_tanh tanh
#define FS_REAL_MAX 1.7976931348623157e+308
#define FS_REAL_EPSILON 2.220446049250313e-16
#endif

// Returns nothing; writes sin x and cos x, within 2 ulp of libm's (libm itself beyond |x| = 1e5 and in float):
// inline, so that the plant's and the controller's Nr theta cost no call.
static inline void fs_sincos(fs_real x, fs_real *s, fs_real *c)
{
#ifndef FS_SINGLE
    // fdlibm's minimax coefficients for sin and cos on [-pi/4, pi/4] (__kernel_sin, __kernel_cos), and pi/2 in
    // three parts whose first two end in zero bits, so n * part is exact for |n| < 2^16 (Cody-Waite).
    static const fs_real S[6] = {-1.66666666666666324348e-01, 8.33333333332248946124e-03,  -1.98412698298579493134e-04,
                                 2.75573137070700676789e-06,  -2.50507602534068634195e-08, 1.58969099521155010221e-10};
    static const fs_real C[6] = {4.16666666666666019037e-02,  -1.38888888888741095749e-03, 2.48015872894767294178e-05,
                                 -2.75573143513906633035e-07, 2.08757232129817482790e-09,  -1.13596475577881948265e-11};
    static const fs_real inv_pio2 = 6.36619772367581382433e-01, pio2_1 = 1.57079632673412561417e+00,
                         pio2_2 = 6.07710050630396597660e-11, pio2_3 = 2.02226624871116645580e-21;
    long n;
    fs_real r, z, hz, w, sr, cr;
    if (fs_fabs(x) < 1e5) {
        // x = n pi/2 + r with |r| <= pi/4; then the quadrant n mod 4 permutes and negates sin r, cos r.
        n = (long)(x * inv_pio2 + (x >= 0 ? 0.5 : -0.5));
        r = ((x - (fs_real)n * pio2_1) - (fs_real)n * pio2_2) - (fs_real)n * pio2_3;
        z = r * r;
        sr = r + z * r * (S[0] + z * (S[1] + z * (S[2] + z * (S[3] + z * (S[4] + z * S[5])))));
        hz = 0.5 * z;
        w = 1 - hz;
        cr = w + (((1 - w) - hz) + z * z * (C[0] + z * (C[1] + z * (C[2] + z * (C[3] + z * (C[4] + z * C[5]))))));
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

// Returns the larger of a and b.
static inline fs_real fs_max(fs_real a, fs_real b)
{
    return a > b ? a : b;
}

// Returns the smaller of a and b.
static inline fs_real fs_min(fs_real a, fs_real b)
{
    return a < b ? a : b;
}

// isfinite is a type-generic macro in C99 <math.h>; this names it once for the whole core.
#define fs_isfinite(x) isfinite(x)

#endif
