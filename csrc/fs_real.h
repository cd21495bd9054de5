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
#define FS_REAL_MAX 1.7976931348623157e+308
#define FS_REAL_EPSILON 2.220446049250313e-16
#endif

// isfinite is a type-generic macro in C99 <math.h>; this names it once for the whole core.
#define fs_isfinite(x) isfinite(x)

#endif
