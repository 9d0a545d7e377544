"""Pump and steam turbine against closed forms, and h(p, s) against CoolProp's IF97.

The references are computed here from CoolProp's IF97 backend with its forward
(p, T) equations (and its saturation states for wet steam), never from dnasim's
own kernel, except where a test checks a law of the component itself (the pump's
P = m dp/(rho eta) with the plant's own density at the inlet node).
"""

import math

import CoolProp.CoolProp as CP
import numpy as np
import pytest
from plant_checks import balances, run_file
from scipy.optimize import brentq

from dnasim.core.errors import PlantError
from dnasim.library import PressureBoundary, Valve
from dnasim.library.pump import Pump
from dnasim.library.turbine import SteamTurbine
from dnasim.media import get_medium
from dnasim.media.isentropic import h_isentropic, h_ps
from dnasim.model.physics import G
from dnasim.plant.plant import Plant
from dnasim.start.initial import initial_values

IF97 = "IF97::Water"
WATER = get_medium("Water")


def steady(plant):
    """Output row {name: value} of the plant's steady state."""
    dae = plant.compile()
    y, _ = initial_values(dae, 0.0, "steady")
    return dict(zip(dae.output_names(), dae.output_row(0.0, y, np.zeros_like(y)), strict=True))


def connect(plant, pairs):
    for a, b in pairs:
        plant.connect(a, b)
    return plant


def h_isentropic_reference(p1, T1, p2):
    """h(p2, s(p1, T1)) [J/kg] from CoolProp IF97: forward s(p, T) solved for T
    (superheated or subcooled), or the quality on the saturation line (wet)."""
    s1 = CP.PropsSI("S", "P", p1, "T", T1, IF97)
    sl, sv = (CP.PropsSI("S", "P", p2, "Q", q, IF97) for q in (0, 1))
    hl, hv = (CP.PropsSI("H", "P", p2, "Q", q, IF97) for q in (0, 1))
    if sl <= s1 <= sv:
        return hl + (s1 - sl) / (sv - sl) * (hv - hl)
    T_sat = CP.PropsSI("T", "P", p2, "Q", 0, IF97)
    lo, hi = (T_sat + 1e-6, 1073.0) if s1 > sv else (273.16, T_sat - 1e-6)
    T = brentq(lambda T: CP.PropsSI("S", "P", p2, "T", T, IF97) - s1, lo, hi, xtol=1e-12)
    return CP.PropsSI("H", "P", p2, "T", T, IF97)


# ------------------------------------------------------------------ h(p, s)
@pytest.mark.parametrize(
    "p1, T1, p2",
    [
        (100e5, 773.15, 50e5),  # superheated to superheated
        (100e5, 773.15, 0.1e5),  # into the wet region (x = 0.87)
        (160e5, 813.15, 0.05e5),  # deep wet expansion
        (30e5, 623.15, 1e5),
        (5e5, 300.0, 200e5),  # liquid compressed (pump direction)
    ],
)
def test_isentropic_enthalpy_matches_coolprop_if97(p1, T1, p2):
    # dnasim's IF97 and CoolProp's evaluate the same forward equations; away from
    # the region boundaries they agree to round-off of h ~ 3e6 J/kg (1e-9 relative
    # of the Newton tolerance on s and of brentq's xtol 1e-12 K * cp) -> 1e-5 J/kg.
    h1 = WATER.h_pT(p1, T1)
    h_s = h_isentropic(WATER, p1, h1, p2)
    assert abs(h_s - h_isentropic_reference(p1, T1, p2)) < 1e-5
    # and h_ps is the inverse of s(p, h) on the isobar to round-off of s (~1e-12 J/(kg K))
    s1 = WATER.state(p1, h1).s
    assert abs(WATER.state(p2, h_ps(WATER, p2, s1)).s - s1) < 1e-9


