"""Physical units for plant files: parse "120 bar", check its dimension, convert to SI.

Why a small table and not pint
------------------------------
Measured on the project's venv (Python 3.11, 2 cores): ``import pint`` costs
0.25-0.28 s (``python -X importtime``) and creating a ``UnitRegistry`` another
0.14-0.26 s, so about 0.4-0.5 s before the first conversion; ``import click``
costs 0.02 s. pint is also not among the project's dependencies. Plant files need
a few dozen engineering units, so this module keeps an explicit table (about
2 ms to import) and is tested unit by unit in ``tests/test_units.py``; pint is a
test dependency only, the reference the table is checked against.

Grammar of a unit expression
----------------------------
- names from the table below, optionally with an SI prefix where the unit allows
  one ("kPa", "MW", "mbar", "kJ", "mm", "ms");
- an exponent written directly after the name or with ``^``/``**``: "m2", "m3",
  "s-1", "m^2", "s**-1"; fractional exponents too: "Pa0.5", "Pa^(1/2)";
- products with ``.``, ``*``, ``·`` or a space: "W/(m2.K)", "N m";
- quotients with ``/`` (left to right: "J/kg/K" is J/(kg.K)); parentheses group;
- "1", "-" or an empty string for a dimensionless number, "%" for 1/100.

A value is one number and one unit, the space between them optional ("20min" is
"20 min", everywhere: plant files, command-line options, sweep cases, the Python
API). A sum ("1 h 30 min", "1h30min", "5 ft 2 in") or a clock time ("1:30") is
refused, with the value in one unit in the message.

Affine units: "degC" and "degF" standing alone are absolute temperatures and are
converted with their offset ("540 degC" is 813.15 K). Inside a compound unit
("W/(m2.degC)", "J/(kg.degC)") they mean a temperature *difference*, like pint's
``delta_degC``; write a difference on its own as "K" or "delta_degC". The gauge
pressures "barg", "mbarg", "kPag", "MPag" and "psig" are affine in the same way:
their zero is the atmosphere, ``STANDARD_ATMOSPHERE`` (101325 Pa) unless a plant
states its site's (``[plant] atmosphere``; the conversions take ``atmosphere``).
"5 barg" is 601325 Pa; inside a compound ("1/barg") a gauge unit is a difference;
a parameter that is a difference ("delta_Pa") refuses "2 barg" and asks for "2 bar".

Names that mean different amounts to different readers are refused with the
choices ("ton": short, long or metric; "MBTU": a thousand or a million; "scfm",
"Nm3": reference conditions). The imperial units are the international ones
(1959 yard and pound), the BTU and "cal_IT" the International Table's, "cal" the
thermochemical calorie (4.184 J), "gal" and "gpm" the US gallon, the manometer
units conventional (water 1000 kg/m3, mercury 13595.1 kg/m3, g = 9.80665 m/s2);
``tests/test_units_pint.py`` checks every factor and offset against pint's.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from fractions import Fraction

from dnasim.core.errors import DnasimError

__all__ = [
    "Unit",
    "STANDARD_ATMOSPHERE",
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

#: the standard atmosphere [Pa] (ISO 2533, CGPM 1954): the default zero of the gauge
#: units ("barg", "psig"); a plant file sets its site's with ``[plant] atmosphere``
STANDARD_ATMOSPHERE = 101325.0

#: the international foot and pound (1959) and the International Table calorie and
#: BTU: lengths, masses and energies of the imperial units below are exact multiples
_FT = 0.3048
_IN = 0.0254
_LB = 0.45359237
_GAL = 231.0 * _IN**3  # US liquid gallon, 3.785411784 L
_G0 = 9.80665  # standard gravity [m/s2]: kgf, at, mmH2O, psi (lbf)
_LBF = _LB * _G0
_PSI = _LBF / _IN**2
_BTU = 1055.05585262  # BTU (IT) = 1 lb x 1 degF at 4.1868 J/(g.K) exactly
_HP = 550.0 * _FT * _LBF  # mechanical horsepower, 550 ft.lbf/s

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
    "lb": (_M, _LB, 0.0, False),
    "lbm": (_M, _LB, 0.0, False),
    "klb": (_M, 1e3 * _LB, 0.0, False),
    "short_ton": (_M, 2000.0 * _LB, 0.0, False),
    "long_ton": (_M, 2240.0 * _LB, 0.0, False),
    # length, area, volume
    "m": (_L, 1.0, 0.0, True),
    "L": (_d(0, 3), 1e-3, 0.0, True),
    "l": (_d(0, 3), 1e-3, 0.0, True),
    "ft": (_L, _FT, 0.0, False),
    "in": (_L, _IN, 0.0, False),
    "inch": (_L, _IN, 0.0, False),
    "yd": (_L, 3.0 * _FT, 0.0, False),
    "gal": (_d(0, 3), _GAL, 0.0, False),  # US liquid gallon
    "impgal": (_d(0, 3), 4.54609e-3, 0.0, False),  # imperial gallon
    "gpm": (_d(0, 3, -1), _GAL / 60.0, 0.0, False),  # US gal/min
    "cfm": (_d(0, 3, -1), _FT**3 / 60.0, 0.0, False),  # ft3/min at the actual state
    "acfm": (_d(0, 3, -1), _FT**3 / 60.0, 0.0, False),
    # time
    "s": (_T, 1.0, 0.0, True),
    "sec": (_T, 1.0, 0.0, False),
    "second": (_T, 1.0, 0.0, False),
    "seconds": (_T, 1.0, 0.0, False),
    "min": (_T, 60.0, 0.0, False),
    "mins": (_T, 60.0, 0.0, False),
    "minute": (_T, 60.0, 0.0, False),
    "minutes": (_T, 60.0, 0.0, False),
    "h": (_T, 3600.0, 0.0, False),
    "hr": (_T, 3600.0, 0.0, False),
    "hrs": (_T, 3600.0, 0.0, False),
    "hour": (_T, 3600.0, 0.0, False),
    "hours": (_T, 3600.0, 0.0, False),
    "d": (_T, 86400.0, 0.0, False),
    "day": (_T, 86400.0, 0.0, False),
    "days": (_T, 86400.0, 0.0, False),
    "Hz": (_d(t=-1), 1.0, 0.0, True),
    # an angular velocity [rad/s] (the radian is dimensionless): 1 rpm = 2 pi/60 1/s
    "rpm": (_d(t=-1), 2.0 * math.pi / 60.0, 0.0, False),
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
    "at": (_PRESSURE, _G0 * 1e4, 0.0, False),  # technical atmosphere, 1 kgf/cm2
    "psi": (_PRESSURE, _PSI, 0.0, False),
    "psia": (_PRESSURE, _PSI, 0.0, False),
    "ksi": (_PRESSURE, 1e3 * _PSI, 0.0, False),
    "Torr": (_PRESSURE, 101325.0 / 760.0, 0.0, False),
    "torr": (_PRESSURE, 101325.0 / 760.0, 0.0, False),
    # conventional manometer units: mercury 13595.1 kg/m3, water 1000 kg/m3, at g_0
    "mmHg": (_PRESSURE, 133.322387415, 0.0, False),
    "inHg": (_PRESSURE, 25.4 * 133.322387415, 0.0, False),
    "mH2O": (_PRESSURE, 1e3 * _G0, 0.0, False),
    "cmH2O": (_PRESSURE, 10.0 * _G0, 0.0, False),
    "mmH2O": (_PRESSURE, _G0, 0.0, False),
    "inH2O": (_PRESSURE, _IN * 1e3 * _G0, 0.0, False),
    "ftH2O": (_PRESSURE, _FT * 1e3 * _G0, 0.0, False),
    # gauge pressures: against the atmosphere (``_GAUGE``; the offset here is the
    # standard atmosphere, replaced by a plant's ``[plant] atmosphere``)
    "barg": (_PRESSURE, 1e5, STANDARD_ATMOSPHERE, False),
    "mbarg": (_PRESSURE, 1e2, STANDARD_ATMOSPHERE, False),
    "kPag": (_PRESSURE, 1e3, STANDARD_ATMOSPHERE, False),
    "MPag": (_PRESSURE, 1e6, STANDARD_ATMOSPHERE, False),
    "psig": (_PRESSURE, _PSI, STANDARD_ATMOSPHERE, False),
    # energy, power, force
    "J": (_ENERGY, 1.0, 0.0, True),
    "Wh": (_ENERGY, 3600.0, 0.0, True),
    "cal": (_ENERGY, 4.184, 0.0, True),  # thermochemical calorie (pint's "calorie")
    "cal_IT": (_ENERGY, 4.1868, 0.0, True),  # International Table calorie
    "BTU": (_ENERGY, _BTU, 0.0, False),
    "Btu": (_ENERGY, _BTU, 0.0, False),
    "kBTU": (_ENERGY, 1e3 * _BTU, 0.0, False),
    "kBtu": (_ENERGY, 1e3 * _BTU, 0.0, False),
    "MMBTU": (_ENERGY, 1e6 * _BTU, 0.0, False),  # MM: a million (oil and gas usage)
    "MMBtu": (_ENERGY, 1e6 * _BTU, 0.0, False),
    "therm": (_ENERGY, 1e5 * _BTU, 0.0, False),
    "W": (_POWER, 1.0, 0.0, True),
    "hp": (_POWER, _HP, 0.0, False),  # mechanical horsepower
    "PS": (_POWER, 75.0 * _G0, 0.0, False),  # metric horsepower, 75 kgf.m/s
    "N": (_FORCE, 1.0, 0.0, True),
    "kgf": (_FORCE, _G0, 0.0, False),
    "lbf": (_FORCE, _LBF, 0.0, False),
}

#: the gauge units: their zero is the atmosphere, not vacuum (affine like degC)
_GAUGE = frozenset({"barg", "mbarg", "kPag", "MPag", "psig"})

#: how a difference of an affine unit is written: "2 barg" as a difference is "2 bar"
_DIFFERENCE_OF = {
    "degC": "K' or '{n} delta_degC",
    "°C": "K' or '{n} delta_degC",
    "degF": "delta_degF",
    "°F": "delta_degF",
    "barg": "bar",
    "mbarg": "mbar",
    "kPag": "kPa",
    "MPag": "MPa",
    "psig": "psi",
}

#: names that are refused, because they mean different amounts to different readers
_AMBIGUOUS = {
    "ton": "'ton' is 907.18 kg (US short ton), 1016.05 kg (long ton) or 1000 kg "
    "(metric) depending on the reader: write 't' or 'tonne' (1000 kg), 'short_ton' "
    "(2000 lb) or 'long_ton' (2240 lb)",
    "tons": "'tons' is ambiguous: write 't' or 'tonne' (1000 kg), 'short_ton' (2000 lb) or "
    "'long_ton' (2240 lb)",
    "MBTU": "'MBTU' is a thousand BTU to some readers (Roman M) and a million to others: "
    "write 'kBTU' (1e3 BTU) or 'MMBTU' (1e6 BTU)",
    "MBtu": "'MBtu' is a thousand BTU to some readers (Roman M) and a million to others: "
    "write 'kBtu' (1e3 BTU) or 'MMBtu' (1e6 BTU)",
    "Mlb": "'Mlb' is a thousand pounds in US boiler practice and a million to others: "
    "write 'klb' (1000 lb) or the number in 'lb'",
    "scfm": "'scfm' (standard cubic feet per minute) is an amount of gas at reference "
    "conditions that differ between standards (60 degF or 68 degF, 14.696 psia or 14.7 psia): "
    "give the mass flow ('kg/s', 'lb/h') or the volume flow at the actual state ('cfm', "
    "'ft3/min')",
    "SCFM": "'SCFM' (standard cubic feet per minute) is an amount of gas at reference "
    "conditions that differ between standards: give the mass flow ('kg/s', 'lb/h') or the "
    "volume flow at the actual state ('cfm', 'ft3/min')",
    "Nm": "'Nm3' (normal cubic metres) is an amount of gas at reference conditions that "
    "differ between standards (0 degC or 15 degC): give the mass flow ('kg/s', 't/h') or "
    "the volume at the actual state ('m3')",
    "Sm": "'Sm3' (standard cubic metres) is an amount of gas at reference conditions that "
    "differ between standards: give the mass flow ('kg/s', 't/h') or the volume at the "
    "actual state ('m3')",
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
    """A parsed unit: ``value_SI = value * scale + offset``; ``dims`` over (kg, m, s, K, mol).

    ``gauge``: a gauge pressure unit ("barg", "psig"), whose zero is the atmosphere:
    ``offset`` is then the standard atmosphere, and the conversions take the
    ``atmosphere`` of the plant instead (:meth:`zero`)."""

    dims: Dims
    scale: float = 1.0
    offset: float = 0.0
    gauge: bool = False

    def zero(self, atmosphere: float | None = None) -> float:
        """The offset [SI] of this unit: the atmosphere [Pa] for a gauge unit
        (``None``: :data:`STANDARD_ATMOSPHERE`), else ``offset``."""
        if self.gauge and atmosphere is not None:
            return float(atmosphere)
        return self.offset

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


_NAME_RE = re.compile(r"[A-Za-z]+[Hh]2[Oo]|[A-Za-z°µμ%]+(?:_[A-Za-z]+)*|1|-(?![0-9])")
_EXP_RE = re.compile(r"(?:\^|\*\*)?([+-]?[0-9]+(?:\.[0-9]+)?|\([+-]?[0-9]+/[0-9]+\))")


#: prefixed forms offered as suggestions for a misspelt unit (with the table's names)
_COMMON_PREFIXED = (
    "kPa", "MPa", "hPa", "mbar", "kJ", "MJ", "GJ", "kW", "MW", "GW", "kWh", "MWh",
    "mm", "cm", "km", "g", "mg", "ms", "kN", "kmol", "kcal", "kcal_IT", "mL", "kHz",
)  # fmt: skip


def _close_units(name: str) -> list[str]:
    """Up to three known unit names close to ``name`` ("barr" -> bar, bara, barg),
    a case-insensitive match first ("KPA" -> kPa)."""
    import difflib

    choices = list(dict.fromkeys([*_TABLE, *_COMMON_PREFIXED]))
    low = [c for c in choices if c.lower() == name.lower()]
    close = difflib.get_close_matches(name, choices, n=3, cutoff=0.6)
    lower = {c.lower(): c for c in choices}
    close += [lower[c] for c in difflib.get_close_matches(name.lower(), list(lower), n=3)]
    return list(dict.fromkeys(low + close))[:3]


def _lookup(name: str, text: str) -> Unit:
    entry = _TABLE.get(name)
    if entry is not None:
        dims, scale, offset, _ = entry
        return Unit(dims, scale, offset, name in _GAUGE)
    for prefix, factor in sorted(_PREFIXES.items(), key=lambda kv: -len(kv[0])):
        if name.startswith(prefix) and len(name) > len(prefix):
            base = _TABLE.get(name[len(prefix) :])
            if base is not None and base[3]:
                return Unit(base[0], base[1] * factor, 0.0)
    where = "" if text.strip() == name else f" in {text!r}"
    if name in _AMBIGUOUS and (name not in ("Nm", "Sm") or re.search(name + r"\^?3", text)):
        raise UnitError(f"unit {name!r}{where} is not accepted: {_AMBIGUOUS[name]}")
    close = _close_units(name)
    hint = ""
    if close:
        names = [repr(c) for c in close]
        hint = (
            "; did you mean "
            + (names[0] if len(names) == 1 else ", ".join(names[:-1]) + " or " + names[-1])
            + "?"
        )
    raise UnitError(
        f"unknown unit {name!r}{where}{hint} (the units are listed in docs/plant_files.md, "
        "'Values and units')"
    )


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
        if self.offset_atoms:  # "degC", "barg" alone: absolute; in a compound: a difference
            first = self.offset_atoms[0]
            if self.n_atoms == 1 and u.dims == first.dims and u.scale == first.scale:
                return first
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
            if u.offset or u.gauge:
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

#: "1 h 30 min", "1h30min", "5 ft 2 in": numbers each followed by a unit name
_SUM_RE = re.compile(r"\s*(?:[0-9]+(?:\.[0-9]*)?\s*[A-Za-z]+\s*){2,}")
_SUM_PART_RE = re.compile(r"([0-9]+(?:\.[0-9]*)?)\s*([A-Za-z]+)")
#: "5 bar(g)", "5 bar g", "5 bar(a)": a gauge or absolute mark after the unit
_MARKED_RE = re.compile(
    r"\s*[0-9.eE+-]+\s*(mbar|bar|kPa|MPa|psi)\s*(?:\(\s*([gGaA])\s*\)|\s([gGaA]))\s*"
)


def _written_like(text: str) -> str | None:
    """A message for a value written in a way that is not one number and one unit: a sum
    of quantities ("1h30min", "20 min 30 s"), a clock time ("1:30"), a gauge or absolute
    mark after the unit ("5 bar(g)", "5 bar g"); ``None`` for anything else."""
    if _SUM_RE.fullmatch(text):
        parts = [(float(n), _TABLE.get(name), name) for n, name in _SUM_PART_RE.findall(text)]
        entries = [e for _, e, _ in parts]
        if all(e is not None and not e[2] for e in entries) and len({e[0] for e in entries}) == 1:
            last = parts[-1]
            total = sum(n * e[1] for n, e, _ in parts) / last[1][1]
            return (
                f"{text.strip()!r} is a sum of {len(parts)} quantities; a value is one number "
                f"and one unit: write '{total:.12g} {last[2]}'"
            )
    m = re.fullmatch(r"\s*[0-9.]+\s*:\s*[0-9]+(?::[0-9]+(?:\.[0-9]*)?)?\s*", text)
    if m:
        return (
            f"{text.strip()!r} looks like a clock time (h:mm or h:mm:ss); a value is one number "
            "and one unit: write e.g. '90 min' or '5400 s'"
        )
    m = _MARKED_RE.fullmatch(text)
    if m:
        unit, mark = m.group(1), (m.group(2) or m.group(3)).lower()
        if mark == "g":
            return f"write a gauge pressure as '{unit}g' (e.g. '5 {unit}g'), not {text.strip()!r}"
        return (
            f"write an absolute pressure as '{unit}'"
            + (f" or '{unit}a'" if unit in ("bar", "psi") else "")
            + f", not {text.strip()!r}"
        )
    return None


def parse_quantity(text: str) -> tuple[float, Unit]:
    """Split "120 bar" into (120.0, Unit of bar). A string with no unit is dimensionless.

    One rule for every value (plant files, command-line options, sweep cases, the
    Python API): one number and one unit, the space between them optional ("20min" is
    "20 min"). Sums ("1 h 30 min", "1h30min") and clock times ("1:30") are refused
    with the value in one unit in the message."""
    if not isinstance(text, str):
        raise UnitError(f"expected a string like '120 bar', not {type(text).__name__}")
    m = _NUMBER_RE.match(text)
    if not m:
        raise UnitError(
            f"{text!r} does not start with a number (write e.g. '120 bar' or '540 degC')"
        )
    value = float(m.group(1).replace("_", ""))
    rest = text[m.end() :].strip()
    why = _written_like(text)
    if why is not None:
        raise UnitError(why)
    return value, parse_unit(rest)


def same_dimension(a: str | Unit, b: str | Unit) -> bool:
    ua = parse_unit(a) if isinstance(a, str) else a
    ub = parse_unit(b) if isinstance(b, str) else b
    return ua.dims == ub.dims


def _finite(x: float, text) -> float:
    if not math.isfinite(x):
        raise UnitError(f"{text!r} is not a finite number")
    return x


def convert(
    value: float, from_unit: str | Unit, to_unit: str | Unit, atmosphere: float | None = None
) -> float:
    """Convert ``value`` between two units of the same dimension (offsets included;
    gauge units against ``atmosphere`` [Pa], default :data:`STANDARD_ATMOSPHERE`)."""
    uf = parse_unit(from_unit) if isinstance(from_unit, str) else from_unit
    ut = parse_unit(to_unit) if isinstance(to_unit, str) else to_unit
    if uf.dims != ut.dims:
        raise UnitError(
            f"cannot convert {from_unit!r} ({uf.dimension}) to {to_unit!r} ({ut.dimension})"
        )
    si = value * uf.scale + uf.zero(atmosphere)
    return (si - ut.zero(atmosphere)) / ut.scale


def to_si(value, unit: str = "1", atmosphere: float | None = None) -> float:
    """Turn a plant-file value into a float in the SI unit ``unit``.

    ``value`` is a plain number (already in ``unit``, which is an SI unit string
    such as "Pa", "K", "kg/s", "W/(m2.K)", "1") or a string with a unit: "120 bar",
    "540 degC", "3.6 t/h", "15 min", "50 %", "5 barg" (a gauge pressure: against
    ``atmosphere`` [Pa], default :data:`STANDARD_ATMOSPHERE`). Raises ``UnitError``
    when the string cannot be read, its unit has another dimension than ``unit``,
    or the number is not finite. Booleans are refused (TOML's ``true`` is not a
    number).
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
        elif target.dims == _T and re.fullmatch(r"\s*\S+\s*m\s*", value):
            hint = " (minutes are 'min')"
        raise UnitError(
            f"{value!r} has the dimension of {u.dimension}, but {target.dimension} is "
            f"expected (unit {unit!r}){hint}"
        )
    si = number * u.scale + u.zero(atmosphere)
    return _finite((si - target.zero(atmosphere)) / target.scale, value)


