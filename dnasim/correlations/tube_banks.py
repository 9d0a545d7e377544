"""Gas side of tube banks in cross flow (Zukauskas) and annular fins (Schmidt)."""

from __future__ import annotations

import numpy as np

# Zukauskas (1972) as tabulated by Incropera et al., "Fundamentals of Heat and Mass
# Transfer", 6th ed., Table 7.5 (N_L >= 20, 0.7 <= Pr <= 500): (Re_max from, C, m);
# 1e2..1e3 "approximate as a single (isolated) cylinder": Table 7.4's C = 0.51, m = 0.5.
_ALIGNED = ((10.0, 0.80, 0.40), (1e2, 0.51, 0.50), (1e3, 0.27, 0.63), (2e5, 0.021, 0.84))
_STAGGERED = ((10.0, 0.90, 0.40), (1e2, 0.51, 0.50), (1e3, None, 0.60), (2e5, 0.022, 0.84))
# Incropera Table 7.6: row correction C2 for N_L < 20 (Re_max > 1e3)
_C2_ROWS = np.array([1, 2, 3, 4, 5, 7, 10, 13, 16, 20])
_C2_ALIGNED = np.array([0.70, 0.80, 0.86, 0.90, 0.92, 0.95, 0.97, 0.98, 0.99, 1.0])
_C2_STAGGERED = np.array([0.64, 0.76, 0.84, 0.89, 0.92, 0.95, 0.97, 0.98, 0.99, 1.0])
#: half-width of the blends at the range boundaries, in ln(Re) (a factor 1.1 each side)
_BLEND = np.log(1.1)


def max_velocity(V, D, S_T, S_L, staggered):
    """Velocity in the narrowest cross-section [m/s] (Incropera eqs. 7.59, 7.61):
    aligned, and staggered with 2 (S_D - D) >= S_T - D: V S_T / (S_T - D); staggered
    otherwise: V S_T / (2 (S_D - D)), S_D = sqrt(S_L^2 + (S_T/2)^2). V: approach
    velocity [m/s]; D tube outer diameter, S_T transverse and S_L longitudinal pitch [m]."""
    V = np.asarray(V, dtype=float)
    a = V * S_T / (S_T - D)
    if not staggered:
        return a
    S_D = np.sqrt(S_L * S_L + 0.25 * S_T * S_T)
    return np.where(2.0 * (S_D - D) >= S_T - D, a, V * S_T / (2.0 * (S_D - D)))


def row_correction(n_rows, staggered):
    """Zukauskas' correction C2 [-] for banks of fewer than 20 rows (Incropera Table 7.6,
    interpolated linearly between the tabulated row numbers; 1 from 20 rows on)."""
    tab = _C2_STAGGERED if staggered else _C2_ALIGNED
    return np.interp(np.asarray(n_rows, dtype=float), _C2_ROWS, tab)


def _branch(Re, Pr, C, m):
    return C * Re**m * Pr**0.36


def nusselt_zukauskas(Re_max, Pr, n_rows, S_T, S_L, staggered, Pr_wall=None):
    """Mean Nusselt number Nu = h D / k [-] of a tube bank in cross flow, Zukauskas
    (Adv. Heat Transfer 8, 93 (1972)) as in Incropera (6th ed.) eq. 7.58 and Tables
    7.5, 7.6:

        Nu = C2 C Re_max^m Pr^0.36 (Pr / Pr_wall)^(1/4)

    Re_max = rho V_max D / mu (:func:`max_velocity`), properties at the mean gas
    temperature except Pr_wall (at the wall; omitted if None). (C, m): aligned
    10..1e2: 0.80, 0.40; 1e2..1e3: 0.51, 0.50 (single cylinder); 1e3..2e5: 0.27, 0.63
    (S_T/S_L > 0.7; below, the bank is ineffective and the same is used); 2e5..2e6:
    0.021, 0.84. Staggered: 0.90, 0.40; 0.51, 0.50; 1e3..2e5: 0.35 (S_T/S_L)^(1/5)
    if S_T/S_L < 2, else 0.40, m = 0.60; 0.022, 0.84. C2 = :func:`row_correction`.
    Valid for N_L >= 1 rows, 0.7 <= Pr <= 500, 10 <= Re_max <= 2e6. Between the Re
    ranges the table jumps (by up to 20 %); here the two neighbouring branches are
    blended in ln Re over a factor 1.1 on each side of 1e2, 1e3 and 2e5 (C1, smoothstep),
    so h is continuous for a solver; elsewhere the table's values exactly. Below
    Re_max = 10 the first branch is extrapolated.
    """
    Re = np.maximum(np.asarray(Re_max, dtype=float), 1e-12)
    Pr = np.asarray(Pr, dtype=float)
    rows = _STAGGERED if staggered else _ALIGNED
    ratio = S_T / S_L
    vals = []
    for _, C, m in rows:
        if C is None:
            C = np.where(ratio < 2.0, 0.35 * np.asarray(ratio, dtype=float) ** 0.2, 0.40)
        vals.append(_branch(Re, Pr, C, m))
    nu = vals[0]
    lnRe = np.log(Re)
    for (Re_b, _, _), v in zip(rows[1:], vals[1:], strict=True):
        t = np.clip((lnRe - np.log(Re_b) + _BLEND) / (2.0 * _BLEND), 0.0, 1.0)
        w = t * t * (3.0 - 2.0 * t)
        nu = (1.0 - w) * nu + w * v
    nu = nu * row_correction(n_rows, staggered)
    if Pr_wall is not None:
        nu = nu * (Pr / np.asarray(Pr_wall, dtype=float)) ** 0.25
    return nu


def annular_fin_efficiency(h, k_fin, t, r_1, r_2):
    """Efficiency [-] of an annular (circular) fin of constant thickness, Schmidt's
    approximation (Schmidt, Z. VDI 91 (1949); VDI Heat Atlas M1; Hewitt (ed.), Heat
    Exchanger Design Handbook 2.5.3):

        eta = tanh(m r_1 phi) / (m r_1 phi),   m = sqrt(2 h / (k t))
        phi = (r_2c / r_1 - 1) (1 + 0.35 ln(r_2c / r_1)),   r_2c = r_2 + t / 2

    (r_2c: the tip corrected for its own area.) h: gas-side coefficient [W/(m2 K)],
    k_fin [W/(m K)], t fin thickness [m], r_1 root (tube outer) radius, r_2 fin tip
    radius [m]. Within 2 % of the exact Bessel-function solution (Incropera eq. 3.96)
    for r_2/r_1 <= 2.4 and eta >= 0.5 (tests/test_correlations.py measures 1.5 % at
    worst); less accurate at low efficiency. h -> 0 gives 1."""
    h = np.asarray(h, dtype=float)
    r2c = r_2 + 0.5 * t
    phi = (r2c / r_1 - 1.0) * (1.0 + 0.35 * np.log(r2c / r_1))
    z = np.sqrt(2.0 * h / (k_fin * t)) * r_1 * phi
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(z > 1e-8, np.tanh(z) / np.where(z > 1e-8, z, 1.0), 1.0)


def finned_surface_efficiency(eta_fin, A_fin, A_total):
    """Overall (surface) efficiency [-] of a finned surface: 1 - (A_fin/A_total)(1 - eta_fin);
    the heat flow is eta_0 h A_total (T_wall - T_gas) (Incropera eq. 3.102)."""
    return 1.0 - np.asarray(A_fin, dtype=float) / A_total * (1.0 - np.asarray(eta_fin, dtype=float))
