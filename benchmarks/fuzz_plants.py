"""Fuzz the command line with mutated example plants; print the tally.

Each case takes one plant of plants/*.toml, applies one to three random mutations
(delete a key, duplicate a line, a value of the wrong type, a wrong or garbled
unit, an extreme number, a dangling node or signal name, an unknown key or
another component type of the library, a gas where a drum needs water, a
``[plant] import`` of a module next to the file, bytes that are not UTF-8) and
runs ``dnasim check`` on it, or, for a sample, ``dnasim run`` with a tiny end time
or ``dnasim sweep`` with fuzzed options (``--set`` values, a cases file with bad
bytes, duplicate columns or long cells, ``--output-interval``, ``--scheduler``
addresses, ``--allow-import``). The command runs in-process (click's CliRunner),
under an alarm.
Outcomes:

    clean      exit 0
    ok         exit 2 with a located message (names the plant file or an option),
               or exit 1 (the simulation failed: its message says where and why)
    unlocated  exit 2 without a file or option in the message
    internal   "internal error" (a bug path of the command line)
    traceback  an exception escaped the command, or a traceback was printed
    hang       more than --timeout seconds of CPU time
    crash      a worker process died (segfault, out of memory)

The last line printed is the tally. Usage::

    .venv/bin/python benchmarks/fuzz_plants.py                  # 10000 cases, 2 processes
    .venv/bin/python benchmarks/fuzz_plants.py --n 500 --jobs 1 # quick look

``tests/test_fuzz_plants.py`` drives :func:`mutate` and :func:`classify` from
hypothesis for about a minute in CI.
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import random
import signal
import sys
import tempfile
import time
import tomllib
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import tomli_w

ROOT = Path(__file__).resolve().parents[1]
PLANTS = sorted((ROOT / "plants").glob("*.toml"))
OUTCOMES = ("clean", "ok", "unlocated", "internal", "traceback", "hang", "crash")

UNITS = [
    "bar", "Pa", "kPa", "MPa", "degC", "degF", "K", "delta_degC", "kg/s", "t/h", "s", "min",
    "h", "m3", "m", "W/K", "J/K", "kJ/K", "1/K", "1/(K.s)", "%", "1", "furlong", "m^999",
    "m^(1/0)", "((((m))))", "kg/(s.Pa0.5)", "W/m2.K", "degC2", "1/degC", "",
]  # fmt: skip
NUMBERS = [
    0, -1, 1, 2, 150, 1e30, -1e30, 1e308, -1e308, 1e-300, 5e-324, 10**20, -(10**20),
    1000000, 100000, 1.5, math.inf, -math.inf, math.nan,
]  # fmt: skip
WRONG = [True, False, [], [1, 2], {}, {"type": "step"}, "", "abc", "1e-300 s", "5000 degC"]
#: component types a mutation may put in place of another: the whole library
TYPES = [
    "Attemperator", "CheckValve", "Condenser", "ControlValve", "DeadTime", "Drum",
    "EnthalpySensor", "FeedwaterTank", "FirstOrderLag", "Gain", "HeatExchanger",
    "LevelSensor", "Limiter", "MassFlowBoundary", "MassFlowSensor", "Mixer",
    "PIController", "PIDController", "Pipe", "PressureBoundary", "PressureSensor", "Pump",
    "QualitySensor", "Ramp", "RateLimiter", "Splitter", "SteamTurbine", "Step", "Sum",
    "Table", "TableSource", "TemperatureSensor", "Valve", "X",
]  # fmt: skip
#: media, among them gases where a drum, a tank or a condenser needs a condensable one
MEDIA = ["Water", "Air", "FlueGas", "Nitrogen", "IF97::Water", "HEOS::Water", "Steam", "x"]
#: a module a plant file may ask to import (written next to it): it must never run
#: without --allow-import; with it, it only leaves a marker file
MODULE = "fuzz_module_{n}"
MODULE_TEXT = "from pathlib import Path\nPath(__file__).with_suffix('.ran').write_text('ran')\n"


# --------------------------------------------------------------------------- mutations


def _paths(data, prefix=()):
    """Every (path, value) below ``data`` (tables and arrays included)."""
    out = []
    if isinstance(data, dict):
        for k, v in data.items():
            out.append((prefix + (k,), v))
            out.extend(_paths(v, prefix + (k,)))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            out.append((prefix + (i,), v))
            out.extend(_paths(v, prefix + (i,)))
    return out


def _parent(data, path):
    for k in path[:-1]:
        data = data[k]
    return data


def _new_value(old, rnd: random.Random):
    kind = rnd.randrange(5)
    if kind == 0:  # an extreme or odd number
        return rnd.choice(NUMBERS)
    if kind == 1 and isinstance(old, str):  # the same number with another unit
        number = old.split()[0] if old.split() else "1"
        return f"{number} {rnd.choice(UNITS)}".strip()
    if kind == 2:  # an extreme number with a plausible unit
        return (
            f"{rnd.choice(['1e30', '-5', '0', '1e-300', '5000', '1e6', '1e9'])} {rnd.choice(UNITS)}"
        )
    if kind == 3:  # a dangling name
        return rnd.choice(["nowhere", "sensr.T", "pi.zz", "n_1", "pipe.inlet", "x.y.z", "."])
    return rnd.choice(WRONG)


def mutate(data: dict, rnd: random.Random) -> str:
    """One to three random mutations of a decoded plant; returns TOML text."""
    data = copy.deepcopy(data)
    text_ops = []
    for _ in range(rnd.randint(1, 3)):
        paths = _paths(data)
        op = rnd.randrange(8)
        if not paths:
            break
        path, value = rnd.choice(paths)
        parent = _parent(data, path)
        key = path[-1]
        if op == 0:  # delete a key or an array element
            del parent[key]
        elif op in (1, 2, 3):  # a new value: wrong type, wrong unit, extreme, dangling
            parent[key] = _new_value(value, rnd)
        elif op == 4 and isinstance(parent, dict):  # an unknown or misspelt key
            parent[rnd.choice(["foo", str(key) + "_", "Kp", "opening", "n_volumes", "type"])] = (
                _new_value(value, rnd)
            )
        elif op == 5 and isinstance(value, dict) and "type" in value:  # another type
            value["type"] = rnd.choice(TYPES)
        elif op == 6 and isinstance(parent, dict) and isinstance(value, dict | int | float | str):
            parent[str(key) + "_copy"] = copy.deepcopy(value)  # a duplicated component/key
        elif op == 7 and rnd.random() < 0.5:  # another medium: for the plant, or one component
            comps = data.get("components")
            tables = [data.get("plant")] + (list(comps.values()) if isinstance(comps, dict) else [])
            table = rnd.choice([t for t in tables if isinstance(t, dict)] or [{}])
            table["medium"] = rnd.choice(MEDIA)
        elif op == 7 and rnd.random() < 0.3 and isinstance(data.get("plant"), dict):
            data["plant"]["import"] = [MODULE.format(n=rnd.randrange(3))]  # code next to it
        else:
            text_ops.append(rnd.choices((0, 1, 2, 3), weights=(9, 9, 2, 1))[0])
    try:
        text = tomli_w.dumps(data)
    except (TypeError, ValueError):  # e.g. an empty key
        text = ""
    lines = text.splitlines()
    for op in text_ops:
        if not lines:
            break
        i = rnd.randrange(len(lines))
        if op == 0:  # a duplicated line: the same key twice
            lines.insert(i, lines[i])
        elif op == 1:  # a deleted line
            del lines[i]
        elif op == 2:  # deep nesting
            lines.insert(i, "deep = " + "[" * 1000 + "]" * 1000)
        else:  # a byte that is not UTF-8 (latin-1 text; decoded back by ``classify``)
            lines.insert(i, "# caf\udce9")
    return "\n".join(lines) + "\n"


def base_plants() -> list[tuple[str, dict]]:
    return [(p.stem, tomllib.loads(p.read_text())) for p in PLANTS]


# --------------------------------------------------------------------------- running


class _Hang(BaseException):
    pass


def _alarm(signum, frame):
    raise _Hang()


#: sweep options: keys (some wrong), --output-interval values, scheduler addresses that
#: are refused before any connection (a valid one would wait for a cluster)
SWEEP_KEYS = ["simulation.t_end", "simulation.rtol", "simulation.output_interval", "x.y", "a"]
INTERVALS = ["0.1 s", "1e-9", "-1", "0", "abc", "1e300", "0.5 bar", "nan"]
SCHEDULERS = [
    "file:///etc/passwd", "http://127.0.0.1:8786", "inproc://x", "ucx://h:1", "tcp://[::1",
    "tcp://" + "h" * 300 + ":8786", "tcp://127.0.0.1", "tcp://127.0.0.1:0", "tcp://a b:1", "",
]  # fmt: skip
CASES_FILES = [
    b"simulation.t_end\n0.3\n0.5\n",
    b"simulation.t_end,simulation.t_end\n0.3,0.4\n",
    b"simulation.t_end\n0.3 \xb5s\n",
    b'simulation.t_end\n"' + b"9" * 140_000 + b'"\n',
    b"simulation.t_end\n0.3\x00\n",
    b"\xef\xbb\xbfsimulation.t_end [s]\n0.4\n",
    b'[[case]]\n"simulation.t_end" = 0.3\nsimulation = { t_end = 0.4 }\n',
    b"[[case]]\nsimulation.t_end = 0.3\n",
    b"=HYPERLINK(1)\n1\n",
]


def sweep_options(rnd: random.Random, workdir: str) -> list[str]:
    """Random options of ``dnasim sweep`` (always one local process, -j 1)."""
    args = ["-j", "1"]
    if rnd.random() < 0.5:
        name = "cases.toml" if rnd.random() < 0.2 else "cases.csv"
        path = os.path.join(workdir, name)
        with open(path, "wb") as f:
            f.write(rnd.choice(CASES_FILES))
        args += ["--cases", path]
    else:
        key = rnd.choice(SWEEP_KEYS)
        values = rnd.choice(["0.3,0.5", "0.4", "", "1e-9", "=cmd", "0.3 s,0.3 s", "[[[[1]]]]"])
        args += ["--set", f"{key}={values}"]
        if rnd.random() < 0.1:
            args += ["--set", f"{key}=0.4"]  # a key given twice
        if key != "simulation.t_end":  # short runs
            args += ["--set", "simulation.t_end=0.4"]
    if rnd.random() < 0.3:
        args += ["--output-interval", rnd.choice(INTERVALS)]
    if rnd.random() < 0.2:
        args += ["--scheduler", rnd.choice(SCHEDULERS)]
    if rnd.random() < 0.2:
        args.append("--allow-import")
    return args


def classify(
    command: str,
    text: str,
    workdir: str,
    timeout: float = 60.0,
    options: list[str] | None = None,
) -> tuple[str, str]:
    """Run ``dnasim check``, ``dnasim run`` (t_end 0.5 s) or ``dnasim sweep`` (with
    ``options``, see :func:`sweep_options`) on ``text``; returns (outcome, output).
    A ``[plant] import`` module is written next to the file; it must not run unless
    the command was given ``--allow-import`` (else the outcome is "internal")."""
    from click.testing import CliRunner

    from dnasim.cli.commands import main

    path = os.path.join(workdir, "fuzz.toml")
    with open(path, "w", encoding="utf-8", errors="surrogateescape") as f:
        f.write(text)  # "\udce9" (a lone surrogate) becomes the byte 0xe9: not UTF-8
    for n in range(3):
        module = os.path.join(workdir, MODULE.format(n=n))
        with open(module + ".py", "w", encoding="utf-8") as f:
            f.write(MODULE_TEXT)
        if os.path.exists(module + ".ran"):
            os.unlink(module + ".ran")
        sys.modules.pop(MODULE.format(n=n), None)
    options = list(options or [])
    args = [command, path]
    if command == "run":
        args += ["-o", os.path.join(workdir, "out"), "-q", "--t-end", "0.5 s"]
    elif command == "sweep":
        args += ["-o", os.path.join(workdir, "sweep"), "-q", *options]
    if "--allow-import" in options and command != "sweep":
        args.append("--allow-import")
    # the limit is on CPU time (ITIMER_PROF), not wall time: on a loaded machine at
    # nice 19 a case that needs 2 s of CPU may take a minute of wall time
    old = signal.signal(signal.SIGPROF, _alarm)
    signal.setitimer(signal.ITIMER_PROF, timeout)
    try:
        res = CliRunner().invoke(main, args, catch_exceptions=True)
    except _Hang:
        return "hang", ""
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, old)
    out = res.output
    ran = [
        n for n in range(3) if os.path.exists(os.path.join(workdir, MODULE.format(n=n) + ".ran"))
    ]
    if ran and "--allow-import" not in options:
        return "internal", f"a plant file ran code without --allow-import\n{out}"
    if isinstance(res.exception, _Hang):
        return "hang", out
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        return "traceback", f"{type(res.exception).__name__}: {res.exception}"
    if "Traceback" in out:
        return "traceback", out
    if "internal error" in out:
        return "internal", out
    if res.exit_code == 0:
        return "clean", out
    if res.exit_code == 1:
        return "ok", out
    if res.exit_code == 2 and (path in out or "fuzz.toml" in out or "option" in out):
        return "ok", out
    return "unlocated", out


def _case(seed: int, run_fraction: float, bases, workdir: str) -> tuple[str, str, list]:
    rnd = random.Random(seed)
    _, data = bases[rnd.randrange(len(bases))]
    text = mutate(data, rnd)
    x = rnd.random()
    command = "run" if x < run_fraction else "sweep" if x < 1.5 * run_fraction else "check"
    options = sweep_options(rnd, workdir) if command == "sweep" else []
    if command != "sweep" and rnd.random() < 0.05:
        options = ["--allow-import"]
    return command, text, options


def _chunk(args) -> list[tuple[int, str, str, str]]:
    seeds, run_fraction, timeout = args
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))  # a runaway case fails alone
    bases = base_plants()
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            command, text, options = _case(seed, run_fraction, bases, tmp)
            outcome, msg = classify(command, text, tmp, timeout, options)
            out.append((seed, command, outcome, msg.strip().splitlines()[-1][:300] if msg else ""))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10_000, help="number of mutated plants")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes")
    ap.add_argument(
        "--run-fraction",
        type=float,
        default=0.05,
        help="share run, not check (and half as many sweep)",
    )
    ap.add_argument("--timeout", type=float, default=60.0, help="CPU seconds before a hang")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--chunk", type=int, default=100, help="cases per task (the tally's step)")
    ap.add_argument("--show", type=int, default=5, help="examples printed per bad outcome")
    args = ap.parse_args(argv)
    seeds = list(range(args.seed, args.seed + args.n))
    k = args.chunk
    chunks = [seeds[i : i + k] for i in range(0, len(seeds), k)]
    tally: Counter = Counter()
    commands: Counter = Counter()
    examples: dict[str, list] = {}
    t0 = time.perf_counter()
    pending = [(c, 0) for c in chunks]  # (seeds, times their pool broke)
    while pending:
        with ProcessPoolExecutor(args.jobs) as pool:
            futures = [
                (c, broke, pool.submit(_chunk, (c, args.run_fraction, args.timeout)))
                for c, broke in pending
            ]
            pending = []
            for c, broke, fut in futures:
                try:
                    rows = fut.result()
                except BrokenProcessPool:
                    # A worker died, and the pool with it: every chunk still in it fails
                    # here. Run such a chunk again in a fresh pool; when it breaks a pool
                    # a second time, run its seeds one by one; a single seed that breaks
                    # a pool is the crash.
                    if broke == 0:
                        pending.append((c, 1))
                    elif len(c) > 1:
                        pending.extend(([s], 1) for s in c)
                    else:
                        tally["crash"] += 1
                        examples.setdefault("crash", []).append((c[0], "?", "worker died"))
                        print(f"  crash: seed {c[0]}", file=sys.stderr)
                    continue
                for seed, command, outcome, msg in rows:
                    tally[outcome] += 1
                    commands[command] += 1
                    if outcome not in ("clean", "ok"):
                        examples.setdefault(outcome, []).append((seed, command, msg))
                        print(f"  {outcome}: seed {seed} ({command}): {msg}", file=sys.stderr)
                # a running tally on stderr, so a run cut short still says how far it got
                print(
                    f"[{time.perf_counter() - t0:.0f} s] {sum(tally.values())} cases: "
                    + " / ".join(f"{o} {tally[o]}" for o in OUTCOMES),
                    file=sys.stderr,
                    flush=True,
                )
    wall = time.perf_counter() - t0
    for outcome, items in examples.items():
        print(f"{outcome}: {len(items)} (first {min(len(items), args.show)}):")
        for seed, command, msg in items[: args.show]:
            print(f"  seed {seed} ({command}): {msg}")
    print(
        f"{sum(tally.values())} mutated plants ({commands['check']} check, {commands['run']} run, "
        f"{commands['sweep']} sweep) "
        f"in {wall:.0f} s with {args.jobs} processes"
    )
    print(" / ".join(f"{o} {tally[o]}" for o in OUTCOMES))
    return 0


if __name__ == "__main__":
    sys.exit(main())
