"""The boundary's checks: every value a user gives goes through them.

The Python constructors, the scenario files and the command line all use them.

* :mod:`~flatstep.validate.checks`: type, finiteness and range of one value (:class:`InputError`);
* :mod:`~flatstep.validate.ranges`: the valid range of every physical quantity, in one table;
* :mod:`~flatstep.validate.limits`: whether a run is consistent (``0 <= t0 < tf <= t_end``, a control period well
  below the move) and affordable (samples, memory, integration steps, PWM edges), with the documented limits.
"""
from .checks import (
    InputError,
    check_bool,
    check_choice,
    check_count,
    check_finite,
    check_instance,
    check_integer,
    check_nonnegative,
    check_positive,
    check_quantity,
    check_sequence,
    short_repr,
)
from .ranges import INTEGER_RANGES, QUANTITIES

__all__ = ["InputError", "check_bool", "check_choice", "check_count", "check_finite", "check_instance",
           "check_integer", "check_nonnegative", "check_positive", "check_quantity", "check_sequence", "short_repr",
           "INTEGER_RANGES", "QUANTITIES"]

