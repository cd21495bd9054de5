// Bare-metal Cortex-M4 program for QEMU's mps2-an386: one time-optimal plan (NEMA 17, 24 V, 1 rad) between
// markers, so that an instruction trace counts the instructions it executes (see embedded/time_optimal_build.sh).
#include "time_optimal.h"

void semihost_write0(const char *s);
void semihost_exit(int code);

static fs_real work[15000];  // time_optimal_work_len() fs_real, checked below
static struct to_result out;

// The traced call, kept out of line so that the trace shows where it starts and ends.
__attribute__((noinline)) int traced_step(const struct motor_params *m, const struct to_limits *l)
{
    return time_optimal_plan(m, l, FS_C(1.0), 0, 0, work, sizeof work / sizeof *work, &out);
}

int main(void)
{
    const struct motor_params m = {FS_C(4.10), FS_C(9.50e-3), FS_C(0.26870058), FS_C(5.6e-6), FS_C(1e-4), 50};
    const struct to_limits l = {24, 1, FS_C(0.3), FS_C(0.025), 10, FS_C(1.1), FS_C(0.84), 0, 0, 0};
    int rc;
    if (time_optimal_work_len() > sizeof work / sizeof *work)
        semihost_exit(2);
    rc = traced_step(&m, &l);
    semihost_write0(rc == TO_OK && out.n > 0 && out.margins.worst <= 0 ? "time_optimal_plan ok\n"
                                                                       : "time_optimal_plan bad\n");
    semihost_exit(rc == TO_OK ? 0 : 1);
    return 0;
}
