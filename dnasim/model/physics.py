"""Small physics helpers shared by components: property arrays, log-mean
temperature difference, regularised friction and valve laws.

All functions are vectorised over numpy arrays.
"""

from __future__ import annotations

import math
from contextlib import contextmanager

import numpy as np

from dnasim.core.timefunctions import Constant

G = 9.80665  # standard gravity [m/s2]


def properties(medium, p, h, branch=None):
    """T [K], rho [kg/m3], u [J/kg] at each (p [Pa], h [J/kg]) as arrays.

    branch: None, or per point the phase branch to evaluate (``has_phase_branches``;
    codes of ``dnasim.media.if97_numba.ph_branch_scalar``: 0 auto, 1 liquid, 2 dome,
    3 vapour); points with branch 0 are evaluated as usual.

    One ``medium.states(p, h)`` call for all points (IF97 water, ideal gases and gas
    mixtures evaluate it as array code; CoolProp media loop inside it); a single point
    goes through the cached ``medium.state`` (cheaper than an array call's fixed cost,
    and shared with the other components at the same node). Raises the medium's
    ``PropertyError`` (a ``ResidualDomainError``) when a state is out of range.
    """
    p = np.atleast_1d(np.asarray(p, dtype=float))
    h = np.atleast_1d(np.asarray(h, dtype=float))
    if branch is not None and np.any(branch):
        r = medium.states(p, h, branch=branch)
        return r.T, r.rho, r.u
    if p.size == 1:
        s = medium.state(float(p[0]), float(h[0]))
        return np.array([s.T]), np.array([s.rho]), np.array([s.u])
    r = medium.states(p, h)
    return r.T, r.rho, r.u


def has_phase_branches(medium) -> bool:
    """True when ``medium.states`` takes ``branch=`` (a forced phase branch per point:
    IF97 water on its compiled kernel)."""
    return bool(getattr(medium, "phase_branches", False))


class _Aside:
    """How many ``aside()`` blocks are open, and the memos' generation
    (``forget_memos``); ``PropertyArrays`` reads both."""

    depth = 0
    generation = 0


def forget_memos() -> None:
    """Every ``PropertyArrays`` starts afresh at its next call, as if new: a simulation
    of a compiled System run twice in one process (a sweep's cases, a notebook) takes
    the same steps each time, whatever was evaluated before (``simulate`` calls this
    at its start)."""
    _Aside.generation += 1


@contextmanager
def aside():
    """Property evaluations inside this block leave no trace in the memos.

    A ``PropertyArrays`` with an IF97 memo starts each moved point's iteration from the
    state it remembers, so its result depends, to round-off, on the points it was called
    with before. Evaluations made for the output (derived values of a row, the re-solve
    of the algebraic values at an output point between steps) must not move the
    integration's later evaluations by that round-off: measured on plants/drum_unit.toml,
    output every 10 s and every 7 s took different step sequences from the first step
    after the start's rest (302.6139 and 302.6105 s), with 78 and 65 Jacobians over
    600 s, and property evaluations without the memo took the same steps for both. Inside
    the block a memoised ``PropertyArrays`` evaluates cold (``properties``) and leaves its
    memo as it was; one without a memo is a pure function of its points anyway.
    Not thread-safe (a process-wide count), like the memos themselves.
    """
    _Aside.depth += 1
    try:
        yield
    finally:
        _Aside.depth -= 1