def test_h_ps_out_of_range_names_the_entropy():
    # an entropy above that of steam at 1073 K and 0.01 bar has no state on the 200 bar isobar
    with pytest.raises(Exception, match="h_ps"):
        h_ps(WATER, 200e5, 20e3)


# ------------------------------------------------------------------ pump
H0, H_NOM, Q_NOM, ETA = 100.0, 80.0, 0.01, 0.7  # [m], [m], [m3/s], [-]
T_SUCTION = 303.15  # [K]


def pump_plant(speed=1.0, C=2e-2, p_out=5e5, **pump):
    plant = Plant("pump", medium="Water")
    plant.add(PressureBoundary("src", p=1e5, T=T_SUCTION, m_nominal=10))
    kw = dict(H0=H0, H_nominal=H_NOM, Q_nominal=Q_NOM, speed=speed, eta=ETA, m_nominal=10)
    kw.update(pump)
    plant.add(Pump("pump", **kw))
    plant.add(Valve("valve", C=C, opening=1.0, m_nominal=10))
    plant.add(PressureBoundary("sink", p=p_out, T=T_SUCTION, m_nominal=10))
    return connect(
        plant,
        [
            ("src.port", "a"),
            ("pump.inlet", "a"),
            ("pump.outlet", "b"),
            ("valve.inlet", "b"),
            ("valve.outlet", "c"),
            ("sink.port", "c"),
        ],
    )


@pytest.mark.parametrize("speed", [1.0, 0.7])
def test_pump_power_head_and_enthalpy_rise(speed):
    row = steady(pump_plant(speed=speed))
    m, dp = row["pump.m"], row["b.p"] - row["a.p"]
    rho = WATER.state(row["a.p"], row["a.h"]).rho  # inlet density
    Q = m / rho
    assert m > 1.0  # a real operating point
    # P = m dp/(rho eta): exact for m beyond the upwind band (1e-3 m_nominal); the
    # steady state is solved to ~1e-12 relative -> 1e-9 relative.
    assert row["pump.P"] == pytest.approx(m * dp / (rho * ETA), rel=1e-9)
    # the enthalpy rise dp/(rho eta) arrives at the discharge node
    assert row["b.h"] - row["a.h"] == pytest.approx(dp / (rho * ETA), rel=1e-9)
    # affinity-law head curve H = H0 r^2 + b Q^2, b = (H_nom - H0)/Q_nom^2; the
    # regularisation b Q sqrt(Q^2 + Q_reg^2) adds |b| Q_reg^2/2 to first order, with
    # Q_reg = 1e-2 m_nominal/rho = 1e-4 m3/s: 1.0e-3 m -> tolerance 1.5e-3 m.
    b = (H_NOM - H0) / Q_NOM**2
    assert dp / (rho * G) == pytest.approx(H0 * speed**2 + b * Q * Q, abs=1.5e-3)
    # the valve sets the flow: m = C sqrt(p_b - p_c); its regularisation
    # (dp_reg/dp)^2/4 is 1.3e-8 at dp = 0.44 bar -> rel 1e-7
    assert m == pytest.approx(2e-2 * math.sqrt(row["b.p"] - row["c.p"]), rel=1e-7)


def test_pump_shut_off_head_against_a_closed_valve():
    # A valve that passes ~1e-6 kg/s: Q ~ 1e-9 m3/s, so H = H0 r^2 to b Q Q_reg ~ 2e-6 m.
    for speed in (1.0, 0.5):
        row = steady(pump_plant(speed=speed, C=1e-9, p_out=1e5))
        assert abs(row["pump.m"]) < 1e-5
        assert row["pump.H"] == pytest.approx(H0 * speed**2, abs=1e-5)
        # the stagnant pump holds suction water: p_out - p_in = rho_in g H0 r^2 with the
        # suction's density from CoolProp's IF97 (forward rho(p, T) at 1 bar, 30 degC; the
        # suction node carries the source's state exactly). 1e-7: H is H0 r^2 to 2e-6 m
        # of 100 m (above) and the two IF97 implementations agree to ~1e-12 relative.
        rho = CP.PropsSI("D", "P", row["a.p"], "T", T_SUCTION, IF97)
        assert row["a.h"] == WATER.h_pT(1e5, T_SUCTION)  # no discharge water in the suction
        assert row["b.p"] - row["a.p"] == pytest.approx(rho * G * H0 * speed**2, rel=1e-7)


