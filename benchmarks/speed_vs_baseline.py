"""Whole `dnasim run` processes of this checkout against commit ea86a1d (issue 10's baseline).

    .venv/bin/python benchmarks/speed_vs_baseline.py            # best of 2, alternating
    .venv/bin/python benchmarks/speed_vs_baseline.py --only pipe_1000 --repeat 1

The baseline is installed once into a scratch directory (default
/tmp/dnasim_ea86a1d): ``git archive ea86a1d`` of this repository unpacked into
``src/``, its own venv in ``venv/``, ``pip install src`` from the package
registry. Both versions then run the same plant files as separate processes,
alternating (baseline, now, baseline, now, ...); the time is the CPU time of the
child process (user + system, ``resource.getrusage(RUSAGE_CHILDREN)``), start-up
and output included, and the best of ``--repeat`` runs is kept. The machine is
shared, so wall time is not used.

Both versions run from compiled bytecode: ``pip install`` compiled the baseline's
modules, and this checkout's (an editable install, whose modules Python would
otherwise compile from source in every process when PYTHONDONTWRITEBYTECODE is
set, as on this machine: about 0.15 s CPU per run) are compiled here first with
``compileall``, as an install would.

Plants (written to a scratch directory):

- pipe_1000: the 1000-volume steam pipe of ``benchmarks/plant_scaling.py``
  (tests/field/long_pipe_step.toml: 50 bar, 500 -> 520 degC inlet step at 1 s,
  4 s simulated, output every 0.1 s);
- air_pipe, attemperator, superheater_line: ``plants/*.toml`` as they are at
  ea86a1d.

The two versions name the absolute tolerance differently in the plant file and on
the command line (ea86a1d: ``atol`` / ``--atol``; now: ``atol_scaled`` /
``--atol-scaled``, the same quantity: atol_i = value * max(nominal_i, |y0_i|)), so
the files carry no such key and each version gets the file's value as its own
option. Everything else in the files is identical for both.

BLAS threads: ``dnasim run`` now sets ``OPENBLAS_NUM_THREADS=1`` (and MKL's and
Accelerate's) unless the environment sets it (``dnasim.cli.entry.single_threaded_blas``);
ea86a1d did not, so by default each version runs as shipped.
``--blas-threads 1`` gives both the same setting in their environment, which shows
how much of the ratio is the BLAS thread pools' idle spinning (the baseline's CPU
time falls by about 0.3 s per run with it on a 2-core machine).

Printed: plant, baseline CPU s, now CPU s, ratio baseline / now (> 1: now faster),
and the accepted steps of each (rows of steps.csv) as a check that both solved
the same problem.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from revision import file_at

ROOT = Path(__file__).resolve().parent.parent
COMMIT = "ea86a1d"
SMALL = ["air_pipe", "attemperator", "superheater_line"]

PIPE_1000 = """\
[plant]
name = "pipe_1000"
description = "1000-volume steam pipe, inlet temperature step"
medium = "Water"

[simulation]
t_end = "4 s"
output_interval = "0.1 s"
rtol = 1e-6
start = "steady"

[components.steam]
type = "PressureBoundary"
p = "50 bar"
T = { type = "step", t0 = "1 s", before = "500 degC", after = "520 degC" }
m_nominal = "2 kg/s"
ports = { port = "n_in" }

[components.pipe]
type = "Pipe"
V = "0.15708 m3"
kA = "6283 W/K"
k = 2e5
C_wall = "129.5 kJ/K"
n_volumes = 1000
m_nominal = "2 kg/s"
ports = { inlet = "n_in", outlet = "n_out" }

[components.valve]
type = "Valve"
C = "0.003 kg/(s.Pa0.5)"
opening = 1
m_nominal = "2 kg/s"
ports = { inlet = "n_out", outlet = "n_exit" }

[components.sink]
type = "PressureBoundary"
p = "45 bar"
m_nominal = "2 kg/s"
ports = { port = "n_exit" }
"""
PIPE_ATOL = "1e-6"


def install_baseline(where: Path) -> Path:
    """The baseline's ``dnasim`` executable, installed into ``where`` if not there yet."""
    exe = where / "venv" / "bin" / "dnasim"
    if exe.exists():
        return exe
    src = where / "src"
    src.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", COMMIT], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
    subprocess.run([sys.executable, "-m", "venv", str(where / "venv")], check=True)
    subprocess.run([str(where / "venv" / "bin" / "pip"), "install", "-q", str(src)], check=True)
    return exe


