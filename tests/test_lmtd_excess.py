"""The bound on the LMTD's excess inside the upwind band (``physics.lmtd_excess_bound``,
``lmtd_excess_scale``; issue 20 item 9): exact where the steady-state energy balance says
it must be, smooth where it acts, and absent for volumes in flow."""

from __future__ import annotations

import numpy as np
import pytest

from dnasim.model import physics
from dnasim.model.physics import (
    LMTD_EXCESS_CAP,
    lmtd,
    lmtd_excess_bound,
    lmtd_excess_scale,
)

EPS = 2e-3  # a band [kg/s] (closed_feed_line_boiling: m_eps = 1e-3 x 2 kg/s)


def _steady_volume(N, m, cp=4200.0, kA=2000.0, dT_a=50.0):
    """A volume in steady single-phase flow m [kg/s] with NTU N: (dQ, H_x) [W] with the
    exact solution T_i - T_w = (T_a - T_w) e^-N, the LMTD of the channel's ``lmtd``."""
    kA = N * m * cp
    dT_i = dT_a * np.exp(-N)
    dT = lmtd(np.array([dT_a]), np.array([dT_i]), 1.0)
    H_x = m * cp * (dT_a - dT_i)  # = m (h_a - h_i), the energy balance's heat flow
    return kA * (dT - dT_i), H_x, kA


@pytest.mark.parametrize("N", [0.1, 1.0, 2.0, 2.66, 5.0, 10.0, 30.0])
def test_steady_states_are_left_exact_inside_the_band(N):
    # (1 - e^-N - N e^-N)/(1 - e^-N) < 1 for every NTU: the heat flow's excess over the
    # own-state form never exceeds the inflow's excess enthalpy at rest, so the bound
    # returns it untouched, even with the inflow well inside the band (a = 0.5 eps)
    m = 0.5 * EPS
    dQ, H_x, kA = _steady_volume(N, m)
    ratio = (1 - np.exp(-N) - N * np.exp(-N)) / (1 - np.exp(-N))
    # the regularised LMTD (dT_reg = 1 K against differences down to 50 e^-30 K) is not
    # the exact one where the outlet difference is within dT_reg: only the plain formula's
    # ratio is checked there
    if 50.0 * np.exp(-N) > 10.0:
        assert dQ[0] / H_x == pytest.approx(ratio, rel=1e-3)
    L = lmtd_excess_scale(np.array([m]), np.array([0.0]), np.array([H_x / m]),
                          np.array([0.0]), np.array([0.0]), kA * 1.0)  # fmt: skip
    a, b = np.array([m]), np.array([0.0])
    if abs(dQ[0]) <= L[0]:
        assert lmtd_excess_bound(dQ, L, a, b, EPS) is dQ


def test_volumes_in_flow_keep_the_plain_lmtd():
    # beyond the band (a + b >= eps) nothing is bounded, however large the excess
    dQ = np.array([1e6, -1e6])
    L = np.array([1.0, 1.0])
    a, b = np.array([EPS, 0.7 * EPS]), np.array([0.0, 0.3 * EPS])
    assert lmtd_excess_bound(dQ, L, a, b, EPS) is dQ


def test_at_rest_the_excess_saturates_below_cap_times_the_inflow_enthalpy():
    # at rest (a = b = w(0) = 3/16 eps: a + b = 3/8 eps, the blend fully on) the bounded
    # excess is odd, monotonic in dQ, equal to dQ up to L and below CAP L beyond
    w0 = float(physics.upwind_weight(0.0, EPS))
    # (plus the weight's tail, 2.5e-4 eps: physics.TAIL_REL)
    assert w0 == pytest.approx(3 / 16 * EPS, rel=2e-3)
    dQ = np.linspace(-50.0, 50.0, 20001)
    L = np.full_like(dQ, 2.0)
    a = b = np.full_like(dQ, w0)
    B = lmtd_excess_bound(dQ, L, a, b, EPS)
    inside = np.abs(dQ) <= 2.0
    assert np.array_equal(B[inside], dQ[inside])
    assert np.all(np.abs(B) <= LMTD_EXCESS_CAP * 2.0)  # tanh reaches 1.0 in floats
    assert np.all(np.diff(B) >= 0) and np.all(np.diff(B)[np.abs(dQ[1:]) < 8.0] > 0)
    np.testing.assert_allclose(B, -B[::-1], rtol=0, atol=1e-14)  # linspace: not exactly odd
    # C1 (indeed C2) at the join |dQ| = L: the slopes on both sides agree to the grid's
    # second-order difference error (spacing 5e-3: slope change ~ (r - 1)^2/w^2 ~ 1e-4)
    s = np.gradient(B, dQ)
    j = np.searchsorted(dQ, 2.0)
    assert abs(s[j - 3] - 1.0) < 1e-3 and abs(s[j + 3] - 1.0) < 1e-3


def test_the_band_blend_is_smooth_in_the_inflow():
    # between 0.4 eps (just above the rest weights) and the band's edge the bound is
    # blended out by a C2 step: the bounded excess moves continuously from L F(dQ/L) to
    # dQ, its slope at most 1.875 (the step's) times (dQ - L F)/(0.6 eps)
    dQ = np.full(2001, 10.0)
    L = np.ones(2001)
    s = np.linspace(0.3 * EPS, 1.1 * EPS, 2001)
    B = lmtd_excess_bound(dQ, L, s, np.zeros_like(s), EPS)
    assert B[0] == pytest.approx(1.0 + 0.5 * np.tanh(9.0 / 0.5))
    assert B[-1] == 10.0
    assert np.max(np.abs(np.diff(B))) < 9.0 * 1.875 / (0.6 * EPS) * (s[1] - s[0]) * 1.01


def test_scale_is_the_excess_enthalpy_inflow():
    # H_x = a (h_l - h_i) + b (h_r - h_i), floored by 1e-3 kA dT_reg
    L = lmtd_excess_scale(np.array([0.1]), np.array([0.05]), np.array([3.0e6]),
                          np.array([2.0e6]), np.array([1.0e6]), 2000.0)  # fmt: skip
    assert L[0] == pytest.approx(np.hypot(0.1 * 1e6 - 0.05 * 1e6, 2.0), rel=1e-12)
