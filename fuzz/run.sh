#!/usr/bin/env sh
# Build and run the fuzz targets for $1 seconds each (default 12), all of them or those named after it:
#   smc         smc_init/smc_step                      (fuzz/fuzz_smc.c)
#   sampled     sampled_init/sampled_run, every law    (fuzz/fuzz_sampled.c)
#   continuous  continuous_run, every law              (fuzz/fuzz_continuous.c)
#   time_optimal time_optimal_plan/time_optimal_margins (fuzz/fuzz_time_optimal.c)
#   traj        traj_* and plan_flag on a table        (fuzz/fuzz_traj.c)
#   flat        plan_*, the flat maps, motor_*, arrays_* (fuzz/fuzz_flat.c)
#   dq_smc      dq_smc_init/dq_smc_step, arrays_controller_step (fuzz/fuzz_dq_smc.c)
#   time_optimal_dq time_optimal_dq_plan                  (fuzz/fuzz_time_optimal_dq.c)
# libFuzzer with ASan+UBSan when clang can link -fsanitize=fuzzer (installing clang with apt-get if it is
# missing and we may), else gcc with the random-input driver (fuzz/driver.c). Each target's corpus lives in
# build/fuzz/<target>/corpus, started from fuzz/seeds/<target> and fuzz/regressions/<target>; crashes land
# in build/fuzz/<target>/.
set -eu
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-12}"
[ $# -gt 0 ] && shift
TARGETS="${*:-smc sampled continuous time_optimal time_optimal_dq traj flat dq_smc}"
SAN="-fsanitize=address,undefined,float-divide-by-zero -fno-sanitize-recover=all -fno-omit-frame-pointer"
FLAGS="-std=c99 -g -O1 -Wall -Wextra -Werror -Icsrc -Ifuzz"
mkdir -p build/fuzz

have_libfuzzer() {
    command -v clang >/dev/null 2>&1 || return 1
    printf 'int LLVMFuzzerTestOneInput(const unsigned char *d, unsigned long n){(void)d;(void)n;return 0;}\n' \
        > build/fuzz/probe.c
    clang -fsanitize=fuzzer build/fuzz/probe.c -o build/fuzz/probe >/dev/null 2>&1
}

# Prints the sources of a target: its harness, its helpers and the core modules it calls.
sources() {
    case "$1" in
    smc) echo "fuzz/fuzz_smc.c $(ls csrc/*.c | tr '\n' ' ')" ;;
    sampled) echo "fuzz/fuzz_sampled.c fuzz/laws.c fuzz/sampled_check.c $(ls csrc/*.c | tr '\n' ' ')" ;;
    continuous) echo "fuzz/fuzz_continuous.c fuzz/laws.c $(ls csrc/*.c | tr '\n' ' ')" ;;
    time_optimal | traj) echo "fuzz/fuzz_$1.c $(ls csrc/*.c | tr '\n' ' ')" ;;
    flat | dq_smc | time_optimal_dq) echo "fuzz/fuzz_$1.c fuzz/laws.c $(ls csrc/*.c | tr '\n' ' ')" ;;
    *) echo "fuzz: unknown target $1 (smc, sampled, continuous, time_optimal, traj, flat, dq_smc, time_optimal_dq)" >&2; exit 2 ;;
    esac
}

if ! have_libfuzzer && command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo -n"
    echo "fuzz: installing clang (libFuzzer) with apt-get"
    ($SUDO apt-get update -qq && $SUDO apt-get install -y -qq clang >/dev/null) || echo "fuzz: apt-get failed"
fi

for target in $TARGETS; do
    OUT="build/fuzz/$target"
    SRC="$(sources "$target")"
    mkdir -p "$OUT/corpus"
    for dir in fuzz/seeds/$target fuzz/regressions/$target; do
        [ -d "$dir" ] && cp "$dir"/* "$OUT/corpus/" 2>/dev/null || true
    done
    if have_libfuzzer; then
        echo "fuzz: $target, libFuzzer, $SECONDS_TO_RUN s"
        # shellcheck disable=SC2086
        clang $FLAGS -fsanitize=fuzzer $SAN $SRC -lm -o "$OUT/fuzz_$target"
        ASAN_OPTIONS=detect_leaks=0 "$OUT/fuzz_$target" -seed="${FUZZ_SEED:-1}" -max_total_time="$SECONDS_TO_RUN" \
            -timeout=2 -max_len=1024 -len_control=0 -print_final_stats=1 -artifact_prefix="$OUT/" "$OUT/corpus"
    else
        CC="${CC:-cc}"
        echo "fuzz: $target, libFuzzer unavailable, $CC with the random-input driver, $SECONDS_TO_RUN s"
        # shellcheck disable=SC2086
        $CC $FLAGS $SAN $SRC fuzz/driver.c -lm -o "$OUT/fuzz_${target}_driver"
        ASAN_OPTIONS=detect_leaks=0 "$OUT/fuzz_${target}_driver" "$OUT"/corpus/*
        ASAN_OPTIONS=detect_leaks=0 FUZZ_SECONDS="$SECONDS_TO_RUN" "$OUT/fuzz_${target}_driver"
    fi
done
