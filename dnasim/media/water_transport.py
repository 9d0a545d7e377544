"""Viscosity, thermal conductivity and surface tension of water and steam (IAPWS).

Formulations
------------
* **Viscosity**: IAPWS R12-08, "Release on the IAPWS Formulation 2008 for the
  Viscosity of Ordinary Water Substance" (Huber et al., J. Phys. Chem. Ref. Data 38,
  101 (2009)), eqs. (10) to (12)::

      mu = mu* mu0(T) mu1(T, rho) mu2,      mu* = 1e-6 Pa s
      mu0 = 100 sqrt(Tr) / sum_{i=0..3} H_i / Tr^i
      mu1 = exp(rho_r sum_{i=0..5} (1/Tr - 1)^i sum_{j=0..6} H_ij (rho_r - 1)^j)

  with Tr = T / 647.096 K, rho_r = rho / 322 kg/m3. **mu2 = 1**: the critical
  enhancement is left out, as the release recommends for industrial use (IAPWS: "the
  near-critical term is negligible except very close to the critical point; it should
  be omitted for industrial use"). Without it mu is too low only in a small
  neighbourhood of the critical point, where no boiler operates for long.

* **Thermal conductivity**: IAPWS R15-11, "Release on the IAPWS Formulation 2011 for
  the Thermal Conductivity of Ordinary Water Substance" (Huber et al., J. Phys. Chem.
  Ref. Data 41, 033102 (2012)), eqs. (10) to (26), in its **industrial form**
  (Sect. 4 of the release): lambda = lambda* (lambda0 lambda1 + lambda2),
  lambda* = 1e-3 W/(m K), with the critical enhancement lambda2 included::

      lambda0 = sqrt(Tr) / sum_{k=0..4} L_k / Tr^k
      lambda1 = exp(rho_r sum_{i=0..4} (1/Tr - 1)^i sum_{j=0..5} L_ij (rho_r - 1)^j)
      lambda2 = Lambda rho_r cp_r Tr / mu_r Z(y, rho_r),   Lambda = 177.8514
      Z = 2 / (pi y) [((1 - 1/kappa) arctan y + y / kappa)
                      - (1 - exp(-1 / (1/y + y^2 / (3 rho_r^2))))]      (Z = 0 for y < 1.2e-7)
      y = xi / (0.40 nm),   xi = 0.13 nm (dchi / 0.06)^(0.630 / 1.239)
      dchi = rho_r [zeta(T, rho) - zeta_R(rho) 1.5 / Tr]   (set to 0 where negative)
      zeta = (p_c / rho_c) (d rho / d p)_T

  cp_r = cp / R with R = 461.51805 J/(kg K) (the release's value, not IF97's),
  kappa = cp / cv, mu_r = mu / 1e-6 Pa s from R12-08 with mu2 = 1. The industrial form
  takes cp, cv and (d rho/d p)_T from IAPWS-IF97 (here: from the IF97 (p, h) kernel of
  this package) and the reference compressibility zeta_R(rho) = zeta at 1.5 T_c from
  the release's piecewise polynomial in rho_r (its eq. (26) and Table 6).

* **Surface tension**: IAPWS R1-76(2014), "Revised Release on Surface Tension of
  Ordinary Water Substance": sigma = B tau^mu (1 + b tau), tau = 1 - T / T_c,
  B = 235.8e-3 N/m, b = -0.625, mu = 1.256; valid from the triple point to T_c (and
  down to 248.15 K in supercooled liquid); 0 at T_c.

Range (R12-08, R15-11): the stable fluid region up to 1173.15 K at pressures to 100 MPa
at least (the releases go to 300 MPa and beyond; IF97 stops at 100 MPa). IF97's region
5 (1073.15 K to 2273.15 K at p <= 50 MPa) is beyond 1173.15 K an extrapolation of both
formulations; they "extrapolate in a physically reasonable way" (R12-08) and are
used as they are.

Implementation: one compiled loop, :func:`_kernel` (numba, ``cache=True``, like
:mod:`dnasim.media.if97_numba`), evaluates mu and lambda per point from (T, rho) and,
for lambda2, (cp, cv, (d rho/d p)_T); without numba the same code runs as Python.
:func:`viscosity` and :func:`conductivity` take (T, rho) as the releases do;
:func:`surface_tension` takes T. ``IF97Water.transport(p, h)`` takes (p, h).
"""

