#!/bin/sh
# Cross-build the time-optimal planner for an ARM Cortex-M4F in single precision: its code size, its workspace,
# its static instruction count and (with QEMU) the instructions one plan executes (NEMA 17, 24 V, 1 rad).
# Run from the repo root: sh embedded/time_optimal_build.sh (needs gcc-arm-none-eabi, libnewlib-arm-none-eabi,
# qemu-system-arm for the executed count)
set -eu

. embedded/common.sh
require_gcc "time_optimal embedded"
PLANNER="time_optimal time_optimal_envelope time_optimal_table"
for f in $PLANNER; do compile_object "$f"; done
echo "-- static instructions (${PREFIX}objdump -d; static functions are inlined where -Os chose to):"
for f in $PLANNER; do "${PREFIX}objdump" -d "$OUT/$f.o"; done | awk '
    /^[0-9a-f]+ <[^>]+>:$/ {name = substr($2, 2, length($2) - 3); next}
    name != "" && $1 ~ /^[0-9a-f]+:$/ && $0 ~ /\t/ {n[name]++; total++}
    END {for (f in n) printf "   %-24s %5d\n", f, n[f] | "sort -k2 -n -r"; close("sort -k2 -n -r");
         printf "   %-24s %5d\n", "total", total}'

elf="$OUT/time_optimal_m4.elf"
link_image "$elf" embedded/time_optimal_main.c
echo "-- firmware image with the planner, its result and the libm it needs (bytes; the workspace is the RAM above .bss):"
"${PREFIX}size" "$elf"
if ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "-- emulation: skipped: $QEMU not found (apt-get install qemu-system-arm)"
    exit 0
fi
echo "-- one time_optimal_plan call (1 rad, 24 V) on $QEMU -M mps2-an386 (Cortex-M4F, newlib libm):"
# shellcheck disable=SC2046
count_calls "$elf" "$OUT/time_optimal_qemu.log" $(one_insn_per_tb)
grep -a 'time_optimal_plan' "$OUT/time_optimal_qemu.log" || echo "   (the program printed nothing: see $OUT/time_optimal_qemu.log)"
