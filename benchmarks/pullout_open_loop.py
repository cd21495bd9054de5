"""Open-loop plans along the pull-out curve against the best safe constant-acceleration trapezoid (docs/curves.md).

For each motor and move: the fastest plan of flatstep.plan.open_loop along the drive's own pull-out curve (measured on
the C engine, studies.open_loop.measured_pullout; the share of it used and the speed cap searched, the share printed)
and the fastest trapezoid that loses no step (studies.open_loop.best_trapezoid), both run by the open-loop
microstepping drive (20 kHz, 24 V) on the 32 plants of +-10 % on R, L, Km, J, B. Prints both durations, their ratio,
the lost runs and the worst angle error over the 32 plants.

    .venv/bin/python benchmarks/pullout_open_loop.py [--quick]
"""
from __future__ import annotations

import argparse
from pathlib import Path

from flatstep.model.datasheet import motor_from_table
from flatstep.model.motor import MotorParams
from flatstep.studies.file_values import read_toml
from flatstep.studies.open_loop import best_open_loop, best_trapezoid, measured_pullout

ROOT = Path(__file__).resolve().parent.parent
V_BUS = 24.0


def motors() -> dict[str, tuple[MotorParams, float]]:
    """The motors and their run currents (current-vector norm, A): the preset at 1 A, a datasheet motor at rated."""
    path = ROOT / "examples/motors/jkongmotor-jk42hs34-0844ya-01.toml"
    jk = motor_from_table(read_toml(path)["motor"], str(path))
    return {"nema17": (MotorParams.preset("nema17"), 1.0), "JK42HS34-0844YA-01": (jk.params, jk.rated_rho)}


def main() -> None:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one motor, two moves")
    args = parser.parse_args()
    moves = (1.0, 20.0) if args.quick else (1.0, 5.0, 20.0, 60.0)
    chosen = dict(list(motors().items())[:1]) if args.quick else motors()
    print(f"{'motor':<20}{'move':>7}{'open loop':>11}{'trapezoid':>11}{'ratio':>7}{'lost':>9}{'worst err':>11}"
          f"{'trap caps (v, a)':>22}{'share':>8}{'ol peak':>8}")
    print(f"{'':<20}{'[rad]':>7}{'[ms]':>11}{'[ms]':>11}{'':>7}{'(ol/trap)':>9}{'[mrad] ol':>11}"
          f"{'[rad/s, rad/s^2]':>22}{'':>8}{'[rad/s]':>8}")
    for name, (motor, current) in chosen.items():
        curve = measured_pullout(motor, V_BUS, current)
        for d in moves:
            plan, info, ol = best_open_loop(motor, V_BUS, current, d, pullout=curve)
            trap, caps, tc = best_trapezoid(motor, V_BUS, current, d)
            print(f"{name:<20}{d:>7g}{1e3 * plan.tf:>11.2f}{1e3 * trap.tf:>11.2f}{plan.tf / trap.tf:>7.3f}"
                  f"{f'{ol.lost}/{tc.lost}':>9}{1e3 * ol.worst_error:>11.2f}"
                  f"{caps['v_max']:>10.1f}, {caps['a_max']:>9.0f}{info['margin']:>8.3f}{info['w_peak']:>8.1f}",
                  flush=True)


if __name__ == "__main__":
    main()
