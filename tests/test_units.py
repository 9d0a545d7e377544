"""dnasim.core.units: strings with units to SI, dimension checks."""

import math
import subprocess
import sys

import pytest

from dnasim.core.units import UnitError, convert, dimension_name, parse_quantity, parse_unit, to_si


@pytest.mark.parametrize(
    "text, unit, expected",
    [
        ("120 bar", "Pa", 1.2e7),
        ("540 degC", "K", 813.15),
        ("540 °C", "K", 813.15),
        ("3.6 t/h", "kg/s", 1.0),
        ("15 min", "s", 900.0),
        ("2 h", "s", 7200.0),
        ("1 d", "s", 86400.0),
        ("250 ms", "s", 0.25),
        ("2 kJ/kg", "J/kg", 2000.0),
        ("2800 kJ/kg", "J/kg", 2.8e6),
        ("50 m3", "m3", 50.0),
        ("500 L", "m3", 0.5),
        ("30 m2", "m2", 30.0),
        ("1.5 W/(m2.K)", "W/(m2.K)", 1.5),
        ("1.5 W/(m2*K)", "W/(m2.K)", 1.5),
        ("1.5 W / (m^2 K)", "W/(m2.K)", 1.5),
        ("1.5 W/m2/K", "W/(m2.K)", 1.5),
        ("1.5 W/(m2.degC)", "W/(m2.K)", 1.5),
        ("4.2 kJ/(kg.K)", "J/(kg.K)", 4200.0),
        ("50 %", "1", 0.5),
        ("50%", "1", 0.5),
        ("0.3", "1", 0.3),
        ("3 MW", "W", 3e6),
        ("12 kW/K", "W/K", 12e3),
        ("5 MJ/K", "J/K", 5e6),
        ("100 kPa", "Pa", 1e5),
        ("1 MPa", "Pa", 1e6),
        ("1 atm", "Pa", 101325.0),
        ("10 mbar", "Pa", 1000.0),
        ("2 s-1", "1/s", 2.0),
        ("2 1/min", "1/s", 2.0 / 60.0),
        ("12 mm", "m", 0.012),
        ("1 km", "m", 1000.0),
        ("750 kg/m3", "kg/m3", 750.0),
        ("1 g/s", "kg/s", 1e-3),
        ("212 degF", "K", 373.15),
        ("1e-3 kg/s", "kg/s", 1e-3),
        ("-5 K", "K", -5.0),
        ("+7.5e2 Pa", "Pa", 750.0),
        ("1_000 Pa", "Pa", 1000.0),
        ("1 kWh", "J", 3.6e6),
        ("10 delta_degC", "K", 10.0),
        ("1e-4 kg/(s.Pa0.5)", "kg/(s.Pa0.5)", 1e-4),
        ("1 kg/(s.Pa^(1/2))", "kg/(s.Pa0.5)", 1.0),
        ("1 kg/(s.bar0.5)", "kg/(s.Pa0.5)", 1e-2 / 3.1622776601683795),
        ("2 1/m4", "1/m4", 2.0),
        ("2 m-4", "1/m4", 2.0),
    ],
)
def test_to_si(text, unit, expected):
    assert to_si(text, unit) == pytest.approx(expected, rel=1e-12)


def test_plain_numbers_are_si_and_pass_through():
    assert to_si(1.2e7, "Pa") == 1.2e7
    assert to_si(813, "K") == 813.0
    assert isinstance(to_si(3, "m3"), float)


def test_string_without_unit_is_a_number_in_the_expected_unit():
    assert to_si("120", "Pa") == 120.0


def test_offset_unit_target():
    assert to_si("300 K", "degC") == pytest.approx(26.85)
    assert convert(100.0, "degC", "K") == pytest.approx(373.15)
    assert convert(373.15, "K", "degC") == pytest.approx(100.0)


