"""How a continuous-time run is solved: :class:`Continuous`.

A sampled run is described by :class:`~flatstep.loop.reference.DriveLoop`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Optional

from ..validate import check_positive

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
    """

    method: Optional[str] = None
    rtol: float = 1e-10
    atol: float = 1e-12
    dt_out: float = 1e-5

    def __post_init__(self) -> None:
        if self.method is not None and self.method not in C_METHODS + SCIPY_METHODS:
            raise ValueError(f"method={self.method!r} is not an integrator; valid: {C_METHODS} (C engine), "
                             f"{SCIPY_METHODS} (scipy engine)")
        for name, unit in (("rtol", ""), ("atol", ""), ("dt_out", " s")):
            object.__setattr__(self, name, check_positive(name, getattr(self, name), unit=unit))

    def as_dict(self) -> dict[str, Any]:
        """The settings, for a result's metadata."""
        return asdict(self)
