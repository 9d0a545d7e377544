"""Results: one simulation's output, a read-only Mapping of output name -> array.

    res = simulate(system, t_end=100.0)
    res["pipe1.T_out"]          # ndarray over res.t [K]
    res.units["pipe1.T_out"]    # "K"
    list(res)                   # the output names, in System.output_names() order
    df = res.to_dataframe()     # index t [s], units in df.attrs["units"]
    ds = res.to_xarray()        # dimension "t", units in each variable's attrs

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

__all__ = ["Results"]


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

    # --------------------------------------------------------------- pickling
    def __getstate__(self):
        self._rows()  # the lazy outputs need the System: compute them now
        return dict(self.__dict__)

    # ------------------------------------------------------------- conversion
    def to_dataframe(self):
        """A pandas DataFrame indexed by t [s], one column per name; the units are in
        ``df.attrs["units"]`` (name -> unit, "t" -> "s") and the restart flags in
        ``df.attrs["restart"]``."""
        import pandas as pd

        rows = self._rows()
        df = pd.DataFrame({n: rows[n] for n in self.names}, index=pd.Index(self.t, name="t"))
        df.attrs["units"] = {"t": "s", **{n: self.units.get(n, "") for n in self.names}}
        df.attrs["restart"] = self.restart.copy()
        return df

    def to_xarray(self):
        """An xarray Dataset with dimension "t" [s]; each variable's ``attrs["units"]``
        holds its unit; ``restart`` is a boolean variable over t."""
        import xarray as xr

        rows = self._rows()
        data = {
            n: xr.Variable(("t",), np.asarray(rows[n]), attrs={"units": self.units.get(n, "")})
            for n in self.names
        }
        data["restart"] = xr.Variable(("t",), self.restart)
        return xr.Dataset(
            data,
            coords={"t": xr.Variable(("t",), self.t, attrs={"units": "s"})},
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
