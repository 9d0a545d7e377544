"""`GasMixture`: an ideal-gas mixture of N2, O2, CO2, H2O and Ar (flue gas) with cp(T).

Each species' isobaric heat capacity, enthalpy and standard entropy come from the NASA
Glenn 7-coefficient polynomials (two ranges, 200 K..1000 K and 1000 K..6000 K)::

    cp_i/R_u        = a1 + a2 T + a3 T^2 + a4 T^3 + a5 T^4                     [-]
    H_i/(R_u T)     = a1 + a2 T/2 + a3 T^2/3 + a4 T^3/4 + a5 T^4/5 + a6/T      [-]
    S°_i/R_u        = a1 ln T + a2 T + a3 T^2/2 + a4 T^3/3 + a5 T^4/4 + a7     [-]

(T in K, R_u = 8.314462618 J/(mol K); S° at the standard pressure p° = 1 bar). Data:
McBride, Zehe & Gordon, NASA/TP-2002-211556, in the 7-coefficient form of Burcat's
"Third Millennium Ideal Gas and Condensed Phase Thermochemical Database" (its
200-1000-6000 K records: N2 "G 8/02", O2 "RUS 89", CO2 "L 7/88", H2O "L 8/89", Ar; the
low-range sets of O2, CO2 and H2O are also those of GRI-Mech 3.0's ``thermo30.dat``,
whose 300-5000 K N2 and Ar records are older fits not used here).
Transcribed in :data:`SPECIES` below. These 7-coefficient refits reproduce the cp of
their parent, the 9-coefficient form of NASA/TP-2002-211556, to 0.41 % or better over
200..6000 K (CO2 near 1260 K worst), and agree with JANAF and CoolProp's ideal-gas parts
to 0.4 % up to 2000 K, except H2O above 1000 K: the NASA data (Gurvich 1989) lie up to
1.1 % above JANAF and IAPWS-95's ideal-gas part at 2000 K.

The mixture, with mole fractions x_i (sum 1), molar mass M = sum x_i M_i [kg/mol] and
specific gas constant R = R_u / M [J/(kg K)], is an ideal mixture of ideal gases, so
its mass-specific polynomial coefficients are A_k = R sum_i x_i a_k,i and::

    cp(T) = A1 + A2 T + A3 T^2 + A4 T^3 + A5 T^4                           [J/(kg K)]
    h(T)  = A1 T + A2 T^2/2 + A3 T^3/3 + A4 T^4/4 + A5 T^5/5 + A6 - h0     [J/kg]
    rho   = p / (R T)                                                       [kg/m3]
    u     = h - p / rho = h - R T                                           [J/kg]
    s     = A1 ln T + A2 T + A3 T^2/2 + A4 T^3/3 + A5 T^4/4 + A7
            - R ln(p / p°) - R sum_i x_i ln x_i                             [J/(kg K)]
    drho/dp|h = 1 / (R T)                                                   [kg/(m3 Pa)]
    drho/dh|p = -rho / (cp T)                                               [kg2/(m3 J)]

**Enthalpy reference.** h is the *sensible* enthalpy: h = 0 at T_ref = 298.15 K (h0 is
the mixture's NASA enthalpy at 298.15 K; the enthalpies of formation drop out because
the composition is fixed). The entropy is absolute (third law, the NASA a7 constants)
with the ideal mixing term, at the standard pressure p° = 1e5 Pa.

**Water is vapour only.** H2O is an ideal-gas species at every temperature: condensation
below the dew point is *not* modelled (no latent heat, no liquid). :meth:`GasMixture.
dew_point` gives T_dew(p) = T_sat(x_H2O p) (IF97) so that a caller can check its
states; for the default flue gas at 1 atm T_dew = 329.6 K (56.5 °C).

**The 1000 K switch.** The published fits are continuous at 1000 K only to the digits
printed: for these five species the high-minus-low jumps at 1000 K are at most 1.7e-6 in
cp/R_u (H2O; 3e-7 relative), 9e-7 in H/(R_u T) and 1.7e-6 in S°/R_u (H2O;
:func:`switch_jumps` computes them). cp is used as published (a relative jump of 3e-7 is
far below the fits' own uncertainty, about 1e-3, and harmless to Newton's method); A6 and
A7 of the high range of the *mixture* are re-set so that h and s are continuous at
1000 K to round-off, so h(T) is continuous and strictly increasing and T(p, h) unique.

**T(p, h)** by Newton's method on h(T), started from linear interpolation in a table of
h at 20 K (below 1000 K) and 50 K (above) nodes; the node interval that holds h is a
bracket, and a Newton step that leaves it is replaced by bisection. Three to four steps
reach round-off: the iteration stops after the first step smaller than 1e-9 T, which
leaves an error of order 1e-18 T (quadratic convergence), i.e. T to an ulp or two.

**Range.** 200 K <= T <= 6000 K (the range of the fits) and p > 0. Outside,
:class:`PropertyError` naming the state and the limit. The gas is ideal (Z = 1): for the
dilute flue gas at boiler pressures (about 1 bar) the real-gas departure is well below
1 % (its water vapour at the dew point: Z = 0.995), but pure steam at 10 bar near
saturation has Z = 0.935 and CO2 at 10 bar and 300 K Z = 0.95 (CoolProp).

Use::

    from dnasim.media import GasMixture, get_medium
    gas = GasMixture("Exhaust", mole_fractions={"N2": 0.75, "O2": 0.1, "CO2": 0.05,
                                                "H2O": 0.09, "Ar": 0.01})
    gas = GasMixture("Exhaust", mass_fractions={...})
    fg = get_medium("FlueGas")                             # default composition, shared
    fg2 = get_medium("FlueGas[N2=0.72,CO2=0.13,H2O=0.11,O2=0.03,Ar=0.01]")  # mole fractions
"""

