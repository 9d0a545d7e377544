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

from dnasim.cli import main
from dnasim.errors import PlantError
from dnasim.output import read_results_csv
from dnasim.plantfile import loads

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
    from dnasim.components.signal_blocks import FirstOrderLag, Gain
    from dnasim.plant import Plant

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
    from dnasim.components.signal_blocks import Step
    from dnasim.components.valve import Valve
    from dnasim.plant import Plant

    plant = Plant("x")
    plant.add(Valve("v", C=1e-3, opening=0.5))
    plant.add(Step("s"))
    with pytest.raises(PlantError, match="the parameter 'opening' is not given.*not both"):
        plant.link("s.y", "v.z")


def test_a_block_fed_by_its_own_output_is_a_loop():
    from dnasim.components.signal_blocks import Gain
    from dnasim.plant import Plant

    plant = Plant("self")
    plant.add(Gain("g", k=0.5))
    plant.link("g.y", "g.u")
    with pytest.raises(PlantError, match="component 'g' reads its own output"):
        plant.compile()
