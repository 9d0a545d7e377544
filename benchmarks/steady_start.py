"""The steady start (issue 20) on every plant of plants/, tests/field/ and tests/plants/.

    .venv/bin/python benchmarks/steady_start.py                 # all plants
    .venv/bin/python benchmarks/steady_start.py plants/rankine.toml tests/plants/steady_*.toml
    .venv/bin/python benchmarks/steady_start.py --settle 20000  # and a settled given start

Printed per plant: whether the steady start found a state at rest ("ok", or the stage
at which it stopped with its reason; "no* balance" for a plant without a state at rest
by design: a balance that closes at rest for no value of its state, e.g. a drum without
level control whose heat input does not match its flows, ``unclosed_balances``), the
stage that found it (newton from which guess, or pseudo-transient), the residual
evaluations of the start (finite-difference Jacobians included), its CPU seconds
(``time.process_time``; the machine may be shared) and max |F| (scaled) after
it: max_i |F_i(t0, y, y')| / max_j |dF_i/du_j| s_j, each residual in units of the
relative change of the unknown u_j it sets (s_j = max(nominal_j, |y_j|); u the y of
the variables at rest, the y' of the accumulators and the free states).

With ``--settle T``: the given start of the plant file run from t0 - T to t0 (rtol and
atol_scaled 1e-8; the time functions are constant before t0 in every plant here), and
the largest difference between its end and the steady start, relative to each
variable's scale (accumulators left out); "-" where the given start fails (many plants
start steady by design and have no initial values of their own).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DIRS = ("plants", "tests/field", "tests/plants")


def scaled_residual(system, t0, y, yp, fixed) -> float:
    """max_i |F_i| / max_j |dF_i/du_j| s_j (module doc), by finite differences."""
    import scipy.sparse as sp

    from dnasim.solver.linear_algebra import IterationMatrix

    f = system.residual(t0, y, yp)
    matrix = IterationMatrix(
        system.residual,
        system.n,
        sparsity=sp.csc_matrix(system.pattern_y + system.pattern_yp),
        residual_for_columns=system.residual_for_columns,
    )
    scale = np.maximum(system.nominal, np.abs(y))
    inc = 1e-7 * scale
    ymask = (~fixed).astype(float)
    jac = matrix.finite_difference(t0, y, yp, f, inc, ymask, 1.0 - ymask)
    jac = sp.csr_matrix(abs(jac) @ sp.diags(scale))
    rows = np.asarray(jac.max(axis=1).todense()).ravel()
    rows = np.where(rows > 0, rows, 1.0)
    return float(np.max(np.abs(f) / rows))


def settled_difference(system, t0, y, T) -> str:
    from dnasim.run.simulation import simulate

    try:
        res = simulate(
            system, t0=t0 - T, t_end=t0, start="given", rtol=1e-8, atol_scaled=1e-8,
            t_eval=[t0 - T, t0],
        )  # fmt: skip
    except Exception:  # noqa: BLE001 - a given start that cannot begin
        return "-"
    if not res.success:
        return "-"
    yg = np.array([res[n][-1] for n in system.names])
    d = np.abs(y - yg) / np.maximum(system.nominal, np.abs(y))
    d[system.accumulator] = 0.0
    return f"{d.max():.1e}"


def one(path: Path, settle: float | None) -> tuple:
    from dnasim.plant.plantfile import load
    from dnasim.start.steady_state import find_steady_state, fixed_mask

    loaded = load(path)
    system = loaded.plant.compile()
    t0 = loaded.simulation.t_start
    try:
        rest = find_steady_state(system, t0)
    except Exception as err:  # noqa: BLE001 - reported in the table
        text = str(err)
        if "cannot close at rest" in text:  # a balance that closes for no value of its state
            where = text[text.find("no state at rest: ") + 18 :]
            return ("no*", "balance", "-", "-", "-", "-", where[:600])
        stage = "pseudo" if "continuation" in text else "ranges" if "ranges" in text else "newton"
        return ("no", stage, "-", "-", "-", "-", text[:160])
    st = rest.stats
    fixed = fixed_mask(system, t0, rest.y)
    f = scaled_residual(system, t0, rest.y, rest.yp, fixed)
    diff = settled_difference(system, t0, rest.y, settle) if settle else ""
    method = st.method.replace("newton ", "").replace("pseudo-transient", "pseudo")
    return ("ok", method, st.residual_evals, f"{st.cpu:.2f}", f"{f:.1e}", diff, "")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plants", nargs="*", help="plant files (default: all)")
    ap.add_argument(
        "--settle", type=float, default=None, metavar="T", help="given start from t0 - T"
    )
    args = ap.parse_args(argv)
    paths = [Path(p) for p in args.plants] or [
        p for d in DIRS for p in sorted((ROOT / d).glob("*.toml"))
    ]
    head = ("plant", "start", "found by", "res. evals", "CPU [s]", "max|F| scaled")
    head += ("settled diff",) if args.settle else ()
    rows, notes = [], []
    for p in paths:
        c = time.process_time()
        r = one(p, args.settle)
        name = str(p.resolve().relative_to(ROOT)) if p.resolve().is_relative_to(ROOT) else str(p)
        rows.append((name,) + r[:5] + ((r[5],) if args.settle else ()))
        if r[6]:
            notes.append(f"{name}: {r[6]}")
        print(f"  ({name}: {time.process_time() - c:.1f} s)", file=sys.stderr)
    widths = [max(len(str(x)) for x in col) for col in zip(head, *rows, strict=True)]
    for line in [head] + rows:
        print("  ".join(str(x).ljust(w) if i == 0 else str(x).rjust(w)
                        for i, (x, w) in enumerate(zip(line, widths, strict=True))))  # fmt: skip
    for n in notes:
        print(n)


if __name__ == "__main__":
    main()
