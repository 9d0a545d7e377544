"""A switch function that is exactly zero at t0 takes the mode the dynamics demand
(``dnasim.solver.events.SwitchFunction.arm``): the side the trajectory moves into
decides, however many derivatives of g vanish at t0.

The plant: a limiter y = max(u, 0) written with a mode, as the components write it
(mode "free": y = u, switch g = u, positive while the mode holds; mode "low": y = 0,
g = -u), and its integral z' = y. A drive x (x' = a(t)) makes u = c x; x(0) = 0, so
u starts exactly at the limit. Closed forms:

  u = -t     (first order, into the limit):  y = 0, z = 0
  u = -t^2/2 (second order: at rest at t0, as MSL's drum boiler): y = 0, z = 0
  u = +t^2/2 (away from the limit):           y = u, z = t^3/6
  u = t - t^2 (away, then into the limit at t = 1): z = 1/6 for t >= 1

Before the rule the first two ran in the free mode with y = u < 0 all along (the
element started at g = 0 and never changed sign): z = -t^2/2 and -t^3/6.
"""

import numpy as np
import pytest

from dnasim import solve_dae


def limiter_run(drive, u_of_x, t_end=2.0, y0_x=0.0):
    """Unknowns x, u, y, z; ``drive(t)`` = x', u = u_of_x(t, x). Returns (result, mode log)."""
    mode = {"m": "free"}
    log = []

    def residual(t, v, vp):
        x, u, y, z = v
        return np.array(
            [
                vp[0] - drive(t),
                u - u_of_x(t, x),
                y - (u if mode["m"] == "free" else 0.0),
                vp[3] - y,
            ]
        )

    def lower(t, v, vp):
        return v[1] if mode["m"] == "free" else -v[1]

    def toggle(t, v, vp):
        mode["m"] = "low" if mode["m"] == "free" else "free"
        log.append((t, mode["m"]))

    lower.direction = -1
    lower.action = toggle
    lower.name = "limiter.lower"
    res = solve_dae(
        residual,
        (0.0, t_end),
        np.array([y0_x, u_of_x(0.0, y0_x), max(u_of_x(0.0, y0_x), 0.0), 0.0]),
        algebraic=np.array([False, True, True, False]),
        events=[lower],
        rtol=1e-8,
        atol=1e-10,
    )
    assert res.success, res.message
    return res, log


def test_a_limit_reached_at_first_order_engages_at_t0():
    res, log = limiter_run(lambda t: 1.0, lambda t, x: -x)
    assert log[0] == (0.0, "low")  # at t0 itself, not a step later
    # y = 0 and z = 0 exactly in the low mode (1e-12: Newton's round-off on y = 0)
    assert np.max(np.abs(res.y[2])) < 1e-12 and np.max(np.abs(res.y[3])) < 1e-12
    assert len(log) == 1


def test_a_limit_reached_at_second_order_from_rest_engages_at_t0():
    # x' = t: dg/dt = 0 at t0, the second derivative moves g into the limit
    res, log = limiter_run(lambda t: t, lambda t, x: -x)
    assert log[0] == (0.0, "low") and len(log) == 1
    assert np.max(np.abs(res.y[3])) < 1e-12  # without the rule z(2) = -4/3


def test_a_limit_left_at_t0_stays_free():
    res, log = limiter_run(lambda t: t, lambda t, x: x)
    assert log == []
    # z = t^3/6 (BDF integrates the cubic to its tolerance; 1e-6 of z(2) = 4/3)
    assert res.y[3][-1] == pytest.approx(8.0 / 6.0, rel=1e-6)


def test_a_limit_first_left_then_reached_is_located_as_any_crossing():
    # u = t - t^2 = x - x^2 with x = t: positive on (0, 1), the limit engages at t = 1
    res, log = limiter_run(lambda t: 1.0, lambda t, x: x - x * x)
    assert len(log) == 1 and log[0][1] == "low"
    assert log[0][0] == pytest.approx(1.0, abs=1e-9)  # located (Brent) to the tolerance
    # z = int_0^1 (t - t^2) dt = 1/6 afterwards (rtol 1e-8 of the integration: 1e-7)
    assert res.y[3][-1] == pytest.approx(1.0 / 6.0, rel=1e-7)


def test_a_terminal_switch_at_zero_moving_out_stops_at_t0():
    # a vessel starting exactly full with inflow: its limit g = V_max - V fires at t0
    def residual(t, v, vp):
        return np.array([vp[0] - 1.0])

    def full(t, v, vp):
        return 1.0 - v[0]

    full.direction = -1
    full.terminal = True
    res = solve_dae(residual, (0.0, 5.0), np.array([1.0]), events=[full], rtol=1e-8, atol=1e-10)
    assert res.status == 1 and res.t[-1] == 0.0, (res.status, res.t[-1], res.message)


def test_a_terminal_switch_at_zero_moving_in_does_not_stop():
    def residual(t, v, vp):
        return np.array([vp[0] + 1.0])

    def full(t, v, vp):
        return 1.0 - v[0]

    full.direction = -1
    full.terminal = True
    res = solve_dae(residual, (0.0, 0.5), np.array([1.0]), events=[full], rtol=1e-8, atol=1e-10)
    assert res.status == 0 and res.t[-1] == 0.5
