"""Signals from any variable or node quantity ("n_hdr.p", "hdr.p_v[0]", "valve.m",
"n_hdr.T"), their units and dimension checks, the messages for bad links
(issue 12: a controller measuring its own output, a valve with both opening and
inputs.z, an unknown signal name first and alone), and a pressure loop and a
flow loop in plant files through the CLI."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.plant.plantfile import loads
from dnasim.run.output import read_results_csv

PLANTS = Path(__file__).parent / "plants"
PRESSURE = (PLANTS / "pressure_loop.toml").read_text()
FLOW = (PLANTS / "flow_loop.toml").read_text()
MEASURED = 'inputs = { measured = "n_hdr.p" }'


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


def write(tmp_path, text, name="p.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def errors_of(text) -> list[str]:
    with pytest.raises(PlantError) as info:
        spec = loads(text, "plant.toml").spec
        spec.build().compile()
    return getattr(info.value, "errors", None) or [str(info.value)]


def test_pressure_loop_through_the_cli(tmp_path):
    res = invoke("run", write(tmp_path, PRESSURE), "-o", tmp_path / "out", "-q")
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(tmp_path / "out" / "results.csv")
    t, p = d["time"], d["n_hdr.p"]
    # integral action: the header returns to the set point 10 bar after the outlet
    # valve opens at 10 s; the loop's slowest mode has decayed to below 1e-4 of the
    # disturbance (about 1 bar) by 120 s, measured 4e-6 relative
    assert abs(p[-1] - 10e5) < 1e-4 * 10e5
    assert np.min(p[t > 10.0]) < 9.9e5  # the disturbance was seen
    assert np.all((d["pid.z"] >= 0.0) & (d["pid.z"] <= 1.0))
    # the error is in the unit of the linked node pressure
    assert d["pid.e"][-1] == pytest.approx(10e5 - p[-1], abs=1e-6)
    # mass balance of the header volume: dM = int (m_in - m_out) dt (trapezoid on the
    # output grid; 1e-3 of the throughput is the quadrature error of its steps)
    dM = d["hdr.M[0]"][-1] - d["hdr.M[0]"][0]
    flow = np.trapezoid(d["hdr.m[0]"] - d["hdr.m[1]"], t)
    assert abs(dM - flow) < 1e-3 * np.trapezoid(d["hdr.m[1]"], t)


def test_flow_loop_through_the_cli(tmp_path):
    res = invoke("run", write(tmp_path, FLOW), "-o", tmp_path / "out", "-q")
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(tmp_path / "out" / "results.csv")
    m = d["v_ctrl.m"]
    # integral action: the flow reaches the new set point 1.5 kg/s; after 110 s the
    # remaining transient is below 1e-5 kg/s (measured 2e-7)
    assert abs(m[-1] - 1.5) < 1e-5
    assert abs(d["flow.m_s"][-1] - 1.5) < 1e-5
    # the fixed valve's law at the end: m = C z sqrt(dp) (dp >> dp_reg), 1e-9 is
    # the Newton tolerance on the flow
    dp = d["n_mid.p"][-1] - d["n_sink.p"][-1]
    assert d["v_fix.m"][-1] == pytest.approx(0.004 * np.sqrt(dp), rel=1e-6)


def test_any_variable_and_node_quantities_as_signals():
    base = loads(PRESSURE, "p.toml").plant
    system = base.compile()
    b = system.block("pid")
    assert b.gidx[b.index["measured"]] == system.index["n_hdr.p"]
    assert system.units["pid.e"] == "Pa"
    # Kp = "0.05 1/bar" was read in 1/Pa: the unit of the linked signal
    assert base.components["pid"].Kp == pytest.approx(0.05e-5, rel=1e-12)
    # a vector element of a component variable
    plant = loads(PRESSURE.replace(MEASURED, 'inputs = { measured = "hdr.p_v[0]" }')).plant
    system = plant.compile()
    b = system.block("pid")
    assert b.gidx[b.index["measured"]] == system.index["hdr.p_v[0]"]


def test_node_temperature_gets_an_ideal_probe_and_the_plant_is_unchanged():
    text = (
        PRESSURE.replace(MEASURED, 'inputs = { measured = "n_hdr.T" }')
        .replace('Kp = "0.05 1/bar"', 'Kp = "0.01 1/K"')
        .replace('setpoint = "10 bar"', 'setpoint = "150 degC"')
        .replace('measured_nominal = "10 bar"', 'measured_nominal = "400 K"')
    )
    plant = loads(text).plant
    system = plant.compile()
    assert "n_hdr~T" not in plant.components  # the caller's plant is not changed
    b = system.block("pid")
    assert b.gidx[b.index["measured"]] == system.index["n_hdr~T.T_s"]
    assert system.units["pid.e"] == "delta_K"
    assert plant.components["pid"].Kp == pytest.approx(0.01, rel=1e-12)


def test_a_temperature_wired_to_a_valve_opening_names_both_ends():
    errs = errors_of(PRESSURE.replace('inputs = { z = "pid.z" }', 'inputs = { z = "n_hdr.T" }'))
    assert len(errs) == 1
    assert "dimension mismatch" in errs[0] and "'n_hdr.T' is a temperature signal" in errs[0]
    assert "input 'z' of Valve 'v_in'" in errs[0]


def test_dimension_follows_a_gain_without_unit():
    # a temperature through a Gain (output unit = its input's) is still a temperature
    text = PRESSURE.replace('inputs = { z = "pid.z" }', 'inputs = { z = "g.y" }') + (
        '\n[components.g]\ntype = "Gain"\nk = 0.001\ninputs = { u = "n_hdr.T" }\n'
    )
    with pytest.raises(PlantError, match="'g.y' is a temperature signal"):
        loads(text).plant.compile()
    ok = text.replace("k = 0.001\n", 'k = 0.001\nunit = "1"\n')
    assert loads(ok).plant.compile() is not None


@pytest.mark.parametrize(
    "source, words",
    [
        ("hdr.p_v", "'hdr.p_v' is a vector of 1 elements; name one element"),
        ("hdr.p_v[3]", "out of range"),
        ("hdr.pv[0]", "Pipe 'hdr' has no signal output or variable 'pv[0]'"),
        ("n_hdr.q", "node 'n_hdr' has no quantity 'q'"),
        ("n_hdx.p", "no component named 'n_hdx' (and no node)"),
    ],
)
def test_an_unknown_signal_is_reported_first_and_alone(source, words):
    errs = errors_of(PRESSURE.replace(MEASURED, f'inputs = {{ measured = "{source}" }}'))
    # one paragraph: no follow-on unit errors on Kp, setpoint, measured_nominal (whose
    # unit is the signal's) and no "unconnected" input
    assert len(errs) == 1, errs
    assert words in errs[0] and "key 'measured'" in errs[0]


def test_valve_with_opening_and_signal_says_so(tmp_path):
    text = PRESSURE.replace('inputs = { z = "pid.z" }', 'opening = 0.5\ninputs = { z = "pid.z" }')
    res = invoke("check", write(tmp_path, text))
    assert res.exit_code == 2
    assert "both the parameter 'opening' and the signal input 'z' are given" in res.output
    assert "has no signal input" not in res.output


@pytest.mark.parametrize("controller", ["PIDController", "PIController"])
def test_controller_measuring_its_own_output(tmp_path, controller):
    text = (
        PRESSURE.replace(MEASURED, 'inputs = { measured = "pid.z" }')
        .replace('Kp = "0.05 1/bar"', "Kp = 0.05")
        .replace('setpoint = "10 bar"', "setpoint = 0.5")
        .replace('measured_nominal = "10 bar"', "measured_nominal = 1")
    )
    if controller == "PIController":
        text = text.replace('type = "PIDController"', 'type = "PIController"').replace(
            'T_i = "5 s"', "KI = 0.01"
        )
    res = invoke("check", write(tmp_path, text))
    assert res.exit_code == 2
    out = " ".join(res.output.split())
    assert "algebraic loop through signals only" in out
    assert "component 'pid' measures its own output ('pid.z' -> 'pid.measured')" in out
    assert "too few" not in out and "Traceback" not in out


def test_python_api_links_and_errors():
    from dnasim.library.signal_blocks import FirstOrderLag, Gain
    from dnasim.plant.plant import Plant

    plant = Plant("p")
    plant.add(FirstOrderLag("f", T=1.0))
    plant.add(Gain("g", k=2.0))
    plant.link("f.y", "g.u")
    plant.link("g.y", "f.u")  # a loop through a lag: fine
    assert plant.compile().n == 2
    with pytest.raises(PlantError, match="has no signal output or variable 'q'"):
        plant.link("f.q", "g.u")
    bad = Plant("p")
    bad.add(Gain("g"))
    bad.link("nowhere.p", "g.u")  # a node may be connected later: checked at compile
    with pytest.raises(PlantError, match="no component named 'nowhere' \\(and no node\\)"):
        bad.compile()
    # two gains in a ring: an algebraic loop through signals only
    ring = Plant("ring")
    ring.add(Gain("a", k=0.5))
    ring.add(Gain("b", k=0.5))
    ring.link("a.y", "b.u")
    ring.link("b.y", "a.u")
    with pytest.raises(PlantError, match="the signals of 'a', 'b' form a closed loop"):
        ring.compile()


def test_python_api_valve_with_opening_and_link_says_so():
    from dnasim.library.signal_blocks import Step
    from dnasim.library.valve import Valve
    from dnasim.plant.plant import Plant

    plant = Plant("x")
    plant.add(Valve("v", C=1e-3, opening=0.5))
    plant.add(Step("s"))
    with pytest.raises(PlantError, match="the parameter 'opening' is not given.*not both"):
        plant.link("s.y", "v.z")


def test_a_block_fed_by_its_own_output_is_a_loop():
    from dnasim.library.signal_blocks import Gain
    from dnasim.plant.plant import Plant

    plant = Plant("self")
    plant.add(Gain("g", k=0.5))
    plant.link("g.y", "g.u")
    with pytest.raises(PlantError, match="component 'g' reads its own output"):
        plant.compile()


# ------------------------------------------------- steady start of the control loops
#
# The plant files start steady. Before the fix the initial guess copied the source
# pressure into every node downstream, so the controlled valve had dp = 0 there:
# its flow m = C z sqrt(dp) did not depend on z, and the columns pid.m_I, pid.v,
# pid.z of the steady-start Jacobian had a common null vector (rows pid.integral,
# pid.output): "singular Jacobian". Now the steady start interpolates the unguessed
# node pressures between the boundaries.


LEAK = 1e-6  # Valve leakage default: z_e = LEAK + (1 - LEAK) z


def _valve_m(C, z, dp, dp_reg=10.0):
    """The Valve law, m = C z_e dp / (dp^2 + dp_reg^2)^(1/4) [kg/s]."""
    return C * (LEAK + (1 - LEAK) * z) * dp / (dp * dp + dp_reg * dp_reg) ** 0.25


def _valve_z(C, m, dp, dp_reg=10.0):
    """The opening z that passes m [kg/s] at dp [Pa]: the Valve law inverted."""
    return (m / _valve_m(C, 1.0, dp, dp_reg) - LEAK) / (1 - LEAK)


def _steady_rows(tmp_path, text):
    res = invoke("run", write(tmp_path, text), "-o", tmp_path / "out", "-q")
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(tmp_path / "out" / "results.csv")
    return d, d["time"] < 10.0  # the disturbance comes at 10 s


def test_pressure_loop_starts_steady_at_its_set_point(tmp_path):
    d, before = _steady_rows(tmp_path, PRESSURE)
    C, p_src, p_set, p_sink, z_out = 0.002, 20e5, 10e5, 1e5, 0.5
    # hand calculation: e = 0 makes p_hdr = 10 bar; the outlet valve passes
    # m = C z_out sqrt(p_hdr - p_sink); the inlet valve must pass the same flow,
    # so z = m / (C sqrt(p_src - p_hdr)). Tolerances: 1e-6 relative is the steady
    # Newton's tolerance (1e-8 of the nominal) with margin.
    m = _valve_m(C, z_out, p_set - p_sink)
    z = _valve_z(C, m, p_src - p_set)
    assert d["pid.e"][0] == pytest.approx(0.0, abs=1e-6 * p_set)
    assert d["n_hdr.p"][0] == pytest.approx(p_set, rel=1e-6)
    assert d["v_in.m"][0] == pytest.approx(m, rel=1e-6)
    assert d["v_out.m"][0] == pytest.approx(m, rel=1e-6)
    assert d["pid.z"][0] == pytest.approx(z, rel=1e-6)
    # the integral is the unknown that meets the set point: m_I = z (e = 0, no D part)
    assert d["pid.m_I"][0] == pytest.approx(z, rel=1e-6)
    # at rest until the disturbance: a steady state stays put (the integrator's
    # error control allows drifts of about rtol = 1e-6 of the scale)
    assert np.ptp(d["n_hdr.p"][before]) < 1e-5 * p_set
    assert np.ptp(d["pid.z"][before]) < 1e-5


def test_flow_loop_starts_steady_at_its_set_point(tmp_path):
    d, before = _steady_rows(tmp_path, FLOW)
    C_ctrl, C_fix, p_src, p_sink, m = 0.002, 0.004, 20e5, 5e5, 1.0
    # hand calculation: the fixed valve (z = 1, z_e = 1) passes m = C_fix sqrt(dp)
    # (1 + (dp_reg/dp)^2)^(-1/4), so p_mid = p_sink + (m/C_fix)^2 sqrt(1 + (dp_reg/dp)^2)
    # (one fixed-point pass from dp = (m/C_fix)^2 is exact to (dp_reg/dp)^4 = 3e-15);
    # the controlled valve's opening is the Valve law inverted at p_src - p_mid;
    # the lagged sensor reads the flow (d m_s/dt = 0). Tolerances as above.
    dp_fix = (m / C_fix) ** 2
    p_mid = p_sink + dp_fix * (1 + (10.0 / dp_fix) ** 2) ** 0.5
    z = _valve_z(C_ctrl, m, p_src - p_mid)
    assert d["pid.e"][0] == pytest.approx(0.0, abs=1e-6)
    assert d["flow.m_s"][0] == pytest.approx(m, rel=1e-6)
    for name in ("v_ctrl.m", "v_fix.m", "src.m"):
        assert d[name][0] == pytest.approx(m, rel=1e-6), name
    assert d["sink.m"][0] == pytest.approx(-m, rel=1e-6)
    assert d["n_mid.p"][0] == pytest.approx(p_mid, rel=1e-6)
    assert d["pid.z"][0] == pytest.approx(z, rel=1e-6)
    assert np.ptp(d["v_ctrl.m"][before]) < 1e-5 * m
    assert np.ptp(d["pid.z"][before]) < 1e-5


def test_steady_guess_interpolates_node_pressures_between_boundaries():
    from dnasim.start.guess import initial_guess

    system = loads(PRESSURE, "p.toml").plant.compile()
    y_steady = initial_guess(system, 0.0, interpolate=True)
    y_given = initial_guess(system, 0.0)
    p = {n: y_steady[system.node_index[n]] for n in ("n_a", "n_hdr")}
    # n_a and n_hdr lie between 20 bar and 1 bar on a chain of three components:
    # the harmonic interpolation on that path is linear, 20 - 19/3 and 20 - 38/3 bar
    assert p["n_a"] == pytest.approx(20e5 - 19e5 / 3, rel=1e-12)
    assert p["n_hdr"] == pytest.approx(20e5 - 38e5 / 3, rel=1e-12)
    # a given start keeps the copied guess (it sets the volumes' initial masses)
    assert y_given[system.node_index["n_hdr"]] == pytest.approx(20e5, rel=1e-12)
