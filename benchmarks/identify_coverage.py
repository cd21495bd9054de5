"""Coverage of identify's intervals on a grid of ordinary recordings (docs/identification.md, "Which recordings").

Run ``.venv/bin/python benchmarks/identify_coverage.py [--cases 240] [--workers 2] [--json rows.json]``: each case
is one move recorded for 1 s on the C engine and identified as a user would (no --detent, no --coulomb);
flatstep.studies.identify_coverage draws the cases from fixed seeds.
"""
import argparse
import json
import time
from concurrent.futures import ProcessPoolExecutor

from flatstep.studies.identify_coverage import cases, coverage_table, run_case

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--cases", type=int, default=240, help="recordings in the grid (default 240)")
parser.add_argument("--seed", type=int, default=0, help="the grid's seed (default 0)")
parser.add_argument("--workers", type=int, default=2, help="processes (default 2)")
parser.add_argument("--json", default=None, help="write every row here")
args = parser.parse_args()

start = time.perf_counter()
with ProcessPoolExecutor(args.workers) as pool:
    rows = list(pool.map(run_case, cases(args.cases, args.seed), chunksize=4))
print(coverage_table(rows))
print(f"{time.perf_counter() - start:.0f} s on {args.workers} processes")
if args.json:
    with open(args.json, "w") as fh:
        json.dump(rows, fh, indent=1)