from __future__ import annotations

import bisect
import math
import re
from dataclasses import dataclass

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.media.base import Medium, _as_arrays, transport_result
from dnasim.media.errors import PropertyError
from dnasim.media.gas_transport import MixtureTransport
from dnasim.media.state import FluidState, FluidStates

#: Universal gas constant [J/(mol K)] (CODATA 2018, exact).
R_U = 8.314462618
#: Standard-state pressure of the NASA data [Pa] (s° is at 1 bar).
P_STD = 1e5
#: Temperature at which the sensible enthalpy h is zero [K].
T_REF = 298.15
#: Range of the polynomials [K]: low range T_MIN..T_MID, high range T_MID..T_MAX.
T_MIN, T_MID, T_MAX = 200.0, 1000.0, 6000.0
#: How far mole or mass fractions may sum away from 1 before it is an error [-].
SUM_TOL = 1e-6
#: ``states`` of at most this many points runs the scalar kernel per point (faster there).
_SMALL = 8


@dataclass(frozen=True)
class Species:
    """One ideal-gas species: molar mass M [kg/mol] and NASA 7-coefficient sets.

    ``low`` applies on 200..1000 K, ``high`` on 1000..6000 K; each is (a1, ..., a7)
    in the form of the module docstring (a1..a5 for cp/R_u [-, 1/K, ..., 1/K^4],
    a6 [K], a7 [-]).
    """

    M: float
    low: tuple[float, ...]
    high: tuple[float, ...]


# NASA Glenn 7-coefficient polynomials, 200-1000-6000 K (McBride, Zehe & Gordon 2002,
# NASA/TP-2002-211556, as tabulated in Burcat's database; see the module docstring).
# Molar masses [kg/mol] as in NASA/TP-2002-211556 (IUPAC atomic weights).
SPECIES: dict[str, Species] = {
    "N2": Species(
        28.0134e-3,
        low=(3.53100528e00, -1.23660988e-04, -5.02999433e-07, 2.43530612e-09,
             -1.40881235e-12, -1.04697628e03, 2.96747038e00),
        high=(2.95257637e00, 1.39690040e-03, -4.92631603e-07, 7.86010195e-11,
              -4.60755204e-15, -9.23948688e02, 5.87188762e00),
    ),
    "O2": Species(
        31.9988e-3,
        low=(3.78245636e00, -2.99673416e-03, 9.84730201e-06, -9.68129509e-09,
             3.24372837e-12, -1.06394356e03, 3.65767573e00),
        high=(3.66096065e00, 6.56365811e-04, -1.41149627e-07, 2.05797935e-11,
              -1.29913436e-15, -1.21597718e03, 3.41536279e00),
    ),
    "CO2": Species(
        44.0095e-3,
        low=(2.35677352e00, 8.98459677e-03, -7.12356269e-06, 2.45919022e-09,
             -1.43699548e-13, -4.83719697e04, 9.90105222e00),
        high=(4.63659493e00, 2.74131991e-03, -9.95828531e-07, 1.60373011e-10,
              -9.16103468e-15, -4.90249341e04, -1.93534855e00),
    ),
    "H2O": Species(
        18.01528e-3,
        low=(4.19864056e00, -2.03643410e-03, 6.52040211e-06, -5.48797062e-09,
             1.77197817e-12, -3.02937267e04, -8.49032208e-01),
        high=(2.67703787e00, 2.97318160e-03, -7.73769690e-07, 9.44336689e-11,
              -4.26900959e-15, -2.98858938e04, 6.88255571e00),
    ),
    "Ar": Species(
        39.948e-3,
        low=(2.5, 0.0, 0.0, 0.0, 0.0, -7.45375000e02, 4.37967491e00),
        high=(2.5, 0.0, 0.0, 0.0, 0.0, -7.45375000e02, 4.37967491e00),
    ),
}  # fmt: skip