def has_unit(text: str) -> bool:
    """Whether a quantity string carries a unit after its number ("120 bar": yes, "120": no)."""
    m = _NUMBER_RE.match(text)
    return bool(m and text[m.end() :].strip())


def _affine(u: Unit, name: str, number: float, atmosphere) -> tuple[str, str]:
    """(what the value is, how its difference is written) for a unit with an offset:
    "an absolute temperature (275.15 K: degC and degF have an offset)", "2 K' or '2
    delta_degC"; "a gauge pressure (301325 Pa absolute, ...)", "2 bar"."""
    absolute = number * u.scale + u.zero(atmosphere)
    diff = _DIFFERENCE_OF.get(name, "K").format(n=f"{number:g}")
    if u.gauge:
        atm = u.zero(atmosphere)
        return (
            f"a gauge pressure ({absolute:g} Pa absolute: gauge units are read against the "
            f"atmosphere, {atm:g} Pa)",
            f"{number:g} {diff}",
        )
    return f"an absolute temperature ({absolute:g} K: degC and degF have an offset)", (
        f"{number:g} {diff}"
    )


def convert_quantity(
    v,
    unit: str,
    difference: bool = False,
    lenient_difference: bool = False,
    atmosphere: float | None = None,
):
    """A number or a quantity string ("120 bar") in ``unit`` (SI), with the rules of
    the affine units (degC, degF, and the gauge pressures barg, psig, ...):
    ``difference`` (a delta_K or delta_Pa parameter): "2 K", "2 delta_degC", "2 bar"
    are differences, "2 degC" (an absolute temperature) and "2 barg" (a gauge
    pressure, 3.01325 bar absolute) are errors; ``lenient_difference``: "10 degC"
    may mean 10 K and "0.5 barg" 0.5 bar (a sine's amplitude next to its mean).
    Gauge pressures are read against ``atmosphere`` [Pa] (default
    :data:`STANDARD_ATMOSPHERE`; a plant file's ``[plant] atmosphere``).
    Raises ``UnitError``. Used by ``Param.si_value`` and the plant files alike."""
    if not isinstance(v, str) or not has_unit(v):
        return to_si(v, unit, atmosphere)
    number, u = parse_quantity(v)
    target = parse_unit(unit)
    if u.offset or u.gauge:
        if lenient_difference:  # "10 degC" as a difference is 10 K
            return float(convert(number, Unit(u.dims, u.scale), unit))
        name = v[_NUMBER_RE.match(v).end() :].strip()
        what, written = _affine(u, name, number, atmosphere)
        if target.dims != u.dims:
            hint = ""
            if target.dims == parse_unit("1/K").dims:
                hint = f"; a gain per kelvin is written '{number:g} 1/K'"
            elif target.dims == parse_unit("1/Pa").dims:
                hint = f"; a gain per bar is written '{number:g} 1/bar'"
            raise UnitError(
                f"{v!r} is {what}, but {target.dimension} is expected (unit {unit!r}){hint}"
            )
        if difference:
            kind = "pressure" if u.gauge else "temperature"
            raise UnitError(
                f"{v!r} is {what}, but this parameter is a {kind} difference: write '{written}'"
            )
    return to_si(v, unit, atmosphere)
