r"""Multi-segment moves: a list of waypoints (angles, optional speeds at via points, dwells) -> one piecewise plan.

The sequence is cut into *pieces* at every point where the rotor rests (the first and the last waypoint and any
waypoint with a dwell); a dwell becomes a segment holding the angle. Within a piece the family decides the shape:

============  =====================================================================================================
``psi``       the paper's polynomial (eq. 17) from waypoint to waypoint, resting at each; theta is :math:`C^4`.
``hermite``   degree-7 segments through the via points at a speed (given, or the harmonic mean of the adjacent
              chord slopes, 0 where they change sign), acceleration and jerk 0 there; theta is :math:`C^3`.
``spline``    one degree-7 interpolating spline per piece (:func:`scipy.interpolate.make_interp_spline`) with
              speed, acceleration and jerk 0 at its ends; theta is :math:`C^6` inside a piece, :math:`C^3` at rests.
``scurve``    the jerk-limited S-curve from waypoint to waypoint, resting at each (:func:`.segments.scurve_rows`);
              theta is :math:`C^2`, theta''' steps between -j, 0 and +j.
============  =====================================================================================================

Durations are given per move, or follow from speed, acceleration and jerk caps: the fastest psi or S-curve move
within them, and for ``hermite`` and ``spline`` the time scaling of the piece that brings its sampled peaks
(129 samples per segment) onto the caps.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Sequence, Union

import numpy as np
from numpy.typing import NDArray

from ..validate import InputError, check_instance, check_quantity, check_sequence, short_repr
from ..validate.checks import is_real
from ..validate.limits import MAX_OPTIMAL_MOVES
from .piecewise import NCOEF, PiecewisePlan, horner
from .segments import dwell_row, hermite_rows, psi_duration, psi_rows, scurve_rows

Array = NDArray[np.float64]
FAMILIES = ("psi", "hermite", "spline", "scurve")
_SAMPLES = np.linspace(0.0, 1.0, 129)


@dataclass(frozen=True)
class Waypoint:
    """An angle to pass [rad], the speed there [rad/s] (``None``: the family's choice) and a rest there [s]."""

    theta: float
    velocity: Optional[float] = None
    dwell: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "theta", check_quantity("angle", self.theta, as_name="waypoint theta"))
        if self.velocity is not None:
            object.__setattr__(self, "velocity", check_quantity("velocity", self.velocity, as_name="waypoint velocity"))
        object.__setattr__(self, "dwell", check_quantity("time", self.dwell, as_name="waypoint dwell"))


@dataclass(frozen=True)
class Caps:
    """Speed, acceleration and jerk caps [rad/s, rad/s^2, rad/s^3] that set durations not given.

    Each in its range of :mod:`flatstep.validate.ranges` (``speed``, ``acceleration``, ``jerk``).
    """

    v_max: float
    a_max: float
    j_max: float

    def __post_init__(self) -> None:
        for name, kind in (("v_max", "speed"), ("a_max", "acceleration"), ("j_max", "jerk")):
            object.__setattr__(self, name, check_quantity(kind, getattr(self, name), as_name=name))


def _peaks(rows: Array, h: Array) -> Array:
    """Sampled peaks of |theta'|, |theta''|, |theta'''| over segments ``rows`` (k, 11) of durations ``h``."""
    coef = np.repeat(rows, _SAMPLES.size, axis=0)
    tau = np.tile(_SAMPLES, rows.shape[0])
    ih = np.repeat(1.0 / h, _SAMPLES.size)
    return np.array([np.max(np.abs(horner(coef, tau, k) * ih**k)) for k in (1, 2, 3)])


def _scale(peaks: Array, caps: Caps) -> float:
    """The time-scaling factor that brings the peaks onto the caps (speed ~ 1/f, acceleration ~ 1/f^2, ...)."""
    return float(max(peaks[0] / caps.v_max, np.sqrt(peaks[1] / caps.a_max), np.cbrt(peaks[2] / caps.j_max)))


def _via_speeds(theta: Array, h: Array, given: list[Optional[float]]) -> Array:
    """Speeds at the waypoints of a piece: 0 at its ends, given, or the harmonic mean of the adjacent slopes."""
    s = np.diff(theta) / h
    s1, s2 = s[:-1], s[1:]
    v = np.zeros(theta.size)
    v[1:-1] = np.divide(2 * s1 * s2, s1 + s2, out=np.zeros_like(s1), where=s1 * s2 > 0)
    for i, g in enumerate(given[1:-1], start=1):
        if g is not None:
            v[i] = g
    return v


