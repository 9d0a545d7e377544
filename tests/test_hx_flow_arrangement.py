"""Gas/water heat exchanger (flue gas hot side, water cold side): parallel flow
against its epsilon-NTU closed form, and the per-side heat transfer coefficient
scaled with the flow, alpha = alpha_nom (m/m_nom)^0.8.

Closed forms (C = m cp with the mean cp of each stream over its own temperature
change, Cr = Cmin/Cmax, NTU = UA/Cmin, UA = 1/(1/kA_hot + 1/kA_cold)):

    counter flow   eps = (1 - exp(-NTU (1 - Cr))) / (1 - Cr exp(-NTU (1 - Cr)))
    parallel flow  eps = (1 - exp(-NTU (1 + Cr))) / (1 + Cr)
    Q = eps Cmin (T_hot,in - T_cold,in)                                         [W]
"""

import math

import pytest

from dnasim.library import HeatExchanger, MassFlowBoundary, PressureBoundary, Valve
from dnasim.plant.plant import Plant
from dnasim.start.initial import initial_values

KA_HOT, KA_COLD = 2000.0, 20000.0  # W/K at the nominal flows
M_GAS, M_WATER = 1.0, 2.0  # kg/s


def economiser(m_gas=M_GAS, **hx):
    p = Plant("economiser")
    p.add(MassFlowBoundary("gas_src", m=m_gas, T=600.0, medium="FlueGas", m_nominal=M_GAS))
    kw = dict(
        hot_V=0.5,
        cold_V=0.05,
        hot_kA=KA_HOT,
        cold_kA=KA_COLD,
        hot_k=100.0,
        cold_k=1e3,
        C_wall=1e4,
        n_sections=40,
        m_nominal=1.0,
    )
    kw.update(hx)
    p.add(HeatExchanger("hx", **kw))
    p.add(Valve("gas_valve", C=0.01, opening=1.0, m_nominal=M_GAS))
    p.add(PressureBoundary("gas_sink", p=1e5, medium="FlueGas", m_nominal=M_GAS))
    p.add(MassFlowBoundary("w_src", m=M_WATER, T=300.0, medium="Water", m_nominal=M_WATER))
    p.add(Valve("w_valve", C=0.01, opening=1.0, m_nominal=M_WATER))
    p.add(PressureBoundary("w_sink", p=10e5, medium="Water", m_nominal=M_WATER))
    for port, node in [
        ("gas_src.port", "g1"),
        ("hx.hot_in", "g1"),
        ("hx.hot_out", "g2"),
        ("gas_valve.inlet", "g2"),
        ("gas_valve.outlet", "g3"),
        ("gas_sink.port", "g3"),
        ("w_src.port", "w1"),
        ("hx.cold_in", "w1"),
        ("hx.cold_out", "w2"),
        ("w_valve.inlet", "w2"),
        ("w_valve.outlet", "w3"),
        ("w_sink.port", "w3"),
    ]:
        p.connect(port, node)
    return p


def steady(plant):
    system = plant.compile()
    y, yp = initial_values(system, 0.0, "steady")
    return dict(zip(system.output_names(), system.output_row(0.0, y, yp), strict=True))


def duty_and_closed_form(o, m_gas, kA_hot, kA_cold, arrangement):
    Q_hot = m_gas * (o["g1.h"] - o["g2.h"])
    Q_cold = M_WATER * (o["w2.h"] - o["w1.h"])
    # steady state: what the gas gives the water takes (Newton tolerance)
    assert Q_cold == pytest.approx(Q_hot, rel=1e-9)
    C_hot = Q_hot / (o["g1.T"] - o["g2.T"])
    C_cold = Q_cold / (o["w2.T"] - o["w1.T"])
    c_min, c_max = min(C_hot, C_cold), max(C_hot, C_cold)
    cr, ntu = c_min / c_max, 1.0 / (1.0 / kA_hot + 1.0 / kA_cold) / c_min
    if arrangement == "parallel":
        eps = (1 - math.exp(-ntu * (1 + cr))) / (1 + cr)
    else:
        eps = (1 - math.exp(-ntu * (1 - cr))) / (1 - cr * math.exp(-ntu * (1 - cr)))
    return Q_hot, eps * c_min * (o["g1.T"] - o["w1.T"]), eps


def test_parallel_flow_eps_ntu_with_two_media():
    o = steady(economiser(flow="parallel"))
    Q, Q_closed, eps = duty_and_closed_form(o, M_GAS, KA_HOT, KA_COLD, "parallel")
    # 0.5 %: as for counter flow (test_two_media_hx): the closed form holds for
    # constant cp, the flue gas's cp changes by a few % over its cooling
    assert Q == pytest.approx(Q_closed, rel=5e-3)
    assert 0.4 < eps < 0.9
    # parallel flow: both outlets at the same end, the water cannot leave hotter
    # than the gas
    assert o["w2.T"] < o["g2.T"]


def test_parallel_flow_transfers_less_than_counter_flow():
    Q_par = steady(economiser(flow="parallel"))
    Q_cnt = steady(economiser(flow="counter"))
    q_par = M_GAS * (Q_par["g1.h"] - Q_par["g2.h"])
    q_cnt = M_GAS * (Q_cnt["g1.h"] - Q_cnt["g2.h"])
    assert q_par < 0.99 * q_cnt


@pytest.mark.parametrize("arrangement", ["counter", "parallel"])
def test_gas_side_alpha_scales_with_flow_to_the_power_0_8(arrangement):
    m_gas = 0.5  # half the nominal gas flow
    o = steady(economiser(m_gas=m_gas, flow=arrangement, hot_kA_exponent=0.8, hot_m_kA=M_GAS))
    # the gas side's kA at half flow: kA_nom 0.5^0.8 (the regularisation flow
    # 1e-2 m_nominal changes it by 2e-4 relative, (m_reg/m)^2 0.8/2)
    kA_hot = KA_HOT * 0.5**0.8
    Q, Q_closed, _ = duty_and_closed_form(o, m_gas, kA_hot, KA_COLD, arrangement)
    assert Q == pytest.approx(Q_closed, rel=5e-3)
    # and not the closed form with the nominal kA (the scaling is visible: the
    # duties differ by 10 to 11 %, far beyond the 0.5 % tolerance)
    _, Q_nominal_kA, _ = duty_and_closed_form(o, m_gas, KA_HOT, KA_COLD, arrangement)
    assert abs(Q - Q_nominal_kA) > 0.03 * Q
