"""Component physics helpers: regularised LMTD, friction, valve law; a valve in reverse flow;
the anti-windup controller leaving saturation."""

import math
import warnings

import numpy as np

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
