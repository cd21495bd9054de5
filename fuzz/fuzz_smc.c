// libFuzzer harness for smc_init/smc_step: any parameters and measurement give finite, bounded voltages.
//
// Input: a header byte, then values decoded by fuzz/decode.h around the nominal (the paper's parameters, the
// planned state at t). Violations abort (libFuzzer reports them as crashes).
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "decode.h"
#include "flat.h"
#include "smc.h"

// Prints the broken guarantee with the step's inputs and outputs, then aborts (libFuzzer saves the input).
#define FAIL(what)                                                                                            \
    do {                                                                                                      \
        fprintf(stderr,                                                                                       \
                "smc_step: %s\n  meas %d t %.17g y %.17g %.17g %.17g %.17g %.17g\n  -> status %u "            \
                "v %.17g %.17g (v_limit %.17g)\n",                                                            \
                what, p.measurement, t, y[0], y[1], y[2], y[3], y[4], (unsigned)st, v[0], v[1], s.p.v_limit); \
        abort();                                                                                              \
    } while (0)

// Returns 0 (libFuzzer's convention); aborts when an smc_step guarantee is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct fz_reader r = {data, size};
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
        p.motor.R = fz_value(&r, p.motor.R), p.motor.L = fz_value(&r, p.motor.L), p.motor.Km = fz_value(&r, p.motor.Km);
        p.motor.J = fz_value(&r, p.motor.J), p.motor.B = fz_value(&r, p.motor.B);
        p.motor.Nr = (int)(signed char)fz_byte(&r, 50);
        p.plan.theta1 = fz_value(&r, 0), p.plan.theta2 = fz_value(&r, 0.02), p.plan.rho1 = fz_value(&r, 0.4);
        p.plan.rho2 = fz_value(&r, 0.4), p.plan.t0 = fz_value(&r, 0.02), p.plan.tf = fz_value(&r, 0.04);
        p.gains.W1 = fz_value(&r, 100), p.gains.W2 = fz_value(&r, 100), p.gains.eps1 = fz_value(&r, 0.005);
        p.gains.eps2 = fz_value(&r, 0.005), p.gains.xi = fz_value(&r, 0.8), p.gains.wn = fz_value(&r, 10);
        p.v_limit = fz_value(&r, 1e3), p.rho_min = fz_value(&r, 1e-6);
    }
    if (head & 4)
        p.measurement = (int)(head >> 3);  // mostly invalid modes: smc_init must refuse them
    else if (head & 8)
        p.gains.hold_damping = head & 2 ? fz_value(&r, 0.7) : 0.7;  // the detent hold from tf on
    if (smc_init(&s, &p) != SMC_PARAMS_OK)
        return 0;
    t = fz_value(&r, 0.03);
    // Nominal measurement: the planned state at t (0 where the flat maps are undefined there).
    plan_eval(&s.p.plan, isfinite(t) ? t : 0.0, f);
    flat_to_state(&s.p.motor, f, 0, x, vff);
    for (k = 0; k < 4; k++)
        y[k] = fz_value(&r, x[k]);
    y[4] = fz_value(&r, f[PLAN_DDTHETA]);
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
