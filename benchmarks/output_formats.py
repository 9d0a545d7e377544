"""Result files: bytes written and CPU time of the writing, results.csv against results.nc.

    .venv/bin/python benchmarks/output_formats.py         # N = 1000: 1 s output, every step
    .venv/bin/python benchmarks/output_formats.py --sizes 100 1000 --interval 1 0.1

Plant: the steam pipe of ``benchmarks/plant_scaling.py`` (50 bar, 500 C stepping to
520 C at t = 1 s, N volumes), steady start, simulated to 60 s with ``t_eval`` every
``--interval`` seconds (0: a row per accepted step, as ``dnasim run`` without
``output_interval``). The run is done once per (N, interval); its rows (exactly the
rows ``simulate`` hands its sinks: ``dnasim.run.sinks.OutputRows``) are recorded, and then
written ``--repeat`` times by each sink alone, the best CPU time
(``time.process_time``) kept:

- ``CSVSink``: results.csv, one text column per output (``repr`` of each float);
- ``NetCDFSink``: results.nc, netCDF-4/HDF5 in SWMR mode, vectors as dimensions,
  told the number of rows an output interval asks for (as ``dnasim run`` does).

Both with the sinks' defaults (a block every 200 rows or 1 s) and the file's
``fsync`` at close. Printed: rows, output columns, bytes on disk, CPU seconds of the
writing (open, every row, close), ns per value, and the ratios CSV / netCDF.

``--cli PLANT ...``: whole ``dnasim run PLANT -q --format F`` processes instead, for
F = csv, netcdf, both: CPU seconds of the child process (user + system,
``resource.getrusage``), best of ``--repeat``; what a small plant pays for the
netCDF file (h5py's import included).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from plant_scaling import T_END, steam_pipe  # noqa: E402

import dnasim  # noqa: E402
from dnasim.run.simulation import simulate  # noqa: E402
from dnasim.run.sinks import CSVSink, NetCDFSink  # noqa: E402


class Recorder:
    """A sink that keeps the rows it is handed."""

    def open(self, names, units):
        self.names, self.units, self.rows = list(names), dict(units), []

    def write(self, t, row):
        self.rows.append((float(t), np.array(row, dtype=float)))

    def close(self):
        pass


def record(n: int, interval: float) -> Recorder:
    system = dnasim.compile(steam_pipe(n))
    rec = Recorder()
    t_eval = np.arange(0.0, T_END + 0.5 * interval, interval) if interval > 0 else None
    res = simulate(system, t_end=T_END, t_eval=t_eval, sinks=[rec])
    if not res.success:
        raise SystemExit(f"N = {n}: the run failed: {res.message}")
    return rec


def write_once(make, rec: Recorder, d: Path) -> tuple[float, int]:
    path = d / "out"
    if path.exists():
        os.unlink(path)
    t0 = time.process_time()
    sink = make(path)
    sink.open(rec.names, rec.units)
    for t, row in rec.rows:
        sink.write(t, row)
    sink.close()
    cpu = time.process_time() - t0
    return cpu, path.stat().st_size


def cli_runs(plants, repeat: int) -> None:
    import resource
    import subprocess

    root = Path(__file__).resolve().parents[1]
    print(f"{'plant':<28} {'format':>7} {'CPU s':>7} {'results bytes':>14}")
    for plant in plants:
        for fmt in ("csv", "netcdf", "both"):
            best, size = float("inf"), 0
            for _ in range(repeat):
                with tempfile.TemporaryDirectory() as out:
                    before = resource.getrusage(resource.RUSAGE_CHILDREN)
                    subprocess.run(
                        [sys.executable, "-m", "dnasim", "run", plant, "-o", out, "-q"]
                        + ["--format", fmt],
                        check=True,
                        cwd=root,
                    )
                    after = resource.getrusage(resource.RUSAGE_CHILDREN)
                    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                    files = [Path(out) / n for n in ("results.csv", "results.nc")]
                    size = sum(f.stat().st_size for f in files if f.exists())
                best = min(best, cpu)
            print(f"{Path(plant).name:<28} {fmt:>7} {best:>7.2f} {size:>14,}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", nargs="+", metavar="PLANT", help="whole dnasim run processes")
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000])
    ap.add_argument("--interval", type=float, nargs="+", default=[1.0, 0.0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if args.cli:
        cli_runs(args.cli, args.repeat)
        return
    head = (
        f"{'N':>5} {'dt [s]':>6} {'rows':>5} {'columns':>7} {'format':>7} {'bytes':>11} "
        f"{'CPU s':>8} {'ns/value':>9}"
    )
    print(head)
    print("-" * len(head))
    ratios = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for n in args.sizes:
            for dt in args.interval:
                rec = record(n, dt)
                expected = round(T_END / dt) + 1 if dt > 0 else None
                sinks = {
                    "csv": lambda p: CSVSink(p),
                    "netcdf": lambda p, e=expected: NetCDFSink(p, expected_rows=e),
                }
                values = len(rec.rows) * (len(rec.names) + 1)
                got = {}
                for name, make in sinks.items():
                    best = min(
                        (write_once(make, rec, d) for _ in range(args.repeat)), key=lambda r: r[0]
                    )
                    got[name] = best
                    cpu, size = best
                    print(
                        f"{n:>5} {dt:>6g} {len(rec.rows):>5} {len(rec.names):>7} {name:>7} "
                        f"{size:>11,} {cpu:>8.3f} {cpu / values * 1e9:>9.0f}"
                    )
                (c_cpu, c_size), (n_cpu, n_size) = got["csv"], got["netcdf"]
                ratios.append((n, dt, c_size / n_size, c_cpu / n_cpu))
    print()
    print(f"{'N':>5} {'dt [s]':>6} {'bytes CSV/nc':>13} {'CPU CSV/nc':>11}")
    for n, dt, rb, rc in ratios:
        print(f"{n:>5} {dt:>6g} {rb:>13.2f} {rc:>11.2f}")


if __name__ == "__main__":
    main()
