"""The pull-out curve of flatstep.model.pullout against a curve a vendor measured and published (docs/curves.md).

Jkongmotor JK42HS34-0844YA-01 (examples/motors/jkongmotor-jk42hs34-0844ya-01.toml), "Pull out Torque Curve" of its
specification sheet: 24 VDC, current 0.84 A, full step; speed in pulses (full steps) per second, torque in kg.cm. The
sheet gives the curve as a figure only: the points below were read off it by eye (at the grid lines' resolution,
about +-0.03 kg.cm), source
https://github.com/c0psrul3/Ender-3-S1-Klipper-BTT-SKR-mini-E3-v3/blob/0c58f0b33ba334911382b0784aa3484481fd00c0/resources/Ender-3__stock_stepper_motor__JK42HS34-0844YA-01.pdf

The sheet's drive steps in full steps; flatstep's curves are those of a sine (microstepping) drive. A full-step drive
moves the equilibrium by 90 electrical degrees at once: at low speed a load x T_hold lags by asin(x) and after a step
needs T_hold cos(asin(x)) > x T_hold to move on, so it carries at most sin(45 deg) = 0.707 of the sine drive's
torque. Prints per point the measured torque, the model's chopper curve (i_d = 0 side, the stable one) times 0.707 and
its error, the field-weakening bound times 0.707 and its error, the band of the datasheet's conventions
(flatstep.model.pullout.convention_band, sine drive), and the sine drive measured on the C engine
(flatstep.studies.pullout.engine_pullout).

    .venv/bin/python benchmarks/pullout_published.py
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from flatstep.model.datasheet import motor_from_table
from flatstep.model.pullout import convention_band, pullout_torque
from flatstep.studies.file_values import read_toml
from flatstep.studies.pullout import engine_pullout

ROOT = Path(__file__).resolve().parent.parent
KGCM = 0.0980665  # N m per kg.cm
#: (full steps per second, kg.cm), read off the published figure.
POINTS = ((100, 1.40), (200, 1.10), (500, 1.81), (750, 1.76), (1000, 1.56), (1250, 1.48), (1500, 1.46),
          (1750, 1.20), (2000, 0.85), (2500, 0.75), (3000, 0.70))
V_BUS, SETTING = 24.0, 0.84  # the sheet's drive: 24 VDC, 0.84 A per phase, full step
FULL_STEP = math.sin(math.pi / 4)  # the share of a sine drive's pull-out torque a full-step drive carries


def main() -> None:
    """Print the table and the mean absolute errors."""
    path = ROOT / "examples/motors/jkongmotor-jk42hs34-0844ya-01.toml"
    model = motor_from_table(read_toml(path)["motor"], str(path))
    motor = model.params
    rho = math.sqrt(2.0) * SETTING  # a full-step drive at 0.84 A per phase: both phases on, the vector norm
    pps = np.array([p for p, _ in POINTS], dtype=float)
    measured = np.array([t for _, t in POINTS]) * KGCM
    w = pps * 2 * math.pi / (4 * motor.Nr)  # 4 Nr full steps a turn
    chopper = pullout_torque(motor, "chopper", V_BUS, rho, w)
    weakening = pullout_torque(motor, "foc_weakening", V_BUS, rho, w)
    low, high = convention_band(model, "chopper", V_BUS, SETTING, w)
    engine = engine_pullout(motor, V_BUS, rho, w, progress=False)
    chopper, weakening = FULL_STEP * chopper, FULL_STEP * weakening
    print(f"{'pps':>6}{'rad/s':>8}{'rpm':>6}{'measured':>10}{'chop.fs':>9}{'err':>6}{'weak.fs':>9}{'err':>6}"
          f"{'band lo':>9}{'band hi':>9}{'engine':>9}")
    print(f"{'':>6}{'':>8}{'':>6}{'[N m]':>10}{'[N m]':>9}{'[%]':>6}{'[N m]':>9}{'[%]':>6}{'[N m]':>9}{'[N m]':>9}"
          f"{'[N m]':>9}")
    for row in zip(pps, w, measured, chopper, weakening, low, high, engine, strict=True):
        p, s, m, c, f, lo, hi, e = row
        print(f"{p:>6.0f}{s:>8.2f}{s * 60 / (2 * math.pi):>6.0f}{m:>10.4f}{c:>9.4f}{100 * (c - m) / m:>6.0f}"
              f"{f:>9.4f}{100 * (f - m) / m:>6.0f}{lo:>9.4f}{hi:>9.4f}{e:>9.4f}")
    inside = int(np.sum((measured >= low) & (measured <= high)))
    print(f"mean |error|: chopper x 0.707 {100 * np.mean(np.abs(chopper - measured) / measured):.0f} %, weakening "
          f"x 0.707 {100 * np.mean(np.abs(weakening - measured) / measured):.0f} %; {inside} of {len(pps)} measured "
          "points inside the sine drive's band")


if __name__ == "__main__":
    main()
