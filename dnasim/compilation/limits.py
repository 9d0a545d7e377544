"""The plant's general limits as one terminal switch of the ``System``.

Two kinds of element, each >= 0 while the state is inside its limit:

  declared range   g = y_i - min_i  or  max_i - y_i   for every variable declared with
                   ``Variable(min=..., max=...)`` (a fluid mass M >= 0 [kg], a wall
                   temperature T_w >= 0 [K], ...)                       [unit of y_i]
  node state       g = +1 while the node's (p, h) lies within its medium's range
                   (IF97: 273.15 K <= T <= 1073.15 K or 2273.15 K, p <= 100 MPa, ...),
                   g = -1 outside it                                    [-]

The solver checks the switch after every accepted step and, when an element changes
sign, locates the crossing and stops there (a terminal switch): the last output row
is the last state inside the limits (``dnasim.solver.api``), and ``message`` names
the component or node, the variable, its value, the limit and the time. A limit
already crossed at the start stops the run before its first output row.

Why both: a component's own switches name its physical limits best (a drum that runs
dry, ``dnasim.library.drum``), but a state outside the medium's range that no
residual evaluates (a node between a boundary and a drum takes the boundary's h,
and the drum's balance uses only that h) gave NaN node temperatures in 226 of 301
rows of a run that reported "finished"; and a range a component declares holds for
every plant that uses it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LimitEvent", "limit_event"]


class LimitEvent:
    """The terminal vector switch of the module doc, on the System's global vectors.

    Attributes for the solver as ``dnasim.compilation.system.PlantEvent``: ``name``, ``names``,
    ``size``, ``direction`` (-1), ``terminal``; ``message(t)`` the plain reason of the
    element that crossed (from the last evaluation, the located crossing)."""

    component = "plant"
    terminal = True
    restart = False
    kink = False
    rearm = False
    direction = -1
    action = None

    def __init__(self, system, lo_idx, lo, hi_idx, hi, groups):
        self.name = "limits"
        self.system_name = system.name
        self.var_names = list(system.names)
        self.units = dict(system.units)
        self.lo_idx, self.lo = lo_idx, lo
        self.hi_idx, self.hi = hi_idx, hi
        self.groups = groups  # [(medium, positions among the nodes, node p indices)]
        self.node_names = list(system.node_names)
        at_node: dict = {}
        for (comp, port), node in system.connections.items():
            at_node.setdefault(node, []).append(f"{comp}.{port}")
        self.at_node = at_node
        self.n_bounds = lo_idx.size + hi_idx.size
        self.size = self.n_bounds + len(self.node_names)
        # "component.variable_min" and "node.in_range": events.csv splits a name at
        # its last "." into component (or node) and switch
        self.names = (
            [f"{self.var_names[i]}_min" for i in lo_idx]
            + [f"{self.var_names[i]}_max" for i in hi_idx]
            + [f"{nd}.in_range" for nd in self.node_names]
        )
        self.switch = self  # the entry of results' event logs (``switch.name``)
        self._last = None

    def __call__(self, t, y, yp):
        y = np.asarray(y, dtype=float)
        g = np.ones(self.size)
        nlo = self.lo_idx.size
        g[:nlo] = y[self.lo_idx] - self.lo
        g[nlo : self.n_bounds] = self.hi - y[self.hi_idx]
        for medium, pos, kp in self.groups:
            r = medium.states(y[kp], y[kp + 1], check=False)
            g[self.n_bounds + pos] = np.where(r.ok, 1.0, -1.0)
        self._last = (t, y.copy(), g)
        return g

    def message(self, t):
        """The reason of the element furthest past its limit in the last evaluation."""
        if self._last is None:
            return None
        _, y, g = self._last
        k = int(np.argmin(g))
        if g[k] >= 0.0:
            return None
        nlo = self.lo_idx.size
        if k < self.n_bounds:
            i = self.lo_idx[k] if k < nlo else self.hi_idx[k - nlo]
            limit = self.lo[k] if k < nlo else self.hi[k - nlo]
            name, unit = self.var_names[i], self.units.get(self.var_names[i], "")
            comp, _, var = name.partition(".")
            side = "minimum" if k < nlo else "maximum"
            return (
                f"component '{comp}': {var} reached its {side} {limit:g} {unit} at "
                f"t = {t:.6g} s ({name} = {_near(y[i], limit):.6g} {unit}); its equations "
                "hold no meaning beyond it"
            )
        j = k - self.n_bounds
        node = self.node_names[j]
        for medium, pos, kp in self.groups:
            hit = np.flatnonzero(pos == j)
            if hit.size:
                p, h = float(y[kp[hit[0]]]), float(y[kp[hit[0]] + 1])
                return node_message(node, medium, p, h, t, self.at_node.get(node, []))
        return None


def node_message(node, medium, p, h, t, ports) -> str:
    """The reason a node's state (p, h) is outside its medium's range, at time t."""
    try:
        medium.state(p, h)
        reason = "outside its range"
    except Exception as exc:  # noqa: BLE001 - the medium's own text names the limit
        reason = getattr(exc, "reason", "") or str(exc)
    where = ", ".join(ports) if ports else "nothing"
    return (
        f"node '{node}': its state p = {p / 1e5:.6g} bar, h = {h / 1e3:.6g} kJ/kg is outside the "
        f"range of {medium.label} at t = {t:.6g} s: {reason}; the node connects {where} "
        "(a boundary's given h or T, or a component's outlet, set its enthalpy there)"
    )


def _near(value: float, limit: float) -> float:
    """``limit`` when ``value`` is it within round-off (1e-9 relative), else ``value``."""
    return limit if abs(value - limit) <= 1e-9 * max(abs(limit), 1.0) else value


def limit_event(system, groups) -> LimitEvent | None:
    """The System's LimitEvent from its declared bounds (``System.lower``/``upper``:
    -inf/inf where none) and node groups; None when there is nothing to watch."""
    lo_idx = np.flatnonzero(np.isfinite(system.lower))
    hi_idx = np.flatnonzero(np.isfinite(system.upper))
    if lo_idx.size + hi_idx.size == 0 and not groups:
        return None
    return LimitEvent(
        system,
        lo_idx.astype(np.intp),
        system.lower[lo_idx],
        hi_idx.astype(np.intp),
        system.upper[hi_idx],
        groups,
    )
