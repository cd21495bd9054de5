"""The sampled-data drive loop, readable reference: sensors -> observer -> controller -> drive -> plant.

One control period k, at ``t_k = k Ts``:

1. the sensors read the plant (encoder angle, ADC currents with offset and noise), possibly ``delay``
   periods old;
2. the observer corrects its estimate with the encoder angle (with ``edge_timing``, where a count edge fell within
   the period, with that edge's angle against the estimate its age ago); speed and acceleration come from it (or,
   with no observer, the speed is the encoder's backward difference and the acceleration the zero-load model);
3. the controller computes the voltages; with ``compute_delay`` they are applied one period later;
4. the drive saturates them at the bus (direction kept) and, in switched mode, chops them into PWM
   segments;
5. the plant (eq. (1) plus any :class:`~flatstep.model.plant.PlantEffects`: detent, Coulomb friction, iron loss)
   is integrated over the period by RK4 (``substeps`` per period, or one step per PWM segment);
6. the observer predicts the next angle, speed and load from the torque of the measured currents, less the
   torques the controller's model knows beyond eq. (1) (its ``observer_torques``, a
   :class:`~flatstep.model.torque_model.TorqueModel`, if it has one), held over the period or, with
   ``torque_ramp``, ramping by its last change.

This loop runs in Python, one period at a time: it is the specification the C engine is tested against,
not the fast path.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..control.protocol import Controller
from ..model.motor import MotorParams, torque
from ..model.plant import PlantEffects, plant_acceleration, plant_rhs
from ..model.torque_model import TorqueModel
from ..validate import check_bool, check_count, check_quantity
from .drive import Drive
from .observers import Observer
from .sensors import Sensors


@dataclass(frozen=True)
class DriveLoop:
    """Sampled control: the control period, the plant's integration, and the parts of the drive.

    The parts around the controller are the drive, the sensors and the observer; ``None`` parts are ideal.

    Parameters
    ----------
    control_period : float
        Ts [s], > 0: the controller fires at ``t = k Ts`` and its voltage is held over the period.
    substeps : int
        RK4 steps of the plant per period (averaged bridge), >= 1.
    compute_delay : bool
        Apply each command one period after it is computed.
    drive : Drive, optional
        Bus saturation and PWM (:class:`~flatstep.loop.drive.Drive`).
    sensors : Sensors, optional
        Quantized and noisy measurements, measurement delay (:class:`~flatstep.loop.sensors.Sensors`).
    observer : Observer, optional
        Estimated angle, speed and load (:class:`~flatstep.loop.observers.Observer`), for a controller with
        ``measurement="observer"``.
    """

    control_period: float = 5e-5
    substeps: int = 4
    compute_delay: bool = False
    drive: Optional[Drive] = None
    sensors: Optional[Sensors] = None
    observer: Optional[Observer] = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "control_period",
                           check_quantity("period", self.control_period, as_name="control_period"))
        object.__setattr__(self, "substeps", check_count("substeps", self.substeps, why="RK4 steps per control period"))
        object.__setattr__(self, "compute_delay", check_bool("compute_delay", self.compute_delay))
        for name, kind in (("drive", Drive), ("sensors", Sensors), ("observer", Observer)):
            part = getattr(self, name)
            if part is not None and not isinstance(part, kind):
                raise ValueError(f"DriveLoop.{name}={part!r} is not a {kind.__name__} (or None)")

    @classmethod
    def at(cls, rate: float, **parts: Any) -> "DriveLoop":
        """The loop at a control rate [Hz] (``control_period = 1 / rate``), with the other settings as keywords."""
        return cls(control_period=1.0 / check_quantity("rate", rate), **parts)

    def as_dict(self) -> dict[str, Any]:
        """The settings, the parts as their own dicts (absent when ideal), for a result's metadata."""
        out: dict[str, Any] = {"control_period": self.control_period, "substeps": self.substeps,
                               "compute_delay": bool(self.compute_delay)}
        out.update({k: getattr(self, k).as_dict() for k in ("drive", "sensors", "observer") if getattr(self, k)})
        return out


