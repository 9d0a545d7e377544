"""Linearisation checked against transfer functions known in closed form."""

from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.signal
import scipy.sparse as sp
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.plant.plantfile import load
from dnasim.tools.linearize import LinearizeError, linearize

PLANTS = Path(__file__).parent / "plants"
LAG = PLANTS / "lag_sensor.toml"
PI = PLANTS / "pi_mixing.toml"
# Forward differences with h = sqrt(eps) * scale have a relative truncation error of
# about sqrt(eps) ~ 1.5e-8 times the curvature; 1e-6 leaves room for the property calls.
FD_RTOL = 1e-6


def test_first_order_lag_sensor():
    """Sensor tau dT_s/dt = T - T_s on the supply node: G(s) = 1/(tau s + 1), tau = 8 s."""
    lm = linearize(load(LAG), ["supply.T"], ["sensor.T_s"])
    assert lm.state_names == ["sensor.T_s"]
    np.testing.assert_allclose(lm.eigenvalues.real, [-1 / 8.0], rtol=FD_RTOL)
    np.testing.assert_allclose(lm.time_constants, [8.0], rtol=FD_RTOL)
    np.testing.assert_allclose(lm.dc_gain, [[1.0]], rtol=FD_RTOL)
    assert isinstance(lm.A, sp.csr_matrix)
    assert lm.input_units == ["K"] and lm.output_units == ["K"]
    # the boundaries' counters are dropped: no output depends on them
    assert "supply.M_passed" in lm.dropped_states
    # usable with scipy.signal: the step response reaches the DC gain (1 - e^-10 at 10 tau)
    t, y = scipy.signal.step(lm.to_statespace(), T=np.linspace(0, 80, 801))
    assert y[-1] == pytest.approx(1 - np.exp(-10), rel=1e-3)  # 1e-3: lsim discretisation


def test_pi_loop_poles_from_characteristic_polynomial():
    """Mixing node T = K z (no storage), sensor 1/(tau s + 1), PI (Kp + KI/s) on
    e = T_s - r: closed-loop poles are the roots of tau s^2 + (1 - K Kp) s - K KI."""
    tau, Kp, KI = 4.0, 0.01, 0.002
    t_op = 110.0  # the loop has settled after the set-point step at 20 s
    open_loop = linearize(load(PI), ["cold_valve.z"], ["n_mix.T", "sensor.T_s"], t=t_op)
    # opening the loop at the valve leaves only the sensor lag
    np.testing.assert_allclose(open_loop.eigenvalues.real, [-1 / tau], rtol=FD_RTOL)
    K = open_loop.D.toarray()[0, 0]
    assert K < 0  # more cold air, lower temperature
    closed = linearize(load(PI), ["pi.setpoint"], ["sensor.T_s", "pi.z"], t=t_op)
    expected = np.sort_complex(np.roots([tau, 1 - K * Kp, -K * KI]))
    np.testing.assert_allclose(np.sort_complex(closed.eigenvalues), expected, rtol=1e-5)
    # integral action: the reading follows the set point with static gain 1; the
    # valve moves by 1/K per kelvin of set point
    np.testing.assert_allclose(closed.dc_gain[:, 0], [1.0, 1.0 / K], rtol=1e-5)


def test_unknown_input_is_reported():
    with pytest.raises(LinearizeError, match="no component named 'nosuch'"):
        linearize(load(LAG), ["nosuch.T"], ["sensor.T_s"])
    with pytest.raises(LinearizeError, match="differential state"):
        linearize(load(LAG), ["sensor.T_s"], ["sensor.T_s"])


def test_cli_writes_npz_and_mat(tmp_path):
    res = CliRunner().invoke(
        main,
        [
            "linearize",
            str(LAG),
            "--inputs",
            "supply.T",
            "--outputs",
            "sensor.T_s",
            "-o",
            str(tmp_path),
        ],
    )
    assert res.exit_code == 0, res.output
    assert "-0.125" in res.output and "DC gains" in res.output
    A = sp.load_npz(tmp_path / "linear_A.npz")
    np.testing.assert_allclose(A.toarray(), [[-0.125]], rtol=FD_RTOL)
    mat = scipy.io.loadmat(tmp_path / "linear.mat")
    np.testing.assert_allclose(mat["A"].toarray(), [[-0.125]], rtol=FD_RTOL)
    meta = np.load(tmp_path / "linear.npz")
    assert list(meta["state_names"]) == ["sensor.T_s"]


