"""`TabulatedWater`: water and steam from bicubic spline tables of IAPWS-IF97 in (p, h).

An option next to :class:`~dnasim.media.if97.IF97Water` for plants whose residual is
dominated by property calls (long pipes): ``get_medium("Water", backend="IF97-TABLES")``,
in a plant file ``medium = "IF97-TABLES::Water"`` (not ``BICUBIC&...``: that prefix
names CoolProp's own tables, which the command line announces). It follows the idea of
IAPWS's *Guideline on the Fast Calculation of Steam and Water Properties with the
Spline-Based Table Look-Up Method (SBTL)* (2015): spline functions per phase in
transformed coordinates, the two-phase region from saturation splines, so that no cell
of a table straddles the saturation line.

Tables (built from this package's compiled IF97 kernel, :mod:`dnasim.media.if97_numba`)
-------------------------------------------------------------------------------------
Coordinates: x = ln p, and per table the normalised enthalpy
xi = (h - h_a(p)) / (h_b(p) - h_a(p)) in [0, 1], both on uniform grids:

* liquid, p_min <= p < p_c: h_a = h(p, 273.16 K), h_b = h'(p) (saturated liquid);
* vapour, p_min <= p < p_c: h_a = h''(p) (saturated vapour), h_b = h(p, 1073.15 K);
* supercritical, p_c <= p <= 100 MPa: h_a = h(p, 273.16 K), h_b = h(p, 1073.15 K);
* the dome (h' < h < h'') from 1-D splines of T_sat, h', h'', ln v', ln v'', s', s''
  in x: the homogeneous mixture, with the formulas of the IF97 kernel.

Each table interpolates T, ln v and s by a not-a-knot tensor-product cubic spline
(C2; derivatives are the spline's own: (d rho/d p)_h, (d rho/d h)_p, cp = 1/(dT/dh)_p).
The saturation splines share the tables' x knots and node values, so the liquid table
at xi = 1 *is* the saturated-liquid spline (and the vapour table at xi = 0 the
saturated-vapour one): T and rho are continuous across the saturation line to
round-off (tested). u = h - p / rho exactly.

Where the tables are not used: the near-critical band ``P_BAND`` (about 20 to 26 MPa,
where rho changes by a factor of 3 within a few kJ/kg and no table of this size holds
the bound), h below h(p, 273.16 K) or above h(p, 1073.15 K) (region 5), p outside
[p_min, 100 MPa]. There the IF97 kernel answers (the same numbers as ``IF97Water``), so
at the band's edges a property jumps by at most the error bound.

Error bound (tests/test_water_tables.py checks it on 5e4 random states against IF97):
rho within ``RHO_REL_BOUND`` = 5e-5 relative and T within ``T_ABS_BOUND`` = 10 mK in
single phase and in the dome, outside the band. Measured maxima over 6e5 random states
(benchmarks/water_tables.py): rho 8e-6 in the liquid, 1.7e-5 in the dome (near 16.5
MPa, where IF97's saturated liquid passes from region 1 to region 3), 2.7e-5 at 60 to
95 MPa and 795 to 855 K (the region 2/3 boundary B23, where the IF97 kernel blends the
two regions' equations over a narrow band); elsewhere in vapour below 1e-5; T 5 mK.
The guideline's 1e-5 is not met along B23 above 60 MPa with these grids. Single-phase
and two-phase states are told apart by the splines h'(p), h''(p). cp and the
derivatives are the tables' own (the spline differentiated, not fitted): cp within 2 %
of IF97's.

Cost: the tables are built once per machine (about 1.5 s CPU: 5e5 IF97 states and the
spline fits) and stored as an ``.npz`` file of about 10 MB in numba's cache directory
for this package (``NUMBA_CACHE_DIR`` if set), rebuilt when the kernel's source changes
(the file name carries a hash of the sources of if97_numba and this module); the
evaluation kernels are compiled once (about 6 s CPU, said on stderr:
:mod:`dnasim.media.kernel_cache`). ``benchmarks/water_tables.py`` measures it.
"""

