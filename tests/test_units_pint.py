"""Every unit of ``dnasim.core.units`` against pint, the well-kept unit library (a test
dependency only: dnasim keeps its own small table, see the module docstring).

For each name of the table: the SI factor (the size of one unit in SI), the offset
(the SI value of the unit's zero: 273.15 K for degC, the atmosphere for barg) and
the dimension must equal pint's.

Tolerance 1e-12 relative: both sides are exact decimal definitions (the 1959 foot
and pound, g_0 = 9.80665 m/s2, the IT calorie 4.1868 J, ...) multiplied out in
double precision in different orders, which differ by a few ulps (1e-16 each); a
wrong digit in a definition is at least 1e-10 off, and the closest real mix-ups are
far larger (the ISO against the IT BTU: 1.4e-7; the US against the EC therm: 2.4e-4;
the thermochemical against the IT calorie: 6.7e-4; rpm read as rev/s: 6.3).
"""

from __future__ import annotations

import pint
import pytest

from dnasim.core import units
from dnasim.core.units import STANDARD_ATMOSPHERE, convert, parse_unit, to_si

REL = 1e-12  # see the module docstring

#: our name -> pint's expression (a unit, or "number unit" for multiples pint has no
#: name for)
PINT = {
    # dimensionless
    "1": "dimensionless",
    "-": "dimensionless",
    "%": "percent",
    "percent": "percent",
    "ppm": "ppm",
    "rad": "radian",
    # mass
    "kg": "kilogram",
    "g": "gram",
    "t": "tonne",
    "tonne": "tonne",
    "lb": "pound",
    "lbm": "pound",
    "klb": "kilopound",
    "short_ton": "short_ton",
    "long_ton": "long_ton",
    # length, volume, volume flow
    "m": "meter",
    "L": "liter",
    "l": "liter",
    "ft": "foot",
    "in": "inch",
    "inch": "inch",
    "yd": "yard",
    "gal": "gallon",  # pint's gallon is the US liquid gallon
    "impgal": "imperial_gallon",
    "gpm": "gallon / minute",
    "cfm": "foot ** 3 / minute",  # pint reads "cfm" as centi-femto-metre
    "acfm": "foot ** 3 / minute",
    # time, frequency, angular velocity
    "s": "second",
    "sec": "second",
    "second": "second",
    "seconds": "second",
    "min": "minute",
    "mins": "minute",
    "minute": "minute",
    "minutes": "minute",
    "h": "hour",
    "hr": "hour",
    "hrs": "hour",
    "hour": "hour",
    "hours": "hour",
    "d": "day",
    "day": "day",
    "days": "day",
    "Hz": "hertz",
    "rpm": "revolution / minute",
    # temperature
    "K": "kelvin",
    "degC": "degree_Celsius",
    "°C": "degree_Celsius",
    "degF": "degree_Fahrenheit",
    "°F": "degree_Fahrenheit",
    "degR": "degree_Rankine",
    "delta_degC": "delta_degree_Celsius",
    "delta_K": "kelvin",
    "delta_degF": "delta_degree_Fahrenheit",
    # amount
    "mol": "mole",
    # pressure
    "Pa": "pascal",
    "delta_Pa": "pascal",
    "bar": "bar",
    "bara": "bar",
    "atm": "atmosphere",
    "at": "technical_atmosphere",
    "psi": "psi",
    "psia": "psi",
    "ksi": "ksi",
    "Torr": "torr",
    "torr": "torr",
    "mmHg": "millimeter_Hg",
    "inHg": "inch_Hg",
    "mH2O": "meter_H2O",
    "cmH2O": "centimeter_H2O",
    "mmH2O": "millimeter_H2O",
    "inH2O": "inch_H2O",
    "ftH2O": "foot_H2O",
    # gauge pressures: pint has none; the size is pint's absolute unit, the zero
    # pint's standard atmosphere (checked below)
    "barg": "bar",
    "mbarg": "millibar",
    "kPag": "kilopascal",
    "MPag": "megapascal",
    "psig": "psi",
    # energy
    "J": "joule",
    "Wh": "watt_hour",
    "cal": "calorie",  # thermochemical, 4.184 J, pint's "calorie" and "kcal"
    "cal_IT": "international_calorie",
    "BTU": "Btu_it",  # pint's plain "BTU" is the ISO one (1055.056 J), 1.4e-7 larger
    "Btu": "Btu_it",
    "kBTU": "1e3 Btu_it",
    "kBtu": "1e3 Btu_it",
    "MMBTU": "1e6 Btu_it",
    "MMBtu": "1e6 Btu_it",
    "therm": "1e5 Btu_it",  # pint's "therm" is 1e5 ISO BTU, the same 1.4e-7 apart
    # power, force
    "W": "watt",
    "hp": "horsepower",  # mechanical, 550 ft.lbf/s
    "PS": "metric_horsepower",
    "N": "newton",
    "kgf": "kilogram_force",
    "lbf": "pound_force",
}

