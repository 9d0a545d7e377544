"""``dnasim.sweep(spec, cases, executor=None)``: run one plant for many parameter sets.

    import dnasim
    from dnasim.plant.plantfile import load
    spec = load("plants/attemperator.toml").spec
    sw = dnasim.sweep(spec, {"spray_valve.C": [0.002, 0.003], "steam.p": ["110 bar", "120 bar"]},
                      out_dir="sweep_out", executor=client.get_executor())
    sw.summary      # pandas DataFrame, one row per case (summary.csv)
    sw.dataset      # xarray Dataset over (case, time) (sweep.nc)

How it works:

* each case is applied to a copy of the spec (``dnasim.plant.cases.apply_case``: the
  plant file's validation and unit conversion) and run by ``run_case`` in a worker
  (any ``concurrent.futures.Executor``: a ``ProcessPoolExecutor``, a Dask client's
  ``get_executor()``; ``None`` runs the cases one after the other here). The worker
  receives the picklable ``PlantSpec`` and the case, runs ``dnasim.run.runner.run_plant``
  into a temporary directory and returns the files it wrote (results.csv,
  events.csv, steps.csv) with the status and counters; workers need no shared disk.
* this process writes each case's files into ``DIR/case_NNNN/`` and then, atomically,
  ``done.json`` (the case, status, message, counters, and the plant's fingerprint):
  the done marker. A sweep started again into the same DIR skips every case whose
  folder (the same position in the list of cases) has a marker with the same
  values *and* the same fingerprint, and runs the others (and those that ended
  "interrupted", with an internal "error" or an "output-error"). The fingerprint
  (:func:`plant_fingerprint`) is a SHA-256 of the plant spec (components,
  parameters, wiring, media, ``[simulation]`` settings with the sweep's output
  interval) and the dnasim version: a plant file edited, or another
  ``--output-interval``, runs the cases again instead of presenting the old
  plant's results as the new one's.
* a case that fails (the solver stops, or a value is refused: out of range, a plant
  that cannot be built) is recorded with status "failed" or "input-error" and its
  message; the other cases go on.
* at the start the previous ``summary.csv`` and ``sweep.nc`` are removed, and at
  the end both are rebuilt from the folders of all cases (``collect``), in memory
  first and then written atomically: a file that does not fit (full disk, file
  size limit) leaves neither file, no temporary file, and an
  :class:`~dnasim.core.errors.OutputError` naming the file and the cases that are safe.
  ``sweep.nc`` (h5netcdf) holds every output over
  (case, time): each case's rows interpolated linearly to one time grid
  (``output_interval`` [s], else the plant's, else 501 points from t_start to
  the largest t_end); NaN outside the times a case reached. At a restart (two rows
  at one time) the state after it is used. Case parameters are coordinates over
  ``case`` in SI, with ``units`` attributes.
"""

from __future__ import annotations

import concurrent.futures as cf
import hashlib
import json
import math
import os
import signal
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dnasim.core.errors import OutputError
from dnasim.plant.cases import CaseError, apply_case, case_units, check_cases, product_cases

__all__ = [
    "LocalPool",
    "SweepResult",
    "collect",
    "local_pool",
    "plant_fingerprint",
    "run_case",
    "sweep",
]

#: files of a case folder that come from the worker
CASE_FILES = ("results.csv", "events.csv", "steps.csv")
#: the done marker of a case folder, written last and atomically
DONE_MARKER = "done.json"
#: time points of the common grid when no output interval is given
DEFAULT_GRID_POINTS = 501
#: the files ``collect`` builds from the case folders (removed when a sweep starts)
COLLECTED_FILES = ("summary.csv", "sweep.nc")
#: seconds between two looks of a local worker at its parent process
PARENT_POLL_SECONDS = 0.5


