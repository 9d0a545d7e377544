"""Single-phase heat transfer inside round tubes: Nusselt numbers Nu = h D / k [-].

Re = G D / mu [-], Pr = mu cp / k [-] at the bulk temperature; all functions vectorised.
"""

from __future__ import annotations

import numpy as np

#: fully developed laminar Nu: constant wall temperature, constant heat flux
NU_LAMINAR_T = 3.66
NU_LAMINAR_Q = 4.364
#: the VDI Heat Atlas (G1) transition: laminar up to 2300, turbulent from 1e4
RE_LAM_MAX = 2300.0
RE_TURB_MIN = 1.0e4


def nusselt_dittus_boelter(Re, Pr, heating=True):
    """Dittus-Boelter: Nu = 0.023 Re^0.8 Pr^n, n = 0.4 heating the fluid, 0.3 cooling it
    (Dittus & Boelter 1930, as in Incropera et al., "Fundamentals of Heat and Mass
    Transfer", 6th ed., eq. 8.60; McAdams' form). Valid for 0.6 <= Pr <= 160,
    Re >= 1e4, L/D >= 10, moderate property variation; up to 25 % error. Evaluated
    as written outside that range."""
    n = np.where(np.asarray(heating), 0.4, 0.3)
    return 0.023 * np.asarray(Re, dtype=float) ** 0.8 * np.asarray(Pr, dtype=float) ** n


def petukhov_friction(Re):
    """Darcy friction factor of smooth tubes by Petukhov (1970): f = (0.790 ln Re - 1.64)^-2
    (Incropera eq. 8.21), 3000 <= Re <= 5e6."""
    return (0.790 * np.log(np.asarray(Re, dtype=float)) - 1.64) ** -2


def nusselt_gnielinski(Re, Pr, f=None):
    """Gnielinski (Int. Chem. Eng. 16, 359 (1976)), fully developed turbulent flow:

        Nu = (f/8) (Re - 1000) Pr / (1 + 12.7 (f/8)^(1/2) (Pr^(2/3) - 1))

    f: the Darcy friction factor (default: smooth tubes by :func:`petukhov_friction`;
    for rough tubes pass Colebrook's, ``dnasim.correlations.friction.colebrook``).
    Valid for 3000 <= Re <= 5e6, 0.5 <= Pr <= 2000 (Incropera eq. 8.62), about 10 %
    error; below Re = 1000 it turns negative (use :func:`nusselt_tube`, which blends to
    laminar flow)."""
    Re = np.asarray(Re, dtype=float)
    Pr = np.asarray(Pr, dtype=float)
    f = petukhov_friction(Re) if f is None else np.asarray(f, dtype=float)
    f8 = f / 8.0
    return f8 * (Re - 1000.0) * Pr / (1.0 + 12.7 * np.sqrt(f8) * (Pr ** (2.0 / 3.0) - 1.0))


def _nu_turbulent_vdi(Re, Pr, d_over_L):
    """VDI Heat Atlas G1 eq. (26)-(27) (Gnielinski 1995): Re instead of Re - 1000 with
    xi = (1.8 log10 Re - 1.5)^-2 and the entrance factor 1 + (d/L)^(2/3)."""
    xi = (1.8 * np.log10(Re) - 1.5) ** -2
    x8 = xi / 8.0
    nu = x8 * Re * Pr / (1.0 + 12.7 * np.sqrt(x8) * (Pr ** (2.0 / 3.0) - 1.0))
    return nu * (1.0 + d_over_L ** (2.0 / 3.0))


def _nu_laminar_vdi(Re, Pr, d_over_L, boundary):
    """Mean laminar Nu of VDI Heat Atlas G1 (constant wall temperature, eq. (12)):
    Nu = (3.66^3 + 0.7^3 + (1.615 (Re Pr d/L)^(1/3) - 0.7)^3
          + ((2/(1 + 22 Pr))^(1/6) (Re Pr d/L)^(1/2))^3)^(1/3),
    which is 3.66 at d/L = 0 (fully developed). Constant heat flux: 4.364 (fully
    developed; the entrance effect is not included for that boundary)."""
    if boundary == "q":
        return np.full(np.broadcast(Re, Pr, d_over_L).shape, NU_LAMINAR_Q)
    gz = Re * Pr * d_over_L
    nu2 = 1.615 * gz ** (1.0 / 3.0)
    nu3 = (2.0 / (1.0 + 22.0 * Pr)) ** (1.0 / 6.0) * np.sqrt(gz)
    return (NU_LAMINAR_T**3 + 0.7**3 + (nu2 - 0.7) ** 3 + nu3**3) ** (1.0 / 3.0)


def nusselt_tube(Re, Pr, d_over_L=0.0, boundary="T"):
    """Mean Nusselt number inside a round tube from laminar to turbulent flow, VDI Heat
    Atlas (2010) chapter G1 (Gnielinski):

    * Re <= 2300: laminar (:func:`_nu_laminar_vdi`; 3.66 or 4.364 fully developed);
    * Re >= 1e4: Gnielinski's VDI form Nu = (xi/8) Re Pr / (1 + 12.7 sqrt(xi/8)
      (Pr^(2/3) - 1)) (1 + (d/L)^(2/3)), xi = (1.8 log10 Re - 1.5)^-2, valid to
      Re = 1e6, 0.1 <= Pr <= 1000;
    * in between the VDI's linear interpolation (G1 eq. (30)):
      Nu = (1 - g) Nu_lam(2300) + g Nu_turb(1e4), g = (Re - 2300)/(1e4 - 2300).

    Continuous in Re (kinks at 2300 and 1e4). d_over_L = D/L [-] (0: fully developed);
    boundary "T" (constant wall temperature) or "q" (constant heat flux). Re = 0 gives
    the laminar value. Properties at the bulk temperature (no wall-viscosity correction).
    """
    Re = np.abs(np.asarray(Re, dtype=float))
    Pr = np.asarray(Pr, dtype=float)
    dl = np.asarray(d_over_L, dtype=float)
    lam = _nu_laminar_vdi(np.minimum(Re, RE_LAM_MAX), Pr, dl, boundary)
    lam_end = _nu_laminar_vdi(RE_LAM_MAX, Pr, dl, boundary)
    turb = _nu_turbulent_vdi(np.maximum(Re, RE_TURB_MIN), Pr, dl)
    turb_start = _nu_turbulent_vdi(RE_TURB_MIN, Pr, dl)
    g = np.clip((Re - RE_LAM_MAX) / (RE_TURB_MIN - RE_LAM_MAX), 0.0, 1.0)
    trans = (1.0 - g) * lam_end + g * turb_start
    return np.where(Re <= RE_LAM_MAX, lam, np.where(Re >= RE_TURB_MIN, turb, trans))
