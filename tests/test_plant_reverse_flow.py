"""Reverse and zero flow: energy upwind of the actual flow, boundaries as sources
and sinks (issue 7, item 3).

The plants are files under tests/plants/, written as a user would write them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from CoolProp.CoolProp import PropsSI
from plant_checks import balances, node_temperatures, run_file

from dnasim.library import Pipe, PressureBoundary, Valve
from dnasim.media import get_medium
from dnasim.plant.plant import Plant
from dnasim.start.initial import initial_values

# ---------------------------------------------------------------- node identity


def three_pipe_node():
    """Pipe a feeds node j; pipes b and c leave it (each to a valve and a sink)."""
    plant = Plant("tee", medium="Air")
    plant.add(PressureBoundary("src", p=2e5, T=500.0))
    for name in "abc":
        plant.add(Pipe(name, V=0.01, k=1e4, n_volumes=2, m_nominal=1.0))
    for name in "bc":
        plant.add(Valve(f"v{name}", C=1e-3, opening=1.0))
        plant.add(PressureBoundary(f"s{name}", p=1e5, T=300.0))
    wires = [("src.port", "in"), ("a.inlet", "in"), ("a.outlet", "j")]
    for name in "bc":
        wires += [
            (f"{name}.inlet", "j"),
            (f"{name}.outlet", f"o{name}"),
            (f"v{name}.inlet", f"o{name}"),
            (f"v{name}.outlet", f"e{name}"),
            (f"s{name}.port", f"e{name}"),
        ]
    for port, node in wires:
        plant.connect(port, node)
    return plant


# flows (kg/s) into node j from a (a's outlet flow), and out of j into b and c
# (their inlet flows): forward, reverse, mixed, all zero, and inside the
# regularisation band (|m| < 1e-3 m_nominal). Binary fractions: the mass balance
# holds exactly in floating point.
FLOWS = {
    "forward": (1.0, 0.625, 0.375),
    "reverse": (-1.0, -0.75, -0.25),
    "mixed": (0.25, -0.5, 0.75),
    "zero": (0.0, 0.0, 0.0),
    "band": (2.0**-11, 2.0**-12, 2.0**-12),
}


@pytest.mark.parametrize("case", FLOWS)
def test_energy_through_a_three_port_node_is_conserved_to_round_off(case):
    plant = three_pipe_node()
    dae = plant.compile()
    y, _ = initial_values(dae, 0.0, "steady")
    yp = np.zeros_like(y)
    ix = dae.index
    ma, mb, mc = FLOWS[case]
    y[ix["a.m[2]"]], y[ix["b.m[0]"]], y[ix["c.m[0]"]] = ma, mb, mc
    # different enthalpies in the volumes next to the node, so that upwinding matters
    y[ix["a.h_v[1]"]] = 4.0e5
    y[ix["b.h_v[0]"]] = 2.0e5
    y[ix["c.h_v[0]"]] = 3.0e5
    # the node enthalpy that solves the node's mixing equation (linear in h_j)
    row = dae.eq_names.index("j.mixing")
    k = ix["j.h"]

    def mixing(h):
        y[k] = h
        return dae.residual(0.0, y, yp)[row]

    # secant from 0 and 1, then two Newton refinements (the first secant loses
    # digits to cancellation when the weights are small)
    slope = mixing(1.0) - mixing(0.0)
    h_j = -mixing(0.0) / slope
    for _ in range(2):
        h_j -= mixing(h_j) / slope
    y[k] = h_j
    F = dae.residual(0.0, y, yp)
    assert F[dae.eq_names.index("j.mass")] == 0.0
    # the mixing residual at h_j is zero to round-off of its terms (|m| h ~ 4e5 W)
    assert abs(F[row]) < 1e-15 * 4e5 * 4
    out = dict(zip(dae.output_names(), dae.output_row(0.0, y, yp), strict=True))
    # energy leaving pipe a through j = energy entering b and c, to round-off:
    # terms of size |m| h <= 4e5 W, a few operations each -> 1e-15 * 4e5 * 8
    leak = out["a.E_out"] - out["b.E_in"] - out["c.E_in"]
    assert abs(leak) < 1e-15 * 4e5 * 8, leak
    # outside the band upwinding is exact up to the weight's tail, d^2/(4 m^2) =
    # 2.5e-13 relative at these flows (d = 1e-6 kg/s): 1e-12 relative
    if case == "forward":  # a's volume enthalpy, carried on into b
        assert math.isclose(h_j, 4.0e5, rel_tol=1e-12)
        assert math.isclose(out["b.E_in"], 0.625 * 4.0e5, rel_tol=1e-12)
    if case == "reverse":  # the inflows from b and c mix in proportion
        assert math.isclose(h_j, 0.75 * 2.0e5 + 0.25 * 3.0e5, rel_tol=1e-12)
        assert math.isclose(out["a.E_out"], -1.0 * h_j, rel_tol=1e-12)
    if case == "zero":
        # h_j is the weighted mean of the three; at zero flow the regularisation
        # exchanges w(0) (h_v - h_j) with w(0) = m_eps/4 = 2.5e-4 kg/s: at most
        # 2.5e-4 * 2e5 W, conserved like any other energy flow
        assert 2.0e5 < h_j < 4.0e5
        assert 0.0 < out["a.E_out"] <= 2.5e-4 * 2e5


# ---------------------------------------------------------------- reversals


def pressure_range(plant, res):
    ps = [res[f"{n}.p"] for n in plant.node_names()]
    return float(np.min(ps)), float(np.max(ps))


def test_adiabatic_steam_pipe_reversal():
    plant, res = run_file("steam_pipe_reversal.toml")
    assert res.success, res.message
    # the flow really reversed: steam leaves through the source at the end
    assert res["source.m"][0] > 1.0 and res["source.m"][-1] < -1.0
    T_hi, T_lo = 573.15, 553.15  # the two inflow temperatures (source, sink)
    p_min, p_max = pressure_range(plant, res)
    # Maximum principle up to compression and expansion: the hottest possible
    # state is the hot inflow compressed isentropically from p_min to p_max; the
    # coldest, the cold inflow expanded isentropically or throttled from p_max to
    # p_min (CoolProp's IF97, an independent implementation). Integration error
    # (rtol 1e-6 on h ~ 3e6 J/kg: ~1 mK) is covered by 0.01 K.
    w = "IF97::Water"
    s_hot = PropsSI("S", "P", p_min, "T", T_hi, w)
    T_upper = PropsSI("T", "P", p_max, "S", s_hot, w) + 0.01
    s_cold = PropsSI("S", "P", p_max, "T", T_lo, w)
    h_cold = PropsSI("H", "P", p_max, "T", T_lo, w)
    T_lower = min(
        PropsSI("T", "P", p_min, "S", s_cold, w), PropsSI("T", "P", p_min, "H", h_cold, w)
    )
    T_lower -= 0.01
    T = node_temperatures(plant, res)
    assert T_upper - T_hi < 5.0 and T_lo - T_lower < 5.0  # the bounds are tight
    assert T.max() <= T_upper and T.min() >= T_lower, (T.min(), T.max(), T_lower, T_upper)
    # at the end the pipe holds the sink's steam, throttled through the valve
    h_sink = res["sink.h_supply"][-1]
    assert abs(res["pipe.h_v[0]"][-1] - h_sink) < 1e-6 * h_sink
    # mass bounded: between the densities of the extreme states
    V = plant.components["pipe"].params["V"]
    rho_max = PropsSI("D", "P", p_max, "T", T_lower, w)
    rho_min = PropsSI("D", "P", p_min, "T", T_upper, w)
    M = res["pipe.M_total"]
    assert V * rho_min <= M.min() and M.max() <= V * rho_max
    # balances over the run, to 1e-6 of the throughput (the solver keeps linear
    # invariants to its Newton tolerance, below rtol = 1e-6)
    err_M, thr_M, err_E, thr_E = balances(plant, res)
    assert err_M < 1e-6 * thr_M and err_E < 1e-6 * thr_E, (err_M / thr_M, err_E / thr_E)


def test_air_pipe_reversal():
    plant, res = run_file("air_pipe_reversal.toml")
    assert res.success, res.message
    assert res["inlet.m"][0] > 0.1 and res["inlet.m"][-1] < -0.1
    air = get_medium("Air")
    st = air.state(1.5e5, air.h_pT(1.5e5, 400.0))
    R = st.p / (st.rho * st.T) if hasattr(st, "p") else 1.5e5 / (st.rho * 400.0)
    kappa = R / st.cp  # ideal gas, constant cp: T p^(-R/cp) is constant along an isentrope
    T_hi, T_lo = 473.15, 293.15  # inflows (inlet, outlet) and the initial state (293.15 K)
    p_min, p_max = pressure_range(plant, res)
    # ideal gas: throttling keeps T; isentropic compression/expansion over the
    # pressure range bounds the rest; 0.01 K for the integration error
    T_upper = T_hi * (p_max / p_min) ** kappa + 0.01
    T_lower = T_lo * (p_min / p_max) ** kappa - 0.01
    T = node_temperatures(plant, res)
    assert T.max() <= T_upper and T.min() >= T_lower, (T.min(), T.max(), T_lower, T_upper)
    # mass bounded by the ideal gas law at the extreme states
    V = plant.components["pipe"].params["V"]
    M = res["pipe.M_total"]
    assert M.max() <= V * p_max / (R * T_lower) and M.min() >= V * p_min / (R * T_upper)
    # settles: the pipe ends full of outlet air, cooled back towards 293 K
    assert res["pipe.T_out"][-1] < 300.0
    err_M, thr_M, err_E, thr_E = balances(plant, res)
    assert err_M < 1e-6 * thr_M and err_E < 1e-6 * thr_E, (err_M / thr_M, err_E / thr_E)


def test_sink_without_temperature_stops_at_reverse_inflow():
    # the steam plant with a sink that is given no reverse-inflow temperature
    plant, res = run_file("steam_pipe_reversal.toml", {'T = "280 degC"': ""})
    assert not res.success
    assert "boundary 'sink'" in res.message and "flow reversed into the plant" in res.message
    assert "give T or h" in res.message
    t_stop = res.t[-1]
    # the sink pressure ramps 39.5 -> 40.5 bar over 10..20 s; the valve's flow turns
    # when it passes the pipe outlet's pressure (a little below the source's 40 bar,
    # which the sink passes at 15 s, while the pipe still fills from the source)
    assert 14.0 < t_stop < 16.0, t_stop
    # the last row is the interpolant at the located crossing: its pressures are right
    # to the local error (tens of Pa at these steps), more than the few Pa of the valve's
    # pressure difference there, so the direction is judged from the flows, which the
    # switch function itself located: the source still feeds less than it did, and the
    # sink's flow points into the plant
    assert res["source.m"][-1] < res["source.m"][0]
    assert f"t = {t_stop:.6g}" in res.message
    # the terminal switch stopped it where the inflow reached its threshold, 1e-3
    # of m_nominal (5 kg/s), located to the switch tolerance
    assert abs(res["sink.m"][-1] - 5e-3) < 1e-9


def test_mass_flow_sink_takes_negative_flow():
    # m < 0 at a MassFlowBoundary takes fluid out of the plant
    plant, res = run_file(
        "steam_pipe_reversal.toml",
        {'type = "PressureBoundary"\np = { type = "ramp"': 'type = "MassFlowBoundary"\nm = -3 #'},
        t_end=5.0,
    )
    assert res.success, res.message
    assert np.allclose(res["sink.m"], -3.0, rtol=0, atol=1e-12)
    # steady: 3 kg/s leave, 3 kg/s enter through the source
    assert abs(res["source.m"][-1] - 3.0) < 1e-6
