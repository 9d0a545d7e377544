"""The cost of one residual evaluation on small plants, in process (issue 10, comp10).

    .venv/bin/python benchmarks/residual_cost.py                       # the four plants
    .venv/bin/python benchmarks/residual_cost.py plants/attemperator.toml --repeat 5
    .venv/bin/python benchmarks/residual_cost.py --components          # per component too
    .venv/bin/python benchmarks/residual_cost.py --base e1ccd3d        # against a revision

For each plant: one run is recorded (every call of ``System.residual`` and of the
finite-difference Jacobian's ``System.residual_for_columns`` functions, with their
arguments, in order), then replayed ``--repeat`` times; the best replay gives

* us per whole-plant residual (``residual``) and per column-group residual (the FD
  Jacobian's partial evaluations), CPU time (``time.process_time`` around each call);
* with ``--components``: us per component and evaluation (each component's share of a
  whole-plant residual, from a replay of those calls alone, timed per evaluation unit:
  a component, or a batch of pipes) and the node equations;
* the whole run in process (load, compile, simulate; no output files), best CPU seconds
  of ``--repeat`` runs, with its counts (steps, residual evaluations, Jacobians).

``--base REV`` runs the same in alternating processes of git revision REV (extracted
with ``git archive`` into a temporary directory and put first on PYTHONPATH) and of
this checkout, ``--repeat`` rounds of one replay and one run each, and prints both rows
and the ratios REV / this, best of the rounds.

The replay runs the recorded calls in their order, so the property memos
(``physics.PropertyArrays``, the IF97 kernel's ``PhMemo``) see the same sequence of
points as in the run. The machine is shared (2 cores): CPU time, best of the repeats.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
PLANTS = (
    "plants/attemperator.toml",
    "plants/superheater_line.toml",
    "plants/air_pipe.toml",
    "tests/field/steam_network_step.toml",
)


def _run(path):
    """(system, results, CPU s) of one in-process run: load, compile, simulate."""
    import dnasim
    from dnasim.run.simulation import simulate, simulation_keywords

    t0 = time.process_time()
    plant = dnasim.load_plant(str(ROOT / path))
    system = plant.compile()
    t_end, kw = simulation_keywords(plant.simulation)
    res = simulate(system, t_end=t_end, **kw)
    return system, res, time.process_time() - t0


def record(path):
    """(system, calls) of one run: calls[k] = ("full", t, y, yp) or ("cols", cols, t, y,
    yp, f0), in the order the solver made them."""
    from dnasim.compilation.system import System

    calls = []
    full, for_cols = System.residual, System.residual_for_columns

    def residual(self, t, y, yp):
        calls.append(("full", t, np.array(y), np.array(yp)))
        return full(self, t, y, yp)

    def residual_for_columns(self, cols):
        f = for_cols(self, cols)
        cols = np.array(cols)

        def f_cols(t, y, yp, f0):
            calls.append(("cols", cols, t, np.array(y), np.array(yp), np.array(f0)))
            return f(t, y, yp, f0)

        return f_cols

    System.residual, System.residual_for_columns = residual, residual_for_columns
    try:
        system, _, _ = _run(path)
    finally:
        System.residual, System.residual_for_columns = full, for_cols
    return system, calls


def replay(system, calls):
    """CPU seconds (whole-plant calls, their number, column calls, their number)."""
    from dnasim.core.errors import ResidualDomainError

    clock = time.process_time
    funcs = {}
    t_full = t_cols = 0.0
    n_full = n_cols = 0
    system.reset_modes()
    for c in calls:
        if c[0] == "full":
            _, t, y, yp = c
            a = clock()
            try:  # a Newton iterate out of range: the solver cuts the step
                system.residual(t, y, yp)
            except ResidualDomainError:
                pass
            t_full += clock() - a
            n_full += 1
        else:
            _, cols, t, y, yp, f0 = c
            key = cols.tobytes()
            f = funcs.get(key)
            if f is None:
                f = funcs[key] = system.residual_for_columns(cols)
            a = clock()
            try:
                f(t, y, yp, f0)
            except ResidualDomainError:
                pass
            t_cols += clock() - a
            n_cols += 1
    return t_full, n_full, t_cols, n_cols


def component_times(system, calls):
    """{unit: CPU s} over the whole-plant calls: each evaluation unit alone (a
    component, or a batch of pipes joined with "+"; ``System.residual_units`` where the
    System has them, else its blocks), and "nodes" (the node equations)."""
    from dnasim.core.errors import ResidualDomainError

    clock = time.process_time
    units = getattr(system, "residual_units", system.blocks)
    names = [u.comp.name if hasattr(u, "comp") else "+".join(u.names) for u in units]
    out = dict.fromkeys(names + ["nodes"], 0.0)
    F = np.empty(system.n_equations)
    system.reset_modes()
    for c in calls:
        if c[0] != "full":
            continue
        _, t, y, yp = c
        for name, u in zip(names, units, strict=True):
            a = clock()
            try:
                system._component_rows(t, y, yp, F, [u])
            except ResidualDomainError:
                pass
            out[name] += clock() - a
        a = clock()
        system._node_rows(y, F)
        out["nodes"] += clock() - a
    return out


def measure(path, repeat, components=False):
    """The row of one plant (see ``HEADER``): best replay and best run of ``repeat``."""
    system, calls = record(path)
    best = None
    for _ in range(repeat):
        r = replay(system, calls)
        if best is None or r[0] + r[2] < best[0] + best[2]:
            best = r
    t_full, n_full, t_cols, n_cols = best
    runs = [_run(path) for _ in range(repeat)]
    st = runs[0][1].stats
    if components:
        ct = component_times(system, calls)
        print(f"{path}: us per component and whole-plant evaluation ({n_full} calls)")
        for name, dt in sorted(ct.items(), key=lambda kv: -kv[1]):
            print(f"    {name:<28} {1e6 * dt / n_full:8.1f}")
    return [
        Path(path).stem,
        system.n,
        1e6 * t_full / max(n_full, 1),
        n_full,
        1e6 * t_cols / max(n_cols, 1),
        n_cols,
        min(r[2] for r in runs),
        st.get("steps"),
        st.get("residual_evals"),
        st.get("jac_evals"),
    ]


HEADER = (
    f"{'plant':<20} {'n':>4} {'us/residual':>11} {'calls':>6} {'us/column F':>11} "
    f"{'calls':>6} {'run CPU s':>9} {'steps':>6} {'F evals':>7} {'Jacs':>5}"
)


def line(r, label=""):
    return (
        f"{label}{r[0]:<20} {r[1]:>4} {r[2]:>11.1f} {r[3]:>6} {r[4]:>11.1f} {r[5]:>6} "
        f"{r[6]:>9.3f} {r[7]:>6} {r[8]:>7} {r[9]:>5}"
    )


def against(rev, plants, repeat):
    """Rows of git revision ``rev`` and of this checkout, measured in alternating
    processes (``repeat`` rounds of one replay and one run each), best of the rounds."""
    import json
    import os
    import subprocess
    import sys
    import tempfile

    src = Path(tempfile.mkdtemp()) / rev
    src.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], capture_output=True)
    subprocess.run(["tar", "-x", "-C", str(src)], input=archive.stdout, check=True)
    best = {}
    for _ in range(repeat):
        for label, where in ((rev, src), ("this", ROOT)):
            env = dict(os.environ, PYTHONPATH=str(where))
            cmd = [sys.executable, __file__, *plants, "--repeat", "1", "--json"]
            out = subprocess.run(cmd, env=env, cwd=where, capture_output=True, text=True)
            for r in json.loads(out.stdout.splitlines()[-1]):
                old = best.get((label, r[0]))
                if old is not None:  # best replay and best run, each on its own
                    r[2], r[4], r[6] = min(r[2], old[2]), min(r[4], old[4]), min(r[6], old[6])
                best[(label, r[0])] = r
    print(" " * 8 + HEADER)
    for path in plants:
        name = Path(path).stem
        a, b = best[(rev, name)], best[("this", name)]
        print(line(a, f"{rev[:7]:<8}"))
        print(line(b, f"{'this':<8}"))
        print(
            f"{'ratio':<8}{'':<25} {a[2] / b[2]:>11.2f} {'':>6} {a[4] / b[4]:>11.2f} {'':>6} "
            f"{a[6] / b[6]:>9.2f}"
        )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("plants", nargs="*", default=PLANTS)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--components", action="store_true")
    ap.add_argument("--base", metavar="REV", help="also git revision REV, alternating")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.base:
        against(args.base, args.plants, args.repeat)
        return
    rows = [measure(path, args.repeat, args.components) for path in args.plants]
    if args.json:
        import json

        print(json.dumps(rows))
        return
    print(HEADER)
    for r in rows:
        print(line(r))


if __name__ == "__main__":
    main()
