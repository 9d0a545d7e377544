"""CPU time of each phase of a whole ``dnasim run PLANT -o DIR -q`` process.

    .venv/bin/python benchmarks/startup_phases.py                 # the three small plants
    .venv/bin/python benchmarks/startup_phases.py plants/rankine.toml --repeat 3

Each run is a fresh child process that installs timers around the functions of
the run (wrappers, nothing else changed) and then runs the command line as
``dnasim`` does (``dnasim.cli.entry.main``). The phases, in CPU seconds
(``time.process_time``, all threads of the process):

- ``python``: the interpreter and ``site`` before the first line of the driver
  (the process's CPU time at that point, ``resource.getrusage``);
- ``cli``: importing ``click`` and ``dnasim.cli.commands`` and parsing the options;
- ``imports``: preparing the output directory and importing the modules of the
  run (numpy, scipy, dnasim's own) up to the medium;
- ``medium``: creating the media (``dnasim.media.registry._create``): for Water
  importing numba and loading the compiled IF97 kernels from numba's cache;
- ``parse``: the rest of ``load`` (reading TOML, building the components);
- ``compile``: ``dnasim.compilation.compiler.compile`` (structure, matching, the System);
- ``start``: the consistent initial values (``dnasim.start.initial.initial_values``;
  the steady start's Newton iterations), with their residual evaluations;
- ``run``: the integration, less the rows;
- ``rows``: computing and writing the rows of results.csv (``OutputRows.row`` and
  ``CSVSink.write``/``close``) inside the run;
- ``netcdf``: results.nc (``NetCDFSink.open``/``write``/``close``: importing h5py,
  defining the file, writing the rows);
- ``files``: events.csv and steps.csv;
- ``exit``: everything after the command returned until the process ended
  (interpreter shutdown), from the child's total CPU time (``RUSAGE_CHILDREN``)
  less the driver's last reading.

``before step`` is python + cli + imports + medium + parse + compile + start:
issue 10's "CPU before the first step". Printed per plant: the best (least
total) of ``--repeat`` runs. The machine may be shared: CPU time, not wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SMALL = ["air_pipe", "attemperator", "superheater_line"]
PHASES = [
    "python",
    "cli",
    "imports",
    "medium",
    "parse",
    "compile",
    "start",
    "run",
    "rows",
    "netcdf",
    "files",
    "exit",
]

# The child: timers around the run's functions, then the command line.
DRIVER = r"""
import json, resource, sys, time
ru = resource.getrusage(resource.RUSAGE_SELF)
t_python = ru.ru_utime + ru.ru_stime
clock = time.process_time
acc = {}
t0 = clock()

def timed(owner, name, key):
    f = getattr(owner, name)
    def wrapper(*a, **k):
        s = clock()
        try:
            return f(*a, **k)
        finally:
            acc[key] = acc.get(key, 0.0) + clock() - s
    setattr(owner, name, wrapper)

import click  # noqa
import dnasim.cli.commands  # noqa
acc["cli"] = clock() - t0
timed(dnasim.cli.commands, "_prepare_output", "prepare")
timed(dnasim.cli.commands, "_coolprop_cache", "prepare")  # imports dnasim.plant.plantfile

orig_load = dnasim.cli.commands._load
def load(plant_file, *a, **k):
    s = clock()
    import dnasim.plant.plantfile as pf
    import dnasim.media.registry as reg
    timed(reg, "_create", "medium")
    import dnasim.run.sinks as sinks
    import dnasim.run.output as output
    import dnasim.run.runner as runner
    import dnasim.compilation.compiler as compiler
    import dnasim.start.initial as start
    acc["imports"] = clock() - s
    timed(compiler, "compile", "compile")
    timed(start, "initial_values", "start")
    timed(runner, "solve_streaming", "solve")
    timed(sinks.OutputRows, "row", "rows")
    timed(sinks.CSVSink, "write", "rows_write")
    timed(sinks.CSVSink, "close", "rows_close")
    timed(sinks.NetCDFSink, "open", "netcdf")  # imports h5py
    timed(sinks.NetCDFSink, "write", "netcdf")
    timed(sinks.NetCDFSink, "close", "netcdf")
    timed(runner, "write_events_csv", "files")
    timed(runner, "write_steps_csv", "files")
    s = clock()
    r = orig_load(plant_file, *a, **k)
    acc["load"] = clock() - s
    return r