#: Dry air by mole (N2 as balance), for :func:`methane_flue_gas` [-].
DRY_AIR = {"N2": 0.78080, "O2": 0.20946, "Ar": 0.00934, "CO2": 0.00040}


def methane_flue_gas(air_ratio: float = 1.15) -> dict[str, float]:
    """Mole fractions [-] of the flue gas of methane burnt completely in dry air.

    CH4 + 2 O2 -> CO2 + 2 H2O with the air ratio ``air_ratio`` = lambda [-] (>= 1):
    n_air = 2 lambda / x_O2,air moles of dry air (:data:`DRY_AIR`) per mole of CH4, so
    the products per mole CH4 are CO2 = 1 + n_air x_CO2,air, H2O = 2,
    O2 = 2 (lambda - 1), N2 = n_air x_N2,air, Ar = n_air x_Ar,air. Natural gas is
    taken as pure methane. For lambda = 1.15 (about 2.5 % O2 in the wet gas, a typical
    gas-fired boiler): N2 0.7156, H2O 0.1669, CO2 0.0838, O2 0.0250, Ar 0.0086.
    """
    lam = float(air_ratio)
    if not (1.0 <= lam < math.inf):
        raise PlantError(f"methane_flue_gas: air ratio must be finite and >= 1, got {lam}")
    n_air = 2.0 * lam / DRY_AIR["O2"]
    n = {
        "N2": n_air * DRY_AIR["N2"],
        "O2": 2.0 * (lam - 1.0),
        "CO2": 1.0 + n_air * DRY_AIR["CO2"],
        "H2O": 2.0,
        "Ar": n_air * DRY_AIR["Ar"],
    }
    tot = sum(n.values())
    return {k: v / tot for k, v in n.items()}


#: Composition of ``get_medium("FlueGas")``: methane in dry air at lambda = 1.15.
FLUE_GAS_DEFAULT = methane_flue_gas(1.15)

_SPECIES_KEYS = {k.lower(): k for k in SPECIES}


def _poly_sets(x: dict[str, float]) -> tuple[np.ndarray, float]:
    """Mixture coefficients (2 x 7, mole-fraction weighted a_k, in units of R_u) and M."""
    a = np.zeros((2, 7))
    M = 0.0
    for k, xi in x.items():
        sp = SPECIES[k]
        a[0] += xi * np.asarray(sp.low)
        a[1] += xi * np.asarray(sp.high)
        M += xi * sp.M
    return a, M


def _H_over_R(a, T: float) -> float:
    """H/R_u [K] of a coefficient set a at T [K]."""
    return T * (a[0] + T * (a[1] / 2 + T * (a[2] / 3 + T * (a[3] / 4 + T * a[4] / 5)))) + a[5]


def _S_over_R(a, T: float) -> float:
    """S°/R_u [-] of a coefficient set a at T [K]."""
    return a[0] * math.log(T) + T * (a[1] + T * (a[2] / 2 + T * (a[3] / 3 + T * a[4] / 4))) + a[6]


def _cp_over_R(a, T: float) -> float:
    """cp/R_u [-] of a coefficient set a at T [K]."""
    return a[0] + T * (a[1] + T * (a[2] + T * (a[3] + T * a[4])))


