// libFuzzer harness for the segment tables of trajectory.h: traj_valid is its documented rule on any table
// (0 to 8 segments, any breaks and coefficients, missing arrays); on any table of at least one segment the lookups
// stay inside it (arrays of exactly the table's size on the heap, so ASan sees a read past them); on a valid one
// traj_segment finds t's segment, traj_flag holds the ends, traj_flag_seg (any guess), traj_flag_n, traj_theta and
// plan_flag on the table agree with traj_flag bit for bit, and moderate coefficients give finite flags.
//
// Input: a header byte (segments n = (head & 7) + bit 64, so 0 .. 8; 8: no theta array, 16: no breaks, 32:
// plan_flag), the breaks
// (around 0.01 i), the theta and rho rows (around a ramp at 0.4 A), the number of times and the times (spread over
// the table and 10 % beyond each end), the segment guesses (fuzz/decode.h).
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include "decode.h"
#include "laws.h"
#include "trajectory.h"

#define N_T_MAX 24

// Returns traj.h's rule for a valid table, written from the header.
static bool valid_rule(const struct traj *tr)
{
    size_t i, j;
    double ih;
    if (tr->n < 1 || !tr->breaks || !tr->theta || !tr->rho)
        return false;
    for (i = 0; i <= tr->n; i++)
        if (!isfinite(tr->breaks[i]) || (i > 0 && !(tr->breaks[i] > tr->breaks[i - 1])))
            return false;
    for (i = 0; i < tr->n; i++) {
        ih = 1 / (tr->breaks[i + 1] - tr->breaks[i]);
        if (!isfinite(tr->breaks[i + 1] - tr->breaks[i]) || !isfinite(ih * ih * ih * ih))
            return false;
    }
    for (j = 0; j < tr->n * TRAJ_NCOEF; j++)
        if (!isfinite(tr->theta[j]) || !isfinite(tr->rho[j]))
            return false;
    return true;
}

// Returns nothing; aborts unless the flag at t on the valid table tr keeps trajectory.h's guarantees.
static void check_time(const struct traj *tr, double t, size_t guess, bool moderate)
{
    double f[PLAN_FLAG_LEN], g[PLAN_FLAG_LEN], th;
    size_t i = traj_segment(tr, t), seg = guess, n = tr->n;
    bool in = traj_flag(tr, t, f), in2;
    int k;
    if (in != (t > tr->breaks[0] && t < tr->breaks[n]))
        FZ_FAIL("traj_flag returned %d at t = %.17g on [%.17g, %.17g]", in, t, tr->breaks[0], tr->breaks[n]);
    if (t >= tr->breaks[0] && t < tr->breaks[n] ? !(tr->breaks[i] <= t && t < tr->breaks[i + 1])
                                                : i != (t >= tr->breaks[n] ? n - 1 : 0))
        FZ_FAIL("traj_segment gave %zu at t = %.17g", i, t);
    in2 = traj_flag_seg(tr, t, &seg, g);
    if (in2 != in || memcmp(f, g, sizeof f) != 0 || (in && seg != i))
        FZ_FAIL("traj_flag_seg (guess %zu, segment %zu) differs from traj_flag at t = %.17g", guess, seg, t);
    for (k = 0; k < 4; k++) {
        th = traj_theta(tr, t, k);
        if (memcmp(&th, &f[PLAN_THETA + k], sizeof th) != 0)
            FZ_FAIL("traj_theta(order %d) = %.17g, traj_flag %.17g at t = %.17g", k, th, f[PLAN_THETA + k], t);
    }
    if (traj_theta(tr, t, 5) != 0 || traj_theta(tr, t, -1) != 0)
        FZ_FAIL("traj_theta: an order out of range is not 0");
    if (!in
        && (f[PLAN_DRHO] != 0 || f[PLAN_DTHETA] != 0 || f[PLAN_DDTHETA] != 0 || f[PLAN_DDDTHETA] != 0
            || traj_theta(tr, t, 4) != 0))
        FZ_FAIL("traj_flag: a derivative is not 0 outside the table at t = %.17g", t);
    if (!in && !(t >= tr->breaks[n])
        && (f[PLAN_THETA] != tr->theta[TRAJ_NCOEF - 1] || f[PLAN_RHO] != tr->rho[TRAJ_NCOEF - 1]))
        FZ_FAIL("traj_flag: the start is not held at t = %.17g", t);
    for (k = 0; moderate && k < PLAN_FLAG_LEN; k++)
        if (!isfinite(f[k]))
            FZ_FAIL("traj_flag: flag[%d] = %g at t = %.17g with coefficients within 1e20", k, f[k], t);
}

