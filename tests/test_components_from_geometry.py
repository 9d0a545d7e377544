"""Components from geometry (issue 22 items 1-3): plants written as an engineer writes
them from a datasheet (tube counts, diameters, lengths, wall and bank geometry), run
through the CLI, and checked against hand calculations with the same correlations:

- the pressure drop of a heated tube, single phase and boiling (Friedel), face by
  face from the run's own states, and by the engineer's one-line estimate;
- the outlet temperature of a counter-flow economiser from epsilon-NTU with the U
  the correlations give;
- a condenser's duty from its tube geometry;
- the lumped form as the limit: a lumped pipe with the correlation's kA and k gives
  the geometry pipe's result;
- a flow reversal and a stagnant pipe from geometry (smooth through zero flow), and
  mass and energy closed over each run;
- the input errors of mixed lumped and geometry parameters (exit code 2).
"""

from __future__ import annotations

import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from CoolProp.CoolProp import PropsSI
from field_checks import Run, balances, read_results

from dnasim.correlations import friction, heat_transfer, metals, tube_banks
from dnasim.correlations.condensation import nusselt_horizontal_tube
from dnasim.library.submodels.tube_geometry import Tubes
from dnasim.media import get_medium
from dnasim.plant.plantfile import load

G = 9.80665
WATER = get_medium("Water")
ROOT_PLANTS = Path(__file__).resolve().parents[1] / "plants"


def run_cli(tmp_path, name, text):
    """Write the plant file, run it as a user does (``python -m dnasim run``), and
    return the ``field_checks.Run`` (results.csv without units, the loaded plant)."""
    path = tmp_path / f"{name}.toml"
    path.write_text(textwrap.dedent(text))
    out = tmp_path / f"{name}_out"
    proc = subprocess.run(
        [sys.executable, "-m", "dnasim", "run", str(path), "-o", str(out), "-q"],
        capture_output=True,
        text=True,
    )
    df = read_results(out / "results.csv") if (out / "results.csv").exists() else None
    loaded = load(path) if proc.returncode == 0 else None
    t_end = loaded.simulation.t_end if loaded else math.nan
    plant = loaded.plant if loaded else None
    return Run(name, proc.returncode, proc.stdout + proc.stderr, df, 0, 0.0, t_end, plant)


def last(run, key):
    return float(run.df[key].iloc[-1])


def face_friction(m, p, h, D, L_face, n_tubes, roughness, two_phase="friedel"):
    """Hand calculation of one face's friction [Pa] at the state (p, h) upstream:
    Darcy-Weisbach (Colebrook), Friedel in the dome, with the library's functions and
    the medium's transport properties (dnasim.correlations, Medium.transport)."""
    mt = m / n_tubes
    st = WATER.state(p, h)
    hl, hv = (float(v[0]) for v in WATER.saturation_enthalpies(np.array([p])))
    x = (h - hl) / (hv - hl)
    if 0.0 < x < 1.0:
        s = WATER.saturation_transport(np.array([p]))
        rl, rv = float(s["rho_l"][0]), float(s["rho_v"][0])
        ml, mv, sig = float(s["mu_l"][0]), float(s["mu_v"][0]), float(s["sigma"][0])
        if two_phase == "friedel":
            return float(
                friction.friedel_pressure_drop(mt, x, rl, rv, ml, mv, sig, D, L_face, roughness)
            )
        return float(
            friction.homogeneous_pressure_drop(mt, x, rl, rv, ml, mv, D, L_face, roughness)
        )
    mu = float(WATER.transport(np.array([p]), np.array([h]))["mu"][0])
    return float(friction.pressure_drop(mt, st.rho, mu, D, L_face, roughness))


# ---------------------------------------------------------------- single phase

HEATED_TUBE = """
    # Feedwater heated in a tube bundle: 5 tubes, 20 mm bore, 50 m long, 3 mm P235GH
    # wall held at 200 degC, rising 10 m from inlet to outlet.
    [plant]
    name = "heated_tube"
    medium = "Water"
    [simulation]
    t_end = "1 s"
    start = "steady"
    [components.feed]
    type = "MassFlowBoundary"
    m = "3 kg/s"
    T = "150 degC"
    m_nominal = "3 kg/s"
    ports = { port = "a" }
    [components.tube]
    type = "Pipe"
    D = "20 mm"
    length = "50 m"
    n_tubes = 5
    wall_thickness = "3 mm"
    wall_material = "P235GH"
    T_wall = "200 degC"
    dz = "10 m"
    n_volumes = 20
    m_nominal = "3 kg/s"
    ports = { inlet = "a", outlet = "b" }
    [components.valve]
    type = "Valve"
    C = "0.01 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "3 kg/s"
    ports = { inlet = "b", outlet = "c" }
    [components.header]
    type = "PressureBoundary"
    p = "40 bar"
    m_nominal = "3 kg/s"
    ports = { port = "c" }
"""


