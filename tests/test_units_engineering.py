"""Units engineers type (issue 24, item 4): gauge pressures against a stated atmosphere,
the refused ambiguous names, suggestions for unknown units, and one rule for a number
written with or without a space before its unit."""

from __future__ import annotations

from pathlib import Path

import pytest

from dnasim.core.errors import PlantError, Problems
from dnasim.core.units import STANDARD_ATMOSPHERE, UnitError, convert, convert_quantity, to_si
from dnasim.plant.plantfile import loads

ROOT = Path(__file__).resolve().parents[1]
PRESSURE_LOOP = (ROOT / "tests" / "plants" / "pressure_loop.toml").read_text()

REL = 1e-12  # products of exact decimal definitions: a few ulps apart (test_units_pint.py)


# ------------------------------------------------------------------ gauge units


@pytest.mark.parametrize(
    "text, atmosphere, expected",
    [
        ("5 barg", None, 5e5 + 101325.0),
        ("0 barg", None, 101325.0),
        ("-1.01325 barg", None, 0.0),
        ("150 psig", None, 150 * 6894.757293168361 + 101325.0),
        ("0 psig", None, 101325.0),
        ("20 mbarg", None, 2000.0 + 101325.0),
        ("-30 kPag", None, -30e3 + 101325.0),
        ("16 MPag", None, 16e6 + 101325.0),
        ("5 barg", 95000.0, 5e5 + 95000.0),
        ("5 bar", 95000.0, 5e5),  # an absolute unit ignores the atmosphere
        ("5 bara", 95000.0, 5e5),
        ("14.7 psia", 95000.0, 14.7 * 6894.757293168361),
    ],
)
def test_gauge_pressures_are_absolute_plus_the_atmosphere(text, atmosphere, expected):
    assert to_si(text, "Pa", atmosphere) == pytest.approx(expected, rel=REL, abs=1e-9)
    assert convert_quantity(text, "Pa", atmosphere=atmosphere) == pytest.approx(
        expected, rel=REL, abs=1e-9
    )


def test_the_default_atmosphere_is_the_standard_one():
    assert STANDARD_ATMOSPHERE == 101325.0  # ISO 2533 / CGPM 1954, exactly


def test_conversion_to_a_gauge_unit_is_the_inverse():
    assert convert(601325.0, "Pa", "barg") == pytest.approx(5.0, rel=REL)
    assert convert(5.0, "barg", "psig") == pytest.approx(5e5 / 6894.757293168361, rel=REL)
    assert convert(5.0, "barg", "bar") == pytest.approx(6.01325, rel=REL)
    assert convert(5.0, "barg", "bar", atmosphere=1e5) == pytest.approx(6.0, rel=REL)


def test_a_gauge_unit_inside_a_compound_is_a_difference():
    # like degC in "W/(m2.degC)": a gain per bar of gauge pressure is a gain per bar
    assert to_si("0.05 1/barg", "1/Pa") == pytest.approx(0.05e-5, rel=REL)
    assert to_si("2 kg/(s.barg0.5)", "kg/(s.Pa0.5)") == pytest.approx(2 / 316.22776601683796)


def test_a_difference_parameter_refuses_a_gauge_pressure():
    with pytest.raises(UnitError) as info:
        convert_quantity("2 barg", "Pa", difference=True)
    msg = str(info.value)
    assert "gauge pressure" in msg and "pressure difference" in msg and "'2 bar'" in msg
    with pytest.raises(UnitError, match="'30 psi'"):
        convert_quantity("30 psig", "Pa", difference=True)
    # the absolute unit of the same size is the difference
    assert convert_quantity("2 bar", "Pa", difference=True) == 2e5


def test_a_gauge_pressure_where_no_pressure_is_expected_is_refused():
    with pytest.raises(UnitError, match="gauge pressure.*dimensionless"):
        convert_quantity("2 barg", "1")
    with pytest.raises(UnitError, match="'2 1/bar'"):
        convert_quantity("2 barg", "1/Pa")


