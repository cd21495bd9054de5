#!/bin/sh
# Cross-build csrc/ for an ARM Cortex-M4F in single precision; print code sizes, the static instruction count
# of smc_step, and (with QEMU) the instructions one smc_step call executes and the cycles they take.
# Run from the repo root: sh embedded/build.sh (make embedded runs it and the other scripts of embedded/)
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
if ! link_image "$elf" embedded/count_main.c 2>"$OUT/link.log"; then
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

# 4. Executed instructions (embedded/common.sh, count_calls) and the cycles they take at least and at most.
echo "-- one smc_step call on $QEMU -M mps2-an386 (Cortex-M4F, newlib libm):"
# shellcheck disable=SC2046
count_calls "$elf" "$OUT/qemu.log" $(one_insn_per_tb)
grep -a 'smc_step status' "$OUT/qemu.log" || echo "   (the program printed nothing: see $OUT/qemu.log)"
