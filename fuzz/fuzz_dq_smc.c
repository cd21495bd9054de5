// libFuzzer harness for dq_smc_init/dq_smc_step and arrays_controller_step: any parameters (motor, plan, d current,
// gains, torque model, measurement, voltage limit, integral action, adaptation, angle advance) give a documented
// init code, and then, over a sequence of steps at any times and measurements, finite voltages within v_limit,
// documented status bits, 0 V on a fault, CTRL_NONFINITE on a non-finite input; arrays_controller_step on the same
// sequence from the same state gives the same bits.
//
// Input: a header byte (1 model measurement; 2 .. 64 the groups decoded hostile: motor, plan, d current, gains,
// torque model, integral action; 128 adaptation), an options byte (1 v_limit, 2 any measurement mode, 4 the angle
// advance around 25 us), the groups' values around dq_smc_params_default (integral and adaptation around ki 50,
// rate 100 at 200 us and 24 V), the number of steps and each step's time and measurement around the planned state
// (fuzz/decode.h).
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include "arrays.h"
#include "dq_smc.h"
#include "flat.h"
#include "laws.h"

#define STEPS_MAX 8

// Returns nothing; decodes the torque model field by field around t.
static void decode_torques(struct fz_reader *r, struct torque_model *t)
{
    uint8_t b;
    t->detent_torque = fz_value(r, 2e-3);
    b = fz_byte(r, 4);
    t->detent_harmonic = b & 0x80 ? fz_u32(r, 4) : b % 9;
    t->detent_phase = fz_value(r, t->detent_phase), t->coulomb_torque = fz_value(r, 1e-3);
    t->coulomb_speed = fz_value(r, t->coulomb_speed), t->load = fz_value(r, 5e-3);
    t->load_step = fz_value(r, 1e-3), t->load_t0 = fz_value(r, t->load_t0), t->load_tf = fz_value(r, t->load_tf);
}

// Returns nothing; decodes the parameters around dq_smc_params_default, each group hostile by its header bit.
static void decode_params(struct fz_reader *r, uint8_t head, uint8_t opts, struct dq_smc_params *p)
{
    struct dq_smc_current *c = &p->current;
    struct smc_gains *g = &p->gains;
    dq_smc_params_default(p);
    p->measurement = head & 1 ? SMC_MODEL : SMC_IDEAL;
    fz_motor(r, head & 2, &p->motor);
    fz_plan(r, head & 4, p->plan.t0, p->plan.tf, &p->plan);
    if (head & 8) {
        c->i_d1 = fz_value(r, 0), c->i_d2 = fz_value(r, -0.1), c->t0 = fz_value(r, 0.02), c->tf = fz_value(r, 0.04);
        c->weakening = fz_value(r, 1e-3), c->weakening_speed = fz_value(r, 50);
    }
    if (head & 16) {
        g->W1 = fz_value(r, g->W1), g->W2 = fz_value(r, g->W2), g->eps1 = fz_value(r, g->eps1);
        g->eps2 = fz_value(r, g->eps2), g->xi = fz_value(r, g->xi), g->wn = fz_value(r, g->wn);
        g->hold_damping = fz_value(r, 0);
    }
    if (head & 32)
        decode_torques(r, &p->torques);
    if (head & 64)
        p->integral.ki = fz_value(r, 50), p->integral.Ts = fz_value(r, 2e-4), p->integral.v_hold = fz_value(r, 24);
    if (head & 128) {
        p->adapt.rate = fz_value(r, 100), p->adapt.phi0 = fz_value(r, 10), p->adapt.range = fz_value(r, 0.2);
        p->adapt.Ts = fz_value(r, 2e-4), p->adapt.v_hold = fz_value(r, 24);
    }
    if (opts & 1)
        p->v_limit = fz_value(r, p->v_limit);
    if (opts & 4)
        p->advance = fz_value(r, 2.5e-5);
    if (opts & 2)
        p->measurement = (int)fz_u32(r, SMC_IDEAL);  // mostly invalid: dq_smc_init must refuse it
}

