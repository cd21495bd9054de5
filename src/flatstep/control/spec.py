"""What controller to build: a law and its orthogonal options, validated in one place.

A :class:`ControllerSpec` names one of the :data:`LAWS` and the options it takes (:data:`OPTIONS`, one row each:
the laws that take it, what it needs from a run, what it requires or excludes):

=====================  =============================================================  ==============================
option                 what it adds                                                   laws
=====================  =============================================================  ==============================
``feedforward``        the torques known beyond eq. (1) (a ``TorqueModel``: detent,   smc, dq_smc, cascade,
                       Coulomb friction, load) in the law's voltages and observer     exact_linearization
                       (the cascade: anti-cogging, as firmware does it)
``observer_torques``   the cascade's observer knows those torques too                cascade (with feedforward)
``integral``           integral action on ``s2``                                      dq_smc
``km_estimate``        an online estimate of ``Km``                                   dq_smc (integral, feedforward)
``advance``            the applied voltage turned by the angle the rotor turns over   dq_smc
                       half a control period (the held voltage's mean delay)
``hold``               the detent hold from ``tf`` on                                 smc
``rho_plan``           ``"plan"`` (the plan's rho*) or ``"loss_aware"`` (rho*(t)      smc
                       from the torque the move needs)
``voltage_feedforward`` the voltage of the planned q current, ``R iq* + L diq*/dt``   cascade
                       (with the known torques along the plan when ``feedforward``)
``plan_frame``         the current loops in the plan's frame, a share ``d_hold`` of   cascade
                       the plan's ``rho*`` held on its d axis (its torque answers an
                       angle error at once)
``back_emf``           the back EMF at the plan's angle and speed                     microstep
``load_angle``         lead the current vector by the plan's load angle               microstep
=====================  =============================================================  ==============================

Every combination the table allows is a controller; :meth:`ControllerSpec.name` is its name (the historical type
names, ``"dq_smc_i_ff"`` say, for the combinations that had one: :data:`ALIASES`), and :meth:`ControllerSpec.parse`
reads a name back, either form. What each law needs from a run (a control period, the torque model, the sliding
gains) is derived here from :data:`LAW_TABLE` and :data:`OPTIONS`, not listed by hand; each law's file builds its
controller from the spec (its ``from_spec``, registered in :data:`LAW_TABLE`), so that adding an option touches this
file and the law's file alone.
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any, Callable, Mapping

from ..validate import InputError
from . import cascade, dq_smc, exact_linearization, microstep, smc
from .build import BuildContext

#: What an option or a law may need from a run: the torque model it knows, the control period it advances by.
NEEDS = ("torques", "control_period")


@dataclass(frozen=True)
class Law:
    """A control law: how to build it, its label, and what it needs.

    Parameters
    ----------
    build : callable
        ``build(spec, context) -> controller``, the law file's ``from_spec``.
    label : str
        Its short label for tables and figures.
    sliding : bool
        Whether its gains are the run's :class:`~flatstep.control.smc.SMCGains` (designed or given), else tuned by
        rule from the control period.
    gains : type
        Its gains class (a dataclass): the names a scenario's ``[controller]`` table may give.
    needs : tuple of str
        Of :data:`NEEDS`, what the law needs with every option off.
    """

    build: Callable[["ControllerSpec", BuildContext], Any]
    label: str
    sliding: bool
    gains: type
    needs: tuple[str, ...] = ()


@dataclass(frozen=True)
class Option:
    """An option of the spec: the laws that take it and what it needs.

    Parameters
    ----------
    laws : tuple of str
        The laws that take it.
    doc : str
        What it adds, one line (the scenario files' reference).
    label : str
        Its part of a controller's label (:meth:`ControllerSpec.label`).
    rank : int
        The place of that part in the label.
    needs : tuple of str
        Of :data:`NEEDS`, what the option needs from a run when on.
    requires : tuple of str
        The options that must be on with it, and ``why`` says why.
    excludes : tuple of str
        The options that must be off (at their default) with it.
    why : str
        Why it requires or excludes those.
    values : tuple of str
        For a choice (not true/false): its values, the first the default (off).
    hides : tuple of str
        Options whose label part this one's replaces.
    """

    laws: tuple[str, ...]
    doc: str
    label: str
    rank: int
    needs: tuple[str, ...] = ()
    requires: tuple[str, ...] = ()
    excludes: tuple[str, ...] = ()
    why: str = ""
    values: tuple[str, ...] = ()
    hides: tuple[str, ...] = ()


#: The control laws, the paper's first, each with its builder.
LAW_TABLE: dict[str, Law] = {
    "smc": Law(smc.from_spec, "flatness + SMC", True, smc.SMCGains),
    "dq_smc": Law(dq_smc.from_spec, "flatness d-q SMC", True, smc.SMCGains),
    "cascade": Law(cascade.from_spec, "cascaded PID (FOC)", False, cascade.CascadeGains, ("control_period",)),
    "microstep": Law(microstep.from_spec, "open-loop microstep", False, microstep.MicrostepGains,
                     ("control_period",)),
    "exact_linearization": Law(exact_linearization.from_spec, "exact linearization", False,
                               exact_linearization.LinearizationGains, ("control_period",)),
}
#: The options, in the order of a controller's name.
OPTIONS: dict[str, Option] = {
    "feedforward": Option(("smc", "dq_smc", "cascade", "exact_linearization"),
                          "the known torques ([feedforward]) in the law and its observer", "ff", 2, needs=("torques",)),
    "observer_torques": Option(("cascade",), "the cascade's observer knows the torques too", "model obs.", 3,
                               requires=("feedforward",),
                               why="the observer shares the torque model the feedforward brings",
                               hides=("feedforward",)),
    "integral": Option(("dq_smc",), "integral action on s2", "I", 1, needs=("control_period",)),
    "km_estimate": Option(("dq_smc",), "an online estimate of Km", "Km", 4, needs=("control_period",),
                          requires=("integral", "feedforward"),
                          why="the estimate runs on the integral's error, with the torques known"),
    "advance": Option(("dq_smc",), "the applied voltage turned by the angle of the held voltage's mean delay",
                      "adv", 9, needs=("control_period",)),
    "hold": Option(("smc",), "hold the target's detent from tf on", "hold", 5, excludes=("rho_plan",),
                   why="the hold holds the plan's rho at the target"),
    "rho_plan": Option(("smc",), "the plan's rho*, or rho*(t) from the torque the move needs", "rho(t)", 0,
                       values=("plan", "loss_aware")),
    "voltage_feedforward": Option(("cascade",), "the voltage of the planned q current, R iq* + L diq*/dt (with the "
                                  "known torques along the plan when feedforward)", "v ff", 6),
    "plan_frame": Option(("cascade",), "the current loops in the plan's frame (Park by Nr theta*), a share d_hold of "
                         "the plan's rho* held on its d axis", "plan frame", 9),
    "back_emf": Option(("microstep",), "the back EMF at the plan's angle and speed in the driver's voltages", "emf", 7),
    "load_angle": Option(("microstep",), "lead the current vector by the load angle of the torque the plan needs",
                         "load angle", 8),
}
#: The control laws, the paper's first.
LAWS = tuple(LAW_TABLE)
#: The laws whose gains are the run's :class:`~flatstep.control.smc.SMCGains` (designed or given, not by rule).
SLIDING_LAWS = tuple(k for k, law in LAW_TABLE.items() if law.sliding)
#: Which laws take each option (a choice: its values other than the first).
OPTION_LAWS: dict[str, tuple[str, ...]] = {name: opt.laws for name, opt in OPTIONS.items()}
#: The values of ``rho_plan``.
RHO_PLANS = OPTIONS["rho_plan"].values
#: The gain names each law takes (its gains class's fields; the options' own switches left out).
LAW_GAINS: dict[str, tuple[str, ...]] = {k: tuple(f.name for f in fields(law.gains) if f.name not in OPTIONS)
                                         for k, law in LAW_TABLE.items()}
#: Short labels of the laws, for tables and figures.
LAW_LABELS = {k: law.label for k, law in LAW_TABLE.items()}


def _off(name: str) -> Any:
    """The value of option ``name`` when off: false, or a choice's first value."""
    return OPTIONS[name].values[0] if OPTIONS[name].values else False


@dataclass(frozen=True)
class ControllerSpec:
    """A law and its options (module docstring); invalid combinations are refused with what is valid.

    Parameters
    ----------
    law : str
        One of :data:`LAWS`.
    feedforward, observer_torques, integral, km_estimate, hold : bool
        The options of the module docstring's table (default off).
    rho_plan : str
        ``"plan"`` or ``"loss_aware"`` (:data:`RHO_PLANS`).
    voltage_feedforward : bool
        The cascade's current-reference voltage (module docstring; default off).
    back_emf, load_angle : bool
        The microstepping driver's back-EMF feedforward and load-angle lead (default off).
    plan_frame : bool
        The cascade's current loops in the plan's frame with a held d current (module docstring; default off).
    advance : bool
        The d-q law's angle advance of the applied voltage (default off).
    """

    law: str = "smc"
    feedforward: bool = False
    observer_torques: bool = False
    integral: bool = False
    km_estimate: bool = False
    hold: bool = False
    rho_plan: str = "plan"
    voltage_feedforward: bool = False
    back_emf: bool = False
    load_angle: bool = False
    plan_frame: bool = False
    advance: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.law, str) or self.law not in LAWS:
            raise InputError("law", self.law, f"law={self.law!r} is unknown; valid: {list(LAWS)}")
        for name, opt in OPTIONS.items():
            value = getattr(self, name)
            if opt.values:
                if not isinstance(value, str) or value not in opt.values:
                    raise InputError(name, value, f"{name}={value!r} is unknown; valid: {list(opt.values)}")
                if value != opt.values[0] and self.law not in opt.laws:
                    raise InputError(name, value, f"{name}={value!r} is an option of {list(opt.laws)}, not of law "
                                     f"{self.law!r}")
                continue
            if not isinstance(value, bool):
                raise InputError(name, value, f"{name}={value!r} is not true or false")
            if value and self.law not in opt.laws:
                raise InputError(name, value, f"{name}=true is not an option of law {self.law!r} (it is one of "
                                 f"{list(opt.laws)}); the options of {self.law!r}: {self.options_of(self.law)}")
        for name in self.options_on():
            opt = OPTIONS[name]
            if opt.requires and not all(getattr(self, r) != _off(r) for r in opt.requires):
                raise InputError(name, getattr(self, name), f"{self._shown(name)} needs "
                                 f"{' and '.join(f'{r}=true' for r in opt.requires)} ({opt.why})")
            for other in opt.excludes:
                if getattr(self, other) != _off(other):
                    raise InputError(name, getattr(self, name), f"{self._shown(name)}: {opt.why}; with "
                                     f"{self._shown(other)} give one of them")

    def _shown(self, name: str) -> str:
        """``name=value`` as a file would write it."""
        value = getattr(self, name)
        return f"{name}=true" if value is True else f"{name}={value!r}"

    @staticmethod
    def options_of(law: str) -> list[str]:
        """The options ``law`` takes."""
        return [name for name, laws in OPTION_LAWS.items() if law in laws]

    def options_on(self) -> list[str]:
        """The options not at their default, in :data:`OPTIONS` order."""
        return [name for name in OPTIONS if getattr(self, name) != _off(name)]

    # -- what the law needs, derived -------------------------------------------------------------------------------
    def needs(self) -> set[str]:
        """What the law and its options need from a run (of :data:`NEEDS`)."""
        return {*LAW_TABLE[self.law].needs, *(n for name in self.options_on() for n in OPTIONS[name].needs)}

    @property
    def needs_torques(self) -> bool:
        """Whether a torque model (a scenario's ``[feedforward]``) must be given."""
        return "torques" in self.needs()

    def without_torques(self) -> "ControllerSpec":
        """The same law with every option that needs the torques off (and the options that require those)."""
        off = {name for name in self.options_on() if "torques" in OPTIONS[name].needs}
        while True:
            more = {name for name in self.options_on() if name not in off and set(OPTIONS[name].requires) & off}
            if not more:
                break
            off |= more
        return replace(self, **{name: _off(name) for name in off})

    @property
    def sliding(self) -> bool:
        """Whether the gains are the run's SMCGains (else tuned by rule from the control period)."""
        return LAW_TABLE[self.law].sliding

    @property
    def needs_control_period(self) -> bool:
        """Whether the law is tuned from, or advances by, the control period (no continuous-time run)."""
        return "control_period" in self.needs()

    @property
    def continuous(self) -> bool:
        """Whether the law can run in continuous time (flatstep.engine.settings.Continuous)."""
        return not self.needs_control_period

    def build(self, context: BuildContext) -> Any:
        """The controller: the law's builder (:data:`LAW_TABLE`) on this spec and ``context``."""
        return LAW_TABLE[self.law].build(self, context)

    # -- names -----------------------------------------------------------------------------------------------------
    def name(self) -> str:
        """The controller's name: its historical type name (:data:`ALIASES`), else ``law+option+...``."""
        for alias, spec in ALIASES.items():
            if spec == self:
                return alias
        opts = [name for name in self.options_on() if not OPTIONS[name].values]
        opts += [getattr(self, name) for name in self.options_on() if OPTIONS[name].values]
        return "+".join([self.law, *opts])

    def label(self) -> str:
        """A short label for tables and figures."""
        on = self.options_on()
        hidden = {h for name in on for h in OPTIONS[name].hides}
        extra = [OPTIONS[name].label for name in sorted(on, key=lambda n: OPTIONS[n].rank) if name not in hidden]
        return LAW_LABELS[self.law] + (", " + "+".join(extra) if extra else "")

    @classmethod
    def parse(cls, value: Any, where: str = "controller") -> "ControllerSpec":
        """A spec from a name (``law+option+...``, an alias, or ``alias+option+...``), a mapping of fields, or a spec.

        Raises
        ------
        InputError
            Naming ``where``, the value, and the valid names or options.
        """
        if isinstance(value, ControllerSpec):
            return value
        if isinstance(value, Mapping):
            unknown = sorted(set(value) - {f.name for f in fields(cls)})
            if unknown:
                raise InputError(where, dict(value), f"{where}: unknown key(s) {unknown}; valid: "
                                 f"{[f.name for f in fields(cls)]}")
            try:
                return cls(**value)
            except InputError as exc:
                raise exc.at(where) from None
        if not isinstance(value, str):
            raise InputError(where, value, f"{where}={value!r} is not a controller name; valid: {list(ALIASES)} or "
                             f"law+option+... with a law of {list(LAWS)}")
        if value in ALIASES:
            return ALIASES[value]
        law, *opts = value.split("+")
        kwargs: dict[str, Any] = {}
        if law in ALIASES:  # a historical name with more options: "cascade_model+voltage_feedforward"
            base = ALIASES[law]
            law, kwargs = base.law, {name: getattr(base, name) for name in base.options_on()}
        if law not in LAWS:
            raise InputError(where, value, f"{where}={value!r} is unknown; valid: {list(ALIASES)}, or "
                             f"law+option+... with a law of {list(LAWS)} and options of {list(OPTIONS)}")
        choices = {v: name for name, opt in OPTIONS.items() for v in opt.values}
        for opt in opts:
            if opt in choices:
                kwargs[choices[opt]] = opt
            elif opt in OPTIONS and not OPTIONS[opt].values:
                kwargs[opt] = True
            else:
                raise InputError(where, value, f"{where}={value!r}: unknown option {opt!r}; the options of "
                                 f"{law!r}: {cls.options_of(law)}")
        try:
            return cls(law, **kwargs)
        except InputError as exc:
            raise exc.at(f"{where}={value!r}") from None