from __future__ import annotations

import math

import numpy as np

try:
    import numba

    _njit = numba.njit(cache=True, fastmath=False, nogil=True)
except ImportError:  # pragma: no cover - numba is a dependency

    def _njit(f):
        return f


#: critical temperature [K], density [kg/m3], pressure [Pa] (the releases' values)
T_C = 647.096
RHO_C = 322.0
P_C = 22.064e6
#: specific gas constant of R15-11 [J/(kg K)] (used to reduce cp)
R_15_11 = 461.51805

# R12-08 Table 1 (H_i) and Table 2 (H_ij, i = 0..5 rows, j = 0..6 columns)
MU_H0 = np.array([1.67752, 2.20462, 0.6366564, -0.241605])
MU_H1 = np.array(
    [
        [5.20094e-1, 2.22531e-1, -2.81378e-1, 1.61913e-1, -3.25372e-2, 0.0, 0.0],
        [8.50895e-2, 9.99115e-1, -9.06851e-1, 2.57399e-1, 0.0, 0.0, 0.0],
        [-1.08374, 1.88797, -7.72479e-1, 0.0, 0.0, 0.0, 0.0],
        [-2.89555e-1, 1.26613, -4.89837e-1, 0.0, 6.98452e-2, 0.0, -4.35673e-3],
        [0.0, 0.0, -2.57040e-1, 0.0, 0.0, 8.72102e-3, 0.0],
        [0.0, 1.20573e-1, 0.0, 0.0, 0.0, 0.0, -5.93264e-4],
    ]
)
# R15-11 Table 1 (L_k) and Table 2 (L_ij, i = 0..4 rows, j = 0..5 columns)
K_L0 = np.array([2.443221e-3, 1.323095e-2, 6.770357e-3, -3.454586e-3, 4.096266e-4])
K_L1 = np.array(
    [
        [1.60397357, -0.646013523, 0.111443906, 0.102997357, -0.0504123634, 0.00609859258],
        [2.33771842, -2.78843778, 1.53616167, -0.463045512, 0.0832827019, -0.00719201245],
        [2.19650529, -4.54580785, 3.55777244, -1.40944978, 0.275418278, -0.0205938816],
        [-1.21051378, 1.60812989, -0.621178141, 0.0716373224, 0.0, 0.0],
        [-2.7203370, 4.57586331, -3.18369245, 1.1168348, -0.19268305, 0.012913842],
    ]
)
# R15-11 Table 6: 1/zeta_R(rho_r) = sum_i A_ij rho_r^i on the density intervals j
ZETA_R_BOUNDS = np.array([0.310559006, 0.776397516, 1.242236025, 1.863354037])
ZETA_R_A = np.array(
    [
        [6.53786807199516, -5.61149954923348, 3.39624167361325,
         -2.27492629730878, 10.2631854662709, 1.97815050331519],
        [6.52717759281799, -6.30816983387575, 8.08379285492595,
         -9.82240510197603, 12.1358413791395, -5.54349664571295],
        [5.35500529896124, -3.96415689925446, 8.91990208918795,
         -12.0338729505790, 9.19494865194302, -2.16866274479712],
        [1.55225959906681, 0.464621290821181, 8.93237374861479,
         -11.0321960061126, 6.16780999933360, -0.965458722086812],
        [1.11999926419994, 0.595748562571649, 9.88952565078920,
         -10.3255051147040, 4.66861294457414, -0.503243546373828],
    ]
)  # fmt: skip

# R1-76(2014)
SIGMA_B = 235.8e-3  # [N/m]
SIGMA_b = -0.625
SIGMA_MU = 1.256
#: lowest temperature of R1-76 [K] (supercooled liquid; the triple point is 273.16 K)
SIGMA_T_MIN = 248.15


