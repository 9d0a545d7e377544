"""Cost and accuracy of the output points between steps (``driver.Driver.refine``).

    .venv/bin/python benchmarks/refine_cost.py                 # plants/*.toml, 1200 s
    .venv/bin/python benchmarks/refine_cost.py plants/drum_boiler.toml --t-end 3600

Each plant is run as ``dnasim run`` runs it (``run_plant``, t_end cut to ``--t-end``
seconds after t_start as in bit_identity_csv.py), with the re-solve on whatever the
plant file says, in these ways (``--ways``; default off, solve, choose0, choose, ref):

- ``off``: no refinement (the interpolated points; ``refine_output`` off);
- ``prev``: the refinement as first committed (the convergence test on all unknowns,
  the algebraic y and the differential y' together, from the interpolated point:
  ``refine.ALGEBRAIC_TEST = WARM_START = SPLICE = False``, ``RATE_TRUSTED = inf``,
  no choice);
- ``rate``: ``prev`` with the rate test trusted only below ``refine.RATE_TRUSTED``;
- ``solve``: the current re-solve (``refine.ALGEBRAIC_TEST``: the test on the
  algebraic y alone where the matrix is block triangular; ``refine.WARM_START``,
  ``refine.SPLICE``), every solved value taken (``driver.CHOOSE = False``);
- ``choose0``: ``solve``, then per variable the solved or the interpolated value by
  their estimated errors (``driver.CHOOSE``, ``Driver._choose``), every point solved
  first (``driver.PRESKIP = False``: the choice as first committed);
- ``choose``: the current defaults: ``choose0`` with the decision before the solve
  (``driver.PRESKIP``): a point is not solved where no value can gain from it (the
  solve's first Newton iteration moves none by more than ``driver.PRESKIP_WITHIN`` of
  its tolerance, ``Driver._over``, or the choice would keep those interpolated,
  ``Driver._gains``);
- ``ref``: the re-solve at maximum effort: every output point between steps solved
  (no skip), a fresh Jacobian at every point, converged to 1e-3 of the tolerance in
  up to 12 iterations, every solved value taken.

and once more as the TRUE reference (``true``, unless ``--no-true``): refinement off and
max_step = output_interval / ``--true-divisor`` (default 8), so that a point between
steps is within an eighth of the interval of one and the interpolation error there is
(1/8)^(q+1) of the plant's; it has its own steps, so its deviation from the others
includes the integration's own error: ``at steps`` below is that floor.

Printed per plant and way: residual evaluations, Jacobians (the solver's counter,
``jac_evals``, does not count the refiner's: its Jacobians are counted here as
``ref.Jacs``, those of its Newton and of ``propagate``; ``splice``: the kept matrices
given the integrator's algebraic columns instead), CPU seconds (``time.process_time``,
the run with its start; the machine is shared, repeat for ratios), the output points
between steps solved, ``interp``: the values the choice kept interpolated (algebraic y
and differential y'), ``skip``: the points between steps not solved, where the solve
would move no value by more than ``driver.PRESKIP_WITHIN`` of its tolerance (``_over``)
+ where the choice would keep the others interpolated (``_gains``), and the largest
deviations of the output points' algebraic variables in units of their tolerance,
max_i |y_i - y_ref,i| / (rtol |y_ref,i| + atol_i):

- ``dev alg``, ``dev yp``: from ``ref`` (y' of the differential variables in units of
  (rtol |y_ref| + atol) / h, h the step), over the points at the times both runs have
  (``points``: compared / all). The differential ones are the same polynomial in all
  ways where the steps do not depend on the output: not quite on drum_unit.toml and
  evaporator.toml, see benchmarks/README.md;
- ``true btw``: from ``true``, over the points of this way that lie between its steps,
  with the variable (``worst``) and both values (``value``, ``true``);
- ``at steps``: from ``true``, over the points at this way's steps (the same in every
  way: the integration's error, the floor of ``true btw``).
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
WAYS = ("off", "prev", "rate", "solve", "choose0", "choose", "local", "global", "ref")
DEFAULT_WAYS = ("off", "solve", "choose0", "choose", "ref")


@contextlib.contextmanager
def _patched(obj, name, value):
    old = getattr(obj, name)
    setattr(obj, name, value)
    try:
        yield
    finally:
        setattr(obj, name, old)


def run_way(path: Path, t_end_cut: float, way: str, true_divisor: float = 8.0, t_eval=None) -> dict:
    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant
    from dnasim.solver import driver, output, refine

    loaded = load(path)
    sim = loaded.simulation
    if sim.t_end - sim.t_start > t_end_cut:
        sim.t_end = sim.t_start + t_end_cut
    sim.refine_output = way not in ("off", "true")
    if way == "true":  # at the other ways' output times and steps (``t_eval``)
        if not sim.output_interval:
            return None
        sim.max_step = sim.output_interval / true_divisor
        sim.output_interval, sim.t_eval = None, tuple(t_eval)
    points, at_steps, info = [], [], {"refiner_jacs": 0}
    emit, init, take = output.Output._emit, driver.Driver.__init__, output.Output.step
    call, fresh_matrix = refine.AlgebraicRefiner.__call__, refine.AlgebraicRefiner._fresh_matrix

    def record(self, t, y, yp):
        points.append((t, np.array(y, dtype=float), np.array(yp, dtype=float)))
        emit(self, t, y, yp)

    def stepped(self, solver, t_prev, t_until):
        take(self, solver, t_prev, t_until)
        at_steps.append((self.left[0], np.array(self.left[1], dtype=float)))

    def grab(self, problem, *args, **kw):
        init(self, problem, *args, **kw)
        info["rtol"], info["atol"] = self.opt["rtol"], problem.atol
        info["driver"], info["names"] = self, list(problem.names)

    def counted(self, *args, **kw):
        info["refiner_jacs"] += 1
        return fresh_matrix(self, *args, **kw)

    def fresh_always(self, *args, **kw):
        self.kept = False
        return call(self, *args, **kw)

    with contextlib.ExitStack() as stack:
        stack.enter_context(_patched(output.Output, "_emit", record))
        stack.enter_context(_patched(output.Output, "step", stepped))
        stack.enter_context(_patched(driver.Driver, "__init__", grab))
        stack.enter_context(_patched(refine.AlgebraicRefiner, "_fresh_matrix", counted))
        if way not in ("choose", "choose0", "local", "global"):
            stack.enter_context(_patched(driver, "CHOOSE", False))
        if way == "local":  # ``choose`` without the globalised Newton's last resort
            stack.enter_context(_patched(refine, "GLOBALISED", False))
        if way == "global":  # ``choose`` with it
            stack.enter_context(_patched(refine, "GLOBALISED", True))
        if way == "choose0":
            stack.enter_context(_patched(driver, "PRESKIP", False))
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
        "at_steps": at_steps,
        "names": info["names"],
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
        "interpolated": d.stats_chosen[0] + d.stats_chosen[1],
        "skipped": tuple(d.stats_skipped),
        "cpu": cpu,
        "status": outcome.status,
        "driver": d,
    }


def _pairs(r: dict, ref: dict):
    """(t, y, yp, y_ref, yp_ref) at the times both runs have (the k-th point at a time
    with the k-th of the reference there: both sides of a restart)."""
    at = {}
    for t, y, yp in ref["points"]:
        at.setdefault(t, []).append((y, yp))
    seen: dict = {}
    for t, y, yp in r["points"]:
        k = seen.get(t, 0)
        seen[t] = k + 1
        if k < len(at.get(t, ())):
            yield t, y, yp, *at[t][k]


def deviation(r: dict, ref: dict) -> tuple[float, float, int]:
    """(dev alg, dev y', points compared): the largest deviations from the reference
    (module doc) over the output points at the times both runs have."""
    a = r["algebraic"]
    t_steps, hs = ref["t_steps"], np.array(ref["h"])
    worst_y = worst_p = 0.0
    compared = 0
    for t, y, yp, y_r, yp_r in _pairs(r, ref):
        compared += 1
        tol = r["rtol"] * np.abs(y_r) + r["atol"]
        i = min(np.searchsorted(t_steps, t), len(hs) - 1)
        worst_y = max(worst_y, float(np.max(np.abs(y - y_r)[a] / tol[a], initial=0.0)))
        worst_p = max(worst_p, float(np.max(np.abs(yp - yp_r)[~a] * hs[i] / tol[~a], initial=0.0)))
    return worst_y, worst_p, compared


def true_deviation(r: dict, true: dict) -> tuple[float, float, float, str, float, float]:
    """(true btw, at steps, excess, worst, value, true) from the TRUE reference (module
    doc): the largest deviations of an algebraic variable over the points between this
    run's steps and at its steps, the largest excess over the points between its steps
    with the variable and both values there."""
    a = r["algebraic"]
    tol_of = lambda y_r: r["rtol"] * np.abs(y_r) + r["atol"]  # noqa: E731
    true_at = {}
    for t, y, _ in true["points"]:
        true_at.setdefault(t, y)
    # the signed error in tolerance units at each step of this run (its steps' states)
    t_steps = np.array([t for t, _ in r["at_steps"]])
    err_steps = [
        (y - true_at[t]) / tol_of(true_at[t]) if t in true_at else None for t, y in r["at_steps"]
    ]
    steps = set(t_steps.tolist())
    btw = at = excess = 0.0
    where = ("-", np.nan, np.nan)
    for t, y, _, y_r, _ in _pairs(r, true):
        e = np.where(a, (y - y_r) / tol_of(y_r), 0.0)
        dev = float(np.max(np.abs(e)))
        if t in steps:
            at = max(at, dev)
            continue
        btw = max(btw, dev)
        k = int(np.searchsorted(t_steps, t))
        if k == 0 or k >= len(t_steps) or err_steps[k - 1] is None or err_steps[k] is None:
            continue
        theta = (t - t_steps[k - 1]) / (t_steps[k] - t_steps[k - 1])
        smooth = (1.0 - theta) * err_steps[k - 1] + theta * err_steps[k]
        x = np.where(a, np.abs(e - smooth), 0.0)
        i = int(np.argmax(x))
        if x[i] > excess:
            excess, where = float(x[i]), (r["names"][i], float(y[i]), float(y_r[i]))
    return btw, at, excess, *where


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("plants", nargs="*", help="plant files (default: plants/*.toml)")
    ap.add_argument("--t-end", type=float, default=1200.0, help="longest span [s] (default 1200)")
    ap.add_argument("--ways", default=",".join(DEFAULT_WAYS), help=f"of {', '.join(WAYS)}")
    ap.add_argument("--no-true", action="store_true", help="no TRUE reference (module doc)")
    ap.add_argument("--true-divisor", type=float, default=8.0, help="max_step = interval / this")
    args = ap.parse_args(argv)
    ways = [w for w in args.ways.split(",") if w]
    if any(w not in WAYS for w in ways):
        ap.error(f"--ways: of {', '.join(WAYS)}")
    if "ref" not in ways:
        ways.append("ref")
    paths = [Path(p) for p in args.plants] or sorted((ROOT / "plants").glob("*.toml"))
    print(
        f"{'plant':<22} {'way':<7} {'steps':>6} {'res.evals':>9} {'Jacs':>5} {'ref.Jacs':>8} "
        f"{'solves':>6} {'splice':>6} {'interp':>6} {'skip':>9} {'CPU s':>6} "
        f"{'dev alg':>8} {'dev yp':>8} "
        f"{'points':>11} {'true btw':>8} {'at steps':>8} {'excess':>8} {'worst':<18} "
        f"{'value':>10} {'true':>10}"
    )
    for p in paths:
        runs = {w: run_way(p, args.t_end, w) for w in ways}
        times = {t for r in runs.values() for t, _, _ in r["points"]}
        times |= {t for r in runs.values() for t, _ in r["at_steps"]}
        true = None
        if not args.no_true:
            true = run_way(p, args.t_end, "true", args.true_divisor, sorted(times))
        for w in [*ways, *(["true"] if true is not None else [])]:
            r = runs.get(w, true)
            dy, dp, n_cmp = deviation(r, runs["ref"])
            compared = f"{n_cmp}/{len(r['points'])}"
            skip = "{}+{}".format(*r["skipped"])
            line = (
                f"{p.stem[:22]:<22} {w:<7} {r['steps']:>6} {r['residual_evals']:>9} "
                f"{r['jac_evals']:>5} {r['refiner_jacs']:>8} {r['solves']:>6} "
                f"{r['splices']:>6} {r['interpolated']:>6} {skip:>9} {r['cpu']:>6.2f} "
                f"{dy:>8.3g} {dp:>8.3g} {compared:>11}"
            )
            if true is not None and w != "true":
                tb, ts, ex, name, v, v_true = true_deviation(r, true)
                line += (
                    f" {tb:>8.3g} {ts:>8.3g} {ex:>8.3g} {name[:18]:<18} {v:>10.4g} {v_true:>10.4g}"
                )
            print(line)
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
