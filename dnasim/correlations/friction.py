"""Friction in pipes: Darcy friction factor, signed pressure drop, two-phase flow.

All functions take and return SI numbers or numpy arrays (broadcast). Symbols:
Re = |G| D / mu (G = m / A mass flux [kg/(m2 s)]), eps = roughness / D [-],
f the Darcy friction factor [-] (dp = f L/D rho w^2 / 2).
"""

from __future__ import annotations

import numpy as np

#: [m/s2] standard gravity
G_N = 9.80665
#: Reynolds numbers where the laminar-turbulent blend starts and ends [-]
RE_LAMINAR = 2000.0
RE_TURBULENT = 4000.0


def colebrook(Re, eps):
    """Darcy friction factor [-] of the Colebrook-White equation, solved to round-off.

        1/sqrt(f) = -2 log10(eps / 3.7 + 2.51 / (Re sqrt(f)))

    Colebrook, J. Inst. Civ. Eng. 11, 133 (1939); the basis of the Moody chart.
    Solved by Newton's method on y = 1/sqrt(f) from the Swamee-Jain estimate (three
    steps, quadratic from Swamee-Jain's 1 %: the residual is below 4e-15 for
    2000 <= Re <= 1e8, 0 <= eps <= 0.05; two steps leave 2e-10).
    Valid for turbulent flow, Re > about 4000 (used here from 2000 on, inside the
    blend of :func:`darcy_friction`); Re <= 0 gives NaN.
    """
    Re, eps = np.broadcast_arrays(np.asarray(Re, dtype=float), np.asarray(eps, dtype=float))
    with np.errstate(invalid="ignore", divide="ignore"):
        a = eps / 3.7
        b = 2.51 / Re
        y = -2.0 * np.log10(a + 5.74 / Re**0.9)  # Swamee & Jain (1976)
        c = 2.0 / np.log(10.0)
        for _ in range(3):
            s = a + b * y
            g = y + 2.0 * np.log10(s)
            y = y - g / (1.0 + c * b / s)
        f = 1.0 / (y * y)
    return np.where(Re > 0.0, f, np.nan)


def haaland(Re, eps):
    """Haaland's explicit approximation of Colebrook [-] (J. Fluids Eng. 105, 89 (1983)):
    1/sqrt(f) = -1.8 log10((eps/3.7)^1.11 + 6.9/Re); within 2 % of Colebrook for
    4000 <= Re <= 1e8, eps <= 0.05 (its author's statement)."""
    Re, eps = np.asarray(Re, dtype=float), np.asarray(eps, dtype=float)
    return (-1.8 * np.log10((eps / 3.7) ** 1.11 + 6.9 / Re)) ** -2


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def darcy_friction_Re(Re, eps, turbulent=None):
    """f Re [-]: the Darcy friction factor times the Reynolds number, finite at Re = 0.

    Laminar (Hagen-Poiseuille) f Re = 64 for Re <= 2000; Colebrook (:func:`colebrook`)
    for Re >= 4000; in between a C1 blend w f_turb Re + (1 - w) 64 with the cubic
    w = 3 t^2 - 2 t^3, t = (Re - 2000)/2000 (a choice: the real transition is not a
    function of Re alone). Re < 0 is taken as |Re|. ``turbulent``: the turbulent law
    f(Re, eps) (default :func:`colebrook`; :func:`haaland` is the explicit option).
    """
    Re = np.abs(np.asarray(Re, dtype=float))
    eps = np.asarray(eps, dtype=float)
    law = colebrook if turbulent is None else turbulent
    w = _smoothstep((Re - RE_LAMINAR) / (RE_TURBULENT - RE_LAMINAR))
    Rt = np.maximum(Re, RE_LAMINAR)
    return 64.0 + w * (law(Rt, eps) * Rt - 64.0)


def darcy_friction(Re, eps):
    """Darcy friction factor f [-] from laminar (64/Re) to turbulent (Colebrook) flow,
    blended as :func:`darcy_friction_Re` says; inf at Re = 0."""
    Re = np.abs(np.asarray(Re, dtype=float))
    with np.errstate(divide="ignore"):
        return darcy_friction_Re(Re, eps) / Re


