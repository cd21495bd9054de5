// Parity with the Python reference: every record of tests/vectors/core.txt agrees to 1e-12 relative.
#include <stdlib.h>
#include <string.h>
#include "arrays.h"
#include "cascade.h"
#include "check.h"
#include "exact_linearization.h"
#include "flat.h"
#include "microstep.h"
#include "plan.h"
#include "plant.h"
#include "smc.h"

#define TOL 1e-12
#define FLOOR 1e-13  // absolute floor of compare_floor
#define MAX_NUMS 64

// Returns the number of numbers parsed from s into out.
static int parse(const char *s, double *out)
{
    char *end;
    int n = 0;
    while (n < MAX_NUMS) {
        out[n] = strtod(s, &end);
        if (end == s)
            break;
        s = end;
        n++;
    }
    return n;
}

// Returns nothing; fills a motor from six numbers (R, L, Km, J, B, Nr).
static void motor_from(const double *a, struct motor_params *m)
{
    m->R = a[0], m->L = a[1], m->Km = a[2], m->J = a[3], m->B = a[4], m->Nr = (int)a[5];
}

// Returns the largest componentwise relative difference of n values (also checked against TOL).
static double compare(const char *kind, int line, const double *c, const double *p, int n)
{
    double worst = 0, r;
    int k;
    for (k = 0; k < n; k++) {
        r = rel_diff(c[k], p[k]);
        worst = r > worst ? r : worst;
        CHECK(fabs(c[k] - p[k]) <= TOL * fabs(p[k]), "%s line %d component %d: C %.17g vs Python %.17g", kind, line, k,
              c[k], p[k]);
    }
    return worst;
}

// Returns the largest componentwise relative difference of n values; checks |c - p| <= TOL |p| + FLOOR, the
// floor for values that cancel to near 0 (volts, amperes, rad/s^2 of the baseline and plant records).
static double compare_floor(const char *kind, int line, const double *c, const double *p, int n)
{
    double worst = 0, r;
    int k;
    for (k = 0; k < n; k++) {
        r = fabs(p[k]) > FLOOR / TOL ? rel_diff(c[k], p[k]) : fabs(c[k] - p[k]) * TOL / FLOOR;
        worst = r > worst ? r : worst;
        CHECK(fabs(c[k] - p[k]) <= TOL * fabs(p[k]) + FLOOR, "%s line %d component %d: C %.17g vs Python %.17g", kind,
              line, k, c[k], p[k]);
    }
    return worst;
}

// Returns true when the status is Python's: no fault, CTRL_SATURATED exactly when max(|va|, |vb|) > v_limit.
static bool status_matches(uint32_t status, const double *v, double v_limit)
{
    return status == (fmax(fabs(v[0]), fabs(v[1])) > v_limit ? CTRL_SATURATED : CTRL_OK);
}

// Returns the worst difference of one "ms" record: motor, plan, (wc, feedforward, Ts, v_limit), t, state,
// y, then Python's v and state after the step.
static double check_microstep(int line, const double *a)
{
    struct microstep_params p = {.motor = {0}};
    struct microstep s;
    double out[4];
    uint32_t st;
    motor_from(a, &p.motor);
    p.plan = (struct plan){a[6], a[7], a[8], a[9], a[10], a[11], NULL};
    p.gains = (struct microstep_gains){a[12], a[13] != 0, false, false};
    p.Ts = a[14], p.v_limit = a[15];
    CHECK(microstep_init(&s, &p) == MICROSTEP_PARAMS_OK, "line %d: init", line);
    s.integral[0] = a[17], s.integral[1] = a[18];
    st = microstep_step(&s, a[16], a + 19, out);
    CHECK(status_matches(st, a + 24, p.v_limit), "line %d: status %u", line, st);
    out[2] = s.integral[0], out[3] = s.integral[1];
    return compare_floor("ms", line, out, a + 24, 4);
}

// Returns the worst difference of one "cas" record: motor, plan, (wc, w, decoupling, Ts, v_limit), t, state,
// y, then Python's v and state after the step.
static double check_cascade(int line, const double *a)
{
    struct cascade_params p = {.motor = {0}};
    struct cascade s;
    double out[5];
    uint32_t st;
    motor_from(a, &p.motor);
    p.plan = (struct plan){a[6], a[7], a[8], a[9], a[10], a[11], NULL};
    p.gains =
        (struct cascade_gains){a[12], a[13] / 3, 2.25 * a[13], 0.75 * (a[13] * a[13]), a[14] != 0, false, false, 0};
    p.Ts = a[15], p.v_limit = a[16];
    CHECK(cascade_init(&s, &p) == CASCADE_PARAMS_OK, "line %d: init", line);
    memcpy(s.integral, a + 18, 3 * sizeof *a);
    st = cascade_step(&s, a[17], a + 21, out);
    CHECK(status_matches(st, a + 26, p.v_limit), "line %d: status %u", line, st);
    memcpy(out + 2, s.integral, 3 * sizeof *out);
    return compare_floor("cas", line, out, a + 26, 5);
}