from __future__ import annotations

import hashlib
import math
import os
import sys
from pathlib import Path

import numpy as np

from dnasim.media import if97_numba as NB
from dnasim.media import kernel_cache as KC
from dnasim.media.base import Medium
from dnasim.media.errors import PropertyError
from dnasim.media.if97 import IF97Water
from dnasim.media.state import FluidState, FluidStates

try:
    import numba

    _njit = numba.njit(cache=True, fastmath=False, nogil=True)
    # the per-point helpers inlined into their callers at numba's IR level: as separate
    # functions each call passes arrays, and numba's reference counting of each array
    # argument (atomic increments) cost more than the arithmetic (0.2 us per state
    # against 0.05 us inlined, measured)
    _inline = numba.njit(cache=True, fastmath=False, nogil=True, inline="always")
except ImportError:  # pragma: no cover - numba is a dependency

    def _njit(f):
        return f

    _inline = _njit


P_MIN = NB.P_MIN  # [Pa]
P_C = NB.P_C  # [Pa]
P_MAX = NB.P_MAX  # [Pa]
T_LO = 273.16  # [K] the tables' lower temperature (just above IF97's 273.15 K)
T_HI = 1073.15  # [K] the tables' upper temperature (region 2 / 5 boundary)

#: [Pa] the near-critical band answered by the IF97 kernel, not the tables
P_BAND = (20.0e6, 26.0e6)

#: [Pa] the last node of the subcritical tables, the first of the supercritical one
P_SUB_NODES, P_SUP_NODES = 21.0e6, 25.0e6

#: grid sizes: x = ln p nodes of the subcritical tables, of the supercritical table,
#: and xi nodes of each table (liquid, vapour, supercritical)
NX_SUB, NX_SUP = 1000, 80
NY_LIQ, NY_VAP, NY_SUP = 150, 200, 600

#: the stated and tested error bounds (module doc)
RHO_REL_BOUND = 5e-5
T_ABS_BOUND = 10e-3  # [K]

#: status codes of the table kernel: 0 ok, 8 not in the tables (IF97 answers)
OUTSIDE = 8

_SOURCES = (Path(NB.__file__), Path(__file__))


# ------------------------------------------------------------------ splines (numba)
@_inline
def _basis(t, n, u, x0, dx):
    """(span mu, N, dN) of the cubic B-spline basis on knots t (n coefficients,
    not-a-knot knots of a uniform grid x0 + j dx) at u: the four basis functions
    N_{mu-3..mu} and their derivatives as tuples (Piegl and Tiller, The NURBS Book,
    A2.2, unrolled: no arrays, so nothing is allocated per point)."""
    j = int(math.floor((u - x0) / dx))
    i = min(max(j + 2, 3), n - 1)
    l1 = u - t[i]
    l2 = u - t[i - 1]
    l3 = u - t[i - 2]
    r1 = t[i + 1] - u
    r2 = t[i + 2] - u
    r3 = t[i + 3] - u
    temp = 1.0 / (r1 + l1)
    n0 = r1 * temp
    n1 = l1 * temp
    d20 = r1 + l2  # t[i+1] - t[i-1]
    d21 = r2 + l1  # t[i+2] - t[i]
    temp = n0 / d20
    m0 = r1 * temp
    saved = l2 * temp
    temp = n1 / d21
    m1 = saved + r2 * temp
    m2 = l1 * temp
    e0 = r1 + l3  # t[i+1] - t[i-2]
    e1 = r2 + l2  # t[i+2] - t[i-1]
    e2 = r3 + l1  # t[i+3] - t[i]
    temp = m0 / e0
    q0 = r1 * temp
    saved = l3 * temp
    temp = m1 / e1
    q1 = saved + r2 * temp
    saved = l2 * temp
    temp = m2 / e2
    q2 = saved + r3 * temp
    q3 = l1 * temp
    a0 = 3.0 * m0 / e0
    a1 = 3.0 * m1 / e1
    a2 = 3.0 * m2 / e2
    return i, (q0, q1, q2, q3), (-a0, a0 - a1, a1 - a2, a2)


