"""Each law's tunable gains, in one table: their ``[controller]`` keys, their bounds in log space, how to apply them.

:data:`TUNABLE` maps a law (:data:`flatstep.control.spec.LAWS`) to a :class:`LawGains`: the gains the tuner
(:mod:`flatstep.studies.tune`) searches, each a ``[controller]`` key of a scenario file, with its bounds as decades
around the scenario's own value (the design rule's, or the file's), and the two functions that read those values
from a :class:`~flatstep.studies.scenario.Scenario` and give back the scenario with new ones. Every controller type
of a law (its options: feedforward, observer torques, integral, ...) searches its law's gains.

A law that gains a parameter gains a row in its ``gains`` here, and the tuner, its output file and
``flatstep compare --tuned`` follow.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Mapping

from ..control.spec import ControllerSpec
from ..validate import InputError
from .scenario import Scenario


@dataclass(frozen=True)
class Gain:
    r"""One tunable gain: its ``[controller]`` key and its bounds, in decades around the scenario's value.

    Parameters
    ----------
    key : str
        The gain's key in a scenario file's ``[controller]`` table (docs/scenario-reference.md).
    low, high : float
        The search's bounds, :math:`\log_{10}` of the gain over the scenario's own value (``-1, 1``: a tenth to ten
        times), ``low < 0 < high`` so that the scenario's value is inside.
    """

    key: str
    low: float
    high: float

    def __post_init__(self) -> None:
        if not self.low < 0.0 < self.high:
            raise ValueError(f"Gain({self.key!r}): bounds ({self.low}, {self.high}) decades must hold 0 "
                             "(the scenario's own value)")


@dataclass(frozen=True)
class LawGains:
    """A law's tunable gains and how a scenario holds them.

    Parameters
    ----------
    gains : tuple of Gain
        The gains searched, in the order of the search vector.
    read : callable
        ``read(scenario) -> {key: value}``: the scenario's own values of ``gains`` (the search's centre and its
        first candidate).
    apply : callable
        ``apply(scenario, {key: value}) -> Scenario``: the scenario with those values.
    """

    gains: tuple[Gain, ...]
    read: Callable[[Scenario], dict[str, float]]
    apply: Callable[[Scenario, Mapping[str, float]], Scenario]

    @property
    def keys(self) -> tuple[str, ...]:
        """The gains' ``[controller]`` keys, in order."""
        return tuple(g.key for g in self.gains)


#: The sliding laws' tuned gains (:class:`~flatstep.control.smc.SMCGains`): the reaching gains, the boundary layers
#: (their ratio is the current loop's speed W1/eps1) and the error dynamics' natural frequency; the damping stays.
SLIDING_GAINS = (Gain("W1", -1.0, 1.0), Gain("eps1", -1.0, 1.0), Gain("W2", -1.0, 1.0), Gain("eps2", -1.0, 1.0),
                 Gain("wn", -1.0, 1.0))
#: The cascade's (:class:`~flatstep.control.cascade.CascadeGains`): the current loops' bandwidth (a fifth to five
#: times the rule's lambda Ts = 0.3) and the three free gains of its P-PI loop, around the rule's w, w, w/4 poles
#: (wide enough to hold every bandwidth of the rule scaled by a fifth to five, the integral gain with its square).
CASCADE_GAINS = (Gain("current_bandwidth", -0.7, 0.7), Gain("k_theta", -1.0, 1.0), Gain("k_omega", -1.0, 1.0),
                 Gain("ki_omega", -2.0, 1.5))
#: Open-loop microstepping's (:class:`~flatstep.control.microstep.MicrostepGains`): its current loops' bandwidth.
MICROSTEP_GAINS = (Gain("current_bandwidth", -0.7, 0.7),)
#: Exact linearization's (:class:`~flatstep.control.exact_linearization.LinearizationGains`): its poles.
LINEARIZATION_GAINS = (Gain("wn", -1.0, 1.0), Gain("xi", -0.5, 0.3), Gain("p3", -1.0, 0.7), Gain("pd", -1.0, 0.7))


def _read(keys: tuple[Gain, ...]) -> Callable[[Scenario], dict[str, float]]:
    """A reader of the gains ``keys`` from the scenario's controller as built (the rule's, or the file's)."""

    def read(scenario: Scenario) -> dict[str, float]:
        gains = scenario.controller().gains
        return {g.key: float(getattr(gains, g.key)) for g in keys}

    return read


def _sliding_apply(scenario: Scenario, values: Mapping[str, float]) -> Scenario:
    """The sliding law's gains in ``gains`` (the current loop's speed is W1/eps1: no ``lambda_ts`` over it)."""
    return replace(scenario, gains=replace(scenario.gains, **values), lambda_ts=None)


def _baseline_apply(scenario: Scenario, values: Mapping[str, float]) -> Scenario:
    """A baseline's gains by name over its rule (``law_gains[law]``), every one given: no scale or ``lambda_ts`` left.

    The other laws' gains in ``law_gains`` stay.
    """
    law = ControllerSpec.parse(scenario.controller_type).law
    by_law = dict(scenario.law_gains or {})
    by_law[law] = {**by_law.get(law, {}), **values}
    return replace(scenario, law_gains=by_law, lambda_ts=None, bandwidth_scale=1.0)


_SLIDING = LawGains(SLIDING_GAINS, _read(SLIDING_GAINS), _sliding_apply)

#: Each law's tunable gains (module docstring).
TUNABLE: dict[str, LawGains] = {
    "smc": _SLIDING, "dq_smc": _SLIDING,
    "cascade": LawGains(CASCADE_GAINS, _read(CASCADE_GAINS), _baseline_apply),
    "microstep": LawGains(MICROSTEP_GAINS, _read(MICROSTEP_GAINS), _baseline_apply),
    "exact_linearization": LawGains(LINEARIZATION_GAINS, _read(LINEARIZATION_GAINS), _baseline_apply)}
#: The ``[controller]`` keys a tuned table leaves out: the rule's scalings, which its gains, all given, replace.
RULE_KEYS = ("bandwidth_scale", "lambda_ts")


def law_gains(kind: str, where: str = "law") -> LawGains:
    """The tunable gains of the controller type ``kind`` (any name :class:`ControllerSpec` reads), by its law."""
    spec = ControllerSpec.parse(kind, where)
    if spec.law not in TUNABLE:
        raise InputError(where, kind, f"{where} {kind!r}: law {spec.law!r} has no tunable gains; tunable laws: "
                         f"{list(TUNABLE)}")
    return TUNABLE[spec.law]