def _rk4(x: NDArray[np.float64], v: ArrayLike, h: float, motor: MotorParams, load: float,
         effects: Optional[PlantEffects] = None) -> NDArray[np.float64]:
    """The plant's state after one classical RK4 step of length ``h`` under the constant voltages ``v``."""
    f = lambda y: plant_rhs(y, v, motor, load, effects)  # noqa: E731  (load constant over the period)
    k1 = f(x)
    k2 = f(x + 0.5 * h * k1)
    k3 = f(x + 0.5 * h * k2)
    k4 = f(x + h * k3)
    return x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def run_reference(plant: MotorParams, controller: Controller, loop: DriveLoop, x0: ArrayLike, load: float,
                  n_periods: int, effects: Optional[PlantEffects] = None) -> dict[str, NDArray[np.float64]]:
    """Run ``n_periods`` control periods of the drive loop, one period at a time.

    Parameters
    ----------
    plant : MotorParams
        The motor being driven.
    controller : Controller
        Any object with ``motor`` (its nominal model, also the observer's) and
        ``step(state, y, t) -> (v, new_state)``, and optionally ``initial_state()``.
    loop : DriveLoop
        The control period, the plant's integration and the parts of the drive.
    x0 : array_like
        The plant's start state (ia, ib, omega, theta).
    load : float
        The constant load torque [N m].
    n_periods : int
        How many control periods to run.
    effects : PlantEffects, optional
        Effects acting on the plant only.

    Returns
    -------
    dict of str to ndarray
        The time series at the control instants: ``t``, the plant state ``x`` (4, n+1), the applied voltages
        ``v`` (2, n+1, as averaged over the following period), what the controller saw, ``y`` (5, n+1), and the
        times at which the law faulted (``faults``; the drive then applied 0 V for that period).
    """
    Ts, model = loop.control_period, controller.motor
    torques: Optional[TorqueModel] = getattr(controller, "observer_torques", None)  # what the observer also knows
    sensors, drive, observer = loop.sensors, loop.drive, loop.observer
    noise = sensors.noise(n_periods + 1) if sensors else np.zeros((n_periods + 1, 2))
    if observer is not None:
        Ad, Bd, Lc = observer.matrices(model, Ts)
        Bf = observer.ramp(model, Ts)
        Te_prev: Optional[float] = None  # the torque of the last prediction (the observer's torque ramp)
    X, V, Y = np.empty((4, n_periods + 1)), np.zeros((2, n_periods + 1)), np.empty((5, n_periods + 1))
    x = np.array(x0, dtype=float)
    history: list[tuple[float, ...]] = []  # past readings (theta_m, ia_m, ib_m, theta_edge, age) for the delay
    xh: Optional[NDArray[np.float64]] = None
    v_hold = model.R * x[:2]  # what the bridge applies before the first command (the start equilibrium)
    theta_prev: Optional[float] = None
    y: tuple[float | NDArray[np.float64], ...]
    faults: list[float] = []
    ctrl_state = controller.initial_state()
    for k in range(n_periods + 1):
        t = k * Ts
        X[:, k] = x
        if sensors is None:
            reading: tuple[float, ...] = (x[3], x[0], x[1], 0.0, -1.0)
        else:
            i_m = sensors.read_currents(x[:2], noise[k])
            reading = (float(sensors.read_angle(x[3])), float(i_m[0]), float(i_m[1]),
                       *sensors.read_edge(float(x[3]), float(x[2])))
        history.append(reading)
        delay = sensors.delay if sensors else 0
        th_m, ia_m, ib_m, th_e, age = history[max(0, len(history) - 1 - delay)]
        if observer is not None:
            if xh is None:
                xh = np.array([th_m] + [0.0] * (observer.order - 1))
            elif 0.0 <= age < Ts:  # an edge within the period: the angle age ago was the edge's
                xh = xh + Lc * (th_e - (xh[0] - xh[1] * age))
            else:
                xh = xh + Lc * (th_m - xh[0])
            x_m = (ia_m, ib_m, xh[1], xh[0])  # measured currents, estimated speed and angle
            # the motor torque less the torques the controller knows (its torque model), as the C loop computes it
            Te = torque(x_m, model) - (0.0 if torques is None else float(torques.torque(t, xh[0], xh[1], model.Nr)))
            y = (*x_m, (Te - model.B * xh[1] - (xh[2] if observer.order > 2 else 0.0)) / model.J)
        elif sensors is None:
            y = (*x, float(plant_acceleration(x, plant, load, effects)))
        else:
            omega = 0.0 if theta_prev is None else (th_m - theta_prev) / Ts
            y = (ia_m, ib_m, omega, th_m, 0.0)
        theta_prev = th_m
        Y[:, k] = y
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            v_cmd, ctrl_state = controller.step(ctrl_state, np.array(y), t)
        if not np.all(np.isfinite(v_cmd)):
            # outside the law's domain (singular sqrt, rho = 0): de-energise, as the C smc_step does
            v_cmd = np.zeros(2)
            faults.append(t)
        v_new = drive.saturate(v_cmd) if drive is not None else v_cmd
        v_apply, v_hold = (v_hold, v_new) if loop.compute_delay else (v_new, v_new)
        V[:, k] = v_apply
        if k == n_periods:
            break
        if drive is not None and drive.pwm == "switched":
            durations, levels = drive.pwm_segments(v_apply, x[:2], Ts)
            for h, lv in zip(durations, levels, strict=True):  # one level per segment
                x = _rk4(x, lv, h, plant, load, effects)
        else:
            for _ in range(loop.substeps):
                x = _rk4(x, v_apply, Ts / loop.substeps, plant, load, effects)
        if not np.all(np.isfinite(x)):
            raise RuntimeError(f"the plant state became non-finite at t={t + Ts:.6g} s")
        if observer is not None:
            assert xh is not None, "the observer corrects its estimate every period"
            xh = Ad @ xh + Bd * Te + Bf * (0.0 if Te_prev is None else Te - Te_prev)
            Te_prev = float(Te)
    return {"t": np.arange(n_periods + 1) * Ts, "x": X, "v": V, "y": Y, "faults": np.array(faults)}