def test_sine_amplitude_in_barg_is_a_difference():
    # the amplitude of a sine next to its mean in barg: 0.5 barg means 0.5 bar, as
    # "10 degC" means 10 K there
    assert convert_quantity("0.5 barg", "Pa", lenient_difference=True) == 5e4


def test_delta_pa_parameter_of_a_component_refuses_barg():
    from dnasim.core.values import param_value
    from dnasim.library import REGISTRY

    valve = REGISTRY["Valve"]
    p = next(p for p in valve.PARAMS if p.name == "dp_reg")
    assert p.unit == "delta_Pa"
    errors = Problems("plant.toml", None)
    assert param_value("2 barg", p, errors, ("components", "v"), "dp_reg", cls=valve) is None
    (item,) = errors.items
    assert "pressure difference" in str(item) and "'2 bar'" in str(item)
    errors = Problems("plant.toml", None)
    assert param_value("2 bar", p, errors, ("components", "v"), "dp_reg", cls=valve) == 2e5
    assert not errors.items
    # the same from Python
    with pytest.raises(PlantError, match="dp_reg.*pressure difference"):
        valve("v", C=0.002, dp_reg="2 barg")


def _pressure_loop(atmosphere_line: str = "") -> str:
    text = PRESSURE_LOOP.replace('p = "20 bar"', 'p = "19 barg"')
    text = text.replace('p = "1 bar"', 'p = "0 barg"')
    text = text.replace('setpoint = "10 bar"', 'setpoint = "9 barg"')
    text = text.replace('Kp = "0.05 1/bar"', 'Kp = "0.05 1/barg"')
    return text.replace('medium = "Water"', f'medium = "Water"\n{atmosphere_line}')


@pytest.mark.parametrize(
    "line, atm",
    [
        ("", 101325.0),
        ('atmosphere = "1 bar"', 1e5),
        ('atmosphere = "0.95 bar"', 95000.0),
        ('atmosphere = "13.5 psi"', 13.5 * 6894.757293168361),
        ("atmosphere = 98000", 98000.0),
    ],
)
def test_plant_file_gauge_values_use_the_stated_atmosphere(line, atm):
    loaded = loads(_pressure_loop(line), "gauge.toml")
    assert loaded.spec.atmosphere == pytest.approx(atm, rel=REL)
    comps = loaded.plant.components
    assert comps["src"].param_at("p", 0.0) == pytest.approx(19e5 + atm, rel=REL)
    assert comps["sink"].param_at("p", 0.0) == pytest.approx(atm, rel=REL)
    # the set point is in the unit of the measured node pressure (Pa), absolute
    assert comps["pid"].param_at("setpoint", 0.0) == pytest.approx(9e5 + atm, rel=REL)
    assert comps["pid"].Kp == pytest.approx(0.05e-5, rel=REL)


def test_the_same_plant_in_absolute_units_gives_the_same_parameters():
    gauge = loads(_pressure_loop('atmosphere = "1 bar"'), "gauge.toml").plant.components
    absolute = loads(PRESSURE_LOOP, "abs.toml").plant.components
    for name, key in (("src", "p"), ("sink", "p"), ("pid", "setpoint")):
        assert gauge[name].param_at(key, 0.0) == pytest.approx(
            absolute[name].param_at(key, 0.0), rel=REL
        )


def test_a_time_function_in_barg():
    text = _pressure_loop('atmosphere = "1 bar"').replace(
        'p = "19 barg"',
        'p = { type = "sine", mean = "19 barg", amplitude = "0.5 barg", period = "60 s" }',
    )
    f = loads(text, "sine.toml").plant.components["src"].params["p"]
    assert f.mean == pytest.approx(20e5) and f.amplitude == pytest.approx(0.5e5)


