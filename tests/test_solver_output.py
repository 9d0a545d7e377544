"""Output points of ``solve_dae``: a lazily generated output grid, rows handed to the
callback only, and both sides of every restart (issue 12, item 3; issue 11)."""

from __future__ import annotations

import numpy as np
import pytest

from dnasim.core.errors import DAEError
from dnasim.solver import solve_dae


def _heated(t, y, yp):
    """y' = q(t), q = 1 before t = 1 and 3 after: y(2) = 1 + 3 = 4 exactly."""
    q = 1.0 if t < 1.0 else 3.0
    return np.array([yp[0] - q])


def test_output_interval_matches_t_eval_and_allocates_no_grid():
    a = solve_dae(_heated, (0.0, 2.0), [0.0], [1.0], tstops=[1.0], output_interval=0.25)
    te = np.arange(0.0, 2.0 + 1e-12, 0.25)
    b = solve_dae(_heated, (0.0, 2.0), [0.0], [1.0], tstops=[1.0], t_eval=te)
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.y, b.y)
    # the last point is t_end even when the interval does not divide the span
    c = solve_dae(_heated, (0.0, 2.0), [0.0], [1.0], output_interval=0.3)
    assert c.t[-1] == 2.0 and np.all(np.diff(c.t) > 0)
    # a grid of 1e12 points (8 TB as an array) costs nothing until it is reached: a
    # terminal switch at t = 1e-7 s ends the run after 101 of them
    stop = lambda t, y, yp: t - 1e-7  # noqa: E731
    stop.terminal = True
    stop.direction = 1
    d = solve_dae(
        _heated, (0.0, 1e3), [0.0], [1.0], output_interval=1e-9, events=[stop], keep_output=False
    )
    assert d.status == 1 and d.t.size == 0
    rows = []
    solve_dae(
        _heated,
        (0.0, 1e3),
        [0.0],
        [1.0],
        output_interval=1e-9,
        events=[stop],
        callback=lambda t, y, yp: rows.append(t),
    )
    assert 100 <= len(rows) <= 102 and rows[-1] <= 1e-7 * (1 + 1e-9)
    with pytest.raises(DAEError, match="not both"):
        solve_dae(_heated, (0.0, 2.0), [0.0], [1.0], output_interval=0.5, t_eval=te)
    with pytest.raises(DAEError, match="output_interval"):
        solve_dae(_heated, (0.0, 2.0), [0.0], [1.0], output_interval=float("nan"))


def test_both_sides_of_a_time_event_make_integrals_exact():
    """Trapezoidal integral of y' over the output rows: exact (4, to round-off) only if
    the row at t = 1 holds both the value before (q = 1) and after (q = 3)."""
    res = solve_dae(_heated, (0.0, 2.0), [0.0], [1.0], tstops=[1.0], output_interval=0.5)
    at1 = np.flatnonzero(res.t == 1.0)
    assert at1.size == 2  # left and right of the discontinuity
    assert res.yp[0, at1[0]] == pytest.approx(1.0) and res.yp[0, at1[1]] == pytest.approx(3.0)
    integral = np.sum(0.5 * (res.yp[0, 1:] + res.yp[0, :-1]) * np.diff(res.t))
    # q is piecewise constant, so the trapezoidal sum is exact up to the solver's
    # round-off in y' (1e-12 of the value)
    assert integral == pytest.approx(4.0, rel=1e-12)
    assert res.y[0, -1] == pytest.approx(4.0, rel=1e-9)  # rtol 1e-6 on a linear solution


def test_rows_go_to_the_callback_only():
    rows = []
    res = solve_dae(
        _heated,
        (0.0, 2.0),
        [0.0],
        [1.0],
        tstops=[1.0],
        output_interval=0.1,
        keep_output=False,
        dense_output=False,
        callback=lambda t, y, yp: rows.append((t, y[0])),
    )
    assert res.success and res.t.size == 0  # nothing kept
    assert len(rows) == 21 + 1  # 0, 0.1, ..., 2 and the second row at the tstop
    assert rows[-1][0] == 2.0 and rows[-1][1] == pytest.approx(4.0, rel=1e-9)
