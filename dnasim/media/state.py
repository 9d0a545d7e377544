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
