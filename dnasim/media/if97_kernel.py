"""Vectorised IAPWS-IF97 water and steam: (p, h) -> every property, in one call.

::

    from dnasim.media.if97_kernel import ph, pT
    r = ph(p, h)                 # p [Pa], h [J/kg]: arrays of any (equal, broadcast) shape
    r.T, r.rho, r.u, r.s, r.cp, r.x, r.drho_dp_h, r.drho_dh_p, r.region, r.ok
    r.raise_first_bad("Water (IF97)")   # PropertyError for the first state that failed
    pT(p, T).h                   # forward: single-phase h(p, T) etc.

Pure numpy; no CoolProp. The units are SI throughout.

Formulations (IAPWS R7-97(2012), coefficients in :mod:`if97_coefficients`)
--------------------------------------------------------------------------
* region 1 (liquid, T <= 623.15 K): Gibbs g(p, T) = R T gamma(pi, tau),
  pi = p/16.53 MPa, tau = 1386 K/T;
* region 2 (vapour, T <= 1073.15 K): Gibbs, ideal part + residual part,
  pi = p/1 MPa, tau = 540 K/T;
* region 3 (623.15 K <= T <= T_B23(p)): Helmholtz f(rho, T) = R T phi(delta, tau),
  delta = rho/322 kg/m3, tau = 647.096 K/T; rho(p, T) is solved by Newton's
  method on p(rho, T) = p, on the branch the phase asks for;
* region 4 (saturation): p_sat(T), T_sat(p) (eqs. 30 and 31, exact inverses),
  the saturated states are the single-phase formulations at (p, T_sat(p)):
  regions 1 and 2 below 16.529 MPa, region 3 (liquid and vapour roots) above;
* region 5 (1073.15 K < T <= 2273.15 K, p <= 50 MPa): Gibbs, pi = p/1 MPa,
  tau = 1000 K/T.

Relations used for a Gibbs region (gamma and its derivatives in pi, tau; p*, T*
the reducing values)::

    v = R T gamma_pi / p*           h = R T* gamma_tau          s = R (tau gamma_tau - gamma)
    cp = (dh/dT)_p = -R tau^2 gamma_tautau
    (dh/dp)_T = R T* gamma_pitau / p*
    (dv/dT)_p = R (gamma_pi - tau gamma_pitau) / p*
    (dv/dp)_T = R T gamma_pipi / p*^2

and for region 3 (phi and its derivatives in delta, tau)::

    p = rho R T delta phi_d          h = R T (tau phi_t + delta phi_d)   s = R (tau phi_t - phi)
    (dp/drho)_T = R T (2 delta phi_d + delta^2 phi_dd)
    (dp/dT)_rho = rho R (delta phi_d - delta tau phi_dt)
    (dh/drho)_T = R T (tau phi_dt + phi_d + delta phi_dd) / rho_c
    (dh/dT)_rho = R (-tau^2 phi_tt + delta phi_d - delta tau phi_dt)

converted to (p, T) derivatives with (drho/dT)_p = -(dp/dT)_rho / (dp/drho)_T.

(p, h) -> state
----------------
Below p_c = 22.064 MPa the saturation enthalpies h'(p), h''(p) (the liquid- and
vapour-side formulations at T_sat(p)) decide the phase. A single-phase T solves
h(p, T) = h by a safeguarded Newton iteration (a bisection step when a Newton step
leaves the bracket or does not halve the previous step, as ``rtsafe``; the bracket is
[273.15 K, T_sat] for a liquid, [T_sat, T_max] for a vapour, [273.15 K, T_max] above
p_c), started from the IF97 backward equation T(p, h) of the region (T1, T2a/b/c with
the B2bc boundary, T3a/T3b of SR3-03 with the h_3ab(p) boundary). A state whose
backward T lies inside region 3 (away from the bands) is solved instead by Newton's
method on (rho, T) for p3(rho, T) = p, h3(rho, T) = h, started from v3a/v3b(p, h):
that stays well conditioned at the critical point, where rho(p, T) is not. The
iterations stop at |h(p, T) - h| <= 2e-14 |h| + 1e-9 J/kg or a T step below
2e-14 T (4e-13 T after 5 iterations: the round-off floor of the region-3 density
is about 1e-13), typically after 2 to 4 iterations. So h(p, T(p, h)) = h to
about 1e-13 relative (5e-12 near the critical point) and every output is the
forward formulation at that T.

Then::

    rho = 1/v     u = h - p/rho (exactly)     cp = (dh/dT)_p
    (drho/dh)_p = -(dv/dT)_p / (v^2 cp)
    (drho/dp)_h = -[(dv/dp)_T - (dv/dT)_p (dh/dp)_T / cp] / v^2

Two-phase (h' <= h <= h'', p < p_c): homogeneous mixture at T_sat(p),
x = (h - h')/(h'' - h'), v = v' + x (v'' - v'), s = s' + x (s'' - s'),
u = h - p v, ``cp = inf`` (the limit of (dh/dT)_p; documented convention),
(drho/dh)_p = -rho^2 (v'' - v')/(h'' - h') and::

    (drho/dp)_h = -rho^2 [v'_p + x (v''_p - v'_p)
                          - (v'' - v') (h'_p + x (h''_p - h'_p)) / (h'' - h')]

with the derivatives along the saturation line X_p = (dX/dp)_T + (dX/dT)_p dT_sat/dp,
all analytic (dT_sat/dp = 1/(dp_sat/dT) from eq. 30).

Continuity at the region boundaries (blending)
---------------------------------------------
The IF97 regions are not exactly equal on their common boundaries (IF97 only
requires them to agree within its consistency tolerances, e.g. |dh| <= 0.2 kJ/kg).
Used as they are, h(p, T) jumps there and rho(p, h) jumps or inverts. Measured
differences of the two formulations on the boundary (tests/test_if97_kernel.py,
p = 17 to 100 MPa for 1/3 and 2/3, 1 kPa to 50 MPa for 2/5), against IF97's
consistency tolerances (|dv/v| 5e-4, |dh| 200 J/kg, |dcp/cp| 1 %):

===========  ==========  ===========  ===========
boundary     max |dv/v|  max |dh|     max |dcp/cp|
===========  ==========  ===========  ===========
1/3          2.8e-5      28 J/kg      0.16 %
2/3 (B23)    1.8e-4      121 J/kg     0.32 %
2/5          1.2e-4      94 J/kg      0.07 %
===========  ==========  ===========  ===========
 This kernel therefore uses,
within a narrow band around each boundary, a smooth blend of the two neighbouring
formulations: with the quintic smoothstep S(t) = t^3 (10 - 15 t + 6 t^2), t in
[0, 1] (S, S', S'' continuous)::

    X = (1 - w) X_A + w X_B     for X = v, h, s, (dv/dp)_T, (dh/dp)_T, (dv/dT)_p, cp
    (dX/dT)_p += (dw/dT) (X_B - X_A),   (dX/dp)_T += (dw/dp) (X_B - X_A)   for X = v, h

so v, h, s, u and all derivatives are continuous (C2 in value) across the boundary,
and the T solved on the blended h(p, T) makes h(p, T(p, h)) = h exact as before.

======================  ==========================  =============================
boundary                band                        formulations
======================  ==========================  =============================
1/3 (T = 623.15 K)      T in 623.15 K +- ``BAND_13`` region 1 -> region 3 (liquid root)
2/3 (T = T_B23(p))      T in T_B23(p) +- ``BAND_23`` region 3 (vapour root) -> region 2
2/5 (T = 1073.15 K)     T in [1073.15, 1073.15 + 2 ``BAND_25``] K  region 2 -> region 5
======================  ==========================  =============================

(the 2/5 band lies above 1073.15 K so that region 5 is never used above 50 MPa; region
2 is used up to 1 K above its nominal limit). Outside the bands the result is IF97
exactly. Inside, each value lies between the two formulations, so it differs from
either by at most the IF97 boundary inconsistency (within IF97's own consistency
tolerances); the sizes are measured in tests/test_if97_kernel.py. The saturated
states are the blended formulations at T_sat, so h'(p), h''(p) are continuous too
(at 16.529 MPa, where region 1 hands the saturated liquid to region 3).

Near the critical point
-----------------------
The region-3 equation and the region-4 T_sat(p) meet the critical point slightly
differently: the region-3 saturated states computed at T_sat(p) cross (h' >= h'')
within about 0.5 Pa of p_c. There the dome is treated as closed (the state is solved
as supercritical); the saturated densities differ by only about 1e-5 relative at
that point, so the change is of that size. Within about 1 Pa of p_c and 10 J/kg of
the critical enthalpy, rho is ill-conditioned (infinite compressibility) and carries
round-off noise of about 1e-5 relative; elsewhere the near-critical states are smooth
and monotone (tests: 22.064, 22.1, 23, 25, 30 MPa scans).

Range and errors
----------------
611.213 Pa <= p <= 100 MPa; T >= 273.15 K; T <= 1073.15 K above 50 MPa and
T <= 2273.15 K up to 50 MPa. A state outside is not raised inside the kernel: its
entry of ``ok`` is False, ``status`` says why (``STATUS_TEXT``), its outputs are NaN,
and :meth:`PhResult.raise_first_bad` raises :class:`PropertyError` for the first one.
"""

