r"""Trajectories of the flat outputs as piecewise polynomials: a segment table, the C core's ``struct traj``.

On segment :math:`i`, :math:`b_i \le t < b_{i+1}`, with :math:`h_i = b_{i+1} - b_i` and the local time
:math:`\tau = (t - b_i)\,h_i^{-1} \in [0, 1)`,

.. math::
    \theta(t) = \sum_{j=0}^{10} c_{ij}\,\tau^{10 - j},\qquad
    \frac{d^k\theta}{dt^k} = h_i^{-k} \sum_{j=0}^{10-k} c_{ij}\,\frac{(10-j)!}{(10-j-k)!}\,\tau^{10-j-k},

and the second flat output :math:`\rho` likewise (highest power first, as :func:`numpy.polyval`). Before
:math:`b_0` the flag holds the value at :math:`\tau = 0` of the first segment, from :math:`b_n` on the value at
:math:`\tau = 1` of the last, with zero derivatives: a :class:`~flatstep.plan.rest_to_rest.RestToRest` is the
one-segment table :meth:`PiecewisePlan.from_rest_to_rest`.

:meth:`PiecewisePlan.flag` evaluates the table as csrc/trajectory.c's ``traj_flag`` does, operation for operation
(Horner chains with the falling factorials, then the powers of :math:`h^{-1}`), vectorized over the samples.
The local time is normalised so that the coefficients stay of the size of the move in any precision (a
firmware's float); :meth:`PiecewisePlan.to_ppoly` and :meth:`PiecewisePlan.from_ppoly` convert to and from
:class:`scipy.interpolate.PPoly`, whose local variable is :math:`t - b_i`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Sequence, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model.equilibria import equilibrium_currents
from ..model.flat import FlatFlag
from ..model.psi import _PSI_HORNER
from ..validate import InputError, check_integer, check_quantity, short_repr
from ..validate.checks import is_real
from ..validate.limits import MAX_FLAG_BOUND
from ..validate.ranges import QUANTITIES
from .table_checks import flag_bound, lowest_rho

if TYPE_CHECKING:  # SciPy's interpolate is imported where a conversion needs it, not with the package
    from scipy.interpolate import PPoly

    from .rest_to_rest import RestToRest  # rest_to_rest builds its table here: no import back at run time

Array = NDArray[np.float64]
#: Coefficients per segment and output (degree 10, the degree of the paper's psi).
NCOEF = 11
#: Highest derivative of theta that :meth:`PiecewisePlan.theta` evaluates.
MAX_ORDER = 4
#: ``FALL[k, j] = p! / (p - k)!`` for the power ``p = 10 - j`` of coefficient ``j``: the k-th derivative's factor.
FALL = np.array([[math.perm(NCOEF - 1 - j, k) for j in range(NCOEF)] for k in range(MAX_ORDER + 1)], dtype=float)


def horner(coef: Array, tau: Array, order: int = 0) -> Array:
    """The ``order``-th tau-derivative of the rows ``coef`` (m, 11) at ``tau`` (m,): Horner over the columns."""
    d = coef[:, : NCOEF - order] * FALL[order, : NCOEF - order] if order else coef
    a = d[:, 0].copy()
    for j in range(1, NCOEF - order):  # a loop over the degree, vectorized over the samples
        a = a * tau + d[:, j]
    return a


def horner_rows(table: Array, i: NDArray[np.intp], tau: Array, order: int = 0) -> Array:
    """:func:`horner` on the rows ``table[i]``, gathering one column at a time (the same operations, less memory)."""
    d = table[:, : NCOEF - order] * FALL[order, : NCOEF - order] if order else table
    a = d[i, 0]
    for j in range(1, NCOEF - order):  # a loop over the degree, vectorized over the samples
        a = a * tau + d[i, j]
    return a


def _numbers(name: str, value: ArrayLike, valid: str) -> Array:
    """``value`` as a new float array, or an InputError unless it holds real numbers only (no str, bool, None)."""
    try:
        arr = np.array(value)
    except (TypeError, ValueError, OverflowError):
        arr = np.array(None)
    if arr.dtype.kind not in "iuf":
        raise InputError(name, value, f"{name}={short_repr(value)} is not an array of real numbers (a "
                         f"{type(value).__name__} of dtype {arr.dtype}); {valid}")
    return arr.astype(float)


def _table(name: str, value: ArrayLike, n: int) -> Array:
    """A coefficient table as an (n, 11) float array, or an InputError naming it."""
    arr = _numbers(name, value, f"give ({n}, k) power coefficients, 1 <= k <= {NCOEF}")
    if arr.ndim == 2 and arr.shape[0] == n and 0 < arr.shape[1] <= NCOEF:
        arr = np.hstack([np.zeros((n, NCOEF - arr.shape[1])), arr])  # a lower degree: leading zeros
    if arr.shape != (n, NCOEF):
        raise InputError(name, value, f"{name} has shape {arr.shape}; expected ({n}, k) with 1 <= k <= {NCOEF} "
                         f"(one row of power coefficients, highest first, per segment): {name}={short_repr(value)}")
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        raise InputError(name, value, f"{name} holds non-finite coefficients in segment(s) {bad.tolist()[:8]} "
                         f"({name}={short_repr(value)}); every coefficient must be finite")
    return arr


def _breaks(value: ArrayLike) -> Array:
    """The breaks as a float array, or an InputError: at least 2, finite, strictly increasing, in the time range."""
    b = _numbers("breaks", value, "give at least 2 finite, strictly increasing times [s]").ravel()
    if b.size < 2 or not np.isfinite(b).all() or not (np.diff(b) > 0).all():
        raise InputError("breaks", value, f"breaks={short_repr(b.tolist())} must be at least 2 finite, strictly "
                         "increasing times [s]")
    time = QUANTITIES["time"]
    if not (time.contains(float(b[0])) and time.contains(float(b[-1]))):
        raise InputError("breaks", value, f"breaks={short_repr(b.tolist())}: the plan's times must lie in "
                         f"{time.describe()} ({time.why})")
    with np.errstate(over="ignore"):
        short = not np.isfinite((1.0 / np.diff(b)) ** MAX_ORDER).all()
    if short:
        raise InputError("breaks", value, f"breaks={short_repr(b.tolist())}: a segment is so short that "
                         f"(1/h)^{MAX_ORDER} overflows")
    return b


def _check_table(b: Array, theta: Array, rho: Array) -> None:
    """Raise an InputError unless rho > 0 on every whole segment and the flag's bound is within MAX_FLAG_BOUND."""
    for name, rows, order in (("theta", theta, MAX_ORDER), ("rho", rho, 1)):
        bound, i = flag_bound(b, rows, order)
        if not bound <= MAX_FLAG_BOUND:
            raise InputError(name, bound, f"{name}: segment {i} on [{float(b[i])!r}, {float(b[i + 1])!r}] s has "
                             f"coefficients and a duration that bound {name} and its first {order} derivatives by "
                             f"{bound:.4g}, above the limit of {MAX_FLAG_BOUND:g} (flatstep.validate.limits."
                             f"MAX_FLAG_BOUND): the flag would overflow; give coefficients of a motor's size or "
                             f"longer segments ({name}[{i}]={short_repr(rows[i].tolist())})")
    low = lowest_rho(rho)
    if low is not None:
        value, k, tau = low
        t = b[k] + tau * (b[k + 1] - b[k])
        raise InputError("rho", value, f"rho falls to {value!r} A on the plan (segment {k}, t={t:.6g} s); the "
                         "current magnitude must stay > 0 on every whole segment")


