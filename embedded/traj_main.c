// Bare-metal Cortex-M4 program for QEMU's mps2-an386: one traj_flag call on a 16-segment table in flash, between
// markers, so that an instruction trace counts exactly the instructions it executes (see embedded/traj_build.sh).
#include <stdint.h>

#include "plan.h"
#include "trajectory.h"

void semihost_write0(const char *s);
void semihost_exit(int code);

#define NSEG 16

// Breaks 0, 10, .., 160 ms and the paper's psi scaled to one radian per segment: a table a firmware keeps in flash.
static const fs_real breaks[NSEG + 1] = {0,          FS_C(0.01), FS_C(0.02), FS_C(0.03), FS_C(0.04), FS_C(0.05),
                                         FS_C(0.06), FS_C(0.07), FS_C(0.08), FS_C(0.09), FS_C(0.10), FS_C(0.11),
                                         FS_C(0.12), FS_C(0.13), FS_C(0.14), FS_C(0.15), FS_C(0.16)};
#define PSI_ROW(k) {-126, 700, -1575, 1800, -1050, 252, 0, 0, 0, 0, (fs_real)(k)}
static const fs_real theta[NSEG][TRAJ_NCOEF] = {
    PSI_ROW(0), PSI_ROW(1), PSI_ROW(2),  PSI_ROW(3),  PSI_ROW(4),  PSI_ROW(5),  PSI_ROW(6),  PSI_ROW(7),
    PSI_ROW(8), PSI_ROW(9), PSI_ROW(10), PSI_ROW(11), PSI_ROW(12), PSI_ROW(13), PSI_ROW(14), PSI_ROW(15)};
#define RHO_ROW {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, FS_C(0.5)}
static const fs_real rho[NSEG][TRAJ_NCOEF] = {RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW,
                                              RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW, RHO_ROW};

// The traced call, kept out of line so that the trace shows where it starts and ends.
__attribute__((noinline)) bool traced_step(const struct traj *tr, fs_real t, fs_real flag[PLAN_FLAG_LEN])
{
    return traj_flag(tr, t, flag);
}

int main(void)
{
    const struct traj tr = {NSEG, breaks, &theta[0][0], &rho[0][0]};
    fs_real flag[PLAN_FLAG_LEN];
    bool inside;
    if (!traj_valid(&tr))
        semihost_exit(1);
    inside = traced_step(&tr, FS_C(0.0937), flag);  // in segment 9, bisection over all 16
    semihost_write0(inside && flag[PLAN_THETA] > 9 && flag[PLAN_THETA] < 10 ? "traj_flag ok\n" : "traj_flag bad\n");
    semihost_exit(inside ? 0 : 1);
    return 0;
}