@pytest.mark.parametrize(
    "value, words",
    [
        ('"1.013"', ["between 0.2 and 1.2 bar", "1.013 Pa", '"1.013 bar"']),
        ('"2 bar"', ["between 0.2 and 1.2 bar"]),
        ('"0 barg"', ["absolute pressure", "'0 barg'"]),
        ('"20 degC"', ["temperature", "pressure"]),
        ("true", ["boolean"]),
    ],
)
def test_an_invalid_atmosphere_is_named(value, words):
    with pytest.raises(PlantError) as info:
        loads(_pressure_loop(f"atmosphere = {value}"), "gauge.toml")
    msg = str(info.value)
    assert "gauge.toml" in msg and "[plant]" in msg and "atmosphere" in msg
    for w in words:
        assert w in msg


def test_python_api_gauge_values():
    from dnasim.library import REGISTRY
    from dnasim.plant.spec import ComponentSpec, PlantSpec

    boundary = REGISTRY["PressureBoundary"]
    assert boundary("b", p="5 barg", T="150 degC").param_at("p", 0) == 601325.0
    b = boundary("b", p="5 barg", T="150 degC", atmosphere="0.95 bar")
    assert b.param_at("p", 0) == pytest.approx(595000.0, rel=REL)
    with pytest.raises(PlantError, match="absolute pressure"):
        boundary("b", p="5 barg", T="150 degC", atmosphere="0 barg")
    # a PlantSpec built in Python carries its atmosphere to its components
    spec = loads(PRESSURE_LOOP, "abs.toml").spec
    spec.atmosphere = 95000.0
    spec.components = [
        ComponentSpec(c.name, c.type, dict(c.params), c.ports, c.inputs) for c in spec.components
    ]
    spec.components[0].params["p"] = "19 barg"
    assert spec.components[0].name == "src"
    plant = PlantSpec.build(spec)
    assert plant.components["src"].param_at("p", 0) == pytest.approx(19e5 + 95000.0, rel=REL)


def test_sweep_cases_in_barg_use_the_plants_atmosphere():
    from dnasim.plant.cases import apply_case, check_cases

    spec = loads(_pressure_loop('atmosphere = "0.95 bar"'), "gauge.toml").spec
    check_cases(spec, [{"src.p": "18 barg"}])
    new = apply_case(spec, {"src.p": "18 barg"})
    assert new.components[0].params["p"] == pytest.approx(18e5 + 95000.0, rel=REL)


# ------------------------------------------------------------------ names refused


@pytest.mark.parametrize(
    "text, unit, words",
    [
        ("10 ton/h", "kg/s", ["'ton'", "short_ton", "tonne", "long_ton"]),
        ("2 MBTU/h", "W", ["'MBTU'", "kBTU", "MMBTU"]),
        ("50 Mlb/h", "kg/s", ["'Mlb'", "klb"]),
        ("300 scfm", "m3/s", ["'scfm'", "reference conditions", "kg/s"]),
        ("1000 Nm3/h", "kg/s", ["normal cubic metres", "kg/s"]),
    ],
)
def test_ambiguous_names_are_refused_with_the_choices(text, unit, words):
    with pytest.raises(UnitError) as info:
        to_si(text, unit)
    msg = str(info.value)
    assert "not accepted" in msg
    for w in words:
        assert w in msg


# ------------------------------------------------------------------ unknown units


@pytest.mark.parametrize(
    "text, suggested",
    [
        ("1 barr", ["bar", "barg"]),
        ("1 KPA", ["kPa"]),
        ("1 btu", ["BTU"]),
        ("1 psg", ["psig"]),
        ("1 rmp", ["rpm"]),
        ("1 mmh2o", ["mmH2O"]),
        ("1 inh2o", ["inH2O"]),
        ("2 degf", ["degF"]),
    ],
)
def test_unknown_unit_suggests_the_closest_known_ones(text, suggested):
    with pytest.raises(UnitError) as info:
        to_si(text, "Pa")
    msg = str(info.value)
    assert "unknown unit" in msg and "did you mean" in msg
    for s in suggested:
        assert f"'{s}'" in msg
    assert "docs/plant_files.md" in msg