def switch_jumps() -> dict[str, tuple[float, float, float]]:
    """The published data's discontinuities at 1000 K, per species.

    Returns ``{species: (d_cp, d_H, d_S)}``: high minus low range of cp/R_u [-],
    H/(R_u T) [-] and S°/R_u [-] at T = 1000 K, as published (before the re-setting of
    A6 and A7 that :class:`GasMixture` does for the mixture).
    """
    out = {}
    for k, sp in SPECIES.items():
        lo, hi = sp.low, sp.high
        out[k] = (
            _cp_over_R(hi, T_MID) - _cp_over_R(lo, T_MID),
            (_H_over_R(hi, T_MID) - _H_over_R(lo, T_MID)) / T_MID,
            _S_over_R(hi, T_MID) - _S_over_R(lo, T_MID),
        )
    return out


def _check_fractions(name: str, fractions, kind: str) -> dict[str, float]:
    """Validated, renormalised fractions {canonical species: value}; PlantError otherwise."""
    if not isinstance(fractions, dict) or not fractions:
        raise PlantError(
            f"GasMixture {name!r}: {kind} fractions must be a non-empty mapping of species to "
            f"fractions, e.g. {{'N2': 0.79, 'O2': 0.21}}; got {fractions!r}"
        )
    out: dict[str, float] = {}
    for key, val in fractions.items():
        k = _SPECIES_KEYS.get(str(key).strip().lower())
        if k is None:
            raise PlantError(
                f"GasMixture {name!r}: unknown species {key!r} in the {kind} fractions; the "
                f"species are {', '.join(SPECIES)}"
            )
        if k in out:
            raise PlantError(f"GasMixture {name!r}: species {k!r} given twice")
        try:
            v = float(val)
        except (TypeError, ValueError):
            raise PlantError(
                f"GasMixture {name!r}: {kind} fraction of {k} must be a number, got {val!r}"
            ) from None
        if not (0.0 <= v <= 1.0):
            raise PlantError(
                f"GasMixture {name!r}: {kind} fraction of {k} must be in [0, 1], got {v!r}"
            )
        out[k] = v
    total = math.fsum(out.values())
    if not abs(total - 1.0) <= SUM_TOL:
        raise PlantError(
            f"GasMixture {name!r}: the {kind} fractions sum to {total:.9g}, not 1 (within "
            f"{SUM_TOL:g}): {out}. Give every species of the gas, with fractions that add up "
            "to 1."
        )
    return {k: v / total for k, v in out.items() if v > 0.0}