def _hermite(theta: Array, h: Array, given: list[Optional[float]]) -> Array:
    """Degree-7 rows through the piece's waypoints at their speeds."""
    v = _via_speeds(theta, h, given)
    zeros = np.zeros(theta.size - 1)
    start = np.column_stack([theta[:-1], v[:-1], zeros, zeros])
    end = np.column_stack([theta[1:], v[1:], zeros, zeros])
    return hermite_rows(start, end, h)


def _spline(theta: Array, h: Array) -> tuple[Array, Array]:
    """Rows and durations of the degree-7 interpolating spline of a piece, at rest at both ends."""
    from scipy.interpolate import PPoly, make_interp_spline

    times = np.concatenate([[0.0], np.cumsum(h)])
    rest = [(1, 0.0), (2, 0.0), (3, 0.0)]
    pp = PPoly.from_spline(make_interp_spline(times, theta, k=7, bc_type=(rest, rest)))
    keep = np.diff(pp.x) > 0
    hh = np.diff(pp.x)[keep]
    c = pp.c[:, keep] * hh[None, :] ** np.arange(7, -1, -1)[:, None]
    return np.hstack([np.zeros((hh.size, NCOEF - 8)), c.T]), hh


def _piece(family: str, points: Sequence[Waypoint], h: Optional[Array],
           caps: Optional[Caps]) -> tuple[Array, Array]:
    """Rows and durations of one piece (rest to rest) of the sequence."""
    theta = np.array([p.theta for p in points])
    given = [p.velocity for p in points]
    if family == "scurve":
        assert caps is not None
        moves = [(a, b) for a, b in zip(theta[:-1], theta[1:], strict=True) if b != a]
        parts = [scurve_rows(a, b, caps.v_max, caps.a_max, caps.j_max) for a, b in moves]
        return np.vstack([r for r, _ in parts]), np.concatenate([d for _, d in parts])
    if h is None:
        assert caps is not None
        h = np.maximum(psi_duration(np.diff(theta), caps.v_max, caps.a_max, caps.j_max), 1e-9)
        if family == "psi":
            return psi_rows(theta[:-1], theta[1:]), h
        for _ in range(50):  # time scaling is exact for automatic speeds; given ones need a few rounds
            rows, hh = _spline(theta, h) if family == "spline" else (_hermite(theta, h, given), h)
            f = _scale(_peaks(rows, hh), caps)
            if abs(f - 1) < 1e-9:
                break
            h = h * f
        if f > 1 + 1e-6:
            raise ValueError(f"the {family} piece through {theta.tolist()} cannot meet the caps {caps} "
                             "with its given via speeds")
    if family == "psi":
        return psi_rows(theta[:-1], theta[1:]), h
    return _spline(theta, h) if family == "spline" else (_hermite(theta, h, given), h)


def _check_points(waypoints: Any, family: Any) -> list[Waypoint]:
    """The waypoints as :class:`Waypoint`, or an InputError naming what is wrong (their count before anything)."""
    if not (isinstance(family, str) and family in FAMILIES):
        raise InputError("family", family, f"family={short_repr(family)} is not a segment family; valid: {FAMILIES}")
    check_sequence("waypoints", waypoints, low=2, high=MAX_OPTIMAL_MOVES + 1, what="waypoints",
                   limit="MAX_OPTIMAL_MOVES, plus the start")
    points = []
    for i, p in enumerate(waypoints):
        if not (isinstance(p, Waypoint) or is_real(p)):
            raise InputError(f"waypoints[{i}]", p, f"waypoints[{i}]={short_repr(p)} is not a Waypoint or an angle "
                             f"({type(p).__name__}); give a number [rad] or a Waypoint(theta, velocity, dwell)")
        if not isinstance(p, Waypoint):
            p = Waypoint(check_quantity("angle", p, as_name=f"waypoints[{i}]"))
        points.append(p)
    for i, p in enumerate(points):
        rest = i in (0, len(points) - 1) or p.dwell > 0 or family in ("psi", "scurve")
        if rest and p.velocity not in (None, 0.0):
            why = "the end points and dwells are rests" if family not in ("psi", "scurve") else \
                f"the {family} family rests at every waypoint"
            raise InputError(f"waypoints[{i}]", p.velocity, f"waypoint {i}: velocity={p.velocity!r} rad/s, but "
                             f"{why}; give 0 or None")
    return points