#: The historical controller type names and what each is.
ALIASES: dict[str, ControllerSpec] = {
    "smc": ControllerSpec("smc"),
    "microstep": ControllerSpec("microstep"),
    "cascade": ControllerSpec("cascade"),
    "exact_linearization": ControllerSpec("exact_linearization"),
    "dq_smc": ControllerSpec("dq_smc"),
    "smc_la": ControllerSpec("smc", rho_plan="loss_aware"),
    "smc_ff": ControllerSpec("smc", feedforward=True),
    "dq_smc_ff": ControllerSpec("dq_smc", feedforward=True),
    "smc_la_ff": ControllerSpec("smc", feedforward=True, rho_plan="loss_aware"),
    "cascade_ff": ControllerSpec("cascade", feedforward=True),
    "cascade_model": ControllerSpec("cascade", feedforward=True, observer_torques=True),
    "dq_smc_i": ControllerSpec("dq_smc", integral=True),
    "dq_smc_i_ff": ControllerSpec("dq_smc", integral=True, feedforward=True),
    "smc_ff_hold": ControllerSpec("smc", feedforward=True, hold=True),
    "dq_smc_i_ff_km": ControllerSpec("dq_smc", integral=True, feedforward=True, km_estimate=True),
}
#: The controllers a scenario can name by their historical type names (``[controller] type``), the paper's first;
#: any other valid combination of a law and its options is named ``law+option+...``.
CONTROLLER_TYPES = tuple(ALIASES)