def test_stopped_pump_is_a_resistance_in_reverse():
    # speed 0, the sink at 5 bar pushes water back through valve and pump:
    # p_out - p_in = rho g b Q|Q| > 0 (b < 0, Q < 0), isenthalpic, no shaft power.
    row = steady(pump_plant(speed=0.0))
    m = row["pump.m"]
    assert m < -1.0
    rho = WATER.state(row["b.p"], row["b.h"]).rho  # the fluid enters at the outlet
    Q = m / rho
    b = (H_NOM - H0) / Q_NOM**2
    # regularisation as above (Q_reg/Q)^2/2 ~ 6e-5 relative -> rel 1e-4
    assert row["b.p"] - row["a.p"] == pytest.approx(rho * G * b * Q * abs(Q), rel=1e-4)
    # P = w(m) (h_2 - h_in) with w(m) the upwind weight's tail 2.5e-7 eps^2/|m|: ~0 W
    assert abs(row["pump.P"]) < 1e-6
    # reverse flow through the pump is a throttling: h at the suction node equals the
    # discharge node's (both are the sink's water throttled isenthalpically)
    assert row["a.h"] == pytest.approx(row["b.h"], abs=1e-6)


TABLE_Q = [0.0, 0.005, 0.01, 0.015, 0.02]  # [m3/s]
TABLE_H = [100.0, 98.0, 88.0, 70.0, 44.0]  # [m], flat at shut-off like a real curve


@pytest.mark.parametrize("speed", [1.0, 0.7])
def test_tabulated_head_curve_with_affinity_laws(speed):
    from scipy.interpolate import PchipInterpolator

    row = steady(
        pump_plant(
            speed=speed,
            H0=None,
            H_nominal=None,
            Q_nominal=None,
            curve_Q=TABLE_Q,
            curve_H=TABLE_H,
            head_curve="table",
        )
    )
    rho = WATER.state(row["a.p"], row["a.h"]).rho
    Q = row["pump.m"] / rho
    assert 0 < Q / speed < TABLE_Q[-1]  # inside the table at the similar point
    # H = r^2 H_1(Q/r), H_1 scipy's PCHIP through the points; no regularisation
    # inside the table: to the steady solution's 1e-9 (relative to H ~ 50 m)
    H_1 = PchipInterpolator(TABLE_Q, TABLE_H)
    dp = row["b.p"] - row["a.p"]
    assert dp / (rho * G) == pytest.approx(speed**2 * float(H_1(Q / speed)), rel=1e-9)


def test_tabulated_head_curve_stopped_pump_is_a_resistance():
    row = steady(
        pump_plant(
            speed=0.0,
            H0=None,
            H_nominal=None,
            Q_nominal=None,
            curve_Q=TABLE_Q,
            curve_H=TABLE_H,
            head_curve="table",
        )
    )
    assert row["pump.m"] < -1.0  # the header pushes water back through the stopped pump
    b = np.polyfit(TABLE_Q, TABLE_H, 2)[0]  # beyond the table: the fitted curvature
    rho = WATER.state(row["b.p"], row["b.h"]).rho
    Q = row["pump.m"] / rho
    # regularisation b Q sqrt(Q^2 + Q_reg^2): (Q_reg/Q)^2/2 ~ 6e-5 relative -> 1e-4
    assert row["b.p"] - row["a.p"] == pytest.approx(rho * G * b * Q * abs(Q), rel=1e-4)


