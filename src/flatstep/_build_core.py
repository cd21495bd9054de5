"""cffi API-mode build of the C core (csrc/) as ``flatstep._flatstep_core``; run by setuptools at install time.

setup.py names this file in ``cffi_modules``; nothing imports it at run time and nothing compiles at run time.
"""
from __future__ import annotations

import os
from pathlib import Path

from cffi import FFI

ROOT = Path(__file__).resolve().parents[2]
MODULES = ("motor", "plan", "flat", "smc", "ode", "sim", "batch", "sensors", "observer", "drive", "sampled")
#: Sources beyond one per module header (ode.h declares both integrators).
EXTRA_SOURCES = ("ode_dop853",)

CDEF = """
typedef double fs_real;

struct motor_params { fs_real R; fs_real L; fs_real Km; fs_real J; fs_real B; int Nr; };
struct plan { fs_real theta1; fs_real theta2; fs_real rho1; fs_real rho2; fs_real t0; fs_real tf; };
struct smc_gains { fs_real W1; fs_real W2; fs_real eps1; fs_real eps2; fs_real xi; fs_real wn;
                   fs_real hold_damping; };
struct smc_params { struct motor_params motor; struct plan plan; struct smc_gains gains; int measurement;
                    fs_real v_limit; fs_real rho_min; };
struct smc { struct smc_params p; fs_real alpha1; fs_real alpha2; uint32_t status_seen; ...; };
struct sim_plant { struct motor_params motor; fs_real load; };
struct sim_continuous_params { fs_real rtol; fs_real atol; fs_real h_max; uint32_t max_steps; uint32_t method; };
enum sim_method { SIM_DOP853, SIM_DOPRI5, SIM_DOP853_DENSE };
struct sim_sampled_params { fs_real Ts; uint32_t substeps; };
struct sim_stats { uint32_t steps; uint32_t rejected; uint32_t rhs_evals; uint32_t smc_status; fs_real t_fail; };

enum smc_measurement { SMC_IDEAL, SMC_MODEL, ... };
enum smc_status { SMC_OK, SMC_NONFINITE, SMC_RHO, SMC_SQRT, SMC_OVERFLOW, SMC_SATURATED, ... };
enum smc_param_error { SMC_PARAMS_OK, SMC_EMOTOR, SMC_EPLAN, SMC_EGAINS, SMC_EMEASUREMENT, SMC_ELIMITS, ... };
enum sim_status { SIM_OK, SIM_EARGS, SIM_ECONTROL, SIM_EHMIN, SIM_EMAXSTEPS, SIM_ENONFINITE, ... };
enum { FLAT_OK, FLAT_ERHO, FLAT_ESQRT, ... };

int smc_init(struct smc *s, const struct smc_params *p);
void smc_reset(struct smc *s);
uint32_t smc_step(struct smc *s, fs_real t, const fs_real y[5], fs_real v[2]);
void smc_params_default(struct smc_params *p);
fs_real plan_psi(fs_real t, fs_real t0, fs_real tf, int order);

void batch_plan_eval(const struct plan *p, const fs_real *t, size_t n, fs_real *flag);
size_t batch_flat_voltages(const struct motor_params *m, const fs_real *args, size_t n, fs_real *v);
size_t batch_flat_to_state(const struct motor_params *m, const fs_real *flag, size_t n, fs_real load, fs_real *x,
                           fs_real *v);
size_t batch_state_to_flat(const struct motor_params *m, const fs_real *x, const fs_real *v, size_t n,
                           fs_real load, fs_real *flag);
uint32_t batch_smc_step(struct smc *s, const fs_real *t, const fs_real *y, size_t n, fs_real *v, uint32_t *status);
size_t batch_plan_flat(const struct plan *p, const struct motor_params *m, const fs_real *t, size_t n,
                       fs_real load, fs_real *flag, fs_real *x, fs_real *v);
enum { RES_VA, RES_VB, RES_ACC, RES_RHO, RES_PHI, RES_THETA_REF, RES_OMEGA_REF, RES_RHO_REF, RES_IA_REF,
       RES_IB_REF, RES_VA_REF, RES_VB_REF, RES_S1, RES_S2, RES_LEN };
size_t batch_result(struct smc *s, const struct motor_params *plant, fs_real load, const fs_real *t,
                    const fs_real *x, size_t n, fs_real *out, uint32_t *status);
struct batch_run { struct smc_params ctrl; struct sim_plant plant; struct sim_sampled_params sp; size_t n_periods;
                   fs_real x0[4]; };
struct batch_summary { int status; uint32_t controller_status; fs_real theta_final; fs_real ia_final;
                       fs_real ib_final; fs_real omega_final; fs_real final_theta_error; fs_real max_abs_theta_error;
                       fs_real max_abs_rho_error; fs_real max_abs_va; fs_real max_abs_vb;
                       fs_real max_abs_theta_error_move; fs_real max_abs_theta_error_after; size_t n_move;
                       size_t n_after; };
size_t batch_sampled(const struct batch_run *runs, size_t n, fs_real *scratch, size_t scratch_len,
                     struct batch_summary *out);

struct sensors_params { fs_real angle_step; fs_real encoder_offset; fs_real current_step; fs_real current_range;
                        fs_real current_offset[2]; uint32_t delay; };
struct observer_params { uint32_t order; fs_real Ad[4][4]; fs_real Bd[4]; fs_real Lc[4]; };
struct drive_params { fs_real v_bus; bool compute_delay; };
struct sampled_params { fs_real Ts; uint32_t substeps; bool sensed; bool observed; struct sensors_params sensors;
                        struct observer_params observer; struct drive_params drive; };
struct sampled { ...; };
#define SENSORS_MAX_DELAY ...

int sampled_init(struct sampled *s, const struct sampled_params *p);
int sampled_run(struct sampled *s, struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4],
                size_t n_periods, const fs_real *noise, fs_real *x_out, fs_real *v_out, fs_real *y_out,
                uint32_t *status_out, struct sim_stats *st);
int sim_continuous(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], const fs_real *t_out,
                   size_t n_out, const struct sim_continuous_params *p, fs_real *x_out, struct sim_stats *st);
int sim_sampled(struct smc *ctrl, const struct sim_plant *plant, const fs_real x0[4], fs_real t_start,
                size_t n_periods, const struct sim_sampled_params *p, fs_real *x_out, fs_real *v_out,
                struct sim_stats *st);
"""


def _relative(path: Path) -> str:
    """Source paths relative to the working directory (setuptools runs from the project root)."""
    try:
        return os.path.relpath(path)
    except ValueError:  # another drive on Windows
        return str(path)


ffibuilder = FFI()
ffibuilder.cdef(CDEF)
ffibuilder.set_source(
    "flatstep._flatstep_core",
    "\n".join(f'#include "{m}.h"' for m in MODULES),
    sources=[_relative(ROOT / "csrc" / f"{m}.c") for m in MODULES + EXTRA_SOURCES],
    include_dirs=[_relative(ROOT / "csrc")],
    # C99 also keeps GCC from contracting a*b+c into FMAs, so the core rounds like the NumPy reference.
    extra_compile_args=["-std=c99", "-O2"] if os.name != "nt" else [],
    libraries=["m"] if os.name != "nt" else [],
)

if __name__ == "__main__":
    ffibuilder.compile(verbose=True)