@pytest.fixture(scope="module")
def heated(tmp_path_factory):
    return run_cli(tmp_path_factory.mktemp("heated"), "heated_tube", HEATED_TUBE)


def test_heated_tube_pressure_drop_single_phase(heated):
    run = heated
    assert run.returncode == 0, run.message
    n, m, D, L, nt, dz = 20, 3.0, 0.02, 50.0, 5, 10.0
    p = [last(run, "a.p")] + [last(run, f"tube.p_v[{i}]") for i in range(n)]
    h = [last(run, "a.h")] + [last(run, f"tube.h_v[{i}]") for i in range(n)]
    dp_f = dp_head = 0.0
    for i in range(n):  # face i: friction and head of the state upstream (forward flow)
        dp_f += face_friction(m, p[i], h[i], D, L / n, nt, 4.5e-5)
        dp_head += WATER.state(p[i], h[i]).rho * G * dz / n
    dp = p[0] - p[-1]
    # the run uses |m| regularised by m_reg = 1 % of m_nominal: dp ~ m m_r^0.75 is
    # (m_reg/m)^2 0.75/2 ~ 4e-5 higher; the face sums otherwise equal to round-off
    print("heated tube: friction run/hand - 1 =", (dp - dp_head) / dp_f - 1)
    assert dp - dp_head == pytest.approx(dp_f, rel=1e-4)
    assert dp_f > 0.3 * dp  # the friction is a real share of the drop here (60 %)
    # the engineer's estimate: mean properties (CoolProp's IAPWS, independent of
    # dnasim's transport code) at the mean of the inlet and outlet temperatures,
    # f from Colebrook at the mean Re, and the static head of the mean density. The
    # properties vary by 6 % (rho) and 30 % (mu) along the tube; dp ~ mu^0.2/rho is
    # close to linear in them: the mean-property estimate is within 1 % (measured
    # 0.3 %)
    T_m = 0.5 * (last(run, "a.T") + last(run, "b.T"))
    p_m = 0.5 * (p[0] + p[-1])
    rho = PropsSI("D", "P", p_m, "T", T_m, "HEOS::Water")
    mu = PropsSI("V", "P", p_m, "T", T_m, "HEOS::Water")
    A = math.pi * D * D / 4
    w = m / nt / (rho * A)
    f = float(friction.colebrook(rho * w * D / mu, 4.5e-5 / D))
    estimate = f * L / D * rho * w * w / 2 + rho * G * dz
    print("heated tube: dp run/estimate - 1 =", dp / estimate - 1, "friction share", dp_f / dp)
    assert dp == pytest.approx(estimate, rel=0.01)


def test_heated_tube_outlet_temperature_from_gnielinski(heated):
    # the wall at a fixed 200 degC: epsilon = 1 - exp(-UA/(m cp)) with UA the series of
    # Gnielinski's (VDI G1) h on the inner surface and the wall's inner half at
    # lambda(T_wall), at the mean bulk temperature; the run's UA varies along the tube
    # with the water's properties (k, mu, Pr: about +-3 % in h), which bends the
    # temperature profile but moves the outlet by < 0.2 K (measured 0.002 K)
    run = heated
    m, D, L, nt, s = 3.0, 0.02, 50.0, 5, 0.003
    T_in, T_out, T_w = last(run, "a.T"), last(run, "b.T"), 473.15
    T_m, p_m = 0.5 * (T_in + T_out), 0.5 * (last(run, "a.p") + last(run, "b.p"))
    h_m = WATER.h_pT(p_m, T_m)
    tr = WATER.transport(np.array([p_m]), np.array([h_m]))
    mu, k, cp = (float(tr[key][0]) for key in ("mu", "k", "cp"))
    Re = m / nt / (math.pi * D * D / 4) * D / mu
    Nu = float(heat_transfer.nusselt_tube(Re, mu * cp / k, D / L, "T"))
    tubes = Tubes(D, L, nt, s, metals.metal("P235GH"))
    lam = float(metals.metal("P235GH").conductivity(T_w))
    UA = 1.0 / (1.0 / (Nu * k / D * tubes.A_inner) + tubes.conduction_resistance(lam, "inner"))
    # cp of the bulk between inlet and outlet, by the enthalpy rise (the exact mean)
    cp_m = (last(run, "b.h") - last(run, "a.h")) / (T_out - T_in)
    T_hand = T_w - (T_w - T_in) * math.exp(-UA / (m * cp_m))
    print("heated tube: T_out run - hand =", T_out - T_hand, "K")
    assert T_out == pytest.approx(T_hand, abs=0.2)
    assert -last(run, "tube.Q_total") == pytest.approx(
        m * (last(run, "b.h") - last(run, "a.h")), rel=1e-6
    )


# ---------------------------------------------------------------- boiling