@_inline
def _spline1(c, mu, N, dN):
    """Value and derivative of a 1-D spline with coefficients c at a point's basis
    (unrolled: a tuple indexed by a loop variable costs a copy per access)."""
    j = mu - 3
    c0 = c[j]
    c1 = c[j + 1]
    c2 = c[j + 2]
    c3 = c[j + 3]
    return (
        c0 * N[0] + c1 * N[1] + c2 * N[2] + c3 * N[3],
        c0 * dN[0] + c1 * dN[1] + c2 * dN[2] + c3 * dN[3],
    )


@_inline
def _spline2(C, k, mx, Nx, dNx, my, Ny, dNy):
    """Value, d/dx, d/dy of the k-th tensor spline C[k] at a point's bases."""
    i = mx - 3
    j = my - 3
    f = 0.0
    fx = 0.0
    fy = 0.0
    for a in range(4):
        s = 0.0
        sy = 0.0
        for b in range(4):
            c = C[k, i + a, j + b]
            s += c * Ny[b]
            sy += c * dNy[b]
        f += s * Nx[a]
        fx += s * dNx[a]
        fy += sy * Nx[a]
    return f, fx, fy


@_inline
def _point(p, h, L, V, U, S, band_lo, band_hi):
    """State tuple (T, rho, u, s, cp, x, drho_dp_h, drho_dh_p, region, status) at (p, h)
    from the tables (L liquid, V vapour, U supercritical: each (tx, ty, C, lo, hi, x0,
    dx, dy); S the saturation splines' (tx, S, x0, dx), on the x knots of L and V),
    status OUTSIDE where they do not answer. One body with few calls of the helpers:
    numba inlines a helper at every call site (``_inline``), so the number of sites
    sets the compile time."""
    nan = math.nan
    bad = (nan, nan, nan, nan, nan, nan, nan, nan, 0, OUTSIDE)
    if not (P_MIN <= p <= P_MAX) or (band_lo <= p <= band_hi) or not math.isfinite(h):
        return bad
    x = math.log(p)
    sup = p >= P_C
    Sc = S[1]
    if sup:
        tab = U
        knots, n, x0, dx = U[0], U[3].size, U[5], U[6]
        rlo, rhi = U[3], U[4]
    else:
        tab = L
        knots, n, x0, dx = S[0], Sc.shape[1], S[2], S[3]
        rlo, rhi = Sc[0], Sc[1]
    mx, Nx, dNx = _basis(knots, n, x, x0, dx)
    # supercritical: the table's bounds; subcritical: h' and h''
    hl, hlx = _spline1(rlo, mx, Nx, dNx)
    hv, hvx = _spline1(rhi, mx, Nx, dNx)
    if not sup and hl < h < hv:  # the dome
        Ts, _ = _spline1(Sc[2], mx, Nx, dNx)
        lvl, lvlx = _spline1(Sc[3], mx, Nx, dNx)
        lvv, lvvx = _spline1(Sc[4], mx, Nx, dNx)
        sl, _ = _spline1(Sc[5], mx, Nx, dNx)
        sv, _ = _spline1(Sc[6], mx, Nx, dNx)
        vl = math.exp(lvl)
        vv = math.exp(lvv)
        dh = hv - hl
        dv = vv - vl
        q = (h - hl) / dh
        rho = 1.0 / (vl + q * dv)
        # p-derivatives along the saturation line: d/dp = (d/dx) / p
        vlp = vl * lvlx / p
        vvp = vv * lvvx / p
        hlp = hlx / p
        hvp = hvx / p
        dp_h = -rho * rho * (vlp + q * (vvp - vlp) - dv * (hlp + q * (hvp - hlp)) / dh)
        sq = sl + q * (sv - sl)
        return Ts, rho, h - p / rho, sq, math.inf, q, dp_h, -rho * rho * dv / dh, 4, 0
    if sup:
        a, da, b, db = hl, hlx, hv, hvx
    else:
        if h <= hl:  # liquid: from h(p, 273.16 K) to h'
            c1 = L[3]
            b, db = hl, hlx
        else:  # vapour: from h'' to h(p, 1073.15 K)
            tab = V
            c1 = V[4]
            a, da = hv, hvx
        e, de = _spline1(c1, mx, Nx, dNx)
        if h <= hl:
            a, da = e, de
        else:
            b, db = e, de
    w = b - a
    y = (h - a) / w
    if not (0.0 <= y <= 1.0):
        return bad
    C = tab[2]
    my, Ny, dNy = _basis(tab[1], C.shape[2], y, 0.0, tab[7])
    T, _, Ty = _spline2(C, 0, mx, Nx, dNx, my, Ny, dNy)
    lv, lvx, lvy = _spline2(C, 1, mx, Nx, dNx, my, Ny, dNy)
    s, _, _ = _spline2(C, 2, mx, Nx, dNx, my, Ny, dNy)
    # d/dh at p: (d/dy) / w; d/dx at h: d/dx + d/dy * dy/dx, dy/dx = -(da + y dw) / w
    yx = -(da + y * (db - da)) / w
    rho = math.exp(-lv)
    dlv_dh = lvy / w
    dlv_dp = (lvx + lvy * yx) / p
    return T, rho, h - p / rho, s, w / Ty, nan, -rho * dlv_dp, -rho * dlv_dh, 0, 0


