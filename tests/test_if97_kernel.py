"""Tests of the vectorised IAPWS-IF97 kernel (dnasim.media.if97_kernel, if97_numba).

References: the verification tables of IAPWS R7-97(2012) (Tables 5, 7, 15, 24, 33, 35,
36, 42) and of IAPWS SR3-03(2014) (check values of T3(p, h) and v3(p, h)), transcribed
from the releases with their printed digits; CoolProp's IF97 and HEOS backends.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from dnasim.media import IF97Water, PropertyError, get_medium
from dnasim.media import if97_kernel as K
from dnasim.media import if97_numba as NB

# A value printed with 9 significant digits carries a rounding error of up to half a
# unit in the 9th digit, i.e. up to 5e-9 relative (for a leading digit 1: 5e-9 of
# 1.0..., for a leading 9: 5.6e-10). REL9 = 6e-9 accepts exactly that rounding.
REL9 = 6e-9


def rec(fn, p, T):
    return fn(np.array([float(p)]), np.array([float(T)]))[:, 0]


# --------------------------------------------------------------------------
# IF97 Table 5 (region 1), Table 15 (region 2), Table 42 (region 5):
# T [K], p [MPa], v [m3/kg], h [kJ/kg], u [kJ/kg], s [kJ/(kg K)], cp [kJ/(kg K)]
TABLE_5 = [
    (300.0, 3.0, 0.100215168e-2, 0.115331273e3, 0.112324818e3, 0.392294792, 0.417301218e1),
    (300.0, 80.0, 0.971180894e-3, 0.184142828e3, 0.106448356e3, 0.368563852, 0.401008987e1),
    (500.0, 3.0, 0.120241800e-2, 0.975542239e3, 0.971934985e3, 0.258041912e1, 0.465580682e1),
]
TABLE_15 = [
    (300.0, 0.0035, 0.394913866e2, 0.254991145e4, 0.241169160e4, 0.852238967e1, 0.191300162e1),
    (700.0, 0.0035, 0.923015898e2, 0.333568375e4, 0.301262819e4, 0.101749996e2, 0.208141274e1),
    (700.0, 30.0, 0.542946619e-2, 0.263149474e4, 0.246861076e4, 0.517540298e1, 0.103505092e2),
]
TABLE_42 = [
    (1500.0, 0.5, 0.138455090e1, 0.521976855e4, 0.452749310e4, 0.965408875e1, 0.261609445e1),
    (1500.0, 30.0, 0.230761299e-1, 0.516723514e4, 0.447495124e4, 0.772970133e1, 0.272724317e1),
    (2000.0, 30.0, 0.311385219e-1, 0.657122604e4, 0.563707038e4, 0.853640523e1, 0.288569882e1),
]
GIBBS_TABLES = (
    [(K.region1, *row) for row in TABLE_5]
    + [(K.region2, *row) for row in TABLE_15]
    + [(K.region5, *row) for row in TABLE_42]
)


@pytest.mark.parametrize("fn, T, p_MPa, v, h_kJ, u_kJ, s_kJ, cp_kJ", GIBBS_TABLES)
def test_forward_tables_gibbs_regions(fn, T, p_MPa, v, h_kJ, u_kJ, s_kJ, cp_kJ):
    """Tables 5, 15, 42 to their 9 printed digits, by the region's own function and
    through the public (blended) pT(): the table points lie outside every band."""
    p = p_MPa * 1e6
    r = rec(fn, p, T)
    assert r[K._V] == pytest.approx(v, rel=REL9)
    assert r[K._H] == pytest.approx(h_kJ * 1e3, rel=REL9)
    assert r[K._H] - p * r[K._V] == pytest.approx(u_kJ * 1e3, rel=REL9)
    assert r[K._S] == pytest.approx(s_kJ * 1e3, rel=REL9)
    assert r[K._HT] == pytest.approx(cp_kJ * 1e3, rel=REL9)
    f = K.pT(p, T)
    assert f.ok and f.h == r[K._H] and f.v == r[K._V]
    assert NB.h_pT_scalar(p, T) == (pytest.approx(r[K._H], rel=1e-14), 0)


# IF97 Table 33 (region 3): T [K], rho [kg/m3], p [MPa], h, u [kJ/kg], s, cp [kJ/(kg K)]
TABLE_33 = [
    (650.0, 500.0, 0.255837018e2, 0.186343019e4, 0.181226279e4, 0.405427273e1, 0.138935717e2),
    (650.0, 200.0, 0.222930643e2, 0.237512401e4, 0.226365868e4, 0.485438792e1, 0.446579342e2),
    (750.0, 500.0, 0.783095639e2, 0.225868845e4, 0.210206932e4, 0.446971906e1, 0.634165359e1),
]


@pytest.mark.parametrize("T, rho, p_MPa, h_kJ, u_kJ, s_kJ, cp_kJ", TABLE_33)
def test_forward_table_33_region_3(T, rho, p_MPa, h_kJ, u_kJ, s_kJ, cp_kJ):
    """Table 33 at (rho, T), and the density solved back from the printed p."""
    p, _, r = K.region3_rhoT(np.array([rho]), np.array([T]))
    assert p[0] == pytest.approx(p_MPa * 1e6, rel=REL9)
    assert r[K._H, 0] == pytest.approx(h_kJ * 1e3, rel=REL9)
    assert r[K._H, 0] - p[0] / rho == pytest.approx(u_kJ * 1e3, rel=REL9)
    assert r[K._S, 0] == pytest.approx(s_kJ * 1e3, rel=REL9)
    assert r[K._HT, 0] == pytest.approx(cp_kJ * 1e3, rel=REL9)
    # rho(p, T) from the rounded p: drho = (rho/p) dp / (rho (dp/drho) / p) <= 5e-9 times
    # the isothermal compressibility factor p / (rho dp/drho), below 20 at these points
    f = K.pT(p_MPa * 1e6, T)
    assert f.ok and f.region == 3
    assert f.rho == pytest.approx(rho, rel=1e-7)


def test_saturation_tables_35_36():
    """Table 35: p_sat(T); Table 36: T_sat(p) (9 printed digits)."""
    ps = K.p_sat(np.array([300.0, 500.0, 600.0]))
    assert ps == pytest.approx(
        np.array([0.353658941e-2, 0.263889776e1, 0.123443146e2]) * 1e6, rel=REL9
    )
    Ts = K.T_sat(np.array([0.1e6, 1e6, 10e6]))
    assert Ts == pytest.approx([0.372755919e3, 0.453035632e3, 0.584149488e3], rel=REL9)


def test_backward_table_7_region_1():
    """Table 7: T1(p, h) at (3 MPa, 500 kJ/kg), (80, 500), (80, 1500)."""
    T = K.backward_T_ph([3e6, 80e6, 80e6], [500e3, 500e3, 1500e3], 1)
    assert T == pytest.approx([0.391798509e3, 0.378108626e3, 0.611041229e3], rel=REL9)


def test_backward_table_24_region_2():
    """Table 24: T2(p, h) in subregions 2a, 2b, 2c."""
    p = np.array([0.001, 3.0, 3.0, 5.0, 5.0, 25.0, 40.0, 60.0, 60.0]) * 1e6
    h = np.array([3000, 3000, 4000, 3500, 4000, 3500, 2700, 2700, 3200]) * 1e3
    ref = [
        0.534433241e3,
        0.575373370e3,
        0.101077577e4,
        0.801299102e3,
        0.101531583e4,
        0.875279054e3,
        0.743056411e3,
        0.791137067e3,
        0.882756860e3,
    ]
    assert K.backward_T_ph(p, h, 2) == pytest.approx(ref, rel=REL9)


def test_backward_sr3_03_region_3():
    """SR3-03 check values of T3(p, h) and v3(p, h) (10 printed digits, so 6e-10)."""
    p = np.array([20.0, 50.0, 100.0, 20.0, 50.0, 100.0]) * 1e6
    h = np.array([1700, 2000, 2100, 2500, 2400, 2700]) * 1e3
    T_ref = [
        6.293083892e2,
        6.905718338e2,
        7.336163014e2,
        6.418418053e2,
        7.351848618e2,
        8.420460876e2,
    ]
    v_ref = [
        1.749903962e-3,
        1.908139035e-3,
        1.676229776e-3,
        6.670547043e-3,
        2.801244590e-3,
        2.404234998e-3,
    ]
    assert K.backward_T_ph(p, h, 3) == pytest.approx(T_ref, rel=6e-10)
    assert K.backward_v3_ph(p, h) == pytest.approx(v_ref, rel=6e-10)
    assert K.h_3ab(25e6) == pytest.approx(2095.936454e3, rel=6e-10)


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
def test_ph_reproduces_forward_tables(kernel):
    """(p, h) -> state at every forward-table point gives back the table's T and v.

    The printed h has a rounding error of up to 5e-9 relative, which moves T by up to
    5e-9 h / cp (3e-6 K at 2550 kJ/kg and cp = 1.9 kJ/(kg K)): 1e-5 K on T; v then
    carries 5e-9 (rounding) plus (dv/dT) dT / v (below 1e-8): 3e-8 relative.
    """
    rows = [(T, p * 1e6, v, h * 1e3) for T, p, v, h, *_ in TABLE_5 + TABLE_15 + TABLE_42]
    rows += [(T, p * 1e6, 1.0 / rho, h * 1e3) for T, rho, p, h, *_ in TABLE_33]
    T, p, v, h = (np.array(c) for c in zip(*rows, strict=True))
    r = K.ph(p, h) if kernel == "numpy" else NB.ph_arrays(p, h)
    assert r.ok.all()
    assert r.T == pytest.approx(T, abs=1e-5)
    # region 3 near the critical point: the compressibility amplifies the T error in v
    assert 1.0 / r.rho == pytest.approx(v, rel=3e-7)
    assert np.all(np.isnan(r.x))


# --------------------------------------------------------------------------
# Region boundaries: continuity, monotonicity, size of the blending change.
# IF97's own consistency requirements at region boundaries (Wagner et al., J. Eng. Gas
# Turbines Power 122 (2000), Table 3): |dv/v| <= 5e-4, |dh| <= 0.2 kJ/kg, |dcp/cp| <= 1 %,
# |ds| <= 0.2 J/(kg K).
IF97_TOL = {"v": 5e-4, "h": 200.0, "cp": 1e-2, "s": 0.2}


def _two_formulations(p, T, a, b):
    """Records of regions a and b at (p, T) (region 3 on the branch of the neighbour)."""
    pa, Ta = np.array([p]), np.array([T])
    out = []
    for reg in (a, b):
        if reg == 3:
            side = np.array([1 if 1 in (a, b) else -1], dtype=np.int8)
            _, r, ok = K._rho3_solve(pa, Ta, np.array([np.nan]), side)
            assert ok.all()
            out.append(r[:, 0])
        else:
            out.append({1: K.region1, 2: K.region2, 5: K.region5}[reg](pa, Ta)[:, 0])
    return out


BOUNDARIES = (
    [("1/3", p, lambda p: K.T_13, 1, 3) for p in (17e6, 20e6, 30e6, 50e6, 100e6)]
    + [("2/3", p, lambda p: float(K.T_b23(p)), 3, 2) for p in (17e6, 20e6, 30e6, 60e6, 100e6)]
    + [("2/5", p, lambda p: K.T_25, 2, 5) for p in (1e3, 1e5, 1e6, 1e7, 50e6)]
)


@pytest.mark.parametrize("name, p, Tb, a, b", BOUNDARIES)
def test_raw_boundary_inconsistency_within_if97_tolerance(name, p, Tb, a, b):
    """The two IF97 formulations differ on their boundary (that is what the blend
    smooths out), by less than IF97's consistency tolerances; the blended value lies
    between them, so the blend changes no value by more than that difference."""
    T = Tb(p)
    A, B = _two_formulations(p, T, a, b)
    assert abs(B[K._V] / A[K._V] - 1.0) <= IF97_TOL["v"]
    assert abs(B[K._H] - A[K._H]) <= IF97_TOL["h"]
    assert abs(B[K._HT] / A[K._HT] - 1.0) <= IF97_TOL["cp"]
    assert abs(B[K._S] - A[K._S]) <= IF97_TOL["s"]
    # inside the band (the 2/5 band starts at 1073.15 K): v, h, s between the two
    Tin = T + (K.BAND_25 if name == "2/5" else 0.3 * K.BAND_13)
    f = K.pT(p, Tin)
    A2, B2 = _two_formulations(p, Tin, a, b)
    for row, val in ((K._V, f.v), (K._H, f.h), (K._S, f.s)):
        lo, hi = sorted((A2[row], B2[row]))
        assert lo - 1e-12 * abs(hi) <= val <= hi + 1e-12 * abs(hi)


def _scan(p, T0, dT=2.0, n=2001, kernel="numpy"):
    hh = K.pT(np.full(2, p), np.array([T0 - dT, T0 + dT])).h
    h = np.linspace(hh[0], hh[1], n)
    r = K.ph(np.full(n, p), h) if kernel == "numpy" else NB.ph_arrays(np.full(n, p), h)
    assert r.ok.all()
    return h, r


SCANS = (
    [(p, K.T_13) for p in (20e6, 25e6, 50e6, 100e6)]
    + [(p, float(K.T_b23(p))) for p in (20e6, 25e6, 50e6, 100e6)]
    + [(p, K.T_25 + K.BAND_25) for p in (1e3, 1e5, 1e6, 1e7, 50e6)]
)


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
@pytest.mark.parametrize("p, T0", SCANS)
def test_continuous_and_monotone_across_boundaries(p, T0, kernel):
    """2001 enthalpies spanning T0 +- 2 K (each band fully inside): T rises and rho
    falls at every step, drho/dh < 0 and cp > 0 everywhere, and no step of rho exceeds
    what its derivative allows (a jump of the size of the raw IF97 inconsistency,
    e.g. 3e-5 of rho, would exceed it by orders of magnitude).

    Bound on a step: |drho| <= 1.01 max|drho/dh| dh: rho is C2, so over one step
    of dh (a few J/kg) the derivative changes by far less than 1 %.
    """
    h, r = _scan(p, T0, kernel=kernel)
    dh = h[1] - h[0]
    assert np.all(np.diff(r.T) > 0.0)
    assert np.all(np.diff(r.rho) < 0.0)
    assert np.all(r.drho_dh_p < 0.0) and np.all(r.cp > 0.0)
    slope = np.maximum(np.abs(r.drho_dh_p[1:]), np.abs(r.drho_dh_p[:-1]))
    assert np.all(np.abs(np.diff(r.rho)) <= 1.01 * slope * dh)
    # u, s continuous too (their slopes are T - p v ... bounded by 2 |du/dh| <= 2)
    assert np.all(np.abs(np.diff(r.u)) <= 2.0 * dh)
    assert np.all(np.abs(np.diff(r.s)) <= 2.0 * dh / r.T.min())


@pytest.mark.parametrize("p", [22.064e6, 22.1e6, 23e6, 25e6, 30e6])
def test_pseudo_critical_region_smooth(p):
    """Above p_c through the pseudo-critical region (and at p_c itself, through the
    critical point): T increasing, rho decreasing, bounded steps (as above, 2 % margin:
    near the critical point drho/dh changes fast)."""
    h = np.linspace(1.6e6, 2.8e6, 12001)
    r = K.ph(np.full(h.size, p), h)
    assert r.ok.all() and np.all(np.isnan(r.x))
    assert np.all(np.diff(r.T) >= 0.0) and np.all(np.diff(r.rho) < 0.0)
    slope = np.maximum(np.abs(r.drho_dh_p[1:]), np.abs(r.drho_dh_p[:-1]))
    assert np.all(np.abs(np.diff(r.rho)) <= 1.02 * slope * (h[1] - h[0]))


def test_saturation_enthalpies_numba_equals_numpy():
    """The compiled saturation enthalpies agree with the numpy kernel's, NaN outside
    [611.213 Pa, p_c) in both. Tolerance: 1e-12 relative plus 1e-12 of the largest
    value (h' passes near zero at 273 K); 1e-10 within 0.1 MPa of p_c, where the
    compressibility amplifies the 1e-13 round-off of the region-3 densities
    (measured 5e-11 at 22.063 MPa)."""
    p = np.concatenate([np.geomspace(500.0, 22.063e6, 400), [22.064e6, 30e6]])
    a = K.saturation_enthalpies(p)
    b = NB.saturation_arrays(p)
    for x, y in zip(a, b, strict=True):
        assert np.array_equal(np.isnan(x), np.isnan(y))
        ok = np.isfinite(x)
        rel = np.where(p[ok] > 21.964e6, 1e-10, 1e-12)
        assert np.all(np.abs(x[ok] - y[ok]) <= rel * np.abs(x[ok]) + 1e-12 * np.abs(x[ok]).max())
    assert np.isnan(a[0][0]) and np.isnan(a[0][-1]) and np.isnan(a[0][-2])


def test_saturation_lines_continuous_across_16_5_MPa():
    """h'(p) and h''(p) with steps of 50 Pa through 16.529 MPa, where the saturated
    liquid passes from region 1 to region 3 and the vapour from 2 to 3: every step is
    within 1 % of its neighbours (both are smooth; the raw IF97 difference there, tens
    of J/kg, would be 10 times the step)."""
    p = np.linspace(16.3e6, 16.8e6, 10001)
    hl, hv = K.saturation_enthalpies(p)
    for y in (hl, hv):
        d = np.diff(y)
        assert np.all(np.abs(d[1:] / d[:-1] - 1.0) < 0.01)


@pytest.mark.parametrize("p", [611.3, 1e3, 1e5, 1e6, 1e7, 16.5e6, 16.6e6, 20e6, 22e6])
def test_dome_boundaries_continuous(p):
    """Across h' and h'' (steps of 1e-3 J/kg): rho and T continuous, quality 0 or 1
    on the dome side. Bound: 1.5 times the larger one-sided drho/dh times the step."""
    hl, hv = K.saturation_enthalpies(np.array([p]))
    for hs in (hl[0], hv[0]):
        h = hs + np.array([-1e-3, 0.0, 1e-3])
        r = K.ph(np.full(3, p), h)
        assert r.ok.all()
        slope = np.abs(r.drho_dh_p).max()
        assert np.all(np.abs(np.diff(r.rho)) <= 1.5 * slope * 1e-3 + 1e-12 * r.rho[1])
        assert np.all(np.abs(np.diff(r.T)) <= 1e-6)


# --------------------------------------------------------------------------
# Round trips and derivatives.
def _grid():
    p = np.geomspace(700.0, 100e6, 120)
    h = np.linspace(-10e3, 4.3e6, 160)
    P, H = np.meshgrid(p, h)
    P = np.concatenate([P.ravel(), np.full(60, 5e7), np.full(60, 1e5)])
    H = np.concatenate([H.ravel(), np.linspace(4.0e6, 7.0e6, 60), np.linspace(3e6, 7.5e6, 60)])
    return P, H


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
def test_round_trip_dense_grid(kernel):
    """h(p, T(p, h)) = h over 19,320 states in all regions.

    Tolerance 5e-12 relative (plus 1e-8 J/kg): the iteration stops at 2e-14 |h| or at
    a T step of 4e-13 T (cp T 4e-13 <= 1e-12 h); near the critical point the region-3
    density, solved anew in the forward call, adds noise of a few 1e-13 |h|.
    Out-of-range states are flagged with the documented status, never silently wrong.
    """
    P, H = _grid()
    r = K.ph(P, H) if kernel == "numpy" else NB.ph_arrays(P, H)
    assert set(np.unique(r.status)) <= {0, 4, 5}
    one = r.ok & (r.region != 4)
    f = K.pT(P[one], r.T[one])
    assert f.ok.all()
    assert np.all(np.abs(f.h - H[one]) <= 5e-12 * np.abs(H[one]) + 1e-8)
    assert np.all(f.region == r.region[one])
    two = r.region == 4
    hl, hv = K.saturation_enthalpies(P[two])
    assert np.all((r.x[two] >= 0.0) & (r.x[two] <= 1.0))
    assert r.x[two] == pytest.approx((H[two] - hl) / (hv - hl), rel=1e-9, abs=1e-9)
    assert np.all(r.u[r.ok] == H[r.ok] - P[r.ok] / r.rho[r.ok])
    # states below 273.15 K (status 4) are exactly those with h < h(p, 273.15 K)
    low = r.status == 4
    assert np.all(H[low] < K.pT(P[low], np.full(low.sum(), K.T_MIN)).h)


def test_numba_and_numpy_agree():
    """The compiled twin reproduces the numpy kernel (same algorithm, different
    summation order, so different round-off, and iterations that stop at different
    round-off-level iterates). Values: 2e-12 relative (measured 7e-13) plus 1e-12 of
    the largest value (s and u pass through zero near 273 K); x: 1e-12
    absolute. Derivatives: 5e-10 relative (measured 1.1e-10): in the blending bands
    they contain dw/dT (h3 - h1), which amplifies the 1e-13 round-off of the region-3
    density by the band's 1/K slope, and near the critical point the compressibility
    amplifies it too."""
    P, H = _grid()
    a = K.ph(P, H)
    b = NB.ph_arrays(P, H)
    assert np.array_equal(a.status, b.status) and np.array_equal(a.region, b.region)
    tols = {"T": 2e-12, "rho": 2e-12, "u": 2e-12, "s": 2e-12}
    for f in ("T", "rho", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p"):
        x, y = getattr(a, f), getattr(b, f)
        fin = np.isfinite(x)
        assert np.array_equal(fin, np.isfinite(y))
        err = np.abs(x[fin] - y[fin])
        if f == "x":
            assert np.all(err <= 1e-12)
        else:  # plus 1e-12 of the field's largest value, for values near zero (s, u)
            scale = np.abs(x[fin]).max()
            assert np.all(err <= tols.get(f, 5e-10) * np.abs(x[fin]) + 1e-12 * scale), f


DERIV_STATES = [
    (3e6, 1.15e5),  # region 1
    (1e5, 2e4),  # near the density maximum
    (20e6, 1.610e6),  # 1/3 band (T ~ 623 K)
    (25e6, 1.9e6),  # region 3, liquid-like
    (25e6, 2.2e6),  # pseudo-critical
    (60e6, 2.5e6),  # region 3
    (30e6, 2.63e6),  # region 2 near B23
    (1e5, 3.0e6),  # region 2
    (1e6, 4.64e6),  # 2/5 band
    (1e6, 5.0e6),  # region 5
    (1e5, 1.0e6),  # two-phase, region 4 (1/2)
    (10e6, 2.0e6),  # two-phase
    (20e6, 2.0e6),  # two-phase, region-3 saturation
]


@pytest.mark.parametrize("p, h", DERIV_STATES)
def test_derivatives_against_finite_differences(p, h):
    """Analytic drho/dp|h and drho/dh|p vs centred differences of rho(p, h).

    Steps 1e-5 p and 10 J/kg: truncation error (h^2/6 rho''') below 1e-7 relative
    here; rounding (1e-14 rho / step) below 1e-7 for the nearly incompressible liquid.
    2e-6 relative covers both with margin.
    """
    dp = 1e-5 * p
    dh = 10.0
    P = np.array([p, p + dp, p - dp, p, p])
    H = np.array([h, h, h, h + dh, h - dh])
    r = K.ph(P, H)
    assert r.ok.all() and len(set(r.region)) == 1
    fd_p = (r.rho[1] - r.rho[2]) / (2 * dp)
    fd_h = (r.rho[3] - r.rho[4]) / (2 * dh)
    assert r.drho_dp_h[0] == pytest.approx(fd_p, rel=2e-6)
    assert r.drho_dh_p[0] == pytest.approx(fd_h, rel=2e-6)
    if r.region[0] != 4:  # cp = dh/dT|p
        fd_T = (r.h[3] - r.h[4]) / (r.T[3] - r.T[4])
        assert r.cp[0] == pytest.approx(fd_T, rel=2e-6)


# --------------------------------------------------------------------------
# Cross-check with CoolProp (IF97 and IAPWS-95) at states outside the blending bands.
CP_STATES = [(1e5, 350.0), (3e6, 500.0), (80e6, 600.0), (1e5, 700.0), (20e6, 900.0)]
CP_STATES += [(25e6, 660.0), (50e6, 700.0), (5e6, 1500.0)]
NEAR_CRITICAL = {(25e6, 660.0)}  # 2.8 kJ/kg from IAPWS-95 there: not compared with HEOS


@pytest.mark.parametrize("p, T", CP_STATES)
def test_against_coolprop(p, T):
    """CoolProp's IF97 forward h, rho at (p, T): the same equations, so 1e-9 relative
    (region 3: CoolProp evaluates rho(p, T) by the SR5-05 backward equations, within
    1e-5 of the basic equation, IF97's own requirement for them). IAPWS-95 (HEOS):
    IF97 agrees within its documented deviations, 0.1 % in v and 1 kJ/kg in h here
    (larger near the critical point, not sampled)."""
    CP = pytest.importorskip("CoolProp.CoolProp")
    f = K.pT(p, T)
    assert f.ok
    reg3 = f.region == 3
    h_if97 = CP.PropsSI("H", "P", p, "T", T, "IF97::Water")
    rho_if97 = CP.PropsSI("D", "P", p, "T", T, "IF97::Water")
    assert f.h == pytest.approx(h_if97, rel=1e-5 if reg3 else 1e-9)
    assert f.rho == pytest.approx(rho_if97, rel=1e-5 if reg3 else 1e-9)
    if (p, T) in NEAR_CRITICAL:
        return
    h95 = CP.PropsSI("H", "P", p, "T", T, "HEOS::Water")
    rho95 = CP.PropsSI("D", "P", p, "T", T, "HEOS::Water")
    assert f.h == pytest.approx(h95, abs=1.0e3)
    assert f.rho == pytest.approx(rho95, rel=5e-3 if reg3 else 1e-3)


# --------------------------------------------------------------------------
# Out of range, errors, medium API.
def test_out_of_range_flags_and_raise():
    p = np.array([1e5, 2e8, 100.0, 1e5, 60e6, 1e5, np.nan])
    h = np.array([1e6, 1e6, 2.6e6, -1e5, 4.5e6, 9e6, 1e5])
    r = K.ph(p, h)
    assert list(r.status) == [0, 3, 2, 4, 5, 5, 1]
    assert list(r.ok) == [True] + [False] * 6
    assert np.all(np.isnan(r.T[1:])) and np.all(r.region[1:] == 0)
    with pytest.raises(PropertyError, match="above the IF97 limit of 100 MPa") as info:
        r.raise_first_bad("Water (IF97)")
    assert info.value.p == 2e8 and "state index 1" in str(info.value)
    K.ph([1e5], [1e6]).raise_first_bad()  # nothing bad: no exception


def test_medium_states_vector_equals_scalar():
    w = get_medium("Water")
    P, H = _grid()
    sel = slice(0, None, 97)
    p, h = P[sel], H[sel]
    sts = w.states(p, h, check=False)
    for i in range(p.size):
        if not sts.ok[i]:
            with pytest.raises(PropertyError):
                w.state(float(p[i]), float(h[i]))
            continue
        st = w.state(float(p[i]), float(h[i]))
        one = sts.state(i)
        for f in ("T", "rho", "u", "s", "cp", "quality", "drho_dp_h", "drho_dh_p"):
            assert getattr(one, f) == getattr(st, f), f
    with pytest.raises(PropertyError):
        w.states(p, h)  # check=True raises for the first bad state


def test_medium_api_saturation_and_hpx():
    w = get_medium("Water")
    assert w.condensable and not get_medium("Air").condensable
    hl, hv = w.saturation_enthalpies(np.array([1e5, 10e6, 23e6]))
    assert hl[0] == pytest.approx(417.436e3, rel=1e-5)  # IF97 at 0.1 MPa: 417.44 kJ/kg
    assert hv[0] == pytest.approx(2674.95e3, rel=1e-5)
    assert np.isnan(hl[2]) and np.isnan(hv[2])
    hx = w.h_px(np.array([1e5, 1e5]), np.array([0.0, 0.25]))
    assert hx[0] == hl[0] and hx[1] == pytest.approx(hl[0] + 0.25 * (hv[0] - hl[0]))
    st = w.state(1e5, float(hx[1]))
    assert st.quality == pytest.approx(0.25, rel=1e-12)
    assert w.h_pQ(1e5, 0.25) == pytest.approx(hx[1], rel=1e-15)
    with pytest.raises(PropertyError, match="not in"):
        w.h_px(1e5, 1.5)
    with pytest.raises(PropertyError, match="critical"):
        w.h_px(23e6, 0.5)
    with pytest.raises(PropertyError):
        get_medium("Air").h_px(1e5, 0.5)


def test_h_pT_at_saturation_names_the_state():
    w = get_medium("Water")
    Ts = float(K.T_sat(150e5))
    with pytest.raises(PropertyError) as info:
        w.h_pT(150e5, Ts)
    msg = str(info.value)
    assert "T = 342.158 °C is the saturation temperature at 150 bar" in msg
    assert "give h or the quality" in msg
    # 2e-6 K away the state is defined (liquid below, vapour above)
    assert w.h_pT(150e5, Ts - 2e-6) < w.h_px(150e5, 0.0) + 1.0
    assert w.h_pT(150e5, Ts + 2e-6) > w.h_px(150e5, 1.0) - 1.0


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
def test_h_pT_and_state_consistent(kernel):
    """state(p, h_pT(p, T)).T == T to round-off, through every boundary band."""
    w = IF97Water(kernel=kernel)
    for p, T in [(20e6, 623.15), (30e6, float(K.T_b23(30e6))), (1e6, 1073.5), (25e6, 657.0)]:
        assert w.state(p, w.h_pT(p, T)).T == pytest.approx(T, abs=1e-9)


def test_ideal_gas_states_vectorised():
    air = get_medium("Air")
    p = np.array([1e5, 2e5, 5e5])
    h = np.array([1e4, 2e5, -1e4])
    sts = air.states(p, h)
    for i in range(3):
        st = air.state(p[i], h[i])
        one = sts.state(i)
        # numpy's log and math.log may differ in the last bit: 1e-15 relative on s
        assert one.s == pytest.approx(st.s, rel=1e-15)
        assert (one.T, one.rho, one.u, one.drho_dp_h, one.drho_dh_p) == (
            st.T,
            st.rho,
            st.u,
            st.drho_dp_h,
            st.drho_dh_p,
        )
    bad = air.states(np.array([1e5, 1e5]), np.array([1e4, -1e6]), check=False)
    assert list(bad.ok) == [True, False] and math.isnan(bad.T[1])
    with pytest.raises(PropertyError, match="not positive"):
        air.states(np.array([1e5]), np.array([-1e6]))


def test_coolprop_medium_fallback_states_and_saturation():
    r134a = get_medium("R134a", backend="HEOS")
    assert r134a.condensable
    p = np.array([3e5, 5e5])
    h = np.array([3.0e5, 4.5e5])  # two-phase at 3 bar, superheated at 5 bar
    sts = r134a.states(p, h)
    for i in range(2):
        assert sts.state(i) == r134a.state(p[i], h[i])
    hl, hv = r134a.saturation_enthalpies(p)
    assert np.all(hl < hv)
    # CoolProp's own quality from its (p, h) flash vs the lever rule: 1e-6
    assert sts.x[0] == pytest.approx((h[0] - hl[0]) / (hv[0] - hl[0]), rel=1e-6)
    assert np.isnan(sts.x[1]) and sts.region[0] == 4


def test_water_does_not_import_coolprop():
    code = (
        "import sys; from dnasim.media import get_medium; w = get_medium('Water');"
        "w.state(1e5, 1e6); w.states([1e5], [3e6]); get_medium('Air').state(1e5, 1e4);"
        "print('CoolProp' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_memo_copies_unchanged_points_and_warm_starts_moved_ones():
    """ph_arrays with a PhMemo (the pipe's property call): the first call and unchanged
    points are bit-for-bit the call without memo; moved points (a Newton iteration's
    relative 1e-6, a predictor's 1e-3) agree with a fresh call to the tolerances of
    test_numba_and_numpy_agree (both stop their T iteration at a round-off-level
    iterate, from different starts), with the same region and status."""
    P, H = _grid()
    m = NB.PhMemo()
    first = NB.ph_arrays(P, H, memo=m)
    assert m.computed == P.size
    fresh = NB.ph_arrays(P, H)
    fields = ("T", "rho", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p", "region", "status")
    for f in fields:
        np.testing.assert_array_equal(getattr(first, f), getattr(fresh, f))
    again = NB.ph_arrays(P, H, memo=m)
    assert m.computed == 0
    for f in fields:
        np.testing.assert_array_equal(getattr(again, f), getattr(fresh, f))
    rng = np.random.default_rng(3)
    tols = {"T": 2e-12, "rho": 2e-12, "u": 2e-12, "s": 2e-12}
    for rel in (1e-6, 1e-3):
        P2 = P * (1.0 + rel * rng.standard_normal(P.size))
        H2 = H * (1.0 + rel * rng.standard_normal(P.size))
        a = NB.ph_arrays(P2, H2)
        b = NB.ph_arrays(P2, H2, memo=m)
        assert m.computed == P.size
        assert np.array_equal(a.status, b.status) and np.array_equal(a.region, b.region)
        for f in ("T", "rho", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p"):
            x, y = getattr(a, f), getattr(b, f)
            fin = np.isfinite(x)
            assert np.array_equal(fin, np.isfinite(y))
            scale = np.abs(x[fin]).max()
            err = np.abs(x[fin] - y[fin])
            assert np.all(err <= tols.get(f, 5e-10) * np.abs(x[fin]) + 1e-12 * scale), (rel, f)


def test_memo_warm_start_that_fails_falls_back_to_the_cold_path():
    """A point moved far, from compressed liquid (region 1, 200 bar, 1000 kJ/kg, 504 K)
    to 245 bar and 1750 kJ/kg (region 3, 640 K): the first-order warm start T_w from the
    remembered state is no start for region 3 and its iteration used to fail (status 7,
    "no convergence", seen when a steady start's guess moved a supercritical pipe's
    volumes). The memo call must give the state of a call without memo, to the
    tolerances of test_memo_copies_unchanged_points_and_warm_starts_moved_ones (both
    then run the same cold iteration: here to the bit)."""
    m = NB.PhMemo()
    P0 = np.array([200e5, 200e5, 235e5])
    H0 = np.array([1.0e6, 1.1e6, 1.0e6])
    assert np.all(NB.ph_arrays(P0, H0, memo=m).status == 0)
    P1 = np.array([245e5, 245e5, 250e5])
    H1 = np.array([1.75e6, 1.76e6, 1.72e6])
    warm = NB.ph_arrays(P1, H1, memo=m)
    cold = NB.ph_arrays(P1, H1)
    assert np.all(cold.status == 0)
    for f in ("T", "rho", "u", "s", "cp", "drho_dp_h", "drho_dh_p", "region", "status"):
        np.testing.assert_array_equal(getattr(warm, f), getattr(cold, f))


def test_memo_reproduces_a_point_moved_and_moved_back():
    """A difference quotient evaluates F(y), F(y + d e_j), F(y + d e_k), ...: a point
    moved by one column (its p) and the next (its h) and back at the third must give
    F(y)'s state to the bit (a
    warm-started recomputation differs by round-off, which (F - F(y))/d would turn
    into an error of 1e-13 |F| / d in an entry that should be zero)."""
    P = np.array([1e5, 5e6, 5e6, 12e6, 25e6])
    H = np.array([2.0e5, 3.4e6, 1.0e6, 3.2e6, 1.8e6])
    m = NB.PhMemo()
    base = NB.ph_arrays(P, H, memo=m)
    for j in range(P.size):
        # column "p of point j", then column "h of point j", then a column elsewhere
        Pj = P.copy()
        Pj[j] *= 1.0 + 1.5e-8
        Hj = H.copy()
        Hj[j] *= 1.0 + 1.5e-8
        for p_col, h_col in ((Pj, H), (P, Hj)):
            moved = NB.ph_arrays(p_col, h_col, memo=m)
            assert m.computed == 1 and moved.rho[j] != base.rho[j]
        back = NB.ph_arrays(P, H, memo=m)
        assert m.computed == 0
        for f in ("T", "rho", "u", "s", "cp", "drho_dp_h", "drho_dh_p", "region", "status"):
            np.testing.assert_array_equal(getattr(back, f), getattr(base, f))


def test_lean_memo_call_is_the_memo_call_bit_for_bit():
    """IF97Water.T_rho_u (a residual's property call: T, rho, u only) gives the numbers
    of states(..., memo=) on the same sequence of points, moved and unchanged, and
    raises the same PropertyError for a state out of range."""
    from dnasim.media import get_medium
    from dnasim.media.errors import PropertyError

    water = get_medium("Water")
    if not water.phase_branches:
        pytest.skip("compiled kernel only")
    P, H = _grid()
    P, H = P.ravel(), H.ravel()
    m_full, m_lean = water.states_memo(), water.states_memo()
    rng = np.random.default_rng(5)
    branch = np.zeros(P.size, dtype=np.int64)
    for k, rel in enumerate((0.0, 0.0, 1e-6, 1e-3, 0.0)):
        P2 = P * (1.0 + rel * rng.standard_normal(P.size))
        H2 = H * (1.0 + rel * rng.standard_normal(P.size))
        ok = water.states(P2, H2, check=False).ok
        P2, H2 = P2[ok], H2[ok]
        if k == 0:
            m_full, m_lean = water.states_memo(), water.states_memo()
        b = branch[: P2.size] if k % 2 else None
        full = water.states(P2, H2, branch=b, memo=m_full)
        T, rho, u = water.T_rho_u(P2, H2, b, m_lean)
        assert m_full.computed == m_lean.computed
        for got, want in ((T, full.T), (rho, full.rho), (u, full.u)):
            np.testing.assert_array_equal(got, want)
    p_bad, h_bad = np.array([1e6, 1e6]), np.array([1e6, -9e5])  # T below 273.15 K
    with pytest.raises(PropertyError) as lean_err:
        water.T_rho_u(p_bad, h_bad, None, water.states_memo())
    with pytest.raises(PropertyError) as full_err:
        water.states(p_bad, h_bad, memo=water.states_memo())
    assert str(lean_err.value) == str(full_err.value)


def test_lean_memo_call_uses_the_loaded_specialisation():
    """numba compiles the memo loop once per argument type, writability included: the
    lean call must pass the read-only branch codes ph_arrays passes, or every process
    would load (and a new machine compile, about 10 s) a second specialisation."""
    code = (
        "import numpy as np; from dnasim.media import get_medium; "
        "from dnasim.media import if97_numba as NB; w = get_medium('Water'); "
        "p, h = np.array([5e6, 6e6]), np.array([3.2e6, 1.0e6]); "
        "w.T_rho_u(p, h, None, w.states_memo()); "
        "w.T_rho_u(p, h, np.array([3, 1]), w.states_memo()); "
        "w.states(p, h, memo=w.states_memo()); "
        "print(len(NB._ph_memo_loop.signatures) if NB.available() else 1)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "1"