class _Labels(dict[str, str]):
    """The historical names' labels; any other controller name's label is its spec's (``LABELS[name]``)."""

    def __missing__(self, name: str) -> str:
        return ControllerSpec.parse(name).label()


#: Short labels of the historical names for tables and figures; ``LABELS[name]`` of any other name is its spec's.
LABELS = _Labels({"smc": "flatness + SMC", "microstep": "open-loop microstep", "cascade": "cascaded PID (FOC)",
          "exact_linearization": "exact linearization", "dq_smc": "flatness d-q + SMC",
          "smc_ff": "flatness + SMC + ff", "dq_smc_ff": "flatness d-q SMC + ff",
          "cascade_ff": "cascade + anti-cogging", "cascade_model": "cascade + model obs.",
          "smc_la": "flatness + SMC, rho(t)", "smc_la_ff": "flatness rho(t) + ff",
          "dq_smc_i": "flatness d-q SMC + I", "dq_smc_i_ff": "flatness d-q SMC+I+ff",
          "smc_ff_hold": "flatness SMC+ff, hold", "dq_smc_i_ff_km": "flatness d-q I+ff+Km"})
#: The types whose gains are the scenario's :class:`~flatstep.control.smc.SMCGains` (not tuned by rule).
SMC_TYPES = tuple(k for k, s in ALIASES.items() if s.sliding)
#: The flatness types that can run in continuous time (no integral or estimate advancing by the control period).
CONTINUOUS_TYPES = tuple(k for k, s in ALIASES.items() if s.continuous)
#: The types that need a torque model.
FEEDFORWARD_TYPES = tuple(k for k, s in ALIASES.items() if s.needs_torques)


