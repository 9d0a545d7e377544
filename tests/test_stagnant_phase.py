"""Phase switches in stagnant volumes (issue 20 item 9): plant files written as an
engineer writes them (tests/field/), run through the CLI and checked against physics:
mass and energy over the run, and the end state of a closed volume by IF97 (CoolProp's
IF97 backend) from its density and temperature.

tests/field/closed_steam_line_condensing.toml: a steam line shut at both ends (tight
isolation valves) whose wall cools from 300 to 150 degC. The closed line keeps its mass
M and volume V, so its density rho = M/V; it ends at the wall temperature, inside the
dome, where IF97 gives p = p_sat(150 degC), and its specific internal energy is the
mixture's u = (1 - x) u' + x u'' with x = (1/rho - v')/(v'' - v') at 150 degC.

tests/field/closed_feed_line_boiling_outlet.toml: a feed line shut at its inlet, open to
a drum at 50 bar, its wall heated to 320 degC: the water boils at near-zero flow and the
line ends as steam at the drum's pressure and the wall's temperature (IF97 from p and h,
and its mass rho(p, T) V). The same plant with the default LMTD heat transfer
(closed_feed_line_boiling.toml) runs to the same end since the LMTD's excess is bounded
inside the upwind band (``physics.lmtd_excess_bound``; before, it stalled at 330 s: its
header).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from CoolProp.CoolProp import PropsSI
from field_checks import BALANCE_RTOL, balances, run_plant

WATER = "IF97::Water"


@pytest.fixture(scope="module")
def condensing(tmp_path_factory):
    outdir = tmp_path_factory.mktemp("cslc")
    return run_plant("closed_steam_line_condensing", outdir), outdir


def _line_sums(df, n=5):
    M = df[[f"line.M[{i}]" for i in range(n)]].sum(axis=1).to_numpy()
    U = df[[f"line.U[{i}]" for i in range(n)]].sum(axis=1).to_numpy()
    return M, U


def test_closed_steam_line_runs_and_closes_its_balances(condensing):
    run, _ = condensing
    assert run.finished, run.message
    bal = balances(run)
    # the field suite's bound: the integrator conserves M and U to its Newton tolerance
    assert bal.mass_err < BALANCE_RTOL and bal.energy_err < BALANCE_RTOL, bal


def test_closed_steam_line_condenses_at_rest(condensing):
    run, outdir = condensing
    df = run.df
    t = df["time"].to_numpy()
    M, U = _line_sums(df)
    shut = t >= 11.0  # both valves shut from 11 s (tight: leakage 0)
    # no mass crosses a shut valve: the line's mass is constant to the round-off of a
    # sum of five masses (measured 7.5e-15)
    assert np.ptp(M[shut]) <= 1e-12 * M[shut][0]
    # every volume crossed the saturated-vapour line, once, as a located phase switch
    ev = pd.read_csv(outdir / "events.csv").drop_duplicates("event", keep="last")
    crossed = sorted(ev.loc[ev["component"] == "line", "switch"])
    assert crossed == [f"h_v[{i}] saturated vapour" for i in range(5)], crossed
    V, T_wall = 0.5, 150.0 + 273.15
    rho = M[-1] / V
    v_l = 1.0 / PropsSI("D", "T", T_wall, "Q", 0, WATER)
    v_v = 1.0 / PropsSI("D", "T", T_wall, "Q", 1, WATER)
    x = (1.0 / rho - v_l) / (v_v - v_l)
    assert 0.1 < x < 0.2  # wet steam (x = 0.152): the line condensed 85 % of its steam
    p_sat = PropsSI("P", "T", T_wall, "Q", 0, WATER)
    u_hand = (1 - x) * PropsSI("U", "T", T_wall, "Q", 0, WATER) + x * PropsSI(
        "U", "T", T_wall, "Q", 1, WATER
    )
    # Tolerances: the shut valves' upwind weight keeps a tail at zero flow
    # (physics.upwind_weight: 2.5e-4 of the open band plus 3/16 of the shut one), through
    # which ~1.7 W of the supply's and the header's enthalpy reach the line; at rest that
    # holds it Q/kA = 3.5e-4 K above the wall (measured), 4.5 Pa above p_sat(150 degC)
    # (dp_sat/dT = 12.9 kPa/K): 9.4e-6 of p, and u 4.2e-6 above the hand value. The bounds
    # are about twice these; the transient itself has decayed (time constant ~30 s).
    for c in ("line.p_v[0]", "line.p_v[2]", "line.p_v[4]", "n_b.p"):
        assert df[c].iloc[-1] == pytest.approx(p_sat, rel=2e-5), c
    for i in range(5):
        assert abs(df[f"line.T[{i}]"].iloc[-1] - T_wall) < 1e-3
    assert U[-1] / M[-1] == pytest.approx(u_hand, rel=1e-5)


# ------------------------------------------------------------------ boiling at rest


@pytest.fixture(scope="module")
def boiling(tmp_path_factory):
    outdir = tmp_path_factory.mktemp("cflb")
    return run_plant("closed_feed_line_boiling_outlet", outdir), outdir


def check_boiled_dry_at_rest(run, outdir, dT_last, dT_others, rel_mass):
    """The closed feed line at its end (both plants below): finished, M and U conserved,
    every volume through the dome (h' then h'', located), the line at the drum's
    pressure, its steam within dT_others [K] of the wall (dT_last [K] for the volume
    next to the drum valve) by IF97, and its mass rho V within rel_mass, no liquid."""
    assert run.finished, run.message
    bal = balances(run)
    # the field suite's bound: the integrator conserves M and U to its Newton tolerance
    assert bal.mass_err < BALANCE_RTOL and bal.energy_err < BALANCE_RTOL, bal
    # every volume boiled through the dome, entering it at h' and leaving it at h'', as
    # located phase switches (the outflow's pulses may take some volumes back and forth
    # across a line), the last one of each volume at h''
    ev = pd.read_csv(outdir / "events.csv").drop_duplicates("event", keep="last")
    line = ev.loc[ev["component"] == "line"].sort_values("time")
    expected = {f"h_v[{i}] saturated {s}" for i in range(5) for s in ("liquid", "vapour")}
    assert set(line["switch"]) == expected, sorted(set(line["switch"]))
    for i in range(5):
        mine = line[line["switch"].str.startswith(f"h_v[{i}] ")]
        assert mine["switch"].iloc[-1] == f"h_v[{i}] saturated vapour", mine
    last = run.df.iloc[-1]
    p_drum, T_wall, V = 50e5, 320.0 + 273.15, 0.2
    M = sum(last[f"line.M[{i}]"] for i in range(5))
    for i in range(5):
        p, h = last[f"line.p_v[{i}]"], last[f"line.h_v[{i}]"]
        # at rest the line's pressure is the drum's: no flow, no friction (measured
        # 5e6 Pa to 8 digits); 1e-6 is the integrator's tolerance
        assert p == pytest.approx(p_drum, rel=1e-6)
        T = PropsSI("T", "P", p, "H", h, WATER)
        assert abs(T - T_wall) < (dT_last if i == 4 else dT_others), (i, T)
    # the mass left in the line is steam at (p_drum, T_wall): rho V, by IF97
    rho = PropsSI("D", "P", p_drum, "T", T_wall, WATER)
    assert M == pytest.approx(rho * V, rel=rel_mass)
    # less than the saturated vapour's mass at 50 bar: no liquid is left
    assert M < PropsSI("D", "P", p_drum, "Q", 1, WATER) * V


def test_closed_feed_line_boils_at_rest_and_ends_superheated(boiling):
    # tests/field/closed_feed_line_boiling_outlet.toml: a feed line shut at its inlet,
    # open to a 50 bar drum, its wall heated from 200 to 320 degC: the water boils at
    # near-zero flow, is pushed out, and the line ends full of steam at the drum's
    # pressure and the wall's temperature. Steam temperatures: the first four volumes
    # within 2e-3 K of the wall (measured); the last one, next to the open drum valve,
    # 0.117 K below it (measured): the valve's regularised exchange at zero flow
    # (physics.upwind_weight, w(0) = 3/16 m_eps) brings in the drum water's enthalpy,
    # kA_i dT = 2 kW/K x 0.117 K = 234 W. The mass: 6.5e-5 above rho V (measured, from
    # the last volume's 0.117 K). Bounds: ~2.5 times these.
    run, outdir = boiling
    check_boiled_dry_at_rest(run, outdir, dT_last=0.3, dT_others=5e-3, rel_mass=2e-4)


# ------------------------------------------------------- boiling at rest, LMTD


@pytest.fixture(scope="module")
def boiling_lmtd(tmp_path_factory):
    outdir = tmp_path_factory.mktemp("cflb_lmtd")
    return run_plant("closed_feed_line_boiling", outdir), outdir


def test_closed_feed_line_with_lmtd_boils_at_rest_and_ends_superheated(boiling_lmtd):
    # tests/field/closed_feed_line_boiling.toml: the plant above with the default LMTD
    # heat transfer, whose heat flows were steep in the face flows inside the upwind band
    # (issue 20 item 9) until the LMTD's excess was bounded there by the enthalpy the
    # inflow brings (physics.lmtd_excess_bound): it now ends as the outlet copy does.
    # Measured: balances 9.5e-15 and 5.7e-14; one h' and one h'' switch per volume; the
    # first four volumes within 2.8e-3 K of the wall; the last one 0.057 K above it
    # (the exchange at zero flow, its excess over the own-state heat flow bounded at
    # rest, leaves it on the wall's far side; the outlet copy: 0.117 K below); the mass
    # 3.2e-5 below rho V. Bounds: ~2.5 times these.
    run, outdir = boiling_lmtd
    check_boiled_dry_at_rest(run, outdir, dT_last=0.15, dT_others=7e-3, rel_mass=1e-4)
