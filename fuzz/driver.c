// A stand-in for libFuzzer where clang is missing: runs the harness on files given as arguments, or on
// random inputs of 1 to 1024 bytes (xorshift, fixed seed) for FUZZ_SECONDS seconds (default 20).
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

// Returns 0 after the run (a broken invariant aborts inside the harness).
int main(int argc, char **argv)
{
    static uint8_t buf[4096];
    uint64_t s = 0x9E3779B97F4A7C15u, runs = 0;
    const char *env = getenv("FUZZ_SECONDS");
    double seconds = env ? atof(env) : 20.0;
    time_t start = time(NULL);
    size_t n, i;
    int a;
    double slowest = 0, took;
    const char *slowest_file = "";
    for (a = 1; a < argc; a++) {
        FILE *f = fopen(argv[a], "rb");
        clock_t c0;
        if (!f)
            continue;
        n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        c0 = clock();
        LLVMFuzzerTestOneInput(buf, n);
        took = (double)(clock() - c0) / CLOCKS_PER_SEC;
        if (took > slowest)
            slowest = took, slowest_file = argv[a];
        runs++;
    }
    if (argc > 1) {
        printf("driver: %llu files ok, the slowest %.1f ms (%s)\n", (unsigned long long)runs, 1e3 * slowest,
               slowest_file);
        return 0;
    }
    while (difftime(time(NULL), start) < seconds) {
        for (int batch = 0; batch < 1000; batch++) {
            s ^= s << 13, s ^= s >> 7, s ^= s << 17;
            n = 1 + s % 1024;
            for (i = 0; i < n; i++) {
                s ^= s << 13, s ^= s >> 7, s ^= s << 17;
                buf[i] = (uint8_t)(s >> 56);
            }
            LLVMFuzzerTestOneInput(buf, n);
            runs++;
        }
    }
    printf("driver: %llu random inputs in %.0f s, no invariant broken\n", (unsigned long long)runs, seconds);
    return 0;
}
