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

10CrMo9-10 (T22/P22, 2 1/4 Cr-1 Mo) has no row in that table. Its conductivity is
taken from the table of the ORNL TRANSFORM library (``TRANSFORM.Media.Solids.Cr225Mo1``,
whose source is the metals design handbook OSTI 455553): 30 points from 70 degF to
1500 degF (294.26 K to 1088.71 K), 36.2 W/(m K) at room temperature, a plateau of 37.2
around 450 to 500 K, 26.5 W/(m K) at 1089 K. Its heat capacity and density are not in
that source (TRANSFORM says so and uses placeholders); here they are the 1 Cr-1/2 Mo
row of Incropera's table (the ferritic Cr-Mo rows of Table A.1 have the same c(T) to
0.5 %, and 2 1/4 Cr-1 Mo's density is 7.85 g/cm3 by the usual data sheets, 0.1 % from
that row's 7858 kg/m3): a composite, stated in ``row``.

X10CrMoVNb9-1 (T91/P91, 9 Cr-1 Mo-V) has no row in Incropera's table either. Its
numbers are those of the Woite Edelstahl data sheet for 1.4903
(https://woite-edelstahl.info/14903de.html), as ClaRa quotes them
(``ClaRa.Basics.Media.Solids.SteelX10CrMoVNb9_1``): lambda 26 W/(m K) at 20 degC
rising linearly to 30 W/(m K) at 500 degC, c = 460 J/(kg K) (one value), rho = 7760
kg/m3. Caution: public data sheets of this steel disagree (29.2 W/(m K) and 460
J/(kg K) by one, 33 and 30 W/(m K) at 20 and 500 degC and 620 J/(kg K) by another);
ASME II-D Table TCD, the source of record, is not public. A wall of P91 is known to
about 15 % in lambda and 30 % in c; give C_wall and the conductivity by hand where
that matters.
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
    #: the temperatures [K] of ``lam`` when they differ from ``T`` (the c table's)
    T_lam: tuple | None = None

    def conductivity(self, T):
        """lambda(T) [W/(m K)] at T [K] (linear interpolation, constant beyond the table)."""
        return np.interp(np.asarray(T, dtype=float), self.T_lam or self.T, self.lam)

    def heat_capacity(self, T):
        """c(T) [J/(kg K)] at T [K] (linear interpolation, constant beyond the table)."""
        return np.interp(np.asarray(T, dtype=float), self.T, self.c)

    def enthalpy(self, T):
        """e(T) = integral of c(T') dT' from 0 K to T [J/kg], with c as
        :meth:`heat_capacity` gives it (c(T_0) below the first tabulated temperature
        T_0, so e = c(T_0) T there; piecewise quadratic between the table's points;
        linear beyond the last). d e/dT = c(T) exactly: a wall storing m e(T_w) has
        the balance m c(T_w) dT_w/dt = Q."""
        T = np.asarray(T, dtype=float)
        Tk = np.asarray(self.T, dtype=float)
        ck = np.asarray(self.c, dtype=float)
        # e at the table's points: c(T_0) T_0, then the trapezoids (exact for linear c)
        steps = 0.5 * (ck[1:] + ck[:-1]) * np.diff(Tk)
        ek = ck[0] * Tk[0] + np.concatenate(([0.0], np.cumsum(steps)))
        j = np.clip(np.searchsorted(Tk, T, side="right") - 1, 0, len(Tk) - 1)
        dT = T - Tk[j]
        slope = np.append(np.diff(ck) / np.diff(Tk), 0.0)[j]
        inside = (T >= Tk[0]) & (j < len(Tk) - 1)
        below = T < Tk[0]
        e = ek[j] + ck[j] * dT + np.where(inside, 0.5 * slope * dT * dT, 0.0)
        return np.where(below, ck[0] * T, e)


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

#: 9 Cr-1 Mo-V (P91): the Woite data sheet as quoted by ClaRa (module docstring)
_P91_ROW = "9 Cr-1 Mo-V: Woite Edelstahl data sheet 1.4903 (via ClaRa)"
_P91_SOURCE = (
    "Woite Edelstahl, data sheet 1.4903 (https://woite-edelstahl.info/14903de.html), as "
    "in ClaRa's ClaRa.Basics.Media.Solids.SteelX10CrMoVNb9_1"
)
_ROWS[_P91_ROW] = (7760.0, (293.15, 773.15), (26.0, 30.0), (460.0, 460.0))

#: 2 1/4 Cr-1 Mo (T22): lambda [W/(m K)] at 70 degF to 1500 degF in steps of 50 degF
#: [K], from ORNL TRANSFORM's Cr225Mo1 (source OSTI 455553); c and rho: the 1 Cr-1/2 Mo
#: row above (module docstring)
_T22_ROW = "2 1/4 Cr-1 Mo: lambda from OSTI 455553 (ORNL TRANSFORM), c, rho of 1 Cr-1/2 Mo"
_T22_SOURCE = (
    "lambda: ORNL TRANSFORM-Library, TRANSFORM.Media.Solids.Cr225Mo1 (OSTI 455553); "
    "c, rho: " + _SOURCE + ", 1 Cr-1/2 Mo"
)
_T22_T = (
    294.26, 310.93, 338.71, 366.48, 394.26, 422.04, 449.82, 477.59, 505.37, 533.15,
    560.93, 588.71, 616.48, 644.26, 672.04, 699.82, 727.59, 755.37, 783.15, 810.93,
    838.71, 866.48, 894.26, 922.04, 949.82, 977.59, 1005.37, 1033.15, 1060.93, 1088.71,
)  # fmt: skip
_T22_LAM = (
    36.17, 36.35, 36.69, 36.86, 37.04, 37.21, 37.21, 37.21, 37.21, 37.04,
    36.86, 36.52, 36.17, 35.83, 35.48, 34.96, 34.61, 34.1, 33.58, 33.06,
    32.54, 32.02, 31.67, 31.15, 30.63, 29.77, 28.38, 27.0, 26.65, 26.48,
)  # fmt: skip

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
    "10CrMo9-10": _T22_ROW,
    "T22": _T22_ROW,
    "P22": _T22_ROW,
    "X10CrMoVNb9-1": _P91_ROW,
    "T91": _P91_ROW,
    "P91": _P91_ROW,
}
_MISSING: set = set()  # names asked for whose source is missing (none at present)


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
            " (9 Cr-1 Mo-V steel: no tabulated source here yet; public data sheets disagree "
            "by 25 %; give C_wall and the conductivity by hand)"
            if _key(name) in missing
            else ""
        )
        raise KeyError(f"no metal {name!r}{why}; known: {', '.join(_NAMES)}")
    row = _NAMES[canon]
    if row == _T22_ROW:
        rho, T, _, c = _ROWS["chromium (low) steel, 1 Cr-1/2 Mo"]
        return Metal(canon, row, rho, T, _T22_LAM, c, _T22_SOURCE, _T22_T)
    rho, T, lam, c = _ROWS[row]
    if row == _P91_ROW:
        return Metal(canon, row, rho, T, lam, c, _P91_SOURCE)
    return Metal(canon, row, rho, T, lam, c)
