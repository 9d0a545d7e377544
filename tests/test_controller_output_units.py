"""Controller parameters in the controller's output unit (issue 24): a PID whose output
is a heat flow (``unit = "W"``) takes its gain as "4 MW/bar" (output unit per measured
unit: 4e6 W / 1e5 Pa = 40 W/Pa) and its limits as "200 MW", in a plant file, from
Python and in a sweep case; a gain of another dimension is refused with one paragraph
naming the file, the component, the key, the value and the unit expected (exit 2).

The plant: docs/tutorial/drum_boiler.toml, whose PID 'fire' sets the drum's heat input
from the drum pressure (measured "drum.p" [Pa]).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

import dnasim
from dnasim.cli.commands import main
from dnasim.library.pid import PIDController
from dnasim.model.component import Component, Equation, SignalPort, Variable
from dnasim.plant.cases import CaseError, apply_case, check_cases
from dnasim.plant.plant import Plant
from dnasim.plant.plantfile import load, loads

ROOT = Path(__file__).resolve().parents[1]
DRUM = ROOT / "docs" / "tutorial" / "drum_boiler.toml"
SUPERHEATER = ROOT / "plants" / "superheater_line.toml"


def _drum_text(**fire):
    """The tutorial's drum boiler with the fire controller's keys replaced."""
    lines = DRUM.read_text().splitlines()
    start = lines.index("[components.fire]                  # drum pressure by the firing rate")
    out = []
    for i, line in enumerate(lines):
        key = line.split("=")[0].strip()
        if i > start and key in fire:
            line = f"{key} = {fire.pop(key)}"
        out.append(line)
    text = "\n".join(out) + "\n"
    # keys the file does not have: added at the end of the fire table (the last one)
    return text + "".join(f"{k} = {v}\n" for k, v in fire.items())


def _fire(loaded):
    return next(c for c in loaded.spec.components if c.name == "fire")


def test_gain_in_output_unit_per_measured_unit_is_exact():
    fire = _fire(load(DRUM))  # the tutorial writes Kp = "4 MW/bar", z_max = "200 MW"
    assert 'Kp = "4 MW/bar"' in DRUM.read_text()
    assert fire.params["Kp"] == 40.0  # 4e6 W / 1e5 Pa, exactly (10 * 4 in binary)
    assert fire.params["z_max"] == 200e6 and fire.params["z_min"] == 0.0
    numbers = _fire(loads(_drum_text(Kp="40.0", z_max="200e6", z_min="0.0"), "drum.toml"))
    assert numbers.params["Kp"] == 40.0 and numbers.params["z_max"] == 200e6
    # other spellings of the same gain
    for text in ('"40 W/Pa"', '"0.04 MW/kPa"', '"4e6 W/bar"'):
        other = _fire(loads(_drum_text(Kp=text), "drum.toml"))
        assert other.params["Kp"] == pytest.approx(40.0, rel=1e-15), text  # decimal rounding


def test_manual_output_time_function_in_the_output_unit():
    tf = '{ type = "step", t0 = "60 s", before = "10 MW", after = "20 MW" }'
    fire = _fire(loads(_drum_text(z_manual=tf), "drum.toml"))
    assert fire.params["z_manual"](0.0) == 10e6 and fire.params["z_manual"](100.0) == 20e6


@pytest.mark.parametrize(
    "value, dimension",
    [('"4 MW/K"', "thermal conductance"), ('"4 1/bar"', "kg-1.m.s2")],
)
def test_gain_of_another_dimension_is_one_paragraph_exit_2(tmp_path, value, dimension):
    plant = tmp_path / "drum.toml"
    plant.write_text(_drum_text(Kp=value))
    res = CliRunner().invoke(main, ["check", str(plant)])
    assert res.exit_code == 2, res.output
    text = res.output.strip()
    assert "Traceback" not in text
    assert "\n\n" not in text  # one paragraph: no follow-on error on the drum's input Q
    assert f"{plant}, [components.fire], key 'Kp'" in text
    assert f"{value.strip(chr(34))!r} has the dimension of {dimension}" in text
    assert "(unit 'W/Pa')" in text  # the expected unit, and where it comes from:
    assert "output unit per measured unit: 'W' (the parameter 'unit') per 'Pa'" in text


def test_limit_in_a_wrong_unit_names_the_output_unit(tmp_path):
    plant = tmp_path / "drum.toml"
    plant.write_text(_drum_text(z_max='"200 bar"'))
    res = CliRunner().invoke(main, ["check", str(plant)])
    assert res.exit_code == 2, res.output
    assert "key 'z_max'" in res.output and "(unit 'W')" in res.output
    assert "z_max is in the output unit, 'W' (the parameter 'unit')" in res.output


def test_dimensionless_pi_controller_still_refuses_an_output_unit(tmp_path):
    # PIController's output is dimensionless: its Kp is 1 per measured unit (1/K here)
    text = SUPERHEATER.read_text()
    assert 'type = "PIController"\nKp = "0.02 1/K"' in text
    plant = tmp_path / "sh.toml"
    plant.write_text(text.replace('Kp = "0.02 1/K"', 'Kp = "4 MW/K"', 1))
    res = CliRunner().invoke(main, ["check", str(plant)])
    assert res.exit_code == 2, res.output
    assert "key 'Kp'" in res.output and "(unit '1/K')" in res.output
    assert "output unit per measured unit: '1' per 'K' (the measured signal)" in res.output
    assert "\n\n" not in res.output.strip()


class PressureSignal(Component):
    """A constant pressure signal p = 90 bar (test only)."""

    REGISTER = False
    USES_MEDIUM = False
    SIGNAL_OUTPUTS = (SignalPort("p", "Pa", "pressure", variable="p"),)

    def variables(self):
        return [Variable("p", "Pa", 1e5)]

    def equations(self):
        return [Equation("p", y=("p",), residual=lambda t, x, xp: x["p"] - 90e5)]


def _python_plant(**pid):
    plant = Plant("signals")
    plant.add(PressureSignal("src"))
    plant.add(
        PIDController(
            "fire", unit="W", T_i="120 s", setpoint="90 bar", measured_nominal="90 bar", **pid
        )
    )
    plant.link("src.p", "fire.measured")
    return plant


def test_python_api_reads_the_output_unit_as_a_plant_file():
    fire = dnasim.compile(_python_plant(Kp="4 MW/bar", z_max="200 MW")).components["fire"]
    assert fire.params["Kp"] == 40.0 and fire.Kp == 40.0  # the gain the equations use
    assert fire.params["z_max"] == 200e6
    # the per-unit gain with its span in the measured unit: Kc * 200 MW / 10 bar
    fire = dnasim.compile(_python_plant(Kc=1.0, measured_span="10 bar", z_max="200 MW")).components[
        "fire"
    ]
    assert fire.Kp == 200.0  # 2e8 W / 1e6 Pa


def test_python_api_refuses_a_gain_of_another_dimension():
    with pytest.raises(dnasim.PlantError, match="component 'fire'") as info:
        dnasim.compile(_python_plant(Kp="4 MW/K"))
    assert "'Kp'" in str(info.value) and "(unit 'W/Pa')" in str(info.value)
    with pytest.raises(dnasim.PlantError, match="z_max") as info:
        PIDController("fire", unit="W", Kp=40.0, setpoint=0.0, z_max="200 bar")
    assert "(unit 'W')" in str(info.value)


def test_sweep_case_gain_in_output_unit():
    spec = load(DRUM).spec
    check_cases(spec, [{"fire.Kp": "4 MW/bar"}, {"fire.Kp": "8 MW/bar"}])
    new = apply_case(spec, {"fire.Kp": "8 MW/bar"})
    assert next(c for c in new.components if c.name == "fire").params["Kp"] == 80.0
    with pytest.raises(CaseError, match="fire.Kp = '4 MW/K'.*unit 'W/Pa'") as info:
        check_cases(spec, [{"fire.Kp": "4 MW/K"}])
    assert "output unit per measured unit: 'W' (the parameter 'unit') per 'Pa'" in str(info.value)