def test_pump_curve_from_points_and_errors():
    # three points on H = 100 - 1e5 Q^2 give that parabola back (exact fit, round-off)
    p = Pump("p", curve_Q=[0.0, 0.01, 0.02], curve_H=[100.0, 90.0, 60.0], speed=1.0)
    assert (p.H0, p.b) == (pytest.approx(100.0), pytest.approx(-1e5))
    assert abs(p.a) < 1e-6
    with pytest.raises(PlantError, match="b = .* must be < 0"):
        Pump("p", H0=100.0, b=10.0, speed=1.0)
    with pytest.raises(PlantError, match="give the head curve"):
        Pump("p", speed=1.0)


# ------------------------------------------------------------------ turbine
P1, T1 = 100e5, 773.15  # live steam [Pa], [K]


def turbine_plant(p_out, **turbine):
    plant = Plant("turbine", medium="Water")
    plant.add(PressureBoundary("src", p=P1, T=T1, m_nominal=10))
    kw = dict(K_t=2.0e-3, eta=0.85, m_nominal=10)
    kw.update(turbine)
    plant.add(SteamTurbine("tur", **kw))
    plant.add(PressureBoundary("sink", p=p_out, m_nominal=10))
    return connect(
        plant, [("src.port", "a"), ("tur.inlet", "a"), ("tur.outlet", "b"), ("sink.port", "b")]
    )


@pytest.mark.parametrize("p_out", [0.1e5, 60e5])
def test_stodola_flow_at_two_pressure_ratios(p_out):
    row = steady(turbine_plant(p_out))
    rho1 = CP.PropsSI("D", "P", P1, "T", T1, IF97)
    exact = 2.0e-3 * math.sqrt(P1 * rho1 * (1.0 - (p_out / P1) ** 2))
    # the regularisation D/(D^2 + D_reg^2)^(1/4) differs from sqrt(D) by
    # (D_reg/D)^2/4 < 1e-10 here; the steady state is solved to ~1e-12 -> 1e-9.
    assert row["tur.m"] == pytest.approx(exact, rel=1e-9)


def test_turbine_power_against_coolprop_isentropic_drop():
    for p_out in (0.1e5, 30e5):  # wet exhaust (x = 0.87 isentropic), superheated exhaust
        row = steady(turbine_plant(p_out))
        h1 = CP.PropsSI("H", "P", P1, "T", T1, IF97)
        drop = h1 - h_isentropic_reference(P1, T1, p_out)
        # the node enthalpies are IF97 to round-off (1e-9 J/kg on 3e6) and the
        # steady state to 1e-12: 1e-9 relative
        assert row["tur.P"] == pytest.approx(row["tur.m"] * 0.85 * drop, rel=1e-9)
        assert row["b.h"] == pytest.approx(h1 - 0.85 * drop, rel=1e-9)
    assert row["tur.P"] > 0


def test_turbine_nominal_point_gives_its_flow():
    # K_t from (m_nom, p_in_nom, p_out_nom, T_in_nom): the same state gives m_nom back
    row = steady(
        turbine_plant(
            0.1e5,
            K_t=None,
            m_nominal=12.0,
            p_in_nominal=P1,
            p_out_nominal=0.1e5,
            T_in_nominal=T1,
        )
    )
    assert row["tur.m"] == pytest.approx(12.0, rel=1e-9)


