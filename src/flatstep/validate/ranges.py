"""The ranges flatstep accepts for every physical quantity a user gives, in one table (docs/errors.md lists it).

The bounds are wide: several orders of magnitude around real stepping motors and drives. They are there to
refuse values that are not a motor (a 1e10-tooth rotor, a 1e300 N m load, a 1 THz PWM), that would overflow the
C core's integers or floats, or that would make a run's numbers meaningless; not to second-guess a design.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Quantity:
    """A range: ``low < x`` (``<=`` when ``low_closed``) and ``x <= high`` (``<`` when ``high_open``)."""

    low: float
    high: float
    unit: str
    why: str
    low_closed: bool = False
    high_open: bool = False

    @property
    def unit_suffix(self) -> str:
        """`` unit`` for messages, or nothing for a dimensionless quantity."""
        return f" {self.unit}" if self.unit else ""

    def contains(self, x: float) -> bool:
        """Whether ``x`` is in the range."""
        above = x >= self.low if self.low_closed else x > self.low
        return above and (x < self.high if self.high_open else x <= self.high)

    def describe(self) -> str:
        """The range in interval notation with its unit, e.g. ``(0, 1e+04] ohm``."""
        return (f"{'[' if self.low_closed else '('}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"
                f"{self.unit_suffix}")


def _q(low: float, high: float, unit: str, why: str, low_closed: bool = False, high_open: bool = False) -> Quantity:
    """A :class:`Quantity`, positionally."""
    return Quantity(low, high, unit, why, low_closed, high_open)


#: Every bounded quantity by name. Integers (teeth, counts, bits, substeps) are bounded in
#: :data:`INTEGER_RANGES`.
QUANTITIES: dict[str, Quantity] = {
    # the motor
    "R": _q(1e-6, 1e4, "ohm", "a phase resistance from 1 uohm to 10 kohm", low_closed=True),
    "L": _q(1e-9, 10.0, "H", "a phase inductance from 1 nH to 10 H", low_closed=True),
    "Km": _q(1e-7, 100.0, "V s/rad", "a torque constant from 1e-7 to 100 N m/A", low_closed=True),
    "J": _q(1e-12, 100.0, "kg m^2", "an inertia from 1e-12 to 100 kg m^2", low_closed=True),
    "B": _q(0.0, 1e3, "N m s/rad", "viscous friction cannot be negative", low_closed=True),
    # the plant's effects and load
    "torque_amplitude": _q(0.0, 1e3, "N m", "an amplitude, >= 0 and at most 1000 N m", low_closed=True),
    "coulomb_speed": _q(1e-9, 1e6, "rad/s", "the speed scale of the smooth sign, from 1e-9 rad/s", low_closed=True),
    "magnetizing_resistance": _q(1e-6, 1e9, "ohm", "an iron-loss resistance from 1 uohm", low_closed=True),
    "load": _q(-1e3, 1e3, "N m", "a load torque within +-1000 N m", low_closed=True),
    # the plan
    "angle": _q(-1e6, 1e6, "rad", "an angle within +-1e6 rad", low_closed=True),
    "current": _q(1e-6, 1e3, "A", "a current-vector norm from 1 uA (the angle of a zero vector is undefined) to "
                                  "1000 A", low_closed=True),
    "time": _q(0.0, 1e6, "s", "the run starts at t = 0: times are >= 0 and at most 1e6 s", low_closed=True),
    "t_end": _q(0.0, 1e6, "s", "a horizon above 0"),
    "duration": _q(1e-3, 3600.0, "s", "a recording from 1 ms to one hour", low_closed=True),
    # the planner's limits and caps (flatstep.plan.limits.MotorLimits, flatstep.plan.waypoints.Caps)
    "speed": _q(0.0, 1e6, "rad/s", "a speed above 0 and at most 1e6 rad/s"),
    "velocity": _q(-1e6, 1e6, "rad/s", "a speed within +-1e6 rad/s", low_closed=True),
    "acceleration": _q(0.0, 1e9, "rad/s^2", "an acceleration above 0 and at most 1e9 rad/s^2"),
    "jerk": _q(0.0, 1e12, "rad/s^3", "a jerk above 0 and at most 1e12 rad/s^3"),
    "torque_angle": _q(0.0, 1.5707963267948966, "rad", "a torque angle above 0 and below pi/2 (where the law is "
                       "singular)", high_open=True),
    "fraction": _q(0.0, 1.0, "", "a share above 0 and at most 1"),
    "d_current": _q(-1e3, 1e3, "A", "a d current within +-1000 A (negative weakens the field)", low_closed=True),
    # the controller
    "gain": _q(1e-12, 1e12, "", "a gain from 1e-12 to 1e12", low_closed=True),
    "damping": _q(1e-6, 1e3, "", "a damping ratio from 1e-6 to 1000", low_closed=True),
    "relative": _q(0.0, 0.5, "", "a relative parameter error in [0, 0.5)", low_closed=True, high_open=True),
    "confidence": _q(0.0, 1.0, "", "a confidence level in (0, 1), e.g. 0.95", high_open=True),
    "scale": _q(0.0, 1e3, "", "a factor above 0 and at most 1000"),
    # the drive, sensors and observer
    "v_bus": _q(1e-3, 1e4, "V", "a bus voltage from 1 mV to 10 kV", low_closed=True),
    "rate": _q(1e-3, 1e8, "Hz", "a rate from 1 mHz to 100 MHz", low_closed=True),
    "period": _q(1e-8, 1e3, "s", "a period of at least 10 ns and at most 1000 s", low_closed=True),
    "current_range": _q(1e-6, 1e4, "A", "an ADC full scale from 1 uA", low_closed=True),
    "current_noise": _q(0.0, 1e3, "A", "a noise standard deviation, >= 0", low_closed=True),
    "current_offset": _q(-1e3, 1e3, "A", "an offset within +-1000 A", low_closed=True),
    "bandwidth": _q(1e-6, 1e9, "rad/s", "a bandwidth from 1e-6 to 1e9 rad/s", low_closed=True),
    # the solver
    "tolerance": _q(1e-16, 1.0, "", "an error tolerance from 1e-16 to 1", low_closed=True),
    "dt_out": _q(1e-12, 1e6, "s", "an output spacing from 1 ps", low_closed=True),
}

#: Integer quantities: ``(low, high)``, inclusive.
INTEGER_RANGES: dict[str, tuple[int, int]] = {
    "Nr": (1, 1000),
    "detent_harmonic": (1, 1000),
    "substeps": (1, 100_000),
    "encoder_counts": (4, 2**30),
    "current_bits": (2, 32),
    "delay": (0, 1000),
    "seed": (0, 2**63 - 1),
    "samples": (0, 100_000),
    "load_states": (0, 2),
    "repeat": (1, 100_000),
    "seeds": (1, 50),
    "periods": (1, 256),
    "microsteps": (1, 1024),
}


def markdown_table() -> str:
    """Every range of :data:`QUANTITIES` and :data:`INTEGER_RANGES` as a Markdown table (docs/errors.md)."""
    rows = ["| quantity | valid | why |", "|---|---|---|"]
    rows += [f"| `{name}` | {q.describe()} | {q.why} |" for name, q in QUANTITIES.items()]
    rows += [f"| `{name}` (integer) | [{low}, {high}] | |" for name, (low, high) in INTEGER_RANGES.items()]
    return "\n".join(rows)