def pressure_drop(m, rho, mu, D, L, roughness=0.0):
    """Frictional pressure drop dp = p_in - p_out [Pa] of a straight round pipe, signed
    with the mass flow m [kg/s] (reverse flow gives dp < 0).

        dp = f(Re) (L / D) m |m| / (2 rho A^2) = (f Re) mu L m / (2 rho A D^2)

    (Darcy-Weisbach), with A = pi D^2 / 4, Re = |m| D / (A mu), f Re from
    :func:`darcy_friction_Re`. Written with f Re it is exact and smooth through m = 0:
    below Re = 2000 it is Hagen-Poiseuille's dp = 32 mu L w / D^2, linear in m, so no
    artificial regularisation is needed; dp(m) is C1 everywhere (the blend is C1).
    rho [kg/m3], mu [Pa s], D, L, roughness [m].
    """
    m = np.asarray(m, dtype=float)
    A = np.pi * np.asarray(D, dtype=float) ** 2 / 4.0
    Re = np.abs(m) * D / (A * mu)
    return (
        darcy_friction_Re(Re, roughness / np.asarray(D, dtype=float))
        * mu
        * L
        * m
        / (2.0 * rho * A * D * D)
    )


# ------------------------------------------------------------------ two-phase flow


def homogeneous_density(x, rho_l, rho_v):
    """Homogeneous mixture density [kg/m3]: 1 / (x / rho_v + (1 - x) / rho_l)."""
    return 1.0 / (x / rho_v + (1.0 - x) / rho_l)


def homogeneous_pressure_drop(m, x, rho_l, rho_v, mu_l, mu_v, D, L, roughness=0.0):
    """Two-phase frictional pressure drop [Pa] by the homogeneous model (signed with m):
    :func:`pressure_drop` with the homogeneous density and McAdams' mixture viscosity
    1/mu = x/mu_v + (1 - x)/mu_l (McAdams, Woods & Heroman, Trans. ASME 64, 193 (1942);
    Collier & Thome, "Convective Boiling and Condensation", 3rd ed., Sect. 2.4).
    x [-] in [0, 1] (clipped), rho [kg/m3], mu [Pa s]."""
    x = np.clip(x, 0.0, 1.0)
    mu = 1.0 / (x / mu_v + (1.0 - x) / mu_l)
    return pressure_drop(m, homogeneous_density(x, rho_l, rho_v), mu, D, L, roughness)


#: [kg/(m2 s)] mass flux below which Friedel's Fr and We are frozen (see friedel_multiplier)
G_FRIEDEL_MIN = 10.0