#: prefixed and compound expressions engineers type, against pint
EXPRESSIONS = {
    "kPa": "kilopascal",
    "MPa": "megapascal",
    "mbar": "millibar",
    "kJ/kg": "kilojoule / kilogram",
    "kWh": "kilowatt_hour",
    "MW": "megawatt",
    "kcal": "kilocalorie",
    "kcal_IT": "kilointernational_calorie",
    "mm": "millimeter",
    "ms": "millisecond",
    "t/h": "tonne / hour",
    "lb/s": "pound / second",
    "lb/h": "pound / hour",
    "lb/hr": "pound / hour",
    "klb/h": "kilopound / hour",
    "gal/min": "gallon / minute",
    "ft3/s": "foot ** 3 / second",
    "ft3/min": "foot ** 3 / minute",
    "ft^3/min": "foot ** 3 / minute",
    "BTU/h": "Btu_it / hour",
    "MMBTU/h": "1e6 Btu_it / hour",
    "BTU/(lb.degF)": "Btu_it / pound / delta_degree_Fahrenheit",
    "BTU/(h.ft2.degF)": "Btu_it / hour / foot ** 2 / delta_degree_Fahrenheit",
    "kgf/cm2": "kilogram_force / centimeter ** 2",
    "lbf/in2": "pound_force / inch ** 2",
    "in2": "inch ** 2",
    "W/(m2.K)": "watt / meter ** 2 / kelvin",
    "J/(kg.degC)": "joule / kilogram / delta_degree_Celsius",
    "1/barg": "1 / bar",  # a gauge unit inside a compound is a difference, like degC
    "kg/(s.bar0.5)": "kilogram / second / bar ** 0.5",
}

_DIMS = ("[mass]", "[length]", "[time]", "[temperature]", "[substance]")


@pytest.fixture(scope="module")
def ureg():
    return pint.UnitRegistry()


def _pint_quantity(ureg, expr: str):
    number, _, unit = expr.partition(" ")
    try:
        return float(number) * ureg.Quantity(1.0, unit)
    except ValueError:
        return ureg.Quantity(1.0, expr)


def _pint_dims(q) -> tuple:
    dim = q.dimensionality
    return tuple(dim.get(k, 0) for k in _DIMS)


def _pint_factor_offset(ureg, name: str, expr: str) -> tuple[float, float, tuple]:
    """(factor [SI per unit], offset [SI value of the unit's zero], dims) by pint."""
    if name in ("degC", "°C", "degF", "°F"):
        zero = ureg.Quantity(0.0, expr).to("kelvin").magnitude
        delta = ureg.Quantity(1.0, "delta_" + expr).to("kelvin").magnitude
        return delta, zero, _pint_dims(ureg.Quantity(1.0, "kelvin"))
    q = _pint_quantity(ureg, expr).to_base_units()
    offset = 0.0
    if name in units._GAUGE:
        offset = ureg.Quantity(1.0, "atmosphere").to("pascal").magnitude
    return float(q.magnitude), offset, _pint_dims(q)


def test_every_unit_of_the_table_is_checked_here():
    assert set(PINT) == set(units._TABLE)


@pytest.mark.parametrize("name", sorted(PINT))
def test_factor_and_offset_equal_pints(ureg, name):
    factor, offset, dims = _pint_factor_offset(ureg, name, PINT[name])
    u = parse_unit(name)
    assert u.scale == pytest.approx(factor, rel=REL)
    assert u.offset == pytest.approx(offset, rel=REL, abs=0.0)
    assert tuple(u.dims) == dims
    # and through the public conversion: 1 unit and the unit's zero in SI
    si = "Pa" if u.gauge else {(0, 0, 0, 1, 0): "K"}.get(tuple(u.dims))
    if si is not None:
        assert convert(1.0, name, si) == pytest.approx(factor + offset, rel=REL)
        assert convert(0.0, name, si) == pytest.approx(offset, rel=REL, abs=1e-300)


@pytest.mark.parametrize("expr", sorted(EXPRESSIONS))
def test_prefixed_and_compound_units_equal_pints(ureg, expr):
    q = _pint_quantity(ureg, EXPRESSIONS[expr]).to_base_units()
    u = parse_unit(expr)
    assert u.scale == pytest.approx(float(q.magnitude), rel=REL)
    assert u.offset == 0.0 and not u.gauge
    assert tuple(float(d) for d in u.dims) == _pint_dims(q)


@pytest.mark.parametrize(
    "text, unit, pint_value, pint_unit",
    [
        ("2 MMBTU/h", "W", "2e6 Btu_it / hour", "watt"),
        ("150 klb/h", "kg/s", "150 kilopound / hour", "kilogram / second"),
        ("400 gpm", "m3/s", "400 gallon / minute", "meter ** 3 / second"),
        ("1480 rpm", "1/s", "1480 revolution / minute", "radian / second"),
        ("300 mmH2O", "Pa", "300 millimeter_H2O", "pascal"),
        ("29.92 inHg", "Pa", "29.92 inch_Hg", "pascal"),
        ("1000 degF", "K", "1000 degree_Fahrenheit", "kelvin"),
        ("671.67 degR", "K", "671.67 degree_Rankine", "kelvin"),
        ("25 delta_degF", "K", "25 delta_degree_Fahrenheit", "kelvin"),
        ("3 therm", "J", "3e5 Btu_it", "joule"),
        ("2500 hp", "W", "2500 horsepower", "watt"),
        ("12 kgf/cm2", "Pa", "12 kilogram_force / centimeter ** 2", "pascal"),
        ("8 at", "Pa", "8 technical_atmosphere", "pascal"),
    ],
)
def test_typed_values_equal_pints(ureg, text, unit, pint_value, pint_unit):
    number, _, rest = pint_value.partition(" ")
    expected = ureg.Quantity(float(number), rest).to(pint_unit).magnitude
    assert to_si(text, unit) == pytest.approx(expected, rel=REL)


def test_gauge_values_equal_pints_absolute_plus_atmosphere(ureg):
    atm = ureg.Quantity(1.0, "atmosphere").to("pascal").magnitude
    assert STANDARD_ATMOSPHERE == atm
    for text, pint_text in [("5 barg", "5 bar"), ("150 psig", "150 psi"), ("-20 kPag", "-20 kPa")]:
        number, _, unit = pint_text.partition(" ")
        expected = ureg.Quantity(float(number), unit).to("pascal").magnitude + atm
        assert to_si(text, "Pa") == pytest.approx(expected, rel=REL)
