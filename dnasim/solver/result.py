"""What ``solve_dae`` returns."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dnasim.solver import nordsieck as nd


class NordsieckSolution:
    """Dense output: the piecewise Nordsieck polynomials of all accepted steps.

    ``sol(t)`` evaluates y at a scalar or an array of times (shape (n,) or (n, m)).
    The polynomial of the step [t_{k-1}, t_k] is used for t in that interval;
    at a restart time (event, tstop) the value before the jump is returned.
    """

    def __init__(self, pieces: list[tuple[float, float, float, int, np.ndarray]], t0: float):
        self.pieces = pieces  # (valid until, t_ref, h, q, z)
        self.t_ends = np.array([p[0] for p in pieces])
        self.t0 = t0

    def _one(self, t: float) -> np.ndarray:
        k = int(np.searchsorted(self.t_ends, t, side="left"))
        k = min(max(k, 0), len(self.pieces) - 1)
        _, t_ref, h, q, z = self.pieces[k]
        return nd.interpolate(z, q, h, (t - t_ref) / h)[0]

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        if t.ndim == 0:
            return self._one(float(t))
        return np.stack([self._one(float(ti)) for ti in t], axis=1)


@dataclass
class DAEResult:
    """The solution of F(t, y, y') = 0.

    t : output times, shape (m,)
    y, yp : solution and derivative, shape (n, m)
    success, status (0: reached the end, 1: a terminal event, -1: failed), message
    t_events, y_events : per switch function, the located times and states (a
        vector switch: one entry per element crossing, in time order)
    event_log : per located crossing (per element for a vector switch), a dict
        with "event" (switch index), "name" (the element's name for a vector
        switch), "element" (0 for a scalar switch), "t" (located time),
        "iterates" (list of (t, g) of the located element; [] for the other
        elements that crossed at the same time) and "terminal"
    stats : steps, rejected_error, rejected_newton, residual_evals, jac_evals,
        lu_decomps, newton_iters
    step_history : array of shape (steps, 3): t, h, order of every accepted step
    sol : dense output (None when dense_output=False)
    """

    t: np.ndarray
    y: np.ndarray
    yp: np.ndarray
    success: bool
    status: int
    message: str
    t_events: list
    y_events: list
    event_log: list
    stats: dict
    step_history: np.ndarray
    sol: NordsieckSolution | None = field(default=None, repr=False)