class PropertyArrays:
    """``properties`` for a fixed set of points that remembers its last result.

    Only the points whose (p, h) changed since the previous call are sent to the
    medium, in one ``medium.states`` call. A finite-difference Jacobian perturbs a
    few points at a time, so for a long pipe this saves most property evaluations;
    a Newton iteration changes every point and costs one array call. A medium with
    ``states_memo`` (IF97 water, compiled) does this bookkeeping itself, in its
    compiled loop, and also starts each moved point from its previous state.
    """

    def __init__(self):
        self.p = None
        self.h = None
        self.branch = None
        self.out = None
        self.medium = None
        self.memo = None
        self.generation = _Aside.generation

    def __call__(self, medium, p, h, branch=None):
        """As ``properties``; ``branch`` (int array or None) is part of each point's key."""
        if self.medium is not medium or self.generation != _Aside.generation:
            self.medium = medium
            self.generation = _Aside.generation
            self.p = None
            new_memo = getattr(medium, "states_memo", None)
            self.memo = new_memo() if new_memo is not None else None
        if self.memo is not None and _Aside.depth:
            return properties(medium, p, h, branch)  # cold: the memo stays as it is
        lean = getattr(medium, "T_rho_u", None)
        if lean is not None and type(p) is np.ndarray and p.ndim == 1:
            # (T, rho, u) alone: IF97 water with its memo (the same compiled loop as
            # ``states(..., memo=)``), an ideal gas's closed forms (a medium without
            # memos: no point is worth remembering)
            if self.memo is not None or not hasattr(medium, "states_memo"):
                return lean(p, h, branch, self.memo)
        if self.memo is not None:
            r = medium.states(p, h, branch=branch, memo=self.memo)
            return r.T, r.rho, r.u
        p = np.asarray(p, dtype=float)
        h = np.asarray(h, dtype=float)
        b = np.zeros(p.shape, dtype=np.int64) if branch is None else np.asarray(branch)
        if self.p is None or self.p.shape != p.shape:
            T, rho, u = properties(medium, p, h, b)
        else:
            changed = np.flatnonzero((p != self.p) | (h != self.h) | (b != self.branch))
            if changed.size == 0:
                return tuple(a.copy() for a in self.out)
            if changed.size == p.size:
                T, rho, u = properties(medium, p, h, b)
            else:
                T, rho, u = (a.copy() for a in self.out)
                T[changed], rho[changed], u[changed] = properties(
                    medium, p[changed], h[changed], b[changed]
                )
        self.p, self.h, self.branch, self.out = p.copy(), h.copy(), b.copy(), (T, rho, u)
        return T.copy(), rho.copy(), u.copy()


def softplus(x, eps):
    """eps * ln(1 + exp(x / eps)) + 1e-9 eps: a smooth, strictly positive max(x, 0).

    The floor 1e-9 eps keeps the value from underflowing to zero (for x < -745 eps),
    where the logarithmic mean below would otherwise jump."""
    return eps * (np.logaddexp(0.0, np.asarray(x, dtype=float) / eps) + 1e-9)


