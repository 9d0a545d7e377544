"""The field-test table (issue 7): every plant in tests/field/, run through the CLI.

    .venv/bin/python benchmarks/field_tests.py                  # all plants, then 5 runs
    .venv/bin/python benchmarks/field_tests.py boiling_10bar    # some plants
    .venv/bin/python benchmarks/field_tests.py --repeat 0       # no repeated runs

Printed per plant: finished (exit 0 and t_end reached, or an accepted located stop),
the largest mass and energy balance errors over the run relative to the throughput
(or the stored amount, whichever is larger; see tests/field_checks.py), checks
passed / checks, accepted steps (rows of steps.csv) and the wall time of the process.
Then the 1000-volume pipe with a step, run as --repeat fresh processes: its step
counts (they must not be bimodal). Failed checks are listed under the table.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import field_checks as fc  # noqa: E402


def _fmt(x: float) -> str:
    return "-" if x != x else f"{x:.1e}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plants", nargs="*", help="plant names (default: all)")
    ap.add_argument("--repeat", type=int, default=5, help="runs of long_pipe_step")
    args = ap.parse_args(argv)
    names = args.plants or [c.name for c in fc.CASES]
    rows, failures = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            case = fc.CASE[name]
            run = fc.run_plant(name, Path(tmp) / name)
            checks = fc.evaluate(case, run)
            if run.df is not None and run.plant is not None and len(run.df) > 1:
                bal = fc.balances(run)
                m_err, e_err = bal.mass_err, bal.energy_err
            else:
                m_err = e_err = float("nan")
            ok = sum(1 for _, passed, _ in checks if passed)
            fin = "yes" if run.finished else ("stop*" if checks and checks[0][1] else "no")
            rows.append(
                (
                    name,
                    fin,
                    _fmt(m_err),
                    _fmt(e_err),
                    f"{ok}/{len(checks)}",
                    run.steps,
                    f"{run.wall:.1f}",
                )
            )
            failures += [(name, n, d) for n, passed, d in checks if not passed]
            print(f"  ... {name}: {fin}, {ok}/{len(checks)}", file=sys.stderr, flush=True)
        head = ("plant", "finished", "mass bal.", "energy bal.", "checks", "steps", "wall [s]")
        w = [max(len(str(r[i])) for r in rows + [head]) for i in range(len(head))]
        line = "  ".join(f"{{:<{w[0]}}}" if i == 0 else f"{{:>{w[i]}}}" for i in range(len(w)))
        print(line.format(*head))
        for r in rows:
            print(line.format(*r))
        if any(r[1] == "stop*" for r in rows):
            print("stop*: stopped with an accepted, located message naming the cause")
        if failures:
            print("\nfailed checks:")
            for name, n, d in failures:
                print(f"  {name}: {n}: {d[:900]}")
        if args.repeat > 0:
            steps = []
            for i in range(args.repeat):
                run = fc.run_plant("long_pipe_step", Path(tmp) / f"repeat{i}")
                steps.append(run.steps if run.finished else f"{run.steps} (failed)")
            print(f"\nlong_pipe_step, {args.repeat} fresh processes, steps: {steps}")


if __name__ == "__main__":
    main()
