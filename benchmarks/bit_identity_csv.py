"""Bit identity of every plant's results across a solver refactor (issue 21, item 6).

    .venv/bin/python benchmarks/bit_identity_csv.py --save before.json   # on the old code
    .venv/bin/python benchmarks/bit_identity_csv.py --compare before.json  # on the new code
    .venv/bin/python benchmarks/bit_identity_csv.py plants/rankine.toml --t-end 500

Each plant of ``plants/*.toml`` (or the files given) is run as ``dnasim run`` runs it
(``dnasim.run.runner.run_plant``: the steady or given start of the file, its tolerances,
its output interval, results streamed to results.csv), with t_end cut to ``--t-end``
seconds after t_start where the file's is longer (default 1200 s; ``--full``: the
file's own). Printed per plant: the sha256 of the bytes of results.csv (its first 16
hex digits), the rows, the solver's counters (accepted steps, residual evaluations,
Jacobians), the CPU seconds of the run (``time.process_time``, start included; the
machine may be shared) and how the run ended. With ``--compare FILE`` the hashes and counters of
an earlier ``--save`` are printed next to them with "identical" yes/no: yes only when
the bytes of results.csv and every counter agree.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COUNTERS = ("steps", "residual_evals", "jac_evals")


def run_one(path: Path, t_end_cut: float | None) -> dict:
    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant

    loaded = load(path)
    sim = loaded.simulation
    if t_end_cut is not None and sim.t_end - sim.t_start > t_end_cut:
        sim.t_end = sim.t_start + t_end_cut
    with tempfile.TemporaryDirectory() as tmp:
        cpu = time.process_time()
        outcome = run_plant(loaded, tmp)
        cpu = time.process_time() - cpu
        csv = Path(tmp) / "results.csv"
        data = csv.read_bytes() if csv.exists() else b""
    stats = outcome.stats or {}
    return {
        "hash": hashlib.sha256(data).hexdigest(),
        "rows": outcome.rows,
        "t_end": sim.t_end,
        "status": outcome.status,
        "cpu": cpu,
        **{k: int(stats.get(k, -1)) for k in COUNTERS},
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("plants", nargs="*", help="plant files (default: plants/*.toml)")
    ap.add_argument("--t-end", type=float, default=1200.0, help="longest span [s] (default 1200)")
    ap.add_argument("--full", action="store_true", help="the file's own t_end")
    ap.add_argument("--save", help="write the hashes and counters to this JSON file")
    ap.add_argument("--compare", help="compare with a JSON file written by --save")
    args = ap.parse_args(argv)
    paths = [Path(p) for p in args.plants] or sorted((ROOT / "plants").glob("*.toml"))
    before = json.loads(Path(args.compare).read_text()) if args.compare else None
    cut = None if args.full else args.t_end
    found = {}
    if before is None:
        print(
            f"{'plant':<30} {'t_end s':>8} {'sha256 results.csv':<17} {'rows':>5} "
            f"{'steps':>6} {'res.evals':>9} {'Jacs':>5} status"
        )
    else:
        print(
            f"{'plant':<30} {'hash before':<17} {'hash after':<17} {'steps b/a':>11} "
            f"{'res.evals b/a':>15} {'Jacs b/a':>9} {'CPU s b/a':>11} identical"
        )
    all_same = True
    for p in paths:
        r = run_one(p, cut)
        name = p.name
        found[name] = r
        if before is None:
            print(
                f"{name:<30} {r['t_end']:>8.6g} {r['hash'][:16]:<17} {r['rows']:>5} "
                f"{r['steps']:>6} {r['residual_evals']:>9} {r['jac_evals']:>5} {r['status']}"
            )
        else:
            b = before.get(name)
            same = b is not None and b["hash"] == r["hash"] and all(b[k] == r[k] for k in COUNTERS)
            all_same &= same
            bh = b["hash"][:16] if b else "-"
            bs = b or {k: "-" for k in COUNTERS}
            cpu = f"{b['cpu']:.2f}/{r['cpu']:.2f}" if b else "-"
            print(
                f"{name:<30} {bh:<17} {r['hash'][:16]:<17} "
                f"{str(bs['steps']) + '/' + str(r['steps']):>11} "
                f"{str(bs['residual_evals']) + '/' + str(r['residual_evals']):>15} "
                f"{str(bs['jac_evals']) + '/' + str(r['jac_evals']):>9} {cpu:>11} "
                f"{'yes' if same else 'NO'}"
            )
        sys.stdout.flush()
    if args.save:
        Path(args.save).write_text(json.dumps(found, indent=1) + "\n")
    return 0 if all_same else 1


if __name__ == "__main__":
    sys.exit(main())
