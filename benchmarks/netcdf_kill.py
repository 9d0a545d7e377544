"""results.nc after SIGKILL: writers killed at random times, every file read back.

    .venv/bin/python benchmarks/netcdf_kill.py            # 40 writers
    .venv/bin/python benchmarks/netcdf_kill.py --runs 100

Each writer (this script with ``--write PATH``) streams rows into a ``NetCDFSink``
as fast as it can, a block every 5 rows (so that most of its time is spent inside
HDF5's writes and flushes, where a kill could tear the file): 50 scalars and two
1000-vectors, every value equal to the row's time, and every 7th row a jump (a
left limit and the state after it, 0.5 s later). It is killed (SIGKILL: no handler,
no close) 0.05 to 1.5 s after its file exists. Then ``dnasim.read_results`` must
open the file and every row on it must be whole: strictly increasing times, each
value equal to its row's time (no unwritten NaN, no value of another row), and the
restart flags on the jumps' rows. Printed: runs, files unreadable or torn, rows
kept (min, max).
"""

from __future__ import annotations

import argparse
import os
import random
import subprocess
import sys
import tempfile
import time

import numpy as np


def write(path: str) -> None:
    from dnasim.run.sinks import NetCDFSink

    names = [f"s{k}" for k in range(50)]
    names += [f"pipe.T[{i}]" for i in range(1000)] + [f"pipe.M[{i}]" for i in range(1000)]
    names += ["restart"]
    sink = NetCDFSink(path, flush_rows=5, flush_seconds=0.0)
    sink.open(names, {})
    print("ready", flush=True)
    k = 0
    while True:
        row = np.full(len(names), float(k))
        row[-1] = 0.0
        sink.write(float(k), row)
        if k % 7 == 3:
            t = k + 0.5
            sink.write(t, row)  # the left limit: the old values
            after = np.full(len(names), t)
            after[-1] = 1.0
            sink.write(t, after)
        k += 1


def check(path: str) -> tuple[bool, int]:
    import dnasim

    res = dnasim.read_results(path)
    ok = res.t.size > 0 and bool(np.all(np.diff(res.t) > 0))
    for name in res.names:
        ok = ok and bool(np.all(res[name] == res.t))
    ok = ok and bool(np.all(res.restart == (res.t % 1 == 0.5)))
    return ok, int(res.t.size)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=40)
    ap.add_argument("--write", metavar="PATH", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.write:
        write(args.write)
        return
    bad, rows = 0, []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.runs):
            path = os.path.join(tmp, f"r{i}.nc")
            proc = subprocess.Popen(
                [sys.executable, __file__, "--write", path], stdout=subprocess.PIPE, text=True
            )
            proc.stdout.readline()
            time.sleep(random.uniform(0.05, 1.5))
            proc.kill()
            proc.wait()
            try:
                ok, n = check(path)
            except Exception as exc:  # unreadable
                ok, n = False, 0
                print(f"run {i}: {type(exc).__name__}: {exc}")
            bad += not ok
            rows.append(n)
            os.unlink(path)
    print(
        f"killed {args.runs} writers at random times: {bad} files unreadable or torn; "
        f"rows kept min {min(rows)} max {max(rows)}"
    )


if __name__ == "__main__":
    main()
