// The moves of benchmarks/field_weakening_optimum.py (its three motors at their i_max, 12 V and 24 V, v_use 0.84,
// the 20 kHz commutation cap) and the durations the double build of time_optimal_dq_plan gives them: the single-
// precision build must plan them within TOD_FLOAT_TOL (csrc/tests/test_float_dq.c). The double suite
// (test_time_optimal_dq.c) checks that the table still is the double planner's; where the planner changes, print
// the new durations with `ctest -R time_optimal_dq -V` and copy them here.
#ifndef FS_TIME_OPTIMAL_DQ_CASES_H
#define FS_TIME_OPTIMAL_DQ_CASES_H

#include "motor.h"

#define TOD_FLOAT_TOL 0.01    // the float build's durations against the table's, relatively
#define TOD_DOUBLE_TOL 0.001  // the double build's against the table's, relatively

// A motor of the benchmark and its i_max [A] (the preset at 1 A, the datasheets at their rated current norm).
struct tod_case_motor {
    const char *name;
    struct motor_params m;
    double i_max;
    double ms[2][5];  // the double durations [ms] at TOD_CASE_BUS x TOD_CASE_DISTANCE
};

static const double TOD_CASE_BUS[2] = {12.0, 24.0};
static const double TOD_CASE_DISTANCE[5] = {0.1, 0.3, 1.0, 5.0, 20.0};

static const struct tod_case_motor TOD_CASES[3] = {
    {"nema17",
     {FS_C(4.10), FS_C(9.50e-3), FS_C(0.26870057685088805), FS_C(5.6e-6), FS_C(1e-4), 50},
     1.0,
     {{4.472825, 7.781678, 16.168607, 61.869964, 233.250018}, {3.563468, 6.110441, 14.109262, 59.810610, 231.190664}}},
    {"ldo-42sth60-2004mac",
     {FS_C(1.4), FS_C(3e-3), FS_C(0.20803081502508228), FS_C(1.2e-5), FS_C(1e-4), 100},
     2.8284271247461903,
     {{4.541653, 9.154536, 25.150027, 116.552723, 459.312830},
      {3.766101, 8.336803, 24.332275, 115.734970, 458.495077}}},
    {"sanyo-103h5208-5240",
     {FS_C(9.5), FS_C(4.1e-3), FS_C(0.2757716446627535), FS_C(5.6e-6), FS_C(1e-4), 50},
     1.4142135623730951,
     {{4.037926, 8.299247, 21.758992, 97.629677, 382.143768}, {2.941615, 5.335300, 13.333041, 59.034389, 230.414443}}},
};

#endif
