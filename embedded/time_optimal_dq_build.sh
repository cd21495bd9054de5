#!/bin/sh
# Cross-build the field-weakening planner (time_optimal_dq_plan) for an ARM Cortex-M4F in single precision: its code
# size, its static instruction count, and (with QEMU) the instructions, stack and workspace of one plan each of
# 0.1, 1 and 20 rad (NEMA 17 preset, 24 V, v_use 0.84, 1 A, 20 kHz control rate).
# Run from the repo root: sh embedded/time_optimal_dq_build.sh (needs gcc-arm-none-eabi, libnewlib-arm-none-eabi,
# qemu-system-arm for the executed count)
set -eu

. embedded/common.sh
require_gcc "time_optimal_dq embedded"
# The planner's own files (whatever time_optimal_dq*.c there are) and the stages it shares with time_optimal_plan.
PLANNER="$(for f in csrc/time_optimal_dq*.c; do basename "$f" .c; done) time_optimal_envelope time_optimal_table"
for f in $PLANNER; do compile_object "$f"; done
echo "-- static instructions (${PREFIX}objdump -d; static functions are inlined where -Os chose to):"
for f in $PLANNER; do "${PREFIX}objdump" -d "$OUT/$f.o"; done | awk '
    /^[0-9a-f]+ <[^>]+>:$/ {name = substr($2, 2, length($2) - 3); next}
    name != "" && $1 ~ /^[0-9a-f]+:$/ && $0 ~ /\t/ {n[name]++; total++}
    END {for (f in n) printf "   %-28s %5d\n", f, n[f] | "sort -k2 -n -r"; close("sort -k2 -n -r");
         printf "   %-28s %5d\n", "total", total}'

elf="$OUT/time_optimal_dq_m4.elf"
link_image "$elf" embedded/time_optimal_dq_main.c
echo "-- firmware image with the planner, its result and the libm it needs (bytes; the workspace is the RAM" \
     "above .bss):"
"${PREFIX}size" "$elf"
if ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "-- emulation: skipped: $QEMU not found (apt-get install qemu-system-arm)"
    exit 0
fi
echo "-- time_optimal_dq_plan on $QEMU -M mps2-an386 (Cortex-M4F, newlib libm), calls 1-3: 0.1, 1, 20 rad:"
# shellcheck disable=SC2046
count_calls "$elf" "$OUT/time_optimal_dq_qemu.log" $(one_insn_per_tb)
grep -a 'time_optimal_dq' "$OUT/time_optimal_dq_qemu.log" || echo "   (the program printed nothing: see $OUT/time_optimal_dq_qemu.log)"
