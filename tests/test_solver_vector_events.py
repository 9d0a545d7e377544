"""Vector switch functions (one call per step for many elements) and restart-only events."""

import numpy as np
import pytest

from dnasim import DAEError, solve_dae


class Thresholds:
    """g_j = y_0 - c_j: element j crosses (falling) when y_0 passes c_j."""

    def __init__(self, levels, direction=-1, restart=True):
        self.levels = np.asarray(levels, dtype=float)
        self.size = self.levels.size
        self.direction = direction
        self.names = [f"level[{j}]" for j in range(self.size)]
        self.terminal = False
        self.restart = restart
        self.calls = 0

    def __call__(self, t, y, yp):
        self.calls += 1
        return y[0] - self.levels


def test_thousand_element_switch_locates_every_crossing_of_a_decay():
    """y' = -y, y(0) = 1: y = exp(-t) passes c_j = exp(-t_j) at t_j exactly."""
    t_cross = np.linspace(0.01, 2.0, 1000)
    g = Thresholds(np.exp(-t_cross))
    res = solve_dae(lambda t, y, yp: yp + y, (0, 2.5), [1.0], events=[g], rtol=1e-9, atol=1e-12)
    assert res.success
    np.testing.assert_array_equal([e["element"] for e in res.event_log], np.arange(1000))
    assert [e["name"] for e in res.event_log[:2]] == ["level[0]", "level[1]"]
    # Located on the computed solution to round-off: y(t*) = c_j to a few ulp.
    np.testing.assert_allclose(np.array(res.y_events[0])[:, 0], g.levels, rtol=0, atol=1e-15)
    # The time error is the solution's global error divided by |y'| = y. Each of the
    # 1000 restarts begins with an order-1 step whose local error is up to the
    # tolerance, so the global error grows like restarts * rtol = 1e-6 at most.
    np.testing.assert_allclose(res.t_events[0], t_cross, rtol=0, atol=1e-6)
    # Restart-only: every crossing cuts the step and the next step is at order 1.
    hist = res.step_history
    for t_star in res.t_events[0][::97]:
        after = np.flatnonzero(hist[:, 0] > t_star)[0]
        assert hist[after, 2] == 1
    # One call of the vector function per step, plus the root-finding iterates and one
    # call after each restart; never one call per element.
    iterates = sum(len(e["iterates"]) for e in res.event_log)
    assert g.calls <= res.stats["steps"] + iterates + 1000 + 1


def test_restart_only_scalar_event_cuts_the_step_and_keeps_the_solution():
    def g(t, y, yp):
        return y[0] - 0.5

    g.restart = True
    residual = lambda t, y, yp: yp + y  # noqa: E731
    res = solve_dae(residual, (0, 2), [1.0], events=[g], rtol=1e-9, atol=1e-12)
    plain = solve_dae(residual, (0, 2), [1.0], rtol=1e-9, atol=1e-12)
    t_star = res.t_events[0][0]
    # Closed form ln 2; location error = global error / |y'| (~1e-9 / 0.5).
    assert t_star == pytest.approx(np.log(2.0), abs=1e-8)
    after = np.flatnonzero(res.step_history[:, 0] > t_star)[0]
    assert res.step_history[after, 2] == 1
    assert res.t[np.flatnonzero(res.t == t_star)].size == 2  # the point before and after
    # The restart changes no state: both runs agree to their tolerance (1e-9 rtol).
    assert res.y[0, -1] == pytest.approx(np.exp(-2.0), rel=1e-7)
    assert plain.y[0, -1] == pytest.approx(np.exp(-2.0), rel=1e-7)


def test_mixed_scalar_and_vector_switches_with_actions():
    """y' = r, r = 1 until y = 1, then r = 2; a vector switch watches y = 0.3, 0.7, 0.7, 1.5.

    Closed form: y = t until t = 1, then y = 1 + 2 (t - 1); so the vector elements
    cross at 0.3, 0.7 (two at once), 1.25; the element with direction -1 never fires.
    """
    state = {"rate": 1.0, "seen": []}

    def residual(t, y, yp):
        return np.array([yp[0] - state["rate"]])

    def faster(t, y, yp):
        return y[0] - 1.0

    def speed_up(t, y, yp):
        state["rate"] = 2.0
        return y, np.array([2.0])

    faster.action = speed_up
    levels = Thresholds([0.3, 0.7, 0.7, 1.5, 0.5], direction=np.array([1, 1, 1, 1, -1]))
    levels.restart = False

    def record(t, y, yp, which):
        state["seen"].append((t, list(which)))

    levels.action = record
    res = solve_dae(residual, (0, 2), [0.0], [1.0], events=[levels, faster], rtol=1e-10, atol=1e-12)
    assert res.success
    times = [t for t, _ in state["seen"]]
    groups = [w for _, w in state["seen"]]
    assert groups == [[0], [1, 2], [3]]
    # Polynomial solutions are exact for BDF; location to a few ulp (1e-12).
    np.testing.assert_allclose(times, [0.3, 0.7, 1.25], atol=1e-12)
    assert res.t_events[1] == pytest.approx([1.0], abs=1e-12)
    names = [e["name"] for e in res.event_log]
    assert names == ["level[0]", "level[1]", "level[2]", "faster", "level[3]"]
    assert res.y[0, -1] == pytest.approx(3.0, abs=1e-10)


def test_vector_switch_of_the_wrong_shape_is_named():
    g = Thresholds([0.5, 0.2])
    g.size = 3
    g.names = ["a", "b", "c"]
    g.name = "levels"
    with pytest.raises(DAEError, match=r"'levels' returned shape \(2,\).*shape \(3,\)"):
        solve_dae(lambda t, y, yp: yp + y, (0, 1), [1.0], events=[g], throw=True)