@dataclass
class SweepResult:
    """What a sweep produced: ``summary`` (pandas DataFrame, = summary.csv),
    ``dataset`` (xarray Dataset over case and time, = sweep.nc), the directory,
    and how many cases ran now (``ran``) and were skipped as already done."""

    out_dir: Path
    summary: Any
    dataset: Any
    cases: list
    ran: int
    skipped: int
    #: cases run again because their folder held the results of another plant or
    #: other settings (another fingerprint)
    changed: int = 0

    @property
    def failed(self) -> int:
        """Number of cases whose status is not "finished"."""
        return int((self.summary["status"] != "finished").sum())

    def __repr__(self):
        return (
            f"SweepResult({len(self.cases)} cases in {self.out_dir}: ran {self.ran}, "
            f"skipped {self.skipped}, failed {self.failed})"
        )


# --------------------------------------------------------------------------- worker


def run_case(spec, case: dict, index: int = 0) -> dict:
    """Run one case in this process (the function a worker executes).

    Returns a dict: index, case, status ("finished", "failed", "interrupted",
    "input-error", "error"), message, t_end and t_reached [s], steps, events,
    wall_time [s], stats (solver counters) and files (file name -> bytes)."""
    global _case_tmp
    t_start = time.perf_counter()
    rec: dict[str, Any] = {
        "index": index,
        "case": case,
        "status": "error",
        "message": "",
        "t_end": math.nan,
        "t_reached": None,
        "steps": 0,
        "events": 0,
        "stats": {},
        "files": {},
    }
    with tempfile.TemporaryDirectory(prefix="dnasim-case-") as tmp:
        _case_tmp = tmp  # removed by a local worker that stops (``_exit_worker``)
        try:
            _run_case_in(spec, case, rec, tmp)
        finally:
            _case_tmp = None
    rec["wall_time"] = time.perf_counter() - t_start
    return rec


def _run_case_in(spec, case, rec, tmp) -> None:
    from dnasim.core.errors import DnasimError, PlantError
    from dnasim.plant.plantfile import LoadedPlant
    from dnasim.plant.spec import build_plant
    from dnasim.run.runner import run_plant

    try:
        s = apply_case(spec, case)
        rec["t_end"] = s.simulation.t_end
        loaded = LoadedPlant(build_plant(s), s.simulation, s, s.path)
        outcome = run_plant(loaded, tmp)
    except PlantError as exc:
        rec["status"], rec["message"] = "input-error", str(exc)
    except OutputError as exc:  # the worker's temporary directory is full
        rec["status"], rec["message"] = "output-error", str(exc)
    except DnasimError as exc:
        rec["status"], rec["message"] = "failed", str(exc)
    except Exception as exc:  # one case's bug must not stop the sweep
        rec["message"] = f"internal error: {type(exc).__name__}: {exc}"
    else:
        rec["status"] = outcome.status
        rec["message"] = outcome.message if outcome.success else outcome.failure_message()
        # the worker's temporary directory means nothing to the reader
        rec["message"] = rec["message"].replace(str(Path(tmp)) + os.sep, "")
        rec["t_reached"] = outcome.t_reached
        rec["steps"], rec["events"] = outcome.n_steps, outcome.n_events
        rec["stats"] = {k: v for k, v in outcome.stats.items() if isinstance(v, int | float | str)}
    for name in CASE_FILES:
        p = Path(tmp) / name
        if p.exists():
            rec["files"][name] = p.read_bytes()


# --------------------------------------------------------------------------- local workers

#: the temporary directory of the case ``run_case`` runs in this process, or None
_case_tmp: str | None = None


def _exit_worker() -> None:
    """Stop a local worker at once: its case's temporary directory removed first (the
    solver may be anywhere; nothing of the case is kept), then ``os._exit``."""
    tmp = _case_tmp
    if tmp is not None:
        import shutil

        shutil.rmtree(tmp, ignore_errors=True)
    os._exit(1)


def _worker_sigterm(signum, frame):
    _exit_worker()