@dataclass(frozen=True, eq=False)
class PiecewisePlan:
    """A plan of the flat outputs (rho, theta) as a table of polynomial segments (module docstring).

    Parameters
    ----------
    breaks : array_like
        The n + 1 increasing segment boundaries [s].
    theta : array_like
        (n, k) power coefficients of theta in the local time tau, highest first, k <= 11 [rad].
    rho : array_like
        (n, k) power coefficients of the current magnitude rho, likewise [A]; rho must stay > 0.
    """

    breaks: Array
    theta: Array
    rho: Array
    _c: dict[str, Any] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        b = _breaks(self.breaks)
        n = b.size - 1
        object.__setattr__(self, "breaks", b)
        object.__setattr__(self, "theta", _table("theta", self.theta, n))
        object.__setattr__(self, "rho", _table("rho", self.rho, n))
        _check_table(self.breaks, self.theta, self.rho)
        for a in (self.breaks, self.theta, self.rho):
            a.flags.writeable = False

    @classmethod
    def _of_checked_table(cls, breaks: Array, theta: Array, rho: Array) -> PiecewisePlan:
        """The plan of a table csrc/time_optimal.c planned, without the constructor's conversions (private).

        Only for the C planner's own tables (flatstep.plan.time_optimal.time_optimal and time_optimal_sequence with
        ``engine="c"``, their dwells' rows held at ``i_hold`` > 0 added), which come as (n + 1,) breaks and
        (n, 11) rows of floats: no copy, no padding of lower degrees. Its search accepts a table where rho > 0 on
        the 9 points ``tau = j/8`` of every segment (time_optimal_margins); that is not a proof, so the table gets
        the constructor's exact checks all the same: finite, increasing breaks in the time range, finite
        coefficients, rho > 0 on every whole segment, a flag within ``MAX_FLAG_BOUND`` (a ValueError otherwise).
        """
        b = np.asarray(breaks, dtype=float)
        th, rh = np.asarray(theta, dtype=float), np.asarray(rho, dtype=float)
        n = b.size - 1
        if not (n >= 1 and th.shape == rh.shape == (n, NCOEF) and np.isfinite(b).all() and (np.diff(b) > 0).all()
                and np.isfinite(th).all() and np.isfinite(rh).all()):
            raise ValueError(f"a table of {n} segment(s) with breaks {b.tolist()!r} is not a finished C plan: its "
                             f"breaks must increase, its rows be ({n}, {NCOEF}) and every value finite")
        _breaks(b)
        _check_table(b, th, rh)
        plan = object.__new__(cls)
        for name, value in (("breaks", b), ("theta", th), ("rho", rh), ("_c", {})):
            object.__setattr__(plan, name, value)
        for a in (b, th, rh):
            a.flags.writeable = False
        return plan

    @property
    def n(self) -> int:
        """The number of segments."""
        return int(self.breaks.size - 1)

    @property
    def t0(self) -> float:
        """Start of the move [s]."""
        return float(self.breaks[0])

    @property
    def tf(self) -> float:
        """End of the move [s]."""
        return float(self.breaks[-1])

    @property
    def knots(self) -> tuple[float, ...]:
        """Where the plan's derivatives may jump: every break (an integrator restarts there)."""
        return tuple(self.breaks.tolist())

    @property
    def durations(self) -> Array:
        """Each segment's duration [s]."""
        return np.diff(self.breaks)

    def _ends(self, coef: Array) -> tuple[float, float]:
        """The value held before the start (tau = 0 of the first row) and after the end (tau = 1 of the last)."""
        return float(coef[0, -1]), float(horner(coef[-1:], np.ones(1))[0])

    @property
    def theta1(self) -> float:
        """Start angle [rad]."""
        return self._ends(self.theta)[0]

    @property
    def theta2(self) -> float:
        """End angle [rad]."""
        return self._ends(self.theta)[1]

    @property
    def rho1(self) -> float:
        """Start current magnitude [A]."""
        return self._ends(self.rho)[0]

    @property
    def rho2(self) -> float:
        """End current magnitude [A]."""
        return self._ends(self.rho)[1]

    def _locate(self, t: Array) -> tuple[NDArray[np.intp], Array, Array, NDArray[np.bool_]]:
        """Per sample: the segment index, 1/h, tau and whether the sample lies inside (b_0, b_n)."""
        b = self.breaks
        i = np.clip(np.searchsorted(b, t, side="right") - 1, 0, self.n - 1)
        inside = (t > b[0]) & (t < b[-1])
        ih = 1.0 / (b[i + 1] - b[i])
        return i, ih, np.where(inside, (t - b[i]) * ih, 0.0), inside  # outside: held, tau unused

    def _held(self, coef: Array, t: Array, inside: NDArray[np.bool_], value: Array) -> Array:
        """``value`` inside the move, the held start or end value outside it (a NaN time holds the start)."""
        start, end = self._ends(coef)
        return np.where(inside, value, np.where(t >= self.breaks[-1], end, start))

    def flag(self, t: ArrayLike) -> FlatFlag:
        """The planned flat flag (rho*, rho*', theta*, theta*', theta*'', theta*''') at times ``t``."""
        t = np.asarray(t, dtype=float)
        tv = t.ravel()
        i, ih, tau, inside = self._locate(tv)
        th, rh = self.theta, self.rho
        ih2 = ih * ih
        out = (self._held(self.rho, tv, inside, horner_rows(rh, i, tau)),
               np.where(inside, horner_rows(rh, i, tau, 1) * ih, 0.0),
               self._held(self.theta, tv, inside, horner_rows(th, i, tau)),
               np.where(inside, horner_rows(th, i, tau, 1) * ih, 0.0),
               np.where(inside, horner_rows(th, i, tau, 2) * ih2, 0.0),
               np.where(inside, horner_rows(th, i, tau, 3) * (ih2 * ih), 0.0))
        return FlatFlag(*(a.reshape(t.shape) for a in out))

    def theta_deriv(self, t: ArrayLike, order: int) -> Array:
        """The ``order``-th time derivative (0..4) of theta at times ``t`` (C ``traj_theta``)."""
        order = check_integer("order", order, low=0, high=MAX_ORDER, why="the table gives theta's derivatives "
                              f"0..{MAX_ORDER}")
        t = np.asarray(t, dtype=float)
        tv = t.ravel()
        i, ih, tau, inside = self._locate(tv)
        scale = np.ones_like(ih)
        for _ in range(order):
            scale = scale * ih
        value = horner_rows(self.theta, i, tau, order) * scale
        out = self._held(self.theta, tv, inside, value) if order == 0 else np.where(inside, value, 0.0)
        return out.reshape(t.shape)

    def continuity(self, order: int = 3) -> Array:
        """The jumps (n - 1, order + 1) of theta's derivatives 0..order at the inner breaks (left minus right)."""
        if self.n == 1:
            return np.zeros((0, order + 1))
        ih = 1.0 / self.durations
        jumps = []
        for k in range(order + 1):
            left = horner(self.theta[:-1], np.ones(self.n - 1), k) * ih[:-1] ** k
            right = horner(self.theta[1:], np.zeros(self.n - 1), k) * ih[1:] ** k
            jumps.append(left - right)
        return np.array(jumps).T

    @classmethod
    def from_rest_to_rest(cls, plan: RestToRest) -> "PiecewisePlan":
        """The paper's move (eqs. 16-18) as a one-segment table on [t0, tf]: psi's coefficients times the steps."""
        psi = _PSI_HORNER[0]
        theta, rho = psi * (plan.theta2 - plan.theta1), psi * (plan.rho2 - plan.rho1)
        theta[-1] += plan.theta1
        rho[-1] += plan.rho1
        return cls(np.array([plan.t0, plan.tf]), theta[None, :], rho[None, :])

    @classmethod
    def hold(cls, theta: float, rho: float, t0: float, t1: float) -> "PiecewisePlan":
        """One segment holding ``theta`` [rad] at the current magnitude ``rho`` [A] over ``[t0, t1]``."""
        theta, rho = check_quantity("angle", theta, as_name="theta"), check_quantity("current", rho, as_name="rho")
        t0, t1 = check_quantity("time", t0, as_name="t0"), check_quantity("time", t1, as_name="t1")
        row = np.zeros((1, NCOEF))
        row[0, -1] = theta
        rho_row = np.zeros((1, NCOEF))
        rho_row[0, -1] = rho
        return cls(np.array([t0, t1]), row, rho_row)

    @classmethod
    def concatenate(cls, parts: Sequence["PiecewisePlan"]) -> "PiecewisePlan":
        """One table of consecutive tables, each starting where the one before ends (a ValueError if not)."""
        if not isinstance(parts, (list, tuple)) or not parts:
            raise InputError("parts", parts, f"parts={short_repr(parts)}: no tables to concatenate; give a list of at "
                             "least one PiecewisePlan")
        for k, p in enumerate(parts):
            if not isinstance(p, PiecewisePlan):
                raise InputError(f"parts[{k}]", p, f"parts[{k}]={short_repr(p)} is not a PiecewisePlan "
                                 f"({type(p).__name__}); give the tables to join")
        for k, (a, b) in enumerate(zip(parts[:-1], parts[1:], strict=True)):
            if abs(b.t0 - a.tf) > 1e-12 * max(1.0, abs(a.tf)):
                raise ValueError(f"table {k + 1} starts at t0={b.t0!r} s, but table {k} ends at tf={a.tf!r} s: "
                                 "consecutive tables must meet")
        return cls(np.concatenate([parts[0].breaks] + [p.breaks[1:] for p in parts[1:]]),
                   np.vstack([p.theta for p in parts]), np.vstack([p.rho for p in parts]))

    @classmethod
    def from_ppoly(cls, theta: "PPoly", rho: Union[float, "PPoly"]) -> "PiecewisePlan":
        r"""A table from a :class:`scipy.interpolate.PPoly` of theta (degree <= 10), with rho constant or a PPoly.

        The coefficients of :math:`(t - b_i)^p` become those of :math:`\tau^p` by the factor :math:`h_i^p`.
        """
        from scipy.interpolate import PPoly

        for name, pp in (("theta", theta), ("rho", rho)):
            if not isinstance(pp, PPoly) and not (name == "rho" and is_real(pp)):
                raise InputError(name, pp, f"{name}={short_repr(pp)} is not a scipy PPoly ({type(pp).__name__})"
                                 + ("; give a PPoly or a number [A]" if name == "rho" else "; give a PPoly"))
        b = np.asarray(theta.x, dtype=float)
        h = np.diff(b)

        def local(pp: "PPoly") -> Array:
            c = np.asarray(pp.c, dtype=float)
            if c.shape[0] > NCOEF or not np.array_equal(pp.x, b):
                raise ValueError(f"a PPoly of degree {c.shape[0] - 1} on {pp.x.size} breaks: the table takes degree "
                                 f"<= {NCOEF - 1} on the breaks of theta")
            powers = np.arange(c.shape[0] - 1, -1, -1)[:, None]
            return (c * h[None, :] ** powers).T

        rh = np.full((b.size - 1, 1), float(rho)) if is_real(rho) else local(rho)
        return cls(b, local(theta), rh)

    def to_ppoly(self) -> tuple["PPoly", "PPoly"]:
        """The table as two :class:`scipy.interpolate.PPoly` (theta, rho) in the local variable ``t - b_i``."""
        from scipy.interpolate import PPoly

        h = self.durations
        scale = h[None, :] ** -np.arange(NCOEF - 1, -1, -1)[:, None]
        return PPoly(self.theta.T * scale, self.breaks), PPoly(self.rho.T * scale, self.breaks)

    def x0(self, Nr: int) -> Array:
        """Initial equilibrium state (ia, ib, omega, theta), eq. (19)."""
        return np.array([*equilibrium_currents(self.theta1, self.rho1, Nr), 0.0, self.theta1])

    def xf(self, Nr: int) -> Array:
        """Final equilibrium state (ia, ib, omega, theta), eqs. (20)-(21)."""
        return np.array([*equilibrium_currents(self.theta2, self.rho2, Nr), 0.0, self.theta2])

    def as_dict(self) -> dict[str, float]:
        """The end points by name (the hold's target, a result's ``meta['plan']``); :meth:`c_plan` adds the table."""
        return dict(theta1=self.theta1, theta2=self.theta2, rho1=self.rho1, rho2=self.rho2, t0=self.t0, tf=self.tf)

    def segments(self) -> dict[str, list[Any]]:
        """The table for JSON: breaks and both coefficient tables."""
        return dict(breaks=self.breaks.tolist(), theta=self.theta.tolist(), rho=self.rho.tolist())

    def to_table(self) -> "PiecewisePlan":
        """The plan itself: it is a table."""
        return self

    def c_plan(self) -> dict[str, Any]:
        """The fields of the C ``struct plan``: the end points and the table (``traj``, :meth:`c_struct`)."""
        return {**self.as_dict(), "traj": self.c_struct()}

    def c_struct(self) -> Any:
        """A C ``struct traj *`` (csrc/trajectory.h) over this table, built once and kept alive with the plan."""
        if "traj" not in self._c:
            from .._flatstep_core import ffi

            arrays = [np.ascontiguousarray(a) for a in (self.breaks, self.theta, self.rho)]
            ptrs = [ffi.from_buffer("double[]", a) for a in arrays]
            self._c["keep"] = (arrays, ptrs)
            self._c["traj"] = ffi.new("struct traj *", dict(n=self.n, breaks=ptrs[0], theta=ptrs[1], rho=ptrs[2]))
        return self._c["traj"]

