"""PlantResults: a simulation's output, every quantity addressed by name."""

from __future__ import annotations

import numpy as np


class PlantResults:
    """Results of ``Plant.simulate``.

    Attributes
    ----------
    t : ndarray [s]
    names : list of output names ("a.p", "pipe1.M[0]", "pipe1.T_out", "a.T", ...)
    units : dict name -> unit string
    results : dict name -> ndarray over t (also ``res[name]``); derived outputs
        (temperatures, ...) cost property calls and are computed on first access
    y, yp : raw solution arrays (n x len(t)) in the order of ``variable_names``
    stats : solver statistics (steps, residual_evals, ...) plus wall_time [s]
    step_history : array of (t, h, order) per accepted step
    event_log : list of dicts {"event", "name", "component", "switch", "iterates", "t"}
    success, message : how the integration ended
    """

    def __init__(
        self,
        t,
        names,
        units,
        values,
        y,
        yp,
        variable_names,
        stats,
        step_history,
        event_log,
        success,
        message,
        sol=None,
    ):
        self.t = t
        self.names = names
        self.units = units
        self._values = values  # array (names x t), or a callable computing it on first use
        self._results = None
        self.y = y
        self.yp = yp
        self.variable_names = variable_names
        self.stats = stats
        self.step_history = step_history
        self.event_log = event_log
        self.success = success
        self.message = message
        self.sol = sol

    @classmethod
    def from_dae_result(cls, plant, dae, res, wall_time=None, init_time=None):
        t = np.asarray(res.t, dtype=float)
        y = np.asarray(res.y, dtype=float)
        yp = np.asarray(res.yp, dtype=float)
        names = dae.output_names()
        units = dae.output_units()

        def values():
            rows = np.array([dae.output_row(t[k], y[:, k], yp[:, k]) for k in range(t.size)])
            return rows.T if rows.size else np.zeros((len(names), 0))

        stats = dict(res.stats)
        if wall_time is not None:
            stats["wall_time"] = wall_time
        if init_time is not None:
            stats["init_time"] = init_time
        log = []
        for entry in res.event_log:
            e = dict(entry)
            idx = e.get("event")
            if idx is not None and 0 <= idx < len(dae.events):
                ev = dae.events[idx]
                e["component"] = ev.component
                e["switch"] = ev.switch.name
                e.setdefault("name", ev.name)
            log.append(e)
        success, message = bool(res.success), str(res.message)
        # a terminal switch that stands for a modelling error (e.g. flow into the
        # plant through a sink-only boundary) ends the run as a failure with the
        # component's own plain message
        for e in reversed(log if getattr(res, "status", 1) == 1 else []):
            idx = e.get("event")
            if e.get("terminal") and idx is not None and 0 <= idx < len(dae.events):
                text = dae.events[idx].message(e["t"])
                if text:
                    success, message = False, text
                break
        return cls(
            t,
            names,
            units,
            values,
            y,
            yp,
            list(dae.names),
            stats,
            np.asarray(res.step_history),
            log,
            success,
            message,
            getattr(res, "sol", None),
        )

    @property
    def results(self) -> dict:
        if self._results is None:
            vals = self._values() if callable(self._values) else self._values
            self._results = dict(zip(self.names, vals, strict=True))
        return self._results

    def __getitem__(self, name):
        try:
            return self.results[name]
        except KeyError:
            raise KeyError(
                f"no output named {name!r}; e.g. {', '.join(self.names[:8])} ..."
            ) from None

    def __contains__(self, name):
        return name in self.names

    def unit(self, name):
        return self.units[name]

    def to_dataframe(self):
        """A pandas DataFrame indexed by t, one column per name (needs pandas)."""
        import pandas as pd

        return pd.DataFrame(
            {n: self.results[n] for n in self.names}, index=pd.Index(self.t, name="t")
        )

    def __repr__(self):
        return (
            f"PlantResults({self.t.size} points, t = {self.t[0]:g} .. {self.t[-1]:g} s, "
            f"{len(self.names)} outputs, success={self.success})"
        )