def _watch_parent(parent_pid: int) -> None:
    """A local worker's thread: when the sweep's process is gone (the worker was
    handed to another parent), stop the worker (``_exit_worker``)."""
    while os.getppid() == parent_pid:
        time.sleep(PARENT_POLL_SECONDS)
    _exit_worker()


def _worker_init(parent_pid: int) -> None:
    """Initializer of a local worker process (``local_pool``): it exits when the
    sweep's process dies, even by SIGKILL (an out-of-memory kill, a CI time-out),
    instead of running on and holding the sweep's stdout open. On Linux the kernel
    sends SIGTERM at the parent's death (``prctl(PR_SET_PDEATHSIG)``); everywhere a
    thread checks the parent every ``PARENT_POLL_SECONDS``."""
    signal.signal(signal.SIGTERM, _worker_sigterm)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the sweep's to handle
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGTERM, 0, 0, 0)  # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):  # no libc prctl: the thread alone
            pass
    if os.getppid() != parent_pid:  # the parent died before the line above
        os._exit(1)
    threading.Thread(
        target=_watch_parent, args=(parent_pid,), name="dnasim-parent-watch", daemon=True
    ).start()


class LocalPool(cf.ProcessPoolExecutor):
    """``n`` local worker processes, spawned (no threads of this process are copied),
    that exit when this process dies (``_worker_init``). Create it in the thread that
    keeps running while it is used (the main thread): on Linux a worker is signalled
    when the thread that started it ends."""

    def __init__(self, n: int):
        import multiprocessing

        super().__init__(
            max_workers=n,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_worker_init,
            initargs=(os.getpid(),),
        )

    def terminate_workers(self) -> None:
        """SIGTERM to every worker (each removes its case's temporary directory and exits):
        after an interrupt or an output error, so that ``shutdown`` does not wait for
        the cases still running."""
        for proc in list((getattr(self, "_processes", None) or {}).values()):
            try:
                proc.terminate()
            except (OSError, ValueError, AttributeError):
                pass


def local_pool(n: int) -> LocalPool:
    """The executor of ``dnasim sweep -j N``: see :class:`LocalPool`."""
    return LocalPool(n)


# --------------------------------------------------------------------------- case folders


def case_dir(out_dir, index: int) -> Path:
    return Path(out_dir) / f"case_{index:04d}"


def _canonical(case: dict) -> Any:
    return json.loads(json.dumps(case, sort_keys=True, default=str))


def _plain(value, depth: int = 0) -> Any:
    """A parameter value as JSON data that is equal exactly when the value is: floats
    by ``repr`` (every bit; NaN and inf too), arrays as lists, time functions and
    other objects by their type and attributes."""
    if depth > 50:
        return repr(value)
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, np.ndarray | np.generic):
        return _plain(value.tolist(), depth + 1)
    if isinstance(value, list | tuple):
        return [_plain(v, depth + 1) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v, depth + 1) for k, v in sorted(value.items(), key=str)}
    attrs = getattr(value, "__dict__", None)
    if attrs is None:
        return repr(value)
    return {"type": type(value).__qualname__, **_plain(attrs, depth + 1)}


def plant_fingerprint(spec) -> str:
    """SHA-256 (hex) of what decides a case's results besides its own values: the
    dnasim version, the components (type, parameters in SI, ports, inputs), the
    plant's medium and modules, and the ``[simulation]`` settings (with the sweep's
    output interval). The file's path, the plant's name and description are left
    out (a moved or renamed file is the same plant)."""
    data = {
        "dnasim": _version(),
        "medium": spec.medium,
        "imports": list(spec.imports),
        "simulation": _plain(asdict(spec.simulation)),
        "components": [
            {
                "name": c.name,
                "type": c.type,
                "params": _plain(c.params),
                "ports": _plain(c.ports),
                "inputs": _plain(c.inputs),
            }
            for c in spec.components
        ],
    }
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("dnasim")
    except PackageNotFoundError:
        return "unknown"


#: statuses of a case that a restarted sweep runs again (the others are final)
RUN_AGAIN = ("interrupted", "error", "output-error")


