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
link_image "$elf" embedded/traj_main.c
if ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "-- emulation: skipped: $QEMU not found (apt-get install qemu-system-arm)"
    exit 0
fi
echo "-- one traj_flag call (16 segments, bisection) on $QEMU -M mps2-an386 (Cortex-M4F):"
# shellcheck disable=SC2046
count_calls "$elf" "$OUT/traj_qemu.log" $(one_insn_per_tb)
grep -a 'traj_flag' "$OUT/traj_qemu.log" || echo "   (the program printed nothing: see $OUT/traj_qemu.log)"