def logarithmic_mean(x, y):
    """(x - y) / ln(x / y) for x, y > 0, continued smoothly to (x + y)/2 at x = y.

    With d = (x - y)/(x + y), ln(x/y) = 2 artanh(d), so the mean is
    (x + y)/2 * d / artanh(d); for |d| < 1e-3 the series
    d/artanh(d) = 1 - d^2/3 - 4 d^4/45 (error O(d^6) < 1e-18) is used. Where both
    arguments are zero the mean is zero. No logarithm of a non-positive number is
    ever taken.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    s = x + y
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        d = np.where(s > 0, (x - y) / np.where(s > 0, s, 1.0), 0.0)
        small = np.abs(d) < 1e-3
        d2 = d * d
        series = 0.5 * s * (1.0 - d2 / 3.0 - 4.0 * d2 * d2 / 45.0)
        safe_x = np.where(small | (x <= 0), 1.0, x)
        safe_y = np.where(small | (y <= 0), 2.0, y)
        exact = (safe_x - safe_y) / np.log(safe_x / safe_y)
        out = np.where(small, series, exact)
        # one argument underflowed to zero: the mean is zero in the limit
        out = np.where((x <= 0) | (y <= 0), 0.0, out)
    return out


#: arrays at least this long go to the compiled ``lmtd`` (``lmtd_numba``); shorter ones
#: stay in numpy, so a small plant does not import numba for it
LMTD_NUMBA_MIN = 64


def _lmtd_compiled():
    """``lmtd_numba.lmtd``, imported on first use; None when numba is missing."""
    if _lmtd_compiled.fn is False:
        try:
            from dnasim.model.lmtd_numba import lmtd as fn
        except ImportError:  # pragma: no cover - numba is a dependency
            fn = None
        _lmtd_compiled.fn = fn
    return _lmtd_compiled.fn


_lmtd_compiled.fn = False


def lmtd(dT_a, dT_b, dT_reg):
    """Regularised, signed log-mean temperature difference [K].

    dT_a, dT_b: temperature differences fluid minus wall at the two ends.
    For dT_a, dT_b >> dT_reg > 0 it equals (dT_a - dT_b)/ln(dT_a/dT_b); for both
    << -dT_reg it equals minus the same for |dT|; at dT_a = dT_b it is the plain
    difference dT_a. It is smooth everywhere (also when the two differences have
    opposite signs, which happens during Newton iterations) because it is built
    from the logarithmic mean of softplus(+dT) minus that of softplus(-dT).

    Why the regularisation width matters: the exact LMTD has an infinite slope
    where one end's difference reaches zero (dL/db = a / (b ln^2(a/b)) as b -> 0),
    so after a step of the inlet temperature of a pipe at thermal equilibrium the
    heat flow ODE is not Lipschitz and Newton fails. With width dT_reg the slope
    is bounded by about a / (dT_reg ln^2(a/dT_reg)); for |dT| >~ 10 dT_reg the
    value is the exact LMTD to 1e-4 relative.

    Arrays of ``LMTD_NUMBA_MIN`` elements or more (long channels) are computed by the
    compiled loop of ``dnasim.model.lmtd_numba`` (the same operations; equal to
    round-off; at 1000 elements 2.7 times faster with every |dT| < 40 dT_reg, more
    beyond).
    """
    if (
        isinstance(dT_a, np.ndarray)
        and isinstance(dT_b, np.ndarray)
        and dT_a.shape == dT_b.shape
        and dT_a.size >= LMTD_NUMBA_MIN
        and _lmtd_compiled() is not None
    ):
        return _lmtd_compiled()(dT_a, dT_b, dT_reg)
    return lmtd_numpy(dT_a, dT_b, dT_reg)


def lmtd_numpy(dT_a, dT_b, dT_reg):
    """``lmtd`` in numpy whatever the size [K]; ``dT_reg`` [K] may be an array of the
    shape of the differences (channels of different widths evaluated together)."""
    # the four softplus arrays (a_pos, b_pos; a_neg, b_neg) in one array z[sign, end],
    # and the two logarithmic means in one call: the same operations on each element
    # as four and two calls, bit-identical (tests/test_physics.py), for a third of the
    # numpy calls (a short channel: 29 -> 15 us)
    dT_a, dT_b = np.broadcast_arrays(np.asarray(dT_a, dtype=float), np.asarray(dT_b, dtype=float))
    z = np.empty((2, 2) + dT_a.shape)
    z[0, 0] = dT_a
    z[0, 1] = dT_b
    np.negative(z[0], out=z[1])
    sp = softplus(z, dT_reg)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        mean = _logmean_positive(sp[:, 0], sp[:, 1])
    return mean[0] - mean[1]


def _logmean_positive(x, y):
    """``logarithmic_mean`` for x, y > 0 (softplus values), the same operations
    without the branches for zero arguments: bit-identical there, and half the
    numpy calls. Call under ``np.errstate`` (nan inputs)."""
    s = x + y
    d = (x - y) / s
    small = np.abs(d) < 1e-3
    if not small.any():  # no pair nearly equal (the usual case): the closed form alone
        return (x - y) / np.log(x / y)
    d2 = d * d
    series = 0.5 * s * (1.0 - d2 / 3.0 - 4.0 * d2 * d2 / 45.0)
    safe_x = np.where(small, 1.0, x)
    safe_y = np.where(small, 2.0, y)
    exact = (safe_x - safe_y) / np.log(safe_x / safe_y)
    return np.where(small, series, exact)


#: default friction regularisation flow m_reg = M_REG_REL * m_nominal. Below m_reg
#: the friction law turns linear (laminar-like). It must not be much smaller: at
#: zero flow the slope d(dp)/dm = k m_reg/rho is all that ties a face's flow to
#: the pressures, and pressures are resolved only to about rtol * p; with 1e-4
#: m_nominal (the former default) a steam pipe's face flows were undetermined by
#: tens of kg/s at a flow reversal and Newton failed. ThermoPower uses the same
#: order (its "wnf", fraction of nominal flow where linear friction equals
#: turbulent friction, 0.01 to 0.02). At m_nominal the law differs from
#: k m|m|/rho by (m_reg/m)^2/2 = 5e-5.
M_REG_REL = 1e-2

#: temperature scale [K] of a wall heat flow's nominal value Q_nom = (kA/n) DT_Q_NOMINAL
#: (pipes, heat exchangers), from which its atol = atol_scaled Q_nom. The fluid's
#: own states resolve its temperature to about rtol u / c_p ~ rtol x 1000 K (u ~ c_p T
#: from the IF97 reference state), so Q = kA (T - T_w) is resolved alike with a
#: 1000 K scale. The former 10 K asked T - T_w to 1e-5 K at rtol 1e-6, 100 times
#: tighter: the 1000-volume steam pipe with its algebraic variables in the error test
#: took 12927 steps, 489 with this scale (benchmarks/README.md).
DT_Q_NOMINAL = 1000.0


def friction_dp(k, m, rho, m_reg):
    """Friction pressure drop k m sqrt(m^2 + m_reg^2) / rho [Pa].

    Equals k m|m|/rho for |m| >> m_reg, odd in m (reverse flow gives reverse
    drop), and keeps d(dp)/dm > 0 at m = 0 so that a zero-flow state does not
    make the Jacobian singular.
    """
    return k * m * np.sqrt(m * m + m_reg * m_reg) / rho


def valve_flow(C, z, dp, dp_reg):
    """Regularised valve law m = C z dp / (dp^2 + dp_reg^2)^(1/4) [kg/s].

    For |dp| >> dp_reg this is C z sign(dp) sqrt(|dp|) (relative error
    (dp_reg/dp)^2/4); near dp = 0 it is linear with finite slope
    C z / sqrt(dp_reg), so the Jacobian stays finite. Reverse flow for dp < 0.
    """
    return C * z * dp / (dp * dp + dp_reg * dp_reg) ** 0.25


#: m_eps = M_EPS_REL * m_nominal: the half-width of the flow band in which the
#: upwind weight is regularised (``upwind_weight``). Outside the band, |m| >= m_eps,
#: upwinding is exact: a forward flow of 1e-3 m_nominal or more carries exactly the
#: upstream enthalpy, so steady closed forms hold to round-off. Inside it, both
#: sides weigh in, and at zero flow states stay defined and the Jacobian regular.
#: Why not smaller: a node's mixed enthalpy switches from one side's value to the
#: other's across the band; when the band is much narrower than the flow changes a
#: Newton iteration makes (1e-6 m_nominal was tried), the node enthalpy cannot
#: converge there and flow reversals stop the run (measured on an air pipe whose
#: back pressure is ramped above the inlet pressure).
M_EPS_REL = 1e-3


#: smallest relative band of a control valve (``opening_band``): a closed valve's band is
#: 1e-3 of its full-open one, m_eps = 1e-6 m_nominal, the order of the flows' absolute
#: tolerance (atol_scaled m_nominal), so that a leakage flow changing sign is resolved.
Z_BAND_MIN = 1e-3


def fixed_value(v) -> bool:
    """True when a parameter's value does not change in time: a number or a
    ``timefunctions.Constant`` (a time-function parameter given as a number)."""
    return isinstance(v, (int, float, Constant))


def opening_band(eps, z_e):
    """A valve's upwind band [kg/s] at effective opening z_e [-]: eps sqrt(z_e^2 + Z_BAND_MIN^2)
    (eps [kg/s]: the full-open band M_EPS_REL m_nominal).

    The band is 1e-3 of the flow the valve can pass at its present opening, as it is
    1e-3 of the nominal flow for the other components: a closed valve exchanges no
    more than its (exactly upwinded) leakage between its two nodes, and at zero flow
    w(0) = 3/16 band + 2.5e-4 eps (the tail, kept at the full-open scale,
    ``upwind_weight``), 2.3e-3 of what a pump or pipe beside it exchanges. With a
    fixed band the regularisation's exchange flow w(0) = 3/16 eps went through a
    closed valve in both directions, and a stagnant node between a pump and its shut
    feed valve took the mean of the pump's delivery enthalpy and the drum's (issue
    20: two-phase at the pump's discharge). Band and tail are the same at both ports,
    so the valve stays energy-neutral (w(m) - w(-m) = m for any band).

    Used by ``ControlValve`` (a ``CheckValve`` keeps the full band: see its doc). The
    seed's ``Valve`` keeps its fixed band, so that the plants written with it keep
    their numbers: the same narrowing
    there moved plants/drum_boiler.toml by 6e-8 and made the draining line of
    tests/plants/inlet_valve_close_reopen.toml (5 volumes) overshoot into reverse
    flow at the sink (-0.010 kg/s against main's -0.0045 kg/s, on a different path
    of step sizes)."""
    return eps * math.sqrt(z_e * z_e + Z_BAND_MIN * Z_BAND_MIN)


#: flow scale of the positive tail of the upwind weight, relative to its band eps
TAIL_REL = 1e-3


def upwind_weight(m, eps, band=None):
    """A C2 smooth max(m, 0) [kg/s], regularised in the band |m| < eps, with a
    tiny positive tail:

        w(m) = (m + q(m)) / 2 + d^2 / (4 sqrt(m^2 + d^2)),       d = 1e-3 eps
        q(m) = |m|                                 for |m| >= eps
        q(m) = eps (3/8 + 3/4 x^2 - 1/8 x^4)       for |m| < eps, x = m/eps

    ``band`` [kg/s] (optional, a number or an array like m): a narrower band for q
    (a valve's, which narrows with its opening: ``opening_band``), with the tail
    kept at d = 1e-3 eps. The tail is what keeps the node's mixing equation regular
    at a Newton iterate whose flows do not balance; scaled with a closed valve's
    band it was 1e-6 of this, and the given start of a feed line whose check valve
    was guessed shut (the only port at its outlet node with a flow towards the node)
    had a singular iteration matrix (condition 5e18).

    q and the tail are even, so w(m) - w(-m) = m exactly (the identity behind the
    exact energy conservation at nodes). q joins |m| with its first and second
    derivatives at |m| = eps. Outside the band w is m (or 0) to within
    d^2/(4|m|) = 2.5e-7 eps^2/|m|: upwinding is exact to 2.5e-13 at m_nominal.
    The tail keeps w > 0 everywhere, so a node's mixing equation keeps a non-zero
    derivative with respect to its enthalpy even at a Newton iterate whose flows
    do not balance (without it, all ports of a node can have w = 0 there and the
    iteration matrix is exactly singular, as measured on a draining pipe behind a
    closed valve). A C1 band was tried first: the integrator's error test failed
    repeatedly where a valve closing in 0.1 s drove flows through the band."""
    if band is None and type(m) is float and type(eps) is float:
        # the same operations in the same order on a Python float (bit-identical to
        # the array branch): a scalar port flow costs 1 us here instead of 10 in numpy
        x = m / eps
        x2 = x * x
        q = abs(m) if abs(x) >= 1.0 else eps * (0.375 + 0.75 * x2 - 0.125 * x2 * x2)
        d = TAIL_REL * eps
        return 0.5 * (m + q) + d * d / (4.0 * math.sqrt(m * m + d * d))
    m = np.asarray(m, dtype=float)
    q = _q(m, eps if band is None else band)
    d = TAIL_REL * eps
    return 0.5 * (m + q) + d * d / (4.0 * np.sqrt(m * m + d * d))


def _q(m, eps):
    """q(m) of ``upwind_weight`` for an array m [kg/s]: |m| outside the band, the
    polynomial inside; when every flow is outside (the usual case) |m| alone."""
    x = m / eps
    outside = np.abs(x) >= 1.0
    if outside.all():
        return np.abs(m)
    x2 = x * x
    return np.where(outside, np.abs(m), eps * (0.375 + 0.75 * x2 - 0.125 * x2 * x2))


def upwind_weight_pair(m, eps):
    """(w(m), w(-m)) for an array of flows m [kg/s]: ``upwind_weight`` of both signs,
    bit-identical to two calls (q and the tail are even in m, and (-m) + q == q - m
    exactly in floating point), for half the array operations."""
    m = np.asarray(m, dtype=float)
    q = _q(m, eps)
    d = TAIL_REL * eps
    tail = d * d / (4.0 * np.sqrt(m * m + d * d))
    return 0.5 * (m + q) + tail, 0.5 * (q - m) + tail


def blend_to_own(a, b, eps):
    """Weight c >= 0 of a volume's own state in its inflow state [kg/s] (eps [kg/s]: a
    number, or an array of the shape of a and b): with
    s = a + b the sum of the inflow weights, c = (eps - s)^3/eps^2 for s < eps, else 0
    (C2 at s = eps). The inflow state (a x_left + b x_right + c x_own)/(s + c) is the
    exact upwind value when the inflow s >= eps, turns smoothly into the volume's
    own state as the inflow vanishes, and s + c >= 0.6 eps > 0."""
    s = np.asarray(a, dtype=float) + np.asarray(b, dtype=float)
    low = s < eps
    if s.ndim == 0 or low.all():
        return np.where(low, (eps - s) ** 3 / eps**2, 0.0)
    c = np.zeros(s.shape)
    if low.any():  # the power only where it is needed (a pipe in flow: nowhere)
        e = eps[low] if np.ndim(eps) else eps  # eps [kg/s]: a number, or one per element
        c[low] = (e - s[low]) ** 3 / e**2
    return c


def energy_in(m, h_node, h_own, eps):
    """Energy flow INTO a component through a port [W], upwind by the actual flow.

        E_in = w(m) h_node - w(-m) h_own

    m [kg/s]: flow into the component at the port; h_node [J/kg]: the node's mixed
    inflow enthalpy; h_own [J/kg]: the enthalpy the component delivers on outflow
    (its ``h_out``). For m >> eps this is m h_node, for m << -eps it is m h_own.
    Every component computes its port energy flows with this one function; with
    the node's mixing equation this makes energy conservation across a node exact
    (proof in ``dnasim.compilation.system``). Exactly m h_node for m >= eps, m h_own for
    m <= -eps."""
    return upwind_weight(m, eps) * h_node - upwind_weight(_neg(m), eps) * h_own


def upwind_mean(m, a, b, eps):
    """Smooth upwind value of a quantity across a face [unit of a]:
    (w(m) a + w(-m) b) / (w(m) + w(-m)); a is the value on the side m > 0 comes
    from (e.g. a density). Equals a for m >= eps, b for m <= -eps, (a + b)/2 at 0."""
    wp = upwind_weight(m, eps)
    wm = upwind_weight(_neg(m), eps)
    return upwind_mean_weighted(wp, wm, a, b)


def upwind_mean_weighted(wp, wm, a, b):
    """``upwind_mean`` from the weights wp = w(m), wm = w(-m) already computed."""
    return (wp * a + wm * b) / (wp + wm)


def reverse_fraction(m: float, eps: float) -> float:
    """sigma(m) [-]: the fraction of a machine's through-flow band that is reverse flow,
    a C2 step from 0 (m >= 0) to 1 (m <= -eps):

        sigma = S(x),  x = clip(-m/eps, 0, 1),  S(x) = x^3 (10 - 15 x + 6 x^2)

    A pump carries the state of the fluid it contains by it: for m >= 0 the suction's
    (forward flow, and the stagnant pump, hold suction fluid), for m <= -eps the
    discharge's (reverse flow), blended in between (``dnasim.library.pump``)."""
    x = -m / eps
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x * x * x * (10.0 + x * (6.0 * x - 15.0))


def _neg(m):
    """-m, a Python float staying one (the scalar branch of ``upwind_weight``)."""
    return -m if type(m) is float else -np.asarray(m, dtype=float)


def saturation_enthalpies(medium, p):
    """(h_liq, h_vap) [J/kg] on the saturation lines at pressures p [Pa] (arrays);
    nan above the critical pressure. Uses ``medium.saturation_enthalpies`` when the
    medium has it, else the medium's h_pQ at qualities 0 and 1."""
    p = np.atleast_1d(np.asarray(p, dtype=float))
    f = getattr(medium, "saturation_enthalpies", None)
    if f is not None:
        hl, hv = f(p)
        return np.asarray(hl, dtype=float), np.asarray(hv, dtype=float)
    hl = np.full(p.size, np.nan)
    hv = np.full(p.size, np.nan)
    for i, pi in enumerate(p):
        try:
            hl[i] = medium.h_pQ(float(pi), 0.0)
            hv[i] = medium.h_pQ(float(pi), 1.0)
        except Exception:  # above the critical pressure or not condensable
            pass
    return hl, hv


def is_condensable(medium) -> bool:
    """True when the medium has a liquid-vapour dome (``medium.condensable`` when the
    medium declares it; else whether h_pQ(1 bar, 0) exists)."""
    flag = getattr(medium, "condensable", None)
    if flag is not None:
        return bool(flag)
    try:
        return bool(np.isfinite(medium.h_pQ(1e5, 0.0)))
    except Exception:
        return False
