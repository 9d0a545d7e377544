"""Component physics helpers: regularised LMTD, friction, valve law; a valve in reverse flow;
the anti-windup controller leaving saturation."""

import math
import warnings

import numpy as np
import pytest

from dnasim.core.timefunctions import Table
from dnasim.model.physics import (
    friction_dp,
    lmtd,
    logarithmic_mean,
    softplus,
    valve_flow,
)
from dnasim.plant.examples import attemperator_plant


def test_lmtd_exact_far_from_zero_and_plain_difference_when_equal():
    a, b = 300.0, 60.0
    # softplus(x, 1 K) = x + ln(1 + e^-x) + 1e-9 differs from x by e^-60 + 1e-9 (the
    # underflow floor), so the LMTD is exact to ~1e-9 K absolute: 1e-10 relative here
    assert math.isclose(lmtd(a, b, 1.0), (a - b) / math.log(a / b), rel_tol=1e-10)
    assert math.isclose(lmtd(-a, -b, 1.0), -(a - b) / math.log(a / b), rel_tol=1e-10)
    for d in (50.0, 1e-6, 1e-12):  # nearly equal differences: the series branch
        assert math.isclose(lmtd(d * (1 + 1e-9), d, 1e-3 * d), d, rel_tol=1e-6)
    # the series and the closed form meet continuously at |d| = 1e-3
    x = 1.0
    for y in (x * (1 - 2e-3) / (1 + 2e-3) * (1 + 1e-9), x * (1 - 2e-3) / (1 + 2e-3) * (1 - 1e-9)):
        assert math.isclose(logarithmic_mean(x, y), (x - y) / math.log(x / y), rel_tol=1e-12)


def test_lmtd_is_finite_and_smooth_everywhere():
    # during Newton iterations the two differences can have any signs: no log of a
    # non-positive number (no warning), finite values, finite slopes
    grid = np.linspace(-50, 50, 401)
    A, B = np.meshgrid(grid, grid)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        L = lmtd(A, B, 1.0)
        dL = (lmtd(A + 1e-6, B, 1.0) - lmtd(A - 1e-6, B, 1.0)) / 2e-6
    assert np.all(np.isfinite(L)) and np.all(np.isfinite(dL))
    # slope bounded (no infinite slope at a zero end difference): here <= 1 + a few
    assert np.max(np.abs(dL)) < 5.0
    # odd symmetry: heat flows the other way when both differences flip
    assert np.allclose(lmtd(-A, -B, 1.0), -L, atol=1e-12)


def test_lmtd_is_its_definition_bit_for_bit_at_any_array_length():
    # lmtd evaluates the four softplus values and the two logarithmic means of its
    # definition in stacked arrays; each element must come out exactly as from the
    # definition written out, and as when evaluated alone (a channel's volumes, or
    # several channels' volumes at once, give each volume the same number)
    rng = np.random.default_rng(7)
    for n in (1, 2, 4, 10, 33):
        a = rng.normal(size=n) * 10.0 ** rng.uniform(-3, 3, size=n)
        b = a + rng.normal(size=n) * 10.0 ** rng.uniform(-6, 2, size=n)
        reg = 0.5
        definition = logarithmic_mean(softplus(a, reg), softplus(b, reg)) - logarithmic_mean(
            softplus(-a, reg), softplus(-b, reg)
        )
        assert np.array_equal(lmtd(a, b, reg), definition)
        alone = np.array([lmtd(a[i : i + 1], b[i : i + 1], reg)[0] for i in range(n)])
        assert np.array_equal(lmtd(a, b, reg), alone)


def test_friction_and_valve_are_odd_with_finite_slope_at_zero():
    assert friction_dp(2.0, 3.0, 4.0, 1e-9) == 2.0 * 9.0 / 4.0
    assert friction_dp(2.0, -3.0, 4.0, 1e-9) == -2.0 * 9.0 / 4.0
    dp = 1e5
    # relative error of the regularised valve law: (dp_reg/dp)^2 / 4 = 2.5e-9
    assert math.isclose(valve_flow(1e-3, 0.5, dp, 10.0), 1e-3 * 0.5 * math.sqrt(dp), rel_tol=3e-9)
    assert valve_flow(1e-3, 0.5, -dp, 10.0) == -valve_flow(1e-3, 0.5, dp, 10.0)
    slope0 = (valve_flow(1e-3, 0.5, 1e-6, 10.0) - valve_flow(1e-3, 0.5, -1e-6, 10.0)) / 2e-6
    assert math.isclose(slope0, 1e-3 * 0.5 / math.sqrt(10.0), rel_tol=1e-6)