def friedel_multiplier(G, x, rho_l, rho_v, mu_l, mu_v, sigma, D, roughness=0.0, turbulent=None):
    """Friedel's two-phase multiplier phi_lo^2 [-] (dp_2ph = phi_lo^2 dp_lo).

        phi_lo^2 = E + 3.24 F H / (Fr^0.0454 We^0.035)
        E = (1 - x)^2 + x^2 rho_l f_vo / (rho_v f_lo)
        F = x^0.78 (1 - x)^0.224
        H = (rho_l/rho_v)^0.91 (mu_v/mu_l)^0.19 (1 - mu_v/mu_l)^0.7
        Fr = G^2 / (g D rho_h^2),  We = G^2 D / (sigma rho_h),  rho_h homogeneous

    f_lo, f_vo: Darcy factors (:func:`darcy_friction`) at Re_lo = G D/mu_l and
    Re_vo = G D/mu_v (all the flow as liquid, as vapour). Friedel, European Two-Phase
    Flow Group Meeting, Ispra, 1979, paper E2; the exponent 0.0454 as in Ghiaasiaan,
    "Two-Phase Flow, Boiling and Condensation" (2007) and Whalley (1987) (often rounded
    to 0.045). For vertical upflow and horizontal flow, mu_l/mu_v < 1000; mean error
    about 30 to 40 %. Fr and We vanish with G, and Fr^-0.0454 We^-0.035 would make the
    pressure drop's slope infinite at G = 0: G in Fr and We is replaced by
    sqrt(G^2 + G_min^2), G_min = 10 kg/(m2 s) (C-infinity; changes phi_lo^2 by less
    than 0.1 % above G = 100 kg/(m2 s)). x is clipped to [0, 1]. G [kg/(m2 s)],
    rho [kg/m3], mu [Pa s], sigma [N/m], D, roughness [m]; ``turbulent`` as in
    :func:`darcy_friction_Re`.
    """
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    G = np.abs(np.asarray(G, dtype=float))
    eps = roughness / np.asarray(D, dtype=float)
    f_lo = darcy_friction_Re(G * D / mu_l, eps, turbulent) * mu_l
    # both times G D: the ratio is f_vo/f_lo
    f_vo = darcy_friction_Re(G * D / mu_v, eps, turbulent) * mu_v
    E = (1.0 - x) ** 2 + x * x * rho_l * f_vo / (rho_v * f_lo)
    F = x**0.78 * (1.0 - x) ** 0.224
    H = (rho_l / rho_v) ** 0.91 * (mu_v / mu_l) ** 0.19 * (1.0 - mu_v / mu_l) ** 0.7
    rho_h = homogeneous_density(x, rho_l, rho_v)
    G2 = G * G + G_FRIEDEL_MIN**2
    Fr = G2 / (G_N * D * rho_h * rho_h)
    We = G2 * D / (sigma * rho_h)
    return E + 3.24 * F * H / (Fr**0.0454 * We**0.035)


def friedel_pressure_drop(m, x, rho_l, rho_v, mu_l, mu_v, sigma, D, L, roughness=0.0):
    """Two-phase frictional pressure drop [Pa] by Friedel (signed with m [kg/s]):
    phi_lo^2 (:func:`friedel_multiplier`) times the liquid-only :func:`pressure_drop`."""
    A = np.pi * np.asarray(D, dtype=float) ** 2 / 4.0
    G = np.asarray(m, dtype=float) / A
    phi2 = friedel_multiplier(G, x, rho_l, rho_v, mu_l, mu_v, sigma, D, roughness)
    return phi2 * pressure_drop(m, rho_l, mu_l, D, L, roughness)


def void_fraction_homogeneous(x, rho_l, rho_v):
    """Void fraction alpha [-] without slip: x / (x + (1 - x) rho_v / rho_l)."""
    x = np.clip(x, 0.0, 1.0)
    return x / (x + (1.0 - x) * rho_v / rho_l)


def void_fraction_zivi(x, rho_l, rho_v):
    """Void fraction alpha [-] by Zivi (J. Heat Transfer 86, 247 (1964)), slip
    S = (rho_l/rho_v)^(1/3): alpha = 1 / (1 + (1 - x)/x (rho_v/rho_l)^(2/3)). An
    annular-flow (minimum entropy production) model: for boiler risers it gives less
    void than homogeneous flow, hence more static head."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    with np.errstate(divide="ignore"):
        return np.where(x > 0.0, 1.0 / (1.0 + (1.0 - x) / x * (rho_v / rho_l) ** (2.0 / 3.0)), 0.0)


def mixture_density(alpha, rho_l, rho_v):
    """Mixture density [kg/m3] of a void fraction alpha [-]: alpha rho_v + (1 - alpha) rho_l
    (the density of the static head; with the homogeneous alpha it equals
    :func:`homogeneous_density`)."""
    return alpha * rho_v + (1.0 - alpha) * rho_l


def static_head(rho, dz, g=G_N):
    """Static pressure difference p_bottom - p_top = rho g dz [Pa] of a column of
    density rho [kg/m3] and height dz [m] (dz > 0 upward from bottom to top); for a
    two-phase column rho is :func:`mixture_density` of its void fraction."""
    return np.asarray(rho, dtype=float) * g * np.asarray(dz, dtype=float)