def _read_marker(out_dir, index: int) -> dict | None:
    try:
        rec = json.loads((case_dir(out_dir, index) / DONE_MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return rec if isinstance(rec, dict) else None


def _done_record(out_dir, index: int, case: dict, fingerprint: str | None = None) -> dict | None:
    """The done marker of case ``index`` if it holds the same case values and (when
    given) the same plant fingerprint, else None."""
    rec = _read_marker(out_dir, index)
    if rec is None or rec.get("case") != _canonical(case):
        return None
    if fingerprint is not None and rec.get("fingerprint") != fingerprint:
        return None
    return rec


def _is_done(out_dir, index: int, case: dict, fingerprint: str | None = None) -> bool:
    rec = _done_record(out_dir, index, case, fingerprint)
    return rec is not None and rec.get("status") not in RUN_AGAIN


def _write_case(out_dir, rec: dict, fingerprint: str | None = None) -> None:
    """The worker's files into the case folder, then the done marker (atomically).
    A file that cannot be written leaves the folder without files and marker."""
    from dnasim.run.output import _atomic_write, clear_results

    d = case_dir(out_dir, rec["index"])
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        from dnasim.run.output import _oserror_text

        raise OutputError(f"cannot create {d}: {_oserror_text(exc)}", path=d) from None
    (d / DONE_MARKER).unlink(missing_ok=True)
    clear_results(d)
    marker = {k: v for k, v in rec.items() if k != "files"}
    marker["case"] = _canonical(rec["case"])
    marker["fingerprint"] = fingerprint
    text = json.dumps(marker, indent=1, default=str).encode()
    try:
        for name, data in rec["files"].items():
            _atomic_write(d / name, lambda f, data=data: f.write(data))
        _atomic_write(d / DONE_MARKER, lambda f: f.write(text))
    except OutputError:
        try:
            clear_results(d)
        except OutputError:
            pass
        raise


def _remove_collected(out: Path) -> None:
    """The previous summary.csv and sweep.nc (and any temporary file of them): they
    describe the cases as they were, and are rebuilt at the end."""
    from dnasim.run.output import _oserror_text

    names = [*COLLECTED_FILES, ".sweep.nc.tmp"]
    names += [p.name for p in out.glob(".summary.csv.*.tmp")]
    names += [p.name for p in out.glob(".sweep.nc.*.tmp")]
    for name in names:
        try:
            os.unlink(out / name)
        except FileNotFoundError:
            pass
        except OSError as exc:
            raise OutputError(
                f"cannot remove the previous {out / name}: {_oserror_text(exc)}", path=out / name
            ) from None


def safe_cases_text(out_dir, cases, fingerprint: str | None) -> str:
    """Which cases of the sweep are safe on disk (their folder has a done marker of
    this plant), in words, for a message after an output error."""
    done = [i for i, c in enumerate(cases) if _is_done(out_dir, i, c, fingerprint)]
    if not done:
        return f"No case of the {len(cases)} is complete in {out_dir} yet"
    names = ", ".join(case_dir(out_dir, i).name for i in done[:8])
    more = f" and {len(done) - 8} more" if len(done) > 8 else ""
    return (
        f"{len(done)} of the {len(cases)} cases are complete and safe in {out_dir} "
        f"({names}{more}: results.csv, events.csv, steps.csv and done.json each)"
    )


def output_failure(exc: OutputError, out_dir, cases, fingerprint) -> OutputError:
    """``exc`` as the one paragraph of a sweep whose output does not fit: the file and
    why, the cases that are safe, and how to resume."""
    msg = (
        f"{exc}. {safe_cases_text(out_dir, cases, fingerprint)}; summary.csv and sweep.nc "
        "were not written. Free disk space (or raise the file size limit) and start the "
        "same command again: the complete cases are skipped, the others run, and "
        "summary.csv and sweep.nc are rebuilt"
    )
    return OutputError(msg, path=getattr(exc, "path", None))


# --------------------------------------------------------------------------- the sweep


def _as_spec(spec):
    """A ``PlantSpec`` from a PlantSpec, a ``LoadedPlant`` or a plant file path."""
    from dnasim.plant.spec import PlantSpec

    if isinstance(spec, PlantSpec):
        return spec
    if isinstance(spec, str | os.PathLike):
        from dnasim.plant.plantfile import load

        return load(spec).spec
    inner = getattr(spec, "spec", None)
    if isinstance(inner, PlantSpec):
        return inner
    raise TypeError(f"sweep(): expected a PlantSpec, a LoadedPlant or a path, got {spec!r}")


def _case_settings(spec, case):
    """The ``[simulation]`` settings case ``case`` runs with (None when its values
    are invalid: the case reports that itself)."""
    from dnasim.core.errors import Problems
    from dnasim.plant.plantfile import _simulation

    values = {k.partition(".")[2]: v for k, v in case.items() if k.startswith("simulation.")}
    if not values:
        return spec.simulation
    raw = {k: v for k, v in asdict(spec.simulation).items() if v is not None}
    if "output_interval" in values:
        raw.pop("t_eval", None)  # a case's output interval replaces the file's times
    raw.update(values)
    errors = Problems(str(spec.path), None)
    sim = _simulation({"simulation": raw}, errors)
    # the output points are checked by the caller; another bad value is the case's own
    others = [e for e in errors.items if "key 'output_interval'" not in e]
    return None if others else sim


def check_output_sizes(spec, cases, output_interval=None) -> None:
    """Raise ``CaseError`` before anything runs when a case asks for more output
    rows than ``dnasim run`` allows (``LIMITS["output_points"]``), or the time grid
    of sweep.nc (``output_interval`` from t_start to the largest t_end) does, or
    the cases times that grid do."""
    from dnasim.core.errors import PlantError
    from dnasim.core.values import LIMITS
    from dnasim.plant.spec import output_point_count

    limit = LIMITS["output_points"]
    try:
        spec.simulation.check_output_points()
    except PlantError as exc:
        raise CaseError(str(exc)) from None
    t_ends = [spec.simulation.t_end]
    for i, case in enumerate(cases):
        if not any(k.startswith("simulation.") for k in case):
            continue
        sim = _case_settings(spec, case)
        if sim is None:
            continue
        try:
            sim.check_output_points()
        except PlantError as exc:
            raise CaseError(f"case {i} ({_case_label(case)}): {exc}") from None
        t_ends.append(sim.t_end)
    dt = output_interval if output_interval is not None else spec.simulation.output_interval
    if dt is None or not t_ends:
        return
    t0 = spec.simulation.t_start
    n = output_point_count(t0, max(t_ends), dt)
    total = n * len(cases)
    if not n <= limit or not total <= limit:
        raise CaseError(
            f"the time grid of sweep.nc (every {dt:g} s from {t0:g} s to {max(t_ends):g} s) "
            f"has {n:g} points, {total:g} for the {len(cases)} cases: above the limit of "
            f"{limit:g} output points; choose a longer --output-interval"
        )


def _case_label(case: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in case.items())


def sweep(
    spec,
    cases,
    executor: cf.Executor | None = None,
    *,
    out_dir=None,
    output_interval: float | None = None,
    progress: bool | None = None,
) -> SweepResult:
    """Run ``spec`` (a PlantSpec, LoadedPlant or plant file) for every case.

    cases: a list of dicts ``{"COMPONENT.PARAMETER": value}`` or a dict of lists
    (their Cartesian product); values as in a plant file ("520 degC", 0.01).
    executor: any ``concurrent.futures.Executor`` (None: one after the other, here).
    out_dir: the sweep directory (default: a new temporary directory); cases done
    there before with the same values and the same plant (``plant_fingerprint``)
    are skipped, the others run (again). output_interval [s]: rows of each case's
    results.csv and the time grid of sweep.nc. progress: a progress bar of the cases
    (tqdm: on stdout in a terminal, the widget in Jupyter; default: when stdout is a
    terminal).

    Raises ``dnasim.plant.cases.CaseError`` for an unknown component or parameter, a
    value of the wrong unit or more output points than allowed (before anything
    runs), and ``OutputError`` when a file does not fit (the message says which
    cases are safe); a case that fails is recorded, never raised.
    """
    spec = _as_spec(spec)
    if isinstance(cases, dict):
        cases = product_cases(cases)
    cases = [dict(c) for c in cases]
    check_cases(spec, cases)
    if output_interval is not None:
        import copy

        spec = copy.deepcopy(spec)
        spec.simulation.output_interval = float(output_interval)
        spec.simulation.t_eval = None  # replaced by the interval
    check_output_sizes(spec, cases, output_interval)
    fingerprint = plant_fingerprint(spec)
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="dnasim-sweep-"))
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        from dnasim.run.output import _oserror_text

        raise OutputError(f"cannot create {out}: {_oserror_text(exc)}", path=out) from None
    todo = [i for i, c in enumerate(cases) if not _is_done(out, i, c, fingerprint)]
    changed = sum(
        1
        for i in todo
        if _done_record(out, i, cases[i]) is not None
        and _done_record(out, i, cases[i], fingerprint) is None
    )
    _remove_collected(out)
    if progress is None:
        progress = sys.stdout.isatty()
    bar = _bar(len(todo)) if progress and todo else None
    try:
        if executor is None:
            for i in todo:
                _write_case(out, run_case(spec, cases[i], i), fingerprint)
                if bar is not None:
                    bar.update(1)
        else:
            futures = {executor.submit(run_case, spec, cases[i], i): i for i in todo}
            try:
                for fut in cf.as_completed(futures):
                    i = futures[fut]
                    try:
                        rec = fut.result()
                    except Exception as exc:  # the worker died (BrokenProcessPool, KilledWorker)
                        rec = {
                            "index": i,
                            "case": cases[i],
                            "status": "error",
                            "message": f"the worker running this case failed: "
                            f"{type(exc).__name__}: {exc}",
                            "files": {},
                        }
                    _write_case(out, rec, fingerprint)
                    if bar is not None:
                        bar.update(1)
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    except OutputError as exc:
        raise output_failure(exc, out, cases, fingerprint) from None
    finally:
        if bar is not None:
            bar.close()
    try:
        summary, dataset = collect(
            spec, cases, out, output_interval=output_interval, fingerprint=fingerprint
        )
    except OutputError as exc:
        raise output_failure(exc, out, cases, fingerprint) from None
    return SweepResult(
        out,
        summary,
        dataset,
        cases,
        ran=len(todo),
        skipped=len(cases) - len(todo),
        changed=changed,
    )


