"""Open-loop plans with a speed-dependent acceleration against the best safe constant-acceleration trapezoid.

For each motor and move (docs/curves.md): the fastest trapezoid that loses no step (studies.open_loop.best_trapezoid:
8 speed caps, 7 bisection steps of the acceleration on the weakest plant each, the candidates confirmed on all 32
plants, then a faster cruise and more acceleration sought by bisection), then the fastest speed-dependent profile
found from it (studies.open_loop.best_profile: the cruise speed and piecewise-linear acceleration and braking profiles,
seeded with that trapezoid, screening as many candidates as the trapezoid's search did, each kept one confirmed on all
32 plants). Both run on the open-loop
microstepping drive (20 kHz, 24 V) over the 32 plants of +-10 % on R, L, Km, J, B. Prints both durations, their ratio,
the runs lost, the worst angle error over the 32 plants, the search budget of each (candidates screened / plant runs)
and the cruise speeds.

    .venv/bin/python benchmarks/pullout_open_loop.py [--quick]
"""
from __future__ import annotations

import argparse
from pathlib import Path

from flatstep.model.datasheet import motor_from_table
from flatstep.model.motor import MotorParams
from flatstep.studies.file_values import read_toml
from flatstep.studies.open_loop import best_profile, best_trapezoid

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
    print(f"{'motor':<20}{'move':>6}{'profile':>9}{'trapezoid':>10}{'ratio':>7}{'lost':>6}{'worst err':>12}"
          f"{'screened':>10}{'plant runs':>12}{'cruise':>13}")
    print(f"{'':<20}{'[rad]':>6}{'[ms]':>9}{'[ms]':>10}{'pr/tr':>7}{'pr/tr':>6}{'pr/tr[mrad]':>12}"
          f"{'pr/tr':>10}{'pr/tr':>12}{'pr/tr[rad/s]':>13}")
    for name, (motor, current) in chosen.items():
        for d in moves:
            trap = best_trapezoid(motor, V_BUS, current, d)
            plan, info, pc = best_profile(motor, V_BUS, current, d, trap, budget=int(trap[1]["candidates"]))
            tp, caps, tc = trap
            budget = f"{info['candidates']}/{caps['candidates']:.0f}"
            runs = f"{info['runs']}/{caps['runs']:.0f}"
            cruise = f"{info['cruise']:.1f}/{caps['v_max']:.1f}"
            print(f"{name:<20}{d:>6g}{1e3 * plan.tf:>9.2f}{1e3 * tp.tf:>10.2f}{plan.tf / tp.tf:>7.3f}"
                  f"{f'{pc.lost}/{tc.lost}':>6}{f'{1e3 * pc.worst_error:.1f}/{1e3 * tc.worst_error:.1f}':>12}"
                  f"{budget:>10}{runs:>12}{cruise:>13}", flush=True)
            print(f"{'':<26}profile: accel {', '.join(f'{x:.0f}' for x in info['accel'])}, brake "
                  f"{', '.join(f'{x:.0f}' for x in info['brake'])} rad/s^2 at "
                  f"{', '.join(f'{x:.1f}' for x in info['knots'])} rad/s; trapezoid a_max {caps['a_max']:.0f}",
                  flush=True)


if __name__ == "__main__":
    main()
