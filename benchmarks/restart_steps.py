"""Step counts with the restart step from the solution against IDA's rule, on plants with
time events (issue 10).

    .venv/bin/python benchmarks/restart_steps.py

After a tstop or a located switch the integration restarts at order 1. IDA's rule
for that first step, 0.5 / ||y'|| in the error weights, knows nothing of the step
sizes before the restart; ``NordsieckBDF.restart_step`` takes the order-1 step the
polynomial before the restart allows. Each plant is run twice in this process
(``dnasim.solver.bdf.RESTART_FROM_SOLUTION`` False, then True) through
``dnasim.run.runner.run_plant`` as ``dnasim run`` does; printed: accepted steps,
rejected steps (error test / Newton), residual evaluations, CPU seconds, and the
change of the last output row against the first run (max over columns of
|difference| / (|value| + 1e-3 max |column|)).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from dnasim.plant.plantfile import load
from dnasim.run.runner import run_plant
from dnasim.solver import bdf

ROOT = Path(__file__).resolve().parent.parent
PLANTS = [
    "plants/attemperator.toml",
    "tests/field/steam_network_step.toml",
    "tests/field/hx_inlet_step.toml",
    "tests/field/valve_close_fast.toml",
]


def run(path: Path, from_solution: bool, out: Path) -> dict:
    bdf.RESTART_FROM_SOLUTION = from_solution
    t0 = time.process_time()
    outcome = run_plant(load(path), out)
    cpu = time.process_time() - t0
    s = outcome.stats
    df = pd.read_csv(out / "results.csv").select_dtypes("number")
    last = df.iloc[-1].to_numpy(dtype=float)
    scale = df.abs().max().to_numpy(dtype=float)
    return dict(
        ok=outcome.success,
        steps=s.get("steps", outcome.n_steps),
        rej=f"{s.get('rejected_error', 0)}/{s.get('rejected_newton', 0)}",
        fevals=s.get("residual_evals", 0),
        cpu=cpu,
        last=last,
        scale=scale,
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plants", nargs="*", default=PLANTS)
    args = ap.parse_args(argv)
    default = bdf.RESTART_FROM_SOLUTION
    head = (
        f"{'plant':<22} {'restart h':<13} {'steps':>6} {'rej e/N':>8} {'F evals':>8} "
        f"{'CPU s':>7} {'last row change':>16}"
    )
    print(head)
    print("-" * len(head))
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.plants:
            path = ROOT / name
            rows = {}
            for mode in (False, True):
                rows[mode] = run(path, mode, Path(tmp) / f"{path.stem}_{mode}")
            ref = rows[False]
            for mode, label in ((False, "IDA 0.5/|y'|"), (True, "from solution")):
                r = rows[mode]
                change = np.nanmax(
                    np.abs(r["last"] - ref["last"]) / (np.abs(ref["last"]) + 1e-3 * ref["scale"])
                )
                print(
                    f"{path.stem:<22} {label:<13} {r['steps']:>6} {r['rej']:>8} {r['fevals']:>8} "
                    f"{r['cpu']:>7.2f} {change:>16.1e}" + ("" if r["ok"] else "  FAILED")
                )
    bdf.RESTART_FROM_SOLUTION = default
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
