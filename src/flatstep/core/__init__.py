"""Thin binding to the C core (csrc/), built at install time by cffi (:mod:`flatstep.core.build`).

The binding is the top of the model-to-loop layers: it imports the parts (model, plan, control, loop) and
nothing below it imports the binding. Each part gives the fields of its own C struct (``MotorParams.c_params``,
a plan's ``c_plan``, a controller's ``c_params``, ...), so the binding knows no part's field names.

Every function takes and returns NumPy arrays and makes one C call per array: no Python loop over samples.
The binding follows the data flow in three modules, re-exported here:

* :mod:`flatstep.core.structs`: the cffi handle (``ffi``, ``lib``), status bits and limits, the struct
  builders (``motor_struct``, ``plan_struct``, ``smc_struct``, ``controller_struct``) and the array marshalling;
* :mod:`flatstep.core.maps`: planner, flat maps and controller over arrays (``plan_flag``, ``flat_voltages``,
  ``flat_to_state``, ``state_to_flat``, ``plan_to_state``, ``smc_voltages``);
* :mod:`flatstep.core.runs`: closed-loop runs and their results (``run_continuous``, ``result_columns``,
  ``continuous_result``, ``run_sampled``, ``run_sampled_summaries``, ``drive_unsupported``).

:mod:`flatstep.core.traj` evaluates a piecewise plan's C ``struct traj`` over arrays.
"""
from .maps import flat_to_state, flat_voltages, plan_flag, plan_to_state, smc_voltages, state_to_flat
from .runs import (
    CONTINUOUS_METHODS,
    RESULT_COLUMNS,
    SUMMARY_KEYS,
    continuous_result,
    drive_unsupported,
    result_columns,
    run_continuous,
    run_sampled,
    run_sampled_summaries,
)
from .structs import (
    FAULT_BITS,
    RHO_MIN,
    STATUS_BITS,
    V_LIMIT,
    Array,
    BoundController,
    controller_struct,
    ffi,
    lib,
    motor_struct,
    plan_struct,
    smc_struct,
    status_names,
)

__all__ = ["CONTINUOUS_METHODS", "FAULT_BITS", "RESULT_COLUMNS", "RHO_MIN", "STATUS_BITS", "SUMMARY_KEYS",
           "V_LIMIT", "Array", "BoundController", "continuous_result", "controller_struct", "drive_unsupported", "ffi",
           "flat_to_state", "flat_voltages",
           "lib", "motor_struct", "plan_flag", "plan_struct", "plan_to_state", "result_columns", "run_continuous",
           "run_sampled", "run_sampled_summaries", "smc_struct", "smc_voltages", "state_to_flat",
           "status_names"]