ATT = Path(__file__).parents[1] / "plants" / "attemperator.toml"


def _steady_output(text, names):
    from dnasim.plant.plantfile import loads
    from dnasim.start.initial import initial_values

    loaded = loads(text, "att.toml")
    system = loaded.plant.compile()
    y, yp = initial_values(system, 0.0, "steady")
    row = system.output_row(0.0, y, yp)
    out = system.output_names()
    return np.array([row[out.index(n)] for n in names])


def test_dc_gain_matches_nonlinear_steady_states():
    """The closed loop's static gains from the steam temperature equal the central
    difference of two nonlinear steady states (steam at 500 -/+ 0.5 degC)."""
    text = ATT.read_text()
    ramp = (
        'T = { type = "ramp", t0 = "10 min", t1 = "11 min", start = "500 degC", end = "600 degC" }'
    )
    assert ramp in text
    names = ["pi.z", "att.T", "spray_valve.m"]
    lo = _steady_output(text.replace(ramp, 'T = "499.5 degC"'), names)
    hi = _steady_output(text.replace(ramp, 'T = "500.5 degC"'), names)
    lm = linearize(load(ATT), ["steam.T"], names)
    # central difference over 1 K: second-order error ~ (0.5 K)^2 |g'''|/6, and the
    # steady-state solves converge to ~1e-10 relative: 1e-4 of the gain is ample
    np.testing.assert_allclose(lm.dc_gain[:, 0], hi - lo, rtol=1e-4, atol=1e-9)
    # integral action: the outlet temperature goes back to its set point
    assert abs(lm.dc_gain[1, 0]) < 1e-6


def test_dropping_states_keeps_the_poles():
    """The reduced model's poles are the full model's poles without the counters'
    zeros (a subsystem no output depends on cannot change the others' poles)."""
    full = linearize(load(ATT), ["spray_valve.z"], ["sensor.T_s"], keep_all_states=True)
    red = linearize(load(ATT), ["spray_valve.z"], ["sensor.T_s"])
    ev_full = full.eigenvalues[np.abs(full.eigenvalues) > 1e-9]
    # with the loop opened at z, the controller's integral only tracks the held z
    # through its back-calculation anti-windup, dm_I/dt = ... + (z - v)/T_t: a pole
    # at -1/T_t (T_t = T_i = 33.3 s) that sensor.T_s does not see, so the reduced
    # model drops it
    aw = np.isclose(ev_full, -1.0 / 33.3, rtol=1e-9)
    assert aw.sum() == 1
    ev_full = ev_full[~aw]
    np.testing.assert_allclose(
        np.sort_complex(red.eigenvalues), np.sort_complex(ev_full), rtol=1e-9
    )
    assert np.all(red.eigenvalues.real < 0)
    assert red.dc_gain[0, 0] < 0  # more spray, colder steam


def test_frequency_response_of_the_lag():
    """|G(jw)| = 1/sqrt(1 + (w tau)^2), phase -atan(w tau) for G = 1/(tau s + 1)."""
    lm = linearize(load(LAG), ["supply.T"], ["sensor.T_s"])
    w = np.array([0.01, 0.125, 1.0])
    G = lm.frequency_response(w)[:, 0, 0]
    np.testing.assert_allclose(np.abs(G), 1 / np.sqrt(1 + (8 * w) ** 2), rtol=FD_RTOL)
    np.testing.assert_allclose(np.angle(G), -np.arctan(8 * w), rtol=FD_RTOL)


def test_cli_at_a_time(tmp_path):
    """--at "110 s": the state simulated up to then (the PI loop of pi_mixing.toml)."""
    res = CliRunner().invoke(
        main,
        [
            "linearize",
            str(PI),
            "--inputs",
            "cold_valve.z",
            "--outputs",
            "sensor.T_s",
            "--at",
            "110 s",
        ],
    )
    assert res.exit_code == 0, res.output
    assert "at t = 110 s" in res.output and "-0.25" in res.output  # the sensor, tau = 4 s
    res = CliRunner().invoke(
        main, ["linearize", str(PI), "--inputs", "pi.nothing", "--outputs", "sensor.T_s"]
    )
    assert res.exit_code == 2 and "pi.nothing" in res.output and "Traceback" not in res.output
