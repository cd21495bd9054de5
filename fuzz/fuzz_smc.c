// libFuzzer harness for smc_init/smc_step: any parameters and measurement give finite, bounded voltages.
//
// Input: a header byte, then 9-byte values (tag byte + 8 payload bytes). The tag picks raw IEEE bits (NaN,
// inf, denormals...), a special value, a scaled value of any magnitude, or a small perturbation of the
// nominal (the paper's parameters, the planned state at t), so both the hostile corners and the law's
// normal domain are explored. Violations abort (libFuzzer reports them as crashes).
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "flat.h"
#include "smc.h"

static const double specials[] = {0.0, -0.0, 1.0, -1.0, DBL_MIN, -DBL_MIN, 4.9406564584124654e-324, DBL_MAX,
                                  -DBL_MAX, INFINITY, -INFINITY, NAN, 1e-300, 1e300, 0.4, 1e-6, 5e-7, 0.02, 0.04};

struct reader {
    const uint8_t *p;
    size_t n;
};

// Returns the next value decoded around nominal (nominal itself when the input is exhausted).
static double next(struct reader *r, double nominal)
{
    uint8_t tag;
    uint64_t bits = 0;
    double x;
    if (r->n < 9)
        return nominal;
    tag = r->p[0];
    memcpy(&bits, r->p + 1, 8);
    r->p += 9;
    r->n -= 9;
    switch (tag & 3) {
    case 0:
        memcpy(&x, &bits, sizeof x);
        return x;
    case 1:
        return specials[bits % (sizeof specials / sizeof specials[0])];
    case 2:  // any sign and magnitude 10^-40 .. 10^40
        return ((double)(int64_t)bits / 9.2233720368547758e18) * pow(10.0, (double)((tag >> 2) % 81) - 40);
    default:  // relative perturbation of the nominal by up to 10^-(tag >> 2 % 16)
        return nominal * (1 + ((double)(int64_t)bits / 9.2233720368547758e18) * pow(10.0, -(double)((tag >> 2) % 16)))
             + ((double)(int64_t)bits / 9.2233720368547758e18) * 1e-9;
    }
}

// Prints the broken guarantee with the step's inputs and outputs, then aborts (libFuzzer saves the input).
#define FAIL(what)                                                                                       \
    do {                                                                                                 \
        fprintf(stderr, "smc_step: %s\n  meas %d t %.17g y %.17g %.17g %.17g %.17g %.17g\n  -> status %u "  \
                "v %.17g %.17g (v_limit %.17g)\n", what, p.measurement, t, y[0], y[1], y[2], y[3], y[4],   \
                (unsigned)st, v[0], v[1], s.p.v_limit);                                                   \
        abort();                                                                                         \
    } while (0)

// Returns 0 (libFuzzer's convention); aborts when an smc_step guarantee is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct reader r = {data, size};
    struct smc_params p;
    struct smc s, s2;
    struct smc_terms w;
    double t, y[5], v[2], v2[2], x[4], vff[2], f[PLAN_FLAG_LEN], norm;
    uint32_t st, st2;
    uint8_t head;
    int k, nonfinite = 0;
    if (size < 1)
        return 0;
    head = data[0];
    r.p++, r.n--;
    smc_params_default(&p);
    p.measurement = head & 1 ? SMC_MODEL : SMC_IDEAL;
    if (head & 2) {  // fuzz the parameters as well
        p.motor.R = next(&r, p.motor.R), p.motor.L = next(&r, p.motor.L), p.motor.Km = next(&r, p.motor.Km);
        p.motor.J = next(&r, p.motor.J), p.motor.B = next(&r, p.motor.B);
        p.motor.Nr = (int)(signed char)(r.n ? (r.p++, r.n--, r.p[-1]) : 50);
        p.plan.theta1 = next(&r, 0), p.plan.theta2 = next(&r, 0.02), p.plan.rho1 = next(&r, 0.4);
        p.plan.rho2 = next(&r, 0.4), p.plan.t0 = next(&r, 0.02), p.plan.tf = next(&r, 0.04);
        p.gains.W1 = next(&r, 100), p.gains.W2 = next(&r, 100), p.gains.eps1 = next(&r, 0.005);
        p.gains.eps2 = next(&r, 0.005), p.gains.xi = next(&r, 0.8), p.gains.wn = next(&r, 10);
        p.v_limit = next(&r, 1e3), p.rho_min = next(&r, 1e-6);
    }
    if (head & 4)
        p.measurement = (int)(head >> 3);  // mostly invalid modes: smc_init must refuse them
    else if (head & 8)  // the detent hold from tf on
        p.gains.hold_damping = head & 2 ? next(&r, 0.7) : 0.7;
    if (smc_init(&s, &p) != SMC_PARAMS_OK)
        return 0;
    t = next(&r, 0.03);
    // Nominal measurement: the planned state at t (0 where the flat maps are undefined there).
    plan_eval(&s.p.plan, isfinite(t) ? t : 0.0, f);
    flat_to_state(&s.p.motor, f, 0, x, vff);
    for (k = 0; k < 4; k++)
        y[k] = next(&r, x[k]);
    y[4] = next(&r, f[PLAN_DDTHETA]);
    s2 = s;
    st = smc_step(&s, t, y, v);
    norm = hypot(v[0], v[1]);
    for (k = 0; k < (p.measurement == SMC_IDEAL ? 5 : 4); k++)
        nonfinite |= !isfinite(y[k]);
    nonfinite |= !isfinite(t);
    if (!isfinite(v[0]) || !isfinite(v[1]))
        FAIL("a non-finite voltage");
    if (!(norm <= s.p.v_limit * (1 + 4 * DBL_EPSILON)))
        FAIL("beyond the configured limit");
    if (st != SMC_OK && st != SMC_NONFINITE && st != SMC_RHO && st != SMC_SQRT && st != SMC_OVERFLOW
        && st != SMC_SATURATED)
        FAIL("not exactly one documented status");
    if ((st & ~(uint32_t)SMC_SATURATED) && (v[0] != 0 || v[1] != 0))
        FAIL("a fault that does not output 0 V");
    if ((st == SMC_NONFINITE) != (nonfinite != 0))
        FAIL("non-finite input reported iff present");
    if (!(s.status_seen & st) && st != SMC_OK)
        FAIL("status_seen misses the status");
    st2 = smc_step(&s2, t, y, v2);  // no hidden state: the same call gives the same bits
    if (st2 != st || memcmp(v, v2, sizeof v) != 0)
        FAIL("the same call gave different results");
    st2 = smc_step_terms(&s2, t, y, NULL, v2, &w);  // the variant that reports its intermediate values
    if (st2 != st || memcmp(v, v2, sizeof v) != 0)
        FAIL("smc_step_terms differs from smc_step");
    if ((w.have == 0) != (st == SMC_NONFINITE))
        FAIL("smc_step_terms: no intermediate values iff the inputs are non-finite");
    return 0;
}