@_njit
def _poly2(x, y, C):
    """sum_i x^i sum_j C[i, j] y^j (Horner in both)."""
    ni, nj = C.shape
    s = 0.0
    for i in range(ni - 1, -1, -1):
        r = 0.0
        for j in range(nj - 1, -1, -1):
            r = r * y + C[i, j]
        s = s * x + r
    return s


@_njit
def _mu_reduced(Tr, dr):
    """mu / (1e-6 Pa s) by R12-08 with mu2 = 1."""
    s = MU_H0[MU_H0.size - 1]  # H0 + H1/Tr + H2/Tr^2 + H3/Tr^3, Horner in 1/Tr
    for i in range(MU_H0.size - 2, -1, -1):
        s = s / Tr + MU_H0[i]
    mu0 = 100.0 * math.sqrt(Tr) / s
    return mu0 * math.exp(dr * _poly2(1.0 / Tr - 1.0, dr - 1.0, MU_H1))


@_njit
def _lambda2(Tr, dr, mu_r, cp, cv, drho_dp_T):
    """Critical enhancement lambda2 / (1e-3 W/(m K)) of R15-11 (industrial form)."""
    if not (cp == cp and cv == cv and drho_dp_T == drho_dp_T):
        return 0.0
    j = 0
    while j < ZETA_R_BOUNDS.size and dr > ZETA_R_BOUNDS[j]:
        j += 1
    a = 0.0
    for i in range(ZETA_R_A.shape[1] - 1, -1, -1):
        a = a * dr + ZETA_R_A[j, i]
    zeta = drho_dp_T * P_C / RHO_C
    dchi = dr * (zeta - 1.5 / (Tr * a))
    if not dchi > 0.0:
        return 0.0
    xi = 0.13 * (dchi / 0.06) ** (0.630 / 1.239)
    y = xi / 0.40
    if y < 1.2e-7:
        return 0.0
    kinv = cv / cp
    Z = (
        2.0
        / (math.pi * y)
        * (
            ((1.0 - kinv) * math.atan(y) + kinv * y)
            - (1.0 - math.exp(-1.0 / (1.0 / y + y * y / (3.0 * dr * dr))))
        )
    )
    return 177.8514 * dr * (cp / R_15_11) * Tr / mu_r * Z


@_njit
def _kernel(T, rho, cp, a, b, mode, mu, k):
    """Fill mu [Pa s] and k [W/(m K)] from T [K], rho [kg/m3] (1-D arrays).

    mode 0: no critical enhancement (a, b, cp unused); mode 1: a = cv [J/(kg K)],
    b = (d rho/d p)_T [kg/(m3 Pa)]; mode 2: a = (d rho/d p)_h, b = (d rho/d h)_p of a
    (p, h) state, converted as :func:`isothermal_inputs` says."""
    for n in range(T.size):
        Tn = T[n]
        rn = rho[n]
        Tr = Tn / T_C
        dr = rn / RHO_C
        if not (Tr > 0.0 and dr >= 0.0 and math.isfinite(Tr) and math.isfinite(dr)):
            mu[n] = math.nan
            k[n] = math.nan
            continue
        mu_r = _mu_reduced(Tr, dr)
        s = K_L0[K_L0.size - 1]
        for i in range(K_L0.size - 2, -1, -1):
            s = s / Tr + K_L0[i]
        lam = math.sqrt(Tr) / s * math.exp(dr * _poly2(1.0 / Tr - 1.0, dr - 1.0, K_L1))
        if mode == 1:
            lam += _lambda2(Tr, dr, mu_r, cp[n], a[n], b[n])
        elif mode == 2:
            c = cp[n]
            rho_T = c * b[n]
            rho_pT = a[n] + b[n] * (1.0 / rn + Tn * rho_T / (rn * rn))
            cv = c - Tn * rho_T * rho_T / (rn * rn * rho_pT)
            lam += _lambda2(Tr, dr, mu_r, c, cv, rho_pT)
        mu[n] = mu_r * 1e-6
        k[n] = lam * 1e-3