from __future__ import annotations

import numpy as np

from dnasim.media import if97_coefficients as C
from dnasim.media.errors import PropertyError

# ----------------------------------------------------------------- constants
R = C.R  # [J/(kg K)]
P_C = C.P_C  # [Pa]
T_C = C.T_C  # [K]
RHO_C = C.RHO_C  # [kg/m3]
P_MIN = 611.213  # [Pa] p_sat(273.15 K): lowest pressure accepted
P_MAX = 100e6  # [Pa]
P_R5_MAX = 50e6  # [Pa] region 5 upper pressure
T_MIN = 273.15  # [K]
T_13 = 623.15  # [K] boundary region 1 / region 3
T_25 = 1073.15  # [K] boundary region 2 / region 5
T_MAX_R5 = 2273.15  # [K]
P_13_SAT = 16.529164252605e6  # [Pa] p_sat(623.15 K)
P_23_MIN = C.B23_N[4] * 1e6  # [Pa] below it the B23 curve does not exist (vapour is region 2)

#: Upper bound [kg/m3] of a region-3 density iterate (the region-3 equation is unphysical
#: above about 900 kg/m3; its densities are below 760 kg/m3).
RHO3_MAX = 850.0

#: Half-widths [K] of the blending bands (see the module docstring).
BAND_13 = 0.5
BAND_23 = 0.5
BAND_25 = 0.5

#: A T within this distance [K] of T_sat(p) does not fix the state in pT() / h_pT.
T_SAT_BAND = 1e-6

#: ``status`` codes of a result, and their meaning.
STATUS_OK = 0
STATUS_TEXT = {
    1: "p or h is not finite",
    2: f"p below the IF97 range (p >= {P_MIN} Pa, the saturation pressure at 273.15 K)",
    3: "p above the IF97 limit of 100 MPa",
    4: "T would be below 273.15 K, the lower limit of IF97",
    5: "T would be above the IF97 limit (2273.15 K up to 50 MPa, 1073.15 K above)",
    6: "T is the saturation temperature at this p: p and T do not fix the state",
    7: "no convergence of the IF97 iteration",
}

# record rows: a (7, N) array holds these single-phase quantities at (p, T)
_V, _H, _S, _VT, _VP, _HT, _HP = range(7)


def _table(prefix: str):
    I = getattr(C, prefix + "_I")  # noqa: E741 (IF97 notation)
    J = getattr(C, prefix + "_J")
    N = getattr(C, prefix + "_N")
    M = np.stack([np.ones_like(I), I, J, I * (I - 1.0), J * (J - 1.0), I * J], axis=1)
    return I, J, N, M, I.astype(np.int64), J.astype(np.int64)


_R1 = _table("R1")
_R2 = _table("R2")
_R3 = _table("R3")
_R5 = _table("R5")
_T1PH = _table("T1PH")
_T2APH = _table("T2APH")
_T2BPH = _table("T2BPH")
_T2CPH = _table("T2CPH")
_T3APH = _table("T3APH")
_T3BPH = _table("T3BPH")
_V3APH = _table("V3APH")
_V3BPH = _table("V3BPH")
_R2_ID = np.stack([C.R2_N0, C.R2_N0 * C.R2_J0, C.R2_N0 * C.R2_J0 * (C.R2_J0 - 1.0)], axis=1)
_R5_ID = np.stack([C.R5_N0, C.R5_N0 * C.R5_J0, C.R5_N0 * C.R5_J0 * (C.R5_J0 - 1.0)], axis=1)