@_inline
def _table_views(F, I, k):
    """Table k (0 liquid, 1 vapour, 2 supercritical) of the flat arrays of
    :func:`_flatten` as (tx, ty, C, lo, hi, x0, dx, dy), views into F."""
    m = I[9 * k : 9 * k + 9]
    o_tx, n_tx, o_ty, n_ty, o_C, nx, ny, o_g = m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7]
    n3 = 3 * nx * ny
    C = F[o_C : o_C + n3].reshape((3, nx, ny))
    lo = F[o_C + n3 : o_C + n3 + nx]
    hi = F[o_C + n3 + nx : o_C + n3 + 2 * nx]
    return (F[o_tx : o_tx + n_tx], F[o_ty : o_ty + n_ty], C, lo, hi, F[o_g], F[o_g + 1], F[o_g + 2])


@_inline
def _views(F, I):
    """(L, V, U, S) of :func:`_point` from the flat arrays of :func:`_flatten`."""
    o_s, n_s, o_S, o_g = I[27], I[28], I[29], I[30]
    S = (F[o_s : o_s + n_s], F[o_S : o_S + 7 * (n_s - 4)].reshape((7, n_s - 4)), F[o_g], F[o_g + 1])
    return _table_views(F, I, 0), _table_views(F, I, 1), _table_views(F, I, 2), S


@_njit
def _state1(p, h, F, I, band_lo, band_hi):
    """The state tuple of :func:`_point` at one (p, h): the scalar entry (6 arguments;
    the array loop's 18 cost 7 us to dispatch)."""
    L, V, U, S = _views(F, I)
    return _point(p, h, L, V, U, S, band_lo, band_hi)


@_njit
def _memo_loop(p, h, F, I, band_lo, band_hi, mp, mh, T, rho, u, s, cp, q, dp, dh, region, status):
    """The states at the points (p, h) into the output arrays, from the tables packed
    in F and I (:func:`_flatten`; two arrays: a tuple of arrays is typed in Python, 10 us
    a call), computing only the points whose (p, h) differ from (mp, mh), the points of
    the previous call (NaN: all); returns how many it computed. The tables give the
    same bits for the same input, so one remembered state per point suffices (the IF97
    kernel's memo keeps three, see if97_numba.PhMemo)."""
    L, V, U, S = _views(F, I)
    computed = 0
    for i in range(p.size):
        if p[i] == mp[i] and h[i] == mh[i]:
            continue
        r = _point(p[i], h[i], L, V, U, S, band_lo, band_hi)
        mp[i] = p[i]
        mh[i] = h[i]
        T[i] = r[0]
        rho[i] = r[1]
        u[i] = r[2]
        s[i] = r[3]
        cp[i] = r[4]
        q[i] = r[5]
        dp[i] = r[6]
        dh[i] = r[7]
        region[i] = r[8]
        status[i] = r[9]
        computed += 1
    return computed


