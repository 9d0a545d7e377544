"""The IF97 (p, h) kernel of :mod:`dnasim.media.if97_kernel`, compiled with numba.

Same formulations, blending bands, iterations and tolerances as the numpy kernel
(see its docstring), written per state: one compiled loop over the states, so the
cost per state no longer depends on how many states a call has. The numpy kernel is
the reference; tests/test_if97_kernel.py checks that both agree to round-off.

Why it exists (benchmarks/media_speed.py, CPU us per state): numpy's cost is per
array operation, so the numpy kernel takes 340 to 1070 us for a single state
(hundreds of small array operations) and 1.3 to 9 us per state in calls of 1000;
this one takes 0.7 to 1.1 us per state in calls of 100 to 10000 states, and 3 us per
scalar ``IF97Water.state(p, h)`` call including the Python around it (the old
CoolProp path: 12 to 50 us). The price: 6 to 9 s CPU to compile on first use on a
machine (12 s before the literal arguments were removed, see ``_NL``), each entry
point at its first call (:mod:`dnasim.media.kernel_cache`, which says so on stderr);
numba caches the result in ``__pycache__`` (or ``NUMBA_CACHE_DIR``) and later
processes load it in about 0.3 s. :func:`available` is False when numba cannot be
imported; the media then use the numpy kernel.

Differences from the numpy kernel: the power sums use tables of powers built by
repeated multiplication instead of exp/log per term, and a single-phase state below
21 MPa evaluates only the saturated side that decides its phase. Results agree with
the numpy kernel to about 1e-12 (tests/test_if97_kernel.py).

Entry points: :func:`ph_arrays` (fills arrays, like ``if97_kernel.ph``),
:func:`ph_scalar` (one state, a tuple), :func:`h_pT_scalar`, :func:`saturation_arrays`.
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.media import if97_coefficients as C
from dnasim.media import if97_kernel as K

try:
    import numba

    _njit = numba.njit(cache=True, fastmath=False, nogil=True)
    _AVAILABLE = True
except ImportError:  # pragma: no cover - numba is a dependency; kept for robustness
    _AVAILABLE = False

    def _njit(f):
        return f


def available() -> bool:
    """True if numba is importable (the compiled kernel is used)."""
    return _AVAILABLE


R = C.R
P_C = C.P_C
T_C = C.T_C
RHO_C = C.RHO_C
P_MIN = K.P_MIN
P_MAX = K.P_MAX
P_R5_MAX = K.P_R5_MAX
T_MIN = K.T_MIN
T_13 = K.T_13
T_25 = K.T_25
T_MAX_R5 = K.T_MAX_R5
P_13_SAT = K.P_13_SAT
P_23_MIN = K.P_23_MIN
B13 = K.BAND_13
B23 = K.BAND_23
B25 = K.BAND_25
RHO3_MAX = K.RHO3_MAX
T_SAT_BAND = K.T_SAT_BAND
N1_3 = C.R3_N1
N4 = np.array(C.R4_N)
NB23 = np.array(C.B23_N)
NB2BC = np.array(C.B2BC_N)
NH3AB = np.array(C.H3AB_N)

R2_J0, R2_N0 = C.R2_J0, C.R2_N0
R5_J0, R5_N0 = C.R5_J0, C.R5_N0
T1_I, T1_J, T1_N = C.T1PH_I, C.T1PH_J, C.T1PH_N
T2A_I, T2A_J, T2A_N = C.T2APH_I, C.T2APH_J, C.T2APH_N
T2B_I, T2B_J, T2B_N = C.T2BPH_I, C.T2BPH_J, C.T2BPH_N
T2C_I, T2C_J, T2C_N = C.T2CPH_I, C.T2CPH_J, C.T2CPH_N
T3A_I, T3A_J, T3A_N = C.T3APH_I, C.T3APH_J, C.T3APH_N
T3B_I, T3B_J, T3B_N = C.T3BPH_I, C.T3BPH_J, C.T3BPH_N
V3A_I, V3A_J, V3A_N = C.V3APH_I, C.V3APH_J, C.V3APH_N
V3B_I, V3B_J, V3B_N = C.V3BPH_I, C.V3BPH_J, C.V3BPH_N


def _table(I, J, N):  # noqa: E741
    """Integer exponents (offset to 0) and ranges of a coefficient table, for power tables."""
    Ii = I.astype(np.int64)
    Ji = J.astype(np.int64)
    return (
        Ii - Ii.min(),
        Ji - Ji.min(),
        N,
        I,
        J,
        int(Ii.min()),
        int(Ii.max()),
        int(Ji.min()),
        int(Ji.max()),
    )


@_njit
def _powers(x, lo, hi):
    """x^lo, x^(lo+1), ..., x^hi by repeated multiplication (x^lo by one power)."""
    out = np.empty(hi - lo + 1)
    out[0] = x**lo
    for k in range(1, hi - lo + 1):
        out[k] = out[k - 1] * x
    return out


@_njit
def _sums(a, b, tab):
    """sum n a^I b^J times 1, I, J, I(I-1), J(J-1), I J (power tables, no exp)."""
    Io, Jo, N, I, J, imin, imax, jmin, jmax = tab  # noqa: E741
    pa = _powers(a, imin, imax)
    pb = _powers(b, jmin, jmax)
    s0 = s1 = s2 = s3 = s4 = s5 = 0.0
    for k in range(N.size):
        i = I[k]
        j = J[k]
        t = N[k] * pa[Io[k]] * pb[Jo[k]]
        s0 += t
        s1 += t * i
        s2 += t * j
        s3 += t * i * (i - 1.0)
        s4 += t * j * (j - 1.0)
        s5 += t * i * j
    return s0, s1, s2, s3, s4, s5


@_njit
def _poly(a, b, I, J, N):  # noqa: E741
    """sum n a^I b^J, bases of any sign, integer exponents."""
    s = 0.0
    for k in range(N.size):
        s += N[k] * a ** int(I[k]) * b ** int(J[k])
    return s


TAB_R1 = _table(C.R1_I, C.R1_J, C.R1_N)
TAB_R2 = _table(C.R2_I, C.R2_J, C.R2_N)
TAB_R3 = _table(C.R3_I, C.R3_J, C.R3_N)
TAB_R5 = _table(C.R5_I, C.R5_J, C.R5_N)


@_njit
def _smooth(t):
    if t <= 0.0:
        return 0.0, 0.0
    if t >= 1.0:
        return 1.0, 0.0
    return t * t * t * (10.0 + t * (-15.0 + 6.0 * t)), 30.0 * t * t * (1.0 - t) ** 2


@_njit
def _gibbs(p, T, tau, ps, Ts, g, gp, gpp, gt, gtt, gpt):
    return (
        R * T * gp / ps,
        R * Ts * gt,
        R * (tau * gt - g),
        R * (gp - tau * gpt) / ps,
        R * T * gpp / (ps * ps),
        -R * tau * tau * gtt,
        R * Ts * gpt / ps,
    )


@_njit
def region1(p, T):
    pi = p / 16.53e6
    tau = 1386.0 / T
    a = 7.1 - pi
    b = tau - 1.222
    s0, s1, s2, s3, s4, s5 = _sums(a, b, TAB_R1)
    return _gibbs(
        p, T, tau, 16.53e6, 1386.0, s0, -s1 / a, s3 / (a * a), s2 / b, s4 / (b * b), -s5 / (a * b)
    )


@_njit
def _region25(p, T, ps, Ts, J0, N0, tab, shift):
    pi = p / ps
    tau = Ts / T
    g0 = g0t = g0tt = 0.0
    for k in range(N0.size):
        t = N0[k] * tau ** int(J0[k])
        g0 += t
        g0t += t * J0[k]
        g0tt += t * J0[k] * (J0[k] - 1.0)
    b = tau - shift
    s0, s1, s2, s3, s4, s5 = _sums(pi, b, tab)
    return _gibbs(
        p,
        T,
        tau,
        ps,
        Ts,
        math.log(pi) + g0 + s0,
        1.0 / pi + s1 / pi,
        -1.0 / (pi * pi) + s3 / (pi * pi),
        g0t / tau + s2 / b,
        g0tt / (tau * tau) + s4 / (b * b),
        s5 / (pi * b),
    )


@_njit
def region2(p, T):
    return _region25(p, T, 1e6, 540.0, R2_J0, R2_N0, TAB_R2, 0.5)


@_njit
def region5(p, T):
    return _region25(p, T, 1e6, 1000.0, R5_J0, R5_N0, TAB_R5, 0.0)


@_njit
def region3(rho, T):
    """(p, dp/drho, dp/dT, dh/drho, dh/dT|rho, record) at (rho, T)."""
    delta = rho / RHO_C
    tau = T_C / T
    s0, s1, s2, s3, s4, s5 = _sums(delta, tau, TAB_R3)
    phi = N1_3 * math.log(delta) + s0
    fd = (N1_3 + s1) / delta
    fdd = (-N1_3 + s3) / (delta * delta)
    ft = s2 / tau
    ftt = s4 / (tau * tau)
    fdt = s5 / (delta * tau)
    RT = R * T
    p = rho * RT * delta * fd
    pr = RT * (2.0 * delta * fd + delta * delta * fdd)
    pT = rho * R * (delta * fd - delta * tau * fdt)
    hr = RT * (tau * fdt + fd + delta * fdd) / RHO_C
    hTr = R * (-tau * tau * ftt + delta * fd - delta * tau * fdt)
    rho_p = 1.0 / pr
    rho_T = -pT / pr
    v = 1.0 / rho
    rec = (
        v,
        RT * (tau * ft + delta * fd),
        R * (tau * ft - phi),
        -rho_T * v * v,
        -rho_p * v * v,
        hTr + hr * rho_T,
        hr * rho_p,
    )
    return p, pr, pT, hr, hTr, rec


@_njit
def _rho_sat_guess(T, side):
    th = max(1.0 - T / T_C, 0.0)
    if side > 0:
        liq = (
            1.0
            + 1.99274064 * th ** (1 / 3)
            + 1.09965342 * th ** (2 / 3)
            - 0.510839303 * th ** (5 / 3)
            - 1.75493479 * th ** (16 / 3)
            - 45.5170352 * th ** (43 / 3)
            - 6.74694450e5 * th ** (110 / 3)
        )
        return RHO_C * (1.0 + 1.05 * (liq - 1.0))
    vap = math.exp(
        -2.03150240 * th ** (2 / 6)
        - 2.68302940 * th ** (4 / 6)
        - 5.38626492 * th ** (8 / 6)
        - 17.2991605 * th ** (18 / 6)
        - 44.7586581 * th ** (37 / 6)
        - 63.9201063 * th ** (71 / 6)
    )
    return RHO_C * (1.0 - 1.05 * (1.0 - vap))


@_njit
def _rho3_solve(p, T, rho, side):
    """As if97_kernel._rho3_solve for one state: (rho, record, converged)."""
    if not (rho == rho):
        rho = _rho_sat_guess(T, side) if side != 0 else RHO_C
    lo = 1.0
    hi = RHO3_MAX
    for it in range(80):
        pp, pr, _, _, _, rec = region3(rho, T)
        f = pp - p
        good = pr > 0.0
        step = f / pr if good else 0.0
        rt = 2e-14 if it < 6 else 1e-12
        if good and (abs(f) <= 2e-13 * p or abs(step) <= rt * rho):
            return rho, rec, True
        lim = 0.2 * rho
        new = rho - min(max(step, -lim), lim)
        if not good:
            if side > 0:
                new = rho * 1.05
            elif side < 0:
                new = rho * 0.95
            else:
                new = rho * 1.05 if f < 0.0 else rho * 0.95
        if side == 0:
            if f < 0.0:
                lo = rho
            if f > 0.0:
                hi = rho
            if new <= lo or new >= hi:
                new = 0.5 * (lo + hi)
        rho = min(max(new, 1.0), RHO3_MAX)
    return rho, rec, False


@_njit
def _tb23(p):
    return NB23[3] + math.sqrt(max(p * 1e-6 - NB23[4], 0.0) / NB23[2])


@_njit
def _blend(A, B, w, wT, wp):
    dv = B[0] - A[0]
    dh = B[1] - A[1]
    return (
        A[0] + w * dv,
        A[1] + w * dh,
        A[2] + w * (B[2] - A[2]),
        A[3] + w * (B[3] - A[3]) + wT * dv,
        A[4] + w * (B[4] - A[4]) + wp * dv,
        A[5] + w * (B[5] - A[5]) + wT * dh,
        A[6] + w * (B[6] - A[6]) + wp * dh,
    )


_ZERO = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

#: False, True and the phase kinds -1 (vapour side), 0, 1 (liquid side) as array
#: elements, for the calls that pass them as constants: numba types a constant argument
#: as a literal (Literal[bool](True), Literal[int](1)) and compiles a separate
#: specialisation of the callee for each value, on top of the one for a variable
#: argument; _solve_single, _eval and _t_guess then compiled three times each (4.9 of
#: the 8.4 CPU s of the first compile, measured with numba's compile events). An array
#: element is typed bool / int64, so every call uses the one specialisation.
_NL = np.array([False, True])
_NK = np.array([-1, 0, 1], dtype=np.int64)


@_njit
def _eval(p, T, L, rho3):
    """Blended record, region-3 density, region code, converged (see if97_kernel._eval)."""
    z = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    if L:
        w, d = _smooth((T - (T_13 - B13)) / (2.0 * B13))
        wT = d / (2.0 * B13)
        r1 = region1(p, T) if w < 1.0 else z
        r3 = z
        ok = True
        if w > 0.0:
            start = rho3
            if not (start == start) and w < 1.0:
                start = 1.0 / r1[0]
            side = 1
            if T >= T_C:
                side = 0
            elif p >= P_C and start < RHO_C:
                side = -1
            rho3, r3, ok = _rho3_solve(p, T, start, side)
        reg = 1 if w < 0.5 else 3
        return _blend(r1, r3, w, wT, 0.0), rho3, reg, ok
    if p > P_23_MIN:
        tb = _tb23(p)
        w23, d23 = _smooth((T - (tb - B23)) / (2.0 * B23))
        root = math.sqrt(max(p * 1e-6 - NB23[4], 1e-30) / NB23[2])
        dtb = 1e-6 / (2.0 * NB23[2] * root)
    else:
        w23, d23, dtb = 1.0, 0.0, 0.0
    w23T = d23 / (2.0 * B23)
    w23p = -w23T * dtb
    w25, d25 = _smooth((T - T_25) / (2.0 * B25))
    w25T = d25 / (2.0 * B25)
    r2 = region2(p, T) if (w23 > 0.0 and w25 < 1.0) else z
    r5 = region5(p, T) if w25 > 0.0 else z
    r3 = z
    ok = True
    if w23 < 1.0:
        start = rho3
        if not (start == start) and w23 > 0.0:
            start = 1.0 / r2[0]
        side = -1
        if T >= T_C:
            side = 0
        elif p >= P_C and not (start < RHO_C):
            side = 1
        rho3, r3, ok = _rho3_solve(p, T, start, side)
    r25 = _blend(r2, r5, w25, w25T, 0.0)
    reg = 3 if w23 < 0.5 else (2 if w25 < 0.5 else 5)
    return _blend(r3, r25, w23, w23T, w23p), rho3, reg, ok


@_njit
def _psat_slope(T):
    n = N4
    th = T + n[8] / (T - n[9])
    dth = 1.0 - n[8] / (T - n[9]) ** 2
    A = th * th + n[0] * th + n[1]
    B = n[2] * th * th + n[3] * th + n[4]
    Cc = n[5] * th * th + n[6] * th + n[7]
    dA = 2.0 * th + n[0]
    dB = 2.0 * n[2] * th + n[3]
    dC = 2.0 * n[5] * th + n[6]
    D = math.sqrt(B * B - 4.0 * A * Cc)
    dD = (B * dB - 2.0 * (dA * Cc + A * dC)) / D
    den = -B + D
    q = 2.0 * Cc / den
    dq = (2.0 * dC * den - 2.0 * Cc * (-dB + dD)) / (den * den)
    return q**4 * 1e6, 4.0 * q**3 * dq * dth * 1e6


@_njit
def _tsat(p):
    n = N4
    beta = (p * 1e-6) ** 0.25
    E = beta * beta + n[2] * beta + n[5]
    F = n[0] * beta * beta + n[3] * beta + n[6]
    G = n[1] * beta * beta + n[4] * beta + n[7]
    D = 2.0 * G / (-F - math.sqrt(F * F - 4.0 * E * G))
    return 0.5 * (n[9] + D - math.sqrt((n[9] + D) ** 2 - 4.0 * (n[8] + n[9] * D)))


@_njit
def _t2_ph(p, h):
    pm = p * 1e-6
    eta = h / 2e6
    h_bc = (NB2BC[3] + math.sqrt(max(pm - NB2BC[4], 0.0) / NB2BC[2])) * 1e3
    if pm <= 4.0:
        return _poly(pm, eta - 2.1, T2A_I, T2A_J, T2A_N)
    if h >= h_bc:
        return _poly(pm - 2.0, eta - 2.6, T2B_I, T2B_J, T2B_N)
    return _poly(pm + 25.0, eta - 1.8, T2C_I, T2C_J, T2C_N)


@_njit
def _t3v3_ph(p, h):
    pi = p / 100e6
    pm = p * 1e-6
    h3ab = (NH3AB[0] + pm * (NH3AB[1] + pm * (NH3AB[2] + pm * NH3AB[3]))) * 1e3
    if h <= h3ab:
        T = 760.0 * _poly(pi + 0.240, h / 2300e3 - 0.615, T3A_I, T3A_J, T3A_N)
        v = 0.0028 * _poly(pi + 0.128, h / 2100e3 - 0.727, V3A_I, V3A_J, V3A_N)
    else:
        T = 860.0 * _poly(pi + 0.298, h / 2800e3 - 0.720, T3B_I, T3B_J, T3B_N)
        v = 0.0088 * _poly(pi + 0.0661, h / 2800e3 - 0.720, V3B_I, V3B_J, V3B_N)
    return T, v


@_njit
def _t_guess(p, h, kind):
    rho = math.nan
    if kind >= 0:
        T = _poly(p * 1e-6, h / 2.5e6 + 1.0, T1_I, T1_J, T1_N)
        use3 = p > P_13_SAT and T > T_13
    else:
        T = _t2_ph(p, h)
        use3 = p > P_13_SAT and T < _tb23(p)
    if use3:
        T3, v3 = _t3v3_ph(p, h)
        T = T3
        rho = 1.0 / v3
        if kind == 0 and T > _tb23(p):
            T = _t2_ph(p, h)
            rho = math.nan
    return T, rho


@_njit
def _solve_region3(p, h, rho, T):
    tol_h = 2e-14 * abs(h) + 1e-9
    rec = _ZERO
    for it in range(30):
        pp, pr, pT_, hr, hT, rec = region3(rho, T)
        fp = pp - p
        fh = rec[1] - h
        det = pr * hT - pT_ * hr
        dr = (-fp * hT + pT_ * fh) / det
        dT = (-fh * pr + hr * fp) / det
        rt = 2e-14 if it < 6 else 1e-12
        if (abs(fp) <= 2e-13 * p and abs(fh) <= tol_h) or (
            abs(dr) <= rt * rho and abs(dT) <= rt * T
        ):
            return T, rec, rho, True
        if not (math.isfinite(dr) and math.isfinite(dT)):
            return T, rec, rho, False
        lim = 0.2 * rho
        rho = min(max(rho + min(max(dr, -lim), lim), 1.0), RHO3_MAX)
        T = T + min(max(dT, -10.0), 10.0)
    return T, rec, rho, False


@_njit
def _solve_single(p, h, kind, lo, hi, Tw):
    """(T, record, region, status) for a single-phase state (see if97_kernel._solve_single).

    Tw [K]: a start temperature (warm start from a nearby solved state, :class:`PhMemo`)
    or NaN: then the backward equations give the start (and, in region 3, the density)."""
    if Tw == Tw:
        T0, rho0 = Tw, math.nan
    else:
        T0, rho0 = _t_guess(p, h, kind)
    if not (T0 > T_MIN + 1.0):
        rec, _, _, _ = _eval(p, T_MIN, _NL[1], rho0)
        if h < rec[1]:
            return math.nan, _ZERO, 0, 4
    if kind <= 0 and not (T0 < hi - 2.0):
        rec, _, _, _ = _eval(p, hi, _NL[0], rho0)
        if h > rec[1]:
            return math.nan, _ZERO, 0, 5
    if rho0 == rho0 and T0 > T_13 + B13 + 1.0 and T0 < _tb23(p) - B23 - 1.0:
        T3, rec3, _, ok3 = _solve_region3(p, h, rho0, T0)
        if ok3 and T3 >= T_13 + B13 and T3 <= _tb23(p) - B23 and lo <= T3 <= hi:
            return T3, rec3, 3, 0
    T = T0 if T0 == T0 else 0.5 * (lo + hi)
    T = min(max(T, lo), hi)
    rho3 = rho0
    tol = 2e-14 * abs(h) + 1e-9
    dT_old = math.inf
    for it in range(60):
        if kind == 0:
            L = T < 0.5 * (T_13 + _tb23(p))
        else:
            L = kind > 0
        rec, rho3, reg, conv = _eval(p, T, L, rho3)
        g = rec[1] - h
        step = g / rec[5]
        stol = 2e-14 if it < 5 else 4e-13
        if conv and (abs(g) <= tol or abs(step) <= stol * T):
            return T, rec, reg, 0
        if g < 0.0:
            lo = T
        if g > 0.0:
            hi = T
        Tn = T - step
        if not (lo < Tn < hi) or abs(2.0 * step) > dT_old:
            dT_old = 0.5 * (hi - lo)
            Tn = 0.5 * (lo + hi)
        else:
            dT_old = abs(step)
        if hi - lo <= 4e-16 * hi:
            return math.nan, _ZERO, 0, 7
        T = Tn
    return math.nan, _ZERO, 0, 7


@_njit
def _sat_records(p):
    Ts = _tsat(p)
    _, dps = _psat_slope(Ts)
    recL, _, _, okL = _eval(p, Ts, _NL[1], math.nan)
    recV, _, _, okV = _eval(p, Ts, _NL[0], math.nan)
    return Ts, 1.0 / dps, recL, recV, okL and okV


@_njit
def ph_scalar(p, h):
    """(T, rho, u, s, cp, x, drho_dp_h, drho_dh_p, region, status) at (p [Pa], h [J/kg])."""
    return _ph_auto(p, h, math.nan)[0]


#: an upper bound [J/kg] of h''(p) over the whole saturation line (its maximum is
#: 2803.285 kJ/kg at 3.08 MPa): above it a state is vapour without evaluating h''(p)
H_VAP_MAX = 2.8035e6


@_njit
def _ph_auto(p, h, Tw):
    """(state tuple of :func:`ph_scalar`, (dT/dp)_h [K/Pa] (NaN in the dome or not ok)).

    Tw: warm-start temperature of a single-phase state, or NaN (:func:`_solve_single`)."""
    nan = math.nan
    if not (math.isfinite(p) and math.isfinite(h)):
        return (nan, nan, nan, nan, nan, nan, nan, nan, 0, 1), nan
    if p < P_MIN:
        return (nan, nan, nan, nan, nan, nan, nan, nan, 0, 2), nan
    if p > P_MAX:
        return (nan, nan, nan, nan, nan, nan, nan, nan, 0, 3), nan
    kind = 0
    lo = T_MIN
    hi = T_MAX_R5 if p <= P_R5_MAX else T_25
    if p < P_C:
        Ts = _tsat(p)
        # one saturated side decides most states; both are needed only in the dome and
        # near p_c (where the dome closes); above H_VAP_MAX neither
        near_c = p > 21e6
        if h > H_VAP_MAX and not near_c:
            return _single_tp(p, h, _solve_single(p, h, _NK[0], Ts, hi, Tw))
        if near_c or h < 2.0e6:
            recL, _, _, _ = _eval(p, Ts, _NL[1], nan)
            if h < recL[1] and not near_c:
                return _single_tp(p, h, _solve_single(p, h, _NK[2], lo, Ts, Tw))
            recV, _, _, _ = _eval(p, Ts, _NL[0], nan)
        else:
            recV, _, _, _ = _eval(p, Ts, _NL[0], nan)
            if h > recV[1]:
                return _single_tp(p, h, _solve_single(p, h, _NK[0], Ts, hi, Tw))
            recL, _, _, _ = _eval(p, Ts, _NL[1], nan)
        _, dps = _psat_slope(Ts)
        dTs = 1.0 / dps
        hL = recL[1]
        hV = recV[1]
        if not (hV > hL):
            kind = 0
        elif h < hL:
            kind = 1
            hi = Ts
        elif h > hV:
            kind = -1
            lo = Ts
        else:
            return _dome(p, h, Ts, dTs, recL, recV), nan
    return _single_tp(p, h, _solve_single(p, h, kind, lo, hi, Tw))


@_njit
def _single_tp(p, h, solved):
    """(state tuple of :func:`_single_out`, (dT/dp)_h = -(dh/dp)_T / cp [K/Pa])."""
    T, rec, reg, st = solved
    return _single_out(p, h, T, rec, reg, st), -rec[6] / rec[5] if st == 0 else math.nan


@_njit
def _dome(p, h, Ts, dTs, recL, recV):
    """The homogeneous two-phase state at (p, h) from the saturated records (any x:
    outside 0 <= x <= 1 it is the dome's formula continued, used by a forced branch)."""
    dh = recV[1] - recL[1]
    vL, vV = recL[0], recV[0]
    dv = vV - vL
    x = (h - recL[1]) / dh
    v = vL + x * dv
    rho = 1.0 / v
    vLp = recL[4] + recL[3] * dTs
    vVp = recV[4] + recV[3] * dTs
    hLp = recL[6] + recL[5] * dTs
    hVp = recV[6] + recV[5] * dTs
    dp_h = -rho * rho * (vLp + x * (vVp - vLp) - dv * (hLp + x * (hVp - hLp)) / dh)
    return (
        Ts,
        rho,
        h - p / rho,
        recL[2] + x * (recV[2] - recL[2]),
        math.inf,
        x,
        dp_h,
        -rho * rho * dv / dh,
        4,
        0,
    )


#: how far [K] beyond T_sat(p) a forced single-phase branch may be continued
#: (metastable liquid or vapour); further out the state is computed as usual
BRANCH_MARGIN_T = 30.0

#: branch codes of :func:`ph_branch_scalar`
AUTO, LIQUID, DOME, VAPOUR = 0, 1, 2, 3


@_njit
def ph_branch_scalar(p, h, branch):
    """As :func:`ph_scalar`, with the phase branch forced (p < p_c only).

    branch AUTO: :func:`ph_scalar`. LIQUID: the liquid-side equations (region 1, or
    region 3 on its liquid root) continued past h'(p) into metastable liquid, up to
    T_sat + BRANCH_MARGIN_T. VAPOUR: the vapour side continued below h''(p). DOME:
    the homogeneous mixture formula continued to x < 0 and x > 1. Each branch is
    smooth in (p, h) and equals the true state on its own side of the saturation
    line, so a model that keeps a volume's branch between located crossings (a
    discrete mode, ``dnasim.library.submodels.channel``) sees no kink within a step. Where
    the forced branch has no solution the true state is returned.
    """
    return _ph_branch(p, h, branch, math.nan)[0]


@_njit
def _ph_branch(p, h, branch, Tw):
    """(state tuple of :func:`ph_branch_scalar`, (dT/dp)_h [K/Pa]); Tw as in
    :func:`_ph_auto`."""
    if branch == AUTO or not (P_MIN <= p < P_C) or not (math.isfinite(p) and math.isfinite(h)):
        return _ph_auto(p, h, Tw)
    Ts = _tsat(p)
    if branch == LIQUID:
        r = _single_tp(p, h, _solve_single(p, h, _NK[2], T_MIN, Ts + BRANCH_MARGIN_T, Tw))
        if r[0][9] != 0:
            return _ph_auto(p, h, math.nan)
        return r
    if branch == VAPOUR:
        hi = T_MAX_R5 if p <= P_R5_MAX else T_25
        lo = max(Ts - BRANCH_MARGIN_T, T_MIN)
        r = _single_tp(p, h, _solve_single(p, h, _NK[0], lo, hi, Tw))
        if r[0][9] != 0:
            return _ph_auto(p, h, math.nan)
        return r
    _, dps = _psat_slope(Ts)
    recL, _, _, okL = _eval(p, Ts, _NL[1], math.nan)
    recV, _, _, okV = _eval(p, Ts, _NL[0], math.nan)
    if not (okL and okV and recV[1] > recL[1]):
        return _ph_auto(p, h, math.nan)
    return _dome(p, h, Ts, 1.0 / dps, recL, recV), math.nan


@_njit
def _single_out(p, h, T, rec, reg, st):
    nan = math.nan
    if st != 0:
        return nan, nan, nan, nan, nan, nan, nan, nan, 0, st
    v = rec[0]
    cp = rec[5]
    vT = rec[3]
    rho = 1.0 / v
    return (
        T,
        rho,
        h - p / rho,
        rec[2],
        cp,
        nan,
        -(rec[4] - vT * rec[6] / cp) / (v * v),
        -vT / (v * v * cp),
        reg,
        0,
    )


@_njit
def _store(r, i, T, rho, u, s, cp, x, dp, dh, region, status):
    """Write the state tuple r of ``ph_scalar`` into position i of the output arrays."""
    T[i] = r[0]
    rho[i] = r[1]
    u[i] = r[2]
    s[i] = r[3]
    cp[i] = r[4]
    x[i] = r[5]
    dp[i] = r[6]
    dh[i] = r[7]
    region[i] = r[8]
    status[i] = r[9]


@_njit
def _ph_branch_loop(p, h, branch, T, rho, u, s, cp, x, dp, dh, region, status):
    for i in range(p.size):
        r = ph_branch_scalar(p[i], h[i], branch[i])
        _store(r, i, T, rho, u, s, cp, x, dp, dh, region, status)


#: states remembered per point by :class:`PhMemo`: the base state and the two states a
#: difference quotient makes by moving p and h of the point in consecutive columns
MEMO_SLOTS = 3


@_njit
def _ph_memo_loop(p, h, branch, order, F, B, RS, T, rho, u, s, cp, x, dp, dh, region, status):
    """As _ph_branch_loop, remembering each point's last MEMO_SLOTS states in the memo
    arrays of :class:`PhMemo` (order[:, i]: its slots from the most to the least recently
    used); returns how many points were computed.

    A point whose (p, h, branch) equals a remembered one is copied from it; otherwise a
    single-phase point of region 1 or 2 starts its T iteration from the most recent
    state moved to first order, T_w = T' + (h - h')/cp' + (dT/dp)_h' (p - p'), instead
    of the backward equations (and from them again if that iteration fails), and the
    result replaces the least recently used slot."""
    n_slots = order.shape[0]
    computed = 0
    for i in range(p.size):
        pi = p[i]
        hi = h[i]
        bi = branch[i]
        rank = -1
        for r in range(n_slots):
            k = order[r, i]
            if pi == F[k, 0, i] and hi == F[k, 1, i] and bi == B[k, i]:
                rank = r
                break
        if rank >= 0:
            T[i] = F[k, 3, i]
            rho[i] = F[k, 4, i]
            u[i] = F[k, 5, i]
            s[i] = F[k, 6, i]
            cp[i] = F[k, 7, i]
            x[i] = F[k, 8, i]
            dp[i] = F[k, 9, i]
            dh[i] = F[k, 10, i]
            region[i] = RS[k, 0, i]
            status[i] = RS[k, 1, i]
        else:
            a = order[0, i]
            Tw = math.nan
            if RS[a, 1, i] == 0 and bi == B[a, i] and (RS[a, 0, i] == 1 or RS[a, 0, i] == 2):
                Tw = F[a, 3, i] + (hi - F[a, 1, i]) / F[a, 7, i] + F[a, 2, i] * (pi - F[a, 0, i])
                # near the limits of the range the backward equations decide (status 4, 5)
                if not (T_MIN + 2.0 < Tw < T_25 - 3.0):
                    Tw = math.nan
            r, Tp = _ph_branch(pi, hi, bi, Tw)
            if r[9] != 0 and Tw == Tw:
                # the warm start failed (a point moved far, e.g. from region 1 into
                # region 3, where the first-order T_w is no start): the cold path, as
                # without a memo
                r, Tp = _ph_branch(pi, hi, bi, math.nan)
            computed += 1
            _store(r, i, T, rho, u, s, cp, x, dp, dh, region, status)
            rank = n_slots - 1
            k = order[rank, i]
            F[k, 0, i] = pi
            F[k, 1, i] = hi
            F[k, 2, i] = Tp
            F[k, 3, i] = r[0]
            F[k, 4, i] = r[1]
            F[k, 5, i] = r[2]
            F[k, 6, i] = r[3]
            F[k, 7, i] = r[4]
            F[k, 8, i] = r[5]
            F[k, 9, i] = r[6]
            F[k, 10, i] = r[7]
            B[k, i] = bi
            RS[k, 0, i] = r[8]
            RS[k, 1, i] = r[9]
        for r in range(rank, 0, -1):  # slot k becomes the most recently used
            order[r, i] = order[r - 1, i]
        order[0, i] = k
    return computed


class PhMemo:
    """The last MEMO_SLOTS states of each of a fixed set of points, for
    :func:`ph_arrays` (``memo=``).

    A finite-difference Jacobian moves a few points per residual and a Newton iteration
    moves every point by little: with a memo, unchanged points are copied and moved
    single-phase points start their temperature iteration from the remembered state
    (one or two evaluations of the Gibbs function instead of the backward equation and
    three). A warm-started result agrees with a call without memo to round-off (the
    iteration stops at the same tolerance), not to the bit, so several states are kept:
    a point moved by difference quotients (its p in one column, its h in the next) and
    moved back is copied, and F(y) is reproduced exactly (a difference quotient
    (F - F(y))/d would turn the round-off into errors of 1e-13 |F| / d in entries that
    should be zero). ``computed``: the points computed by the last call.
    """

    def __init__(self):
        self.n = -1
        self.computed = 0

    def arrays(self, n):
        """The memo arrays (order, floats, branches, region and status) for n points,
        reset when n changes: floats[slot] holds p, h, (dT/dp)_h, then T, rho, u, s,
        cp, x, drho_dp_h, drho_dh_p."""
        if n != self.n:
            self.n = n
            k = MEMO_SLOTS
            self.order = np.repeat(np.arange(k, dtype=np.int64)[:, None], n, axis=1)
            self.floats = np.full((k, 11, n), np.nan)
            self.branches = np.full((k, n), -1, dtype=np.int64)
            self.region_status = np.ones((k, 2, n), dtype=np.int8)
        return self.order, self.floats, self.branches, self.region_status

    def scratch(self, n):
        """Output arrays for ``ph_memo_T_rho_u``'s unused fields (s, cp, x, drho_dp_h,
        drho_dh_p, region), its status array, and n AUTO branch codes (zeros, read-only)."""
        out = self.__dict__.get("_scratch")
        if out is None or out[0].size != n:
            f = [np.empty(n) for _ in range(5)]
            out = self._scratch = (
                *f,
                np.empty(n, dtype=np.int8),
                np.empty(n, dtype=np.int8),
                _read_only(np.zeros(n, dtype=np.int64)),
            )
        return out


def ph_memo_T_rho_u(p, h, branch, memo):
    """(T [K], rho [kg/m3], u [J/kg], status) at the 1-D float arrays p [Pa], h [J/kg]
    with a :class:`PhMemo`: the numbers of ``ph_arrays(p, h, branch, memo)`` (the same
    compiled loop), without building a :class:`PhResult` (a residual's property call
    for a few points costs 2 us in the loop and 11 us in ``ph_arrays``' Python). The
    other fields go to scratch arrays kept in the memo; T, rho, u are new arrays.
    branch: None (AUTO) or an int64 array of the points' branch codes."""
    p = np.ascontiguousarray(p, dtype=float)
    h = np.ascontiguousarray(h, dtype=float)
    n = p.size
    scratch = memo.scratch(n)
    T, rho, u = np.empty(n), np.empty(n), np.empty(n)
    if branch is None:
        branch = scratch[-1]
    else:  # read-only, as ``ph_arrays`` passes it (``_read_only``)
        branch = _read_only(np.ascontiguousarray(branch, dtype=np.int64))
    memo.computed = _ph_memo_loop(p, h, branch, *memo.arrays(n), T, rho, u, *scratch[:-1])
    return T, rho, u, scratch[-2]


def _read_only(a):
    """A read-only view of a: the branch codes ``ph_arrays`` hands the memo loop are a
    read-only view (``np.broadcast_to``), and numba compiles one specialisation per
    writability; ``ph_memo_T_rho_u`` passes the same kind, so both use the one that
    ``dnasim.media.if97`` loads at start (not a second one to compile and load)."""
    v = a.view()
    v.flags.writeable = False
    return v


def ph_arrays(p, h, branch=None, memo=None) -> K.PhResult:
    """As :func:`dnasim.media.if97_kernel.ph`, compiled: a :class:`PhResult` of arrays.

    branch: None, or an int array of the points' branch codes (AUTO, LIQUID, DOME,
    VAPOUR; see :func:`ph_branch_scalar`). memo: None, or a :class:`PhMemo` kept by
    the caller for this set of points (its last states: unchanged points are copied,
    moved ones warm-started)."""
    p, h = np.broadcast_arrays(np.asarray(p, dtype=float), np.asarray(h, dtype=float))
    shape = p.shape
    pf = np.ascontiguousarray(p.ravel())
    hf = np.ascontiguousarray(h.ravel())
    r = K.PhResult()
    n = pf.size
    r.p = pf.copy()
    r.h = hf.copy()
    for f in ("T", "rho", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p"):
        setattr(r, f, np.empty(n))
    r.region = np.empty(n, dtype=np.int8)
    r.status = np.empty(n, dtype=np.int8)
    out = (r.T, r.rho, r.u, r.s, r.cp, r.x, r.drho_dp_h, r.drho_dh_p, r.region, r.status)
    if memo is not None:
        bf = np.zeros(n, dtype=np.int64) if branch is None else branch
        bf = np.ascontiguousarray(np.broadcast_to(np.asarray(bf, dtype=np.int64), shape).ravel())
        bf = _read_only(bf)
        memo.computed = _ph_memo_loop(pf, hf, bf, *memo.arrays(n), *out)
    else:
        # one loop for both: AUTO (0) is ph_scalar's path, so no second loop to compile;
        # read-only branch codes always, one specialisation (see _read_only)
        if branch is None:
            bf = np.zeros(n, dtype=np.int64)
        else:
            bf = np.broadcast_to(np.asarray(branch, dtype=np.int64), shape).ravel()
        _ph_branch_loop(pf, hf, _read_only(np.ascontiguousarray(bf)), *out)
    r.v = 1.0 / r.rho
    r.ok = r.status == 0
    if shape != (n,):
        for f in K.PhResult.__slots__:
            setattr(r, f, getattr(r, f).reshape(shape))
    return r


@_njit
def h_pT_scalar(p, T):
    """(h [J/kg], status) at (p [Pa], T [K]), single phase (status codes of if97_kernel)."""
    if not (math.isfinite(p) and math.isfinite(T)):
        return math.nan, 1
    if p < P_MIN:
        return math.nan, 2
    if p > P_MAX:
        return math.nan, 3
    if T < T_MIN:
        return math.nan, 4
    if T > (T_MAX_R5 if p <= P_R5_MAX else T_25):
        return math.nan, 5
    if p < P_C:
        Ts = _tsat(p)
        if abs(T - Ts) <= T_SAT_BAND:
            return math.nan, 6
        L = T < Ts
    else:
        L = T < 0.5 * (T_13 + _tb23(p))
    rec, _, _, ok = _eval(p, T, L, math.nan)
    if not ok:
        return math.nan, 7
    return rec[1], 0


@_njit
def saturation_scalar(p):
    """(h', h'') [J/kg] at p [Pa]; NaN outside [P_MIN, p_c)."""
    if not (P_MIN <= p < P_C):
        return math.nan, math.nan
    _, _, recL, recV, _ = _sat_records(p)
    return recL[1], recV[1]


@_njit
def _sat_loop(p, hl, hv):
    for i in range(p.size):
        hl[i], hv[i] = saturation_scalar(p[i])


def saturation_arrays(p):
    """(h', h'') [J/kg] arrays of the shape of p [Pa]; NaN outside [P_MIN, p_c)."""
    p = np.asarray(p, dtype=float)
    pf = np.ascontiguousarray(p.ravel())
    hl = np.empty(pf.size)
    hv = np.empty(pf.size)
    _sat_loop(pf, hl, hv)
    return hl.reshape(p.shape), hv.reshape(p.shape)