def test_anti_windup_leaves_saturation_bumplessly():
    # steam temperature up to 560 C (saturates the controller) and back to 480 C
    plant = attemperator_plant(anti_windup=True)
    plant.components["steam"].params["T"] = Table(
        [10.0, 60.0, 400.0, 450.0], [773.15, 833.15, 833.15, 753.15]
    )
    res = plant.simulate(800.0, start="steady", rtol=1e-6)
    assert res.success
    names = [e["name"] for e in res.events]
    assert names[:2] == ["pi.upper", "pi.upper"], names  # enter, then leave
    t_in, t_out = res.events[0]["t"], res.events[1]["t"]
    held = (res.t > t_in + 1e-9) & (res.t < t_out - 1e-9)
    # integrator held while saturated (to the integrator's tolerance)
    assert np.ptp(res["pi.m_I"][held]) < 1e-9
    # the output is continuous through the leaving switch (bumpless transfer)
    k = np.searchsorted(res.t, t_out)
    z = res["pi.z"]
    assert abs(z[k + 1] - 1.0) < 1e-3 and abs(z[k - 1] - 1.0) < 1e-9
    # and the controller closes the spray valve again as the steam cools
    after = res.t > t_out + 1.0
    assert np.all(z[after] < 1.0) and z[-1] < 0.9


def test_lmtd_excess_is_exact_in_steady_flow_and_bounded_by_the_inflow():
    from dnasim.model.physics import LMTD_EXCESS_EXACT, lmtd_excess, net_inflow

    # a steady plug-flow volume of constant c_p (closed form): T_out - T_w = (T_in -
    # T_w) e^-NTU, Q = m c_p (T_in - T_out), the own-state form kA (T_out - T_w); the
    # excess dQ = Q - kA (T_out - T_w) must come back unchanged (to the bit) for every
    # NTU up to 2.5 per volume, where dQ/H_x = 1 - NTU e^-NTU/(1 - e^-NTU) <= 0.78
    m, cp, dTin = 2.0, 4200.0, 50.0
    for ntu in (1e-3, 0.1, 1.0, 2.0, 2.5):
        kA = ntu * m * cp
        dTout = dTin * np.exp(-ntu)
        Q = m * cp * (dTin - dTout)
        dQ = Q - kA * dTout
        assert dQ / Q <= LMTD_EXCESS_EXACT
        assert lmtd_excess(np.array([dQ]), np.array([Q]), 1e-3 * kA)[0] == dQ
    # beyond the inflow's excess enthalpy it is capped at it, odd, and continuous with
    # a slope <= 1 in dQ (sampled at 1e-4 of L: a jump would show as a larger step)
    H = np.full(40001, 1000.0)
    dQ = np.linspace(-2000.0, 2000.0, 40001)
    B = lmtd_excess(dQ, H, 0.0)
    assert np.max(np.abs(B)) == pytest.approx(1000.0, rel=1e-12)
    np.testing.assert_allclose(B, -B[::-1], rtol=0, atol=1e-12 * 1000.0)  # round-off
    assert np.all(np.diff(B) >= 0) and np.max(np.diff(B)) <= np.diff(dQ)[0] * (1 + 1e-9)
    # the stalled case (closed_feed_line_boiling.toml at 357.7 s): the LMTD excess rises
    # by 79 kW as a face flow crosses the band m_eps = 2e-3 kg/s; H_x = net_inflow(m)
    # (h_up - h_i), h_up - h_i = 1.1 MJ/kg. Bounded, its slope in m is of the order of
    # h_up - h_i (< 2 of it, sampled), not 79 kW / 2e-3 kg/s = 4e7 W per kg/s
    eps, dh = 2e-3, 1.1e6
    mm = np.linspace(-4e-3, 4e-3, 8001)
    ramp = np.clip(mm / eps, 0.0, 1.0)
    B = lmtd_excess(79e3 * ramp, net_inflow(mm, eps) * dh, 1e-3 * 2000.0)
    assert np.max(np.abs(np.diff(B) / np.diff(mm))) < 2.0 * dh
    assert net_inflow(0.0, eps) == 0.0
    assert net_inflow(100 * eps, eps) == pytest.approx(100 * eps, rel=1e-4)
