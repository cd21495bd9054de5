// The stages of the field-weakening planner (csrc/time_optimal_dq.c): the d-q envelope
// (time_optimal_dq_envelope.c, flatstep.plan.time_optimal_dq_envelope). Internal: not bound by Python.
#ifndef FS_TIME_OPTIMAL_DQ_STAGES_H
#define FS_TIME_OPTIMAL_DQ_STAGES_H

#include <stdbool.h>
#include "time_optimal_dq.h"
#include "time_optimal_stages.h"

// time_optimal_dq_envelope.c
// Returns true and writes the envelope at bus voltage v, current i_max and speed cap into w->omega, w->ap, w->am
// (TO_GRID speeds) and its d currents into idp, idm; false when the motor cannot start or the envelope is no
// number.
bool tod_envelope(const struct motor_params *m, fs_real v, fs_real i_max, fs_real cap, struct to_work *w, fs_real *idp,
                  fs_real *idm);

#endif
