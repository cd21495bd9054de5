"""Speed, acceleration and load-torque estimation from the quantized encoder: a discrete Luenberger observer."""
from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..model.motor import MotorParams
from ..validate import check_bool, check_count, check_positive, check_quantity

#: The longest estimate the C observer holds (``OBSERVER_MAX_ORDER``, csrc/observer.h): angle, speed, load, its rate.
MAX_ORDER = 4


@dataclass(frozen=True)
class Observer:
    r"""Observer of the mechanical state from the encoder angle and the torque of the measured currents.

    The model, discretized exactly (zero-order hold on the torque) at the control period:

    .. math::
        \dot\theta = \omega,\quad J\dot\omega = T_e - B\omega - \tau_L,\quad
        \dot\tau_L = \tau_L' \ (\text{load\_states} = 2),\quad \dot\tau_L' = 0

    with :math:`T_e = K_m(i_b\cos N_r\hat\theta - i_a\sin N_r\hat\theta)` from the measured currents.
    ``load_states`` = 0 estimates angle and speed only (acceleration from the zero-load model), 1 adds a
    constant load torque, 2 a load torque ramp. The error poles sit at :math:`z = e^{-p_k T_s}` with
    :math:`p_k` spread over ``bandwidth * [1, 1.3]`` (distinct poles for a single-output placement).

    ``torque_ramp`` predicts with the torque ramping over the period by its change over the last one,
    :math:`T_e(t_k + \tau) = T_{e,k} + (T_{e,k} - T_{e,k-1})\,\tau/T_s` (a first-order hold extrapolated from
    the samples), instead of held at :math:`T_{e,k}`: the prediction adds :math:`B_f (T_{e,k} - T_{e,k-1})`
    (:meth:`ramp`). Where the currents slew at the bus's rate (field weakening), the held torque lags the rotor's
    by half a period of that slew, an error the correction must take up from the encoder's counts.
    """

    bandwidth: float = 1200.0
    load_states: int = 2
    torque_ramp: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "bandwidth", check_quantity("bandwidth", self.bandwidth))
        object.__setattr__(self, "load_states", check_count("load_states", self.load_states,
                                                            why="0: speed only, 1: constant load, 2: load ramp"))
        object.__setattr__(self, "torque_ramp", check_bool("torque_ramp", self.torque_ramp))

    @property
    def order(self) -> int:
        """The estimate's length: angle and speed, and the ``load_states``."""
        return 2 + self.load_states

    def matrices(self, motor: MotorParams,
                 Ts: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(Ad, Bd, L)``: the discretized model and the correction gain (current-estimator form)."""
        return _matrices(self, motor.J, motor.B, float(Ts))

    def ramp(self, motor: MotorParams, Ts: float) -> NDArray[np.float64]:
        r"""``Bf``: the response over one period to a torque rising by 1 N m across it (0 without ``torque_ramp``).

        .. math::
            B_f = \frac{1}{T_s}\int_0^{T_s} e^{A(T_s - \tau)} B\,\tau\,d\tau
        """
        return _ramp(self, motor.J, motor.B, float(Ts))

    def as_dict(self) -> dict[str, Any]:
        """The bandwidth, the load states and the torque ramp, for a result's metadata."""
        return asdict(self)

    def c_params(self, motor: MotorParams, Ts: float) -> dict[str, Any]:
        """The fields of the C ``struct observer_params`` (csrc/observer.h): :meth:`matrices` for ``motor`` and ``Ts``.

        ``Ad`` gives its ``order`` rows, each padded to :data:`MAX_ORDER` columns; the rest of the struct is zero.
        """
        Ad, Bd, Lc = self.matrices(motor, Ts)
        n = self.order
        return dict(order=n, Ad=[[float(Ad[i, j]) for j in range(n)] + [0.0] * (MAX_ORDER - n) for i in range(n)],
                    Bd=[float(b) for b in Bd], Lc=[float(c) for c in Lc],
                    Bf=[float(f) for f in self.ramp(motor, Ts)])


def _model(n: int, J: float, B: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The continuous model ``(A, B)`` of order ``n``: angle, speed and the load states, the torque as input."""
    A = np.zeros((n, n))
    A[0, 1], A[1, 1] = 1.0, -B / J
    if n > 2:
        A[1, 2] = -1.0 / J
    if n > 3:
        A[2, 3] = 1.0
    Bc = np.zeros((n, 1))
    Bc[1, 0] = 1.0 / J
    return A, Bc


@lru_cache(maxsize=64)
def _ramp(obs: Observer, J: float, B: float, Ts: float) -> NDArray[np.float64]:
    """:meth:`Observer.ramp` for the motor's ``J`` and ``B`` (cached: hashable arguments)."""
    check_positive("control_period", Ts, unit=" s")
    n = obs.order
    if not obs.torque_ramp:
        return np.zeros(n)
    A, Bc = _model(n, J, B)
    from scipy.linalg import expm  # here: scipy.linalg is a large import that most commands never use

    # the torque tau/Ts over the period as the state of a unit-rate integrator: its response is the ramp's
    M = np.zeros((n + 2, n + 2))
    M[:n, :n], M[:n, n], M[n, n + 1] = A, Bc[:, 0], 1.0
    return np.asarray(expm(M * Ts)[:n, n + 1] / Ts)


@lru_cache(maxsize=64)
def _matrices(obs: Observer, J: float, B: float,
              Ts: float) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The matrices of :meth:`Observer.matrices` for the motor's ``J`` and ``B`` (cached: hashable arguments)."""
    check_positive("control_period", Ts, unit=" s")
    n = obs.order
    A, Bc = _model(n, J, B)
    from scipy.linalg import expm  # here: scipy.linalg is a large import that most commands never use

    M = expm(np.block([[A, Bc], [np.zeros((1, n + 1))]]) * Ts)
    Ad, Bd = M[:n, :n], M[:n, n]
    C = np.zeros((1, n))
    C[0, 0] = 1.0
    poles = np.exp(-obs.bandwidth * Ts * np.linspace(1.0, 1.3, n))
    if np.any(poles < 1e-6):
        raise ValueError(f"bandwidth={obs.bandwidth!r} rad/s is too high for control_period={Ts!r} s; "
                         f"keep bandwidth * control_period below about 1")
    from scipy.signal import place_poles  # here: scipy.signal takes 0.7 s to import, on every command otherwise

    L = place_poles(Ad.T, C.T, poles).gain_matrix.T[:, 0]
    # current-estimator form: correct with the new angle, then predict; L_c = Ad^-1 L
    return Ad, Bd, np.linalg.solve(Ad, L)
