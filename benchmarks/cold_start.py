"""The first `dnasim run` on a fresh machine against a warm one: numba's compile cost.

    .venv/bin/python benchmarks/cold_start.py                      # plants/attemperator.toml
    .venv/bin/python benchmarks/cold_start.py --plants plants/air_pipe.toml plants/rankine.toml
    .venv/bin/python benchmarks/cold_start.py --label before --json rows.json

Each row is whole ``python -m dnasim run PLANT -o DIR`` processes (no ``--plot``: the
plot is not what is measured). "cold": with ``NUMBA_CACHE_DIR`` set to a new empty
directory, so numba finds no cached kernel and compiles every kernel the run calls
(what a fresh ``pip install`` sees: numba's cache of an installed package is written
under ``__pycache__`` next to the sources, or under ``NUMBA_CACHE_DIR`` when that is
set). "warm": the same directory again, now filled by the cold run (best of
``--repeat``). CPU is the child's user + system time (``resource.getrusage
(RUSAGE_CHILDREN)``), wall is ``time.perf_counter`` around the process (the machine is
shared: wall is noisy, CPU is the number to compare). "cache MB": what the cold run
wrote into the cache directory. "stderr note": whether the run said on stderr that it
compiles (the first words of that line).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


SRC = {"dir": ROOT}


def one_run(plant: str, cache_dir: str, out_dir: str) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir, PYTHONPATH=str(SRC["dir"]))
    plant = str((ROOT / plant).resolve())
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "dnasim", "run", plant, "-o", out_dir],
        cwd=SRC["dir"],
        env=env,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - w0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    note = next((ln for ln in proc.stderr.splitlines() if "compiling" in ln), "")
    return {"rc": proc.returncode, "cpu": cpu, "wall": wall, "note": note, "err": proc.stderr}


def dir_mb(path: str) -> float:
    return sum(f.stat().st_size for f in Path(path).rglob("*") if f.is_file()) / 1e6


def measure(plant: str, repeat: int) -> dict:
    with tempfile.TemporaryDirectory(prefix="dnasim_cold_") as tmp:
        cache = os.path.join(tmp, "numba_cache")
        os.mkdir(cache)
        cold = one_run(plant, cache, os.path.join(tmp, "out_cold"))
        if cold["rc"] != 0:
            raise SystemExit(f"{plant}: exit {cold['rc']}\n{cold['err']}")
        mb = dir_mb(cache)
        warm = [one_run(plant, cache, os.path.join(tmp, f"out_warm{i}")) for i in range(repeat)]
        best = min(warm, key=lambda r: r["cpu"])
    return {
        "plant": plant,
        "cold_cpu": cold["cpu"],
        "cold_wall": cold["wall"],
        "warm_cpu": best["cpu"],
        "warm_wall": best["wall"],
        "cache_mb": mb,
        "cold_note": cold["note"],
        "warm_note": best["note"],
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", nargs="+", default=["plants/attemperator.toml"])
    ap.add_argument("--repeat", type=int, default=2, help="warm runs (best CPU of)")
    ap.add_argument("--label", default="", help="a label printed in each row")
    ap.add_argument("--json", help="also write the rows to this file")
    ap.add_argument(
        "--src",
        nargs="+",
        metavar="LABEL=DIR",
        help="run these source trees instead of this checkout (e.g. before=/tmp/base, "
        "extracted by `git archive REV | tar -x -C DIR`); the plant files are this "
        "checkout's",
    )
    args = ap.parse_args(argv)
    trees = [(args.label, ROOT)]
    if args.src:
        trees = [(s.split("=", 1)[0], Path(s.split("=", 1)[1]).resolve()) for s in args.src]
    head = (
        f"{'label':<8} {'plant':<28} {'cold CPU s':>10} {'cold wall s':>11} {'warm CPU s':>10} "
        f"{'warm wall s':>11} {'cache MB':>8}  stderr note (cold run)"
    )
    print(head)
    print("-" * len(head))
    rows = []
    for plant in args.plants:
        for label, tree in trees:
            SRC["dir"] = tree
            r = measure(plant, args.repeat)
            r["label"] = label
            rows.append(r)
            note = r["cold_note"][:60] if r["cold_note"] else "(none)"
            if r["warm_note"]:
                note += "  WARM RUN ALSO SAYS: " + r["warm_note"][:40]
            print(
                f"{label:<8} {Path(plant).name:<28} {r['cold_cpu']:>10.2f} "
                f"{r['cold_wall']:>11.2f} {r['warm_cpu']:>10.2f} {r['warm_wall']:>11.2f} "
                f"{r['cache_mb']:>8.1f}  {note}",
                flush=True,
            )
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