dnasim.cli.commands._load = load

from dnasim.cli.entry import main
code = main(sys.argv[1:])
acc["end"] = clock() - t0 + t_python
acc["python"] = t_python
acc["code"] = code
print("PHASES " + json.dumps(acc), file=sys.stderr)
sys.exit(code)
"""


def run_once(plant: Path, out: Path, checkout: Path = ROOT) -> dict[str, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(
        [sys.executable, "-c", DRIVER, "run", str(plant), "-o", str(out), "-q"],
        capture_output=True,
        text=True,
        cwd=str(checkout),  # python -c: dnasim is imported from the current directory
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    total = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    line = [x for x in proc.stderr.splitlines() if x.startswith("PHASES ")]
    if proc.returncode != 0 or not line:
        raise SystemExit(f"{plant} failed: {proc.stdout[-400:]} {proc.stderr[-800:]}")
    acc = json.loads(line[-1][len("PHASES ") :])
    g = acc.get
    rows = g("rows", 0.0) + g("rows_write", 0.0) + g("rows_close", 0.0)
    ph = {
        "python": g("python", 0.0),
        "cli": g("cli", 0.0),
        "imports": g("prepare", 0.0) + g("imports", 0.0),
        "medium": g("medium", 0.0),
        "parse": g("load", 0.0) - g("medium", 0.0),
        "compile": g("compile", 0.0),
        "start": g("start", 0.0),
        "run": g("solve", 0.0) - g("start", 0.0) - rows - g("netcdf", 0.0),
        "rows": rows,
        "netcdf": g("netcdf", 0.0),
        "files": g("files", 0.0),
    }
    ph["exit"] = total - g("end", 0.0)
    ph["other"] = g("end", 0.0) - sum(v for k, v in ph.items() if k != "exit")
    ph["total"] = total
    ph["before step"] = sum(
        ph[k] for k in ("python", "cli", "imports", "medium", "parse", "compile", "start")
    )
    return ph


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plants", nargs="*", help="plant files (default: the three small plants)")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument(
        "--checkout",
        type=Path,
        default=ROOT,
        help="the source tree whose dnasim runs (default: this one), e.g. an older revision "
        "unpacked with git archive, for a before/after; its dependencies are this Python's",
    )
    args = ap.parse_args(argv)
    plants = [Path(p) for p in args.plants] or [ROOT / "plants" / f"{n}.toml" for n in SMALL]
    # bytecode, as an install would have it (see speed_vs_baseline.py)
    subprocess.run(
        [sys.executable, "-m", "compileall", "-q", str(args.checkout / "dnasim")], check=True
    )
    cols = PHASES + ["other", "before step", "total"]
    best: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeat):
            for plant in plants:
                ph = run_once(plant.resolve(), Path(tmp) / plant.stem, args.checkout.resolve())
                b = best.get(plant.stem)
                if b is None or ph["total"] < b["total"]:
                    best[plant.stem] = ph
    print(f"# CPU s per phase of `dnasim run PLANT -o DIR -q`, best of {args.repeat} (by total)")
    w = max(len(c) for c in cols)
    print(f"{'phase':<{w}} " + " ".join(f"{p.stem[:16]:>16}" for p in plants))
    for c in cols:
        print(f"{c:<{w}} " + " ".join(f"{best[p.stem][c]:>16.3f}" for p in plants))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    raise SystemExit(main())
