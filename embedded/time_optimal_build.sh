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
# shellcheck disable=SC2086
"${PREFIX}gcc" $CFLAGS embedded/startup.c embedded/time_optimal_main.c csrc/time_optimal.c \
    csrc/time_optimal_envelope.c csrc/time_optimal_table.c csrc/motor.c \
    -nostartfiles --specs=nosys.specs -Wl,--gc-sections -T embedded/mps2_an386.ld -lm -o "$elf"
echo "-- firmware image with the planner, its 15000-float workspace and result, and the libm it needs (bytes):"
"${PREFIX}size" "$elf"
if ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "-- emulation: skipped: $QEMU not found (apt-get install qemu-system-arm)"
    exit 0
fi
# One instruction per translation block, each logged with its symbol: the lines from traced_step's entry back
# to main are the plan's instructions (counted as they stream, the trace is millions of lines).
run_count() {
    timeout 1200 "$QEMU" -M mps2-an386 -nographic -semihosting "$@" -d exec,nochain -D /dev/stdout \
        -kernel "$elf" 2>"$OUT/time_optimal_qemu.log" |
        awk '{sym = $NF} sym == "traced_step" {on = 1; next} on && sym == "main" {exit}
             on {n++; by[sym]++} END {
                printf "   executed instructions: %d\n", n
                for (s in by) printf "     %-24s %9d\n", s, by[s] | "sort -k2 -n -r"
             }'
}
echo "-- one time_optimal_plan call (1 rad, 24 V) on $QEMU -M mps2-an386 (Cortex-M4F, newlib libm):"
if timeout 120 "$QEMU" -M mps2-an386 -nographic -semihosting -accel tcg,one-insn-per-tb=on -kernel "$elf" \
        >/dev/null 2>&1; then
    run_count -accel tcg,one-insn-per-tb=on
else
    run_count -singlestep  # the option's name before QEMU 8.1
fi
grep -a 'time_optimal_plan' "$OUT/time_optimal_qemu.log" || true