#: The controller a scenario file with a drive (``[drive] control_rate``) runs when its ``[controller]`` table names
#: none: the cascade with the flat feedforward of its planned currents (``R i* + L di*/dt``), its current loops in
#: the plan's frame with a share of the plan's current held on d, at the rule gains of
#: :func:`flatstep.control.cascade.plan_frame_rule` (docs/comparison.md, "The default controller").
DEFAULT_TYPE = "cascade+voltage_feedforward+plan_frame"
#: The same with the file's ``[feedforward]`` torques in its q-current command and its observer.
DEFAULT_TYPE_TORQUES = "cascade+feedforward+observer_torques+voltage_feedforward+plan_frame"
#: The controller of a file without a drive: the paper's law, in continuous time as in the paper.
DEFAULT_TYPE_CONTINUOUS = "smc"


def default_type(*, sampled: bool, torques: bool) -> str:
    """The controller type a scenario file runs when its ``[controller]`` table gives no ``type`` or ``law``.

    Parameters
    ----------
    sampled : bool
        Whether the file has a drive (``[drive] control_rate``); without one the law runs in continuous time.
    torques : bool
        Whether the file has a ``[feedforward]`` table (known torques).

    Returns
    -------
    str
        :data:`DEFAULT_TYPE_TORQUES` or :data:`DEFAULT_TYPE` with a drive, :data:`DEFAULT_TYPE_CONTINUOUS` without.
    """
    if not sampled:
        return DEFAULT_TYPE_CONTINUOUS
    return DEFAULT_TYPE_TORQUES if torques else DEFAULT_TYPE

