// Bare-metal Cortex-M4 program for QEMU's mps2-an386: three field-weakening plans (time_optimal_dq_plan; NEMA 17
// preset, 24 V, v_use 0.84, 1 A, 20 kHz control rate) of 0.1, 1 and 20 rad, each between markers so that an
// instruction trace counts the instructions it executes (see embedded/time_optimal_dq_build.sh), with the stack it
// used. It calls only time_optimal_dq_work_len and time_optimal_dq_plan and reads only the result's segment table;
// the workspace is the free RAM.
#include "measure.h"
#include "time_optimal_dq.h"

static struct tod_result out;

// The traced call, kept out of line so that the trace shows where it starts and ends.
__attribute__((noinline)) int traced_step(const struct motor_params *m, const struct tod_limits *l, fs_real distance,
                                          fs_real *work, size_t work_len)
{
    return time_optimal_dq_plan(m, l, distance, work, work_len, &out);
}

// Returns x * scale rounded to an integer (INT32_MIN if out of range or NaN).
static int32_t scaled(fs_real x, fs_real scale)
{
    fs_real y = x * scale;
    return fs_fabs(y) < FS_C(2e9) ? (int32_t)(y < 0 ? y - FS_C(0.5) : y + FS_C(0.5)) : INT32_MIN;
}

int main(void)
{
    static const fs_real DISTANCES[3] = {FS_C(0.1), 1, 20};
    const struct motor_params m = {FS_C(4.10), FS_C(9.50e-3), FS_C(0.26870058), FS_C(5.6e-6), FS_C(1e-4), 50};
    const struct tod_limits l = {.v_bus = 24, .v_use = FS_C(0.84), .i_max = 1, .speed_max = 0, .control_rate = 20000};
    size_t room, work_len = time_optimal_dq_work_len();
    fs_real *work = free_ram(&room);
    int bad = 0;
    size_t i;
    if (work_len * sizeof *work > room) {
        semihost_write0("time_optimal_dq_plan: its workspace does not fit in the RAM\n");
        semihost_exit(2);
    }
    for (i = 0; i < 3; i++) {
        uint32_t stack;
        int rc;
        stack_paint();
        rc = traced_step(&m, &l, DISTANCES[i], work, work_len);
        stack = stack_used();
        // The result's segment count and breaks alone (the struct traj layout), so that a new version of the planner
        // with other fields runs unchanged.
        semihost_write0(rc == TOD_OK && out.n > 0 ? "time_optimal_dq_plan ok" : "time_optimal_dq_plan bad");
        put_field("distance_mrad", scaled(DISTANCES[i], 1000));
        put_field("rc", rc);
        put_field("segments", (int32_t)out.n);
        put_field("duration_us", out.n > 0 ? scaled(out.breaks[out.n], FS_C(1e6)) : 0);
        put_field("stack_bytes", (int32_t)stack);
        put_field("work_bytes", (int32_t)(work_len * sizeof *work));
        put_field("result_bytes", (int32_t)sizeof out);
        semihost_write0("\n");
        bad |= rc != TOD_OK;
    }
    semihost_exit(bad);
    return 0;
}