class GasMixture(Medium):
    """Ideal-gas mixture of N2, O2, CO2, H2O, Ar with NASA cp(T) (see the module docstring).

    Give exactly one of ``mole_fractions`` or ``mass_fractions`` (mappings species ->
    fraction [-]; species names N2, O2, CO2, H2O, Ar, case-insensitive; missing species
    are 0; each fraction in [0, 1], summing to 1 within 1e-6, then renormalised). With
    neither, the default flue gas :data:`FLUE_GAS_DEFAULT` is used.

    Parameters
    ----------
    name : str
        Name used in messages (``label`` is ``"<name> (NASA7)"``).
    mole_fractions, mass_fractions : dict, optional
        The composition (see above).
    cache_size : int
        Size of the (p, h) state cache, as for every :class:`Medium`.

    Attributes
    ----------
    mole_fractions, mass_fractions : dict[str, float]
        The composition [-] (species with a zero fraction left out).
    M : float
        Molar mass [kg/mol].
    R : float
        Specific gas constant R_u / M [J/(kg K)].
    T_ref : float
        298.15 K, where h = 0.
    T_min, T_max : float
        200 K and 6000 K, the range of the polynomials.
    h_min, h_max : float
        h [J/kg] at T_min and T_max: the range of ``state``.

    Raises
    ------
    dnasim.core.errors.PlantError
        Unknown species, a negative fraction or one above 1, fractions not summing to 1,
        both or a wrong kind of composition.
    """

    condensable = False

    def __init__(
        self,
        name: str = "FlueGas",
        *,
        mole_fractions: dict | None = None,
        mass_fractions: dict | None = None,
        cache_size: int = 4096,
    ) -> None:
        super().__init__(name, "NASA7", cache_size=cache_size)
        if mole_fractions is not None and mass_fractions is not None:
            raise PlantError(
                f"GasMixture {name!r}: give mole_fractions or mass_fractions, not both"
            )
        if mass_fractions is not None:
            w = _check_fractions(name, mass_fractions, "mass")
            n = {k: v / SPECIES[k].M for k, v in w.items()}
            tot = math.fsum(n.values())
            x = {k: v / tot for k, v in n.items()}
        else:
            x = _check_fractions(
                name, FLUE_GAS_DEFAULT if mole_fractions is None else mole_fractions, "mole"
            )
        a, M = _poly_sets(x)
        self.mole_fractions = x
        self.mass_fractions = {k: v * SPECIES[k].M / M for k, v in x.items()}
        self.M = M
        self.R = R = R_U / M
        self.T_ref = T_REF
        self.T_min, self.T_max = T_MIN, T_MAX
        # Continuity at 1000 K: the high range's a6 and a7 re-set from the low range.
        a[1, 5] += _H_over_R(a[0], T_MID) - _H_over_R(a[1], T_MID)
        a[1, 6] += _S_over_R(a[0], T_MID) - _S_over_R(a[1], T_MID)
        h0 = _H_over_R(a[0], T_REF)
        s_mix = -math.fsum(v * math.log(v) for v in x.values())  # [-], >= 0
        # Per branch (row 0: T < 1000 K, row 1: T >= 1000 K), mass-specific, Horner-ready:
        A = R * a  # A_k [J/(kg K) / K^(k-1)], A6 [J/kg], A7 [J/(kg K)]
        self._cp = A[:, :5].copy()
        self._hc = np.column_stack(
            [A[:, 0], A[:, 1] / 2, A[:, 2] / 3, A[:, 3] / 4, A[:, 4] / 5, A[:, 5] - R * h0]
        )
        self._sc = np.column_stack(
            [A[:, 0], A[:, 1], A[:, 2] / 2, A[:, 3] / 3, A[:, 4] / 4, A[:, 6] + R * s_mix]
        )
        self._cp_t = tuple(map(tuple, self._cp.tolist()))
        self._hc_t = tuple(map(tuple, self._hc.tolist()))
        self._sc_t = tuple(map(tuple, self._sc.tolist()))
        # Newton start table: nodes every 20 K below and 50 K above 1000 K (1000 K a node).
        Tn = np.concatenate([np.linspace(T_MIN, T_MID, 41), np.linspace(T_MID, T_MAX, 101)[1:]])
        self._T_nodes = Tn
        self._h_nodes = self._h_T(Tn)
        self._n_low = 40  # intervals 0..39 are on the low branch
        self._T_nodes_l = Tn.tolist()
        self._h_nodes_l = self._h_nodes.tolist()
        self.h_min = float(self._h_nodes[0])
        self.h_max = float(self._h_nodes[-1])

    # ------------------------------------------------------------ closed forms
    def _branch(self, T):
        return (np.asarray(T) >= T_MID).astype(np.intp)

    def _h_T(self, T, b=None):
        """h [J/kg] at T [K] (arrays); branch b (0 low, 1 high) from T unless given."""
        T = np.asarray(T, dtype=float)
        c = self._hc[self._branch(T) if b is None else b]
        c = np.moveaxis(c, -1, 0)
        return T * (c[0] + T * (c[1] + T * (c[2] + T * (c[3] + T * c[4])))) + c[5]

    def cp_T(self, T):
        """Isobaric specific heat cp [J/(kg K)] at T [K] (arrays; no range check)."""
        T = np.asarray(T, dtype=float)
        c = np.moveaxis(self._cp[self._branch(T)], -1, 0)
        return c[0] + T * (c[1] + T * (c[2] + T * (c[3] + T * c[4])))

    def h_T(self, T):
        """Sensible specific enthalpy h [J/kg] at T [K] (arrays; no range check)."""
        return self._h_T(T)

    def s_pT(self, p, T):
        """Specific entropy s [J/(kg K)] at p [Pa] and T [K] (arrays; no range check)."""
        p, T = _as_arrays(p, T)
        c = np.moveaxis(self._sc[self._branch(T)], -1, 0)
        return (
            c[0] * np.log(T)
            + T * (c[1] + T * (c[2] + T * (c[3] + T * c[4])))
            + c[5]
            - self.R * np.log(p / P_STD)
        )

    def dew_point(self, p):
        """Dew-point temperature [K] at p [Pa]: T_sat(x_H2O p) by IF97 (arrays).

        NaN where the mixture has no water or its partial pressure is below the triple
        point (611.213 Pa). Below this temperature real flue gas condenses water, which
        this medium does not model.
        """
        from dnasim.media import if97_kernel as K

        pw = np.asarray(p, dtype=float) * self.mole_fractions.get("H2O", 0.0)
        with np.errstate(invalid="ignore"):
            T = K.T_sat(np.where(pw >= K.P_MIN, pw, np.nan))
        return T[()] if T.ndim == 0 else T

    # -------------------------------------------------------------- T(p, h)
    def _range_reason(self, h: float) -> str:
        if h < self.h_min:
            return (
                f"T would be below {T_MIN:g} K, the lower limit of the NASA polynomials "
                f"(h({T_MIN:g} K) = {self.h_min:.9g} J/kg)"
            )
        return (
            f"T would be above {T_MAX:g} K, the upper limit of the NASA polynomials "
            f"(h({T_MAX:g} K) = {self.h_max:.9g} J/kg)"
        )

    def _T_scalar(self, p: float, h: float) -> tuple[float, int]:
        """T [K] and branch at h [J/kg] (checked in range): safeguarded Newton, floats."""
        hn = self._h_nodes_l
        Tn = self._T_nodes_l
        k = bisect.bisect_right(hn, h) - 1
        if k < 0 or k >= len(hn) - 1:
            if h == hn[-1]:
                return Tn[-1], 1
            raise PropertyError(self.label, p, h, "state", self._range_reason(h))
        b = 0 if k < self._n_low else 1
        lo, hi = Tn[k], Tn[k + 1]
        hlo, hhi = hn[k], hn[k + 1]
        T = lo + (hi - lo) * (h - hlo) / (hhi - hlo)
        c0, c1, c2, c3, c4, c5 = self._hc_t[b]
        d0, d1, d2, d3, d4 = self._cp_t[b]
        for _ in range(50):
            r = T * (c0 + T * (c1 + T * (c2 + T * (c3 + T * c4)))) + c5 - h
            if r > 0.0:
                hi = T
            elif r < 0.0:
                lo = T
            else:
                return T, b
            cp = d0 + T * (d1 + T * (d2 + T * (d3 + T * d4)))
            Tn1 = T - r / cp
            if not (lo <= Tn1 <= hi):
                Tn1 = 0.5 * (lo + hi)
            elif abs(Tn1 - T) <= 1e-9 * T:  # quadratic convergence: Tn1 is right to ~1e-18
                return Tn1, b
            T = Tn1
        return T, b  # pragma: no cover - the bracket halves at worst, 50 steps reach eps

    def _compute_state(self, p: float, h: float) -> FluidState:
        T, b = self._T_scalar(p, h)
        d0, d1, d2, d3, d4 = self._cp_t[b]
        cp = d0 + T * (d1 + T * (d2 + T * (d3 + T * d4)))
        e0, e1, e2, e3, e4, e5 = self._sc_t[b]
        R = self.R
        s = e0 * math.log(T) + T * (e1 + T * (e2 + T * (e3 + T * e4))) + e5
        s -= R * math.log(p / P_STD)
        rho = p / (R * T)
        return FluidState(p, h, T, rho, h - p / rho, s, cp, -1.0, 1.0 / (R * T), -rho / (cp * T))

    def T_ph(self, p, h, *, check: bool = True):
        """Temperature [K] at p [Pa] and h [J/kg] (arrays, vectorised Newton); see states."""
        p, h = _as_arrays(p, h)
        T, _, ok = self._T_arrays(p, h, check)
        return T

    def _T_arrays(self, p, h, check):
        hn = self._h_nodes
        Tn = self._T_nodes
        ok = (p > 0.0) & (p < math.inf) & (h >= hn[0]) & (h <= hn[-1])
        if not ok.all():
            if check:
                i = int(np.flatnonzero(~ok.ravel())[0])
                pi, hi = float(p.flat[i]), float(h.flat[i])
                reason = (
                    "pressure must be finite and > 0"
                    if not (0.0 < pi < math.inf)
                    else "enthalpy must be finite"
                    if not math.isfinite(hi)
                    else self._range_reason(hi)
                )
                raise PropertyError(self.label, pi, hi, "state", reason)
            h = np.where(ok, h, hn[0])
        k = np.clip(np.searchsorted(hn, h, side="right") - 1, 0, hn.size - 2)
        b = (k >= self._n_low).astype(np.intp)
        lo, hi = Tn[k], Tn[k + 1]
        hlo, hhi = hn[k], hn[k + 1]
        T = lo + (hi - lo) * (h - hlo) / (hhi - hlo)
        c = np.moveaxis(self._hc[b], -1, 0)
        d = np.moveaxis(self._cp[b], -1, 0)
        conv = np.zeros(T.shape, dtype=bool)
        for _ in range(50):
            r = T * (c[0] + T * (c[1] + T * (c[2] + T * (c[3] + T * c[4])))) + c[5] - h
            hi = np.where(r > 0.0, T, hi)
            lo = np.where(r < 0.0, T, lo)
            cp = d[0] + T * (d[1] + T * (d[2] + T * (d[3] + T * d[4])))
            Tn1 = T - r / cp
            inside = (Tn1 >= lo) & (Tn1 <= hi)
            Tn1 = np.where(inside, Tn1, 0.5 * (lo + hi))
            # a Newton step below 1e-9 T leaves an error of order 1e-18 T (quadratic
            # convergence): that step is the last one
            small = inside & (np.abs(Tn1 - T) <= 1e-9 * T)
            T = np.where(conv, T, Tn1)
            conv |= small
            if conv.all():
                break
        if not ok.all():
            T = np.where(ok, T, np.nan)
        return T, b, ok

    def states(self, p, h, *, check: bool = True) -> FluidStates:
        """Vectorised :meth:`state` (numpy; one Newton iteration loop for all points).

        A state with p not finite and > 0, or h outside [h_min, h_max] (T outside
        200..6000 K), raises :class:`PropertyError` naming the state and the limit
        (``check=True``) or gets ``ok = False`` and NaN fields.
        """
        p, h = _as_arrays(p, h)
        if p.size <= _SMALL:
            return self._states_small(p, h, check)
        T, b, ok = self._T_arrays(p, h, check)
        R = self.R
        d = np.moveaxis(self._cp[b], -1, 0)
        e = np.moveaxis(self._sc[b], -1, 0)
        cp = d[0] + T * (d[1] + T * (d[2] + T * (d[3] + T * d[4])))
        with np.errstate(invalid="ignore", divide="ignore"):
            s = e[0] * np.log(T) + T * (e[1] + T * (e[2] + T * (e[3] + T * e[4]))) + e[5]
            s = s - R * np.log(p / P_STD)
            rho = p / (R * T)
            u = h - p / rho
        self.n_evaluations += p.size
        return FluidStates(
            p,
            h,
            T,
            rho,
            u,
            s,
            cp,
            np.full(p.shape, np.nan),
            1.0 / (R * T),
            -rho / (cp * T),
            np.zeros(p.shape, dtype=np.int8),
            ok,
        )

    def _states_small(self, p, h, check: bool) -> FluidStates:
        """:meth:`states` for a few points: the scalar kernel per point (no numpy loop)."""
        n = p.size
        f = np.full((7, n), np.nan)
        ok = np.ones(n, dtype=bool)
        for i in range(n):
            pi, hi = float(p.flat[i]), float(h.flat[i])
            try:
                if not (0.0 < pi < math.inf):
                    raise PropertyError(
                        self.label, pi, hi, "state", "pressure must be finite and > 0"
                    )
                if not math.isfinite(hi):
                    raise PropertyError(self.label, pi, hi, "state", "enthalpy must be finite")
                st = self._compute_state(pi, hi)
            except PropertyError:
                if check:
                    raise
                ok[i] = False
                continue
            f[:, i] = (st.T, st.rho, st.u, st.s, st.cp, st.drho_dp_h, st.drho_dh_p)
        self.n_evaluations += n
        sh = p.shape
        T, rho, u, s, cp, d_p, d_h = (a.reshape(sh) for a in f)
        nan = np.full(sh, np.nan)
        return FluidStates(
            p, h, T, rho, u, s, cp, nan, d_p, d_h, np.zeros(sh, dtype=np.int8), ok.reshape(sh)
        )

    def transport(self, p, h, *, check: bool = True) -> dict:
        """Viscosity, conductivity, cp and Pr at (p [Pa], h [J/kg]) (see
        :meth:`Medium.transport`): T(p, h) of this medium, then the dilute-gas species
        values mixed by Wilke's rule (viscosity) and Wassiljewa/Mason-Saxena
        (conductivity), :mod:`dnasim.media.gas_transport`; cp(T) of this medium's
        NASA polynomials. Independent of p (dilute gas). A state outside 200..6000 K
        raises :class:`PropertyError` (or gets NaN with ``check=False``)."""
        p, h = _as_arrays(p, h)
        model = getattr(self, "_transport_model", None)
        if model is None:
            model = self._transport_model = MixtureTransport(self.mole_fractions)
        pf, hf = p.ravel(), h.ravel()
        if p.size <= _SMALL:  # a few points: the scalar kernels (no numpy loop)
            n = p.size
            mu, k, cp = np.empty(n), np.empty(n), np.empty(n)
            ok = np.ones(n, dtype=bool)
            for i in range(n):
                pi, hi = float(pf[i]), float(hf[i])
                if not (0.0 < pi < math.inf and self.h_min <= hi <= self.h_max):
                    ok[i] = False
                    mu[i] = k[i] = cp[i] = math.nan
                    continue
                T, b = self._T_scalar(pi, hi)
                mu[i], k[i] = model.scalar(T)
                d0, d1, d2, d3, d4 = self._cp_t[b]
                cp[i] = d0 + T * (d1 + T * (d2 + T * (d3 + T * d4)))
        else:
            T, _, ok = self._T_arrays(p, h, False)
            ok = ok.ravel()
            Tf = np.where(ok, T.ravel(), T_REF)
            mu, k = model(Tf)
            cp = self.cp_T(Tf)

        def reason(i):
            if not (0.0 < pf[i] < math.inf):
                return "pressure must be finite and > 0"
            if not math.isfinite(hf[i]):
                return "enthalpy must be finite"
            return self._range_reason(float(hf[i]))

        return transport_result(self.label, p, h, mu, k, cp, ~ok, reason, check)

    def _compute_h_pT(self, p: float, T: float) -> float:
        if not (T_MIN <= T <= T_MAX):
            raise PropertyError(
                self.label,
                p,
                math.nan,
                "h_pT",
                f"T outside {T_MIN:g} K..{T_MAX:g} K, the range of the NASA polynomials",
                T=T,
            )
        c0, c1, c2, c3, c4, c5 = self._hc_t[0 if T < T_MID else 1]
        return T * (c0 + T * (c1 + T * (c2 + T * (c3 + T * c4)))) + c5


