"""Switch functions: location of discontinuities, actions, restarts at order 1."""

import numpy as np
import pytest

from dnasim import solve_dae

G = 9.81


def _bouncing_ball(restitution, t_end, rtol=1e-10):
    """Height x and velocity v: x' = v, v' = -g; at x = 0 (falling) v -> -e v."""

    def residual(t, y, yp):
        return np.array([yp[0] - y[1], yp[1] + G])

    def impact(t, y, yp):
        return y[0]

    impact.direction = -1
    impact.name = "floor"

    def bounce(t, y, yp):
        return np.array([0.0, -restitution * y[1]]), np.array([-restitution * y[1], -G])

    impact.action = bounce
    return solve_dae(
        residual, (0, t_end), [10.0, 0.0], [0.0, -G], events=[impact], rtol=rtol, atol=1e-12
    )


def test_falling_ball_first_impact_and_later_impacts():
    e = 0.8
    res = _bouncing_ball(e, 5.0)
    t1 = np.sqrt(2 * 10.0 / G)
    impacts = res.t_events[0]
    assert impacts[0] == pytest.approx(t1, rel=1e-10)
    # Closed form: each flight after an impact with speed v lasts 2 e v / g, v_k = e^k g t1.
    expected = [t1]
    v = G * t1
    while True:
        v *= e
        nxt = expected[-1] + 2 * v / G
        if nxt > 5.0:
            break
        expected.append(nxt)
    assert len(impacts) == len(expected)
    # The polynomial solution is integrated exactly by BDF of order >= 2; location to 1e-9.
    np.testing.assert_allclose(impacts, expected, rtol=1e-9)


def test_switch_that_changes_the_equations_is_located_exactly():
    """x' = 1 until x = 1, then x' = 0: the switch is at t = 1."""
    mode = {"stopped": False}

    def residual(t, y, yp):
        return np.array([yp[0] - (0.0 if mode["stopped"] else 1.0)])

    def reach_one(t, y, yp):
        return 1.0 if mode["stopped"] else y[0] - 1.0

    def stop(t, y, yp):
        mode["stopped"] = True
        return None

    reach_one.action = stop
    res = solve_dae(residual, (0, 3), [0.0], events=[reach_one], rtol=1e-8, atol=1e-10)
    assert res.t_events[0][0] == pytest.approx(1.0, abs=1e-12)
    assert res.y[0, -1] == pytest.approx(1.0, abs=1e-12)
    log = res.event_log[0]
    assert log["name"] == "reach_one"
    g_values = [abs(g) for _, g in log["iterates"]]
    # The last iterate sits on the switch to round-off, on its new side (g >= 0).
    assert g_values[-1] <= 1e-12
    assert log["iterates"][-1][1] >= 0.0
    # Integration restarts at order 1 right after the switch.
    after = np.flatnonzero(res.step_history[:, 0] > log["t"])[0]
    assert res.step_history[after, 2] == 1


def test_iterates_converge_superlinearly_on_a_curved_switch():
    """y' = -y, y(0) = 1; the switch y - 0.3 = 0 is at t = ln(1/0.3)."""

    def g(t, y, yp):
        return y[0] - 0.3

    g.terminal = True
    res = solve_dae(lambda t, y, yp: yp + y, (0, 5), [1.0], events=[g], rtol=1e-9, atol=1e-12)
    assert res.status == 1
    # The located time is exact for the computed solution; its error is the solution's
    # global error (~1e-8) divided by |y'| = 0.3.
    assert res.t[-1] == pytest.approx(np.log(1 / 0.3), rel=1e-6)
    iterates = res.event_log[0]["iterates"]
    assert abs(iterates[-1][1]) <= 1e-10
    assert len(iterates) <= 12  # a handful, as the seed's Table 10.1


def test_direction_filters_crossings():
    def g(t, y, yp):
        return np.sin(t)

    g.direction = 1  # only rising crossings: t = 2 pi, 4 pi
    # A sign change is seen at step ends: steps must be shorter than half a period.
    res = solve_dae(lambda t, y, yp: yp - 1.0, (0, 14), [0.0], events=[g], rtol=1e-8, max_step=1.0)
    np.testing.assert_allclose(res.t_events[0], [2 * np.pi, 4 * np.pi], rtol=1e-9)


def test_callback_streams_every_output_point():
    seen = []
    res = solve_dae(
        lambda t, y, yp: yp + y, (0, 1), [1.0], callback=lambda t, y, yp: seen.append(t)
    )
    assert seen == list(res.t)


def test_a_crossing_lost_at_a_restart_is_still_acted_on():
    """A switch whose new mode starts a little past its own zero, and moves further past.

    y' = -1 from y = 1. Mode A: g = y - 0.5 fires at t = 0.5 and enters mode B, whose
    g = y - 0.5 - 1e-9 is already -1e-9 at the restart and falls from there: there is
    no sign change left to see. (On plants: a volume switched to two-phase whose
    consistent state lands 1e-10 J/kg on the liquid side of h'; see
    SwitchFunction.missed.) B must still fire, at the restart, and enter mode C.
    Without the rule B never fires and the run ends in the wrong mode."""
    modes = ["A"]
    offset = {"A": 0.0, "B": -1e-9, "C": None}

    def residual(t, y, yp):
        return np.array([yp[0] + 1.0])

    def g(t, y, yp):
        off = offset[modes[-1]]
        return 1.0 if off is None else y[0] - 0.5 + off

    def action(t, y, yp):
        modes.append({"A": "B", "B": "C"}[modes[-1]])

    g.direction = -1
    g.action = action
    g.rearm = True  # each action starts a mode with its own g
    res = solve_dae(residual, (0.0, 1.0), [1.0], [-1.0], events=[g], rtol=1e-8, atol=1e-10)
    assert res.success
    assert modes == ["A", "B", "C"]
    # both fire at the located crossing of A, t = 0.5 to the location's few ulp
    assert res.t_events[0] == pytest.approx([0.5, 0.5], abs=1e-12)
    assert res.y[0, -1] == pytest.approx(0.0, abs=1e-8)  # y' = -1 is untouched by the modes
