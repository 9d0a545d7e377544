"""Compressible and flashing flow laws of valves and relief valves, as plain functions.

Every law here gives the flow of a restriction from its upstream state (p_1 [Pa],
rho_1 [kg/m3], the state's exponent) and the pressure drop dp = p_1 - p_2 [Pa] in
the form the valves use,

    m = K z_e sqrt(rho_1) phi(eps) sqrt(dp),      eps = dp / p_1 = 1 - p_2/p_1   [kg/s]

with K [m2] the flow coefficient (K = Kv/36000 m2, or K = sqrt(2) K_d A for a flow
area A [m2] with discharge coefficient K_d [-]: K sqrt(rho dp) = K_d A sqrt(2 rho dp)),
z_e [-] the effective opening and phi [-] the compressibility factor of the law:
phi = 1 for an incompressible liquid, phi(eps) -> 1 for eps -> 0 for every law, so
the valves' regularised sqrt(dp) near dp = 0 (``physics.valve_flow``) stays as it is.
Each factor is smooth in eps up to its choking limit eps_c; the valves clip eps at
eps_c with ``control_valve.odd_limit`` (the flux has its maximum there, dG/deps = 0,
so the clipped law is C1).

Nozzle flow function (ideal gas, isentropic; de Saint-Venant and Wantzel; ClaRa's
``Valves.Fundamentals.Quadratic_FlowFunction``; EN ISO 4126-7 eqs. for gases):

    m = K_d A Psi(r, kappa) sqrt(2 rho_1 p_1),  r = p_2/p_1 = 1 - eps
    Psi = sqrt(kappa/(kappa - 1) (r^(2/kappa) - r^((kappa + 1)/kappa)))   (r > r_c)
    r_c = (2/(kappa + 1))^(kappa/(kappa - 1)),  Psi(r <= r_c) = Psi(r_c)   (choked)
    phi = Psi(1 - eps) / sqrt(eps)                                     (``nozzle_factor``)

Omega method (homogeneous equilibrium flow, HEM, of a flashing two-phase mixture or
a gas; Leung 1986, 1995; API 520 Part I Annex C, the two-phase sizing of relief
valves), with omega [-] the compressibility of the inlet state. Here omega is the
differential form omega = (p_0/rho_0) (d rho/d p)_s = 1/kappa_s of the homogeneous
equilibrium state (``dnasim.media.isentropic.isentropic_exponent``), eta = p_2/p_0:

  two-phase or gas inlet (``omega_factor``):
    G = sqrt(-2 (omega ln eta + (omega - 1)(1 - eta))) sqrt(p_0 rho_0)
        / (omega (1/eta - 1) + 1)                                          [kg/(m2 s)]
    choked below eta_c: eta_c^2 + (omega^2 - 2 omega)(1 - eta_c)^2
        + 2 omega^2 ln eta_c + 2 omega^2 (1 - eta_c) = 0  (``omega_critical_ratio``)
  subcooled liquid inlet, saturation pressure p_s = p_sat(T_0), eta_s = p_s/p_0,
  omega_s of the saturated liquid at p_s (``omega_subcooled_factor``):
    high subcooling, eta_s < 2 omega_s/(1 + 2 omega_s): the liquid flashes at the
      throat and chokes at p_s: G = sqrt(2 rho_0 (p_0 - max(p_2, p_s)))
    low subcooling: G = sqrt(2 rho_0 (p_0 - p_2)) for eta >= eta_s; below eta_s
      G = sqrt(2 (1 - eta_s) + 2 (omega_s eta_s ln(eta_s/eta) - (omega_s - 1)(eta_s - eta)))
          sqrt(p_0 rho_0) / (omega_s (eta_s/eta - 1) + 1), choked below eta_c:
      (omega_s + 1/omega_s - 2)/(2 eta_s) eta_c^2 - 2 (omega_s - 1) eta_c
          + omega_s eta_s ln(eta_c/eta_s) + 3/2 omega_s eta_s - 1 = 0
  and phi = G / sqrt(2 rho_0 dp). For omega -> 0 (a liquid) every form is Bernoulli's
  G = sqrt(2 rho_0 dp), phi = 1; the subcooled forms join the saturated ones at
  eta_s = 1 and each other at eta_s = 2 omega_s/(1 + 2 omega_s) (continuous; the
  flashing onset p_2 = p_s is a kink). For a gas (omega = 1/kappa) the omega method's
  choked flux is 0.8 % (kappa = 1.1) to 2.8 % (1.4) below the nozzle's.

Napier's formula (ASME BPVC Section I, PG-69.2; API 520 Part I eq. for steam): the
choked flow of dry saturated steam through a relief valve,

    W = 51.5 K A P   [lb/h, in2, psia]   <=>   m = 1.4588e-3 [s/m] K A p_1   [kg/s, m2, Pa]

with K = 0.9 K_D the rated coefficient of discharge, times K_N = (0.1906 P - 1000)/
(0.2292 P - 1061) [P in psia] above 1500 psia (``napier_flow``).

All functions take and return floats in SI units; nothing here knows a medium except
``inlet_exponent``.
"""