def _flat(*arrays):
    b = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in arrays))
    return b[0].shape, [np.ascontiguousarray(a.ravel()) for a in b]


def mu_k(T, rho, cp=None, cv=None, drho_dp_T=None):
    """(mu [Pa s], k [W/(m K)]) arrays at T [K], rho [kg/m3] (broadcast).

    With cp, cv [J/(kg K)] and (d rho/d p)_T [kg/(m3 Pa)] given, k includes the
    critical enhancement lambda2 of R15-11 (industrial form); without them lambda2 = 0
    (the release's verification Table 4). NaN for T not finite and > 0 or rho not
    finite and >= 0 (rho = 0 is the dilute-gas limit).
    """
    if cp is None:
        shape, (T, rho) = _flat(T, rho)
        cp = a = b = T
        mode = 0
    else:
        shape, (T, rho, cp, a, b) = _flat(T, rho, cp, cv, drho_dp_T)
        mode = 1
    mu = np.empty(T.size)
    k = np.empty(T.size)
    _kernel(T, rho, cp, a, b, mode, mu, k)
    return mu.reshape(shape), k.reshape(shape)


def mu_k_ph(T, rho, cp, drho_dp_h, drho_dh_p):
    """(mu [Pa s], k [W/(m K)]) with the critical enhancement from a (p, h) state's
    1-D float arrays T [K], rho [kg/m3], cp [J/(kg K)], (d rho/d p)_h [kg/(m3 Pa)],
    (d rho/d h)_p [kg2/(m3 J)] (:func:`isothermal_inputs` done in the compiled loop)."""
    mu = np.empty(T.size)
    k = np.empty(T.size)
    _kernel(T, rho, cp, drho_dp_h, drho_dh_p, 2, mu, k)
    return mu, k


def viscosity(T, rho):
    """Dynamic viscosity [Pa s] of water at T [K], rho [kg/m3]: R12-08 with mu2 = 1."""
    return mu_k(T, rho)[0]


def conductivity(T, rho, cp=None, cv=None, drho_dp_T=None):
    """Thermal conductivity [W/(m K)] at T [K], rho [kg/m3]: R15-11 (see :func:`mu_k`)."""
    return mu_k(T, rho, cp, cv, drho_dp_T)[1]


def surface_tension(T):
    """Surface tension [N/m] of water against its vapour at T [K] (IAPWS R1-76(2014)).

    NaN outside [248.15 K, T_c]; 0 at T_c.
    """
    T = np.asarray(T, dtype=float)
    tau = 1.0 - T / T_C
    ok = (T >= SIGMA_T_MIN) & (tau >= 0.0)
    tau = np.where(ok, tau, np.nan)
    return SIGMA_B * tau**SIGMA_MU * (1.0 + SIGMA_b * tau)


def isothermal_inputs(T, rho, cp, drho_dp_h, drho_dh_p):
    """(cv [J/(kg K)], (d rho/d p)_T [kg/(m3 Pa)]) from a (p, h) state's T [K],
    rho [kg/m3], cp [J/(kg K)], (d rho/d p)_h [kg/(m3 Pa)], (d rho/d h)_p [kg2/(m3 J)].

    With rho(p, h): (d rho/d T)_p = cp (d rho/d h)_p; (d h/d p)_T = 1/rho -
    T (d v/d T)_p = 1/rho + T (d rho/d T)_p / rho^2; (d rho/d p)_T = (d rho/d p)_h +
    (d rho/d h)_p (d h/d p)_T; cp - cv = T (d rho/d T)_p^2 / (rho^2 (d rho/d p)_T).
    """
    rho_T = cp * drho_dh_p
    rho_pT = drho_dp_h + drho_dh_p * (1.0 / rho + T * rho_T / (rho * rho))
    cv = cp - T * rho_T * rho_T / (rho * rho * rho_pT)
    return cv, rho_pT