def _bar(n: int):
    """The cases' progress bar (tqdm.auto: text on stdout in a terminal, the notebook
    widget in Jupyter, as ``dnasim.run.progress``); ``update(1)`` a case, ``close()``."""
    from dnasim.run.progress import _tqdm_class

    return _tqdm_class()(total=n, desc="cases", unit="case", file=sys.stdout, leave=True)


# --------------------------------------------------------------------------- collecting


def _si_value(value, unit: str, atmosphere: float | None = None):
    """A case value in SI (float) when it is a number or a quantity; else its text.
    Gauge pressures ("5 barg") against ``atmosphere`` [Pa] (the plant's)."""
    from dnasim.core.units import UnitError, convert_quantity

    if isinstance(value, bool) or isinstance(value, dict | list):
        return json.dumps(value) if not isinstance(value, bool) else str(value).lower()
    if unit:
        try:
            return float(convert_quantity(value, unit, atmosphere=atmosphere))
        except (UnitError, TypeError, ValueError):
            pass
    return str(value)


def _read_case(d: Path):
    """(names, units, data) of a case's results.csv, or None; restart rows removed
    (of two rows at one time the state after the restart is kept)."""
    from dnasim.run.output import read_results_csv

    p = d / "results.csv"
    if not p.exists():
        return None
    try:
        names, units, data = read_results_csv(p)
    except (OSError, ValueError, StopIteration):
        return None
    t = np.asarray(data["time"], dtype=float)
    keep = np.r_[t[1:] > t[:-1], True] if t.size else np.zeros(0, bool)
    names = [n for n in names[1:] if n != "restart"]
    return names, units, {n: np.asarray(data[n], float)[keep] for n in ["time", *names]}