def _check_durations(durations: Any, moves: int) -> Array:
    """The durations of ``moves`` moves as an array, or an InputError (their count checked before their values)."""
    check_sequence("durations", durations, low=moves, high=moves, what="durations (one per move)")
    h = [check_quantity("time", d, as_name=f"durations[{i}]") for i, d in enumerate(durations)]
    for i, d in enumerate(h):
        if d <= 0:
            raise InputError(f"durations[{i}]", d, f"durations[{i}]={d!r} s must be > 0")
    return np.array(h)


def plan_waypoints(waypoints: Sequence[Union[Waypoint, float]], *, family: str = "psi", rho: float = 0.5,
                   t0: float = 0.0, durations: Optional[Sequence[float]] = None,
                   caps: Optional[Caps] = None) -> PiecewisePlan:
    """One smooth plan through ``waypoints`` (module docstring), at a constant current magnitude ``rho`` [A].

    Parameters
    ----------
    waypoints : sequence of Waypoint or float
        The angles to pass, in order; a float is a waypoint with no speed given and no dwell. At most
        ``MAX_OPTIMAL_MOVES`` + 1 (flatstep.validate.limits), checked before any work.
    family : str
        The segment family: ``"psi"``, ``"hermite"``, ``"spline"`` or ``"scurve"``.
    rho : float
        The planned current magnitude [A], > 0.
    t0 : float
        When the first move (or the first dwell) starts [s].
    durations : sequence of float, optional
        The duration of each move between consecutive waypoints [s] (not with ``scurve``).
    caps : Caps, optional
        The speed, acceleration and jerk caps that set the durations not given (needed by ``scurve``).
    """
    points = _check_points(waypoints, family)
    rho = check_quantity("current", rho, as_name="rho")
    t0 = check_quantity("time", t0, as_name="t0")
    if caps is not None:
        check_instance("caps", caps, Caps, "a Caps(v_max, a_max, j_max)")
    h_all: Optional[Array] = None
    if durations is not None:
        if family == "scurve":
            raise InputError("durations", durations, f"durations={short_repr(durations)} were given, but an "
                             "S-curve's durations follow from caps; give caps only")
        h_all = _check_durations(durations, len(points) - 1)
    elif caps is None:
        raise InputError("caps", caps, "caps=None and durations=None: neither durations nor caps; give the duration "
                         "of each move or the caps that set them")
    rests = [0] + [i for i, p in enumerate(points[1:-1], 1) if p.dwell > 0 or family in ("psi", "scurve")]
    rests.append(len(points) - 1)
    rows, hs = [], []
    if points[0].dwell > 0:
        rows.append(dwell_row(points[0].theta)[None, :])
        hs.append(np.array([points[0].dwell]))
    for a, b in zip(rests[:-1], rests[1:], strict=True):
        piece = points[a:b + 1]
        if all(p.theta == piece[0].theta for p in piece):
            raise InputError("waypoints", piece[0].theta, f"waypoints {a}..{b} all sit at {piece[0].theta} rad: a "
                             "move needs a distance; give the rest as a dwell")
        if h_all is None and any(p.theta == q.theta for p, q in zip(piece[:-1], piece[1:], strict=True)):
            same = next(p.theta for p, q in zip(piece[:-1], piece[1:], strict=True) if p.theta == q.theta)
            raise InputError("waypoints", same, f"two consecutive waypoints among {a}..{b} sit at the same angle, "
                             f"{same} rad; give the rest there as a dwell, or give durations")
        r, h = _piece(family, piece, None if h_all is None else h_all[a:b], caps)
        rows.append(r)
        hs.append(h)
        if points[b].dwell > 0:
            rows.append(dwell_row(points[b].theta)[None, :])
            hs.append(np.array([points[b].dwell]))
    h_cat = np.concatenate(hs)
    breaks = t0 + np.concatenate([[0.0], np.cumsum(h_cat)])
    theta = np.vstack(rows)
    return PiecewisePlan(breaks, theta, np.column_stack([np.zeros((theta.shape[0], NCOEF - 1)),
                                                          np.full(theta.shape[0], rho)]))