def spec_without_law(options: Mapping[str, Any], default: str, where: str = "controller") -> ControllerSpec:
    """The controller of a ``[controller]`` table that gives options but no ``law``.

    It is the default type's law and options (``default``, from :func:`default_type`), the given options set over them.

    Parameters
    ----------
    options : mapping
        The table's option keys (of :data:`OPTIONS`) and their values.
    default : str
        The controller the file runs when it names none.
    where : str
        The table, for messages (``file:controller``).

    Raises
    ------
    InputError
        Naming the first option set (not at its off value) that the default's law does not take: which law was
        meant is ambiguous, so the table must name it.
    """
    base = ControllerSpec.parse(default)
    for key, value in options.items():
        if key in OPTIONS and base.law not in OPTIONS[key].laws and value != _off(key):
            raise InputError(key, value, f"{where}.{key}: the table names no law, so the controller is the default "
                             f"{default!r} (law {base.law!r}, docs/controllers.md), which has no option {key}; name "
                             f"the law: law = one of {list(OPTIONS[key].laws)}, or give type")
    return ControllerSpec.parse({"law": base.law, **{k: getattr(base, k) for k in base.options_on()}, **options},
                                where)


def label(kind: str) -> str:
    """The label of a controller name (:data:`LABELS`, or the spec's own for a ``law+option+...`` name)."""
    return LABELS[kind]


def is_controller(name: object) -> bool:
    """Whether ``name`` names a controller: an alias, ``law+option+...`` or ``alias+option+...``, valid."""
    try:
        ControllerSpec.parse(name)
    except ValueError:
        return False
    return isinstance(name, str)