BOILING_TUBE = """
    # Furnace wall tubes: 4 tubes, 25 mm bore, 30 m high, 5 mm 16Mo3 wall, 2 MW
    # absorbed through the wall; subcooled water in, a steam-water mixture out.
    [plant]
    name = "boiling_tube"
    medium = "Water"
    [simulation]
    t_end = "1 s"
    start = "steady"
    [components.feed]
    type = "MassFlowBoundary"
    m = "2 kg/s"
    T = "250 degC"
    m_nominal = "2 kg/s"
    ports = { port = "a" }
    [components.riser]
    type = "Pipe"
    D = "25 mm"
    length = "30 m"
    n_tubes = 4
    wall_thickness = "5 mm"
    wall_material = "16Mo3"
    Q_outer = "2 MW"
    dz = "30 m"
    n_volumes = 20
    m_nominal = "2 kg/s"
    TWO_PHASE
    ports = { inlet = "a", outlet = "b" }
    [components.valve]
    type = "Valve"
    C = "0.005 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "2 kg/s"
    ports = { inlet = "b", outlet = "c" }
    [components.drum]
    type = "PressureBoundary"
    p = "60 bar"
    m_nominal = "2 kg/s"
    ports = { port = "c" }
"""


@pytest.fixture(scope="module")
def boiling(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("boiling")
    return {
        law: run_cli(
            tmp,
            f"boiling_{law}",
            BOILING_TUBE.replace("TWO_PHASE", f'two_phase_friction = "{law}"'),
        )  # fmt: skip
        for law in ("friedel", "homogeneous")
    }


@pytest.mark.parametrize("law", ["friedel", "homogeneous"])
def test_boiling_tube_pressure_drop(boiling, law):
    run = boiling[law]
    assert run.returncode == 0, run.message
    n, m, D, L, nt = 20, 2.0, 0.025, 30.0, 4
    # the heat: at rest every volume takes Q_outer/n through its wall, so the enthalpy
    # rises linearly, h_i = h_in + (i + 1) Q/(n m) (exactly: the steady energy balance)
    h_in = last(run, "a.h")
    for i in range(n):
        assert last(run, f"riser.h_v[{i}]") == pytest.approx(
            h_in + (i + 1) * 2e6 / (n * m), rel=1e-8
        )
    p = [last(run, "a.p")] + [last(run, f"riser.p_v[{i}]") for i in range(n)]
    h = [h_in] + [last(run, f"riser.h_v[{i}]") for i in range(n)]
    x_out = WATER.state(p[-1], h[-1]).quality
    assert 0.4 < x_out < 0.7  # the case is a boiling one: x ~ 0.55 at the top
    dp_f = dp_head = 0.0
    for i in range(n):
        dp_f += face_friction(m, p[i], h[i], D, L / n, nt, 4.5e-5, law)
        dp_head += WATER.state(p[i], h[i]).rho * G * L / n
    # as the single-phase case: the run's m_reg changes the friction by < 1e-4
    print("boiling", law, "friction run/hand - 1 =", (p[0] - p[-1] - dp_head) / dp_f - 1,
          "dp", (p[0] - p[-1]) / 1e5, "bar")  # fmt: skip
    assert p[0] - p[-1] - dp_head == pytest.approx(dp_f, rel=1e-4)


def test_friedel_exceeds_homogeneous_and_the_lumped_law_of_the_liquid(boiling):
    # the measured gap of issue 22: a lumped k fitted to the liquid at the inlet gives
    # dp = k m|m|/rho with the mixture's density in the two-phase part, the homogeneous
    # model's multiplier; Friedel's is higher at 60 bar (phi_lo^2 above rho_l/rho_h),
    # and the friction of each differs from the lumped law's by the factors it states
    fr, ho = boiling["friedel"], boiling["homogeneous"]
    dp_fr = last(fr, "a.p") - last(fr, "b.p")
    dp_ho = last(ho, "a.p") - last(ho, "b.p")
    assert dp_fr > dp_ho


# ---------------------------------------------------------------- exchanger

ECONOMISER = """
    # An economiser bank: 40 serpentine tubes 38 x 4 mm (P235GH), 150 m each, staggered
    # at 100 x 90 mm in 50 rows across a 12 m2 flue-gas duct; water inside (counter-flow).
    [plant]
    name = "economiser"
    medium = "Water"
    [simulation]
    t_end = "STOP"
    start = "steady"
    [components.feed]
    type = "MassFlowBoundary"
    m = "20 kg/s"
    T = "180 degC"
    m_nominal = "20 kg/s"
    ports = { port = "w_in" }
    [components.eco]
    type = "HeatExchanger"
    hot_medium = "FlueGas"
    cold_medium = "Water"
    D = "30 mm"
    length = "150 m"
    n_tubes = 40
    wall_thickness = "4 mm"
    wall_material = "P235GH"
    arrangement = "staggered"
    pitch_transverse = "100 mm"
    pitch_longitudinal = "90 mm"
    n_rows = 50
    frontal_area = "12 m2"
    hot_dp_nominal = "5 mbar"
    n_sections = NSEC
    m_nominal = "20 kg/s"
    ports = { hot_in = "g_in", hot_out = "g_out", cold_in = "w_in", cold_out = "w_out" }
    [components.outlet_valve]
    type = "Valve"
    C = "0.03 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "20 kg/s"
    ports = { inlet = "w_out", outlet = "w_hdr" }
    [components.header]
    type = "PressureBoundary"
    p = "100 bar"
    m_nominal = "20 kg/s"
    ports = { port = "w_hdr" }
    [components.flue_gas]
    type = "MassFlowBoundary"
    medium = "FlueGas"
    m = "50 kg/s"
    T = GAS_T
    m_nominal = "50 kg/s"
    ports = { port = "g_in" }
    [components.stack_valve]
    type = "Valve"
    medium = "FlueGas"
    C = "1.6 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "50 kg/s"
    ports = { inlet = "g_out", outlet = "g_stack" }
    [components.stack]
    type = "PressureBoundary"
    medium = "FlueGas"
    p = "1 bar"
    T = "450 K"
    m_nominal = "50 kg/s"
    ports = { port = "g_stack" }
"""


@pytest.fixture(scope="module")
def economiser(tmp_path_factory):
    text = ECONOMISER.replace("STOP", "1 s").replace("NSEC", "40").replace("GAS_T", '"650 K"')
    return run_cli(tmp_path_factory.mktemp("eco"), "economiser", text)


def test_economiser_outlet_from_epsilon_ntu(economiser):
    run = economiser
    assert run.returncode == 0, run.message
    gas = get_medium("FlueGas")
    eco = run.plant.components["eco"]
    bank, tubes = eco.bank, eco.tubes
    m_w, m_g = 20.0, 50.0
    Tw_in, Tw_out = last(run, "w_in.T"), last(run, "w_out.T")
    Tg_in, Tg_out = last(run, "g_in.T"), last(run, "g_out.T")
    # each stream's heat capacity rate from its enthalpy change (the exact means)
    C_w = m_w * (last(run, "w_out.h") - last(run, "w_in.h")) / (Tw_out - Tw_in)
    C_g = m_g * (last(run, "g_in.h") - last(run, "g_out.h")) / (Tg_in - Tg_out)
    # U from the correlations at each stream's mean temperature and pressure
    pw = 0.5 * (last(run, "w_in.p") + last(run, "w_out.p"))
    trw = WATER.transport(np.array([pw]), np.array([WATER.h_pT(pw, 0.5 * (Tw_in + Tw_out))]))
    mu, k, cp = (float(trw[key][0]) for key in ("mu", "k", "cp"))
    D = tubes.D
    Re = m_w / tubes.n_tubes / tubes.A_tube * D / mu
    h_i = float(heat_transfer.nusselt_tube(Re, mu * cp / k, D / tubes.length, "T")) * k / D
    pg = 0.5 * (last(run, "g_in.p") + last(run, "g_out.p"))
    Tg_m = 0.5 * (Tg_in + Tg_out)
    trg = gas.transport(np.array([pg]), np.array([gas.h_pT(pg, Tg_m)]))
    mu_g, k_g, cp_g = (float(trg[key][0]) for key in ("mu", "k", "cp"))
    V_max = float(tube_banks.max_velocity(1.0, bank.D_o, bank.S_T, bank.S_L, True))
    Re_g = m_g / bank.A_front * V_max * bank.D_o / mu_g
    Nu_g = float(
        tube_banks.nusselt_zukauskas(Re_g, mu_g * cp_g / k_g, 50, bank.S_T, bank.S_L, True)
    )
    h_o = Nu_g * k_g / bank.D_o
    T_wall = 0.5 * (Tg_m + 0.5 * (Tw_in + Tw_out))
    lam = float(tubes.metal.conductivity(T_wall))
    UA = 1.0 / (
        1.0 / (h_i * tubes.A_inner) + tubes.conduction_resistance(lam) + 1.0 / (h_o * tubes.A_outer)
    )
    C_min, C_max = min(C_w, C_g), max(C_w, C_g)
    ntu, cr = UA / C_min, C_min / C_max
    eps = (1 - math.exp(-ntu * (1 - cr))) / (1 - cr * math.exp(-ntu * (1 - cr)))
    Q = eps * C_min * (Tg_in - Tw_in)
    # the run: 40 sections; the hand calculation: one U at the streams' mean
    # temperatures (the gas's k and mu change U by about +-4 % from inlet to outlet;
    # with NTU ~ 0.9 that moves the duty by a few tenths of a percent: 1 %)
    print("economiser: NTU", ntu, "Q run/hand - 1", last(run, "eco.Q_total") / Q - 1)
    assert last(run, "eco.Q_total") == pytest.approx(Q, rel=0.01)
    assert Tw_out == pytest.approx(Tw_in + Q / C_w, abs=0.5)
    assert 0.5 < ntu < 2.0  # a real exchanger, not a limit


def test_economiser_balances_and_gas_step(tmp_path):
    text = ECONOMISER.replace("STOP", "300 s").replace("NSEC", "10").replace(
        "GAS_T", '{ type = "step", t0 = "50 s", before = "650 K", after = "720 K" }')  # fmt: skip
    run = run_cli(tmp_path, "eco_step", text)
    assert run.finished, run.message
    b = balances(run)
    # conservation to the integrator's tolerance (issue 7: 1e-6 of the throughput;
    # the wall stores m e(T_w) of its metal, the E_wall column)
    assert b.mass_err < 1e-6 and b.energy_err < 1e-6, b
    assert last(run, "w_out.T") > float(run.df["w_out.T"].iloc[0]) + 5.0


# ---------------------------------------------------------------- condenser

CONDENSER = """
    # A surface condenser: 1200 tubes 25 x 1 mm (AISI 304), 5.5 m, two passes;
    # exhaust steam 10 kg/s, cooling water at 20 degC from 3 bar to 2.5 bar.
    [plant]
    name = "condenser"
    medium = "Water"
    [simulation]
    t_end = "1 s"
    start = "steady"
    [components.exhaust]
    type = "MassFlowBoundary"
    m = "10 kg/s"
    h = "2300 kJ/kg"
    m_nominal = "10 kg/s"
    ports = { port = "n_exhaust" }
    [components.condenser]
    type = "Condenser"
    V = "50 m3"
    A_hotwell = "10 m2"
    D = "23 mm"
    length = "5.5 m"
    n_tubes = 1200
    n_passes = 2
    wall_thickness = "1 mm"
    wall_material = "304"
    cw_m_nominal = "500 kg/s"
    p0 = "0.07 bar"
    level0 = "0.5 m"
    m_nominal = "10 kg/s"
    ports = { steam_in = "n_exhaust", condensate_out = "n_hotwell", cw_in = "n_cw_in", cw_out = "n_cw_out" }
    [components.drain]
    type = "ControlValve"
    Kv = 300
    m_nominal = "10 kg/s"
    ports = { inlet = "n_hotwell", outlet = "n_tank" }
    inputs = { z = "level_pi.z" }
    [components.tank]
    type = "PressureBoundary"
    p = "0.05 bar"
    m_nominal = "10 kg/s"
    ports = { port = "n_tank" }
    [components.level_pi]
    type = "PIController"
    Kp = "0.5 1/m"
    KI = "0.02 1/(m.s)"
    setpoint = "0.5 m"
    error_sign = "measured-setpoint"
    measured_nominal = "1 m"
    anti_windup = true
    inputs = { measured = "condenser.level" }
    [components.cw_supply]
    type = "PressureBoundary"
    p = "3 bar"
    T = "20 degC"
    m_nominal = "500 kg/s"
    ports = { port = "n_cw_in" }
    [components.cw_return]
    type = "PressureBoundary"
    p = "2.5 bar"
    m_nominal = "500 kg/s"
    ports = { port = "n_cw_out" }
"""


def test_condenser_duty_from_geometry(tmp_path):
    run = run_cli(tmp_path, "condenser", CONDENSER)
    assert run.returncode == 0, run.message
    m_w = last(run, "condenser.m_w")
    p_s = last(run, "condenser.p_v")
    Q = last(run, "condenser.Q")
    # the duty is what the steam gives (at rest: 10 kg/s from 2300 kJ/kg to h' of the
    # hotwell) and what the water takes
    h_l = float(WATER.saturation_enthalpies(np.array([p_s]))[0][0])
    assert Q == pytest.approx(10.0 * (2300e3 - h_l), rel=1e-6)
    assert Q == pytest.approx(m_w * (last(run, "n_cw_out.h") - last(run, "n_cw_in.h")), rel=1e-6)
    # hand calculation of the duty from the tubes at the run's shell pressure and flow:
    # water side Gnielinski (VDI G1) per tube of a pass, the 304 wall, Nusselt's film
    # condensation on 35 rows (round(sqrt(1200))) with Kern's N^(-1/6), solved for the
    # film's temperature difference, then epsilon-NTU (C_r = 0)
    D, L, nt, npass, s = 0.023, 5.5, 1200, 2, 0.001
    D_o = D + 2 * s
    p_w, h_w = last(run, "n_cw_in.p"), last(run, "n_cw_in.h")
    st = WATER.state(p_w, h_w)
    tr = WATER.transport(np.array([p_w]), np.array([h_w]))
    mu, k, cp = (float(tr[key][0]) for key in ("mu", "k", "cp"))
    Re = m_w / (nt / npass) / (math.pi * D * D / 4) * D / mu
    h_i = float(heat_transfer.nusselt_tube(Re, mu * cp / k, D / (npass * L), "T")) * k / D
    A_i, A_o = nt * math.pi * D * L, nt * math.pi * D_o * L
    sat = WATER.saturation_transport(np.array([p_s]))
    T_sat = float(sat["T"][0])
    lam = float(metals.metal("304").conductivity(0.5 * (T_sat + st.T)))
    R_w = math.log(D_o / D) / (2 * math.pi * lam * nt * L)
    args = [float(sat[key][0]) for key in ("rho_l", "rho_v", "mu_l", "k_l", "cp_l")]
    h_lv = float(sat["h_v"][0] - sat["h_l"][0])
    C = st.cp * m_w
    dT_in = T_sat - st.T
    dT_f = 2.0
    for _ in range(50):
        h_c = float(nusselt_horizontal_tube(D_o, dT_f, *args, h_lv, 35))
        R_c = 1 / (h_c * A_o)
        UA = 1 / (R_c + R_w + 1 / (h_i * A_i))
        Q_hand = -math.expm1(-UA / C) * C * dT_in
        dT_f = Q_hand / UA * R_c * UA
    # the run regularises the film difference (sqrt(dT^2 + 0.01 K^2): 0.05 % at 2 K)
    # and the flow (m_reg = 1 % of cw_m_nominal in NTU: 1e-4 at 700 kg/s): 5e-4
    print("condenser: Q run/hand - 1 =", Q / Q_hand - 1, "U =", UA / A_o, "W/(m2 K)")
    assert Q == pytest.approx(Q_hand, rel=5e-4)
    assert last(run, "condenser.UA") == pytest.approx(UA, rel=5e-4)
    # a clean condenser's overall coefficient (HEI design values 2.5 to 4 kW/(m2 K))
    assert 2000 < UA / A_o < 4500


# ---------------------------------------------------------------- lumped limit

LIMIT = """
    [plant]
    name = "limit"
    medium = "Water"
    [simulation]
    t_end = "1 s"
    start = "steady"
    [components.feed]
    type = "MassFlowBoundary"
    m = "4 kg/s"
    T = "50 degC"
    m_nominal = "4 kg/s"
    ports = { port = "a" }
    [components.tube]
    type = "Pipe"
    TUBE
    T_wall = "51 degC"
    n_volumes = 10
    m_nominal = "4 kg/s"
    ports = { inlet = "a", outlet = "b" }
    [components.valve]
    type = "Valve"
    C = "0.02 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "4 kg/s"
    ports = { inlet = "b", outlet = "c" }
    [components.sink]
    type = "PressureBoundary"
    p = "10 bar"
    m_nominal = "4 kg/s"
    ports = { port = "c" }
"""


def test_lumped_form_is_the_limit(tmp_path):
    # at (nearly) uniform properties the correlations' UA and k are constants: a
    # lumped pipe with those numbers is the same equations. The geometry here: 2
    # tubes of 25 mm, 20 m, no wall thickness (no conduction), water at 50 degC
    # heated by 1 K
    geo = run_cli(
        tmp_path, "geo", LIMIT.replace("TUBE", 'D = "25 mm"\nlength = "20 m"\nn_tubes = 2')
    )
    assert geo.returncode == 0, geo.message
    D, L, nt, n, m = 0.025, 20.0, 2, 10, 4.0
    p = [last(geo, "a.p")] + [last(geo, f"tube.p_v[{i}]") for i in range(n)]
    h = [last(geo, "a.h")] + [last(geo, f"tube.h_v[{i}]") for i in range(n)]
    # the correlation's UA and friction k (dp = k m|m|/rho) of the mean state
    pm, hm = 0.5 * (p[0] + p[-1]), 0.5 * (h[0] + h[-1])
    tr = WATER.transport(np.array([pm]), np.array([hm]))
    mu, kc, cp = (float(tr[key][0]) for key in ("mu", "k", "cp"))
    Re = m / nt / (math.pi * D * D / 4) * D / mu
    UA = (
        float(heat_transfer.nusselt_tube(Re, mu * cp / kc, D / L, "T"))
        * kc
        / D
        * nt
        * math.pi
        * D
        * L
    )
    rho = WATER.state(pm, hm).rho
    k = float(friction.pressure_drop(m / nt, rho, mu, D, L, 4.5e-5)) * rho / m**2
    V = nt * math.pi * D * D / 4 * L
    lumped = run_cli(tmp_path, "lumped", LIMIT.replace(
        "TUBE", f"V = {V!r}\nkA = {UA!r}\nk = {k!r}"))  # fmt: skip
    assert lumped.returncode == 0, lumped.message
    # the water's properties change by < 0.1 % over the 1 K: outlet temperature and
    # pressure drop agree to that share of the heating (1 K) and of the drop
    print("limit: T_out geo - lumped =", last(geo, "b.T") - last(lumped, "b.T"))
    assert last(geo, "b.T") == pytest.approx(last(lumped, "b.T"), abs=2e-3)
    dp_g = last(geo, "a.p") - last(geo, "b.p")
    dp_l = last(lumped, "a.p") - last(lumped, "b.p")
    print("limit: dp geo/lumped - 1 =", dp_g / dp_l - 1)
    assert dp_g == pytest.approx(dp_l, rel=2e-3)


# ---------------------------------------------------------------- zero flow, reversal

REVERSAL = """
    # A connecting line (3 parallel pipes, 50 mm, 40 m, 5 mm carbon steel wall):
    # the back pressure rises above the supply, the flow stops and reverses, then
    # the pressures are equal for a while (no flow).
    [plant]
    name = "reversal"
    medium = "Water"
    [simulation]
    t_end = "200 s"
    start = "steady"
    [components.supply]
    type = "PressureBoundary"
    p = "5 bar"
    T = "80 degC"
    m_nominal = "10 kg/s"
    ports = { port = "a" }
    [components.line]
    type = "Pipe"
    D = "50 mm"
    length = "40 m"
    n_tubes = 3
    wall_thickness = "5 mm"
    wall_material = "carbon steel"
    n_volumes = 8
    m_nominal = "10 kg/s"
    ports = { inlet = "a", outlet = "b" }
    [components.valve]
    type = "Valve"
    C = "0.02 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "10 kg/s"
    ports = { inlet = "b", outlet = "c" }
    [components.back]
    type = "PressureBoundary"
    T = "20 degC"
    m_nominal = "10 kg/s"
    ports = { port = "c" }
    [components.back.p]
    type = "table"
    times = ["0 s", "20 s", "80 s", "120 s", "160 s", "200 s"]
    values = ["4.5 bar", "4.5 bar", "5.5 bar", "5.5 bar", "5 bar", "5 bar"]
"""


def test_flow_reversal_and_zero_flow_through_a_geometry_pipe(tmp_path):
    run = run_cli(tmp_path, "reversal", REVERSAL)
    assert run.finished, run.message
    df = run.df
    m = df["line.m[0]"].to_numpy()
    assert m[0] > 3.0 and m.min() < -3.0  # forward, then reversed
    # equal pressures at the end: no flow (laminar friction and the static head of a
    # horizontal line: the flow is 0 to the solver's tolerance of the pressures)
    assert abs(m[-1]) < 1e-3
    # the cold water from the back side fills the line on reversal
    assert df["b.T"].iloc[df["line.m[0]"].idxmin()] < 320.0
    b = balances(run)
    assert b.mass_err < 1e-6 and b.energy_err < 1e-6, b


# ---------------------------------------------------------------- input errors


@pytest.mark.parametrize(
    "extra, words",
    [
        ('V = "0.1 m3"', "'V' follows from the geometry"),
        ("k = 1000", "two models of one thing"),
        ('kA = "10 kW/K"', "two models of one thing"),
        ('C_wall = "1 MJ/K"', "'C_wall' follows from wall_thickness"),
    ],
)
def test_mixed_lumped_and_geometry_parameters_are_input_errors(tmp_path, extra, words):
    text = HEATED_TUBE.replace('T_wall = "200 degC"', f'T_wall = "200 degC"\n    {extra}')
    run = run_cli(tmp_path, "mixed", text)
    assert run.returncode == 2, run.message
    assert "tube" in run.message and words in run.message
    assert "Traceback" not in run.message


# ---------------------------------------------------------------- ClaRa's evaporator

CLARA_EVAPORATOR = """
    # ClaRa's Components.VolumesValvesFittings.Pipes.Check.TwoPhaseFlow.Test_Pipe_L4_Advanced
    # (ClaRa 1.9.0): 300 vertical tubes of 30 mm bore, 80 m high, 280 kg/s of water at
    # 1400 kJ/kg in, 190 bar out; alpha = 10 kW/(m2 K) to a 5 mm steel wall whose outer
    # surface is held at T_OUTER; pressure loss "QuadraticNominalPoint_L4" (1e4 Pa at
    # 100 kg/s and rho(1 bar, 100 kJ/kg) = 998.2 kg/m3, i.e. k = 998.2 1/m4), 40 cells
    [plant]
    name = "clara_evaporator"
    medium = "Water"
    [simulation]
    t_end = "1 s"
    start = "steady"
    [components.source]
    type = "MassFlowBoundary"
    m = "280 kg/s"
    h = "1400 kJ/kg"
    m_nominal = "280 kg/s"
    ports = { port = "n_in" }
    [components.tube]
    type = "Pipe"
    PIPE
    dz = "80 m"
    n_volumes = 40
    wall_layers = 1
    T_outer = "T_OUTER"
    heat_transfer = "outlet"
    m_nominal = "280 kg/s"
    p0 = "195 bar"
    ports = { inlet = "n_in", outlet = "n_out" }
    [components.outlet]
    type = "Valve"
    C = "28 kg/(s.Pa0.5)"
    opening = 1
    m_nominal = "280 kg/s"
    ports = { inlet = "n_out", outlet = "n_sink" }
    [components.sink]
    type = "PressureBoundary"
    p = "190 bar"
    h = "100 kJ/kg"
    m_nominal = "280 kg/s"
    ports = { port = "n_sink" }
"""

#: ClaRa's published reference result (ReferenceResults/...Test_Pipe_L4_Advanced.mat,
#: Dymola): tube.inlet.p at rest with the outer wall at 573 K (t = 990 s) and at 873 K
#: (t = 3000 s) [Pa]
CLARA_INLET_P = {573.15: 196.8009e5, 873.15: 203.1763e5}
_A_I = 300 * math.pi * 0.03 * 80
CLARA_LUMPED = (
    f"V = {300 * math.pi / 4 * 0.03**2 * 80!r}\n    k = 998.2\n    kA = {1e4 * _A_I!r}\n"
    f"    C_wall = {7850 * 300 * math.pi / 4 * (0.04**2 - 0.03**2) * 80 * 460!r}\n"
    "    r_in = 0.015\n    r_out = 0.02\n    length = 24000\n    wall_conductivity = 50"
)
CLARA_GEOMETRY = (
    'D = "30 mm"\n    length = "80 m"\n    n_tubes = 300\n    wall_thickness = "5 mm"\n'
    f'    wall_material = "carbon steel"\n    convection = "lumped"\n    kA = {1e4 * _A_I!r}'
)


def test_clara_evaporator_reference_and_the_friction_from_geometry(tmp_path):
    out = {}
    for T in (573.15, 873.15):
        for tag, pipe in (("lumped", CLARA_LUMPED), ("geometry", CLARA_GEOMETRY)):
            text = CLARA_EVAPORATOR.replace("PIPE", pipe).replace("T_OUTER", f"{T} K")
            run = run_cli(tmp_path, f"clara_{tag}_{int(T)}", text)
            assert run.returncode == 0, run.message
            out[tag, T] = last(run, "n_in.p")
    # ClaRa's own law (dp = k m|m|/rho, the upwind density) reproduces its result: to
    # 0.01 bar in liquid, 0.12 bar after the wall heats the steam to 540 degC (TILMedia's
    # steel conductivity is not published with the test; 50 W/(m K) here): 0.2 bar
    for T, ref in CLARA_INLET_P.items():
        print("ClaRa", T, "ref", ref / 1e5, "lumped", out["lumped", T] / 1e5,
              "geometry", out["geometry", T] / 1e5)  # fmt: skip
        assert out["lumped", T] == pytest.approx(ref, abs=0.2e5)
    # from geometry, Darcy-Weisbach with Colebrook (and Friedel through the dome) gives
    # the friction of the actual flow: 0.37 bar less in liquid (the nominal point's
    # density is cold water's) and 4.3 bar less in superheated steam, where the
    # nominal-point law's 1/rho overstates it (issue 22: "friction is always divided by
    # density")
    assert out["lumped", 573.15] - out["geometry", 573.15] == pytest.approx(0.37e5, abs=0.1e5)
    assert out["lumped", 873.15] - out["geometry", 873.15] == pytest.approx(4.3e5, abs=0.3e5)


# ---------------------------------------------------------------- boiling front


def test_evaporator_from_geometry_through_boiling_onset(tmp_path):
    # plants/evaporator.toml written from geometry (20 tubes 32 x 4 mm of 16Mo3, 30 m,
    # a staggered finned bank of 16 rows with gas radiation): the flue gas ramps from
    # 560 K to 850 K, the water starts to boil at the outlet and the boiling front
    # moves upstream through the sections, each crossing located (phase modes); the
    # coefficients join at the saturation line (no chattering: tube_laws' doc)
    text = (
        (ROOT_PLANTS / "evaporator.toml")
        .read_text()
        .replace(
            """hot_V = "40 m3"
cold_V = "0.5 m3"
hot_kA = "30 kW/K"
cold_kA = "300 kW/K"
hot_dp_nominal = "0.005 bar"
cold_dp_nominal = "0.5 bar"
C_wall = "2 MJ/K\"""",
            """D = "32 mm"
length = "30 m"
n_tubes = 20
wall_thickness = "4 mm"
wall_material = "16Mo3"
arrangement = "staggered"
pitch_transverse = "90 mm"
pitch_longitudinal = "80 mm"
n_rows = 16
fin_height = "12 mm"
fin_thickness = "1 mm"
fin_pitch = "6 mm"
gas_radiation = true
hot_dp_nominal = "0.005 bar\"""",
        )
        .replace('t_end = "1200 s"', 't_end = "450 s"')
    )
    assert "arrangement" in text
    run = run_cli(tmp_path, "evaporator_geometry", textwrap.dedent(text))
    assert run.finished, run.message
    b = balances(run)
    assert b.mass_err < 1e-6 and b.energy_err < 1e-6, b
    p, h = last(run, "w_out.p"), last(run, "w_out.h")
    hl, hv = (float(v[0]) for v in WATER.saturation_enthalpies(np.array([p])))
    assert (h - hl) / (hv - hl) > 0.5  # boiling through most of the tubes at the end
    events = (tmp_path / "evaporator_geometry_out" / "events.csv").read_text()
    assert events.count("saturated liquid") >= 5  # the front crossed the sections
