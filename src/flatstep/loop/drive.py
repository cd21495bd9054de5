"""The power stage: DC-bus saturation per H-bridge, averaged or switched PWM."""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import check_finite, check_positive

PWM_MODES = ("averaged", "switched")


@dataclass(frozen=True)
class Drive:
    """Two H-bridges on a DC bus.

    Parameters
    ----------
    v_bus : bus voltage [V]; each phase voltage is limited to ``|v| <= v_bus``.
    pwm : ``"averaged"`` (the bridge delivers the commanded voltage, default) or ``"switched"`` (bipolar,
        centre-aligned PWM at ``f_pwm``: the phase sees +-v_bus, with ``dead_time`` per edge during which the
        freewheeling diodes apply ``-sign(i) v_bus``).
    """

    v_bus: float = 24.0
    pwm: str = "averaged"
    f_pwm: float = 40e3
    dead_time: float = 0.0

    def __post_init__(self) -> None:
        check_positive("v_bus", self.v_bus, unit=" V")
        check_positive("f_pwm", self.f_pwm, unit=" Hz")
        if self.pwm not in PWM_MODES:
            raise ValueError(f"pwm={self.pwm!r} is not a PWM mode; valid: {PWM_MODES}")
        dt = check_finite("dead_time", self.dead_time)
        if not 0.0 <= dt < 0.25 / self.f_pwm:
            raise ValueError(f"dead_time={dt!r} s must be in [0, {0.25 / self.f_pwm:.3g}) s (a quarter PWM period)")

    def saturate(self, v: ArrayLike) -> NDArray[np.float64]:
        """Scale the voltage vector (va, vb) so that ``max(|va|, |vb|) <= v_bus``, keeping its direction."""
        v = np.asarray(v, dtype=float)
        peak = np.max(np.abs(v), axis=0)
        return v / np.maximum(1.0, peak / self.v_bus)

    def pwm_segments(self, v: ArrayLike, i: ArrayLike, Ts: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Piecewise-constant phase voltages over one control period ``Ts`` for commanded ``v`` (2,) and
        phase currents ``i`` (2,) at its start: returns (durations (m,), voltages (m, 2)).

        Averaged mode returns the single segment ``(Ts, v)``.
        """
        v = self.saturate(v)
        if self.pwm == "averaged":
            return np.array([Ts]), v[None, :]
        Tp = 1.0 / self.f_pwm
        n = max(1, int(round(Ts / Tp)))
        Tp = Ts / n
        edges = []
        for ph in range(2):
            d = 0.5 * (1.0 + v[ph] / self.v_bus)  # fraction of the period at +v_bus
            on, off = 0.5 * (1.0 - d) * Tp, 0.5 * (1.0 + d) * Tp
            free = -np.sign(i[ph]) * self.v_bus if i[ph] != 0 else 0.0
            td = min(self.dead_time, on, Tp - off) if self.dead_time > 0 else 0.0
            # (start, level) breakpoints within one PWM period for this phase
            pts = [(0.0, -self.v_bus), (on, free), (on + td, self.v_bus), (off, free), (off + td, -self.v_bus)]
            edges.append(pts)
        cuts = sorted({round(k * Tp + s, 15) for k in range(n) for pts in edges for s, _ in pts} | {Ts})
        cuts = np.array([c for c in cuts if c <= Ts])
        mid = 0.5 * (cuts[:-1] + cuts[1:])
        out = np.empty((mid.size, 2))
        for ph, pts in enumerate(edges):
            starts = np.array([s for s, _ in pts])
            vals = np.array([lv for _, lv in pts])
            out[:, ph] = vals[np.searchsorted(starts, np.mod(mid, Tp), side="right") - 1]
        dur = np.diff(cuts)
        keep = dur > 0
        return dur[keep], out[keep]

    def as_dict(self) -> dict:
        return asdict(self)
