r"""Gain design for a sampled drive: sliding gains, boundary layers, error dynamics and observer bandwidth.

The rules, for a control period :math:`T_s` (see docs/drive.md for the reasoning and the measurements):

* **Boundary-layer bandwidth.** Inside the layer :math:`s' = -(W/\epsilon)s`; sampled with a zero-order
  hold this is the pole :math:`1 - \lambda T_s` with :math:`\lambda = W/\epsilon`. :math:`\lambda T_s = 0.3`
  (0.15 with a computation delay) keeps it well damped with margin for model error. The paper's
  :math:`W/\epsilon = 2\cdot10^4\,s^{-1}` gives :math:`\lambda T_s = 1` at 20 kHz: on the edge.
* **Error dynamics** :math:`e'' + 2\xi\omega_n e' + \omega_n^2 e = s_2`: :math:`\omega_n = \lambda/4`,
  :math:`\xi = 0.9`, slower than the layer they sit on.
* **Reaching gains.** :math:`W` must exceed the disturbance the model error injects into :math:`s'`;
  :math:`W = 2 d_{max}`, with :math:`d_{max}` bounded along the plan from the relative parameter
  uncertainty :math:`\delta`:

  .. math::
      d_1 = \frac{\delta}{L}\big(R\rho + K_m|\omega| + L|\dot\rho|\big)_{max},\qquad
      d_2 = \delta\Big(\frac{K_m\rho}{J}N_r|\omega| + 2|\theta^{*(3)}| + \frac{B}{J}|\ddot\theta^*|\Big)_{max}
            + \frac{\tau_{max}\lambda}{J}

  (an inductance error turns the commanded current-angle rate :math:`-N_r\omega` into a torque-rate error; a
  torque-constant or inertia error scales :math:`\theta^{*(3)}`; a load step of :math:`\tau` enters
  :math:`s_2` as :math:`\tau/J` and must be removed within :math:`1/\lambda`).
* **Observer** bandwidth :math:`= \omega_n`, with a load-torque ramp state: fast enough to follow the
  disturbance at the error bandwidth, slow enough to average the encoder's quantization.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from ..control.smc import SMCGains
from ..control.tuning import LAMBDA_TS, LAMBDA_TS_DELAYED, W_MARGIN, WN_OVER_LAMBDA, XI
from ..model.motor import MotorParams
from ..plan.feasibility import check_feasibility
from ..plan.protocol import Plan
from ..validate import check_bool, check_count, check_quantity
from .observers import Observer


@dataclass(frozen=True)
class Design:
    """Result of :func:`design_gains`: the gains, the observer and the numbers behind them."""

    gains: SMCGains
    observer: Observer
    rationale: dict[str, float]
    warnings: tuple[str, ...] = field(default_factory=tuple)

    def as_dict(self) -> dict[str, Any]:
        """The gains, the observer, the rationale and the warnings, for JSON."""
        return {"gains": self.gains.as_dict(), "observer": self.observer.as_dict(),
                "rationale": dict(self.rationale), "warnings": list(self.warnings)}


def design_gains(motor: MotorParams, plan: Plan, *, control_period: float = 5e-5, v_bus: float = 24.0,
                 encoder_counts: Optional[int] = 16384, current_step: float = 4.0 / 4096,
                 load_torque: float = 1e-5, uncertainty: float = 0.1, compute_delay: bool = False) -> Design:
    """Pick W1, W2, eps1, eps2, xi, wn and the observer bandwidth for a sampled drive.

    Parameters
    ----------
    motor : MotorParams
        The controller's model of the motor.
    plan : Plan
        The move it must track.
    control_period : float
        Ts [s] (default 50 us, 20 kHz).
    v_bus : float
        Bus voltage [V]; the design warns when the plan's feedforward leaves less than 25 % headroom.
    encoder_counts : int, optional
        Encoder resolution (counts per revolution), ``None`` without an encoder; with ``current_step``, used
        to check that quantization noise stays inside the boundary layers.
    current_step : float
        Current ADC step [A].
    load_torque : float
        The largest load torque expected [N m].
    uncertainty : float
        Relative error of every model parameter (0.1 for +-10 %).
    compute_delay : bool
        One control period between measuring and applying.

    Returns
    -------
    Design
        The gains, the observer and the numbers behind them, with any warnings.
    """
    Ts = check_quantity("period", control_period, as_name="control_period")
    v_bus = check_quantity("v_bus", v_bus)
    delta = check_quantity("relative", uncertainty, as_name="uncertainty")
    if delta >= 0.5:
        raise ValueError(f"uncertainty={delta!r} must be in [0, 0.5) (a relative parameter error)")
    tau = abs(check_quantity("load", load_torque, as_name="load_torque"))
    current_step = check_quantity("current_noise", current_step, as_name="current_step")
    if encoder_counts is not None:
        encoder_counts = check_count("encoder_counts", encoder_counts)
    compute_delay = check_bool("compute_delay", compute_delay)
    lam = (LAMBDA_TS_DELAYED if compute_delay else LAMBDA_TS) / Ts
    wn = WN_OVER_LAMBDA * lam
    t = np.linspace(plan.t0, plan.tf, 2001)
    f = plan.flag(t)
    m = motor
    d1 = delta / m.L * np.max(m.R * f.rho + m.Km * np.abs(f.dtheta) + m.L * np.abs(f.drho))
    d2 = float(delta * np.max(m.Km * f.rho / m.J * m.Nr * np.abs(f.dtheta) + 2 * np.abs(f.dddtheta)
                              + m.B / m.J * np.abs(f.ddtheta)) + tau * lam / m.J)
    W1, W2 = W_MARGIN * max(d1, 1e-3 * np.max(f.rho) * lam), W_MARGIN * max(d2, 1.0)
    gains = SMCGains(W1=float(W1), W2=float(W2), eps1=float(W1 / lam), eps2=float(W2 / lam), xi=XI, wn=float(wn))
    observer = Observer(bandwidth=float(wn), load_states=2)

    warnings = []
    q = 0.0 if encoder_counts is None else 2 * math.pi / encoder_counts
    # one ADC step moves the acceleration estimate (Km di / J), hence s2, by this much
    s2_noise = m.Km * current_step / m.J
    if s2_noise > gains.eps2:
        warnings.append(f"one ADC step moves s2 by {s2_noise:.3g}, more than eps2={gains.eps2:.3g}: "
                        "expect chattering; use a finer current ADC or a slower control rate")
    if q * wn > 0.5 * np.max(np.abs(f.dtheta)):
        warnings.append(f"one encoder count per 1/wn ({q * wn:.3g} rad/s) is comparable to the planned speed: "
                        "the observer cannot resolve the motion; use a finer encoder")
    if current_step > gains.eps1:
        warnings.append(f"ADC step {current_step:.3g} A exceeds eps1={gains.eps1:.3g} A: expect current chattering")
    rep = check_feasibility(plan, motor, load_torque=tau)
    if not rep.feasible:
        warnings.append("the plan itself is infeasible: " + "; ".join(rep.violations))
    elif rep.peak_voltage > 0.75 * v_bus:
        warnings.append(f"the feedforward needs {rep.peak_voltage:.3g} V, more than 75 % of v_bus={v_bus:.3g} V: "
                        "little headroom is left for the feedback")
    rationale = {"lambda": lam, "lambda_Ts": lam * Ts, "d1_max": float(d1), "d2_max": d2,
                 "s2_adc_step": float(s2_noise), "feedforward_peak_voltage": rep.peak_voltage,
                 "encoder_count": q}
    return Design(gains, observer, rationale, tuple(warnings))