def _grid(spec, records, output_interval):
    t0 = spec.simulation.t_start
    ends = [r.get("t_end") for r in records if r and np.isfinite(r.get("t_end", math.nan))]
    t1 = max(ends) if ends else spec.simulation.t_end
    dt = output_interval if output_interval is not None else spec.simulation.output_interval
    if dt is None and output_interval is None and spec.simulation.t_eval is not None:
        return np.array(spec.simulation.t_eval, dtype=float)  # the file's output times
    if dt is None:
        return np.linspace(t0, t1, DEFAULT_GRID_POINTS)
    n = int(math.floor((t1 - t0) / dt + 1e-9))
    t = t0 + dt * np.arange(n + 1)
    if t[-1] < t1 - 1e-9 * max(1.0, abs(t1)):
        t = np.append(t, t1)
    return t


def collect(spec, cases, out_dir, *, output_interval=None, fingerprint=None):
    """Build ``summary.csv`` and ``sweep.nc`` in ``out_dir`` from the case folders of
    ``cases``; returns (summary DataFrame, xarray Dataset).

    Only folders whose done marker holds this plant's fingerprint (``fingerprint``,
    default ``plant_fingerprint`` of ``spec`` with ``output_interval``) are read;
    the others are "not run". Both files are made in memory and then written
    atomically, sweep.nc first; when one does not fit, neither is left and
    ``OutputError`` names the file."""
    import pandas as pd
    import xarray as xr

    from dnasim.run.output import _atomic_write, column_header, spreadsheet_frame

    out = Path(out_dir)
    if fingerprint is None:
        if output_interval is not None:
            import copy

            spec = copy.deepcopy(spec)
            spec.simulation.output_interval = float(output_interval)
        spec.simulation.t_eval = None  # replaced by the interval
        fingerprint = plant_fingerprint(spec)
    keys = list(dict.fromkeys(k for c in cases for k in c))
    punits = case_units(spec, keys)
    records, tables = [], []
    for i, case in enumerate(cases):
        rec = _done_record(out, i, case, fingerprint)
        if rec is None:
            rec = {"status": "not run", "message": "the case has not run", "case": case}
            tables.append(None)
        else:
            tables.append(_read_case(case_dir(out, i)))
        records.append(rec)
    # outputs: the union over the cases, in the order of their first appearance
    names, units = [], {}
    for tab in tables:
        if tab is not None:
            for n in tab[0]:
                if n not in units:
                    names.append(n)
                    units[n] = tab[1].get(n, "")
    grid = _grid(spec, records, output_interval)
    _check_memory(len(cases) * grid.size * len(names), out / "sweep.nc")

    rows = []
    arrays = {n: np.full((len(cases), grid.size), np.nan) for n in names}
    for i, (case, rec, tab) in enumerate(zip(cases, records, tables, strict=True)):
        row = {"case": i}
        for k in keys:
            row[column_header(k, punits[k]) if punits[k] else k] = (
                _si_value(case[k], punits[k], spec.atmosphere) if k in case else None
            )
        row["status"] = rec.get("status")
        row["message"] = rec.get("message", "")
        row[column_header("t_reached", "s")] = rec.get("t_reached")
        row["steps"] = rec.get("steps")
        row["events"] = rec.get("events")
        row[column_header("wall_time", "s")] = rec.get("wall_time")
        if tab is not None:
            data = tab[2]
            t = data["time"]
            for n in names:
                v = data.get(n)
                if v is None or v.size == 0:
                    continue
                arrays[n][i] = np.interp(grid, t, v, left=np.nan, right=np.nan)
                u = units[n]
                row[column_header(f"{n} final", u)] = v[-1]
                row[column_header(f"{n} min", u)] = np.nanmin(v)
                row[column_header(f"{n} max", u)] = np.nanmax(v)
        rows.append(row)
    summary = pd.DataFrame(rows)
    summary_bytes = spreadsheet_frame(summary).to_csv(index=False).encode("utf-8")

    coords = {
        "case": np.arange(len(cases)),
        "time": xr.Variable(("time",), grid, attrs={"units": "s"}),
    }
    for k in keys:
        vals = [_si_value(c[k], punits[k], spec.atmosphere) if k in c else None for c in cases]
        # a parameter that is also an output (pi.setpoint): the coordinate says so
        cname = f"{k} (parameter)" if k in units else k
        if all(isinstance(v, float) for v in vals):
            coords[cname] = xr.Variable(
                ("case",), np.array(vals), attrs={"units": punits[k] or "1"}
            )
        else:
            coords[cname] = xr.Variable(
                ("case",), np.array(["" if v is None else str(v) for v in vals])
            )
    data_vars = {
        n: xr.Variable(("case", "time"), arrays[n], attrs={"units": units[n] or "1"}) for n in names
    }
    data_vars["status"] = xr.Variable(("case",), np.array([str(r.get("status")) for r in records]))
    data_vars["message"] = xr.Variable(
        ("case",), np.array([str(r.get("message", "")) for r in records])
    )
    for k, u in (("steps", "1"), ("events", "1"), ("wall_time", "s"), ("t_reached", "s")):
        vals = [r.get(k) for r in records]
        data_vars[k] = xr.Variable(
            ("case",),
            np.array([math.nan if v is None else float(v) for v in vals]),
            attrs={"units": u},
        )
    ds = xr.Dataset(
        data_vars,
        coords=coords,
        attrs={
            "plant": spec.name,
            "plant_file": str(spec.path),
            "parameters": json.dumps(keys),
            "title": f"dnasim sweep of {spec.name}: {len(cases)} cases",
        },
    )
    # made in memory, then written as any result file: a file that does not fit
    # fails in our own write (OutputError), never inside HDF5
    nc_bytes = _netcdf_bytes(ds)
    _atomic_write(out / "sweep.nc", lambda f: f.write(nc_bytes))
    try:
        _atomic_write(out / "summary.csv", lambda f: f.write(summary_bytes))
    except OutputError:
        (out / "sweep.nc").unlink(missing_ok=True)  # the two files or neither
        raise
    return summary, ds


def _netcdf_bytes(ds) -> memoryview:
    """``ds`` as the bytes of a netCDF-4 file (h5netcdf), made in memory. With a Dask
    client active xarray would take a cluster-wide lock named after the memory
    buffer, which the scheduler does not know: the local synchronous scheduler's
    lock is used instead (the data are in memory, nothing is computed)."""
    if "dask" in sys.modules:
        import dask

        with dask.config.set(scheduler="synchronous"):
            return ds.to_netcdf(engine="h5netcdf")
    return ds.to_netcdf(engine="h5netcdf")


def _check_memory(values: int, path: Path) -> None:
    """Refuse to build a sweep.nc of ``values`` floats when it would not fit in a
    quarter of this machine's memory (it is held twice while written)."""
    from dnasim.core.errors import OutputError

    try:
        budget = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 4
    except (ValueError, OSError, AttributeError):
        budget = 1 << 31
    need = 16 * values
    if need > budget:
        raise OutputError(
            f"cannot build {path}: its {values:g} values would need {need / 2**30:.3g} GiB of "
            f"memory, more than this machine can spare ({budget / 2**30:.3g} GiB); choose a "
            "longer --output-interval",
            path=path,
        )
