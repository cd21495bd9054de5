#!/bin/sh
# Cross-build csrc/ for an ARM Cortex-M4F in single precision; print code sizes, the static instruction count
# of smc_step, and (with QEMU) the instructions one smc_step call executes. Run from the repo root: make embedded
set -eu

. embedded/common.sh
require_gcc "embedded"
echo "== ${PREFIX}gcc $("${PREFIX}gcc" -dumpversion): csrc/*.c with $(echo $CFLAGS | sed 's/ -W.*//')"

# 1. Every module of the core, unchanged, in single precision (fs_real = float); -Werror -Wdouble-promotion
#    proves no expression silently falls back to double (software floating point on the M4).
objs=""
for src in csrc/*.c; do
    obj="$OUT/$(basename "$src" .c).o"
    # shellcheck disable=SC2086
    "${PREFIX}gcc" $CFLAGS -c "$src" -o "$obj"
    objs="$objs $obj"
done
echo "-- code size per object (bytes; ${PREFIX}size):"
# shellcheck disable=SC2086
"${PREFIX}size" -t $objs

# 2. Static instruction count: the instructions in smc_step (smc_law is inlined into it) and in each core
#    function it calls, from the disassembly.
count_static() {  # object function -> number of instructions in the function's disassembly
    "${PREFIX}objdump" -d "$1" | awk -v f="<$2>:" '$2 == f {on = 1; next} on && NF == 0 {exit}
        on && $1 ~ /^[0-9a-f]+:$/ && $0 ~ /\t/ {n++} END {print n + 0}'
}
echo "-- static instructions (${PREFIX}objdump -d):"
total=0
for pair in smc:smc_step plan:plan_flag plan:psi_all plan:flag_of_psi flat:flat_voltages_trig; do
    n=$(count_static "$OUT/${pair%%:*}.o" "${pair#*:}")
    total=$((total + n))
    printf '   %-20s %5d\n' "${pair#*:}" "$n"
done
printf '   %-20s %5d  (smc_step and the core functions it calls; libm not included)\n' "total" "$total"

# 3. A bare-metal image for QEMU's mps2-an386 (Cortex-M4): one smc_step call between markers.
elf="$OUT/smc_step_m4.elf"
# shellcheck disable=SC2086
if ! "${PREFIX}gcc" $CFLAGS embedded/startup.c embedded/count_main.c csrc/motor.c csrc/plan.c csrc/trajectory.c csrc/flat.c \
        csrc/smc.c csrc/torque_model.c -nostartfiles --specs=nosys.specs -Wl,--gc-sections -T embedded/mps2_an386.ld -lm \
        -o "$elf" 2>"$OUT/link.log"; then
    echo "-- emulation: skipped: the link failed (see $OUT/link.log; without newlib's libm:" \
         "Debian: apt-get install libnewlib-arm-none-eabi)"
    exit 0
fi
echo "-- firmware image with the controller and the libm it needs (bytes; ${PREFIX}size):"
"${PREFIX}size" "$elf"
if ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "-- emulation: skipped: $QEMU not found (Debian: apt-get install qemu-system-arm)"
    exit 0
fi

# 4. Executed instructions: QEMU runs one instruction per translation block and logs each executed block
#    with its symbol; the lines from traced_step's entry back to main are the call's instructions.
run_trace() {  # extra QEMU options -> trace in $OUT/trace.log; the program writes to stderr (semihosting)
    timeout 120 "$QEMU" -M mps2-an386 -nographic -semihosting "$@" -d exec,nochain -D "$OUT/trace.log" \
        -kernel "$elf" 2>"$OUT/qemu.log"
}
run_trace -accel tcg,one-insn-per-tb=on || run_trace -singlestep  # the option's name before QEMU 8.1
echo "-- one smc_step call on $QEMU -M mps2-an386 (Cortex-M4F, newlib libm):" \
     "$(grep -a 'smc_step status' "$OUT/qemu.log")"
awk '{sym = $NF} sym == "traced_step" {on = 1; next} on && sym == "main" {exit}
     on {n++; by[sym]++} END {
        printf "   executed instructions: %d\n", n
        for (s in by) printf "     %-24s %5d\n", s, by[s] | "sort -k2 -n -r"
     }' "$OUT/trace.log"
