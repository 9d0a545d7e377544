"""``dnasim.sweep(spec, cases, executor=None)``: run one plant for many parameter sets.

    import dnasim
    from dnasim.plantfile import load
    spec = load("plants/attemperator.toml").spec
    sw = dnasim.sweep(spec, {"spray_valve.C": [0.002, 0.003], "steam.p": ["110 bar", "120 bar"]},
                      out_dir="sweep_out", executor=client.get_executor())
    sw.summary      # pandas DataFrame, one row per case (summary.csv)
    sw.dataset      # xarray Dataset over (case, time) (sweep.nc)

How it works:

* each case is applied to a copy of the spec (``dnasim.cases.apply_case``: the
  plant file's validation and unit conversion) and run by ``run_case`` in a worker
  (any ``concurrent.futures.Executor``: a ``ProcessPoolExecutor``, a Dask client's
  ``get_executor()``; ``None`` runs the cases one after the other here). The worker
  receives the picklable ``PlantSpec`` and the case, runs ``dnasim.runner.run_plant``
  into a temporary directory and returns the files it wrote (results.csv,
  events.csv, steps.csv) with the status and counters; workers need no shared disk.
* this process writes each case's files into ``DIR/case_NNNN/`` and then, atomically,
  ``done.json`` (the case, status, message, counters): the done marker. A sweep
  started again into the same DIR skips every case whose folder (the same position
  in the list of cases) has a marker with the same values, and runs the others
  (and those that ended "interrupted" or with an internal "error").
* a case that fails (the solver stops, or a value is refused: out of range, a plant
  that cannot be built) is recorded with status "failed" or "input-error" and its
  message; the other cases go on.
* at the end ``summary.csv`` and ``sweep.nc`` are rebuilt from the folders of all
  cases (``collect``). ``sweep.nc`` (h5netcdf) holds every output over
  (case, time): each case's rows interpolated linearly to one time grid
  (``output_interval`` [s], else the plant's, else 501 points from t_start to
  the largest t_end); NaN outside the times a case reached. At a restart (two rows
  at one time) the state after it is used. Case parameters are coordinates over
  ``case`` in SI, with ``units`` attributes.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from dnasim.cases import apply_case, case_units, check_cases, product_cases

__all__ = ["SweepResult", "collect", "run_case", "sweep"]

#: files of a case folder that come from the worker
CASE_FILES = ("results.csv", "events.csv", "steps.csv")
#: the done marker of a case folder, written last and atomically
DONE_MARKER = "done.json"
#: time points of the common grid when no output interval is given
DEFAULT_GRID_POINTS = 501


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
    from dnasim.errors import DnasimError, PlantError
    from dnasim.plantfile import LoadedPlant
    from dnasim.runner import run_plant
    from dnasim.spec import build_plant

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
        try:
            s = apply_case(spec, case)
            rec["t_end"] = s.simulation.t_end
            loaded = LoadedPlant(build_plant(s), s.simulation, s, s.path)
            outcome = run_plant(loaded, tmp)
        except PlantError as exc:
            rec["status"], rec["message"] = "input-error", str(exc)
        except DnasimError as exc:
            rec["status"], rec["message"] = "failed", str(exc)
        except Exception as exc:  # one case's bug must not stop the sweep
            rec["message"] = f"internal error: {type(exc).__name__}: {exc}"
        else:
            rec["status"] = outcome.status
            rec["message"] = outcome.message if outcome.success else outcome.failure_message()
            # the worker's temporary directory means nothing to the reader
            rec["message"] = rec["message"].replace(str(Path(tmp) / "results.csv"), "results.csv")
            rec["t_reached"] = outcome.t_reached
            rec["steps"], rec["events"] = outcome.n_steps, outcome.n_events
            rec["stats"] = {
                k: v for k, v in outcome.stats.items() if isinstance(v, int | float | str)
            }
        for name in CASE_FILES:
            p = Path(tmp) / name
            if p.exists():
                rec["files"][name] = p.read_bytes()
    rec["wall_time"] = time.perf_counter() - t_start
    return rec


# --------------------------------------------------------------------------- case folders


def case_dir(out_dir, index: int) -> Path:
    return Path(out_dir) / f"case_{index:04d}"


def _canonical(case: dict) -> Any:
    return json.loads(json.dumps(case, sort_keys=True, default=str))


#: statuses of a case that a restarted sweep runs again (the others are final)
RUN_AGAIN = ("interrupted", "error")


def _done_record(out_dir, index: int, case: dict) -> dict | None:
    """The done marker of case ``index`` if it holds the same case values, else None."""
    try:
        rec = json.loads((case_dir(out_dir, index) / DONE_MARKER).read_text())
    except (OSError, ValueError):
        return None
    return rec if rec.get("case") == _canonical(case) else None


def _is_done(out_dir, index: int, case: dict) -> bool:
    rec = _done_record(out_dir, index, case)
    return rec is not None and rec.get("status") not in RUN_AGAIN


def _write_case(out_dir, rec: dict) -> None:
    """The worker's files into the case folder, then the done marker (atomically)."""
    from dnasim.output import _atomic_write, clear_results

    d = case_dir(out_dir, rec["index"])
    d.mkdir(parents=True, exist_ok=True)
    (d / DONE_MARKER).unlink(missing_ok=True)
    clear_results(d)
    for name, data in rec["files"].items():
        _atomic_write(d / name, lambda f, data=data: f.write(data))
    marker = {k: v for k, v in rec.items() if k != "files"}
    marker["case"] = _canonical(rec["case"])
    text = json.dumps(marker, indent=1, default=str).encode()
    _atomic_write(d / DONE_MARKER, lambda f: f.write(text))


