"""Switch crossings: located in a step, logged, acted on.

``locate_crossings`` finds the crossings of the switch functions in the last step on
its interpolant (the earliest restarting one cuts the step); ``EventLog`` keeps the
record of every crossing (``DAEResult.event_log``, ``t_events``, ``y_events``);
``run_action`` runs a switch's action; ``predicted_crossing`` is the stepper's hook
that finds a restart switch's crossing on the predictor polynomial.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dnasim.core.errors import DAEError
from dnasim.solver.callbacks import call_user
from dnasim.solver.events import locate_earliest, locate_zero


class EventLog:
    """The record of the located crossings, per element: ``entries`` (the result's
    ``event_log``), and per switch the times and states (``t_events``, ``y_events``)."""

    def __init__(self, switches):
        self.switches = switches
        self.entries: list[dict] = []
        self.t_events: list[list] = [[] for _ in switches]
        self.y_events: list[list] = [[] for _ in switches]

    def record(self, c: Crossing) -> None:
        """Every element of ``c`` that crossed; the located one with its iterates."""
        sw = self.switches[c.switch]
        for j in c.which:
            self.entries.append(
                {
                    "event": c.switch,
                    "name": sw.names[j],
                    "element": int(j),
                    "t": c.t,
                    "iterates": c.iterates if j == c.located else [],
                    "terminal": sw.terminal,
                }
            )
            self.t_events[c.switch].append(c.t)
            self.y_events[c.switch].append(c.y)

    def arrays(self, n):
        """(t_events, y_events) as arrays, per switch."""
        return (
            [np.array(v) for v in self.t_events],
            [np.array(v).reshape(-1, n) for v in self.y_events],
        )


@dataclass
class Crossing:
    """A located crossing in the last step: switch index, time, state, elements."""

    switch: int
    t: float
    y: np.ndarray
    yp: np.ndarray
    which: np.ndarray  # the elements that crossed at t (one for a scalar switch)
    located: int  # the element whose zero was located (the iterates are its)
    iterates: list
    restarts: bool


def locate_crossings(solver, switches, g_old, g_new, t_prev) -> list[Crossing]:
    """Locate the crossings in the last step; return those up to the first that restarts.

    A restarting switch (terminal, with an action or ``restart``) gives its
    earliest crossing only (elements crossing at the same located time are
    reported together); an observing switch gives every crossed element, each
    located on its own. Crossings of observing switches before the first
    restarting one are all returned; later ones are dropped (found again after
    the restart).
    """
    found = []
    for k, sw in enumerate(switches):
        crossed = sw.crossed(g_old[k], g_new[k])
        if not crossed.any():
            continue

        def values(t, sw=sw):
            y, yp = solver.interpolate(t)
            return sw.value(t, y, yp)

        if sw.restarts:
            t_star, _, which, j, iterates = locate_earliest(
                values, sw, t_prev, g_old[k], solver.t, g_new[k]
            )
            y_star, yp_star = solver.interpolate(t_star)
            found.append(Crossing(k, t_star, y_star, yp_star, which, j, iterates, True))
            continue
        for j in np.flatnonzero(crossed):

            def element(t, values=values, j=j):
                return float(values(t)[j])

            t_star, _, iterates, _ = locate_zero(
                element, t_prev, g_old[k][j], solver.t, g_new[k][j]
            )
            y_star, yp_star = solver.interpolate(t_star)
            found.append(
                Crossing(k, t_star, y_star, yp_star, np.array([j]), int(j), iterates, False)
            )
    found.sort(key=lambda c: c.t)
    result = []
    for c in found:
        result.append(c)
        if c.restarts:
            break
    return result


def terminal_past_zero(switches, g0) -> tuple[int, int] | None:
    """(switch, element) of the first directed terminal switch that is strictly past its
    zero (on the side its direction reports) at the start, or None."""
    for k, sw in enumerate(switches):
        if not sw.terminal:
            continue
        past = np.flatnonzero((sw.direction != 0) & (-sw.direction * g0[k] < 0.0))
        if past.size:
            return k, int(past[0])
    return None


def old_side(c: Crossing, g_a: np.ndarray) -> float:
    """The latest time of the located element's iterates before ``c.t`` on the side of
    its value ``g_a`` at the start of the step (the old-side end of the final bracket,
    a few ulp before the crossing); ``c.t`` when g is exactly zero there (the search
    stopped on the zero itself) or when there is none (a crossing at the step's start)."""
    if any(t == c.t and v == 0.0 for t, v in c.iterates):
        return c.t
    old = np.sign(g_a[c.located])
    return max((t for t, v in c.iterates if t < c.t and np.sign(v) == old), default=c.t)


def predicted_crossing(kinks, solver, t_a, t_b):
    """Earliest crossing of a restart switch on the predictor polynomial in (t_a, t_b].

    The predictor is the last accepted step's Nordsieck polynomial extrapolated
    (``solver.interpolate`` beyond solver.t); t_a is the solver's time. Returns the
    located time, or None when no restart switch changes sign on the prediction.
    With ``kinks`` bound (functools.partial), the stepper's ``predicted_crossing`` hook.
    """
    best = None
    for sw in kinks:
        g_a = sw.value(t_a, solver.y, solver.yp)
        y_b, yp_b = solver.interpolate(t_b)
        try:
            g_b = sw.value(t_b, y_b, yp_b)
        except DAEError:  # the prediction is outside the switch's domain
            continue
        if not sw.crossed(g_a, g_b).any():
            continue

        def values(t, sw=sw):
            y, yp = solver.interpolate(t)
            return sw.value(t, y, yp)

        try:
            t_c = locate_earliest(values, sw, t_a, g_a, t_b, g_b)[0]
        except DAEError:
            continue
        if t_c <= t_a:  # a missed crossing (SwitchFunction.missed): acted on after the step
            continue
        best = t_c if best is None else min(best, t_c)
    return best


def run_action(sw, c: Crossing, n: int):
    """The switch's action at the crossing: new (y, yp), checked, or the located state."""
    if sw.action is None:
        return c.y, c.yp
    args = (c.t, c.y.copy(), c.yp.copy()) + ((c.which.copy(),) if sw.vector else ())
    changed = call_user(sw.action, f"the action of switch {sw.name!r}", c.t, *args)
    if changed is None:
        return c.y, c.yp
    try:
        y_new, yp_new = changed
        y_new = np.asarray(y_new, dtype=float)
        yp_new = np.asarray(yp_new, dtype=float)
    except (TypeError, ValueError):
        raise DAEError(
            f"The action of switch {sw.name!r} returned {type(changed).__name__}; it must "
            f"return None or a pair (y, yp) of arrays of {n} numbers."
        ) from None
    if y_new.shape != (n,) or yp_new.shape != (n,):
        raise DAEError(
            f"The action of switch {sw.name!r} returned arrays of shapes {y_new.shape} and "
            f"{yp_new.shape}; it must return None or (y, yp) of shape ({n},) each."
        )
    if not (np.all(np.isfinite(y_new)) and np.all(np.isfinite(yp_new))):
        raise DAEError(f"The action of switch {sw.name!r} returned NaN or inf at t = {c.t:.10g}.")
    return y_new, yp_new
