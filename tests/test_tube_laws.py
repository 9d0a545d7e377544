"""The laws of dnasim.library.submodels.tube_laws, one by one, against the correlations they
are made of (the formulas of their module doc written out here), and their smoothness
through zero flow and the saturation line."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dnasim.correlations import boiling, condensation, friction, metals, radiation, tube_banks
from dnasim.library.submodels.tube_geometry import TubeBank, Tubes
from dnasim.library.submodels.tube_laws import (
    DOME,
    LIQUID,
    BankConvection,
    FluidProperties,
    PropertyMemos,
    TubeConvection,
    TubeFriction,
)
from dnasim.media import get_medium

WATER = get_medium("Water")


def states(medium, p, h):
    st = medium.states(np.asarray(p, float), np.asarray(h, float))
    return np.asarray(p, float), np.asarray(h, float), st.T, st.rho


def test_tube_geometry_numbers():
    t = Tubes(D=0.03, length=10.0, n_tubes=4, wall_thickness=0.004, metal=metals.metal("16Mo3"))
    assert t.V == pytest.approx(4 * math.pi * 0.03**2 / 4 * 10.0, rel=1e-15)
    assert t.wall_mass == pytest.approx(7822.0 * 4 * math.pi / 4 * (0.038**2 - 0.03**2) * 10.0)
    lam = 37.0
    whole = math.log(0.038 / 0.03) / (2 * math.pi * lam * 4 * 10.0)
    assert t.conduction_resistance(lam) == pytest.approx(whole, rel=1e-14)
    # the two half-shells in series are the whole wall
    halves = t.conduction_resistance(lam, "inner") + t.conduction_resistance(lam, "outer")
    assert halves == pytest.approx(whole, rel=1e-14)


def test_friction_single_and_two_phase_against_the_library():
    t = Tubes(D=0.025, length=20.0, n_tubes=4, roughness=4.5e-5)
    law = TubeFriction(t, n=4, m_reg=0.0)
    p = np.array([60e5, 60e5, 60e5])
    hl, hv = (float(v[0]) for v in WATER.saturation_enthalpies(p[:1]))
    h = np.array([1.0e6, hl + 0.3 * (hv - hl), hv + 2e5])  # liquid, two-phase, vapour
    fp = FluidProperties(WATER, *states(WATER, p, h))
    m = np.array([2.0, 2.0, 2.0])
    dp = law.dp(m, fp, np.arange(3))
    tr = WATER.transport(p[[0, 2]], h[[0, 2]])
    rho = WATER.states(p, h).rho
    for i, j in ((0, 0), (2, 1)):
        want = friction.pressure_drop(0.5, rho[i], tr["mu"][j], 0.025, 5.0, 4.5e-5)
        assert dp[i] == pytest.approx(float(want), rel=1e-12)
    s = WATER.saturation_transport(p[:1])
    want = friction.friedel_pressure_drop(
        0.5, 0.3, s["rho_l"][0], s["rho_v"][0], s["mu_l"][0], s["mu_v"][0], s["sigma"][0],
        0.025, 5.0, 4.5e-5,
    )  # fmt: skip
    # x of the state is 0.3 to round-off of the enthalpies
    assert dp[1] == pytest.approx(float(want), rel=1e-9)


def test_friction_is_odd_and_smooth_through_zero_flow():
    t = Tubes(D=0.05, length=40.0, n_tubes=3)
    law = TubeFriction(t, n=8, m_reg=0.1)
    p, h = np.full(1, 5e5), np.full(1, 3.4e5)
    fp = FluidProperties(WATER, *states(WATER, p, h))
    half = np.linspace(0.0, 0.5, 1001)
    m = np.concatenate((-half[:0:-1], half))
    dp = law.dp(m, fp, np.zeros(m.size, dtype=np.intp))
    np.testing.assert_array_equal(dp, -dp[::-1])  # odd: reverse flow, to the bit
    slope = np.diff(dp) / np.diff(m)
    assert slope.min() > 0 and np.isfinite(slope).all()  # monotone, finite slope at 0
    # C1: the slope changes by at most 2 % from one step of 5e-4 kg/s to the next (the
    # largest changes are in the laminar-turbulent blend, Re_r 2000 to 4000, whose
    # f Re has a bounded second derivative: 1.2 % measured; a kink would jump by a
    # sizeable fraction of the slope itself)
    assert np.max(np.abs(np.diff(slope)) / slope[1:]) < 0.02


def test_phase_weights_follow_the_modes_and_fade_in_without_them():
    p = np.full(4, 10e5)
    hl, hv = (float(v[0]) for v in WATER.saturation_enthalpies(p[:1]))
    h = np.array([hl - 1e4, hl + 0.005 * (hv - hl), hl + 0.5 * (hv - hl), hv + 1e4])
    args = states(WATER, p, h)
    fp = FluidProperties(WATER, *args)
    # without modes: 0 outside, the cubic ramp over the first 1 % of quality, 1 inside
    np.testing.assert_allclose(fp.w2, [0.0, 0.5, 1.0, 0.0], atol=1e-9)
    # a volume kept liquid (its mode) past h' is single phase with the saturated
    # liquid's properties; a volume in the dome mode takes the two-phase laws
    fpm = FluidProperties(WATER, *args, branch=np.array([LIQUID, LIQUID, DOME, 0]))
    assert list(fpm.w2) == [0.0, 0.0, 1.0, 0.0]
    s = WATER.saturation_transport(p[:1])
    assert fpm.mu[1] == s["mu_l"][0]


def test_convection_inside_single_and_boiling():
    metal = metals.metal("carbon steel")
    t = Tubes(D=0.025, length=30.0, n_tubes=4, wall_thickness=0.005, metal=metal)
    law = TubeConvection(t, n=10, m_reg=0.0)
    p = np.array([60e5, 60e5])
    hl, hv = (float(v[0]) for v in WATER.saturation_enthalpies(p[:1]))
    h = np.array([1.0e6, hl + 0.2 * (hv - hl)])
    fp = FluidProperties(WATER, *states(WATER, p, h), branch=np.array([0, DOME]))
    T_w = np.array([560.0, 565.0])
    UA = law.conductance(np.array([2.0, 2.0]), T_w, fp, np.arange(2))
    G = 0.5 / t.A_tube
    A_vol = t.A_inner / 10
    R_in = 10 * t.conduction_resistance(metal.conductivity(T_w), "inner")
    # single phase: VDI G1 (Gnielinski) with d/L of the whole tube
    tr = WATER.transport(p[:1], h[:1])
    mu, k, cp = tr["mu"][0], tr["k"][0], tr["cp"][0]
    from dnasim.correlations import heat_transfer

    h1 = heat_transfer.nusselt_tube(G * 0.025 / mu, mu * cp / k, 0.025 / 30.0, "T") * k / 0.025
    assert UA[0] == pytest.approx(1 / (1 / (h1 * A_vol) + R_in[0]), rel=1e-12)
    # boiling: Chen at the inner surface temperature, two fixed-point steps from T_w
    s = {key: v[0] for key, v in WATER.saturation_transport(p[:1]).items()}
    h_lv = s["h_v"] - s["h_l"]

    # Chen's and Shah's liquid coefficients by the law's own single-phase Nu (VDI G1)
    def nu(Re, Pr):
        return heat_transfer.nusselt_tube(Re, Pr, 0.025 / 30.0, "T")

    def h_two(T_s):
        dT = T_s - s["T"]
        dps = boiling.clapeyron_dp_sat(dT, s["T"], 60e5, h_lv, s["rho_l"], s["rho_v"])
        hb = boiling.chen_boiling(G, 0.2, 0.025, s["rho_l"], s["rho_v"], s["mu_l"], s["mu_v"],
                                  s["k_l"], s["cp_l"], h_lv, s["sigma"], dT, dps, 0.9,
                                  s["k_v"], s["cp_v"], nu)  # fmt: skip
        hc = condensation.shah_condensation(G, 0.2, 0.025, s["mu_l"], s["k_l"], s["cp_l"],
                                            60e5 / 22.064e6, nu)  # fmt: skip
        w = 0.5 * (1 + np.tanh(dT))
        return w * hb + (1 - w) * hc

    T_s = T_w[1]
    hh = h_two(T_s)
    for _ in range(2):
        R_c = 1 / (hh * A_vol)
        T_s = s["T"] + (T_w[1] - s["T"]) * R_c / (R_c + R_in[1])
        hh = h_two(T_s)
    assert UA[1] == pytest.approx(1 / (1 / (hh * A_vol) + R_in[1]), rel=1e-10)
    assert 2e4 < hh < 2e5  # nucleate boiling at 60 bar: tens of kW/(m2 K)


def test_two_phase_coefficient_joins_the_single_phase_one_at_the_lines():
    # at x = 0 (no wall superheat: no nucleate term) and at x = 1 the two-phase law
    # gives the single-phase law's coefficient of the saturated liquid and vapour:
    # a volume changing its phase mode sees no jump of h
    t = Tubes(D=0.025, length=30.0, n_tubes=4)
    law = TubeConvection(t, n=10, m_reg=0.0)
    p = np.full(2, 60e5)
    hl, hv = (float(v[0]) for v in WATER.saturation_enthalpies(p[:1]))
    args = states(WATER, p, np.array([hl, hv]))
    sat = WATER.saturation_transport(p[:1])
    T_sat = float(sat["T"][0])
    for branch in ([LIQUID, 3], [DOME, DOME]):
        fp = FluidProperties(WATER, *args, branch=np.array(branch))
        h, _ = law.h(np.array([2.0, 2.0]), np.array([T_sat, T_sat]), fp, np.arange(2))
        if branch[0] == LIQUID:
            single = h
        else:
            two = h
    # saturated-line states from (p, h') and (p, h''): round-off of the property calls
    np.testing.assert_allclose(two, single, rtol=1e-9)


def test_bank_with_fins_and_gas_radiation():
    metal = metals.metal("P235GH")
    t = Tubes(D=0.03, length=100.0, n_tubes=40, wall_thickness=0.004, metal=metal)
    bank = TubeBank(t, True, 0.1, 0.09, 30, None, 0.015, 0.0012, 0.008, metal)
    gas = get_medium("FlueGas")
    law = BankConvection(bank, n=5, m_reg=0.0, radiation=True, wall_emissivity=0.8)
    law.check_medium(gas, "eco")
    p = np.array([1.01e5])
    T = np.array([900.0])
    h = np.array([gas.h_pT(1.01e5, 900.0)])
    fp = FluidProperties(gas, p, h, T, gas.states(p, h).rho)
    T_w = np.array([600.0])
    UA = law.conductance(np.array([50.0]), T_w, fp, np.array([0]))
    tr = gas.transport(p, h)
    mu, k, cp = tr["mu"][0], tr["k"][0], tr["cp"][0]
    D_eff = 0.038 + 2 * 0.015 * 0.0012 / 0.008
    r = tube_banks.max_velocity(1.0, D_eff, 0.1, 0.09, True)
    Re = 50.0 / bank.A_front * r * 0.038 / mu
    hc = tube_banks.nusselt_zukauskas(Re, mu * cp / k, 30, 0.1, 0.09, True) * k / 0.038
    eta = tube_banks.annular_fin_efficiency(hc, metal.conductivity(600.0), 0.0012, 0.019, 0.034)
    eta0 = tube_banks.finned_surface_efficiency(eta, bank.A_fin, bank.A_out)
    x = gas.mole_fractions
    eps_g = radiation.gas_emissivity(900.0, x["H2O"] * 1.01e5, x["CO2"] * 1.01e5, bank.beam_length)
    q = radiation.gas_wall_heat_flux(900.0, 600.0, eps_g, 0.8)
    G_out = eta0 * hc * bank.A_out / 5 + q / 300.0 * t.A_outer / 5
    R_out = 5 * t.conduction_resistance(metal.conductivity(600.0), "outer")
    assert UA[0] == pytest.approx(1 / (1 / G_out + R_out), rel=1e-12)
    assert 0.5 < eta0 < 1.0 and 0.05 < eps_g < 0.3  # fins, a thin gas layer


def test_bank_radiation_needs_a_gas_with_composition():
    from dnasim.core.errors import PlantError

    t = Tubes(D=0.03, length=10.0, n_tubes=4, wall_thickness=0.004, metal=metals.metal("P235GH"))
    law = BankConvection(TubeBank(t, False, 0.08, 0.08, 4), n=2, radiation=True)
    with pytest.raises(PlantError, match="composition"):
        law.check_medium(get_medium("Air"), "eco")


def test_property_memos_recompute_only_what_changed():
    p = np.linspace(40e5, 60e5, 12)
    h = np.linspace(1.0e6, 2.6e6, 12)
    memos = PropertyMemos(WATER)
    args = states(WATER, p, h)
    first = FluidProperties(WATER, *args, memos=memos)
    p2 = p.copy()
    p2[3] *= 1.001
    args2 = states(WATER, p2, h)
    again = FluidProperties(WATER, *args2, memos=memos)
    fresh = FluidProperties(WATER, *args2)
    for key in ("mu", "k", "cp", "x", "w2"):
        np.testing.assert_array_equal(getattr(again, key), getattr(fresh, key))
    assert not np.array_equal(first.mu, again.mu)
