"""The solver's own cost per step, outside the residual: dnasim (numpy step and compiled
loops) against IDA (scikit-sundae) on small Test Set problems.

For each problem the residual's CPU time per call is measured alone (2000 calls at the
initial point, best of --repeat), then each solver's whole run (CPU time of this
process, best of --repeat); the cost outside the residual per step is

    (CPU of the run - residual evaluations x CPU per residual call) / steps   [us]

Residual evaluations and steps are the solvers' own counts (dnasim's: every call,
finite-difference columns included; IDA's: nre plus its difference-quotient calls as
scikit-sundae reports them). dnasim's two variants make the same decisions to the bit
(tests/test_solver_kernels.py), so their counts are equal.

    python benchmarks/step_overhead.py [--repeat 5]

With PYTHONPATH set to an older source tree of dnasim (``git archive REV | tar -x``)
it measures that version's step (both dnasim columns are then its numpy step).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import solver_vs_peers as svp  # noqa: E402
from problems import as_residual  # noqa: E402

from dnasim import solve_dae  # noqa: E402
from dnasim.solver import bdf  # noqa: E402
from dnasim.solver import nordsieck as nd  # noqa: E402
from dnasim.testing.ida import solve_with_ida  # noqa: E402

CASES = [("Robertson", 1e-6), ("Akzo Nobel", 1e-6), ("HIRES", 1e-6), ("Transistor amp", 1e-4)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    import numba  # noqa: F401  (loaded first: the compiled variant runs from its first step)

    bdf.KERNELS_AFTER_STEPS_LOADED = 0

    problems = {p["name"]: p for p in svp.problems()}
    head = (
        f"{'problem':<16} {'rtol':>6} {'steps':>6} {'F evals':>8} {'F [us]':>7} | "
        f"{'numpy step':>10} {'compiled':>9} {'IDA':>6}   (us/step outside the residual)"
    )
    print(head)
    print("-" * len(head))
    for name, rtol in CASES:
        p = problems[name]
        residual = p.get("residual") or as_residual(p["rhs"])
        y0, yp0 = svp.consistent_start(p)
        yp_probe = np.zeros_like(y0) if yp0 is None else yp0
        atol = rtol * p["atol_scale"]
        per_call, _ = svp.best_of(
            args.repeat, lambda: [residual(0.0, y0, yp_probe) for _ in range(2000)]
        )
        per_call /= 2000

        # the same problem and options for dnasim and IDA
        problem = (residual, (0, p["t_end"]), y0, yp0)
        options = dict(algebraic=p.get("algebraic"), rtol=rtol, atol=atol)

        def ours(compiled):
            bdf.KERNELS = compiled
            if not compiled and hasattr(bdf, "_compiled_wrms"):  # the hooks back to numpy
                bdf._compiled_wrms[0] = None
                nd.compiled_rescale = None
            return solve_dae(
                *problem, calc_initial=False, dense_output=False, throw=True, **options
            )

        cols = []
        for compiled in (False, True):
            cpu, r = svp.best_of(args.repeat, lambda compiled=compiled: ours(compiled))
            s = r.stats
            cols.append((cpu - s["residual_evals"] * per_call) / s["steps"])
        bdf.KERNELS = True
        cpu, run = svp.best_of(args.repeat, lambda: solve_with_ida(*problem, **options))
        si = run.stats
        ida = (cpu - si["residual_evals"] * per_call) / si["steps"]
        print(
            f"{name:<16} {rtol:>6.0e} {s['steps']:>6} {s['residual_evals']:>8} "
            f"{1e6 * per_call:>7.2f} | {1e6 * cols[0]:>10.1f} {1e6 * cols[1]:>9.1f} "
            f"{1e6 * ida:>6.1f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
