#!/usr/bin/env sh
# Build and run the smc_step fuzzer for $1 seconds (default 25): libFuzzer with ASan+UBSan when clang can
# link -fsanitize=fuzzer (installing clang with apt-get if it is missing and we may), else gcc with the
# random-input driver. The corpus lives in build/fuzz/corpus; crashes land in build/fuzz/.
set -eu
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-25}"
OUT=build/fuzz
mkdir -p "$OUT/corpus"
SAN="-fsanitize=address,undefined,float-divide-by-zero -fno-sanitize-recover=all -fno-omit-frame-pointer"
SRC="fuzz/fuzz_smc.c csrc/motor.c csrc/plan.c csrc/flat.c csrc/smc.c"
FLAGS="-std=c99 -g -O1 -Wall -Wextra -Werror -Icsrc"

have_libfuzzer() {
    command -v clang >/dev/null 2>&1 || return 1
    printf 'int LLVMFuzzerTestOneInput(const unsigned char *d, unsigned long n){(void)d;(void)n;return 0;}\n' \
        > "$OUT/probe.c"
    clang -fsanitize=fuzzer "$OUT/probe.c" -o "$OUT/probe" >/dev/null 2>&1
}

if ! have_libfuzzer && command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo -n"
    echo "fuzz: installing clang (libFuzzer) with apt-get"
    ($SUDO apt-get update -qq && $SUDO apt-get install -y -qq clang >/dev/null) || echo "fuzz: apt-get failed"
fi

if have_libfuzzer; then
    # shellcheck disable=SC2086
    clang $FLAGS -fsanitize=fuzzer $SAN $SRC -lm -o "$OUT/fuzz_smc"
    ASAN_OPTIONS=detect_leaks=0 "$OUT/fuzz_smc" -seed="${FUZZ_SEED:-1}" -max_total_time="$SECONDS_TO_RUN" -print_final_stats=1 \
        -artifact_prefix="$OUT/" "$OUT/corpus"
else
    CC="${CC:-cc}"
    echo "fuzz: libFuzzer unavailable, using $CC with the random-input driver"
    # shellcheck disable=SC2086
    $CC $FLAGS $SAN $SRC fuzz/driver.c -lm -o "$OUT/fuzz_smc_driver"
    ASAN_OPTIONS=detect_leaks=0 FUZZ_SECONDS="$SECONDS_TO_RUN" "$OUT/fuzz_smc_driver"
fi