def plant_files(tmp: Path) -> dict[str, tuple[Path, str]]:
    """name -> (plant file without an absolute-tolerance key, that tolerance)."""
    files = {}
    pipe = tmp / "pipe_1000.toml"
    pipe.write_text(PIPE_1000)
    files["pipe_1000"] = (pipe, PIPE_ATOL)
    for name in SMALL:
        text = file_at(COMMIT, f"plants/{name}.toml")
        if text is None:
            raise SystemExit(f"git cannot show {COMMIT}:plants/{name}.toml in {ROOT}")
        atol, lines = None, []
        for line in text.splitlines():
            if line.replace(" ", "").startswith("atol="):
                atol = line.split("=", 1)[1].split("#")[0].strip()
            else:
                lines.append(line)
        path = tmp / f"{name}.toml"
        path.write_text("\n".join(lines) + "\n")
        files[name] = (path, atol)
    return files


def cpu_run(cmd: list[str], env=None) -> tuple[float, subprocess.CompletedProcess]:
    """CPU seconds (user + system) of one child process, and the process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, proc


def steps_of(out: Path) -> int:
    path = out / "steps.csv"
    if not path.exists():
        return -1
    with path.open() as f:
        return sum(1 for _ in f) - 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline-dir", type=Path, default=Path("/tmp/dnasim_ea86a1d"))
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--only", nargs="+", default=None, help="plant names to run")
    ap.add_argument(
        "--now-exe",
        default=None,
        help="the dnasim executable to compare with the baseline (default: this checkout's, "
        "next to this Python); e.g. a script running another checkout for a before/after: "
        "PYTHONPATH=<checkout> python -P -c 'from dnasim.cli.entry import main; main()' \"$@\" "
        "(-P: else the current directory's dnasim comes first)",
    )
    ap.add_argument(
        "--blas-threads",
        default=None,
        help="OPENBLAS_NUM_THREADS (and MKL_NUM_THREADS) for both versions' processes "
        "(default: each version as shipped, see the module doc)",
    )
    args = ap.parse_args(argv)
    env = None
    if args.blas_threads is not None:
        env = dict(os.environ)
        env.update(OPENBLAS_NUM_THREADS=args.blas_threads, MKL_NUM_THREADS=args.blas_threads)
    base_exe = install_baseline(args.baseline_dir)
    # bytecode of this checkout, as pip install gives the baseline (module doc)
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(ROOT / "dnasim")], check=True)
    now_exe = args.now_exe or Path(sys.executable).parent / "dnasim"
    versions = {
        "baseline": (str(base_exe), "--atol"),
        "now": (str(now_exe), "--atol-scaled"),
    }
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        files = plant_files(tmp)
        names = args.only or list(files)
        best: dict[tuple[str, str], float] = {}
        steps: dict[tuple[str, str], int] = {}
        for _ in range(args.repeat):
            for name in names:
                path, atol = files[name]
                for version, (exe, atol_option) in versions.items():
                    out = tmp / f"out_{name}_{version}"
                    cmd = [exe, "run", str(path), "-o", str(out), "-q"]
                    if atol is not None:
                        cmd += [atol_option, atol]
                    cpu, proc = cpu_run(cmd, env)
                    if proc.returncode != 0:
                        print(f"# {version} failed on {name}: {(proc.stdout + proc.stderr)[-400:]}")
                        cpu = float("nan")
                    key = (name, version)
                    best[key] = min(best.get(key, float("inf")), cpu)
                    steps[key] = steps_of(out)
                    print(f"# {name} {version}: {cpu:.2f} CPU s", file=sys.stderr, flush=True)
    head = (
        f"{'plant':<18} {'baseline CPU s':>14} {'now CPU s':>10} {'ratio':>7} "
        f"{'steps base':>10} {'steps now':>10}"
    )
    blas = "as shipped" if env is None else f"OPENBLAS_NUM_THREADS={args.blas_threads} for both"
    print(
        f"# speed_vs_baseline: {COMMIT} against this checkout, best of {args.repeat}, "
        f"BLAS threads {blas}"
    )
    print(head)
    print("-" * len(head))
    for name in names:
        b, n = best[(name, "baseline")], best[(name, "now")]
        print(
            f"{name:<18} {b:>14.2f} {n:>10.2f} {b / n:>7.2f} "
            f"{steps[(name, 'baseline')]:>10} {steps[(name, 'now')]:>10}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
