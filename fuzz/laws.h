// The four controllers of the core built from fuzz input, and a wrapper that checks controller.h's contract on
// every call the run loops make.
#ifndef FUZZ_LAWS_H
#define FUZZ_LAWS_H

#include <stdbool.h>
#include <stdint.h>
#include "cascade.h"
#include "decode.h"
#include "exact_linearization.h"
#include "microstep.h"
#include "plant.h"
#include "smc.h"

enum fz_kind { FZ_SMC, FZ_MICROSTEP, FZ_CASCADE, FZ_EXACT, FZ_KINDS };

// Calls whose (t, y, status, v) the wrapper keeps, for the loop's checks.
#define FZ_RECORD 300

// Prints the broken guarantee and aborts (libFuzzer then saves the input).
#define FZ_FAIL(...)                  \
    do {                              \
        fprintf(stderr, "fuzz: ");    \
        fprintf(stderr, __VA_ARGS__); \
        fprintf(stderr, "\n");        \
        abort();                      \
    } while (0)

// A controller under test: the law's state, its bound interface, and the wrapper the run loop calls.
struct fz_law {
    int kind;
    union {
        struct smc smc;
        struct microstep ms;
        struct cascade cas;
        struct exact_linearization el;
    } u;
    struct controller inner;  // the law itself
    struct controller outer;  // the checking wrapper around it (what the loops get)
    double v_limit;           // the law's own voltage limit
    unsigned used_y;          // bit k: the law reads y[k]
    uint32_t calls, status_or, fault_calls;
    uint32_t cancel_at;  // set *cancel at this call (0: never)
    volatile uint32_t *cancel;
    double t[FZ_RECORD], y[FZ_RECORD][CTRL_Y_LEN], v[FZ_RECORD][2];
    uint32_t status[FZ_RECORD];
};

// Returns nothing; decodes the motor's fields around m's own, in place: R, L, Km, J, B, then Nr from a byte (default 50):
// with wide_nr a byte of bit 7 set is followed by Nr as any 32-bit int (else 0..127), without Nr is the byte.
static inline void fz_motor_fields(struct fz_reader *r, bool wide_nr, struct motor_params *m)
{
    uint8_t b;
    m->R = fz_value(r, m->R), m->L = fz_value(r, m->L), m->Km = fz_value(r, m->Km);
    m->J = fz_value(r, m->J), m->B = fz_value(r, m->B);
    b = fz_byte(r, 50);
    m->Nr = wide_nr && (b & 0x80) ? (int)fz_u32(r, 50) : b;
}

// Returns nothing; decodes a motor around the paper's (all fields when hostile, else the nominal).
void fz_motor(struct fz_reader *r, bool hostile, struct motor_params *m);

// Returns nothing; decodes a plan around the nominal one (t0 .. tf) when hostile.
void fz_plan(struct fz_reader *r, bool hostile, double t0, double tf, struct plan *p);

// Returns nothing; decodes the plant's load and effects (each group hostile or off by its bit in mask).
void fz_plant(struct fz_reader *r, uint8_t mask, const struct motor_params *m, struct plant *p);

// Returns true when plant.h's documented ranges hold (motor, load and effects finite and in range).
bool fz_plant_ok(const struct plant *p);

// Returns true when plant_acceleration at x is plant.h's formula up to rounding (laws.c).
bool fz_acceleration_ok(const struct plant *p, const double x[4]);

// Returns the law's init status (0: accepted); decodes its gains and limits (hostile or near the nominal) and
// binds the wrapper. Aborts when a documented requirement is broken and the law accepts it anyway.
int fz_law_init(struct fz_law *c, int kind, struct fz_reader *r, bool hostile, uint8_t options,
                const struct motor_params *model, const struct plan *plan, double Ts, double v_limit);

#endif
