"""`FluidState`: every property of one (p, h) state, as plain floats."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class FluidState:
    """Thermodynamic state of a fluid fixed by pressure and specific enthalpy.

    Returned by :meth:`dnasim.media.Medium.state` and shared through the
    medium's cache between every component that asks for the same (p, h), which
    is why it is frozen.

    Attributes
    ----------
    p : float
        Pressure [Pa] (the input, unchanged).
    h : float
        Specific enthalpy [J/kg] (the input, unchanged).
    T : float
        Temperature [K]. Inside the two-phase dome: the saturation temperature.
    rho : float
        Density [kg/m3]. Inside the dome: the homogeneous mixture density
        ``1 / (x / rho_V + (1 - x) / rho_L)``.
    u : float
        Specific internal energy [J/kg], always exactly ``h - p / rho``, so that
        energy balances that combine ``u`` (storage) and ``h`` (flows) are
        consistent to rounding.
    s : float
        Specific entropy [J/(kg K)] (reference state of the backend; for the
        ideal gas ``s = 0`` at ``T_ref``, ``p_ref``).
    cp : float
        Isobaric specific heat [J/(kg K)]. Inside the dome ``math.inf`` (the
        limit of dh/dT at constant p).
    quality : float
        Vapour mass fraction x [-] inside the dome and on its boundary
        (0 <= x <= 1); ``-1.0`` outside the dome (subcooled, superheated,
        supercritical, ideal gas), as in CoolProp.
    drho_dp_h : float
        (d rho / d p) at constant h [kg/(m3 Pa)] = [s2/m2].
    drho_dh_p : float
        (d rho / d h) at constant p [kg2/(m3 J)].
    """

    p: float
    h: float
    T: float
    rho: float
    u: float
    s: float
    cp: float
    quality: float
    drho_dp_h: float
    drho_dh_p: float

    @property
    def v(self) -> float:
        """Specific volume [m3/kg]."""
        return 1.0 / self.rho

    @property
    def two_phase(self) -> bool:
        """True inside the two-phase dome or on its boundary (0 <= quality <= 1)."""
        return 0.0 <= self.quality <= 1.0


class FluidStates:
    """Arrays of states at (p, h), returned by :meth:`dnasim.media.Medium.states`.

    Every field is a float numpy array of the shape of the broadcast inputs (``region``
    int8, ``ok`` bool). Units as in :class:`FluidState`.

    Attributes
    ----------
    p, h : ndarray
        Pressure [Pa] and specific enthalpy [J/kg] (the inputs, broadcast, float).
    T : ndarray
        Temperature [K]; the saturation temperature inside the two-phase dome.
    rho : ndarray
        Density [kg/m3] (homogeneous mixture density inside the dome).
    u : ndarray
        Specific internal energy [J/kg], exactly ``h - p / rho``.
    s : ndarray
        Specific entropy [J/(kg K)].
    cp : ndarray
        Isobaric specific heat [J/(kg K)]; ``inf`` inside the dome.
    x : ndarray
        Vapour quality [-] inside the dome and on its boundary (0 <= x <= 1); NaN outside
        (note: :class:`FluidState` uses -1 there).
    drho_dp_h : ndarray
        (d rho / d p) at constant h [kg/(m3 Pa)].
    drho_dh_p : ndarray
        (d rho / d h) at constant p [kg2/(m3 J)].
    region : ndarray of int8
        IF97 region (1, 2, 3, 5; 4 = two-phase) for IF97 water; for other media 4 inside
        the dome and 0 elsewhere. 0 where not ``ok``.
    ok : ndarray of bool
        False where the state could not be evaluated (only with ``check=False``; the
        other fields are NaN there).
    """

    __slots__ = (
        "p",
        "h",
        "T",
        "rho",
        "u",
        "s",
        "cp",
        "x",
        "drho_dp_h",
        "drho_dh_p",
        "region",
        "ok",
    )

    def __init__(self, p, h, T, rho, u, s, cp, x, drho_dp_h, drho_dh_p, region, ok):
        self.p = p
        self.h = h
        self.T = T
        self.rho = rho
        self.u = u
        self.s = s
        self.cp = cp
        self.x = x
        self.drho_dp_h = drho_dp_h
        self.drho_dh_p = drho_dh_p
        self.region = region
        self.ok = ok

    @property
    def v(self):
        """Specific volume [m3/kg]."""
        return 1.0 / self.rho

    def __len__(self) -> int:
        return self.p.size

    def state(self, i) -> FluidState:
        """The ``i``-th state (flat index) as a :class:`FluidState` (quality -1 outside)."""
        q = float(self.x.flat[i])
        return FluidState(
            float(self.p.flat[i]),
            float(self.h.flat[i]),
            float(self.T.flat[i]),
            float(self.rho.flat[i]),
            float(self.u.flat[i]),
            float(self.s.flat[i]),
            float(self.cp.flat[i]),
            -1.0 if q != q else q,
            float(self.drho_dp_h.flat[i]),
            float(self.drho_dh_p.flat[i]),
        )
