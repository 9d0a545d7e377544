"""Physical units for plant files: parse "120 bar", check its dimension, convert to SI.

Why a small table and not pint
------------------------------
Measured on the project's venv (Python 3.11, 2 cores): ``import pint`` costs
0.25-0.28 s (``python -X importtime``) and creating a ``UnitRegistry`` another
0.14-0.26 s, so about 0.4-0.5 s before the first conversion; ``import click``
costs 0.02 s. pint is also not among the project's dependencies. Plant files need
a few dozen engineering units, so this module keeps an explicit table (about
2 ms to import) and is tested unit by unit in ``tests/test_units.py``.

Grammar of a unit expression
----------------------------
- names from the table below, optionally with an SI prefix where the unit allows
  one ("kPa", "MW", "mbar", "kJ", "mm", "ms");
- an exponent written directly after the name or with ``^``/``**``: "m2", "m3",
  "s-1", "m^2", "s**-1"; fractional exponents too: "Pa0.5", "Pa^(1/2)";
- products with ``.``, ``*``, ``·`` or a space: "W/(m2.K)", "N m";
- quotients with ``/`` (left to right: "J/kg/K" is J/(kg.K)); parentheses group;
- "1", "-" or an empty string for a dimensionless number, "%" for 1/100.

Temperatures: "degC" and "degF" standing alone are absolute temperatures and are
converted with their offset ("540 degC" is 813.15 K). Inside a compound unit
("W/(m2.degC)", "J/(kg.degC)") they mean a temperature *difference*, like pint's
``delta_degC``; write a difference on its own as "K" or "delta_degC".
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from fractions import Fraction

from dnasim.errors import DnasimError

__all__ = [
    "Unit",
    "UnitError",
    "parse_unit",
    "parse_quantity",
    "to_si",
    "convert",
    "dimension_name",
    "same_dimension",
    "known_units",
    "has_unit",
]


class UnitError(DnasimError, ValueError):
    """A unit or a quantity string cannot be read, or has the wrong dimension."""


# Dimensions are exponent vectors over (mass, length, time, temperature, amount).
_DIM_NAMES = ("kg", "m", "s", "K", "mol")
Dims = tuple[int, int, int, int, int]

_NONE: Dims = (0, 0, 0, 0, 0)
_M: Dims = (1, 0, 0, 0, 0)
_L: Dims = (0, 1, 0, 0, 0)
_T: Dims = (0, 0, 1, 0, 0)
_TH: Dims = (0, 0, 0, 1, 0)
_N: Dims = (0, 0, 0, 0, 1)


def _d(m=0, l=0, t=0, th=0, n=0) -> Dims:
    return (m, l, t, th, n)


_PRESSURE = _d(1, -1, -2)
_ENERGY = _d(1, 2, -2)
_POWER = _d(1, 2, -3)
_FORCE = _d(1, 1, -2)

# name -> (dims, scale, offset, prefixable)
_TABLE: dict[str, tuple[Dims, float, float, bool]] = {
    # dimensionless
    "1": (_NONE, 1.0, 0.0, False),
    "-": (_NONE, 1.0, 0.0, False),
    "%": (_NONE, 0.01, 0.0, False),
    "percent": (_NONE, 0.01, 0.0, False),
    "ppm": (_NONE, 1e-6, 0.0, False),
    "rad": (_NONE, 1.0, 0.0, False),
    # mass
    "kg": (_M, 1.0, 0.0, False),
    "g": (_M, 1e-3, 0.0, True),
    "t": (_M, 1e3, 0.0, False),
    "tonne": (_M, 1e3, 0.0, False),
    "lb": (_M, 0.45359237, 0.0, False),
    # length, area, volume
    "m": (_L, 1.0, 0.0, True),
    "L": (_d(0, 3), 1e-3, 0.0, True),
    "l": (_d(0, 3), 1e-3, 0.0, True),
    "ft": (_L, 0.3048, 0.0, False),
    # time
    "s": (_T, 1.0, 0.0, True),
    "min": (_T, 60.0, 0.0, False),
    "h": (_T, 3600.0, 0.0, False),
    "hr": (_T, 3600.0, 0.0, False),
    "d": (_T, 86400.0, 0.0, False),
    "day": (_T, 86400.0, 0.0, False),
    "Hz": (_d(t=-1), 1.0, 0.0, True),
    # temperature (absolute when alone; a difference inside a compound unit)
    "K": (_TH, 1.0, 0.0, False),
    "degC": (_TH, 1.0, 273.15, False),
    "°C": (_TH, 1.0, 273.15, False),
    "degF": (_TH, 5.0 / 9.0, 459.67 * 5.0 / 9.0, False),
    "°F": (_TH, 5.0 / 9.0, 459.67 * 5.0 / 9.0, False),
    "degR": (_TH, 5.0 / 9.0, 0.0, False),
    "delta_degC": (_TH, 1.0, 0.0, False),
    "delta_K": (_TH, 1.0, 0.0, False),
    "delta_degF": (_TH, 5.0 / 9.0, 0.0, False),
    # amount
    "mol": (_N, 1.0, 0.0, True),
    # pressure
    "Pa": (_PRESSURE, 1.0, 0.0, True),
    "delta_Pa": (_PRESSURE, 1.0, 0.0, False),  # a pressure difference (may be <= 0)
    "bar": (_PRESSURE, 1e5, 0.0, True),
    "bara": (_PRESSURE, 1e5, 0.0, False),
    "atm": (_PRESSURE, 101325.0, 0.0, False),
    "psi": (_PRESSURE, 6894.757293168361, 0.0, False),
    "mmHg": (_PRESSURE, 133.322387415, 0.0, False),
    "mH2O": (_PRESSURE, 9806.65, 0.0, False),
    # energy, power, force
    "J": (_ENERGY, 1.0, 0.0, True),
    "Wh": (_ENERGY, 3600.0, 0.0, True),
    "cal": (_ENERGY, 4.184, 0.0, True),
    "W": (_POWER, 1.0, 0.0, True),
    "N": (_FORCE, 1.0, 0.0, True),
}

_PREFIXES = {
    "G": 1e9,
    "M": 1e6,
    "k": 1e3,
    "h": 1e2,
    "da": 1e1,
    "d": 1e-1,
    "c": 1e-2,
    "m": 1e-3,
    "u": 1e-6,
    "µ": 1e-6,
    "μ": 1e-6,
    "n": 1e-9,
}

# Names used in error messages for common dimensions.
_DIMENSION_NAMES: dict[Dims, str] = {
    _NONE: "dimensionless",
    _M: "mass",
    _L: "length",
    _d(0, 2): "area",
    _d(0, 3): "volume",
    _T: "time",
    _TH: "temperature",
    _N: "amount of substance",
    _d(t=-1): "frequency (1/time)",
    _PRESSURE: "pressure",
    _ENERGY: "energy",
    _POWER: "power",
    _FORCE: "force",
    _d(1, 0, -1): "mass flow",
    _d(0, 3, -1): "volume flow",
    _d(0, 2, -2): "specific energy",
    _d(0, 2, -2, -1): "specific heat capacity",
    _d(1, -3): "density",
    _d(0, 3): "volume",
    _d(-1, 3): "specific volume",
    _d(1, 0, -3, -1): "heat transfer coefficient",
    _d(1, 2, -3, -1): "thermal conductance",
    _d(1, 2, -2, -1): "heat capacity",
    _d(0, 1, -1): "velocity",
    _d(1, 1, -3, -1): "thermal conductivity",
    _d(0, 0, 0, -1): "1/temperature",
    _d(0, 0, -1, -1): "1/(temperature.time)",
    _d(0, -4): "friction coefficient (1/m4)",
    (Fraction(1, 2), Fraction(1, 2), 0, 0, 0): "valve flow coefficient (kg/(s.Pa0.5))",
}


@dataclass(frozen=True)
class Unit:
    """A parsed unit: ``value_SI = value * scale + offset``; ``dims`` over (kg, m, s, K, mol)."""

    dims: Dims
    scale: float = 1.0
    offset: float = 0.0

    def __mul__(self, other: Unit) -> Unit:
        return Unit(
            tuple(a + b for a, b in zip(self.dims, other.dims, strict=True)),
            self.scale * other.scale,
        )

    def __truediv__(self, other: Unit) -> Unit:
        return Unit(
            tuple(a - b for a, b in zip(self.dims, other.dims, strict=True)),
            self.scale / other.scale,
        )

    def __pow__(self, k) -> Unit:
        try:
            scale = self.scale ** float(k)
        except OverflowError:
            scale = math.inf
        return Unit(tuple(a * k for a in self.dims), scale)

    @property
    def dimension(self) -> str:
        return dimension_name(self.dims)


def dimension_name(dims: Dims) -> str:
    """A readable name of a dimension vector: "pressure", or "kg.m-1.s-2" when it has no name."""
    name = _DIMENSION_NAMES.get(tuple(dims))
    if name is not None:
        return name
    parts = [
        f"{b}{'' if e == 1 else _exp_text(e)}" for b, e in zip(_DIM_NAMES, dims, strict=True) if e
    ]
    return ".".join(parts) or "dimensionless"


def _exp_text(e) -> str:
    e = Fraction(e)
    if e.denominator == 1:
        return str(e.numerator)
    f = float(e)
    return repr(f) if f == round(f, 6) else f"({e})"


def known_units() -> list[str]:
    """The unit names of the table (without prefixed forms)."""
    return sorted(_TABLE)


_NAME_RE = re.compile(r"mH2O|(?:delta_)?[A-Za-z°µμ%]+|1|-(?![0-9])")
_EXP_RE = re.compile(r"(?:\^|\*\*)?([+-]?[0-9]+(?:\.[0-9]+)?|\([+-]?[0-9]+/[0-9]+\))")


def _lookup(name: str, text: str) -> Unit:
    entry = _TABLE.get(name)
    if entry is not None:
        dims, scale, offset, _ = entry
        return Unit(dims, scale, offset)
    for prefix, factor in sorted(_PREFIXES.items(), key=lambda kv: -len(kv[0])):
        if name.startswith(prefix) and len(name) > len(prefix):
            base = _TABLE.get(name[len(prefix) :])
            if base is not None and base[3]:
                return Unit(base[0], base[1] * factor, 0.0)
    hint = ""
    import difflib

    close = difflib.get_close_matches(name, list(_TABLE), n=1)
    if close:
        hint = f"; did you mean {close[0]!r}?"
    raise UnitError(f"unknown unit {name!r} in {text!r}{hint}")


#: limits of the grammar: exponents up to this magnitude, parentheses this deep,
#: this many characters (longer expressions are not units, they are mistakes)
MAX_EXPONENT = 12
MAX_DEPTH = 20
MAX_LENGTH = 200


class _Parser:
    """Recursive descent over a unit expression."""

    def __init__(self, text: str):
        self.text = text
        # Spaces around operators do not matter; other spaces multiply.
        s = re.sub(r"\s*([./*·^()])\s*", r"\1", text.strip())
        s = re.sub(r"\*\*\s*", "**", s)
        self.s = s
        self.i = 0
        self.depth = 0
        self.n_atoms = 0
        self.offset_atoms: list[Unit] = []

    def error(self, why: str) -> UnitError:
        return UnitError(f"cannot read unit {self.text!r}: {why}")

    def peek(self) -> str:
        return self.s[self.i] if self.i < len(self.s) else ""

    def parse(self) -> Unit:
        if self.s in ("", "1", "-"):
            return Unit(_NONE)
        if len(self.text) > MAX_LENGTH:
            raise self.error(f"longer than {MAX_LENGTH} characters")
        u = self.expr()
        if not (math.isfinite(u.scale) and u.scale > 0):
            raise self.error("its size is out of the range of floating-point numbers")
        if self.i != len(self.s):
            raise self.error(f"unexpected {self.s[self.i :]!r}")
        if self.offset_atoms:
            if self.n_atoms == 1 and u.dims == _TH and u.scale == self.offset_atoms[0].scale:
                return self.offset_atoms[0]
        return u

    def expr(self) -> Unit:
        u = self.term()
        while True:
            c = self.peek()
            if c == "/":
                self.i += 1
                u = u / self.term()
            elif c in (".", "·") or (c == "*" and self.s[self.i : self.i + 2] != "**"):
                self.i += 1
                u = u * self.term()
            elif c == " ":
                self.i += 1
                u = u * self.term()
            else:
                return u

    def term(self) -> Unit:
        c = self.peek()
        if c == "(":
            self.depth += 1
            if self.depth > MAX_DEPTH:
                raise self.error(f"parentheses nested more than {MAX_DEPTH} deep")
            self.i += 1
            u = self.expr()
            if self.peek() != ")":
                raise self.error("missing ')'")
            self.i += 1
            self.depth -= 1
        else:
            m = _NAME_RE.match(self.s, self.i)
            if not m:
                raise self.error(f"expected a unit name at {self.s[self.i :]!r}")
            self.i = m.end()
            name = m.group(0)
            u = _lookup(name, self.text)
            self.n_atoms += 1
            if u.offset:
                self.offset_atoms.append(u)
                u = Unit(u.dims, u.scale)  # a difference inside compounds
        m = _EXP_RE.match(self.s, self.i)
        if m:
            self.i = m.end()
            try:
                k = Fraction(m.group(1).strip("()"))
            except ZeroDivisionError:
                raise self.error(f"the exponent {m.group(1)} divides by zero") from None
            if abs(k) > MAX_EXPONENT:
                raise self.error(
                    f"the exponent {m.group(1)} is out of range (at most {MAX_EXPONENT} in "
                    "magnitude)"
                )
            if k.denominator == 1:
                k = int(k)
            if k != 1:
                self.n_atoms += 1  # degC2 is not an absolute temperature
            u = u**k
        return u


_UNIT_CACHE: dict[str, Unit] = {}


def parse_unit(text: str) -> Unit:
    """Parse a unit expression such as "kJ/kg", "W/(m2.K)", "t/h", "degC"."""
    if not isinstance(text, str):
        raise UnitError(f"a unit must be a string, not {type(text).__name__}")
    u = _UNIT_CACHE.get(text)
    if u is None:
        u = _Parser(text).parse()
        _UNIT_CACHE[text] = u
    return u


_NUMBER_RE = re.compile(
    r"\s*([+-]?(?:[0-9]+(?:_[0-9]+)*(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
)


def parse_quantity(text: str) -> tuple[float, Unit]:
    """Split "120 bar" into (120.0, Unit of bar). A string with no unit is dimensionless."""
    if not isinstance(text, str):
        raise UnitError(f"expected a string like '120 bar', not {type(text).__name__}")
    m = _NUMBER_RE.match(text)
    if not m:
        raise UnitError(
            f"{text!r} does not start with a number (write e.g. '120 bar' or '540 degC')"
        )
    value = float(m.group(1).replace("_", ""))
    rest = text[m.end() :].strip()
    return value, parse_unit(rest)


def same_dimension(a: str | Unit, b: str | Unit) -> bool:
    ua = parse_unit(a) if isinstance(a, str) else a
    ub = parse_unit(b) if isinstance(b, str) else b
    return ua.dims == ub.dims


def _finite(x: float, text) -> float:
    if not math.isfinite(x):
        raise UnitError(f"{text!r} is not a finite number")
    return x


def convert(value: float, from_unit: str | Unit, to_unit: str | Unit) -> float:
    """Convert ``value`` between two units of the same dimension (offsets included)."""
    uf = parse_unit(from_unit) if isinstance(from_unit, str) else from_unit
    ut = parse_unit(to_unit) if isinstance(to_unit, str) else to_unit
    if uf.dims != ut.dims:
        raise UnitError(
            f"cannot convert {from_unit!r} ({uf.dimension}) to {to_unit!r} ({ut.dimension})"
        )
    si = value * uf.scale + uf.offset
    return (si - ut.offset) / ut.scale


def to_si(value, unit: str = "1") -> float:
    """Turn a plant-file value into a float in the SI unit ``unit``.

    ``value`` is a plain number (already in ``unit``, which is an SI unit string
    such as "Pa", "K", "kg/s", "W/(m2.K)", "1") or a string with a unit: "120 bar",
    "540 degC", "3.6 t/h", "15 min", "50 %". Raises ``UnitError`` when the string
    cannot be read, its unit has another dimension than ``unit``, or the number is
    not finite. Booleans are refused (TOML's ``true`` is not a number).
    """
    if isinstance(value, bool):
        raise UnitError(f"expected a number or a string with a unit, not the boolean {value!r}")
    target = parse_unit(unit)
    if isinstance(value, int | float):
        return _finite(float(value), value)  # a plain number is already in ``unit``
    if not isinstance(value, str):
        raise UnitError(
            f"expected a number or a string with a unit, not {type(value).__name__} {value!r}"
        )
    number, u = parse_quantity(value)
    if not has_unit(value):
        return _finite(number, value)  # "120" as a string: a number in ``unit``
    if u.dims != target.dims:
        hint = ""
        if "/" in value and re.search(r"/[^()]*[.*·]", value):
            hint = " (products after '/' need parentheses: write 'W/(m2.K)', not 'W/m2.K')"
        raise UnitError(
            f"{value!r} has the dimension of {u.dimension}, but {target.dimension} is "
            f"expected (unit {unit!r}){hint}"
        )
    si = number * u.scale + u.offset
    return _finite((si - target.offset) / target.scale, value)


def has_unit(text: str) -> bool:
    """Whether a quantity string carries a unit after its number ("120 bar": yes, "120": no)."""
    m = _NUMBER_RE.match(text)
    return bool(m and text[m.end() :].strip())


def convert_quantity(v, unit: str, difference: bool = False, lenient_difference: bool = False):
    """A number or a quantity string ("120 bar") in ``unit`` (SI), with the rules of
    temperatures: ``difference`` (a delta_K parameter): "2 K" and "2 delta_degC" are
    2 K, "2 degC" (an absolute temperature) is an error; ``lenient_difference``:
    "10 degC" may mean 10 K (a sine's amplitude next to its mean in degC).
    Raises ``UnitError``. Used by ``Param.si_value`` and the plant files alike."""
    if not isinstance(v, str) or not has_unit(v):
        return to_si(v, unit)
    number, u = parse_quantity(v)
    target = parse_unit(unit)
    if u.offset:
        absolute = number * u.scale + u.offset
        if lenient_difference:  # "10 degC" as a difference is 10 K
            return float(convert(number, Unit(u.dims, u.scale), unit))
        if target.dims != u.dims:
            hint = ""
            if target.dims == parse_unit("1/K").dims:
                hint = f"; a gain per kelvin is written '{number:g} 1/K'"
            raise UnitError(
                f"{v!r} is an absolute temperature ({absolute:g} K: degC and degF have an "
                f"offset), but {target.dimension} is expected (unit {unit!r}){hint}"
            )
        if difference:
            raise UnitError(
                f"{v!r} is an absolute temperature ({absolute:g} K), but this parameter is a "
                f"temperature difference: write '{number:g} K' or '{number:g} delta_degC'"
            )
    return to_si(v, unit)
