"""plants/rankine.toml: a closed Rankine cycle (feed pump, flue-gas economiser, drum
heated by the furnace, flue-gas superheater, steam turbine, condenser). Its
steady-state cycle efficiency against a hand calculation with IF97 (CoolProp), its
balances, its response to a flue-gas step; and the node guesses that let the closed loop start.

Hand calculation (the same component parameters: pump efficiency eta_p, turbine
isentropic efficiency eta_t; the cycle's pressures and the live-steam temperature
from the run's steady state; every enthalpy from CoolProp's IF97):

    1 pump suction   h1 = h'(p_cond)                (saturated condensate)       [J/kg]
    2 pump outlet    h2 = h1 + (p2 - p1)/(rho(p1, h1) eta_p)
    3 live steam     h3 = h(p3, T3),  s3 = s(p3, h3)
    4 exhaust        h4 = h3 - eta_t (h3 - h(p4, s3))
    eta = ((h3 - h4) - (h2 - h1)) / (h3 - h2)                                    [-]

The simulated efficiency is (P_turbine - P_pump) / (Q_drum + Q_economiser +
Q_superheater), the heat inputs on the furnace / flue-gas side.
"""

from pathlib import Path

import numpy as np
import pytest
from CoolProp.CoolProp import PropsSI

from dnasim.plant.plantfile import load, simulate_plant
from dnasim.start.guess import initial_guess

ROOT = Path(__file__).resolve().parents[1]
WATER = "IF97::Water"
T_STEP = 4000.0  # s, the flue-gas step in plants/rankine.toml


@pytest.fixture(scope="module")
def rankine():
    loaded = load(ROOT / "plants" / "rankine.toml")
    res = simulate_plant(loaded.plant, loaded.simulation)
    assert res.success, res.message
    return loaded.plant, res


def _at(r, name, t):
    return float(np.interp(t, r.t, r[name]))


def efficiencies(plant, r, t):
    """(simulated, hand) cycle efficiency [-] at time t [s]."""
    P = plant.components
    eta_p, eta_t = P["pump"].params["eta"], P["turbine"].params["eta"]
    p_cond = _at(r, "condenser.p_v", t)
    p1, p2 = _at(r, "n_hotwell.p", t), _at(r, "n_pump.p", t)
    p3, T3 = _at(r, "n_live.p", t), _at(r, "n_live.T", t)
    p4 = _at(r, "n_exhaust.p", t)
    h1 = PropsSI("H", "P", p_cond, "Q", 0, WATER)
    rho1 = PropsSI("D", "P", p1, "H", h1, WATER)
    h2 = h1 + (p2 - p1) / (rho1 * eta_p)
    h3 = PropsSI("H", "P", p3, "T", T3, WATER)
    s3 = PropsSI("S", "P", p3, "H", h3, WATER)
    h4 = h3 - eta_t * (h3 - PropsSI("H", "P", p4, "S", s3, WATER))
    eta_hand = ((h3 - h4) - (h2 - h1)) / (h3 - h2)
    Q_in = sum(_at(r, k, t) for k in ("drum.Q_in", "economiser.Q_total", "superheater.Q_total"))
    eta_sim = (_at(r, "turbine.P", t) - _at(r, "pump.P", t)) / Q_in
    return eta_sim, eta_hand


def test_rankine_has_settled_at_the_end(rankine):
    # the efficiency comparison below needs a steady state: pump and turbine flows
    # equal and the live-steam temperature still; 1e-3 is the 0.1 % of the
    # efficiency test (a flow imbalance of x shifts the heat balance by about x)
    _, r = rankine
    m_p, m_t = r["pump.m"][-1], r["turbine.m"][-1]
    assert abs(m_p - m_t) < 1e-3 * m_t, (m_p, m_t)
    T = r["n_live.T"]
    assert abs(T[-1] - _at(r, "n_live.T", r.t[-1] - 200.0)) < 0.5  # K over the last 200 s


def test_rankine_has_settled_before_its_step(rankine):
    # the step response below is a response from a steady state only if the plant
    # has settled from its given start before the step: pump and turbine flows equal
    # to 1e-3 (as at the end), the live steam and the drum pressure still over the
    # last 200 s (0.5 K as at the end; 0.05 bar, 5e-4 of the pressure), the level
    # at its set point to 1 cm. With the step at 1500 s the flows differed by 2 %.
    _, r = rankine
    t = T_STEP - 1.0
    m_p, m_t = _at(r, "pump.m", t), _at(r, "turbine.m", t)
    assert abs(m_p - m_t) < 1e-3 * m_t, (m_p, m_t)
    assert abs(_at(r, "n_live.T", t) - _at(r, "n_live.T", t - 200.0)) < 0.5
    assert abs(_at(r, "drum.p", t) - _at(r, "drum.p", t - 200.0)) < 0.05e5
    assert abs(_at(r, "drum.level", t) - 2.0) < 0.01


def test_rankine_cycle_efficiency_matches_the_hand_calculation(rankine):
    plant, r = rankine
    eta_sim, eta_hand = efficiencies(plant, r, r.t[-1])
    # 0.1 % (the issue's): the run has settled (test above), so the heat taken from
    # the furnace and the flue gas is the water's enthalpy rise h3 - h2
    assert eta_sim == pytest.approx(eta_hand, rel=1e-3), (eta_sim, eta_hand)
    assert 0.30 < eta_sim < 0.40  # a Rankine cycle at 95 bar / 530 degC / 0.086 bar


def test_rankine_flue_gas_step_and_physical_states(rankine):
    # +10 % flue gas at 1500 s: the gas/water exchangers take more heat at once (the
    # gas side settles in < 1 s; 20 s later the walls have moved little): > 2 %
    _, r = rankine
    gas_heat = ("economiser.Q_total", "superheater.Q_total")
    before = sum(_at(r, k, T_STEP - 1.0) for k in gas_heat)
    after = sum(_at(r, k, T_STEP + 20.0) for k in gas_heat)
    assert after > 1.02 * before, (before, after)
    # the drum level is back at its set point (PI with integral action), to 1 cm
    assert abs(r["drum.level"][-1] - 2.0) < 0.01
    # the economiser never steams: its outlet stays below the drum's saturation
    # temperature (the economiser's own pressure is higher still)
    assert np.all(r["n_eco.T"] < r["drum.T"])
    # the live steam is superheated, flows stay forward
    assert np.all(r["n_live.T"] > r["drum.T"])
    assert np.all(r["pump.m"] > 0) and np.all(r["turbine.m"] > 0)


def test_node_guesses_stay_within_each_stream():
    # The gas side of a flue-gas/water heat exchanger must not take the water side's
    # pressure guess (it once started at the condenser's 0.08 bar), and the feed line
    # behind the pump must not start at suction pressure (it flashed to steam).
    loaded = load(ROOT / "plants" / "rankine.toml")
    system = loaded.plant.compile()
    y = initial_guess(system, 0.0)

    def p(node):
        return y[system.node_index[node]]

    assert p("g_eco") == pytest.approx(1e5, rel=0.2)  # the stack's 1 bar, not 0.08 bar
    pump = loaded.plant.components["pump"]
    # the discharge guess is 1 bar + rho g H(m_nominal) with 1000 kg/m3
    assert p("n_pump") > p("n_feed")  # above the drum: the feed valve starts forward
    assert pump.guess_nodes(0.0)["outlet"][0] > 100e5