# --------------------------------------------------------------------------- the sweep


def _as_spec(spec):
    """A ``PlantSpec`` from a PlantSpec, a ``LoadedPlant`` or a plant file path."""
    from dnasim.spec import PlantSpec

    if isinstance(spec, PlantSpec):
        return spec
    if isinstance(spec, str | os.PathLike):
        from dnasim.plantfile import load

        return load(spec).spec
    inner = getattr(spec, "spec", None)
    if isinstance(inner, PlantSpec):
        return inner
    raise TypeError(f"sweep(): expected a PlantSpec, a LoadedPlant or a path, got {spec!r}")


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
    there before with the same values are skipped. output_interval [s]: rows of each
    case's results.csv and the time grid of sweep.nc. progress: a progress bar
    (default: when stdout is a terminal).

    Raises ``dnasim.cases.CaseError`` for an unknown component or parameter or a
    value of the wrong unit; a case that fails is recorded, never raised.
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
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="dnasim-sweep-"))
    out.mkdir(parents=True, exist_ok=True)
    todo = [i for i, c in enumerate(cases) if not _is_done(out, i, c)]
    if progress is None:
        progress = sys.stdout.isatty()
    bar = _bar(len(todo)) if progress and todo else None
    try:
        if executor is None:
            for i in todo:
                _write_case(out, run_case(spec, cases[i], i))
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
                    _write_case(out, rec)
                    if bar is not None:
                        bar.update(1)
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    finally:
        if bar is not None:
            bar.__exit__(None, None, None)
    summary, dataset = collect(spec, cases, out, output_interval=output_interval)
    return SweepResult(out, summary, dataset, cases, ran=len(todo), skipped=len(cases) - len(todo))


def _bar(n: int):
    import click

    bar = click.progressbar(length=n, label="cases", show_eta=True, show_pos=True, width=30)
    bar.__enter__()
    return bar


# --------------------------------------------------------------------------- collecting


def _si_value(value, unit: str, atmosphere: float | None = None):
    """A case value in SI (float) when it is a number or a quantity; else its text.
    Gauge pressures ("5 barg") against ``atmosphere`` [Pa] (the plant's)."""
    from dnasim.units import UnitError, convert_quantity

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
    from dnasim.output import read_results_csv

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
    if dt is None:
        return np.linspace(t0, t1, DEFAULT_GRID_POINTS)
    n = int(math.floor((t1 - t0) / dt + 1e-9))
    t = t0 + dt * np.arange(n + 1)
    if t[-1] < t1 - 1e-9 * max(1.0, abs(t1)):
        t = np.append(t, t1)
    return t


def collect(spec, cases, out_dir, *, output_interval=None):
    """Build ``summary.csv`` and ``sweep.nc`` in ``out_dir`` from the case folders of
    ``cases``; returns (summary DataFrame, xarray Dataset)."""
    import pandas as pd
    import xarray as xr

    from dnasim.output import _atomic_write, column_header

    out = Path(out_dir)
    keys = list(dict.fromkeys(k for c in cases for k in c))
    punits = case_units(spec, keys)
    records, tables = [], []
    for i, case in enumerate(cases):
        rec = _done_record(out, i, case)
        if rec is None:
            rec = {"status": "not run", "message": "the case has not run", "case": case}
        records.append(rec)
        tables.append(_read_case(case_dir(out, i)))
    # outputs: the union over the cases, in the order of their first appearance
    names, units = [], {}
    for tab in tables:
        if tab is not None:
            for n in tab[0]:
                if n not in units:
                    names.append(n)
                    units[n] = tab[1].get(n, "")
    grid = _grid(spec, records, output_interval)

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
    _atomic_write(out / "summary.csv", lambda f: f.write(summary.to_csv(index=False).encode()))

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
    tmp = out / ".sweep.nc.tmp"
    tmp.unlink(missing_ok=True)
    ds.to_netcdf(tmp, engine="h5netcdf")
    os.replace(tmp, out / "sweep.nc")
    return summary, ds
