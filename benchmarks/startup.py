"""Start-up cost of small dnasim commands: CPU seconds of whole processes (issue 23 item 8).

    .venv/bin/python benchmarks/startup.py                    # this checkout, 5 runs each
    .venv/bin/python benchmarks/startup.py --before 872daac   # and a before column
    .venv/bin/python benchmarks/startup.py --repeat 9 --no-contributors

Each command is run ``--repeat`` times as a fresh process (after one warm-up run
that fills numba's cache and the bytecode) and the least CPU time is printed:
user + system of the child (``resource.getrusage(RUSAGE_CHILDREN)``), so the
interpreter, every import, the media, the work and the exit are all in it. The
minimum because the machine is shared: other work only ever adds time.

``--before REV`` runs the same commands on ``git archive REV`` unpacked into a
temporary directory (its modules first on ``sys.path``; the dependencies are this
Python's) for a before/after table.

The contributors (one more run of each command with ``python -X importtime``,
the least of ``--repeat`` such runs per module): the import time of each
top-level package, its own modules' self times summed, in milliseconds. These are
wall-clock times (importtime uses ``perf_counter``), so on a loaded machine they
are an upper bound of the CPU. ``loaded`` lists which of the heavy optional
packages (numba, scipy, h5py, CoolProp, matplotlib, pandas, xarray, networkx) the
process had imported when it ended.
"""

from __future__ import annotations

import argparse
import collections
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("numba", "scipy", "h5py", "CoolProp", "matplotlib", "pandas", "xarray", "networkx")
COMMANDS = [
    ("dnasim --help", ["--help"]),
    ("dnasim check plants/air_pipe.toml", ["check", "plants/air_pipe.toml"]),
    ("dnasim check plants/attemperator.toml", ["check", "plants/attemperator.toml"]),
    ("dnasim run plants/air_pipe.toml -o DIR", ["run", "plants/air_pipe.toml", "-o", "{out}"]),
    (
        "dnasim run plants/attemperator.toml -o DIR",
        ["run", "plants/attemperator.toml", "-o", "{out}"],
    ),
]

# The child: ``dnasim`` as the console script runs it, from CHECKOUT (argv[1]); at exit
# it names the heavy packages it imported.
DRIVER = r"""
import atexit, sys
checkout = sys.argv.pop(1)
sys.path.insert(0, checkout)
HEAVY = HEAVY_NAMES
def _loaded():
    print("LOADED " + " ".join(h for h in HEAVY if h in sys.modules), file=sys.stderr)
atexit.register(_loaded)
from dnasim.cli.entry import main
sys.exit(main(sys.argv[1:]))
""".replace("HEAVY_NAMES", repr(HEAVY))


def _child(checkout: Path, args: list[str], out: Path, importtime: bool = False):
    argv = [a.replace("{out}", str(out)) for a in args]
    cmd = [sys.executable, "-P"] + (["-X", "importtime"] if importtime else [])
    cmd += ["-c", DRIVER, str(checkout)] + argv
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=str(checkout))
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} in {checkout} failed: {proc.stderr[-800:]}")
    loaded = [x for x in proc.stderr.splitlines() if x.startswith("LOADED")]
    return cpu, (loaded[-1][7:] if loaded else ""), proc.stderr


def _import_self_times(stderr: str) -> dict[str, int]:
    """Self import time [us] per module from ``-X importtime`` output."""
    out = {}
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        parts = line[len("import time:") :].split("|")
        if len(parts) == 3:
            out[parts[2].strip()] = int(parts[0])
    return out


def measure(checkout: Path, repeat: int, contributors: bool) -> dict[str, dict]:
    subprocess.run(
        [sys.executable, "-m", "compileall", "-q", str(checkout / "dnasim")],
        check=True,
        capture_output=True,
    )
    res = {}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        for name, args in COMMANDS:
            _child(checkout, args, out)  # warm-up: numba's cache, bytecode
            cpus, loaded = [], ""
            for _ in range(repeat):
                cpu, loaded, _ = _child(checkout, args, out)
                cpus.append(cpu)
            row = {"cpu": min(cpus), "loaded": loaded}
            if contributors:
                best: dict[str, int] = {}
                for _ in range(repeat):
                    _, _, err = _child(checkout, args, out, importtime=True)
                    for mod, us in _import_self_times(err).items():
                        best[mod] = min(best.get(mod, us), us)
                pkg: collections.Counter = collections.Counter()
                for mod, us in best.items():
                    pkg[mod.split(".")[0]] += us
                row["imports_ms"] = sum(best.values()) / 1e3
                row["top"] = pkg.most_common(6)
            res[name] = row
    return res


def _archive(rev: str, dest: Path) -> Path:
    data = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=data, check=True)
    return dest


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per command (default 5)")
    ap.add_argument("--before", metavar="REV", help="also run git revision REV (a column)")
    ap.add_argument("--no-contributors", action="store_true", help="skip the importtime runs")
    args = ap.parse_args(argv)
    contributors = not args.no_contributors
    before = None
    if args.before:
        with tempfile.TemporaryDirectory() as tmp:
            before = measure(_archive(args.before, Path(tmp)), args.repeat, False)
    after = measure(ROOT, args.repeat, contributors)
    w = max(len(n) for n, _ in COMMANDS)
    print(
        f"# CPU s (user+sys) of whole processes, min of {args.repeat}; "
        f"python {sys.version.split()[0]}"
    )
    head = f"{'command':<{w}} "
    if before is not None:
        head += f"{args.before[:10]:>10} "
    head += f"{'CPU s':>7}  heavy modules loaded"
    print(head)
    for name, _ in COMMANDS:
        line = f"{name:<{w}} "
        if before is not None:
            line += f"{before[name]['cpu']:>10.3f} "
        line += f"{after[name]['cpu']:>7.3f}  {after[name]['loaded'] or '-'}"
        print(line)
    if contributors:
        print()
        print(
            "# import time by top-level package, ms (wall, -X importtime, "
            f"min of {args.repeat} per module)"
        )
        for name, _ in COMMANDS:
            r = after[name]
            top = ", ".join(f"{p} {us / 1e3:.0f}" for p, us in r["top"])
            print(f"{name:<{w}} all {r['imports_ms']:.0f}: {top}")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONHASHSEED", "0")
    raise SystemExit(main())