# ------------------------------------------------------------------ names
_NAME_RE = re.compile(r"^\s*FlueGas\s*(?:\[(?P<body>[^\]]*)\])?\s*$", re.IGNORECASE)


def is_gas_mixture_name(name: str) -> bool:
    """True for ``"FlueGas"`` and ``"FlueGas[N2=0.72,CO2=0.13,...]"`` (any case)."""
    return bool(_NAME_RE.match(name))


def gas_mixture_from_name(name: str) -> GasMixture:
    """The mixture named ``"FlueGas"`` (default composition) or ``"FlueGas[N2=..,...]"``.

    In brackets, comma-separated ``species=mole fraction`` pairs (N2, O2, CO2, H2O, Ar;
    missing ones are 0), summing to 1 within 1e-6. The medium's name is the canonical
    spelling ``"FlueGas[N2=0.72,O2=0.03,CO2=0.13,H2O=0.11,Ar=0.01]"`` (species in that
    order, fractions as given), so equal compositions share one instance in
    :func:`~dnasim.media.get_medium`.

    Raises
    ------
    dnasim.core.errors.PlantError
        For a malformed name or composition.
    """
    m = _NAME_RE.match(name)
    if m is None:
        raise PlantError(f"{name!r} is not a gas-mixture name: use 'FlueGas' or 'FlueGas[N2=...]'")
    body = m.group("body")
    if body is None:
        return GasMixture("FlueGas")
    fr: dict[str, str] = {}
    for part in body.split(","):
        if not part.strip():
            continue
        key, sep, val = part.partition("=")
        if not sep:
            raise PlantError(
                f"gas mixture {name!r}: {part.strip()!r} is not 'species=mole fraction' "
                "(e.g. 'FlueGas[N2=0.72,CO2=0.13,H2O=0.11,O2=0.03,Ar=0.01]')"
            )
        fr[key.strip()] = val.strip()
    x = _check_fractions(name, fr, "mole")
    given = {_SPECIES_KEYS[k.lower()]: float(v) for k, v in fr.items()}
    canon = "FlueGas[" + ",".join(f"{k}={given[k]!r}" for k in SPECIES if k in x) + "]"
    return GasMixture(canon, mole_fractions={k: given[k] for k in x})
