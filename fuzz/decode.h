// How the fuzz harnesses read their input: values decoded around a nominal, so that both the hostile corners
// (NaN, inf, denormals, any magnitude) and the normal domain near the nominal are explored.
//
// A value takes 9 bytes (a tag byte and 8 payload bytes). The tag picks raw IEEE bits, a special value, a
// scaled value of any magnitude, or a small perturbation of the nominal. An exhausted input yields the
// nominal, so that short inputs describe the nominal case.
#ifndef FUZZ_DECODE_H
#define FUZZ_DECODE_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

struct fz_reader {
    const uint8_t *p;
    size_t n;
};

// Returns a special value: 0, +-1, the smallest normal and denormal, the largest, inf, NaN, the defaults
// (the table fuzz/regressions/smc was recorded with: keep it as it is).
static inline double fz_special(uint64_t k)
{
    static const double specials[] = {
        0.0,     -0.0,     1.0,      -1.0,      DBL_MIN, -DBL_MIN, 4.9406564584124654e-324,
        DBL_MAX, -DBL_MAX, INFINITY, -INFINITY, NAN,     1e-300,   1e300,
        0.4,     1e-6,     5e-7,     0.02,      0.04};
    return specials[k % (sizeof specials / sizeof specials[0])];
}

// Returns the next value decoded around nominal (nominal itself when the input is exhausted).
static inline double fz_value(struct fz_reader *r, double nominal)
{
    uint8_t tag;
    uint64_t bits = 0;
    double x, u;
    if (r->n < 9)
        return nominal;
    tag = r->p[0];
    memcpy(&bits, r->p + 1, 8);
    r->p += 9;
    r->n -= 9;
    u = (double)(int64_t)bits / 9.2233720368547758e18;  // in [-1, 1]
    switch (tag & 3) {
    case 0: memcpy(&x, &bits, sizeof x); return x;
    case 1: return fz_special(bits);
    case 2:  // any sign and magnitude 10^-40 .. 10^40
        return u * pow(10.0, (double)((tag >> 2) % 81) - 40);
    default:  // relative perturbation of the nominal by up to 10^-((tag >> 2) % 16)
        return nominal * (1 + u * pow(10.0, -(double)((tag >> 2) % 16))) + u * 1e-9;
    }
}

// Returns the next byte (dflt when the input is exhausted).
static inline uint8_t fz_byte(struct fz_reader *r, uint8_t dflt)
{
    if (r->n < 1)
        return dflt;
    r->n--;
    return *r->p++;
}

// Returns the next 4 bytes as an unsigned integer (dflt when fewer are left).
static inline uint32_t fz_u32(struct fz_reader *r, uint32_t dflt)
{
    uint32_t x;
    if (r->n < 4)
        return dflt;
    memcpy(&x, r->p, 4);
    r->p += 4;
    r->n -= 4;
    return x;
}

// Returns true when x is finite and > 0.
static inline int fz_positive(double x)
{
    return isfinite(x) && x > 0;
}

#endif
