"""The corrector's Newton convergence test (issue 23 item 3): dnasim alone on the Test
Set problems of ``solver_vs_peers.py`` and on the plants, with the Newton tolerance
given (``--tol``: fractions of the error test, ``newton.NEWTON_TOL``), each against
the default 0.03.

    .venv/bin/python benchmarks/newton_tolerance.py --tol 0.1 [--rtols 1e-4 1e-6 1e-8]
    .venv/bin/python benchmarks/newton_tolerance.py --tol 0.1 --plants

Printed per problem and rtol: correct digits at the end point (as solver_vs_peers),
steps, Newton iterations per step, residual evaluations, CPU s (best of --repeat); per
plant (``--plants``: plants/*.toml run as ``dnasim run`` runs them): steps, Newton
iterations per step, residual evaluations, CPU s, and the error: the largest
difference of the results.csv rows from those of a run at rtol = atol_scaled = 1e-8,
on the output times both hold, in units of each column's tolerance at rtol 1e-6
(1e-6 |x| + 1e-6 max |column|). The default (0.03) is always the first row.
"""

from __future__ import annotations

import argparse
import csv
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from solver_vs_peers import consistent_start, digits, problems, reference  # noqa: E402

from dnasim import solve_dae  # noqa: E402
from dnasim.solver import newton  # noqa: E402

DEFAULT = newton.NEWTON_TOL


def set_tol(tol) -> None:
    """The corrector's Newton tolerance (``newton.NEWTON_TOL``, read at every test)."""
    newton.NEWTON_TOL = float(tol)


def test_set(tols, rtols, repeat):
    from problems import as_residual as as_res

    print(
        f"{'problem':<22} {'rtol':>6} {'tol':>5} {'digits':>6} {'steps':>6} "
        f"{'Newton/step':>11} {'res.evals':>9} {'CPU s':>7}"
    )
    for p in problems():
        y0, yp0 = consistent_start(p)
        ref = reference(p, y0, yp0)
        residual = p.get("residual") or as_res(p["rhs"])
        for rtol in rtols:
            atol = rtol * p["atol_scale"]
            for tol in [DEFAULT, *tols]:
                set_tol(tol)
                best = np.inf
                for _ in range(repeat):
                    c = time.process_time()
                    r = solve_dae(
                        residual,
                        (0, p["t_end"]),
                        y0,
                        yp0,
                        algebraic=p.get("algebraic"),
                        rtol=rtol,
                        atol=atol,
                        calc_initial=False,
                        dense_output=False,
                        t_eval=[p["t_end"]],
                    )
                    best = min(best, time.process_time() - c)
                s = r.stats
                d = digits(r.y[:, -1], ref, atol) if r.success else float("nan")
                print(
                    f"{p['name']:<22} {rtol:>6.0e} {str(tol):>5} {d:>6.2f} {s['steps']:>6} "
                    f"{s['newton_iters'] / max(s['steps'], 1):>11.2f} "
                    f"{s['residual_evals']:>9} {best:>7.3f}"
                )
                sys.stdout.flush()
    set_tol(DEFAULT)


def _csv(path):
    with open(path) as f:
        rows = [r for r in csv.reader(f)]
    return np.array([[float(v) for v in r] for r in rows[1:] if r and not r[0].startswith("#")])


def _run(path, rtol=None):
    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant

    loaded = load(path)
    if rtol is not None:
        loaded.simulation.rtol = rtol
        loaded.simulation.atol_scaled = rtol
    with tempfile.TemporaryDirectory() as tmp:
        c = time.process_time()
        out = run_plant(loaded, tmp)
        c = time.process_time() - c
        rows = _csv(Path(tmp) / "results.csv")
    return out, rows, c


def _error(rows, ref):
    """Largest |x - x_ref| over the grid rows both runs hold (the last row at a time),
    in units of the column's tolerance 1e-6 |x_ref| + 1e-6 max |column|."""

    def last_at(r):
        t = r[:, 0]
        keep = np.append(t[1:] != t[:-1], True)
        return r[keep]

    rows, ref = last_at(rows), last_at(ref)
    common, i, j = np.intersect1d(rows[:, 0], ref[:, 0], return_indices=True)
    a, b = rows[i, 1:], ref[j, 1:]
    scale = 1e-6 * np.abs(b) + 1e-6 * np.max(np.abs(ref[:, 1:]), axis=0)
    return float(np.max(np.abs(a - b) / np.where(scale > 0, scale, 1.0)))


def plants(tols):
    print(
        f"{'plant':<30} {'tol':>5} {'steps':>6} {'Newton/step':>11} {'res.evals':>9} "
        f"{'CPU s':>7} {'err/tol':>9}"
    )
    for path in sorted((ROOT / "plants").glob("*.toml")):
        set_tol(DEFAULT)
        _, ref, _ = _run(path, rtol=1e-8)
        for tol in [DEFAULT, *tols]:
            set_tol(tol)
            out, rows, c = _run(path)
            s = out.stats
            print(
                f"{path.name:<30} {str(tol):>5} {s['steps']:>6} "
                f"{s['newton_iters'] / max(s['steps'], 1):>11.2f} {s['residual_evals']:>9} "
                f"{c:>7.2f} {_error(rows, ref):>9.3g}"
            )
            sys.stdout.flush()
    set_tol(DEFAULT)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--tol", nargs="+", default=["0.1"], help="Newton tolerances to compare")
    ap.add_argument("--rtols", type=float, nargs="+", default=[1e-4, 1e-6, 1e-8])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--plants", action="store_true", help="the plants instead of the Test Set")
    args = ap.parse_args(argv)
    if args.plants:
        plants(args.tol)
    else:
        test_set(args.tol, args.rtols, args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