class TableMemo:
    """The last (p, h) and (T, rho, u) of each of a fixed set of points (a pipe's
    volumes), for :meth:`TabulatedWater.T_rho_u`: a finite-difference Jacobian moves a
    few points per residual, and only those are computed."""

    def __init__(self):
        self.n = -1
        self.computed = 0

    def arrays(self, n):
        """(p, h) of the remembered points (NaN: none yet) and the ten output arrays of
        ``_memo_loop`` (T, rho, u, s, cp, x, drho_dp_h, drho_dh_p, region, status),
        reset when n changes."""
        if n != self.n:
            self.n = n
            self.p = np.full(n, np.nan)
            self.h = np.full(n, np.nan)
            self.out = _outputs(n)
        return (self.p, self.h, *self.out)


def _outputs(n):
    out = [np.empty(n) for _ in range(8)] + [np.empty(n, np.int8), np.empty(n, np.int8)]
    out[9][:] = OUTSIDE
    return out


# ------------------------------------------------------------------ building
def _fit_2d(x, y, Z):
    """Coefficients (knots tx, ty, C) of the not-a-knot tensor cubic spline through Z."""
    from scipy.interpolate import make_interp_spline

    sx = make_interp_spline(x, Z, k=3, axis=0)
    sy = make_interp_spline(y, sx.c, k=3, axis=1)  # its c: the y axis first
    return sx.t, sy.t, np.ascontiguousarray(np.moveaxis(sy.c, 0, 1))


def _fit_1d(x, f):
    from scipy.interpolate import make_interp_spline

    return make_interp_spline(x, f, k=3).c


def _nodes(p, h, branch):
    """IF97 (T, ln v, s) at the node grid (2-D arrays), by the compiled kernel with the
    phase branch forced (the saturated side of a node on the line)."""
    r = NB.ph_arrays(p, h, np.full(p.shape, branch, dtype=np.int64))
    if not r.ok.all():  # pragma: no cover - the grid lies inside IF97's range
        i = int(np.flatnonzero(~r.ok.ravel())[0])
        raise RuntimeError(f"IF97 failed at table node p = {p.flat[i]}, h = {h.flat[i]}")
    return np.stack([r.T, -np.log(r.rho), r.s])


def _h_pT(p, T):
    return np.array([NB.h_pT_scalar(float(pi), T)[0] for pi in p])


