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