// Returns 0 (libFuzzer's convention); aborts when a contract of trajectory.h is broken.
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct fz_reader r = {data, size};
    uint8_t head = fz_byte(&r, 4);
    size_t n = (head & 7u) + ((head >> 6) & 1u), nt, i, k, guess[N_T_MAX];
    double *breaks = malloc((n + 1) * sizeof *breaks), *theta = malloc((n ? n : 1) * TRAJ_NCOEF * sizeof *theta);
    double *rho = malloc((n ? n : 1) * TRAJ_NCOEF * sizeof *rho), t[N_T_MAX], *flags = NULL, f[PLAN_FLAG_LEN], span;
    struct traj tr = {n, breaks, theta, rho};
    struct plan_coef c;
    struct plan p = {0, 1, 0.4, 0.4, 0, 1, NULL};
    bool valid, moderate = true;
    if (!breaks || !theta || !rho)
        goto done;
    for (i = 0; i <= n; i++)
        breaks[i] = fz_value(&r, 0.01 * (double)i);
    for (k = 0; k < n * TRAJ_NCOEF; k++) {  // nominal: theta a ramp of 0.1 rad per segment, rho 0.4 A
        theta[k] = fz_value(&r, k % TRAJ_NCOEF == 9 ? 0.1 : k % TRAJ_NCOEF == 10 ? 0.1 * (double)(k / TRAJ_NCOEF) : 0);
        rho[k] = fz_value(&r, k % TRAJ_NCOEF == 10 ? 0.4 : 0);
        moderate &= fabs(theta[k]) <= 1e20 && fabs(rho[k]) <= 1e20;
    }
    if (head & 8)
        tr.theta = NULL;
    if (head & 16)
        tr.breaks = NULL;
    valid = traj_valid(&tr);
    if (valid != valid_rule(&tr))
        FZ_FAIL("traj_valid returned %d on a table of %zu segments", valid, n);
    if (traj_valid(NULL))
        FZ_FAIL("traj_valid(NULL) is true");
    if (n < 1 || !tr.theta || !tr.breaks)
        goto done;
    nt = fz_byte(&r, 8) % (N_T_MAX + 1);
    span = isfinite(breaks[n] - breaks[0]) ? breaks[n] - breaks[0] : 1;
    for (k = 0; k < nt; k++) {
        t[k] = fz_value(&r, breaks[0] + span * (-0.1 + 1.2 * (double)k / (double)(nt > 1 ? nt - 1 : 1)));
        guess[k] = fz_byte(&r, 0) & 0x80 ? fz_u32(&r, 0) : (size_t)fz_byte(&r, 0) % (n + 2);
    }
    for (k = 0; k < nt; k++) {  // any table of at least one segment: lookups stay inside (ASan)
        size_t seg = guess[k];
        bool in = traj_flag_seg(&tr, t[k], &seg, f);
        if (traj_segment(&tr, t[k]) >= n || (in && seg >= n))
            FZ_FAIL("a segment index past the table at t = %.17g", t[k]);
        traj_theta(&tr, t[k], (int)(k % 6));
    }
    if (!valid)
        goto done;
    for (k = 0; k < nt; k++)
        check_time(&tr, t[k], guess[k], moderate);
    flags = malloc((nt ? nt : 1) * PLAN_FLAG_LEN * sizeof *flags);
    if (!flags)
        goto done;
    traj_flag_n(&tr, t, nt, flags);
    for (k = 0; k < nt; k++) {
        traj_flag(&tr, t[k], f);
        if (memcmp(f, flags + k * PLAN_FLAG_LEN, sizeof f) != 0)
            FZ_FAIL("traj_flag_n differs from traj_flag at sample %zu (t = %.17g)", k, t[k]);
    }
    if (head & 32) {  // plan_flag with the table bound evaluates the table
        double g[PLAN_FLAG_LEN];
        plan_init(&c, &p);
        c.traj = &tr;
        for (k = 0; k < nt; k++)
            if (plan_flag(&c, t[k], g) != traj_flag(&tr, t[k], f) || memcmp(f, g, sizeof f) != 0)
                FZ_FAIL("plan_flag on a table differs from traj_flag at t = %.17g", t[k]);
    }
done:
    free(breaks), free(theta), free(rho), free(flags);
    return 0;
}