def build_tables() -> dict:
    """Build the tables (module doc) from the IF97 kernel: a dict of arrays."""
    KC.ensure("states")
    KC.ensure("saturation")
    KC.ensure("h_pT")
    out = {}
    # subcritical: x up to P_SUB_NODES, past the band's start (20 MPa), so that the
    # splines end beyond the part the tables answer
    x_sub = np.linspace(math.log(P_MIN), math.log(P_SUB_NODES), NX_SUB)
    p_sub = np.exp(x_sub)
    p_sub[0], p_sub[-1] = P_MIN, P_SUB_NODES  # exactly: exp(ln p) may fall below P_MIN
    p_sat = p_sub
    hl, hv = NB.saturation_arrays(p_sat)
    h_lo = _h_pT(p_sub, T_LO)
    h_hi = _h_pT(p_sub, T_HI)
    dx_sub = x_sub[1] - x_sub[0]
    for name, a, b, ny, branch in (
        ("L", h_lo, hl, NY_LIQ, NB.LIQUID),
        ("V", hv, h_hi, NY_VAP, NB.VAPOUR),
    ):
        y = np.linspace(0.0, 1.0, ny)
        P = np.repeat(p_sat[:, None], ny, axis=1)
        H = a[:, None] + y[None, :] * (b - a)[:, None]
        Z = _nodes(P, H, branch)
        tx, ty, C = zip(*(_fit_2d(x_sub, y, Z[k]) for k in range(3)), strict=True)
        out[name + "_tx"], out[name + "_ty"] = tx[0], ty[0]
        out[name + "_C"] = np.stack(C)
        out[name + "_lo"], out[name + "_hi"] = _fit_1d(x_sub, a), _fit_1d(x_sub, b)
        out[name + "_grid"] = np.array([x_sub[0], dx_sub, y[1] - y[0]])
        if name == "L":
            sat_l = Z[:, :, -1]  # T, ln v, s of the saturated liquid (xi = 1)
        else:
            sat_v = Z[:, :, 0]
    out["S_tx"] = out["L_tx"]
    out["S"] = np.stack(
        [_fit_1d(x_sub, f) for f in (hl, hv, sat_l[0], sat_l[1], sat_v[1], sat_l[2], sat_v[2])]
    )
    out["S_grid"] = np.array([x_sub[0], dx_sub])
    # supercritical
    x_sup = np.linspace(math.log(P_SUP_NODES), math.log(P_MAX), NX_SUP)
    p_sup = np.exp(x_sup)
    p_sup[0], p_sup[-1] = P_SUP_NODES, P_MAX
    y = np.linspace(0.0, 1.0, NY_SUP)
    a, b = _h_pT(p_sup, T_LO), _h_pT(p_sup, T_HI)
    P = np.repeat(p_sup[:, None], NY_SUP, axis=1)
    H = a[:, None] + y[None, :] * (b - a)[:, None]
    Z = _nodes(P, H, NB.AUTO)
    tx, ty, C = zip(*(_fit_2d(x_sup, y, Z[k]) for k in range(3)), strict=True)
    out["U_tx"], out["U_ty"], out["U_C"] = tx[0], ty[0], np.stack(C)
    out["U_lo"], out["U_hi"] = _fit_1d(x_sup, a), _fit_1d(x_sup, b)
    out["U_grid"] = np.array([x_sup[0], x_sup[1] - x_sup[0], y[1] - y[0]])
    return out


def _source_hash() -> str:
    h = hashlib.sha256()
    for path in _SOURCES:
        h.update(path.read_bytes())
    h.update(
        repr(
            (P_SUB_NODES, P_SUP_NODES, NX_SUB, NX_SUP, NY_LIQ, NY_VAP, NY_SUP, P_BAND, T_LO, T_HI)
        ).encode()
    )
    return h.hexdigest()[:16]


def table_path() -> Path:
    """Where the tables are stored: ``water_tables_<hash>.npz`` in numba's cache
    directory for this package (``NUMBA_CACHE_DIR`` when set; else the package's
    ``__pycache__``; else the user's cache directory)."""
    base = os.environ.get("NUMBA_CACHE_DIR")
    if base:
        d = Path(base)
    else:
        d = Path(__file__).resolve().parent / "__pycache__"
        if not os.access(d.parent, os.W_OK):
            d = Path.home() / ".cache" / "dnasim"
    return d / f"water_tables_{_source_hash()}.npz"


def load_tables() -> dict:
    """The tables from their file, or built (and stored) when absent, saying so."""
    path = table_path()
    try:
        with np.load(path) as z:
            return {k: z[k] for k in z.files}
    except (OSError, ValueError, KeyError):
        pass
    sys.stderr.write(
        f"dnasim: building the water property tables once (about 1 s); kept in {path}\n"
    )
    sys.stderr.flush()
    tables = build_tables()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
        np.savez(tmp, **tables)
        os.replace(tmp, path)
    except OSError:  # pragma: no cover - a read-only cache: build each process
        pass
    return tables


