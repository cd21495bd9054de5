// Entry point of the C unit tests: `test_core <suite> [vector file]`, one ctest test per suite.
#include <string.h>
#include "check.h"

int check_count, check_failures;

// Returns 0 when every check of the named suite passed, 1 otherwise (2 for an unknown suite).
int main(int argc, char **argv)
{
    const char *suite = argc > 1 ? argv[1] : "";
    if (strcmp(suite, "vectors") == 0 && argc > 2)
        test_vectors(argv[2]);
    else if (strcmp(suite, "plan") == 0)
        test_plan();
    else if (strcmp(suite, "smc") == 0)
        test_smc();
    else if (strcmp(suite, "ode") == 0)
        test_ode();
    else if (strcmp(suite, "sim") == 0)
        test_sim();
    else if (strcmp(suite, "drive") == 0)
        test_drive();
    else if (strcmp(suite, "baselines") == 0)
        test_baselines();
    else if (strcmp(suite, "dq_smc") == 0)
        test_dq_smc();
    else if (strcmp(suite, "trajectory") == 0)
        test_trajectory();
    else if (strcmp(suite, "time_optimal") == 0)
        test_time_optimal();
    else if (strcmp(suite, "time_optimal_dq") == 0)
        test_time_optimal_dq();
    else {
        printf("usage: %s vectors FILE | plan | smc | ode | sim | drive | baselines | dq_smc | trajectory | "
               "time_optimal | time_optimal_dq\n",
               argv[0]);
        return 2;
    }
    printf("%s: %d checks, %d failed\n", suite, check_count, check_failures);
    return check_failures != 0 || check_count == 0;
}