// Returns 0 (libFuzzer's convention); aborts when a contract of dq_smc.h or arrays.h is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct dq_smc s, s0;
    struct fz_reader r = {data, size};
    struct dq_smc_params p;
    struct controller c;
    uint8_t head = fz_byte(&r, 0), opts = fz_byte(&r, 0);
    double t[STEPS_MAX], y[STEPS_MAX * 5], v[2], va[STEPS_MAX * 2], f[PLAN_FLAG_LEN], x[4], vff[2], lim;
    uint32_t st[STEPS_MAX], sa[STEPS_MAX], or_all = 0, or_arr;
    size_t n, k, j;
    bool nonfinite;
    int rc;
    decode_params(&r, head, opts, &p);
    rc = dq_smc_init(&s, &p);
    if (rc < DQ_SMC_PARAMS_OK || rc > DQ_SMC_EADVANCE)
        FZ_FAIL("dq_smc_init returned %d, not a dq_smc_param_error", rc);
    if (rc != DQ_SMC_PARAMS_OK && !(head & 0xfe) && !(opts & 7))
        FZ_FAIL("dq_smc_init refused the defaults (%d)", rc);
    if (rc != DQ_SMC_PARAMS_OK)
        return 0;
    s0 = s;
    n = fz_byte(&r, 4) % (STEPS_MAX + 1);
    lim = s.p.v_limit;
    for (k = 0; k < n; k++) {
        t[k] = fz_value(&r, 0.02 + 0.005 * (double)k);
        plan_eval(&s.p.plan, isfinite(t[k]) ? t[k] : 0.0, f);
        flat_to_state(&s.p.motor, f, 0, x, vff);
        for (j = 0; j < 4; j++)
            y[5 * k + j] = fz_value(&r, x[j]);
        y[5 * k + 4] = fz_value(&r, f[PLAN_DDTHETA]);
    }
    for (k = 0; k < n; k++) {
        st[k] = dq_smc_step(&s, t[k], y + 5 * k, v);
        va[2 * k] = v[0], va[2 * k + 1] = v[1];
        or_all |= st[k];
        nonfinite = !isfinite(t[k]);
        for (j = 0; j < (s.p.measurement == SMC_IDEAL ? 5u : 4u); j++)
            nonfinite |= !isfinite(y[5 * k + j]);
        if (!isfinite(v[0]) || !isfinite(v[1]) || !(hypot(v[0], v[1]) <= lim * (1 + 4 * DBL_EPSILON)))
            FZ_FAIL("dq_smc_step: v = (%g, %g) beyond v_limit %g or not finite", v[0], v[1], lim);
        if (st[k] & ~(uint32_t)(CTRL_FAULTS | CTRL_SATURATED))
            FZ_FAIL("dq_smc_step: undocumented status %u", (unsigned)st[k]);
        if ((st[k] & CTRL_FAULTS) && (v[0] != 0 || v[1] != 0))
            FZ_FAIL("dq_smc_step: status %u with v = (%g, %g), not 0", (unsigned)st[k], v[0], v[1]);
        if (nonfinite && !(st[k] & CTRL_NONFINITE))
            FZ_FAIL("dq_smc_step: a non-finite input without CTRL_NONFINITE (status %u)", (unsigned)st[k]);
        if ((s.status_seen & st[k]) != st[k])
            FZ_FAIL("dq_smc_step: status_seen misses the status");
    }
    // the same sequence through the array wrapper, from the state after init
    dq_smc_controller(&s0, &c);
    {
        double *vo = malloc((n ? n : 1) * 2 * sizeof *vo);  // exactly n rows: ASan sees a write past them
        if (!vo)
            return 0;
        or_arr = arrays_controller_step(&c, t, y, n, vo, sa);
        if (or_arr != or_all || memcmp(sa, st, n * sizeof *st) != 0 || memcmp(vo, va, n * 2 * sizeof *vo) != 0)
            FZ_FAIL("arrays_controller_step differs from dq_smc_step (status %u, %u)", (unsigned)or_arr,
                    (unsigned)or_all);
        free(vo);
    }
    return 0;
}
