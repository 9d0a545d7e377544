"""The cost of one residual evaluation on small plants, in process (issue 10, comp10).

    .venv/bin/python benchmarks/residual_cost.py                       # the four plants
    .venv/bin/python benchmarks/residual_cost.py plants/attemperator.toml --repeat 5
    .venv/bin/python benchmarks/residual_cost.py --components          # per component too

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
    from dnasim.simulation import simulate, simulation_keywords

    t0 = time.process_time()
    plant = dnasim.load_plant(str(ROOT / path))
    system = plant.compile()
    kw = simulation_keywords(plant.simulation)
    res = simulate(system, t_end=plant.simulation.t_end, **kw)
    return system, res, time.process_time() - t0


def record(path):
    """(system, calls) of one run: calls[k] = ("full", t, y, yp) or ("cols", cols, t, y,
    yp, f0), in the order the solver made them."""
    from dnasim.system import System

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
    from dnasim.errors import ResidualDomainError

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
    from dnasim.errors import ResidualDomainError

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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("plants", nargs="*", default=PLANTS)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--components", action="store_true")
    args = ap.parse_args(argv)
    rows = []
    for path in args.plants:
        system, calls = record(path)
        best = None
        for _ in range(args.repeat):
            r = replay(system, calls)
            if best is None or r[0] + r[2] < best[0] + best[2]:
                best = r
        t_full, n_full, t_cols, n_cols = best
        runs = [_run(path) for _ in range(args.repeat)]
        cpu = min(r[2] for r in runs)
        st = runs[0][1].stats
        rows.append(
            (
                Path(path).stem,
                system.n,
                1e6 * t_full / max(n_full, 1),
                n_full,
                1e6 * t_cols / max(n_cols, 1),
                n_cols,
                cpu,
                st.get("steps"),
                st.get("residual_evals"),
                st.get("jac_evals"),
            )
        )
        if args.components:
            ct = component_times(system, calls)
            print(f"{path}: us per component and whole-plant evaluation ({n_full} calls)")
            for name, dt in sorted(ct.items(), key=lambda kv: -kv[1]):
                print(f"    {name:<28} {1e6 * dt / n_full:8.1f}")
    print(
        f"{'plant':<20} {'n':>4} {'us/residual':>11} {'calls':>6} {'us/column F':>11} "
        f"{'calls':>6} {'run CPU s':>9} {'steps':>6} {'F evals':>7} {'Jacs':>5}"
    )
    for r in rows:
        print(
            f"{r[0]:<20} {r[1]:>4} {r[2]:>11.1f} {r[3]:>6} {r[4]:>11.1f} {r[5]:>6} "
            f"{r[6]:>9.3f} {r[7]:>6} {r[8]:>7} {r[9]:>5}"
        )


if __name__ == "__main__":
    main()
