"""The power stage: DC-bus saturation per H-bridge, averaged or switched PWM."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import InputError, check_choice, check_finite, check_quantity

#: The bridge's modes, in the order of C ``enum drive_pwm`` (csrc/drive.h: ``DRIVE_AVERAGED = 0``,
#: ``DRIVE_SWITCHED = 1``).
PWM_MODES = ("averaged", "switched")


@dataclass(frozen=True)
class Drive:
    """Two H-bridges on a DC bus.

    Parameters
    ----------
    v_bus : float
        Bus voltage [V], > 0; each phase voltage is limited to ``|v| <= v_bus``.
    pwm : {"averaged", "switched"}
        ``"averaged"`` (the bridge delivers the commanded voltage, default) or ``"switched"`` (bipolar,
        centre-aligned PWM at ``f_pwm``: the phase sees +-v_bus, with ``dead_time`` per edge during which the
        freewheeling diodes apply ``-sign(i) v_bus``).
    f_pwm : float
        PWM frequency [Hz], > 0 (switched mode).
    dead_time : float
        Dead time per edge [s], in [0, 1/(4 f_pwm)) (switched mode).
    """

    v_bus: float = 24.0
    pwm: str = "averaged"
    f_pwm: float = 40e3
    dead_time: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "v_bus", check_quantity("v_bus", self.v_bus))
        object.__setattr__(self, "f_pwm", check_quantity("rate", self.f_pwm, as_name="f_pwm"))
        check_choice("pwm", self.pwm, PWM_MODES)
        dt = check_finite("dead_time", self.dead_time)
        if not 0.0 <= dt < 0.25 / self.f_pwm:
            raise InputError("dead_time", dt,
                             f"dead_time={dt!r} s must be in [0, {0.25 / self.f_pwm:.3g}) s (a quarter PWM period)")
        object.__setattr__(self, "dead_time", dt)

    def saturate(self, v: ArrayLike) -> NDArray[np.float64]:
        """Scale the voltage vector (va, vb) so that ``max(|va|, |vb|) <= v_bus``, keeping its direction."""
        v = np.asarray(v, dtype=float)
        peak = np.max(np.abs(v), axis=0)
        return v / np.maximum(1.0, peak / self.v_bus)

    def pwm_periods(self, Ts: float) -> int:
        """The number ``n = max(1, round(Ts f_pwm))`` of PWM periods in a control period ``Ts``, each ``Ts / n``."""
        return max(1, int(round(Ts / (1.0 / self.f_pwm))))

    def pwm_period(self, v: ArrayLike, i: ArrayLike, Tp: float) -> tuple[list[float], list[tuple[float, float]]]:
        """The segments of one PWM period, in the arithmetic of C ``drive_pwm_period``.

        Each phase has five breakpoints within the period, at offsets ``0, on, on + td, off, off + td`` with
        levels ``-v_bus, free, +v_bus, free, -v_bus`` (centre-aligned: ``on = (1 - d) Tp / 2``,
        ``off = (1 + d) Tp / 2`` for the duty ``d = (1 + v / v_bus) / 2``; ``free = -sign(i) v_bus`` during the
        dead time ``td = min(dead_time, on, Tp - off)``). The segments start at every distinct breakpoint below
        ``Tp`` in increasing order; on each, a phase has the level of its last breakpoint (in the order above) at
        or before the segment's start, so a high pulse shorter than the dead time vanishes into freewheeling.

        Parameters
        ----------
        v : array_like
            The commanded phase voltages (va, vb) [V], saturated here.
        i : array_like
            The phase currents (ia, ib) [A] that choose the freewheeling level.
        Tp : float
            The PWM period [s].

        Returns
        -------
        durations : list of float
            At most 9 segment durations [s], summing to ``Tp`` up to rounding.
        levels : list of (float, float)
            The phase voltages (va, vb) [V] on each segment.
        """
        vs = [float(u) for u in self.saturate(v)]
        cur = [float(c) for c in np.asarray(i, dtype=float)]
        starts: list[list[float]] = []
        levels: list[list[float]] = []
        for ph in range(2):
            d = 0.5 * (1.0 + vs[ph] / self.v_bus)  # fraction of the period at +v_bus
            on, off = 0.5 * (1.0 - d) * Tp, 0.5 * (1.0 + d) * Tp
            free = -self.v_bus if cur[ph] > 0 else (self.v_bus if cur[ph] < 0 else 0.0)  # freewheeling diodes
            td = min(self.dead_time, on, Tp - off) if self.dead_time > 0 else 0.0
            starts.append([0.0, on, on + td, off, off + td])
            levels.append([-self.v_bus, free, self.v_bus, free, -self.v_bus])
        durations: list[float] = []
        out: list[tuple[float, float]] = []
        t = 0.0
        while t < Tp:
            nxt = min([Tp] + [s for ph in range(2) for s in starts[ph] if s > t])  # the next breakpoint
            va, vb = (next(levels[ph][j] for j in range(4, -1, -1) if starts[ph][j] <= t) for ph in range(2))
            durations.append(nxt - t)
            out.append((va, vb))
            t = nxt
        return durations, out

    def pwm_segments(self, v: ArrayLike, i: ArrayLike, Ts: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Piecewise-constant phase voltages over one control period.

        Averaged mode returns the single segment ``(Ts, saturated v)``. Switched mode returns the segments of
        :meth:`pwm_period` for ``Tp = Ts / n``, repeated for the :meth:`pwm_periods` ``n`` PWM periods (the
        command and the currents are those of the control period's start).

        Parameters
        ----------
        v : array_like
            The commanded phase voltages (va, vb) [V].
        i : array_like
            The phase currents (ia, ib) [A] at the start of the control period.
        Ts : float
            The control period [s].

        Returns
        -------
        durations : ndarray
            The (m,) segment durations [s].
        levels : ndarray
            The (m, 2) phase voltages on each segment [V].
        """
        if self.pwm == "averaged":
            return np.array([Ts]), self.saturate(v)[None, :]
        n = self.pwm_periods(Ts)
        dur, lv = self.pwm_period(v, i, Ts / n)
        return np.tile(np.array(dur), n), np.tile(np.array(lv), (n, 1))

    def as_dict(self) -> dict[str, Any]:
        """The parameters as a dict, for a result's metadata."""
        return asdict(self)

    def c_params(self, compute_delay: bool = False) -> dict[str, Any]:
        """The fields of the C ``struct drive_params`` (csrc/drive.h) for this drive.

        Parameters
        ----------
        compute_delay : bool
            Apply each command one period after it is computed (a setting of the loop, kept in this struct).
        """
        return dict(v_bus=self.v_bus, compute_delay=bool(compute_delay), pwm=PWM_MODES.index(self.pwm),
                    f_pwm=self.f_pwm, dead_time=self.dead_time)

    @staticmethod
    def c_ideal_params(compute_delay: bool = False) -> dict[str, Any]:
        """The fields of the C ``struct drive_params`` without a drive: an unlimited averaged bridge (v_bus = inf)."""
        return dict(v_bus=math.inf, compute_delay=bool(compute_delay))
