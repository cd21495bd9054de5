// Parity with the Python reference: every record of tests/vectors/core.txt agrees to 1e-12 relative.
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "arrays.h"
#include "flat.h"
#include "plan.h"
#include "smc.h"

#define TOL 1e-12
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
        CHECK(fabs(c[k] - p[k]) <= TOL * fabs(p[k]), "%s line %d component %d: C %.17g vs Python %.17g", kind, line,
              k, c[k], p[k]);
    }
    return worst;
}

// Returns the number of records read; checks each against the C core and prints the worst differences.
int test_vectors(const char *path)
{
    static const char *kinds[] = {"plan", "fv", "f2s", "s2f", "smc"};
    char line[8192], kind[16];
    double a[MAX_NUMS], out[8], worst[5] = {0}, r = 0;
    int counts[5] = {0}, lineno = 0, n, k, total = 0;
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
            struct plan p = {a[0], a[1], a[2], a[3], a[4], a[5]};
            plan_eval(&p, a[6], out);
            r = compare(kind, lineno, out, a + 7, 6), k = 0;
        } else if (strcmp(kind, "fv") == 0 && n == 16) {
            struct motor_params m;
            motor_from(a, &m);
            CHECK(flat_voltages(&m, a[6], a[7], a[8], a[9], a[10], a[11], a[12], a[13], out) == FLAT_OK, "line %d", lineno);
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
            p.plan = (struct plan){a[6], a[7], a[8], a[9], a[10], a[11]};
            p.gains = (struct smc_gains){a[12], a[13], a[14], a[15], a[16], a[17], 0};  // the vectors predate the hold
            p.measurement = (int)a[18];
            CHECK(smc_init(&s, &p) == SMC_PARAMS_OK, "line %d", lineno);
            CHECK(smc_step(&s, a[19], a + 20, out) == SMC_OK, "line %d: status", lineno);
            r = compare(kind, lineno, out, a + 25, 2), k = 4;
        } else {
            CHECK(0, "line %d: unknown record '%s' with %d numbers", lineno, kind, n);
            continue;
        }
        counts[k]++;
        worst[k] = r > worst[k] ? r : worst[k];
        total++;
    }
    fclose(f);
    for (k = 0; k < 5; k++) {
        printf("  %-5s %5d records, max relative difference %.3g\n", kinds[k], counts[k], worst[k]);
        CHECK(counts[k] > 0, "no %s records in %s", kinds[k], path);
    }
    return total;
}
