"""Thermal properties of boiler steels and copper: lambda(T), c(T), rho, by name.

Source of every number: Incropera, DeWitt, Bergman & Lavine, "Fundamentals of Heat and
Mass Transfer", 6th ed. (Wiley 2007), Table A.1 ("Thermophysical properties of selected
metallic solids"; its data are from Touloukian et al., TPRC Data Series, and the ASM
Metals Handbook). rho at 300 K; lambda [W/(m K)] and c [J/(kg K)] at the tabulated
temperatures, interpolated linearly in T, and held constant beyond the first and last
temperature (below 300 K the room-temperature value; no boiler wall is above 1000 K).

The boiler-steel names are mapped to the nearest composition row of the table:

* ``P235GH``, ``SA-210``, ``carbon steel`` -> "carbon-silicon steel
  (Mn <= 1 %, 0.1 % < Si <= 0.6 %)";
* ``16Mo3`` -> "chromium (low) steel, 1/2 Cr-1/4 Mo-Si" (a C-Mo steel: the nearest
  low-alloy row; Incropera has no C-1/2 Mo row);
* ``13CrMo4-5``, ``T12``, ``P12`` -> "chromium (low) steel, 1 Cr-1/2 Mo";
* ``304``, ``304H``, ``316``, ``316H``, ``347``, ``TP347H`` -> the AISI rows;
* ``copper`` -> pure copper.

10CrMo9-10 (T22/P22) and X10CrMoVNb9-1 (P91) have no row in that table and are not
given here (asking for them raises ``KeyError`` saying so): their lambda (about 36 and
26 W/(m K) at 20 degC) differs from the 1 Cr-1/2 Mo row by 15 to 40 %, so a
substitute would be wrong; EN 10216-2 / ASME II-D Table TCD values should be added.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_SOURCE = "Incropera et al., Fundamentals of Heat and Mass Transfer, 6th ed., Table A.1"


@dataclass(frozen=True)
class Metal:
    """A metal's tabulated properties (see the module docstring).

    Attributes: ``name``, ``row`` (the source's row), ``source``, ``rho`` [kg/m3],
    ``T`` [K], ``lam`` [W/(m K)] and ``c`` [J/(kg K)] at ``T``.
    """

    name: str
    row: str
    rho: float
    T: tuple
    lam: tuple
    c: tuple
    source: str = _SOURCE

    def conductivity(self, T):
        """lambda(T) [W/(m K)] at T [K] (linear interpolation, constant beyond the table)."""
        return np.interp(np.asarray(T, dtype=float), self.T, self.lam)

    def heat_capacity(self, T):
        """c(T) [J/(kg K)] at T [K] (linear interpolation, constant beyond the table)."""
        return np.interp(np.asarray(T, dtype=float), self.T, self.c)


_T5 = (300.0, 400.0, 600.0, 800.0, 1000.0)
_ROWS = {
    "carbon-silicon steel (Mn <= 1 %, 0.1 % < Si <= 0.6 %)": (
        7817.0, _T5, (51.9, 49.8, 44.0, 37.4, 29.3), (446.0, 501.0, 582.0, 699.0, 971.0)),
    "plain carbon steel (Mn <= 1 %, Si <= 0.1 %)": (
        7854.0, _T5, (60.5, 56.7, 48.0, 39.2, 30.0), (434.0, 487.0, 559.0, 685.0, 1169.0)),
    "chromium (low) steel, 1/2 Cr-1/4 Mo-Si": (
        7822.0, _T5, (37.7, 38.2, 36.7, 33.3, 26.9), (444.0, 492.0, 575.0, 688.0, 969.0)),
    "chromium (low) steel, 1 Cr-1/2 Mo": (
        7858.0, _T5, (42.3, 42.0, 39.1, 34.5, 27.4), (442.0, 492.0, 575.0, 688.0, 969.0)),
    "stainless steel, AISI 304": (
        7900.0, (100.0, 200.0, 300.0, 400.0, 600.0, 800.0, 1000.0, 1200.0, 1500.0),
        (9.2, 12.6, 14.9, 16.6, 19.8, 22.6, 25.4, 28.0, 31.7),
        (272.0, 402.0, 477.0, 515.0, 557.0, 582.0, 611.0, 640.0, 682.0)),
    "stainless steel, AISI 316": (
        8238.0, _T5, (13.4, 15.2, 18.3, 21.3, 24.2), (468.0, 504.0, 550.0, 576.0, 602.0)),
    "stainless steel, AISI 347": (
        7978.0, _T5, (14.2, 15.8, 18.9, 21.9, 24.7), (480.0, 513.0, 559.0, 585.0, 606.0)),
    "copper, pure": (
        8933.0, (100.0, 200.0, 300.0, 400.0, 600.0, 800.0, 1000.0, 1200.0),
        (482.0, 413.0, 401.0, 393.0, 379.0, 366.0, 352.0, 339.0),
        (252.0, 356.0, 385.0, 397.0, 417.0, 433.0, 451.0, 480.0)),
}  # fmt: skip

_NAMES = {
    "P235GH": "carbon-silicon steel (Mn <= 1 %, 0.1 % < Si <= 0.6 %)",
    "SA-210": "carbon-silicon steel (Mn <= 1 %, 0.1 % < Si <= 0.6 %)",
    "carbon steel": "carbon-silicon steel (Mn <= 1 %, 0.1 % < Si <= 0.6 %)",
    "plain carbon steel": "plain carbon steel (Mn <= 1 %, Si <= 0.1 %)",
    "16Mo3": "chromium (low) steel, 1/2 Cr-1/4 Mo-Si",
    "13CrMo4-5": "chromium (low) steel, 1 Cr-1/2 Mo",
    "T12": "chromium (low) steel, 1 Cr-1/2 Mo",
    "P12": "chromium (low) steel, 1 Cr-1/2 Mo",
    "304": "stainless steel, AISI 304",
    "304H": "stainless steel, AISI 304",
    "316": "stainless steel, AISI 316",
    "316H": "stainless steel, AISI 316",
    "347": "stainless steel, AISI 347",
    "TP347H": "stainless steel, AISI 347",
    "copper": "copper, pure",
}
_MISSING = {"10CrMo9-10", "T22", "P22", "X10CrMoVNb9-1", "T91", "P91"}


def _key(name: str) -> str:
    return name.strip().lower().replace("_", " ")


_LOOKUP = {_key(k): k for k in _NAMES}


def metal_names() -> tuple[str, ...]:
    """The names :func:`metal` knows."""
    return tuple(_NAMES)


def metal(name: str) -> Metal:
    """The :class:`Metal` of a name (case, '_' and spaces at the ends do not matter).

    Raises ``KeyError`` naming the known names (and saying why T22/P91 are missing).
    """
    canon = _LOOKUP.get(_key(name))
    if canon is None:
        missing = {_key(m) for m in _MISSING}
        why = (
            " (2 1/4 Cr-1 Mo and 9 Cr-1 Mo-V steels: no tabulated source here yet)"
            if _key(name) in missing
            else ""
        )
        raise KeyError(f"no metal {name!r}{why}; known: {', '.join(_NAMES)}")
    row = _NAMES[canon]
    rho, T, lam, c = _ROWS[row]
    return Metal(canon, row, rho, T, lam, c)