// Returns the worst difference of one "el" record: motor, plan, (wn, xi, p3, pd), measurement, v_limit, t, y,
// then Python's v.
static double check_linearization(int line, const double *a)
{
    struct exact_linearization_params p = {.motor = {0}};
    struct exact_linearization s;
    double out[2];
    uint32_t st;
    motor_from(a, &p.motor);
    p.plan = (struct plan){a[6], a[7], a[8], a[9], a[10], a[11], NULL};
    p.gains = (struct exact_linearization_gains){a[12], a[13], a[14], a[15]};
    p.measurement = (int)a[16], p.v_limit = a[17];
    CHECK(exact_linearization_init(&s, &p) == EXACT_LINEARIZATION_PARAMS_OK, "line %d: init", line);
    st = exact_linearization_step(&s, a[18], a + 19, out);
    CHECK(status_matches(st, a + 24, p.v_limit), "line %d: status %u", line, st);
    return compare_floor("el", line, out, a + 24, 2);
}

// Returns the worst difference of one "plant" record: motor, load, (T_d, T_c, omega_s, R_m or 0), x, v, then
// Python's plant_rhs (the detent on Python's fixed fourth harmonic).
static double check_plant(int line, const double *a)
{
    struct plant p;
    double dx[4];
    motor_from(a, &p.motor);
    p.load = a[6];
    p.effects = (struct plant_effects){a[7], 4, a[8], a[9], a[10]};
    CHECK(plant_valid(&p), "line %d: plant", line);
    plant_rhs(&p, a + 11, a + 15, dx);
    return compare_floor("plant", line, dx, a + 17, 4);
}

// Returns the number of records read; checks each against the C core and prints the worst differences.
int test_vectors(const char *path)
{
    static const char *kinds[] = {"plan", "fv", "f2s", "s2f", "smc", "ms", "cas", "el", "plant"};
    char line[8192], kind[16];
    double a[MAX_NUMS], out[8], worst[9] = {0}, r = 0;
    int counts[9] = {0}, lineno = 0, n, k, total = 0;
    FILE *f = fopen(path, "r");
    CHECK(f != NULL, "cannot open %s", path);
    if (!f)
        return 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (line[0] == '#' || sscanf(line, "%15s", kind) != 1)
            continue;
        n = parse(line + strlen(kind), a);
        if (strcmp(kind, "plan") == 0 && n == 13) {
            struct plan p = {a[0], a[1], a[2], a[3], a[4], a[5], NULL};
            plan_eval(&p, a[6], out);
            r = compare(kind, lineno, out, a + 7, 6), k = 0;
        } else if (strcmp(kind, "fv") == 0 && n == 16) {
            struct motor_params m;
            motor_from(a, &m);
            CHECK(flat_voltages(&m, a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[13], out) == FLAT_OK, "line %d",
                  lineno);
            r = compare(kind, lineno, out, a + 14, 2), k = 1;
        } else if (strcmp(kind, "f2s") == 0 && n == 19) {
            struct motor_params m;
            motor_from(a, &m);
            CHECK(flat_to_state(&m, a + 7, a[6], out, out + 4) == FLAT_OK, "line %d", lineno);
            r = compare(kind, lineno, out, a + 13, 6), k = 2;
        } else if (strcmp(kind, "s2f") == 0 && n == 19) {
            struct motor_params m;
            motor_from(a, &m);
            CHECK(state_to_flat(&m, a + 7, a + 11, a[6], out) == FLAT_OK, "line %d", lineno);
            r = compare(kind, lineno, out, a + 13, 6), k = 3;
        } else if (strcmp(kind, "smc") == 0 && n == 27) {
            struct smc_params p;
            struct smc s;
            smc_params_default(&p);
            motor_from(a, &p.motor);
            p.plan = (struct plan){a[6], a[7], a[8], a[9], a[10], a[11], NULL};
            p.gains = (struct smc_gains){a[12], a[13], a[14], a[15], a[16], a[17], 0};  // the vectors predate the hold
            p.measurement = (int)a[18];
            CHECK(smc_init(&s, &p) == SMC_PARAMS_OK, "line %d", lineno);
            CHECK(smc_step(&s, a[19], a + 20, out) == SMC_OK, "line %d: status", lineno);
            r = compare(kind, lineno, out, a + 25, 2), k = 4;
        } else if (strcmp(kind, "ms") == 0 && n == 28) {
            r = check_microstep(lineno, a), k = 5;
        } else if (strcmp(kind, "cas") == 0 && n == 31) {
            r = check_cascade(lineno, a), k = 6;
        } else if (strcmp(kind, "el") == 0 && n == 26) {
            r = check_linearization(lineno, a), k = 7;
        } else if (strcmp(kind, "plant") == 0 && n == 21) {
            r = check_plant(lineno, a), k = 8;
        } else {
            CHECK(0, "line %d: unknown record '%s' with %d numbers", lineno, kind, n);
            continue;
        }
        counts[k]++;
        worst[k] = r > worst[k] ? r : worst[k];
        total++;
    }
    fclose(f);
    for (k = 0; k < 9; k++) {
        printf("  %-5s %5d records, max relative difference %.3g\n", kinds[k], counts[k], worst[k]);
        CHECK(counts[k] > 0, "no %s records in %s", kinds[k], path);
    }
    return total;
}
