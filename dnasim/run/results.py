"""Results: one simulation's output, a read-only Mapping of output name -> array.

    res = simulate(system, t_end=100.0)
    res["pipe1.T_out"]          # ndarray over res.t [K]
    res.units["pipe1.T_out"]    # "K"
    list(res)                   # the output names, in System.output_names() order
    df = res.to_dataframe()     # index t [s], units in df.attrs["units"]
    ds = res.to_xarray()        # dimension "time", units in each variable's attrs
    res.at(42.0)["pipe1.T_out"] # linear between output points [K]
    res.interp([0, 10, 20])     # Results on those times
    res = read_results("results/attemperator")   # the same from a run's files

Time is strictly increasing. A solver hands over two rows at the time of a
restart (a located switch, a time-function breakpoint): the state before and
the state after the jump. Results keeps the one after and marks it in
``restart`` (bool over t); the value before is the limit from the left of the
row before it.

Failures: ``success`` False and ``message`` say why the run ended early; the
rows up to that point are kept. ``simulate(..., throw=True)`` raises
``DAEError`` instead, carrying these Results as ``err.result``.

Pickling: derived outputs (temperatures, ...) are computed on first access
from the System; pickling computes them first, so a pickle holds arrays only
(and the dense output ``sol`` when the solver kept it).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["Results", "read_results"]


class Results(Mapping):
    """Output name -> ndarray over ``t``.

    Attributes
    ----------
    t : ndarray [s], strictly increasing
    restart : ndarray of bool over t; True where the row is the state just after
        a restart at that time
    names : list of output names ("a.p", "pipe1.M[0]", "pipe1.T_out", "a.T", ...)
    units : dict name -> unit string
    y, yp : raw solution (n x len(t)) in the order of ``variable_names``
    events : list of dicts {"event", "name", "component", "switch", "iterates", "t",
        "terminal"}, one per located switch crossing
    steps : ndarray (steps x 3): t [s], h [s], order of each accepted step
    stats : solver counters (steps, residual_evals, jac_evals, lu_decomps, ...),
        plus wall_time and init_time [s]
    success, message : how the integration ended
    solver : the name of the backend ("NordsieckBDF", "IDA")
    sol : dense output y(t) when the solver kept it, else None
    warnings : the components' warnings of the run, in plain words (a pump that
        cavitates with ``cavitation = "warn"``; ``System.warnings``)
    """

    def __init__(
        self,
        t,
        names,
        units,
        values,
        *,
        y=None,
        yp=None,
        variable_names=(),
        restart=None,
        events=(),
        steps=None,
        stats=None,
        success=True,
        message="",
        solver="",
        sol=None,
        warnings=(),
    ):
        self.t = np.asarray(t, dtype=float)
        self.names = list(names)
        self.units = dict(units)
        self._values = values  # array (names x t), or a callable computing it on first use
        self._table = None
        self.y = y
        self.yp = yp
        self.variable_names = list(variable_names)
        self.restart = (
            np.zeros(self.t.size, dtype=bool) if restart is None else np.asarray(restart, bool)
        )
        self.events = list(events)
        self.steps = np.zeros((0, 3)) if steps is None else np.asarray(steps, dtype=float)
        self.stats = dict(stats or {})
        self.success = bool(success)
        self.message = str(message)
        self.solver = solver
        self.sol = sol
        self.warnings = list(warnings)

    # ---------------------------------------------------------------- Mapping
    def _rows(self) -> dict:
        if self._table is None:
            vals = self._values() if callable(self._values) else self._values
            self._table = dict(zip(self.names, vals, strict=True))
            self._values = None
        return self._table

    def __getitem__(self, name):
        try:
            return self._rows()[name]
        except KeyError:
            raise KeyError(
                f"no output named {name!r}; e.g. {', '.join(self.names[:8])} ..."
            ) from None

    def __iter__(self):
        return iter(self.names)

    def __len__(self):
        return len(self.names)

    def __contains__(self, name):
        return name in self.units

    # ---------------------------------------------------------- interpolation
    def _time_weights(self, t):
        """Row indices i and weights w with value(t) = (1 - w) v[i] + w v[i + 1]."""
        tq = np.asarray(t, dtype=float)
        if self.t.size == 0:
            raise ValueError("these Results have no output points")
        lo, hi = self.t[0], self.t[-1]
        bad = (tq < lo) | (tq > hi) | ~np.isfinite(tq)
        if np.any(bad):
            first = float(np.atleast_1d(tq)[np.atleast_1d(bad)][0])
            raise ValueError(
                f"t = {first:g} s is outside the results, t = {lo:g} .. {hi:g} s (no extrapolation)"
            )
        if self.t.size == 1:
            return np.zeros(tq.shape, dtype=np.intp), np.zeros(tq.shape)
        i = np.clip(np.searchsorted(self.t, tq, side="right") - 1, 0, self.t.size - 2)
        w = (tq - self.t[i]) / (self.t[i + 1] - self.t[i])
        return i, w

    def at(self, t, names=None) -> dict:
        """Named outputs at time(s) ``t`` [s]: name -> value (a float for a scalar t,
        an array for an array of times), in the units of ``units``.

        Linear interpolation between the output points (``t``), exact at them; at a
        restart time the value is the state after the jump (the row kept). The
        dense output of the solver (``sol``, the raw unknowns) is not used: the
        named outputs (temperatures, ...) exist at the output points only, so ask
        for the times you need with ``t_eval`` or ``output_interval`` when linear
        interpolation between steps is not accurate enough. ``names``: a subset
        (default: every output). Outside t[0] .. t[-1]: ``ValueError``.
        """
        i, w = self._time_weights(t)
        picked = self.names if names is None else [names] if isinstance(names, str) else names
        out = {}
        for n in picked:
            v = np.asarray(self[n], dtype=float)
            if v.size == 1:
                val = np.full(np.shape(i), v[0])
            else:
                val = (1.0 - w) * v[i] + w * v[np.minimum(i + 1, v.size - 1)]
                exact = w == 0.0  # at an output point: its value, bit for bit
                val = np.where(exact, v[i], val)
            out[n] = float(val) if np.ndim(val) == 0 else val
        return out

    def interp(self, t, names=None) -> Results:
        """``Results`` on the times ``t`` [s] (strictly increasing), each output
        interpolated as :meth:`at` does; ``restart`` marks the times that are
        restart times of these Results."""
        tq = np.atleast_1d(np.asarray(t, dtype=float))
        if tq.size > 1 and not np.all(np.diff(tq) > 0):
            raise ValueError("interp: the times must be strictly increasing")
        vals = self.at(tq, names)
        picked = list(vals)
        restart_times = self.t[self.restart]
        return Results(
            tq,
            picked,
            {n: self.units.get(n, "") for n in picked},
            np.array([vals[n] for n in picked]).reshape(len(picked), tq.size),
            restart=np.isin(tq, restart_times),
            success=self.success,
            message=self.message,
            solver=self.solver,
        )

    # --------------------------------------------------------------- pickling
    def __getstate__(self):
        self._rows()  # the lazy outputs need the System: compute them now
        return dict(self.__dict__)

    # ------------------------------------------------------------- conversion
    def to_dataframe(self):
        """A pandas DataFrame indexed by time [s] (named "time", as in results.csv,
        results.nc and a sweep's sweep.nc), one column per name; the units are in
        ``df.attrs["units"]`` (name -> unit, "time" -> "s") and the restart flags in
        ``df.attrs["restart"]`` (a tuple of bools over t: pandas compares the attrs of
        frames it merges or concatenates, which an array would break)."""
        import pandas as pd

        rows = self._rows()
        df = pd.DataFrame({n: rows[n] for n in self.names}, index=pd.Index(self.t, name="time"))
        df.attrs["units"] = {"time": "s", **{n: self.units.get(n, "") for n in self.names}}
        df.attrs["restart"] = tuple(bool(r) for r in self.restart)
        return df

    def to_xarray(self):
        """An xarray Dataset with dimension "time" [s] (as in results.nc and sweep.nc);
        each variable's ``attrs["units"]`` holds its unit; ``restart`` is a boolean
        variable over time (CF flag attributes, as in results.nc)."""
        import xarray as xr

        rows = self._rows()
        data = {
            n: xr.Variable(("time",), np.asarray(rows[n]), attrs={"units": self.units.get(n, "")})
            for n in self.names
        }
        data["restart"] = xr.Variable(
            ("time",),
            self.restart,
            attrs={
                "long_name": "row holds the state right after a restart at this time",
                "units": "1",
                "flag_values": np.array([0, 1], dtype="i1"),
                "flag_meanings": "continuous state_after_restart",
            },
        )
        return xr.Dataset(
            data,
            coords={"time": xr.Variable(("time",), self.t, attrs={"units": "s"})},
            attrs={"success": int(self.success), "message": self.message, "solver": self.solver},
        )

    def __repr__(self):
        span = f"t = {self.t[0]:g} .. {self.t[-1]:g} s" if self.t.size else "no points"
        return (
            f"Results({self.t.size} points, {span}, {len(self.names)} outputs, "
            f"success={self.success})"
        )


def strictly_increasing(t):
    """Indices of the rows to keep and the restart flags of the kept rows.

    Of consecutive rows at equal t the last one is kept (the state after the
    restart) and flagged."""
    t = np.asarray(t, dtype=float)
    if t.size == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=bool)
    same_as_prev = np.r_[False, t[1:] <= t[:-1]]
    keep = np.flatnonzero(np.r_[~same_as_prev[1:], True])
    return keep, same_as_prev[keep]


# --------------------------------------------------------------------------- reading


def read_results(path) -> Results:
    """The ``Results`` of a run, read from its folder or from one results file.

    ``path``: a directory written by ``dnasim run`` (its ``results.nc`` if there is
    one, else its ``results.csv``; ``steps.csv`` and ``events.csv`` beside it fill
    ``steps`` and ``events``), or a ``.nc`` or ``.csv`` file itself. The rows are
    those of ``simulate()``: strictly increasing ``t`` [s], at a restart the state
    after the jump, flagged in ``restart``; units as ``System.output_units()`` gives
    them (``res.units``); ``stats``: the solver's counters (netCDF only).
    ``success``/``message``: how the run ended, as the netCDF file records it
    (a CSV file does not: True and ""). A netCDF file whose writer was killed
    (SIGKILL, no chance to close it) is read in HDF5's SWMR mode, up to its last
    whole block of rows; ``message`` then says so and ``success`` is False.
    """
    from pathlib import Path

    p = Path(path)
    if p.is_dir():
        nc, csv = p / "results.nc", p / "results.csv"
        if nc.exists():
            res = _read_netcdf(nc)
        elif csv.exists():
            res = _read_csv(csv)
        else:
            raise FileNotFoundError(f"{p} holds neither results.nc nor results.csv")
        steps = p / "steps.csv"
        if steps.exists():
            res.steps = _read_steps(steps)
        events = p / "events.csv"
        if events.exists():
            res.events = _read_events(events)
        return res
    if not p.exists():
        raise FileNotFoundError(f"{p} does not exist")
    if p.suffix.lower() == ".nc":
        return _read_netcdf(p)
    if p.suffix.lower() == ".csv":
        return _read_csv(p)
    raise ValueError(f"{p}: not a results file (.nc or .csv) nor a results folder")


def _read_steps(path):
    from dnasim.run.output import read_results_csv

    _, _, data = read_results_csv(path)
    if "time" not in data:
        return np.zeros((0, 3))
    return np.column_stack([data["time"], data["step_size"], data["order"]])


def _read_events(path) -> list[dict]:
    """events.csv -> ``Results.events``: one dict per located switch (its iterates
    (t, switch value), ``t`` the located time, the last iterate's)."""
    import csv

    out: dict[int, dict] = {}
    with open(path, newline="", encoding="utf-8") as f:
        for row in csv.DictReader(f):
            k = int(row["event"])
            comp, switch = row["component"], row["switch"]
            e = out.setdefault(
                k,
                {
                    "event": k,
                    "name": f"{comp}.{switch}" if comp else switch,
                    "component": comp,
                    "switch": switch,
                    "iterates": [],
                },
            )
            e["iterates"].append((float(row["time"]), float(row["switch_value"])))
            e["t"] = float(row["time"])
    return [out[k] for k in sorted(out)]


def _read_csv(path) -> Results:
    from dnasim.run.output import read_results_csv
    from dnasim.run.sinks import RESTART_COLUMN

    names, units, data = read_results_csv(path)
    t = data[names[0]]
    keep, restart = strictly_increasing(t)
    outputs = [n for n in names[1:] if n != RESTART_COLUMN]
    values = np.array([data[n][keep] for n in outputs]).reshape(len(outputs), keep.size)
    if RESTART_COLUMN in data:
        restart = data[RESTART_COLUMN][keep] == 1.0
    return Results(t[keep], outputs, {n: units[n] for n in outputs}, values, restart=restart)


def _read_netcdf(path) -> Results:
    import h5py

    killed = False
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        if "already open for write" not in str(exc):
            raise
        f = h5py.File(path, "r", swmr=True)  # its writer never closed it
        killed = True
    with f:
        t = f["time"][:]
        n = t.size
        flags = f["restart"][:n]
        n = min(n, flags.size)
        cols: list[tuple[int, str, str, object]] = []
        for var, ds in f.items():
            if not isinstance(ds, h5py.Dataset) or "dnasim_columns" not in ds.attrs:
                continue
            positions = np.atleast_1d(ds.attrs["dnasim_columns"])
            var = _text(ds.attrs.get("long_name", var))  # the output name itself
            unit = _text(ds.attrs.get("dnasim_unit", ds.attrs.get("units", "")))
            n = min(n, ds.shape[0])
            if ds.ndim == 1:
                cols.append((int(positions[0]), var, unit, ds))
            else:
                for i, j in enumerate(positions):
                    cols.append((int(j), f"{var}[{i}]", unit, (ds, i)))
        cols.sort(key=lambda c: c[0])
        values = np.empty((len(cols), n))
        blocks = {}
        for k, (_, _, _, src) in enumerate(cols):
            if isinstance(src, tuple):
                ds, i = src
                if ds.name not in blocks:
                    blocks[ds.name] = ds[:n, :]
                values[k] = blocks[ds.name][:, i]
            else:
                values[k] = src[:n]
        stats = {
            k.removeprefix("stats_"): v.item() if hasattr(v, "item") else v
            for k, v in f.attrs.items()
            if k.startswith("stats_")
        }
        status = _text(f.attrs.get("status", ""))
        message = _text(f.attrs.get("message", ""))
        solver = _text(f.attrs.get("simulation_solver", ""))
    if killed:
        success = False
        message = (
            f"{path} was not closed by its writer (killed?); it holds the {n} whole rows "
            "written before"
        )
    else:
        success = status in ("finished", "closed")
    return Results(
        t[:n],
        [c[1] for c in cols],
        {c[1]: c[2] for c in cols},
        values,
        restart=flags[:n] == 1,
        stats=stats,
        success=success,
        message=message,
        solver=solver,
    )


def _text(v) -> str:
    return v.decode() if isinstance(v, bytes) else str(v)
