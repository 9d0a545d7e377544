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
(closed_feed_line_boiling.toml) does not yet run to its end: its header says why.
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


def test_closed_feed_line_boils_at_rest_and_ends_superheated(boiling):
    # tests/field/closed_feed_line_boiling_outlet.toml: a feed line shut at its inlet,
    # open to a 50 bar drum, its wall heated from 200 to 320 degC: the water boils at
    # near-zero flow, is pushed out, and the line ends full of steam at the drum's
    # pressure and the wall's temperature (the same plant with the default LMTD heat
    # transfer stalls: its header, issue 20 item 9)
    run, outdir = boiling
    assert run.finished, run.message
    bal = balances(run)
    # the field suite's bound: the integrator conserves M and U to its Newton tolerance
    assert bal.mass_err < BALANCE_RTOL and bal.energy_err < BALANCE_RTOL, bal
    # every volume boiled through the dome, entering it at h' and leaving it at h'', as
    # located phase switches (16 of them: the outflow's pulses take some volumes back
    # and forth across a line), the last one of each volume at h''
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
        # superheated steam at the wall temperature, by IF97 from (p, h): the first
        # four volumes within 2e-3 K (measured); the last one, next to the open drum
        # valve, 0.117 K below the wall (measured): the valve's regularised exchange at
        # zero flow (physics.upwind_weight, w(0) = 3/16 m_eps) brings in the drum
        # water's enthalpy, kA_i dT = 2 kW/K x 0.117 K = 234 W. Bounds: ~2.5 times these.
        T = PropsSI("T", "P", p, "H", h, WATER)
        assert abs(T - T_wall) < (0.3 if i == 4 else 5e-3), (i, T)
    # the mass left in the line is steam at (p_drum, T_wall): rho V, by IF97 (measured
    # 6.5e-5 above it, from the last volume's 0.117 K)
    rho = PropsSI("D", "P", p_drum, "T", T_wall, WATER)
    assert M == pytest.approx(rho * V, rel=2e-4)
    # less than the saturated vapour's mass at 50 bar: no liquid is left
    assert M < PropsSI("D", "P", p_drum, "Q", 1, WATER) * V
