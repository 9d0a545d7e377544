"""The output of ``solve_dae``: which points are output (``OutputGrid``) and what is
emitted at them (``Output``: kept in the result, handed to the callback, dense output).
"""

from __future__ import annotations

import numpy as np

from dnasim.solver.callbacks import call_user
from dnasim.solver.result import NordsieckSolution


class OutputGrid:
    """Output times, consumed in order: an array (``t_eval``) or the lazy grid
    t0 + k dt, k = 0, 1, ..., closed by t_end (``output_interval``): nothing of
    the size of the grid is allocated."""

    @classmethod
    def of(cls, t_eval, interval, t0, t_end) -> OutputGrid | None:
        """The grid of the validated ``t_eval`` or ``output_interval`` (None: every step)."""
        if t_eval is not None:
            return cls(t_eval=t_eval)
        if interval is not None:
            return cls(interval=interval, t0=t0, t_end=t_end)
        return None

    def __init__(self, t_eval=None, interval=None, t0=0.0, t_end=0.0):
        self.array = t_eval
        self.interval = interval
        self.t0, self.t_end = t0, t_end
        self.k = 0
        self.done = False

    def peek(self) -> float | None:
        if self.array is not None:
            return float(self.array[self.k]) if self.k < len(self.array) else None
        if self.done:
            return None
        t = self.t0 + self.k * self.interval
        if t >= self.t_end - 1e-9 * (self.t_end - self.t0):
            return self.t_end
        return t

    def advance(self) -> None:
        if self.array is None and self.peek() == self.t_end:
            self.done = True
        self.k += 1


class Output:
    """Collects output points (and dense-output pieces) and forwards them to the callback.

    Without output times every accepted step is an output point, and after a
    restart (tstop or located switch) the state right after it is a second point
    at the same t. With output times (``t_eval`` or ``output_interval``) both
    sides of every restart are output points as well (two points at the same t), so
    that integrals over the output are exact across the discontinuity.
    ``keep=False``: points go to the callback only and nothing grows with them.

    ``refine(t, y, yp) -> (y, yp)`` (optional): applied to every output time strictly
    inside the solver's last step (the driver's ``refine``: algebraic variables solved
    from the interpolated differential states); points at steps are the solver's own,
    and the state at a located crossing is the polynomial's (the switch's zero was
    located on it: refined, a vessel's volume at its limit moved 5e-7 m3 past it).
    """

    def __init__(self, grid, callback, dense_output, t0, keep=True, refine=None):
        self.grid = grid
        self.refine = refine
        self.callback = callback
        self.dense = dense_output
        self.keep = keep
        self.t, self.y, self.yp = [], [], []
        self.history = []
        self.pieces = []
        self.t0 = t0
        self.last_t = None
        self.left = None  # (t, y, yp) at the end of the last step, for a restart there

    def _emit(self, t, y, yp):
        if self.keep:
            self.t.append(t)
            self.y.append(y.copy() if type(y) is np.ndarray else np.array(y))
            self.yp.append(yp.copy() if type(yp) is np.ndarray else np.array(yp))
        self.last_t = t
        if self.callback is not None:
            call_user(self.callback, "the output callback", t, t, y, yp)

    def initial(self, t, y, yp):
        if self.grid is None:
            self._emit(t, y, yp)
            return
        te = self.grid.peek()
        while te is not None and te <= t:
            self._emit(te, y, yp)
            self.grid.advance()
            te = self.grid.peek()

    def step(self, solver, t_prev, t_until):
        """Output of the step just taken, on (t_prev, t_until] (t_until <= solver.t)."""
        self.history.append((t_until, t_until - t_prev, solver.q_used))
        if self.dense:
            t_ref, h, q, z = solver.nordsieck_snapshot()
            self.pieces.append((t_until, t_ref, h, q, z))
        if t_until == solver.t:
            self.left = (t_until, solver.y, solver.yp)
        else:
            # a located crossing: the state there is the polynomial's, on which the
            # zero was located (and from which the restart starts), not refined
            self.left = (t_until, *solver.interpolate(t_until))
        if self.grid is None:
            self._emit(*self.left)
            return
        te = self.grid.peek()
        while te is not None and te <= t_until:
            if te == t_until:
                self._emit(*self.left)
            else:
                self._emit(te, *self._between(solver, te))
            self.grid.advance()
            te = self.grid.peek()

    def _between(self, solver, t):
        """(y, yp) at t inside the last step: interpolated, then refined."""
        y, yp = solver.interpolate(t)
        if self.refine is not None:
            y, yp = self.refine(t, y, yp)
        return y, yp

    def final(self):
        """The state at the end of the last step as the last output point (a run stopped
        by a terminal switch between output times)."""
        if self.left is not None and self.last_t != self.left[0]:
            self._emit(*self.left)

    def restart(self, t, y, yp):
        """After a discontinuity at t: the state right after it, an extra point at the
        same t (with output times, preceded by the state right before it)."""
        if self.grid is not None and self.last_t != t and self.left is not None:
            self._emit(*self.left)
        self._emit(t, y, yp)

    def arrays(self, n):
        if not self.t:
            return np.empty(0), np.empty((n, 0)), np.empty((n, 0))
        return np.array(self.t), np.array(self.y).T, np.array(self.yp).T

    def step_history(self):
        return np.array(self.history, dtype=float).reshape(-1, 3)

    def solution(self):
        return NordsieckSolution(self.pieces, self.t0) if self.dense and self.pieces else None