@pytest.mark.parametrize(
    "text, unit, words",
    [
        ("120 bar", "K", ["pressure", "temperature"]),
        ("540 degC", "Pa", ["temperature", "pressure"]),
        ("3.6 t/h", "kg", ["mass flow", "mass"]),
        ("15 min", "m", ["time", "length"]),
        ("2 kJ/kg", "J", ["specific energy", "energy"]),
        ("50 m3", "m2", ["volume", "area"]),
        ("50 %", "Pa", ["dimensionless", "pressure"]),
        ("5 kg/s", "1", ["mass flow", "dimensionless"]),
        ("5 kg/s", "kg/(s.Pa0.5)", ["mass flow", "valve flow coefficient"]),
    ],
)
def test_wrong_dimension(text, unit, words):
    with pytest.raises(UnitError) as info:
        to_si(text, unit)
    msg = str(info.value)
    assert text in msg
    for w in words:
        assert w in msg


def test_wrong_dimension_hint_for_missing_parentheses():
    with pytest.raises(UnitError, match=r"W/\(m2\.K\)"):
        to_si("1 W/m2.K", "W/(m2.K)")


@pytest.mark.parametrize(
    "value",
    ["bar", "", "  ", "12 furlongs", "1 (m", "1 m)", "1 m^", "nan", "inf Pa", "1e999 Pa", "1 2 3"],
)
def test_unreadable_values(value):
    with pytest.raises(UnitError):
        to_si(value, "Pa")


def test_unknown_unit_suggests():
    with pytest.raises(UnitError, match="did you mean 'bar'"):
        to_si("1 barr", "Pa")


@pytest.mark.parametrize("value", [True, False, None, [1, 2], {"a": 1}, float("nan"), math.inf])
def test_non_numbers_are_refused(value):
    with pytest.raises(UnitError):
        to_si(value, "Pa")


def test_unit_error_is_a_value_error_and_a_dnasim_error():
    from dnasim.core.errors import DnasimError

    with pytest.raises(ValueError):
        to_si("1 K", "Pa")
    with pytest.raises(DnasimError):
        to_si("1 K", "Pa")


@pytest.mark.parametrize(
    "unit",
    ["Pa", "K", "kg/s", "J/kg", "m3", "m2", "W/(m2.K)", "W/K", "J/K", "1", "s", "m", "kg", "1/s"],
)
def test_every_si_parameter_unit_parses_with_scale_one(unit):
    u = parse_unit(unit)
    assert u.scale == pytest.approx(1.0) and u.offset == 0.0


def test_degc_inside_a_compound_is_a_difference():
    u = parse_unit("J/(kg.degC)")
    assert u.offset == 0.0 and u.dims == parse_unit("J/(kg.K)").dims
    assert parse_unit("degC").offset == pytest.approx(273.15)
    assert parse_unit("degC2").offset == 0.0


def test_prefix_and_name_resolution():
    assert parse_unit("min").scale == 60.0  # not milli-inch
    assert parse_unit("mm").scale == pytest.approx(1e-3)
    assert parse_unit("ms").scale == pytest.approx(1e-3)
    assert parse_unit("hPa").scale == pytest.approx(100.0)
    assert parse_unit("kg").scale == 1.0
    with pytest.raises(UnitError):
        parse_unit("kmin")  # min takes no prefix


def test_parse_quantity():
    v, u = parse_quantity("  3.6 t/h ")
    assert v == 3.6 and u.scale == pytest.approx(1000.0 / 3600.0)


def test_dimension_names():
    assert dimension_name(parse_unit("bar").dims) == "pressure"
    assert dimension_name(parse_unit("W/(m2.K)").dims) == "heat transfer coefficient"
    assert dimension_name(parse_unit("kg.m").dims) == "kg.m"


def test_import_is_light():
    """dnasim.core.units must not pull pint, matplotlib or CoolProp (start-up time of the CLI)."""
    code = (
        "import sys, dnasim.core.units; "
        "bad = [m for m in ('pint', 'matplotlib', 'CoolProp') if m in sys.modules]; "
        "print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
