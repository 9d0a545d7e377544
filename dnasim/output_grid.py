"""Rows of ``results.csv`` on a fixed output grid, with both sides of every discontinuity.

The solver runs without ``t_eval`` and hands every accepted step (t, y, y') to
:class:`OutputGrid`, and after a time event (tstop) or a located switch, the
state right after it at the same t. OutputGrid turns that into:

- the grid rows t_k = t0 + k dt (``SimulationSettings.t_eval()``), from the cubic
  Hermite interpolant of (y, y') at the two ends of the step that holds t_k
  (y'(t) of the step ends is the Nordsieck derivative, for algebraic variables too);
- at a discontinuity t*: the left limit (the step that ends at t*, flag
  ``restart = 0``) and the state after it (``restart = 1``), two rows at the same
  time, whether or not t* is on the grid.

So the CSV, read as piecewise-linear between rows, never straddles a jump and a
trapezoidal integral over it is exact across events (the row at a time event
used to hold only the value before it). The Hermite interpolant has an error of
h^4/384 max|y''''| on a step of length h, below the step's own error estimate
for the orders 1-3 the solver uses near events; the rows at step ends and at
discontinuities are the solver's values themselves.

``emit(t, y, yp, restart)`` receives the rows; ``restart`` is 0 or 1.
"""

from __future__ import annotations

import numpy as np

__all__ = ["OutputGrid", "hermite"]


def hermite(t0, y0, yp0, t1, y1, yp1, t):
    """Cubic Hermite value and derivative at t in [t0, t1] from (y, y') at both ends."""
    h = t1 - t0
    s = (t - t0) / h
    s2, s3 = s * s, s * s * s
    h00, h10, h01, h11 = 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2
    d00, d10, d01, d11 = 6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s
    y = h00 * y0 + h10 * h * yp0 + h01 * y1 + h11 * h * yp1
    yp = (d00 * y0 + d01 * y1) / h + d10 * yp0 + d11 * yp1
    return y, yp


class OutputGrid:
    """Callback ``grid(t, y, yp)`` for the solver; see the module docstring."""

    def __init__(self, times, emit):
        self.times = np.asarray(times, dtype=float)
        self.k = 0  # next grid time to write
        self.emit = emit
        self.prev = None  # (t, y, yp) of the last point received
        self.prev_written = False  # was the last point written as a row?

    def __call__(self, t, y, yp):
        t = float(t)
        y = np.array(y, dtype=float)
        yp = np.array(yp, dtype=float)
        if self.prev is not None and t == self.prev[0]:
            # the state after a discontinuity at t: write its left limit first
            if not self.prev_written:
                self.emit(t, self.prev[1], self.prev[2], 0)
            self.emit(t, y, yp, 1)
            self.prev, self.prev_written = (t, y, yp), True
            while self.k < len(self.times) and self.times[self.k] <= t:
                self.k += 1
            return
        written = False
        if self.prev is not None:
            t0, y0, yp0 = self.prev
            while self.k < len(self.times) and self.times[self.k] < t:
                tk = self.times[self.k]
                if tk > t0:
                    yk, ypk = hermite(t0, y0, yp0, t, y, yp, tk)
                    self.emit(tk, yk, ypk, 0)
                self.k += 1
        while self.k < len(self.times) and self.times[self.k] <= t:
            if self.times[self.k] == t:
                self.emit(t, y, yp, 0)
                written = True
            self.k += 1
        self.prev, self.prev_written = (t, y, yp), written
