"""Cost and accuracy of the output points between steps (``driver.Driver.refine``).

    .venv/bin/python benchmarks/refine_cost.py                 # plants/*.toml, 1200 s
    .venv/bin/python benchmarks/refine_cost.py plants/drum_boiler.toml --t-end 3600

Each plant is run as ``dnasim run`` runs it (``run_plant``, t_end cut to ``--t-end``
seconds after t_start as in bit_identity_csv.py) in five ways:

- ``off``: no refinement (the interpolated points; ``refine_output`` off);
- ``prev``: the refinement as first committed (the convergence test on all unknowns,
  the algebraic y and the differential y' together, from the interpolated point:
  ``refine.ALGEBRAIC_TEST = WARM_START = SPLICE = False``, ``RATE_TRUSTED = inf``);
- ``rate``: ``prev`` with the rate test trusted only below ``refine.RATE_TRUSTED``;
- ``new``: the current defaults (``refine.ALGEBRAIC_TEST``: the test on the algebraic y
  alone where the matrix is block triangular; ``refine.WARM_START``, ``refine.SPLICE``);
- ``ref``: the reference, refinement at maximum effort: every output point between
  steps solved (no skip), a fresh Jacobian at every point, converged to 1e-3 of the
  tolerance in up to 12 iterations.

Printed per plant and way: residual evaluations, Jacobians (the solver's counter,
``jac_evals``, does not count the refiner's: its Jacobians are counted here as
``ref.Jacs``; ``splice``: the kept matrices given the integrator's algebraic columns
instead), CPU seconds (``time.process_time``, the run with its start; the machine
is shared, repeat for ratios), the output points between steps solved, and the largest
deviation of any output point's algebraic variables from the reference in units of
their tolerance, max_i |y_i - y_ref,i| / (rtol |y_ref,i| + atol_i) (``dev alg``; the
differential ones are the same polynomial in all five ways where the steps do not
depend on the output: not quite on drum_unit.toml and evaporator.toml, see
benchmarks/README.md), and of its y' in units of (rtol |y_ref| + atol) / h (``dev y'``, h the
step), over the points at the times both runs have (``points``: compared / all).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
WAYS = ("off", "prev", "rate", "new", "ref")


@contextlib.contextmanager
def _patched(obj, name, value):
    old = getattr(obj, name)
    setattr(obj, name, value)
    try:
        yield
    finally:
        setattr(obj, name, old)


def run_way(path: Path, t_end_cut: float, way: str) -> dict:
    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant
    from dnasim.solver import driver, output, refine

    loaded = load(path)
    sim = loaded.simulation
    if sim.t_end - sim.t_start > t_end_cut:
        sim.t_end = sim.t_start + t_end_cut
    points, info = [], {"refiner_jacs": 0}
    emit, init = output.Output._emit, driver.Driver.__init__
    call, newton = refine.AlgebraicRefiner.__call__, refine.AlgebraicRefiner._newton

    def record(self, t, y, yp):
        points.append((t, np.array(y, dtype=float), np.array(yp, dtype=float)))
        emit(self, t, y, yp)

    def grab(self, problem, *args, **kw):
        init(self, problem, *args, **kw)
        info["rtol"], info["atol"] = self.opt["rtol"], problem.atol
        info["driver"] = self
        if way == "off":
            self.out.refine = None

    def counted(self, t, y, yp, h, fresh):
        info["refiner_jacs"] += bool(fresh)
        return newton(self, t, y, yp, h, fresh)

    def fresh_always(self, *args, **kw):
        self.kept = False
        return call(self, *args, **kw)

    with contextlib.ExitStack() as stack:
        stack.enter_context(_patched(output.Output, "_emit", record))
        stack.enter_context(_patched(driver.Driver, "__init__", grab))
        stack.enter_context(_patched(refine.AlgebraicRefiner, "_newton", counted))
        if way in ("prev", "rate"):
            stack.enter_context(_patched(refine, "ALGEBRAIC_TEST", False))
            stack.enter_context(_patched(refine, "WARM_START", False))
            stack.enter_context(_patched(refine, "SPLICE", False))
        if way == "prev":
            stack.enter_context(_patched(refine, "RATE_TRUSTED", np.inf))
        if way == "ref":
            stack.enter_context(_patched(driver, "REFINE_SKIP_BELOW", -np.inf))
            stack.enter_context(_patched(refine, "CONVERGED", 1e-3 * refine.CONVERGED))
            stack.enter_context(_patched(refine, "MAX_ITERS", 12))
            stack.enter_context(_patched(refine.AlgebraicRefiner, "__call__", fresh_always))
        with tempfile.TemporaryDirectory() as tmp:
            cpu = time.process_time()
            outcome = run_plant(loaded, tmp)
            cpu = time.process_time() - cpu
    stats = outcome.stats or {}
    d = info["driver"]
    return {
        "points": points,
        "rtol": info["rtol"],
        "atol": np.broadcast_to(info["atol"], points[0][1].shape),
        "algebraic": np.asarray(d.algebraic, dtype=bool),
        "h": [h for (_, h, _) in d.out.history],
        "t_steps": np.array([t for (t, _, _) in d.out.history]),
        "steps": int(stats.get("steps", -1)),
        "residual_evals": int(stats.get("residual_evals", -1)),
        "jac_evals": int(stats.get("jac_evals", -1)),
        "refiner_jacs": info["refiner_jacs"],
        "solves": int(stats.get("output_solves", 0)),
        "splices": 0 if d._refiner is None else d._refiner.stats_spliced,
        "cpu": cpu,
        "status": outcome.status,
        "driver": d,
    }


def deviation(r: dict, ref: dict) -> tuple[float, float, int]:
    """(dev alg, dev y', points compared): the largest deviations from the reference
    (module doc) over the output points at the times both runs have (the k-th point at
    a time with the k-th of the reference there: both sides of a restart)."""
    a = r["algebraic"]
    t_steps, hs = ref["t_steps"], np.array(ref["h"])
    at = {}
    for t, y, yp in ref["points"]:
        at.setdefault(t, []).append((y, yp))
    seen: dict = {}
    worst_y = worst_p = 0.0
    compared = 0
    for t, y, yp in r["points"]:
        k = seen.get(t, 0)
        seen[t] = k + 1
        if k >= len(at.get(t, ())):
            continue
        y_r, yp_r = at[t][k]
        compared += 1
        tol = r["rtol"] * np.abs(y_r) + r["atol"]
        i = min(np.searchsorted(t_steps, t), len(hs) - 1)
        worst_y = max(worst_y, float(np.max(np.abs(y - y_r)[a] / tol[a], initial=0.0)))
        worst_p = max(worst_p, float(np.max(np.abs(yp - yp_r)[~a] * hs[i] / tol[~a], initial=0.0)))
    return worst_y, worst_p, compared


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("plants", nargs="*", help="plant files (default: plants/*.toml)")
    ap.add_argument("--t-end", type=float, default=1200.0, help="longest span [s] (default 1200)")
    args = ap.parse_args(argv)
    paths = [Path(p) for p in args.plants] or sorted((ROOT / "plants").glob("*.toml"))
    print(
        f"{'plant':<30} {'way':<4} {'steps':>6} {'res.evals':>9} {'Jacs':>5} {'ref.Jacs':>8} "
        f"{'solves':>6} {'splice':>6} {'CPU s':>6} {'dev alg':>9} {'dev yp':>9} {'points':>11}"
    )
    for p in paths:
        runs = {w: run_way(p, args.t_end, w) for w in WAYS}
        for w in WAYS:
            r = runs[w]
            dy, dp, n_cmp = deviation(r, runs["ref"])
            compared = f"{n_cmp}/{len(r['points'])}"
            print(
                f"{p.name:<30} {w:<4} {r['steps']:>6} {r['residual_evals']:>9} "
                f"{r['jac_evals']:>5} {r['refiner_jacs']:>8} {r['solves']:>6} "
                f"{r['splices']:>6} {r['cpu']:>6.2f} "
                f"{dy:>9.3g} {dp:>9.3g} {compared:>11}"
            )
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
