"""What controller to build: a law and its orthogonal options, validated in one place.

A :class:`ControllerSpec` names one of the :data:`LAWS` and the options it takes:

=====================  =============================================================  ==============================
option                 what it adds                                                   laws
=====================  =============================================================  ==============================
``feedforward``        the torques known beyond eq. (1) (a ``TorqueModel``: detent,   smc, dq_smc, cascade
                       Coulomb friction, load) in the law's voltages and observer
                       (the cascade: anti-cogging, as firmware does it)
``observer_torques``   the cascade's observer knows those torques too                cascade (with feedforward)
``integral``           integral action on ``s2``                                      dq_smc
``km_estimate``        an online estimate of ``Km``                                   dq_smc (integral, feedforward)
``hold``               the detent hold from ``tf`` on                                 smc
``rho_plan``           ``"plan"`` (the plan's rho*) or ``"loss_aware"`` (rho*(t)      smc
                       from the torque the move needs)
=====================  =============================================================  ==============================

Every combination the table allows is a controller; :meth:`ControllerSpec.name` is its name (the historical type
names, ``"dq_smc_i_ff"`` say, for the combinations that had one: :data:`ALIASES`), and :meth:`ControllerSpec.parse`
reads a name back, either form. What each law needs from a run (a control period, the torque model, the sliding
gains) is derived here, not listed by hand.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Mapping

from ..validate import InputError

#: The control laws, the paper's first.
LAWS = ("smc", "dq_smc", "cascade", "microstep", "exact_linearization")
#: The laws whose gains are the run's :class:`~flatstep.control.smc.SMCGains` (designed or given, not by rule).
SLIDING_LAWS = ("smc", "dq_smc")
#: Which laws take each option (``rho_plan``: its values other than ``"plan"``).
OPTION_LAWS: dict[str, tuple[str, ...]] = {
    "feedforward": ("smc", "dq_smc", "cascade"),
    "observer_torques": ("cascade",),
    "integral": ("dq_smc",),
    "km_estimate": ("dq_smc",),
    "hold": ("smc",),
    "rho_plan": ("smc",),
}
#: The values of ``rho_plan``.
RHO_PLANS = ("plan", "loss_aware")
#: Short labels of the laws, for tables and figures.
LAW_LABELS = {"smc": "flatness + SMC", "dq_smc": "flatness d-q SMC", "cascade": "cascaded PID (FOC)",
              "microstep": "open-loop microstep", "exact_linearization": "exact linearization"}


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
    """

    law: str = "smc"
    feedforward: bool = False
    observer_torques: bool = False
    integral: bool = False
    km_estimate: bool = False
    hold: bool = False
    rho_plan: str = "plan"

    def __post_init__(self) -> None:
        if not isinstance(self.law, str) or self.law not in LAWS:
            raise InputError("law", self.law, f"law={self.law!r} is unknown; valid: {list(LAWS)}")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("law", "rho_plan"):
                continue
            if not isinstance(value, bool):
                raise InputError(f.name, value, f"{f.name}={value!r} is not true or false")
            if value and self.law not in OPTION_LAWS[f.name]:
                raise InputError(f.name, value, f"{f.name}=true is not an option of law {self.law!r} (it is one of "
                                 f"{list(OPTION_LAWS[f.name])}); the options of {self.law!r}: "
                                 f"{self.options_of(self.law)}")
        if not isinstance(self.rho_plan, str) or self.rho_plan not in RHO_PLANS:
            raise InputError("rho_plan", self.rho_plan, f"rho_plan={self.rho_plan!r} is unknown; valid: "
                             f"{list(RHO_PLANS)}")
        if self.rho_plan != "plan" and self.law not in OPTION_LAWS["rho_plan"]:
            raise InputError("rho_plan", self.rho_plan, f"rho_plan={self.rho_plan!r} is an option of "
                             f"{list(OPTION_LAWS['rho_plan'])}, not of law {self.law!r}")
        if self.observer_torques and not self.feedforward:
            raise InputError("observer_torques", True, "observer_torques=true needs feedforward=true (the observer "
                             "shares the torque model the feedforward brings)")
        if self.km_estimate and not (self.integral and self.feedforward):
            raise InputError("km_estimate", True, "km_estimate=true needs integral=true and feedforward=true (the "
                             "estimate runs on the integral's error, with the torques known)")
        if self.hold and self.rho_plan != "plan":
            raise InputError("hold", True, "hold=true holds the plan's rho at the target; with rho_plan='loss_aware' "
                             "give one of them")

    @staticmethod
    def options_of(law: str) -> list[str]:
        """The options ``law`` takes."""
        return [name for name, laws in OPTION_LAWS.items() if law in laws]

    # -- what the law needs, derived -------------------------------------------------------------------------------
    @property
    def needs_torques(self) -> bool:
        """Whether a torque model (a scenario's ``[feedforward]``) must be given."""
        return self.feedforward

    @property
    def sliding(self) -> bool:
        """Whether the gains are the run's SMCGains (else tuned by rule from the control period)."""
        return self.law in SLIDING_LAWS

    @property
    def needs_control_period(self) -> bool:
        """Whether the law is tuned from, or advances by, the control period (no continuous-time run)."""
        return not self.sliding or self.integral

    @property
    def continuous(self) -> bool:
        """Whether the law can run in continuous time (flatstep.engine.settings.Continuous)."""
        return not self.needs_control_period

    # -- names -----------------------------------------------------------------------------------------------------
    def name(self) -> str:
        """The controller's name: its historical type name (:data:`ALIASES`), else ``law+option+...``."""
        for alias, spec in ALIASES.items():
            if spec == self:
                return alias
        opts = [f.name for f in fields(self) if f.name not in ("law", "rho_plan") and getattr(self, f.name)]
        if self.rho_plan != "plan":
            opts.append(self.rho_plan)
        return "+".join([self.law, *opts])

    def label(self) -> str:
        """A short label for tables and figures."""
        base = LAW_LABELS[self.law]
        extra = [text for on, text in ((self.rho_plan == "loss_aware", "rho(t)"), (self.integral, "I"),
                                       (self.feedforward and not self.observer_torques, "ff"),
                                       (self.observer_torques, "model obs."), (self.km_estimate, "Km"),
                                       (self.hold, "hold")) if on]
        return base + (", " + "+".join(extra) if extra else "")

    @classmethod
    def parse(cls, value: Any, where: str = "controller") -> "ControllerSpec":
        """A spec from a name (an alias or ``law+option+...``), a mapping of fields, or a spec.

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
        if law not in LAWS:
            raise InputError(where, value, f"{where}={value!r} is unknown; valid: {list(ALIASES)}, or "
                             f"law+option+... with a law of {list(LAWS)} and options of {list(OPTION_LAWS)}")
        kwargs: dict[str, Any] = {}
        for opt in opts:
            if opt in RHO_PLANS:
                kwargs["rho_plan"] = opt
            elif opt in OPTION_LAWS and opt != "rho_plan":
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
