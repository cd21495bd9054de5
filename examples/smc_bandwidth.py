"""The sliding controller with its bandwidths scaled, as docs/comparison.md scales the baselines'.

Run: python examples/smc_bandwidth.py [SCENARIO.toml ...]
lambda = W/eps and omega_n (and the observer's bandwidth) multiplied by each factor, W kept: the worst
over the 32 plant corners of the file, max |theta - theta*| during the move in encoder counts and the
peak phase voltage.
"""
import sys
from dataclasses import replace
from pathlib import Path

from flatstep.control.smc import SMCGains
from flatstep.studies.compare import compare_worst
from flatstep.studies.robustness import encoder_count
from flatstep.studies.scenario_file import Robustness, load_scenario

here = Path(__file__).parent
files = sys.argv[1:] or [here / "compare-paper-20khz.toml", here / "compare-nema17-fast.toml"]
for path in files:
    scenario, study = load_scenario(path)
    study = study or Robustness()
    count, loop = encoder_count(scenario), scenario.loop
    g = scenario.gains
    for scale in (0.5, 1.0, 2.0):
        gains = SMCGains(W1=g.W1, W2=g.W2, eps1=g.eps1 / scale, eps2=g.eps2 / scale, xi=g.xi, wn=g.wn * scale)
        observer = replace(loop.observer, bandwidth=loop.observer.bandwidth * scale)
        scaled = replace(scenario, gains=gains, loop=replace(loop, observer=observer))
        worst = compare_worst(scaled, study, ["smc"])["smc"]["worst"]
        print(f"{Path(path).stem:<22} x{scale:<4g} lambda Ts = {0.3 * scale:.2f}: max error during the move "
              f"{worst['move_max'] / count:7.3f} counts, peak {worst['peak_voltage']:.3g} V")
