# Shared by the embedded build scripts (sourced from the repo root): the cross compiler, the output folder,
# QEMU, the Cortex-M4F single-precision flags, and require_gcc.
PREFIX=${ARM_PREFIX:-arm-none-eabi-}
OUT=${EMBEDDED_OUT:-build/embedded}
QEMU=${QEMU_SYSTEM_ARM:-qemu-system-arm}
CFLAGS="-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard -Os -std=c99 -DFS_SINGLE
        -ffunction-sections -fdata-sections -Wall -Wextra -Wdouble-promotion -Werror -Icsrc"

# require_gcc WHAT: ends the calling script with status 0 and a note naming WHAT when the cross compiler is
# missing; otherwise makes the output folder.
require_gcc() {
    if ! command -v "${PREFIX}gcc" >/dev/null 2>&1; then
        echo "$1: skipped: ${PREFIX}gcc not found" \
             "(Debian/Ubuntu: apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi)"
        exit 0
    fi
    mkdir -p "$OUT"
}

# compile_object NAME: csrc/NAME.c alone to $OUT/NAME.o, with its code size.
compile_object() {
    # shellcheck disable=SC2086
    "${PREFIX}gcc" $CFLAGS -c "csrc/$1.c" -o "$OUT/$1.o"
    echo "== ${PREFIX}gcc $("${PREFIX}gcc" -dumpversion), float, -Os: csrc/$1.c"
    "${PREFIX}size" "$OUT/$1.o"
}

# link_image ELF MAIN: a bare-metal image for QEMU's mps2-an386 of embedded/startup.c, embedded/measure.c, MAIN and
# every csrc/*.c (the linker keeps only what MAIN reaches), with newlib's libm.
link_image() {
    # shellcheck disable=SC2086
    "${PREFIX}gcc" $CFLAGS embedded/startup.c embedded/measure.c "$2" csrc/*.c -nostartfiles --specs=nosys.specs -Wl,--gc-sections \
        -T embedded/mps2_an386.ld -lm -o "$1"
}

# count_calls ELF LOG [QEMU options]: runs ELF once on QEMU's mps2-an386 (semihosting output to LOG) and prints the
# instructions each call of traced_step executes, with the functions they ran in, and bounds on its Cortex-M4F
# cycles (embedded/m4_cycles.awk). QEMU translates one instruction per block and logs every executed block with its
# address and symbol; the lines from traced_step's entry back to main are the call's instructions (counted as they
# stream: a trace can be many millions of lines). ELF.pcs keeps the count per call and address.
count_calls() {
    elf=$1 log=$2
    shift 2
    timeout 3600 "$QEMU" -M mps2-an386 -nographic -semihosting "$@" -d exec,nochain -D /dev/stdout \
        -kernel "$elf" 2>"$log" |
        awk -v pcs="$elf.pcs" 'BEGIN {printf "" > pcs}
             {sym = $NF} sym == "traced_step" {if (!on) {on = 1; k++}; next} on && sym == "main" {on = 0; next}
             on {n[k]++; by[k, sym]++; syms[sym] = 1; split($4, f, "/"); at[k, f[2]]++}
             END {
                for (c = 1; c <= k; c++) {
                    printf "   call %d: executed instructions: %d\n", c, n[c]
                    cmd = "sort -k2 -n -r | head -12"
                    for (s in syms) if (by[c, s]) printf "     %-28s %10d\n", s, by[c, s] | cmd
                    close(cmd)
                }
                for (key in at) {split(key, p, SUBSEP); print p[1], p[2], at[key] > pcs}
             }'
    echo "-- cycles at zero wait states, from the instruction mix and ARM's Cortex-M4 instruction timings" \
         "(embedded/m4_cycles.awk):"
    "${PREFIX}objdump" -d "$elf" | awk -f embedded/m4_cycles.awk - "$elf.pcs"
}

# one_insn_per_tb: prints the QEMU option that translates one instruction per block (-singlestep before QEMU 8.1).
one_insn_per_tb() {
    "$QEMU" --version | awk 'NR == 1 {split($4, v, "."); new = v[1] > 8 || (v[1] == 8 && v[2] >= 1)
        print new ? "-accel tcg,one-insn-per-tb=on" : "-singlestep"}'
}