from __future__ import annotations

import math

from dnasim.media.isentropic import heat_capacity_ratio, isentropic_exponent

__all__ = [
    "EXPONENT_MODELS",
    "DEW_BAND",
    "inlet_exponent",
    "critical_pressure_ratio",
    "nozzle_factor",
    "omega_critical_ratio",
    "omega_factor",
    "omega_subcooled_critical_ratio",
    "omega_subcooled_factor",
    "NAPIER_SI",
    "napier_flow",
]

#: how a valve takes the exponent of its inlet state (see ``inlet_exponent``)
EXPONENT_MODELS = ("fixed", "cp_cv", "isentropic")
#: enthalpy band [J/kg] above the dew line over which the exponent of a vapour blends
#: (C1) into the value on the dew line (ClaRa's GenericValveVLE_L1 uses the same
#: 1000 J/kg): the equilibrium exponent jumps at the dew line (IF97, 10 bar:
#: kappa_s 1.140 wet, 1.291 dry), and a jump in a residual would stall Newton
DEW_BAND = 1000.0
#: |kappa - 1| below which the kappa -> 1 limits are used [-]
KAPPA_ONE = 1e-9
#: Napier's 51.5 lb/(h in2 psia) in SI: 51.5 * 0.45359237/3600 / (0.0254^2 * 6894.757) [s/m]
NAPIER_SI = 51.5 * 0.45359237 / 3600.0 / (0.0254**2 * 6894.757293168361)
#: 1500 psia [Pa], above which ASME I multiplies Napier's formula by K_N
NAPIER_HIGH_P = 1500.0 * 6894.757293168361


def _step(s: float) -> float:
    """C1 step 0 (s <= 0) -> 1 (s >= 1): 3 s^2 - 2 s^3 in between."""
    s = min(max(s, 0.0), 1.0)
    return s * s * (3.0 - 2.0 * s)


def inlet_exponent(medium, st, model: str) -> float:
    """The exponent [-] of the inlet state ``st`` (a FluidState of ``medium``) for the
    compressible valve laws, by ``model``:

      "isentropic"  kappa_s = -(v/p)(dp/dv)_s of the real fluid (equilibrium mixture in
                    the dome: 1.14 for dry saturated steam at 10 bar, 1.04 at x = 0.5;
                    a liquid's is large, which turns the gas laws into the liquid law);
      "cp_cv"       cp/cv of the inlet state (IEC 60534-2-1's "specific heat ratio"
                    gamma; ClaRa's GenericValveVLE_L1): for wet steam and liquid the
                    value of the vapour on the dew line at p (cp/cv is undefined in the
                    dome). Near saturation at high pressure cp/cv of steam is far from
                    the expansion's exponent (IF97 at 100 bar: 2.30, kappa_s 1.24).

    A condensable medium below its critical pressure blends the vapour value into
    the dew-line value over ``DEW_BAND`` above the dew line (C1 in h), so that the
    exponent has no jump where a state crosses the dew line. ("fixed" is the
    valve's own constant and never reaches here.)"""
    if model == "isentropic":
        own = isentropic_exponent
    elif model == "cp_cv":
        own = heat_capacity_ratio
    else:
        raise ValueError(f"no exponent model {model!r}")
    h_v = _dew_enthalpy(medium, st.p)
    if h_v is None or st.h >= h_v + DEW_BAND:
        return own(st)
    # on the dew line: the dome's (equilibrium) value for kappa_s, the vapour's
    # side (1 mJ/kg above h'') for cp/cv, which is not defined in the dome
    dew = medium.state(st.p, h_v if model == "isentropic" else h_v + 1e-3)
    at_dew = own(dew)
    if model == "cp_cv" and st.h <= h_v:
        return at_dew
    if st.h <= h_v:  # isentropic, wet or liquid: the state's own value
        return own(st)
    s = _step((st.h - h_v) / DEW_BAND)
    return at_dew + s * (own(st) - at_dew)