def _sums(a, b, tab):
    """Columns of sum n a^I b^J times [1, I, J, I(I-1), J(J-1), I J]; a, b > 0, shape (N, 6)."""
    I, J, N, M, _, _ = tab  # noqa: E741
    E = N * np.exp(np.multiply.outer(np.log(a), I) + np.multiply.outer(np.log(b), J))
    return E @ M


def _poly(a, b, tab):
    """sum n a^I b^J for bases of any sign (integer exponents), shape (N,)."""
    I, J, N, _, Ii, Ji = tab  # noqa: E741
    a = np.where(a == 0.0, 1e-300, a)
    b = np.where(b == 0.0, 1e-300, b)
    E = np.exp(np.multiply.outer(np.log(np.abs(a)), I) + np.multiply.outer(np.log(np.abs(b)), J))
    neg = np.multiply.outer(a < 0.0, Ii % 2 == 1) ^ np.multiply.outer(b < 0.0, Ji % 2 == 1)
    return np.where(neg, -E, E) @ N


def _smooth(t):
    """Quintic smoothstep S(t) and S'(t), t clipped to [0, 1]."""
    t = np.clip(t, 0.0, 1.0)
    return t * t * t * (10.0 + t * (-15.0 + 6.0 * t)), 30.0 * t * t * (1.0 - t) ** 2


# ------------------------------------------------------------- region 4
_N4 = C.R4_N


def p_sat(T):
    """Saturation pressure [Pa] at T [K] (IF97 eq. 30), 273.15 K <= T <= 647.096 K."""
    return _psat_and_slope(np.asarray(T, dtype=float))[0]


def _psat_and_slope(T):
    """p_sat(T) [Pa] and dp_sat/dT [Pa/K] (eq. 30 and its analytic derivative)."""
    n = _N4
    th = T + n[8] / (T - n[9])
    dth = 1.0 - n[8] / (T - n[9]) ** 2
    A = th * th + n[0] * th + n[1]
    B = n[2] * th * th + n[3] * th + n[4]
    Cc = n[5] * th * th + n[6] * th + n[7]
    dA = 2.0 * th + n[0]
    dB = 2.0 * n[2] * th + n[3]
    dC = 2.0 * n[5] * th + n[6]
    D = np.sqrt(B * B - 4.0 * A * Cc)
    dD = (B * dB - 2.0 * (dA * Cc + A * dC)) / D
    den = -B + D
    q = 2.0 * Cc / den
    dq = (2.0 * dC * den - 2.0 * Cc * (-dB + dD)) / (den * den)
    return q**4 * 1e6, 4.0 * q**3 * dq * dth * 1e6


def T_sat(p):
    """Saturation temperature [K] at p [Pa] (IF97 eq. 31), 611.213 Pa <= p <= 22.064 MPa."""
    n = _N4
    beta = (np.asarray(p, dtype=float) * 1e-6) ** 0.25
    E = beta * beta + n[2] * beta + n[5]
    F = n[0] * beta * beta + n[3] * beta + n[6]
    G = n[1] * beta * beta + n[4] * beta + n[7]
    D = 2.0 * G / (-F - np.sqrt(F * F - 4.0 * E * G))
    return 0.5 * (n[9] + D - np.sqrt((n[9] + D) ** 2 - 4.0 * (n[8] + n[9] * D)))


def T_b23(p):
    """Temperature [K] of the region 2/3 boundary (B23, IF97 eq. 6) at p [Pa] >= 13.92 MPa."""
    n = C.B23_N
    return n[3] + np.sqrt(np.maximum(np.asarray(p, dtype=float) * 1e-6 - n[4], 0.0) / n[2])


def _dTb23_dp(p):
    n = C.B23_N
    root = np.sqrt(np.maximum(p * 1e-6 - n[4], 1e-30) / n[2])
    return 1e-6 / (2.0 * n[2] * root)


# ---------------------------------------------------------- Gibbs regions
def _gibbs_record(p, T, tau, p_star, T_star, g, g_p, g_pp, g_t, g_tt, g_pt):
    rec = np.empty((7, p.size))
    rec[_V] = R * T * g_p / p_star
    rec[_H] = R * T_star * g_t
    rec[_S] = R * (tau * g_t - g)
    rec[_VT] = R * (g_p - tau * g_pt) / p_star
    rec[_VP] = R * T * g_pp / p_star**2
    rec[_HT] = -R * tau * tau * g_tt
    rec[_HP] = R * T_star * g_pt / p_star
    return rec


def region1(p, T):
    """Region 1 record (7, N): v, h, s, (dv/dT)_p, (dv/dp)_T, cp, (dh/dp)_T at (p [Pa], T [K])."""
    pi = p / 16.53e6
    tau = 1386.0 / T
    a = 7.1 - pi
    b = tau - 1.222
    S = _sums(a, b, _R1)
    return _gibbs_record(
        p,
        T,
        tau,
        16.53e6,
        1386.0,
        S[:, 0],
        -S[:, 1] / a,
        S[:, 3] / (a * a),
        S[:, 2] / b,
        S[:, 4] / (b * b),
        -S[:, 5] / (a * b),
    )


def _gibbs_ideal_residual(p, T, p_star, T_star, ideal, tab, tau_shift):
    pi = p / p_star
    tau = T_star / T
    # ideal part: ln(pi) + sum n0 tau^J0
    J0 = ideal[:, 1] / np.where(ideal[:, 0] != 0.0, ideal[:, 0], 1.0)
    P0 = np.power(tau[:, None], J0)
    G0 = P0 @ ideal
    b = tau - tau_shift
    S = _sums(pi, b, tab)
    return _gibbs_record(
        p,
        T,
        tau,
        p_star,
        T_star,
        np.log(pi) + G0[:, 0] + S[:, 0],
        1.0 / pi + S[:, 1] / pi,
        -1.0 / (pi * pi) + S[:, 3] / (pi * pi),
        G0[:, 1] / tau + S[:, 2] / b,
        G0[:, 2] / (tau * tau) + S[:, 4] / (b * b),
        S[:, 5] / (pi * b),
    )


def region2(p, T):
    """Region 2 record (7, N) at (p [Pa], T [K]); see :func:`region1` for the rows."""
    return _gibbs_ideal_residual(p, T, 1e6, 540.0, _R2_ID, _R2, 0.5)