def test_two_turbines_in_series():
    # HP and LP groups joined by a node without volume. The node pressure p_m makes
    # the two Stodola flows equal:
    #   K1 sqrt(rho1/p1 (p1^2 - p_m^2)) = K2 sqrt(rho_m/p_m (p_m^2 - p2^2)),
    # rho_m the density after the HP expansion (CoolProp IF97 at p_m and the HP
    # outlet enthalpy); total power = m (h1 - h_out).
    K1, K2, p2 = 2.0e-3, 2.0e-2, 0.1e5
    plant = Plant("series", medium="Water")
    plant.add(PressureBoundary("src", p=P1, T=T1, m_nominal=10))
    plant.add(SteamTurbine("hp", K_t=K1, eta=0.88, m_nominal=10))
    plant.add(SteamTurbine("lp", K_t=K2, eta=0.82, m_nominal=10))
    plant.add(PressureBoundary("sink", p=p2, m_nominal=10))
    connect(
        plant,
        [
            ("src.port", "a"),
            ("hp.inlet", "a"),
            ("hp.outlet", "m"),
            ("lp.inlet", "m"),
            ("lp.outlet", "b"),
            ("sink.port", "b"),
        ],
    )
    row = steady(plant)
    m, p_m = row["hp.m"], row["m.p"]
    assert row["lp.m"] == pytest.approx(m, rel=1e-12)  # no storage at the node
    assert p2 < p_m < P1
    rho1 = CP.PropsSI("D", "P", P1, "T", T1, IF97)
    h1 = CP.PropsSI("H", "P", P1, "T", T1, IF97)
    h_m = h1 - 0.88 * (h1 - h_isentropic_reference(P1, T1, p_m))
    T_m = CP.PropsSI("T", "P", p_m, "H", h_m, IF97)
    rho_m = CP.PropsSI("D", "P", p_m, "T", T_m, IF97)
    # CoolProp's (p, h) -> T uses IF97's backward equation (consistent to ~1 mK),
    # so rho_m is known to ~1e-5 relative -> 1e-5 on the LP flow
    assert m == pytest.approx(K1 * math.sqrt(rho1 / P1 * (P1**2 - p_m**2)), rel=1e-9)
    assert m == pytest.approx(K2 * math.sqrt(rho_m / p_m * (p_m**2 - p2**2)), rel=1e-5)
    assert row["hp.P"] + row["lp.P"] == pytest.approx(m * (h1 - row["b.h"]), rel=1e-9)
    assert row["m.h"] == pytest.approx(h_m, rel=1e-9)


# ------------------------------------------------------------ plant files
def test_turbine_plant_file_closes_its_balances_and_is_physical():
    plant, res = run_file("turbine_two_stage.toml")
    assert res.success
    err_M, thr_M, err_E, thr_E = balances(plant, res)
    # M, U and the running integrals (boundaries' M_passed, H_passed and the
    # turbines' W) are states of one BDF solution: linear invariants are kept to
    # the Newton tolerance, well below rtol = 1e-6 of the throughput
    assert err_M < 1e-6 * thr_M
    assert err_E < 1e-6 * thr_E
    # the live-steam ramp 100 -> 70 bar: the HP flow falls with p_in (cone law at a
    # large pressure ratio: m ~ p_in sqrt(rho_in/p_in) ~ 0.7 at equal T, within 2 %)
    assert res["hp.m"][-1] / res["hp.m"][0] == pytest.approx(0.7, rel=0.02)
    assert np.all(res["hp.P"] > 0) and np.all(res["lp.P"] > 0)
    # the LP exhaust at 0.1 bar is wet steam: h between h' and h''
    hl, hv = WATER.saturation_enthalpies(np.array([0.1e5]))
    assert np.all((res["n_exhaust.h"] > hl[0]) & (res["n_exhaust.h"] < hv[0]))


def test_pump_plant_file_speed_change_closes_its_balances():
    # the example runs down to standstill (reverse flow); here only to 80 % speed,
    # which keeps the test short (the reversal in the water-filled line takes
    # ~1300 steps, the solver's current behaviour on liquid flow reversal)
    table = "values = [1, 0, 0, 1]"
    plant, res = run_file("pump_stop_restart.toml", replace={table: "values = [1, 0.8, 0.8, 1]"})
    assert res.success
    err_M, thr_M, err_E, thr_E = balances(plant, res)
    assert err_M < 1e-6 * thr_M  # as above
    assert err_E < 1e-6 * thr_E
    assert np.all(res["pump.m"] > 0) and np.all(res["pump.P"] > 0)
    # affinity: the head at 80 % speed is below the full-speed head
    assert res["pump.H"][np.searchsorted(res.t, 45.0)] < res["pump.H"][0]