def _dew_enthalpy(medium, p):
    """h'' [J/kg] at p [Pa], or None (not condensable, at or above the critical point)."""
    if not getattr(medium, "condensable", False):
        return None
    import numpy as np

    _, hv = medium.saturation_enthalpies(np.array([p]))
    hv = float(hv[0])
    return hv if math.isfinite(hv) else None


# ------------------------------------------------------------------ nozzle (gas)
def critical_pressure_ratio(kappa: float) -> float:
    """r_c = (2/(kappa + 1))^(kappa/(kappa - 1)) [-]; exp(-1/2) at kappa = 1."""
    if abs(kappa - 1.0) < KAPPA_ONE:
        return math.exp(-0.5 * kappa)
    return math.exp(-math.log1p(0.5 * (kappa - 1.0)) * kappa / (kappa - 1.0))


def nozzle_factor(eps: float, kappa: float) -> float:
    """phi = Psi(1 - eps, kappa)/sqrt(eps) [-] of the nozzle flow function (module doc),
    for 0 <= eps < 1 (the caller clips eps at eps_c = 1 - r_c): with a = (kappa-1)/kappa,
    Psi^2 = r^(2/kappa) (1 - r^a)/a, written as -expm1(a ln r)/a so that kappa -> 1
    (-> -ln r) and eps -> 0 (phi -> 1) lose no digits."""
    eps = abs(eps)
    if eps == 0.0:
        return 1.0
    ln_r = math.log1p(-eps)
    a = (kappa - 1.0) / kappa
    term = -ln_r if abs(a) < KAPPA_ONE else -math.expm1(a * ln_r) / a
    return math.sqrt(math.exp(2.0 / kappa * ln_r) * term / eps)


# --------------------------------------------------------------- omega method
def omega_critical_ratio(omega: float) -> float:
    """eta_c [-] of the omega method for a two-phase or gas inlet (module doc): the
    root in (0, 1) of eta^2 + (w^2 - 2w)(1 - eta)^2 + 2 w^2 ln eta + 2 w^2 (1 - eta),
    by Newton from Leung's fit, safeguarded by bisection; 0 for omega = 0."""
    w = omega
    if w <= 0.0:
        return 0.0

    def f(e):
        return e * e + (w * w - 2.0 * w) * (1.0 - e) ** 2 + 2.0 * w * w * (math.log(e) + 1.0 - e)

    def df(e):
        return 2.0 * e - 2.0 * (w * w - 2.0 * w) * (1.0 - e) + 2.0 * w * w * (1.0 / e - 1.0)

    return _root(f, df, 1e-300, 1.0, _leung_guess(w))


def _leung_guess(w: float) -> float:
    """Leung's fit eta_c = 0.55 + 0.217 ln w - 0.046 (ln w)^2 + 0.004 (ln w)^3 (w >= 4),
    the ideal-gas-like 0.6 w^0.3 below; a start only."""
    if w >= 4.0:
        L = math.log(w)
        return min(0.55 + 0.217 * L - 0.046 * L * L + 0.004 * L**3, 0.999)
    return min(max(0.6 * w**0.3, 1e-6), 0.99)


def _root(f, df, lo, hi, x):
    """The root of f in (lo, hi) with f(lo) < 0 < f(hi): Newton steps kept inside the
    bracket (bisection otherwise), to 1e-15 relative."""
    for _ in range(200):
        fx = f(x)
        if fx == 0.0:
            return x
        if fx < 0.0:
            lo = x
        else:
            hi = x
        d = df(x)
        step = fx / d if d != 0.0 else math.inf
        new = x - step
        if not (lo < new < hi):
            new = 0.5 * (lo + hi) if lo > 1e-290 else math.sqrt(max(lo, 1e-300) * hi)
        if abs(new - x) <= 1e-15 * abs(x):
            return new
        x = new
    return x


