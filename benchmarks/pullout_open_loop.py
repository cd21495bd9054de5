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
    print(f"{'motor':<20}{'move':>6}{'open loop':>10}{'trapezoid':>10}{'ratio':>7}{'lost':>6}{'worst err':>13}"
          f"{'share':>7}{'ol peak':>8}{'trap v, a':>17}")
    print(f"{'':<20}{'[rad]':>6}{'[ms]':>10}{'[ms]':>10}{'ol/trap':>7}{'ol/tr':>6}{'ol/tr [mrad]':>13}"
          f"{'':>7}{'[rad/s]':>8}{'[rad/s, rad/s^2]':>17}")
    for name, (motor, current) in chosen.items():
        curve = measured_pullout(motor, V_BUS, current)
        for d in moves:
            plan, info, ol = best_open_loop(motor, V_BUS, current, d, pullout=curve)
            trap, caps, tc = best_trapezoid(motor, V_BUS, current, d)
            print(f"{name:<20}{d:>6g}{1e3 * plan.tf:>10.2f}{1e3 * trap.tf:>10.2f}{plan.tf / trap.tf:>7.3f}"
                  f"{f'{ol.lost}/{tc.lost}':>6}{f'{1e3 * ol.worst_error:.1f}/{1e3 * tc.worst_error:.1f}':>13}"
                  f"{info['margin']:>7.3f}{info['w_peak']:>8.1f}{caps['v_max']:>8.1f},{caps['a_max']:>8.0f}",
                  flush=True)


if __name__ == "__main__":
    main()
