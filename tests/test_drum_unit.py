"""The whole drum unit, plants/drum_unit.toml (issue 22 item 7): its steady state at
full load against a hand heat balance with IF97 (CoolProp's, not dnasim's), the
mass and energy balance over the 100 -> 50 -> 100 % load change, the controls doing
their work, and the run through the CLI.

The hand heat balance (``hand_balance``) takes the operating points of the steady
state, pressures and temperatures as an engineer reads them off the instruments
(drum, live steam, turbine stage pressures, the heaters' outlets and drains, the
deaerator, the pumps' suction and discharge), and the heat inputs of the plant file;
from these alone it computes, stage by stage with IF97 enthalpies, the steam and
feed flows (boiler and superheater energy balances), the expansion lines (the
turbine groups' efficiencies), the extraction flows (the two HP heaters', the
deaerator's and the two LP heaters' energy and mass balances), the shaft powers, the
net power and the cycle efficiency; these are compared with the simulation's.
``design_balance`` is the design heat balance the plant was sized from (the
plant file's header), compared more loosely: the heaters and the deaerator settle
where their components put them, not at the design's round numbers.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from CoolProp.CoolProp import PropsSI
from plant_checks import stored

from dnasim.cli.commands import main
from dnasim.library.pump import Pump
from dnasim.plant.plantfile import load, simulate_plant
from dnasim.run.output import read_results_csv

PLANT = Path(__file__).resolve().parent.parent / "plants" / "drum_unit.toml"
IF97 = "IF97::Water"

#: the heat inputs at 100 % load [W] (the plant file's tables before 300 s)
Q = {
    "economiser": 49.8e6,
    "drum": 111.8e6,
    "sh1": 50.6e6,
    "sh2": 36.0e6,
    "reheater": 39.8e6,
}
#: the turbine groups' isentropic efficiencies
ETA = {"hp": 0.87, "ip1": 0.90, "ip2": 0.90, "lp1a": 0.88, "lp1b": 0.88, "lp2": 0.85}
ETA_PUMP = 0.8  # both pumps


def h_pT(p, T):
    return PropsSI("H", "P", p, "T", T, IF97)


def h_sat(p, q):
    return PropsSI("H", "P", p, "Q", q, IF97)


def expand(p1, h1, p2, eta):
    """h_2 [J/kg] of an expansion from (p1, h1) to p2 with isentropic efficiency eta."""
    s1 = PropsSI("S", "P", p1, "H", h1, IF97)
    return h1 - eta * (h1 - PropsSI("H", "P", p2, "S", s1, IF97))


def hand_balance(v):
    """The cycle's flows and powers from its operating points v (pressures [Pa],
    temperatures [K], the blow-down flow [kg/s]); see the module docstring."""
    h = {}
    out = {}
    p_d = v["p_drum"]
    h_l, h_v = h_sat(p_d, 0), h_sat(p_d, 1)
    h_fw = h_pT(v["p_hph"], v["T_hph"])  # feed water after HPH1 (the upper HP heater)
    h_fw2 = h_pT(v["p_hph2"], v["T_hph2"])  # between HPH2 and HPH1
    h_fp = h_pT(v["p_fp"], v["T_fp"])  # feed pump discharge (and the spray water)
    h_ms = h_pT(v["p_ms"], v["T_ms"])  # live steam
    m_bd = v["m_bd"]
    # economiser + drum: m_feed h_fw + Q = m_s h'' + m_bd h', m_feed = m_s + m_bd
    m_s = (Q["economiser"] + Q["drum"] - m_bd * (h_l - h_fw)) / (h_v - h_fw)
    m_feed = m_s + m_bd
    # superheaters and spray: m_s h'' + m_sp h_fp + Q_sh = (m_s + m_sp) h_ms
    m_sp = (Q["sh1"] + Q["sh2"] - m_s * (h_ms - h_v)) / (h_ms - h_fp)
    m_ms = m_s + m_sp
    # HP turbine (after the isenthalpic turbine valve)
    h["crh"] = expand(v["p_hp"], h_ms, v["p_crh"], ETA["hp"])
    # HPH1 (cold reheat): m_feed (h_fw - h_fw2) = m_hph (h_crh - h_drain)
    h_hd = h_pT(v["p_hph_drain"], v["T_hph_drain"])
    m_hph = m_feed * (h_fw - h_fw2) / (h["crh"] - h_hd)
    # reheater (the pegging valve is shut at full load: its leakage, ~3e-5 kg/s, is
    # left out), reheat spray after it: m_rh h_rho + m_rsp h_fp = (m_rh + m_rsp) h_hrh
    m_rh = m_ms - m_hph
    h["rho"] = h["crh"] + Q["reheater"] / m_rh
    out["T_rho"] = PropsSI("T", "P", v["p_rho"], "H", h["rho"], IF97)
    h["hrh"] = h_pT(v["p_hrh"], v["T_hrh"])  # after the reheat spray (controlled)
    m_rsp = m_rh * (h["rho"] - h["hrh"]) / (h["hrh"] - h_fp)
    m_ip1 = m_rh + m_rsp
    # IP1 to the HPH2 extraction; HPH2: m_feed (h_fw2 - h_fp) = m_hph2 (h_ipx - h_drain2)
    h["ipx"] = expand(v["p_hrh"], h["hrh"], v["p_ipx"], ETA["ip1"])
    h_hd2 = h_pT(v["p_hph2_drain"], v["T_hph2_drain"])
    m_hph2 = m_feed * (h_fw2 - h_fp) / (h["ipx"] - h_hd2)
    m_ip2 = m_ip1 - m_hph2
    h["xo"] = expand(v["p_ipx"], h["ipx"], v["p_xo"], ETA["ip2"])
    # deaerator, both HP heaters draining to it: m_c h_c + m_hph h_hd + m_hph2 h_hd2
    # + m_da h_xo = m_fp h'(p_da), m_c + m_hph + m_hph2 + m_da = m_fp
    m_fp = m_feed + m_sp + m_rsp
    h_c = h_pT(v["p_lph2"], v["T_lph2"])  # condensate after LPH2 (isenthalpic valve)
    h_da = h_sat(v["p_da"], 0)
    m_dr = m_hph + m_hph2
    m_da = (m_fp * h_da - m_hph * h_hd - m_hph2 * h_hd2 - (m_fp - m_dr) * h_c) / (h["xo"] - h_c)
    m_cond = m_fp - m_dr - m_da
    # LP turbine groups and the two LP heaters, each draining to the condenser. LPH2
    # (extraction between LP1a and LP1b): m_cond (h_c - h_c1) = m_lph2 (h_lpx - h_ld2);
    # LPH1 (between LP1b and LP2): m_cond (h_c1 - h_cp) = m_lph (h_lp - h_ld)
    m_lp1a = m_ip2 - m_da
    h["lpx"] = expand(v["p_xo"], h["xo"], v["p_lpx"], ETA["lp1a"])
    h_c1 = h_pT(v["p_lph"], v["T_lph"])  # condensate between LPH1 and LPH2
    h_ld2 = h_pT(v["p_lph2_drain"], v["T_lph2_drain"])
    m_lph2 = m_cond * (h_c - h_c1) / (h["lpx"] - h_ld2)
    m_lp1b = m_lp1a - m_lph2
    h["lp"] = expand(v["p_lpx"], h["lpx"], v["p_lp"], ETA["lp1b"])
    h_cp = h_pT(v["p_cp"], v["T_cp"])
    h_ld = h_pT(v["p_lph_drain"], v["T_lph_drain"])
    m_lph = m_cond * (h_c1 - h_cp) / (h["lp"] - h_ld)
    m_lp2 = m_lp1b - m_lph
    h["exh"] = expand(v["p_lp"], h["lp"], v["p_exh"], ETA["lp2"])
    P_t = {
        "hp": m_ms * (h_ms - h["crh"]),
        "ip1": m_ip1 * (h["hrh"] - h["ipx"]),
        "ip2": m_ip2 * (h["ipx"] - h["xo"]),
        "lp1a": m_lp1a * (h["xo"] - h["lpx"]),
        "lp1b": m_lp1b * (h["lpx"] - h["lp"]),
        "lp2": m_lp2 * (h["lp"] - h["exh"]),
    }
    # pumps: P = m dp/(rho_suction eta)
    rho_hw = PropsSI("D", "P", v["p_hw"], "T", v["T_hw"], IF97)
    rho_fps = PropsSI("D", "P", v["p_fps"], "T", v["T_fps"], IF97)
    P_cp = m_cond * (v["p_cp"] - v["p_hw"]) / (rho_hw * ETA_PUMP)
    P_fp = m_fp * (v["p_fp"] - v["p_fps"]) / (rho_fps * ETA_PUMP)
    Q_in = sum(Q.values())
    net = sum(P_t.values()) - P_cp - P_fp
    out.update(
        m_steam=m_ms,
        m_feed=m_feed,
        m_spray=m_sp,
        m_rh_spray=m_rsp,
        m_hph=m_hph,
        m_hph2=m_hph2,
        m_da=m_da,
        m_cond=m_cond,
        m_lph=m_lph,
        m_lph2=m_lph2,
        P_hp=P_t["hp"],
        P_ip=P_t["ip1"] + P_t["ip2"],
        P_lp=P_t["lp1a"] + P_t["lp1b"] + P_t["lp2"],
        P_pumps=P_cp + P_fp,
        Q_in=Q_in,
        net=net,
        eta=net / Q_in,
    )
    return out


def design_balance():
    """The design heat balance the plant was sized from (the plant file's header):
    100 kg/s at 130 bar / 540 degC, cold reheat 36 bar, hot reheat 34 bar / 540 degC,
    IP extraction 15 bar (HPH2), crossover 6 bar, LP extractions 2.5 bar (LPH2) and
    1.2 bar (LPH1), condenser 0.07 bar; heaters 5 K below the saturation of their
    (1 bar lower; LP: 0.1 bar lower) shells, drains saturated (both HP heaters' to
    the deaerator); deaerator 5.5 bar with
    1.8 bar of static head at the feed pump; feed pump 170 bar, condensate pump 10
    bar; spray 3 kg/s, blow-down 1 kg/s, drum 140 bar."""
    bar = 1e5
    m_ms, m_bd, m_sp = 100.0, 1.0, 3.0
    h_ms = h_pT(130 * bar, 813.15)
    h_crh = expand(130 * bar, h_ms, 36 * bar, ETA["hp"])
    h_hrh = h_pT(34 * bar, 813.15)
    h_ipx = expand(34 * bar, h_hrh, 15 * bar, ETA["ip1"])
    h_xo = expand(15 * bar, h_ipx, 6 * bar, ETA["ip2"])
    h_lpx = expand(6 * bar, h_xo, 2.5 * bar, ETA["lp1a"])
    h_lp = expand(2.5 * bar, h_lpx, 1.2 * bar, ETA["lp1b"])
    h_exh = expand(1.2 * bar, h_lp, 0.07 * bar, ETA["lp2"])
    h_hw = h_sat(0.07 * bar, 0)
    rho_hw = PropsSI("D", "P", 0.07 * bar, "Q", 0, IF97)
    h_cp = h_hw + (10 - 0.07) * bar / (rho_hw * ETA_PUMP)
    h_da = h_sat(5.5 * bar, 0)
    rho_da = PropsSI("D", "P", 5.5 * bar, "Q", 0, IF97)
    h_fp = h_da + (170 - 7.3) * bar / (rho_da * ETA_PUMP)
    T_sat = lambda p: PropsSI("T", "P", p, "Q", 0, IF97)  # noqa: E731
    h_fw = h_pT(160 * bar, T_sat(35 * bar) - 5)  # after HPH1
    h_fw2 = h_pT(165 * bar, T_sat(14 * bar) - 5)  # after HPH2
    m_feed = m_ms - m_sp + m_bd
    m_fp = m_feed + m_sp
    m_hph = m_feed * (h_fw - h_fw2) / (h_crh - h_sat(35 * bar, 0))
    m_hph2 = m_feed * (h_fw2 - h_fp) / (h_ipx - h_sat(14 * bar, 0))
    h_dr = m_hph * h_sat(35 * bar, 0) + m_hph2 * h_sat(14 * bar, 0)  # the drains [W]
    h_c1 = h_pT(9.5 * bar, T_sat(1.1 * bar) - 5)  # after LPH1
    h_c = h_pT(9.2 * bar, T_sat(2.4 * bar) - 5)  # after LPH2
    m_da = (m_fp * h_da - h_dr - (m_fp - m_hph - m_hph2) * h_c) / (h_xo - h_c)
    m_cond = m_fp - m_hph - m_hph2 - m_da
    m_lph2 = m_cond * (h_c - h_c1) / (h_lpx - h_sat(2.4 * bar, 0))
    m_lph = m_cond * (h_c1 - h_cp) / (h_lp - h_sat(1.1 * bar, 0))
    m_rh = m_ms - m_hph
    m_lp1 = m_rh - m_hph2 - m_da
    P_t = (
        m_ms * (h_ms - h_crh)
        + m_rh * (h_hrh - h_ipx)
        + (m_rh - m_hph2) * (h_ipx - h_xo)
        + m_lp1 * (h_xo - h_lpx)
        + (m_lp1 - m_lph2) * (h_lpx - h_lp)
        + (m_lp1 - m_lph2 - m_lph) * (h_lp - h_exh)
    )
    P_p = m_cond * (h_cp - h_hw) + m_fp * (h_fp - h_da)
    p_d = 140 * bar
    Q_in = (
        m_feed * (h_sat(p_d, 1) - h_fw)
        - m_bd * (h_sat(p_d, 1) - h_sat(p_d, 0))
        + m_ms * h_ms
        - (m_ms - m_sp) * h_sat(p_d, 1)
        - m_sp * h_fp
        + m_rh * (h_hrh - h_crh)
    )
    return {
        "m_steam": m_ms,
        "m_feed": m_feed,
        "m_hph": m_hph,
        "m_hph2": m_hph2,
        "net": P_t - P_p,
        "Q_in": Q_in,
        "eta": (P_t - P_p) / Q_in,
    }


@pytest.fixture(scope="module")
def run():
    """The plant file's whole scenario (3300 s), with its own settings; CPU seconds."""
    loaded = load(PLANT)
    t0 = time.process_time()
    res = simulate_plant(loaded.plant, loaded.simulation)
    return loaded.plant, res, time.process_time() - t0


def operating_points(res, k=0):
    """The instruments' readings at row k: pressures [Pa], temperatures [K]."""
    v = {}
    for key, node in [
        ("hph", "n_hph"), ("fp", "n_fp"), ("ms", "n_ms"), ("hp", "n_hp"), ("crh", "n_crh"),
        ("rho", "n_rho"), ("hrh", "n_hrh"), ("xo", "n_xo"), ("lp", "n_lp"), ("exh", "n_exh"),
        ("lph", "n_lph"), ("cp", "n_cp"), ("hw", "n_hw"), ("fps", "n_fps"),
        ("hph_drain", "n_hph_drain"), ("lph_drain", "n_lph_drain"), ("lpx", "n_lpx"),
        ("lph2", "n_lph2"), ("lph2_drain", "n_lph2_drain"), ("hph2", "n_hph2"),
        ("ipx", "n_ipx"), ("hph2_drain", "n_hph2_drain"),
    ]:  # fmt: skip
        v[f"p_{key}"] = res[f"{node}.p"][k]
        v[f"T_{key}"] = res[f"{node}.T"][k]
    v["p_drum"] = res["drum.p"][k]
    v["p_da"] = res["deaerator.p"][k]
    v["m_bd"] = res["blowdown.m"][k]
    return v


def simulated(res, k=0):
    P = lambda name: res[f"{name}.P"][k]  # noqa: E731 - a turbine's P: delivered [W]
    pumps = res["condensate_pump.P"][k] + res["feed_pump.P"][k]
    turbines = P("hp") + P("ip1") + P("ip2") + P("lp1a") + P("lp1b") + P("lp2")
    Q_in = sum(Q.values())  # the given heat fluxes: at rest each reaches its fluid
    return {
        "m_steam": res["turbine_valve.m"][k],
        "m_feed": res["feed_valve.m"][k],
        "m_spray": res["spray_valve.m"][k],
        "m_rh_spray": res["rh_spray_valve.m"][k],
        "m_hph": res["hph_drain.m"][k],
        "m_hph2": res["hph2_drain.m"][k],
        "m_da": res["da_steam_valve.m"][k],
        "m_cond": res["condensate_valve.m"][k],
        "m_lph": res["lph_drain.m"][k],
        "m_lph2": res["lph2_drain.m"][k],
        "P_hp": P("hp"),
        "P_ip": P("ip1") + P("ip2"),
        "P_lp": P("lp1a") + P("lp1b") + P("lp2"),
        "P_pumps": pumps,
        "net": turbines - pumps,
        "eta": (turbines - pumps) / Q_in,
        "T_rho": res["n_rho.T"][k],
    }


def test_full_load_steady_state_against_the_hand_heat_balance(run):
    _, res, _ = run
    hand = hand_balance(operating_points(res))
    sim = simulated(res)
    # The hand balance reads temperatures and uses CoolProp's IF97 (forward h(p, T),
    # s(p, h), h(p, s)); the extraction flows divide by enthalpy differences of
    # 240-2800 kJ/kg. Measured (benchmarks/drum_unit.py): flows <= 5e-6 but the
    # deaerator's extraction, 1.6e-5 (2.5 kg/s, a difference of larger flows), turbine
    # powers <= 4.2e-5 (h(p, s) of the wet LP exhaust), net power and efficiency
    # 1.1e-5, reheater outlet 7 mK. Tolerances 3e-4: a few times the largest of these.
    for key in ("m_steam", "m_feed", "m_spray", "m_cond", "m_hph", "m_hph2", "m_da", "m_lph",
                "m_lph2"):  # fmt: skip
        assert sim[key] == pytest.approx(hand[key], rel=3e-4), key
    # The reheat spray is a small difference: m_rh (h_rho - h_hrh)/(h_hrh - h_fp) with
    # h_rho - h_hrh ~ 15 kJ/kg, so the reheater outlet's 7 mK (~17 J/kg) become
    # ~5e-4 kg/s of its 0.45 kg/s; measured -4.0e-4 relative. Tolerance 2e-3.
    assert sim["m_rh_spray"] == pytest.approx(hand["m_rh_spray"], rel=2e-3)
    for key in ("P_hp", "P_ip", "P_lp", "P_pumps", "net", "eta"):
        assert sim[key] == pytest.approx(hand[key], rel=3e-4), key
    assert sim["T_rho"] == pytest.approx(hand["T_rho"], abs=0.05)  # [K], reheater outlet


def test_full_load_steady_state_near_the_design_heat_balance(run):
    # The design heat balance's round numbers (the plant file's header). The steady
    # state differs where the components, not the design's round numbers, decide: the
    # HP heater's counter-flow shell desuperheats the extraction over the feed-water
    # outlet (251 degC against the design's 238), both shells sub-cool their drains
    # (design: saturated), the spray settles at 1.3 kg/s (design 3), the hot reheat
    # is held at 522 degC by a reheat spray of 0.45 kg/s (design: 540 degC, no
    # spray); and the plant file's heat inputs came from a first balance that counted
    # the spray's heat twice (284.0 MW against this balance's 279.3 MW; with HPH2
    # and the reheater's 39.8 MW: 288.0 against 282.1). HPH2 heats the feed water to
    # 207 degC (design 190), so its extraction is 9.0 kg/s (design 5.4). Measured:
    # heat input +2.1 %, steam flow +6.1 %, net power +4.1 %, efficiency +0.87
    # points. Tolerances: 2.5 % on the heat, 8 % on
    # the steam flow and the power, 1.5 points on the efficiency.
    _, res, _ = run
    design = design_balance()
    sim = simulated(res)
    assert design["Q_in"] == pytest.approx(sum(Q.values()), rel=0.025)
    assert sim["m_steam"] == pytest.approx(design["m_steam"], rel=0.08)
    # (the economiser's feed flow is not compared: with the design's spray of 3 kg/s
    # it carries 98 kg/s, the simulation 105.1)
    assert sim["net"] == pytest.approx(design["net"], rel=0.08)
    assert sim["eta"] == pytest.approx(design["eta"], abs=0.015)


def test_mass_and_energy_balance_over_the_load_change(run):
    plant, res, cpu = run
    M, E = stored(plant, res)
    bounds = ["blowdown_sink", "makeup", "cw_supply", "cw_return"]
    M_in = sum(res[f"{b}.M_passed"] for b in bounds)
    H_in = sum(res[f"{b}.H_passed"] for b in bounds)
    Q_out = sum(res[f"{c}.Q_passed"] for c in plant.components if f"{c}.Q_passed" in res)
    W_in = sum(
        (1.0 if isinstance(c, Pump) else -1.0) * res[f"{c.name}.W"]
        for c in plant.components.values()
        if f"{c.name}.W" in res
    )
    err_M = np.max(np.abs((M - M[0]) - (M_in - M_in[0])))
    err_E = np.max(np.abs((E - E[0]) - (H_in - H_in[0]) + (Q_out - Q_out[0]) - (W_in - W_in[0])))
    # throughputs: the water through the cycle (~100 kg/s over 3300 s) and the heat
    # (~280 MW). The components' fluxes are conservative (upwind energy flows at the
    # nodes, the drum's and the tanks' own balances), so the mass balance closes to
    # round-off (measured 5.5e-15 of the throughput); the energy balance to the
    # integration of the tube walls' m c(T) dT/dt against their stored e(T) (walls
    # from geometry, steel's c(T)): measured 6.7e-10.
    thr_M = np.trapezoid(res["feed_valve.m"], res.t)
    thr_E = np.sum(np.abs(np.diff(Q_out)))
    assert thr_M > 2e5 and thr_E > 5e11
    assert err_M < 1e-10 * thr_M
    assert err_E < 1e-7 * thr_E


def test_load_change_is_followed_and_the_controls_hold(run):
    _, res, _ = run
    t = res.t
    m = res["turbine_valve.m"]
    m0 = m[0]
    half = (t > 1400) & (t < 1800)  # 50 % firing, settled
    # the steam flow follows the firing (measured 0.467-0.476 of full load: the feed
    # water is colder at part load, so half the heat makes less than half the steam)
    assert np.all(np.abs(m[half] / m0 - 0.48) < 0.04)
    # drum pressure held at 140 bar by the turbine valve (+-2 bar; measured 1.3 bar)
    assert np.max(np.abs(res["drum.p"] - 140e5)) < 2e5
    # drum level within +-0.1 m of its 2.5 m set point (three-element; measured 0.04)
    assert np.max(np.abs(res["drum.level"] - 2.5)) < 0.1
    # live steam within +-10 K of 540 degC (measured 3.9 K), +-3 K in the last 300 s
    T = res["n_ms.T"] - 813.15
    assert np.max(np.abs(T)) < 10.0 and np.max(np.abs(T[t > 3000])) < 3.0
    # deaerator and hotwell levels stay in their vessels' working ranges (measured
    # 2.08-3.00 m and 0.33-1.79 m: the ramp down moves water from the hotwell to the
    # deaerator, the make-up saturates at 5 kg/s, and it flows back at 50 %)
    assert 2.0 < np.min(res["deaerator.level"]) and np.max(res["deaerator.level"]) < 3.2
    assert 0.2 < np.min(res["condenser.level"]) and np.max(res["condenser.level"]) < 2.0
    # the feed water cools at part load (the HP heater's extraction pressure falls)
    T_fw = res["n_hph.T"]
    assert np.min(T_fw[half]) < T_fw[0] - 10.0
    # the economiser does not steam: its outlet stays subcooled at its own pressure
    # (~170 bar; measured >= 120 kJ/kg below h'; the feed valve then throttles it to
    # the drum's 140 bar, where it arrives from 7 kJ/kg subcooled at full load to
    # saturated, within 0.1 kJ/kg, at 2750 s during the ramp back up)
    h_l = np.array([h_sat(p, 0) for p in res["n_eco.p"]])
    assert np.min(h_l - res["n_eco.h"]) > 50e3
    # and at the end the unit is back near full load
    assert m[-1] == pytest.approx(m0, rel=0.03)


# Deaerator pressure bands [Pa]. Measured (benchmarks/drum_unit.py): 5.24-5.69 bar
# over the whole run (with HPH2: 5.24-5.68 bar, at 50 % 5.29-5.34) (0.06 bar
# below the pegging set point while the ramp down
# outruns the pegging PI, 0.19 bar above 5.5 bar on the ramp up, at 2410 s); at 50
# %, 1400-1800 s, 5.34-5.39 bar, within 0.09 bar of 5.3 bar; after 3100 s within
# 0.009 bar of 5.5 bar. The bands are these with a margin of about 1.1 to 10 times
# (1.1 on the whole run's upper edge: 5.69 bar against 5.8).
BAND_DA = 0.3e5
BAND_DA_HALF = 0.15e5
BAND_DA_END = 0.1e5


def test_deaerator_pressure_is_held_by_extraction_and_pegging_steam(run):
    _, res, _ = run
    t = res.t
    p_da = res["deaerator.p"]
    half = (t > 1400) & (t < 1800)  # 50 % firing, settled
    # full load: the extraction's control valve holds the set point 5.5 bar (the
    # steady start: to the solver's tolerance), the pegging valve shut (its leakage)
    assert p_da[0] == pytest.approx(5.5e5, rel=1e-6)
    assert res["pegging_valve.m"][0] < 1e-3
    # half load: the crossover lies below the deaerator, the non-return valve is
    # shut (at most its leakage, backwards). The pegging steam opens on the way down
    # (measured up to 5.6 kg/s at 930 s); at 50 % the deaerator stays just above its
    # 5.3 bar set point, held by the pegging steam and the HP heater's drain flashing
    # in it (with LPH2 the condensate arrives at ~125 degC, so the pegging PI may sit
    # at its lower limit there)
    assert np.all(res["n_xo.p"][half] < p_da[half])
    assert np.all(np.abs(res["da_nrv.m"][half]) < 1e-3)
    assert np.max(res["pegging_valve.m"]) > 1.0
    assert np.all(np.abs(p_da[half] - 5.3e5) < BAND_DA_HALF)
    # through the whole load change the pressure stays within a band around the
    # two set points (5.3-5.5 bar): the ramp at 5 %/min outruns the PIs for a while
    # when the extraction runs out and when it takes over again
    assert 5.3e5 - BAND_DA < np.min(p_da) and np.max(p_da) < 5.5e5 + BAND_DA
    # and at the end the extraction holds 5.5 bar again, the pegging valve shut
    end = t > 3100
    assert np.all(np.abs(p_da[end] - 5.5e5) < BAND_DA_END)
    assert np.all(res["pegging_valve.m"][end] < 1e-3)


# Hot reheat band [K] around its 522 degC set point. Measured (benchmarks/drum_unit.py):
# 0.58 K over the whole run, 0.18 K after 3000 s; the bands are about 3 times these.
BAND_RH = 1.5
BAND_RH_END = 0.5


def test_hot_reheat_temperature_is_held_by_the_reheat_spray(run):
    _, res, _ = run
    t = res.t
    T = res["n_hrh.T"] - 795.15  # set point 522 degC
    # the reheater's outlet floats by ~7 K with the load (measured 799.5-806.8 K,
    # with HPH2 801.5-811.2 K:
    # hotter at part load); the spray after it holds the hot reheat
    T_rho = res["n_rho.T"]
    assert np.max(T_rho) - np.min(T_rho) > 5.0
    assert np.all(res["rh_spray_valve.m"] > 0.05)  # spraying throughout, not saturated
    assert np.max(np.abs(T)) < BAND_RH
    assert np.max(np.abs(T[t > 3000])) < BAND_RH_END


def test_drum_unit_runs_through_the_cli(tmp_path):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["run", str(PLANT), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(out / "results.csv")
    assert d["time"][-1] == pytest.approx(3300.0)