def region5(p, T):
    """Region 5 record (7, N) at (p [Pa], T [K]); see :func:`region1` for the rows."""
    return _gibbs_ideal_residual(p, T, 1e6, 1000.0, _R5_ID, _R5, 0.0)


# --------------------------------------------------------------- region 3
def region3_rhoT(rho, T, full=False):
    """Region 3 at (rho [kg/m3], T [K]): (p [Pa], (dp/drho)_T, record (7, N) at (p, T)).

    With ``full``, also ((dp/dT)_rho, (dh/drho)_T, (dh/dT)_rho) as a fourth item.
    """
    delta = rho / RHO_C
    tau = T_C / T
    S = _sums(delta, tau, _R3)
    n1 = C.R3_N1
    phi = n1 * np.log(delta) + S[:, 0]
    f_d = (n1 + S[:, 1]) / delta
    f_dd = (-n1 + S[:, 3]) / (delta * delta)
    f_t = S[:, 2] / tau
    f_tt = S[:, 4] / (tau * tau)
    f_dt = S[:, 5] / (delta * tau)
    RT = R * T
    p = rho * RT * delta * f_d
    p_r = RT * (2.0 * delta * f_d + delta * delta * f_dd)
    p_T = rho * R * (delta * f_d - delta * tau * f_dt)
    h_r = RT * (tau * f_dt + f_d + delta * f_dd) / RHO_C
    h_Tr = R * (-tau * tau * f_tt + delta * f_d - delta * tau * f_dt)
    rho_p = 1.0 / p_r
    rho_T = -p_T / p_r
    v = 1.0 / rho
    rec = np.empty((7, rho.size))
    rec[_V] = v
    rec[_H] = RT * (tau * f_t + delta * f_d)
    rec[_S] = R * (tau * f_t - phi)
    rec[_VT] = -rho_T * v * v
    rec[_VP] = -rho_p * v * v
    rec[_HT] = h_Tr + h_r * rho_T
    rec[_HP] = h_r * rho_p
    if full:
        return p, p_r, rec, (p_T, h_r, h_Tr)
    return p, p_r, rec


# auxiliary saturated densities (IAPWS-95 auxiliary equations, Wagner & Pruss 2002), used
# only as starting values of the region-3 density iteration
_B_LIQ = (1.99274064, 1.09965342, -0.510839303, -1.75493479, -45.5170352, -6.74694450e5)
_E_LIQ = (1 / 3, 2 / 3, 5 / 3, 16 / 3, 43 / 3, 110 / 3)
_C_VAP = (-2.03150240, -2.68302940, -5.38626492, -17.2991605, -44.7586581, -63.9201063)
_E_VAP = (2 / 6, 4 / 6, 8 / 6, 18 / 6, 37 / 6, 71 / 6)


def _rho_sat_guess(T, side):
    """Starting density [kg/m3] on the liquid (side > 0) or vapour (side < 0) branch at T < T_c.

    The auxiliary equations (1/3-power scaling) put the start outside the IF97 saturated
    density near T_c (mean-field scaling), on the side where Newton's method converges
    monotonically; the factor 1.05 keeps it there further from T_c.
    """
    th = np.maximum(1.0 - T / T_C, 0.0)
    liq = 1.0 + sum(b * th**e for b, e in zip(_B_LIQ, _E_LIQ, strict=True))
    vap = np.exp(sum(c * th**e for c, e in zip(_C_VAP, _E_VAP, strict=True)))
    return RHO_C * np.where(side > 0, 1.0 + 1.05 * (liq - 1.0), 1.0 - 1.05 * (1.0 - vap))


def _rho3_solve(p, T, rho, side):
    """Solve p3(rho, T) = p for rho on the branch ``side`` (+1 liquid, -1 vapour, 0 T >= T_c).

    Newton's method from ``rho`` (NaN entries start from the auxiliary saturated density,
    or the middle of the bracket for side 0), with the step limited to 20 % of rho; for
    side 0, where p3 is monotone in rho, the bracket [1, ``RHO3_MAX``] kg/m3 is kept and a step
    that leaves it is replaced by a bisection. Returns (rho, record, converged mask).
    """
    n = p.size
    rho = rho.copy()
    miss = ~np.isfinite(rho)
    if miss.any():
        sub = miss & (side != 0)
        rho[sub] = _rho_sat_guess(T[sub], side[sub])
        rho[miss & (side == 0)] = RHO_C
    lo = np.full(n, 1.0)
    hi = np.full(n, RHO3_MAX)
    rec = np.empty((7, n))
    conv = np.zeros(n, dtype=bool)
    idx = np.arange(n)
    for it in range(80):
        pp, pr, r = region3_rhoT(rho[idx], T[idx])
        f = pp - p[idx]
        rec[:, idx] = r
        good = pr > 0.0
        step = np.where(good, f / np.where(good, pr, 1.0), 0.0)
        rtol = 2e-14 if it < 6 else 1e-12  # the noise floor of p3 is about 1e-13 p
        done = good & ((np.abs(f) <= 2e-13 * p[idx]) | (np.abs(step) <= rtol * rho[idx]))
        conv[idx[done]] = True
        keep = ~done
        idx, f, step, good = idx[keep], f[keep], step[keep], good[keep]
        if idx.size == 0:
            break
        r_old = rho[idx]
        sd = side[idx]
        lim = 0.2 * r_old
        new = r_old - np.clip(step, -lim, lim)
        # unstable branch (dp/drho <= 0): move towards the branch asked for
        bad = ~good
        new = np.where(bad & (sd > 0), r_old * 1.05, new)
        new = np.where(bad & (sd < 0), r_old * 0.95, new)
        new = np.where(bad & (sd == 0), np.where(f < 0.0, r_old * 1.05, r_old * 0.95), new)
        # side 0: keep the bracket, bisect when Newton leaves it
        s0 = sd == 0
        lo_i = np.where(s0 & (f < 0.0), r_old, lo[idx])
        hi_i = np.where(s0 & (f > 0.0), r_old, hi[idx])
        lo[idx] = lo_i
        hi[idx] = hi_i
        out = s0 & ((new <= lo_i) | (new >= hi_i))
        new = np.where(out, 0.5 * (lo_i + hi_i), new)
        rho[idx] = np.clip(new, 1.0, RHO3_MAX)
    return rho, rec, conv


