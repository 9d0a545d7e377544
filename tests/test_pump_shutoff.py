"""Pump at shut-off (tests/plants/pump_shutoff.toml through the CLI): the discharge
valve is shut from 12 s to 72 s; the shaft power at zero flow P_0 heats the water
in the pump casing (mass M), and the run goes on when the valve reopens.

Closed forms (Pump docstring), with rho = rho(p_out, h_2) from CoolProp's IF97:

    running    P = m (p_out - p_in)/(rho eta) + P_0,   h_2 = h_in + P/m       (steady)
    shut       dh_2/dt = P_0/M  [J/(kg s)],   dT_2/dt = P_0/(M c_p(p, T_2))  [K/s]
    energy     W = Delta(U_line + E_wall + M h_2) - H_passed(tank) - H_passed(header)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from CoolProp.CoolProp import PropsSI
from scipy.optimize import brentq

from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.plant.plantfile import loads
from dnasim.run.output import read_results_csv

PLANT = Path(__file__).parent / "plants" / "pump_shutoff.toml"
WATER = "IF97::Water"
M, P0, ETA = 20.0, 20e3, 0.7  # kg, W, - (the plant file's M_casing, P_shutoff, eta)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("shutoff") / "out"
    res = CliRunner().invoke(main, ["run", str(PLANT), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output  # the run continues after the valve reopens
    _, _, d = read_results_csv(out / "results.csv")
    return d


def _rho_ph(p, h):
    """rho [kg/m3] at (p, h) from IF97's forward equation: T solved from h(p, T) = h.
    (CoolProp's IF97 rho(p, h) goes through the backward equation T(p, h), whose
    +-25 mK consistency is 7e-6 of rho here.)"""
    T = brentq(lambda T: PropsSI("H", "P", p, "T", T, WATER) - h, 274.0, 600.0, xtol=1e-12)
    return PropsSI("D", "P", p, "T", T, WATER)


def _shaft_power(d, i):
    p_in, p_out, h_2 = d["n_suction.p"][i], d["n_discharge.p"][i], d["pump.h_2"][i]
    rho = _rho_ph(p_out, h_2)
    return d["pump.m"][i] * (p_out - p_in) / (rho * ETA) + P0


def test_running_pump_power_and_enthalpy_rise(run):
    d = run
    for i in (0, -1):  # steady before the valve closes, and again at the end
        m = d["pump.m"][i]
        assert m > 10.0
        # P = m dp/(rho eta) + P_0; 1e-6: the steady Newton and the integrator's
        # tolerance at the end (measured 1e-13 and 4e-13)
        assert d["pump.P"][i] == pytest.approx(_shaft_power(d, i), rel=1e-6)
        # the casing at rest: h_2 = h_in + P/m. At the steady start to the Newton
        # tolerance (1e-9, measured 1e-13); at the end, 46 s after the valve opened,
        # the line (50 kg, flushed in 3.8 s) is still settling: h_2 - h_in - P/m =
        # -(M/m) dh_2/dt, measured 1e-8 of the rise; 1e-6
        rise = d["pump.h_2"][i] - d["n_suction.h"][i]
        assert rise == pytest.approx(d["pump.P"][i] / m, rel=1e-9 if i == 0 else 1e-6)


def test_shut_pump_heats_its_water_at_p_over_m_cp(run):
    d = run
    t = d["time"]
    shut = (t >= 20.0) & (t <= 70.0)  # the valve is closed from 12 s to 72 s
    # the flow is the closed valve's leakage (1e-6 of the open flow, ~2e-5 kg/s)
    assert np.max(np.abs(d["pump.m"][shut])) < 1e-4
    # the shaft power is P_0, plus w(0) dp/(rho eta) = 2.6 W (w(0) = 3/16 m_eps =
    # 1.9e-3 kg/s, the smooth upwind weight at zero flow; Pump docstring): 2e-4 of P_0
    # (measured 1.3e-4)
    assert np.allclose(d["pump.P"][shut], P0, rtol=2e-4)
    # the enthalpy rises at P_0/M. The same w(0) exchanges casing water with the
    # discharge node (the suction gets back its own water, h_1 = h_in: Pump doc), a
    # loss w(0) (h_2 - h_out); h_out is the mean of h_2 and the line's stagnant water,
    # so the loss is at most w(0) (h_2 - h_line)/2 = 1.9e-3 kg/s x 30 kJ/kg = 57 W at
    # the end: 0.3 % of P_0 (measured -0.15 % on the mean slope; -0.31 % before the
    # suction stopped taking casing water)
    slope, _ = np.polyfit(t[shut], d["pump.h_2"][shut], 1)
    assert slope == pytest.approx(P0 / M, rel=3e-3)
    # the temperature at dT/dt = P_0/(M c_p): central differences on the 0.5 s grid
    # (c_p changes by 1e-4 over a step: the difference quotient is exact to 1e-7),
    # c_p from CoolProp at the casing state; 0.8 % for the zero-flow exchange above,
    # which grows with h_2 - h_line (measured -0.02 % at 20 s, -0.25 % at 70 s)
    for tc in (20.0, 45.0, 70.0):
        k = int(np.argmin(np.abs(t - tc)))
        dTdt = (d["pump.T_2"][k + 1] - d["pump.T_2"][k - 1]) / (t[k + 1] - t[k - 1])
        cp = PropsSI("C", "P", d["n_discharge.p"][k], "T", d["pump.T_2"][k], WATER)
        assert dTdt == pytest.approx(P0 / (M * cp), rel=8e-3), tc
    # about 14 K in the 60 s: P_0 60 s/(M c_p) = 14.35 K at c_p = 4180 J/(kg K), the
    # mean of 12 s to 72 s (measured 14.47 K: the ramps' own heating at part flow)
    rise = d["pump.T_2"][np.argmin(np.abs(t - 72.0))] - d["pump.T_2"][0]
    assert 14.0 < rise < 15.0


def test_valve_reopens_and_the_plant_returns_to_its_steady_state(run):
    d = run
    # the warm water is flushed out (the casing in M/m = 1.5 s, the line in 3.8 s):
    # 46 s later the state is the initial steady state again (1e-6: the tail of the
    # transient is e^-12 of it, measured 5e-9)
    for name in ("pump.m", "pump.h_2", "pump.P", "n_discharge.p"):
        assert d[name][-1] == pytest.approx(d[name][0], rel=1e-6), name


def test_pump_energy_balance_over_the_run(run):
    d = run

    # the shaft work W = int P dt (an accumulator) ends up as the energy that left
    # through the boundaries plus what the line, its wall and the casing water stored;
    # 1e-5 of W is the integrators' tolerance on the ~1e8 J of enthalpy that passed
    # the boundaries (rtol 1e-6 of each accumulator; measured 2e-13 of W)
    def delta(name):
        return d[name][-1] - d[name][0]

    stored = delta("line.U_total") + delta("line.E_wall") + M * delta("pump.h_2")
    passed = d["tank.H_passed"][-1] + d["header.H_passed"][-1]
    W = d["pump.W"][-1]
    assert W == pytest.approx(stored - passed, rel=1e-5)


def test_shutoff_power_needs_the_casing():
    text = PLANT.read_text().replace('M_casing = "20 kg"\n', "")
    with pytest.raises(PlantError, match="P_shutoff needs M_casing"):
        loads(text, "p.toml")
