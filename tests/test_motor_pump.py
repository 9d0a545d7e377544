"""MotorPump (issue 22 item 6): a pump driven by an induction motor, its speed a state
of the rotor's inertia. Checked against closed forms nobody here wrote: Kloss's
formula at its rated and breakdown points, the run-down of a rotor whose load torque
is proportional to omega^2 (a pump against a pure resistance) and of one braked by
omega^2 and omega terms (a pump against a shut check valve), the rotor's energy
balance, and the shut-off head at which the check valve of a tripped feed pump
closes. The field plant plants/feedpump_motor_trip.toml runs through the CLI."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from CoolProp.CoolProp import PropsSI

from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.core.timefunctions import Step, Table
from dnasim.library import PressureBoundary, Valve
from dnasim.library.motor_pump import MotorPump, breakdown_slip, kloss_torque
from dnasim.media import get_medium
from dnasim.model.physics import G
from dnasim.plant.plant import Plant
from dnasim.run.output import read_results_csv

FIELD = Path(__file__).resolve().parent.parent / "plants" / "feedpump_motor_trip.toml"
RPM = 2.0 * math.pi / 60.0  # [rad/s] per rpm

MOTOR = dict(J=10.0, n_sync=1500 * RPM, n_rated=1485 * RPM, P_rated=150e3)


def resistance_plant(**kw):
    """A water pump (H0 = 100 m, 80 m at 0.1 m3/s, a = 0, eta = 0.8) between two 2 bar
    boundaries through a fully open valve: the system curve is a pure resistance, so the
    operating point moves along Q ~ omega and the hydraulic torque is ~ omega^2."""
    plant = Plant("p", medium="Water")
    plant.add(PressureBoundary("src", p=2e5, T=293.15, m_nominal=100))
    args = dict(MOTOR, H0=100.0, H_nominal=80.0, Q_nominal=0.1, eta=0.8, m_nominal=100)
    args.update(kw)
    plant.add(MotorPump("pump", **args))
    plant.add(Valve("valve", C=0.1, opening=1.0, m_nominal=100))
    plant.add(PressureBoundary("sink", p=2e5, T=293.15, m_nominal=100))
    for a, n in [
        ("src.port", "a"),
        ("pump.inlet", "a"),
        ("pump.outlet", "b"),
        ("valve.inlet", "b"),
        ("valve.outlet", "c"),
        ("sink.port", "c"),
    ]:
        plant.connect(a, n)
    return plant


def test_kloss_curve_passes_the_rated_and_breakdown_points():
    # tau(s_r) = tau_r and max tau = k tau_r at s_k (Kloss's formula, e.g. Fischer,
    # Elektrische Maschinen, ch. 6): closed forms, to round-off
    ws, wr, k, P_r = 1500 * RPM, 1485 * RPM, 2.5, 150e3
    s_r, tau_r = (ws - wr) / ws, P_r / wr
    s_k = breakdown_slip(s_r, k)
    assert kloss_torque(s_r, k * tau_r, s_k) == pytest.approx(tau_r, rel=1e-12)
    assert kloss_torque(s_k, k * tau_r, s_k) == pytest.approx(k * tau_r, rel=1e-12)
    s = np.linspace(1e-4, 1.0, 20001)
    tau = np.array([kloss_torque(x, k * tau_r, s_k) for x in s])
    assert s[np.argmax(tau)] == pytest.approx(s_k, abs=1e-4)  # the grid's spacing
    assert kloss_torque(-s_r, k * tau_r, s_k) == pytest.approx(-tau_r)  # generator
    assert kloss_torque(0.0, k * tau_r, s_k) == 0.0  # no torque at synchronous speed


def test_steady_start_balances_motor_and_pump_torque():
    # the steady start: tau_m(omega) = P/omega + tau_f on the stable side of Kloss's
    # curve (slip below s_k), P the pump's shaft power m dp/(rho eta). 1e-9: the
    # steady Newton's tolerance, relative to torques ~600 N m.
    res = resistance_plant(P_friction=2e3).simulate(0.1, start="steady")
    w, tau_m, P, m = (res[k][0] for k in ("pump.omega", "pump.tau_m", "pump.P", "pump.m"))
    ws = MOTOR["n_sync"]
    w_reg = 1e-3 * MOTOR["n_rated"]  # P/omega regularised: (w_reg/omega)^2 = 1e-6 here
    tau_h = P * w / (w * w + w_reg**2)
    assert tau_m == pytest.approx(tau_h + 2e3 * w / MOTOR["n_rated"] ** 2, rel=1e-9)
    s_r = (ws - MOTOR["n_rated"]) / ws
    assert 0 < (ws - w) / ws < breakdown_slip(s_r, 2.5)
    rho = float(get_medium("Water").state(2e5, res["a.h"][0]).rho)
    dp = res["b.p"][0] - 2e5
    assert P == pytest.approx(m * dp / (rho * 0.8), rel=1e-6)  # softplus(dp, 100 Pa)


def test_run_down_after_trip_follows_the_closed_form():
    """Run-down of a tripped pump against a pure resistance.

    Against a system curve through the origin (a valve between two equal pressures)
    and a head curve H = H0 r^2 + b Q|Q| (a = 0), the operating point is similar at
    every speed: Q ~ r, H ~ r^2, so the shaft power P = rho g H Q/eta ~ r^3 and the
    hydraulic torque tau_h = P/omega = tau_0 (omega/omega_0)^2, tau_0 = P_0/omega_0 at
    the trip (constant eta). With the motor's torque gone and no friction,

        J domega/dt = -tau_0 omega^2/omega_0^2
        => d(1/omega)/dt = tau_0/(J omega_0^2)
        => omega(t) = omega_0/(1 + (t - t_trip)/tau),   tau = J omega_0/tau_0.

    The pump's regularisations (Q_reg = 1e-2 m_nominal/rho in the head curve, the valve's
    laminar band) break the similarity below ~1/10 of the speed; checked to omega_0/8.
    """
    t_trip = 1.0
    res = resistance_plant(supply=Step(t_trip, 1.0, 0.0)).simulate(
        40.0, start="steady", rtol=1e-8, atol_scaled=1e-8
    )
    t, w = res.t, res["pump.omega"]
    w0, tau0 = w[0], res["pump.tau_h"][0]
    tau = MOTOR["J"] * w0 / tau0
    after = (t > t_trip) & (w > w0 / 8)
    assert np.count_nonzero(after) > 20 and t[after][-1] - t_trip > 5 * tau
    exact = w0 / (1.0 + (t[after] - t_trip) / tau)
    err = np.abs(w[after] / exact - 1.0)
    # the regularisations' share grows as the flow falls (the solver's rtol is 1e-8):
    # measured 1.4e-7 down to 0.9 omega_0, 1.0e-5 to omega_0/2, 3.2e-4 to omega_0/8
    assert np.max(err[w[after] > 0.9 * w0]) < 1e-6
    assert np.max(err[w[after] > 0.5 * w0]) < 3e-5
    assert np.max(err) < 1e-3
    # and before the trip the speed holds
    assert np.all(np.abs(w[t < t_trip] / w0 - 1) < 1e-9)


def test_rotor_energy_balance_over_trip_and_restart():
    # W_motor = W_pump + W_friction + J (omega^2 - omega_0^2)/2 over a trip at 1 s and a
    # restart at 8 s (run-up on Kloss's curve); the accumulators integrate the powers
    # with the solver's error control, so the balance holds to its tolerance (rtol
    # 1e-7), relative to the motor's work (1.15 MJ). Measured 1.7e-6.
    plant = resistance_plant(P_friction=3e3, supply=Table([1.0, 1.01, 8.0, 8.01], [1, 0, 0, 1]))
    res = plant.simulate(20.0, start="steady", rtol=1e-7, atol_scaled=1e-7)
    w = res["pump.omega"]
    W_m, W_p, W_f = res["pump.W_motor"], res["pump.W"], res["pump.W_friction"]
    kinetic = 0.5 * MOTOR["J"] * (w**2 - w[0] ** 2)
    scale = np.max(np.abs(W_m))
    assert scale > 1e6
    assert np.max(np.abs(W_m - (W_p - W_p[0]) - W_f - kinetic)) < 1e-5 * scale
    assert w.min() < 0.5 * w[0]  # it ran down ...
    assert w[-1] == pytest.approx(w[0], rel=1e-5)  # ... and back up to its steady speed


def test_bad_motor_parameters_name_the_component():
    with pytest.raises(PlantError, match=r"'pump' \(MotorPump\).*n_rated.*below n_sync"):
        MotorPump("pump", **dict(MOTOR, n_rated=1600 * RPM), H0=100.0, b=-2000.0)
    with pytest.raises(PlantError, match=r"'pump' \(MotorPump\).*give J"):
        MotorPump("pump", **{k: v for k, v in MOTOR.items() if k != "J"}, H0=100.0, b=-2000.0)
    with pytest.raises(PlantError, match="unknown parameter.*speed"):
        MotorPump("pump", **MOTOR, H0=100.0, b=-2000.0, speed=1.0)


def test_feed_pump_motor_trip_field_plant_through_the_cli(tmp_path):
    """plants/feedpump_motor_trip.toml through ``dnasim run``: trip at 10 s, restart at 40 s.

    1. The check valve shuts where the flow passes zero, i.e. where the pump's shut-off
       head equals the back pressure: p_drum - p_in = rho g H0 r^2, so
       r_c = sqrt((p_drum - p_in)/(rho g H0)) (the line stands still: no friction; rho
       the casing water's density).
    2. Against the shut check valve only the shut-off losses P_0 r^3 (tau = P_0
       omega^2/n_0^3 = a omega^2) and the bearings (tau = P_f omega/n_r^2 = c omega) brake:
       J domega/dt = -a omega^2 - c omega, with u = 1/omega: J du/dt = a + c u, so
           omega(t) = 1/((1/omega_1 + a/c) exp(c (t - t_1)/J) - a/c)
       from (t_1, omega_1) just after the closure.
    3. After the restart the pump is back at its steady point.
    """
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["run", str(FIELD), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(out / "results.csv")
    t, w, m = d["time"], d["pump.omega"], d["pump.m"]
    assert t[-1] == pytest.approx(80.0)
    n0, J, P0, Pf = 2980 * RPM, 30.0, 120e3, 10e3
    # the steady point: ~57 kg/s at slip below rated (load 0.8 MW of 1.2 MW)
    assert 55.0 < m[0] < 62.0 and 3000 * RPM > w[0] > n0
    # 1. the flow passes zero at the shut-off head = the drum's back pressure
    k = np.flatnonzero((t > 10.0) & (m <= 0.0))[0]
    # the head's density is the casing water's, rho(p_out, h_2) (Pump with M_casing;
    # 2.2 K warmer than the suction after the compression and the shut-off losses),
    # from CoolProp's IF97, whose rho(p, h) goes through the backward T(p, h) (+-25 mK:
    # 2e-5 in rho, 1e-5 in r; measured 9e-6); the rows around the crossing: 7e-7 in r
    rho = PropsSI("D", "P", d["n_discharge.p"][k], "H", d["pump.h_2"][k], "IF97::Water")
    r_c = math.sqrt((100e5 - 6.8e5) / (rho * G * 1400.0))
    assert w[k] / n0 == pytest.approx(r_c, abs=3e-5)
    # 2. the run-down against the shut valve, from 1 s after the closure to the restart
    k1 = np.flatnonzero(t > t[k] + 1.0)[0]
    a, c = P0 / n0**3, Pf / n0**2
    sel = (t >= t[k1]) & (t < 40.0)
    exact = 1.0 / ((1.0 / w[k1] + a / c) * np.exp(c * (t[sel] - t[k1]) / J) - a / c)
    # measured 1.1e-3: the pump's zero-flow exchange w(0) dp/(rho eta) (~80 W against
    # 20-80 kW of shut-off power) and the check valve's leakage, left out of the form
    assert np.max(np.abs(w[sel] / exact - 1.0)) < 3e-3
    assert w[sel][-1] < 0.45 * n0  # a real run-down: below half speed after 30 s
    assert np.max(np.abs(m[sel])) < 0.01  # the check valve holds (leakage only)
    # 3. after the restart: back at the steady point
    assert w[-1] == pytest.approx(w[0], rel=1e-4)
    assert m[-1] == pytest.approx(m[0], rel=1e-3)
    # the suction never flashes (NPSH available ~ 20 m throughout)
    assert np.min(d["pump.NPSH_a"]) > 15.0


def test_run_up_from_rest_follows_the_motor_and_load_curves():
    """Start from standstill (given start, speed0 = 0) against the pure resistance.

    The load is similar at every speed (see the run-down test): tau_h = tau_0
    (omega/omega_0)^2 with tau_0, omega_0 of the steady point; the motor gives Kloss's
    tau_m(omega). So J domega/dt = tau_m(omega) - tau_0 (omega/omega_0)^2, integrated
    here by scipy (solve_ivp, rtol 1e-10) and compared with the plant's omega(t)."""
    from scipy.integrate import solve_ivp

    steady = resistance_plant().simulate(0.1, start="steady")
    w0, tau0 = steady["pump.omega"][0], steady["pump.tau_h"][0]
    res = resistance_plant(speed0=0.0).simulate(20.0, start="given", rtol=1e-8, atol_scaled=1e-8)
    ws, wr = MOTOR["n_sync"], MOTOR["n_rated"]
    tau_r = MOTOR["P_rated"] / wr
    s_k = breakdown_slip((ws - wr) / ws, 2.5)

    def f(t, y):
        s = (ws - y[0]) / ws
        return [(kloss_torque(s, 2.5 * tau_r, s_k) - tau0 * (y[0] / w0) ** 2) / MOTOR["J"]]

    ref = solve_ivp(f, (0.0, 20.0), [0.0], t_eval=res.t, rtol=1e-10, atol=1e-8)
    w = res["pump.omega"]
    # the load's similarity breaks below ~omega_0/10 (the head curve's Q_reg): compare
    # from 0.2 omega_0 on, relative to omega_0; measured 1.3e-4 (over the whole run too)
    sel = ref.y[0] > 0.2 * w0
    assert np.count_nonzero(sel) > 20
    assert np.max(np.abs(w[sel] - ref.y[0][sel])) < 1e-3 * w0
    assert w[-1] == pytest.approx(w0, rel=1e-6)  # at the steady point again


def test_bad_motor_parameters_in_a_plant_file_are_input_errors(tmp_path):
    # exit 2 and one paragraph naming the file, the table, the key and its line
    text = FIELD.read_text().replace('n_rated = "2980 rpm"', 'n_rated = "3100 rpm"')
    path = tmp_path / "plant.toml"
    path.write_text(text)
    res = CliRunner().invoke(main, ["check", str(path)])
    assert res.exit_code == 2
    out = res.output
    assert "plant.toml, [components.pump], key 'n_rated', line" in out
    assert "must be below n_sync" in out and out.count("\n") == 1
    assert "Traceback" not in res.output