# ------------------------------------------------------ blended formulations
def _blend(A, B, w, w_T, w_p):
    """(1 - w) A + w B with the derivative corrections of w(T, p) on v and h rows."""
    out = A + w * (B - A)
    dv = B[_V] - A[_V]
    dh = B[_H] - A[_H]
    out[_VT] += w_T * dv
    out[_HT] += w_T * dh
    out[_VP] += w_p * dv
    out[_HP] += w_p * dh
    return out


def _root_side(p, T, liquid_formula, rho_guess):
    """Branch of the region-3 density: +1 liquid, -1 vapour, 0 for T >= T_c (one root).

    Below p_c the phase decides. At p >= p_c and T < T_c the isotherm of the region-3
    equation is monotone except within a few Pa of p_c (its critical point and the
    region-4 T_sat(p_c) differ slightly); there the branch follows the starting density.
    """
    below = T < T_C
    sup = p >= P_C
    liq = np.where(sup, ~(rho_guess < RHO_C), liquid_formula)
    return np.where(below, np.where(liq, 1, -1), 0).astype(np.int8)


def _eval(p, T, liquid_formula, rho3):
    """Blended single-phase record (7, N), region-3 density and region code at (p, T).

    ``liquid_formula`` selects the liquid-side blend (regions 1 and 3 around 623.15 K)
    or the vapour-side blend (regions 3 and 2 around T_B23(p), regions 2 and 5 above
    1073.15 K). ``rho3`` carries region-3 starting densities (NaN: none) and is updated.
    Returns (record, rho3, region, converged).
    """
    n = p.size
    L = liquid_formula
    V = ~L
    # weights
    w13, d13 = _smooth((T - (T_13 - BAND_13)) / (2.0 * BAND_13))
    w13_T = d13 / (2.0 * BAND_13)
    has_b23 = p > P_23_MIN
    tb = T_b23(p)
    w23, d23 = _smooth((T - (tb - BAND_23)) / (2.0 * BAND_23))
    w23 = np.where(has_b23, w23, 1.0)
    d23 = np.where(has_b23, d23, 0.0)
    w23_T = d23 / (2.0 * BAND_23)
    w23_p = -w23_T * np.where(has_b23, _dTb23_dp(p), 0.0)
    w25, d25 = _smooth((T - T_25) / (2.0 * BAND_25))
    w25_T = d25 / (2.0 * BAND_25)

    need1 = L & (w13 < 1.0)
    need3 = (L & (w13 > 0.0)) | (V & (w23 < 1.0))
    need2 = V & (w23 > 0.0) & (w25 < 1.0)
    need5 = V & (w25 > 0.0)

    zeros = np.zeros((7, n))
    r1 = zeros.copy()
    r2 = zeros.copy()
    r3 = zeros.copy()
    r5 = zeros.copy()
    if need1.any():
        r1[:, need1] = region1(p[need1], T[need1])
    if need2.any():
        r2[:, need2] = region2(p[need2], T[need2])
    if need5.any():
        r5[:, need5] = region5(p[need5], T[need5])
    rho3 = rho3.copy()
    conv = np.ones(n, dtype=bool)
    if need3.any():
        # start from the neighbouring formulation inside a band when nothing better is known
        start = rho3[need3]
        nb1 = (need1 & need3)[need3]
        nb2 = (need2 & need3)[need3]
        v1 = np.where(nb1, r1[_V, need3], 1.0)
        v2 = np.where(nb2, r2[_V, need3], 1.0)
        start = np.where(~np.isfinite(start) & nb1, 1.0 / v1, start)
        start = np.where(~np.isfinite(start) & nb2, 1.0 / v2, start)
        side = _root_side(p[need3], T[need3], L[need3], start)
        rr, rec3, ok3 = _rho3_solve(p[need3], T[need3], start, side)
        rho3[need3] = rr
        r3[:, need3] = rec3
        conv[need3] = ok3

    liq = _blend(r1, r3, w13, w13_T, 0.0)
    r25 = _blend(r2, r5, w25, w25_T, 0.0)
    vap = _blend(r3, r25, w23, w23_T, w23_p)
    rec = np.where(L, liq, vap)
    region = np.where(
        L,
        np.where(w13 < 0.5, 1, 3),
        np.where(w23 < 0.5, 3, np.where(w25 < 0.5, 2, 5)),
    ).astype(np.int8)
    return rec, rho3, region, conv


def _T_mid(p):
    """A temperature [K] inside region 3 above p_c: where the two blends meet (both pure 3)."""
    return 0.5 * (T_13 + T_b23(p))


# ------------------------------------------------------ backward equations
def _T1_ph(p, h):
    return _poly(p * 1e-6, h / 2.5e6 + 1.0, _T1PH)


def _T2_ph(p, h):
    """IF97 T(p, h) for region 2 with the 2a/2b (4 MPa) and 2b/2c (B2bc) boundaries."""
    pm = p * 1e-6
    eta = h / 2e6
    n = C.B2BC_N
    h_bc = (n[3] + np.sqrt(np.maximum(pm - n[4], 0.0) / n[2])) * 1e3
    T = np.empty_like(p)
    a = pm <= 4.0
    b = ~a & (h >= h_bc)
    c = ~a & ~b
    if a.any():
        T[a] = _poly(pm[a], eta[a] - 2.1, _T2APH)
    if b.any():
        T[b] = _poly(pm[b] - 2.0, eta[b] - 2.6, _T2BPH)
    if c.any():
        T[c] = _poly(pm[c] + 25.0, eta[c] - 1.8, _T2CPH)
    return T


def h_3ab(p):
    """Enthalpy [J/kg] of the boundary between subregions 3a and 3b (SR3-03 eq. 1)."""
    pm = np.asarray(p, dtype=float) * 1e-6
    n = C.H3AB_N
    return (n[0] + pm * (n[1] + pm * (n[2] + pm * n[3]))) * 1e3


def _T3_v3_ph(p, h):
    """SR3-03 backward T(p, h) [K] and v(p, h) [m3/kg] for region 3."""
    pi = p / 100e6
    a = h <= h_3ab(p)
    T = np.empty_like(p)
    v = np.empty_like(p)
    if a.any():
        T[a] = 760.0 * _poly(pi[a] + 0.240, h[a] / 2300e3 - 0.615, _T3APH)
        v[a] = 0.0028 * _poly(pi[a] + 0.128, h[a] / 2100e3 - 0.727, _V3APH)
    b = ~a
    if b.any():
        T[b] = 860.0 * _poly(pi[b] + 0.298, h[b] / 2800e3 - 0.720, _T3BPH)
        v[b] = 0.0088 * _poly(pi[b] + 0.0661, h[b] / 2800e3 - 0.720, _V3BPH)
    return T, v


