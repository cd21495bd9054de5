"""Sensors of a drive: a quantized encoder and quantized, offset, noisy phase-current sensors."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validate import InputError, check_bool, check_count, check_finite, check_quantity


@dataclass(frozen=True)
class Sensors:
    """What the controller measures.

    Parameters
    ----------
    encoder_counts : int, optional
        Counts per revolution; the angle is read as the centre of its count,
        ``q round(theta/q - offset) + q offset`` with ``q = 2 pi / counts``; ``None``: exact angle.
    encoder_offset : float
        Where the count edges sit, as a fraction of a count in [-0.5, 0.5).
    current_bits : int, optional
        ADC resolution over ``[-current_range, current_range]`` A; ``None``: exact currents.
    current_range : float
        The ADC's full scale [A].
    current_offset : tuple of float
        Constant offsets (ia, ib) added before conversion [A].
    current_noise : float
        Standard deviation of the white noise added to each phase current [A].
    delay : int
        Measurement delay in control periods (the controller sees the samples of ``delay`` periods ago).
    seed : int
        Seed of the noise sequence (reproducible runs).
    edge_timing : bool
        The encoder interface also latches the time of each count edge (a capture timer, its resolution
        neglected): a reading then carries the angle of the last edge crossed, ``theta_m -+ q/2`` behind the
        motion, and its age at the sample, ``(theta - theta_edge)/omega`` from the rotor's speed at the sample
        (exact to the acceleration's share ``a age^2/2``); :meth:`read_edge`.
    """

    encoder_counts: Optional[int] = 16384
    encoder_offset: float = 0.0
    current_bits: Optional[int] = 12
    current_range: float = 2.0
    current_offset: tuple[float, float] = (0.0, 0.0)
    current_noise: float = 0.0
    delay: int = 0
    seed: int = 0
    edge_timing: bool = False

    def __post_init__(self) -> None:
        for name in ("encoder_counts", "current_bits", "delay"):
            if getattr(self, name) is not None or name == "delay":
                object.__setattr__(self, name, check_count(name, getattr(self, name),
                                                           why="or None for an exact measurement"
                                                           if name != "delay" else "control periods"))
        object.__setattr__(self, "seed", check_count("seed", self.seed, why="the noise's seed"))
        off = check_finite("encoder_offset", self.encoder_offset)
        if not -0.5 <= off < 0.5:
            raise InputError("encoder_offset", off, f"encoder_offset={off!r} must be in [-0.5, 0.5) counts")
        object.__setattr__(self, "current_range", check_quantity("current_range", self.current_range))
        if not isinstance(self.current_offset, (tuple, list)) or len(self.current_offset) != 2:
            raise InputError("current_offset", self.current_offset,
                             f"current_offset={self.current_offset!r} must be two offsets (ia, ib) in A")
        object.__setattr__(self, "current_offset",
                           tuple(check_quantity("current_offset", o) for o in self.current_offset))
        object.__setattr__(self, "current_noise", check_quantity("current_noise", self.current_noise))
        object.__setattr__(self, "edge_timing", check_bool("edge_timing", self.edge_timing))

    @property
    def angle_step(self) -> float:
        """One encoder count [rad] (0 for an exact angle)."""
        return 0.0 if self.encoder_counts is None else 2 * math.pi / self.encoder_counts

    @property
    def current_step(self) -> float:
        """One ADC step [A] (0 for exact currents)."""
        return 0.0 if self.current_bits is None else 2 * self.current_range / 2**self.current_bits

    def read_angle(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Encoder reading of the true angle ``theta``."""
        theta = np.asarray(theta, dtype=float)
        q = self.angle_step
        if q == 0.0:
            return theta
        return q * (np.round(theta / q - self.encoder_offset) + self.encoder_offset)

    def read_edge(self, theta: float, omega: float) -> tuple[float, float]:
        """``(theta_edge, age)``: the last count edge the rotor crossed and how long ago [s], or ``(0, -1)``: none.

        None without ``edge_timing``, an encoder or motion (``omega = 0``). In C: ``sensors_edge``.
        """
        q = self.angle_step
        if not self.edge_timing or q == 0.0 or omega == 0.0:
            return 0.0, -1.0
        edge = float(self.read_angle(theta)) - math.copysign(0.5 * q, omega)
        return edge, (theta - edge) / omega

    def read_currents(self, i: ArrayLike, noise: ArrayLike = 0.0) -> NDArray[np.float64]:
        """ADC reading of the phase currents ``i`` (2, ...) with the given noise sample(s) added."""
        offset = np.asarray(self.current_offset).reshape((2,) + (1,) * (np.ndim(i) - 1))
        i_in = np.asarray(i, dtype=float) + offset + noise
        q = self.current_step
        if q == 0.0:
            return i_in
        return np.clip(q * np.round(i_in / q), -self.current_range, self.current_range)

    def noise(self, n: int) -> NDArray[np.float64]:
        """The (n, 2) current-noise sequence of a run, from ``seed``."""
        if self.current_noise == 0.0:
            return np.zeros((n, 2))
        return self.current_noise * np.random.default_rng(self.seed).standard_normal((n, 2))

    def as_dict(self) -> dict[str, Any]:
        """The parameters as a dict, for a result's metadata."""
        return asdict(self)

    def c_params(self) -> dict[str, Any]:
        """The fields of the C ``struct sensors_params`` (csrc/sensors.h) for these sensors (the noise stays here)."""
        return dict(angle_step=self.angle_step, encoder_offset=self.encoder_offset, current_step=self.current_step,
                    current_range=self.current_range, current_offset=list(self.current_offset), delay=self.delay,
                    edge_timing=self.edge_timing)
