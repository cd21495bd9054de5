// Bare-metal Cortex-M4 program for QEMU's mps2-an386: one time-optimal plan (NEMA 17, 24 V, 1 rad) between
// markers, so that an instruction trace counts the instructions it executes (see embedded/time_optimal_build.sh),
// with the stack it used. The workspace is the free RAM.
#include "measure.h"
#include "time_optimal.h"

static struct to_result out;

// The traced call, kept out of line so that the trace shows where it starts and ends.
__attribute__((noinline)) int traced_step(const struct motor_params *m, const struct to_limits *l, fs_real *work,
                                          size_t work_len)
{
    return time_optimal_plan(m, l, FS_C(1.0), 0, 0, work, work_len, &out);
}

int main(void)
{
    const struct motor_params m = {FS_C(4.10), FS_C(9.50e-3), FS_C(0.26870058), FS_C(5.6e-6), FS_C(1e-4), 50};
    const struct to_limits l = {24, 1, FS_C(0.3), FS_C(0.025), 10, FS_C(1.1), FS_C(0.84), 0, 0, 0};
    size_t room, work_len = time_optimal_work_len();
    fs_real *work = free_ram(&room);
    uint32_t stack;
    int rc;
    if (work_len * sizeof *work > room)
        semihost_exit(2);
    stack_paint();
    rc = traced_step(&m, &l, work, work_len);
    stack = stack_used();
    semihost_write0(rc == TO_OK && out.n > 0 && out.margins.worst <= 0 ? "time_optimal_plan ok"
                                                                       : "time_optimal_plan bad");
    put_field("rc", rc);
    put_field("duration_us", out.n > 0 ? (int32_t)(out.breaks[out.n] * FS_C(1e6) + FS_C(0.5)) : 0);
    put_field("stack_bytes", (int32_t)stack);
    put_field("work_bytes", (int32_t)(work_len * sizeof *work));
    put_field("result_bytes", (int32_t)sizeof out);
    semihost_write0("\n");
    semihost_exit(rc == TO_OK ? 0 : 1);
    return 0;
}
