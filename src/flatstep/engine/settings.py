"""How a continuous-time run is solved: :class:`Continuous`.

A sampled run is described by :class:`~flatstep.loop.reference.DriveLoop`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Optional

from ..validate import check_integer, check_quantity

#: Integrators of the C continuous loop (csrc/continuous.h) and of :func:`scipy.integrate.solve_ivp`.
C_METHODS = ("DOP853", "DOPRI5", "DOP853-dense7")
SCIPY_METHODS = ("LSODA", "Radau", "BDF", "DOP853", "RK45")


@dataclass(frozen=True)
class Continuous:
    """Continuous-time control: the law evaluated inside the plant's right-hand side, solved adaptively.

    Parameters
    ----------
    method : str, optional
        The integrator: on the C engine one of :data:`C_METHODS` (default ``"DOP853"``, Dormand-Prince 8(5,3)
        with Hermite output), on the scipy engine one of :data:`SCIPY_METHODS` (default ``"LSODA"``, the
        fastest of them on this mildly stiff loop); ``None``: the engine's default.
    rtol, atol : float
        Relative and absolute error tolerances, > 0.
    dt_out : float
        Spacing of the returned samples [s], > 0.
    max_steps : int
        Bound on the integrator's accepted steps over the run (C engine), or on its right-hand-side evaluations
        (scipy engine); a run that needs more stops with a RunError naming the bound.
    max_wall_time : float
        Bound on the wall time of a scipy run [s]; a run that takes longer stops with a RunError (the C engine
        is bounded by ``max_steps`` and stopped by Ctrl-C).
    """

    method: Optional[str] = None
    rtol: float = 1e-10
    atol: float = 1e-12
    dt_out: float = 1e-5
    max_steps: int = 10_000_000
    max_wall_time: float = 15.0

    def __post_init__(self) -> None:
        if self.method is not None and self.method not in C_METHODS + SCIPY_METHODS:
            raise ValueError(f"method={self.method!r} is not an integrator; valid: {C_METHODS} (C engine), "
                             f"{SCIPY_METHODS} (scipy engine)")
        for name, kind in (("rtol", "tolerance"), ("atol", "tolerance"), ("dt_out", "dt_out"),
                           ("max_wall_time", "period")):
            object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))
        object.__setattr__(self, "max_steps", check_integer("max_steps", self.max_steps, high=2**32 - 1))

    def as_dict(self) -> dict[str, Any]:
        """The settings, for a result's metadata."""
        return asdict(self)
