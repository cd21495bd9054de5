#!/bin/sh
# Cross-build the trajectory evaluator for an ARM Cortex-M4F in single precision: its code size, its static
# instruction count and (with QEMU) the instructions one traj_flag call executes on a 16-segment table.
# Run from the repo root: sh embedded/traj_build.sh (needs gcc-arm-none-eabi, libnewlib-arm-none-eabi, qemu-system-arm)
set -eu

. embedded/common.sh
require_gcc "traj embedded"
compile_object trajectory
echo "-- static instructions (${PREFIX}objdump -d):"
for f in traj_flag traj_flag_seg traj_segment traj_value traj_eval traj_valid; do
    n=$("${PREFIX}objdump" -d "$OUT/trajectory.o" | awk -v f="<$f>:" '$2 == f {on = 1; next} on && NF == 0 {exit}
        on && $1 ~ /^[0-9a-f]+:$/ && $0 ~ /\t/ {n++} END {print n + 0}')
    printf '   %-16s %5d\n' "$f" "$n"
done

elf="$OUT/traj_m4.elf"
# shellcheck disable=SC2086
"${PREFIX}gcc" $CFLAGS embedded/startup.c embedded/traj_main.c csrc/trajectory.c csrc/plan.c -nostartfiles \
    --specs=nosys.specs -Wl,--gc-sections -T embedded/mps2_an386.ld -lm -o "$elf"
if ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "-- emulation: skipped: $QEMU not found (apt-get install qemu-system-arm)"
    exit 0
fi
run_trace() {
    timeout 120 "$QEMU" -M mps2-an386 -nographic -semihosting "$@" -d exec,nochain -D "$OUT/traj_trace.log" \
        -kernel "$elf" 2>"$OUT/traj_qemu.log"
}
run_trace -accel tcg,one-insn-per-tb=on || run_trace -singlestep
echo "-- one traj_flag call (16 segments, bisection) on $QEMU -M mps2-an386: $(grep -a 'traj_flag' "$OUT/traj_qemu.log")"
awk '{sym = $NF} sym == "traced_step" {on = 1; next} on && sym == "main" {exit}
     on {n++; by[sym]++} END {
        printf "   executed instructions: %d\n", n
        for (s in by) printf "     %-24s %5d\n", s, by[s] | "sort -k2 -n -r"
     }' "$OUT/traj_trace.log"