def test_unknown_unit_in_a_plant_file_names_file_table_key_and_suggestion():
    text = PRESSURE_LOOP.replace('p = "20 bar"', 'p = "20 barr"')
    with pytest.raises(PlantError) as info:
        loads(text, "plant.toml")
    msg = str(info.value)
    assert "plant.toml" in msg and "[components.src]" in msg and "'p'" in msg
    assert "did you mean 'bar'" in msg


@pytest.mark.parametrize(
    "text, unit, expected",
    [
        ("300 mmH2O", "Pa", 300 * 9.80665),
        ("10 inH2O", "Pa", 10 * 0.0254 * 9806.65),
        ("1480 rpm", "1/s", 1480 * 2 * 3.141592653589793 / 60),
        ("6 in", "m", 0.1524),
        ("1 BTU", "J", 1055.05585262),
        ("3.4 MMBTU/h", "W", 3.4e6 * 1055.05585262 / 3600),
        ("2 hrs", "s", 7200.0),
        ("20 minutes", "s", 1200.0),
        ("10 sec", "s", 10.0),
    ],
)
def test_engineering_units_are_read(text, unit, expected):
    assert to_si(text, unit) == pytest.approx(expected, rel=REL)


# ------------------------------------------------------------------ one number, one unit


@pytest.mark.parametrize(
    "a, b",
    [
        ("20min", "20 min"),
        ("1.5h", "1.5 h"),
        ("250ms", "250 ms"),
        ("5barg", "5 barg"),
        ("3.6t/h", "3.6 t/h"),
        ("540degC", "540 degC"),
        ("1e3s", "1e3 s"),
    ],
)
def test_a_number_directly_followed_by_its_unit_is_the_same_value(a, b):
    unit = {"h": "s", "min": "s", "ms": "s", "s": "s"}.get(b.split()[-1], None)
    unit = unit or {"barg": "Pa", "t/h": "kg/s", "degC": "K"}[b.split()[-1]]
    assert to_si(a, unit) == to_si(b, unit)


@pytest.mark.parametrize(
    "text, unit, written",
    [
        ("1h30min", "s", "'90 min'"),
        ("1 h 30 min", "s", "'90 min'"),
        ("20 min 30 s", "s", "'1230 s'"),
        ("5 ft 2 in", "m", "'62 in'"),
    ],
)
def test_a_sum_of_quantities_is_refused_with_the_value_in_one_unit(text, unit, written):
    with pytest.raises(UnitError) as info:
        to_si(text, unit)
    msg = str(info.value)
    assert "sum of" in msg and "one number and one unit" in msg and written in msg


@pytest.mark.parametrize("text", ["1:30", "01:30:00", "0:45"])
def test_a_clock_time_is_refused(text):
    with pytest.raises(UnitError, match="clock time"):
        to_si(text, "s")


@pytest.mark.parametrize(
    "text, words",
    [
        ("5 bar(g)", ["'barg'"]),
        ("5 bar g", ["'barg'"]),
        ("70 psi(g)", ["'psig'"]),
        ("5 bar(a)", ["'bar'", "'bara'"]),
    ],
)
def test_gauge_marks_after_the_unit_are_refused_with_the_spelling(text, words):
    with pytest.raises(UnitError) as info:
        to_si(text, "Pa")
    for w in words:
        assert w in str(info.value)


def test_metres_for_a_time_hint_at_minutes():
    with pytest.raises(UnitError, match="minutes are 'min'"):
        to_si("20 m", "s")


def test_plant_file_times_follow_the_same_rule():
    base = PRESSURE_LOOP
    assert loads(base.replace('t_end = "120 s"', 't_end = "2min"')).simulation.t_end == 120.0
    assert loads(base.replace('t_end = "120 s"', 't_end = "2 min"')).simulation.t_end == 120.0
    with pytest.raises(PlantError) as info:
        loads(base.replace('t_end = "120 s"', 't_end = "1 min 30 s"'), "p.toml")
    msg = str(info.value)
    assert "[simulation]" in msg and "t_end" in msg and "'90 s'" in msg