def omega_factor(eps: float, omega: float) -> float:
    """phi = G/sqrt(2 rho_0 p_0 eps) [-] of the omega method for a two-phase or gas inlet
    at eps = 1 - eta (the caller clips eps at 1 - eta_c): with N = -2 (w ln eta +
    (w - 1)(1 - eta)) = 2 eps - 2 w (ln(1 - eps) + eps), phi = sqrt(N/(2 eps)) /
    (w (1/eta - 1) + 1); the series of ln(1 - eps) + eps for small eps."""
    eps = abs(eps)
    w = omega
    if eps == 0.0:
        return 1.0
    c = _log1m_plus(eps) / eps  # (ln(1 - eps) + eps)/eps = -eps/2 - eps^2/3 - ...
    ratio = 1.0 - w * c
    eta = 1.0 - eps
    return math.sqrt(ratio) / (w * eps / eta + 1.0)


def _log1m_plus(eps: float) -> float:
    """ln(1 - eps) + eps, without cancellation for small eps."""
    if eps < 1e-3:
        return -(eps**2) * (0.5 + eps * (1.0 / 3.0 + eps * (0.25 + eps * 0.2)))
    return math.log1p(-eps) + eps


def omega_subcooled_critical_ratio(omega_s: float, eta_s: float) -> float:
    """eta_c [-] of a subcooled liquid inlet (module doc): eta_s for high subcooling
    (eta_s < 2 w/(1 + 2 w): choked at the saturation pressure), else the root in
    (0, eta_s] of (w + 1/w - 2)/(2 eta_s) eta^2 - 2 (w - 1) eta + w eta_s ln(eta/eta_s)
    + 3/2 w eta_s - 1."""
    w = omega_s
    if w <= 0.0 or eta_s <= 0.0:
        return max(eta_s, 0.0)
    if eta_s < 2.0 * w / (1.0 + 2.0 * w):
        return eta_s
    A = (w + 1.0 / w - 2.0) / (2.0 * eta_s)

    def f(e):
        return A * e * e - 2.0 * (w - 1.0) * e + w * eta_s * (math.log(e / eta_s) + 1.5) - 1.0

    def df(e):
        return 2.0 * A * e - 2.0 * (w - 1.0) + w * eta_s / e

    if f(eta_s) <= 0.0:
        return eta_s
    return _root(f, df, 1e-300, eta_s, min(_leung_guess(w), eta_s) * 0.999)


def omega_subcooled_factor(eps: float, omega_s: float, eta_s: float) -> float:
    """phi = G/sqrt(2 rho_0 p_0 eps) [-] of a subcooled liquid inlet at eps = 1 - eta
    (the caller clips eps at 1 - eta_c): 1 while p_2 >= p_s (eps <= 1 - eta_s) and for
    high subcooling (where the clip at eta_c = eta_s is the choking), else the
    flashing form of the module doc."""
    eps = abs(eps)
    w = omega_s
    eta = 1.0 - eps
    if eps == 0.0 or eta >= eta_s or w <= 0.0 or eta_s < 2.0 * w / (1.0 + 2.0 * w):
        return 1.0
    flash = w * eta_s * math.log(eta_s / eta) - (w - 1.0) * (eta_s - eta)
    num = 2.0 * (1.0 - eta_s) + 2.0 * flash
    return math.sqrt(num / (2.0 * eps)) / (w * (eta_s / eta - 1.0) + 1.0)


# ------------------------------------------------------------------------- Napier
def napier_flow(A: float, K: float, p1: float) -> float:
    """Napier's choked flow m [kg/s] of dry saturated steam (module doc) through the
    flow area A [m2] with the rated coefficient of discharge K [-] at the relieving
    pressure p1 [Pa absolute]: NAPIER_SI K A p1 K_N. K_N = (0.1906 P - 1000)/
    (0.2292 P - 1061) (P in psia) where it exceeds 1, which is above 1579.9 psia
    (10.893 MPa): ASME I applies it from 1500 psia, where it is 0.9957, so this
    continuous form (no jump in a residual) is up to 0.43 % above ASME's between
    1500 and 1580 psia, and equal elsewhere. ASME I gives K_N up to 3200 psia (near the
    critical point, 22.06 MPa); above it K_N is held at its 3200 psia value (1.19)."""
    P = min(p1 / 6894.757293168361, 3200.0)
    K_N = 1.0
    if P > 1500.0:
        K_N = max(1.0, (0.1906 * P - 1000.0) / (0.2292 * P - 1061.0))
    return NAPIER_SI * K * A * p1 * K_N
