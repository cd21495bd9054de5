// Bare-metal Cortex-M4 program for QEMU's mps2-an386: one smc_step call between markers, so that an
// instruction trace counts exactly the instructions it executes (see embedded/build.sh).
#include <stdint.h>

#include "flat.h"
#include "plan.h"
#include "smc.h"

void semihost_write0(const char *s);
void semihost_exit(int code);

// The traced call, kept out of line so that the trace shows where it starts and ends.
__attribute__((noinline)) uint32_t traced_step(struct smc *s, fs_real t, const fs_real y[5], fs_real v[2])
{
    return smc_step(s, t, y, v);
}

// Returns nothing; writes x in units of 1e-6 as a decimal string ("-1234567") into buf (>= 16 chars).
static void micro_to_string(fs_real x, char *buf)
{
    char digits[12];
    int32_t n = (int32_t)(x * FS_C(1e6));
    uint32_t u = n < 0 ? (uint32_t)(-n) : (uint32_t)n;
    int k = 0, j = 0;
    do {
        digits[k++] = (char)('0' + u % 10);
        u /= 10;
    } while (u && k < 11);
    if (n < 0)
        buf[j++] = '-';
    while (k)
        buf[j++] = digits[--k];
    buf[j++] = ' ';
    buf[j] = 0;
}

int main(void)
{
    struct smc_params p;
    struct smc s;
    fs_real flag[PLAN_FLAG_LEN], x[4], v[2], y[5], t = FS_C(0.03);
    char buf[16];
    uint32_t status;
    smc_params_default(&p);
    if (smc_init(&s, &p) != SMC_PARAMS_OK)
        semihost_exit(1);
    // Mid-move, off the plan by a few percent, as in benchmarks/smc_step_bench.c.
    plan_eval(&p.plan, t, flag);
    flat_to_state(&p.motor, flag, 0, x, v);
    y[0] = x[0] + FS_C(0.01);
    y[1] = x[1] - FS_C(0.01);
    y[2] = x[2] + FS_C(0.2);
    y[3] = x[3] + FS_C(5e-4);
    y[4] = flag[PLAN_DDTHETA] + 20;
    status = traced_step(&s, t, y, v);
    semihost_write0("smc_step status ");
    micro_to_string((fs_real)status * FS_C(1e-6), buf);
    semihost_write0(buf);
    semihost_write0("v_uV ");
    micro_to_string(v[0], buf);
    semihost_write0(buf);
    micro_to_string(v[1], buf);
    semihost_write0(buf);
    semihost_write0("\n");
    semihost_exit(status & ~(uint32_t)SMC_SATURATED ? 1 : 0);
    return 0;
}