def backward_T_ph(p, h, region):
    """The IF97 backward equation T(p, h) [K] of ``region`` (1, 2 or 3) at p [Pa], h [J/kg].

    Region 1: IF97 eq. 11; region 2: eqs. 22 to 24 (subregions by p = 4 MPa and B2bc);
    region 3: SR3-03 eqs. 2 and 3 (subregions by h_3ab(p)). No refinement.
    """
    p = np.atleast_1d(np.asarray(p, dtype=float))
    h = np.atleast_1d(np.asarray(h, dtype=float))
    if region == 1:
        return _T1_ph(p, h)
    if region == 2:
        return _T2_ph(p, h)
    return _T3_v3_ph(p, h)[0]


def backward_v3_ph(p, h):
    """SR3-03 backward v(p, h) [m3/kg] for region 3 (eqs. 4 and 5), no refinement."""
    p = np.atleast_1d(np.asarray(p, dtype=float))
    h = np.atleast_1d(np.asarray(h, dtype=float))
    return _T3_v3_ph(p, h)[1]


def _T_guess(p, h, kind):
    """Starting T [K] and region-3 density [kg/m3] (NaN: none) for the T(p, h) iteration.

    kind: +1 liquid, -1 vapour, 0 supercritical. Liquid and supercritical try region 1,
    then region 3 above 623.15 K; vapour and supercritical try region 2, region 3 below
    T_B23(p).
    """
    n = p.size
    T = np.full(n, np.nan)
    rho = np.full(n, np.nan)
    lq = kind >= 0
    vp = ~lq
    if lq.any():
        T[lq] = _T1_ph(p[lq], h[lq])
    if vp.any():
        T[vp] = _T2_ph(p[vp], h[vp])
    hi_p = p > P_13_SAT
    use3 = hi_p & ((lq & (T > T_13)) | (vp & (T < T_b23(p))))
    if use3.any():
        T3, v3 = _T3_v3_ph(p[use3], h[use3])
        T[use3] = T3
        rho[use3] = 1.0 / v3
    use2 = (kind == 0) & use3 & (T > T_b23(p))
    if use2.any():
        T[use2] = _T2_ph(p[use2], h[use2])
        rho[use2] = np.nan
    return T, rho


# ----------------------------------------------------------------- results
class PhResult:
    """Arrays of the states at (p, h); every field has the shape of the broadcast inputs.

    Fields (NaN where ``ok`` is False):

    - ``p`` [Pa], ``h`` [J/kg]: the inputs (broadcast, float).
    - ``T`` [K] (T_sat(p) in the dome), ``rho`` [kg/m3], ``v`` [m3/kg] = 1/rho,
      ``u`` [J/kg] = h - p/rho exactly, ``s`` [J/(kg K)].
    - ``cp`` [J/(kg K)]: (dh/dT)_p; ``inf`` in the two-phase dome.
    - ``x`` [-]: vapour quality in the dome (0 <= x <= 1), NaN outside it.
    - ``drho_dp_h`` [kg/(m3 Pa)], ``drho_dh_p`` [kg2/(m3 J)]: (drho/dp)_h, (drho/dh)_p
      (the homogeneous-mixture derivatives in the dome).
    - ``region`` (int8): 1, 2, 3, 5 (single phase; in a blending band, the formulation of
      larger weight), 4 (two-phase), 0 (not ok).
    - ``ok`` (bool), ``status`` (int8, 0 = ok, else a key of ``STATUS_TEXT``).
    """

    __slots__ = (
        "p",
        "h",
        "T",
        "rho",
        "v",
        "u",
        "s",
        "cp",
        "x",
        "drho_dp_h",
        "drho_dh_p",
        "region",
        "ok",
        "status",
    )

    def __len__(self) -> int:
        return self.p.size

    def raise_first_bad(self, label: str = "Water (IF97)") -> None:
        """Raise :class:`PropertyError` for the first state that is not ok (no-op if all are)."""
        if self.ok.all():
            return
        i = int(np.flatnonzero(~self.ok.ravel())[0])
        code = int(self.status.ravel()[i])
        raise PropertyError(
            label,
            float(self.p.ravel()[i]),
            float(self.h.ravel()[i]),
            "state",
            STATUS_TEXT.get(code, "invalid state") + f" (state index {i})",
        )