def _flatten(t: dict):
    """The tables of :func:`build_tables` as one float array F and one int array I of
    offsets and sizes (read by ``_table_views`` and ``_views``)."""
    parts = []
    meta = []
    size = 0

    def put(a):
        nonlocal size
        a = np.ascontiguousarray(a, dtype=float).ravel()
        parts.append(a)
        size += a.size
        return size - a.size

    for n in ("L", "V", "U"):
        C = t[n + "_C"]
        o_tx, o_ty = put(t[n + "_tx"]), put(t[n + "_ty"])
        o_C = put(C)
        put(t[n + "_lo"])
        put(t[n + "_hi"])
        o_g = put(t[n + "_grid"])
        meta += [o_tx, t[n + "_tx"].size, o_ty, t[n + "_ty"].size, o_C, C.shape[1], C.shape[2]]
        meta += [o_g, 0]
    o_s = put(t["S_tx"])
    o_S = put(t["S"])
    o_g = put(t["S_grid"])
    meta += [o_s, t["S_tx"].size, o_S, o_g]
    return np.concatenate(parts), np.array(meta, dtype=np.int64)


# ------------------------------------------------------------------ the medium
class TabulatedWater(Medium):
    """Water and steam from bicubic tables of IF97 (module doc), ``backend="IF97-TABLES"``.

    ``state``, ``states`` and ``T_rho_u`` come from the tables (the IF97 kernel where
    they do not answer); ``h_pT``, the saturation line (``saturation_enthalpies``,
    ``h_px``, ``h_pQ``) and the transport properties are IF97's (``IF97Water``'s).
    """

    condensable = True
    phase_branches = False  # no forced phase branches: the pipes use automatic phases

    def __init__(self, *, cache_size: int = 4096) -> None:
        super().__init__("Water", "IF97-TABLES", cache_size=cache_size)
        self.p_critical = P_C
        self.T_critical = NB.T_C
        self._if97 = IF97Water(kernel="numba")
        self._packed = None
        self.n_fallback = 0  # states the IF97 kernel answered (outside the tables)

    def _tables(self):
        if self._packed is None:
            self._packed = _flatten(load_tables())
            KC.ensure("tables")
        return self._packed

    def _arrays(self, p, h):
        """Flat outputs (T, rho, u, s, cp, x, dp, dh, region, status) at flat p, h."""
        F, I = self._tables()  # noqa: E741
        n = p.size
        out = _outputs(n)
        nan = np.full(n, np.nan)  # no point remembered: all computed
        _memo_loop(p, h, F, I, P_BAND[0], P_BAND[1], nan, nan.copy(), *out)
        miss = out[9] == OUTSIDE
        if miss.any():
            idx = np.flatnonzero(miss)
            KC.ensure("states")
            r = NB.ph_arrays(p[idx], h[idx])
            for k, f in enumerate(("T", "rho", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p")):
                out[k][idx] = getattr(r, f)
            out[8][idx] = r.region
            out[9][idx] = r.status
            self.n_fallback += idx.size
        return out

    def _compute_state(self, p: float, h: float) -> FluidState:
        F, I = self._tables()  # noqa: E741
        T, rho, u, s, cp, x, d_p, d_h, _, st = _state1(p, h, F, I, P_BAND[0], P_BAND[1])
        if st == OUTSIDE:  # the IF97 kernel answers
            self.n_fallback += 1
            KC.ensure("state")
            T, rho, u, s, cp, x, d_p, d_h, _, st = NB.ph_scalar(p, h)
        if st != 0:
            raise PropertyError(self.label, p, h, "state", NB.K.STATUS_TEXT[int(st)])
        return FluidState(p, h, T, rho, u, s, cp, -1.0 if x != x else float(x), d_p, d_h)

    def states(self, p, h, *, check: bool = True, branch=None, memo=None) -> FluidStates:
        """Vectorised :meth:`state` from the tables (``branch`` and ``memo`` are
        accepted and ignored: the tables have no forced branches and need no memo)."""
        p, h = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(h, dtype=float))
        shape = p.shape
        pf = np.ascontiguousarray(p.ravel())
        hf = np.ascontiguousarray(h.ravel())
        T, rho, u, s, cp, x, d_p, d_h, region, status = self._arrays(pf, hf)
        ok = status == 0
        if check and not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            raise PropertyError(
                self.label, float(pf[i]), float(hf[i]), "state", NB.K.STATUS_TEXT[int(status[i])]
            )
        self.n_evaluations += pf.size
        return FluidStates(
            *(a.reshape(shape) for a in (pf, hf, T, rho, u, s, cp, x, d_p, d_h, region, ok))
        )

    def states_memo(self):
        """A new memo for ``T_rho_u`` (:class:`TableMemo`: one per fixed set of points)."""
        return TableMemo()

    def T_rho_u(self, p, h, branch=None, memo=None):
        """(T [K], rho [kg/m3], u [J/kg]) at 1-D p [Pa], h [J/kg] (a residual's call:
        ``dnasim.model.physics.PropertyArrays``), with a :meth:`states_memo` (only
        moved points are computed) or without; ``branch`` is ignored (no forced
        branches). PropertyError for the first state out of range."""
        pf = np.ascontiguousarray(p, dtype=float)
        hf = np.ascontiguousarray(h, dtype=float)
        if memo is None:
            out = self._arrays(pf, hf)
            n_new = pf.size
        else:
            F, I = self._tables()  # noqa: E741
            arrays = memo.arrays(pf.size)
            n_new = _memo_loop(pf, hf, F, I, P_BAND[0], P_BAND[1], *arrays)
            mT, mrho, mu, mst = arrays[2], arrays[3], arrays[4], arrays[11]
            out = [mT.copy(), mrho.copy(), mu.copy()] + [None] * 6 + [mst.copy()]
            miss = mst == OUTSIDE
            if miss.any():  # the IF97 kernel answers (not remembered: computed each call)
                idx = np.flatnonzero(miss)
                KC.ensure("states")
                r = NB.ph_arrays(pf[idx], hf[idx])
                out[0][idx], out[1][idx], out[2][idx], out[9][idx] = r.T, r.rho, r.u, r.status
                self.n_fallback += idx.size
                n_new += idx.size
            memo.computed = n_new
        status = out[9]
        if status.any():
            i = int(np.flatnonzero(status)[0])
            raise PropertyError(
                self.label,
                float(pf[i]),
                float(hf[i]),
                "state",
                NB.K.STATUS_TEXT.get(int(status[i]), "invalid state") + f" (state index {i})",
            )
        self.n_evaluations += n_new
        return out[0], out[1], out[2]

    # IF97 for the rest
    def _compute_h_pT(self, p: float, T: float) -> float:
        return self._if97._compute_h_pT(p, T)

    def saturation_enthalpies(self, p):
        """(h', h'') [J/kg] by IF97 (see ``IF97Water.saturation_enthalpies``)."""
        return self._if97.saturation_enthalpies(p)

    def _compute_h_pQ(self, p: float, x: float) -> float:
        return self._if97._compute_h_pQ(p, x)

    def transport(self, p, h, *, check: bool = True) -> dict:
        """IF97Water's transport properties (IAPWS R12-08, R15-11)."""
        return self._if97.transport(p, h, check=check)

    def saturation_transport(self, p) -> dict:
        """IF97Water's saturated transport properties."""
        return self._if97.saturation_transport(p)


def _register() -> None:
    def warm_up():
        F, I = _flatten(load_tables())  # noqa: E741
        p, h = np.array([1e6]), np.array([1e6])
        _state1(1e6, 1e6, F, I, P_BAND[0], P_BAND[1])
        _memo_loop(p, h, F, I, P_BAND[0], P_BAND[1], *TableMemo().arrays(1))

    KC.register("tables", (_state1, _memo_loop), warm_up, 6.0, label="water-table")


if NB.available():
    _register()