def _empty_result(p, h):
    n = p.size
    r = PhResult()
    r.p = p
    r.h = h
    for f in ("T", "rho", "v", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p"):
        setattr(r, f, np.full(n, np.nan))
    r.region = np.zeros(n, dtype=np.int8)
    r.status = np.zeros(n, dtype=np.int8)
    r.ok = np.zeros(n, dtype=bool)
    return r


def _fill_single(r, sel, p, h, T, rec, region):
    v = rec[_V]
    cp = rec[_HT]
    vT = rec[_VT]
    rho = 1.0 / v
    r.T[sel] = T
    r.v[sel] = v
    r.rho[sel] = rho
    r.u[sel] = h - p / rho  # exactly h - p / rho (FluidState's promise)
    r.s[sel] = rec[_S]
    r.cp[sel] = cp
    r.drho_dh_p[sel] = -vT / (v * v * cp)
    r.drho_dp_h[sel] = -(rec[_VP] - vT * rec[_HP] / cp) / (v * v)
    r.region[sel] = region


def _saturation(p):
    """Saturated liquid and vapour records (7, N) at p < p_c, T_sat and dT_sat/dp."""
    Ts = T_sat(p)
    _, dps = _psat_and_slope(Ts)
    n = p.size
    nan = np.full(n, np.nan)
    recL, _, _, okL = _eval(p, Ts, np.ones(n, dtype=bool), nan)
    recV, _, _, okV = _eval(p, Ts, np.zeros(n, dtype=bool), nan)
    return Ts, 1.0 / dps, recL, recV, okL & okV


def saturation_enthalpies(p):
    """(h', h'') [J/kg] of saturated liquid and vapour at p [Pa]; NaN outside [P_MIN, p_c)."""
    p = np.atleast_1d(np.asarray(p, dtype=float))
    hl = np.full(p.shape, np.nan)
    hv = np.full(p.shape, np.nan)
    sel = (p >= P_MIN) & (p < P_C)
    if sel.any():
        _, _, recL, recV, _ = _saturation(p[sel])
        hl[sel] = recL[_H]
        hv[sel] = recV[_H]
    return hl, hv


def ph(p, h) -> PhResult:
    """All properties at pressure p [Pa] and specific enthalpy h [J/kg] (arrays, broadcast).

    See the module docstring for the method and :class:`PhResult` for the fields.
    """
    p, h = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(h, dtype=float))
    shape = p.shape
    p = p.ravel().copy()
    h = h.ravel().copy()
    r = _empty_result(p, h)
    st = r.status
    st[~(np.isfinite(p) & np.isfinite(h))] = 1
    st[(st == 0) & (p < P_MIN)] = 2
    st[(st == 0) & (p > P_MAX)] = 3
    good = st == 0

    kind = np.zeros(p.size, dtype=np.int8)  # +1 liquid, -1 vapour, 0 supercritical, 4 two-phase
    Tlo = np.full(p.size, T_MIN)
    Thi = np.where(p <= P_R5_MAX, T_MAX_R5, T_25)
    sub = good & (p < P_C)
    if sub.any():
        ps = p[sub]
        hs = h[sub]
        Ts, dTs, recL, recV, _ = _saturation(ps)
        hL = recL[_H]
        hV = recV[_H]
        k = np.where(hs < hL, 1, np.where(hs > hV, -1, 4)).astype(np.int8)
        # within about 1 Pa of p_c the region-3 saturated states cross (h' >= h''): the
        # dome has closed there, the state is treated as supercritical
        k[~(hV > hL)] = 0
        kind[sub] = k
        Thi[sub] = np.where(k == 1, Ts, Thi[sub])
        Tlo[sub] = np.where(k == -1, Ts, Tlo[sub])
        two = k == 4
        if two.any():
            ix = np.flatnonzero(sub)[two]
            _fill_two_phase(r, ix, ps[two], hs[two], Ts[two], dTs[two], recL[:, two], recV[:, two])

    single = good & (kind != 4)
    if single.any():
        ix = np.flatnonzero(single)
        _solve_single(r, ix, p[ix], h[ix], kind[ix], Tlo[ix], Thi[ix])

    r.ok = r.status == 0
    bad = ~r.ok
    if bad.any():
        for f in ("T", "rho", "v", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p"):
            getattr(r, f)[bad] = np.nan
        r.region[bad] = 0
    if shape != p.shape:
        for f in PhResult.__slots__:
            setattr(r, f, getattr(r, f).reshape(shape))
    return r


def _fill_two_phase(r, ix, p, h, Ts, dTs, recL, recV):
    hL, hV = recL[_H], recV[_H]
    vL, vV = recL[_V], recV[_V]
    dh = hV - hL
    dv = vV - vL
    x = (h - hL) / dh
    v = vL + x * dv
    rho = 1.0 / v
    # derivatives along the saturation line: X_p + X_T dT_sat/dp
    vLp = recL[_VP] + recL[_VT] * dTs
    vVp = recV[_VP] + recV[_VT] * dTs
    hLp = recL[_HP] + recL[_HT] * dTs
    hVp = recV[_HP] + recV[_HT] * dTs
    r.T[ix] = Ts
    r.v[ix] = v
    r.rho[ix] = rho
    r.u[ix] = h - p / rho
    r.s[ix] = recL[_S] + x * (recV[_S] - recL[_S])
    r.cp[ix] = np.inf
    r.x[ix] = x
    r.drho_dh_p[ix] = -rho * rho * dv / dh
    r.drho_dp_h[ix] = -rho * rho * (vLp + x * (vVp - vLp) - dv * (hLp + x * (hVp - hLp)) / dh)
    r.region[ix] = 4


def _solve_region3(p, h, rho, T):
    """Newton's method on (rho, T) for p3(rho, T) = p, h3(rho, T) = h (pure region 3).

    Well conditioned up to the critical point, where (dp/drho)_T = 0 makes rho(p, T)
    ill-conditioned. Steps are limited to 20 % in rho and 10 K in T. Returns
    (T, record, region-3 density, converged mask).
    """
    n = p.size
    rec = np.empty((7, n))
    conv = np.zeros(n, dtype=bool)
    rho = rho.copy()
    T = T.copy()
    idx = np.arange(n)
    tol_h = 2e-14 * np.abs(h) + 1e-9
    for it in range(30):
        pp, pr, rc, (pT_, hr, hT) = region3_rhoT(rho[idx], T[idx], full=True)
        rec[:, idx] = rc
        fp = pp - p[idx]
        fh = rc[_H] - h[idx]
        det = pr * hT - pT_ * hr
        dr = (-fp * hT + pT_ * fh) / det
        dT = (-fh * pr + hr * fp) / det
        rt = 2e-14 if it < 6 else 1e-12
        small = (np.abs(dr) <= rt * rho[idx]) & (np.abs(dT) <= rt * T[idx])
        fin = ((np.abs(fp) <= 2e-13 * p[idx]) & (np.abs(fh) <= tol_h[idx])) | small
        conv[idx[fin]] = True
        keep = ~fin & np.isfinite(dr) & np.isfinite(dT)
        idx, dr, dT = idx[keep], dr[keep], dT[keep]
        if idx.size == 0:
            break
        lim = 0.2 * rho[idx]
        rho[idx] = np.clip(rho[idx] + np.clip(dr, -lim, lim), 1.0, RHO3_MAX)
        T[idx] = T[idx] + np.clip(dT, -10.0, 10.0)
    return T, rec, rho, conv


def _solve_single(r, ix, p, h, kind, lo, hi):
    """Safeguarded Newton for T on the blended h(p, T) = h; fills r at ix."""
    n = p.size
    # range: h below h(p, 273.15 K) or above h(p, T_max)
    T0, rho0 = _T_guess(p, h, kind)
    liquid_side = kind > 0
    chk_lo = ~(T0 > T_MIN + 1.0)
    if chk_lo.any():
        q = np.flatnonzero(chk_lo)
        rec, _, _, _ = _eval(p[q], np.full(q.size, T_MIN), np.ones(q.size, bool), rho0[q])
        below = h[q] < rec[_H]
        r.status[ix[q[below]]] = 4
    chk_hi = ~(T0 < hi - 2.0) & (kind <= 0)
    if chk_hi.any():
        q = np.flatnonzero(chk_hi)
        rec, _, _, _ = _eval(p[q], hi[q], np.zeros(q.size, bool), rho0[q])
        above = h[q] > rec[_H]
        r.status[ix[q[above]]] = 5
    T = np.clip(np.where(np.isfinite(T0), T0, 0.5 * (lo + hi)), lo, hi)
    rho3 = rho0
    done = np.zeros(n, dtype=bool)
    # pure region 3 (started from the SR3-03 backward equations): Newton on (rho, T)
    q = np.flatnonzero(
        (r.status[ix] == 0)
        & np.isfinite(rho0)
        & (T0 > T_13 + BAND_13 + 1.0)
        & (T0 < T_b23(p) - BAND_23 - 1.0)
    )
    if q.size:
        T3, rec3, rr3, ok3 = _solve_region3(p[q], h[q], rho0[q], T0[q])
        inside = ok3 & (T3 >= T_13 + BAND_13) & (T3 <= T_b23(p[q]) - BAND_23)
        inside &= (T3 >= lo[q]) & (T3 <= hi[q])
        if inside.any():
            qi = q[inside]
            reg3 = np.full(qi.size, 3, dtype=np.int8)
            _fill_single(r, ix[qi], p[qi], h[qi], T3[inside], rec3[:, inside], reg3)
            done[qi] = True
    act = np.flatnonzero((r.status[ix] == 0) & ~done)
    dT_old = np.full(n, np.inf)
    tol = 2e-14 * np.abs(h) + 1e-9
    for it in range(60):
        if act.size == 0:
            break
        pa, Ta = p[act], T[act]
        L = np.where(kind[act] == 0, Ta < _T_mid(pa), liquid_side[act])
        rec, rr, reg, conv = _eval(pa, Ta, L, rho3[act])
        rho3[act] = rr
        g = rec[_H] - h[act]
        cp = rec[_HT]
        step = g / cp
        fin = conv & ((np.abs(g) <= tol[act]) | (np.abs(step) <= (2e-14 if it < 5 else 4e-13) * Ta))
        if fin.any():
            q = act[fin]
            _fill_single(r, ix[q], pa[fin], h[q], Ta[fin], rec[:, fin], reg[fin])
            done[q] = True
        keep = ~fin
        act, g, step, Ta = act[keep], g[keep], step[keep], Ta[keep]
        lo[act] = np.where(g < 0.0, Ta, lo[act])
        hi[act] = np.where(g > 0.0, Ta, hi[act])
        Tn = Ta - step
        outside = ~((Tn > lo[act]) & (Tn < hi[act])) | (np.abs(2.0 * step) > dT_old[act])
        dT_old[act] = np.where(outside, 0.5 * (hi[act] - lo[act]), np.abs(step))
        Tn = np.where(outside, 0.5 * (lo[act] + hi[act]), Tn)
        collapsed = hi[act] - lo[act] <= 4e-16 * hi[act]
        if collapsed.any():
            r.status[ix[act[collapsed]]] = 7
            act, Tn = act[~collapsed], Tn[~collapsed]
        T[act] = Tn
    r.status[ix[~done & (r.status[ix] == 0)]] = 7


# ----------------------------------------------------------- forward (p, T)
class PtResult:
    """Single-phase states at (p [Pa], T [K]): fields p, T, h, rho, v, u, s, cp,
    drho_dp_h, drho_dh_p, region, ok, status (as :class:`PhResult`)."""

    __slots__ = (
        "p",
        "T",
        "h",
        "rho",
        "v",
        "u",
        "s",
        "cp",
        "drho_dp_h",
        "drho_dh_p",
        "region",
        "ok",
        "status",
    )


def pT(p, T) -> PtResult:
    """Single-phase properties at p [Pa], T [K] (the blended formulation, as :func:`ph` uses).

    The phase is liquid for p > p_sat(T), vapour for p < p_sat(T) (T < T_c, p < p_c);
    ``status`` 6 where |T - T_sat(p)| <= ``T_SAT_BAND`` (the state is not fixed by p, T);
    4 and 5 below 273.15 K or above the upper limit; 2 and 3 for p out of range.
    """
    p, T = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(T, dtype=float))
    shape = p.shape
    p = p.ravel().copy()
    T = T.ravel().copy()
    n = p.size
    r = PtResult()
    r.p, r.T = p, T
    st = np.zeros(n, dtype=np.int8)
    st[~(np.isfinite(p) & np.isfinite(T))] = 1
    st[(st == 0) & (p < P_MIN)] = 2
    st[(st == 0) & (p > P_MAX)] = 3
    st[(st == 0) & (T < T_MIN)] = 4
    Tmax = np.where(p <= P_R5_MAX, T_MAX_R5, T_25)
    st[(st == 0) & (T > Tmax)] = 5
    sub = (st == 0) & (p < P_C)
    liquid = np.zeros(n, dtype=bool)
    if sub.any():
        Ts = T_sat(p[sub])
        s6 = np.abs(T[sub] - Ts) <= T_SAT_BAND
        st[np.flatnonzero(sub)[s6]] = 6
        liquid[sub] = T[sub] < Ts
    sc = (st == 0) & (p >= P_C)
    liquid[sc] = T[sc] < _T_mid(p[sc])
    good = st == 0
    for f in ("h", "rho", "v", "u", "s", "cp", "drho_dp_h", "drho_dh_p"):
        setattr(r, f, np.full(n, np.nan))
    r.region = np.zeros(n, dtype=np.int8)
    if good.any():
        q = np.flatnonzero(good)
        rec, _, reg, conv = _eval(p[q], T[q], liquid[q], np.full(q.size, np.nan))
        v = rec[_V]
        cp = rec[_HT]
        r.h[q] = rec[_H]
        r.v[q] = v
        r.rho[q] = 1.0 / v
        r.u[q] = rec[_H] - p[q] / r.rho[q]
        r.s[q] = rec[_S]
        r.cp[q] = cp
        r.drho_dh_p[q] = -rec[_VT] / (v * v * cp)
        r.drho_dp_h[q] = -(rec[_VP] - rec[_VT] * rec[_HP] / cp) / (v * v)
        r.region[q] = reg
        st[q[~conv]] = 7
    r.status = st
    r.ok = st == 0
    if shape != p.shape:
        for f in PtResult.__slots__:
            setattr(r, f, getattr(r, f).reshape(shape))
    return r
