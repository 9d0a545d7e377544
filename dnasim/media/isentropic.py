"""Specific enthalpy from pressure and entropy, h(p, s), for any medium.

The media give (p, h) -> state, with the specific entropy s [J/(kg K)] among the
outputs. The inverse at a fixed pressure follows from the Gibbs relation
dh = T ds + v dp: at constant p, (ds/dh)_p = 1/T [1/K], positive everywhere
(also inside the two-phase dome, where T = T_sat(p)). Newton's iteration

    h_(k+1) = h_k - T(p, h_k) (s(p, h_k) - s)                            [J/kg]

therefore converges from any start on the same isobar, quadratically near the
root; s(h) is concave on an isobar (T rises with h), so a step never overshoots
by much. A step that leaves the medium's range is halved. When Newton has not
converged after ``MAX_NEWTON`` steps, scipy's brentq finishes on a bracket.

The isentropic exponent and the ratio of specific heats of a state
(``isentropic_exponent``, ``heat_capacity_ratio``) from its (p, h) derivatives are
here too; the valve laws (``dnasim.library.submodels.valve_laws``) take the exponent of the
inlet state from them.

Used by the steam turbine (``dnasim.library.turbine``) for the isentropic
outlet state h_s = h(p_out, s(p_in, h_in)); with IF97 water the result is checked
against CoolProp's IF97 backend in ``tests/test_isentropic.py``.
"""

from __future__ import annotations

import math

from dnasim.media.errors import PropertyError

#: Newton stops when a step is below H_TOL_REL |h| + H_TOL_ABS [J/kg]
H_TOL_REL = 1e-13
H_TOL_ABS = 1e-7
MAX_NEWTON = 30


def h_ps(medium, p: float, s: float, h_guess: float | None = None) -> float:
    """Specific enthalpy h [J/kg] with s(p, h) = s at pressure p [Pa], entropy s [J/(kg K)].

    ``h_guess`` [J/kg]: a start on the isobar (default: the medium's h at 1e6 J/kg,
    or the last valid iterate). Raises :class:`PropertyError` when no state on the
    isobar has this entropy within the medium's range.
    """
    h = 1e6 if h_guess is None else float(h_guess)
    st = _state(medium, p, h)
    if st is None:
        raise PropertyError(medium.label, p, h, "h_ps", "start of the iteration out of range")
    for _ in range(MAX_NEWTON):
        full = step = -st.T * (st.s - s)
        h_new = h + step
        new = _state(medium, p, h_new)
        while new is None and abs(step) > H_TOL_ABS:
            step *= 0.5
            h_new = h + step
            new = _state(medium, p, h_new)
        if new is None:
            break
        h, st = h_new, new
        if abs(full) <= H_TOL_REL * abs(h) + H_TOL_ABS:  # a full Newton step, not a cut one
            return h
    return _bracketed(medium, p, s, h, st)


def h_isentropic(medium, p_in: float, h_in: float, p_out: float) -> float:
    """Outlet enthalpy h_s [J/kg] of an isentropic change from (p_in [Pa], h_in [J/kg])
    to p_out [Pa]: h_s = h(p_out, s(p_in, h_in))."""
    s_in = medium.state(p_in, h_in).s
    # start from the inlet enthalpy shifted by v dp (exact to first order in dp)
    rho = medium.state(p_in, h_in).rho
    guess = h_in + (p_out - p_in) / rho
    if _state(medium, p_out, guess) is None:
        guess = h_in
    return h_ps(medium, p_out, s_in, guess)


def _state(medium, p, h):
    try:
        return medium.state(p, h)
    except PropertyError:
        return None


def _bracketed(medium, p, s, h, st):
    """brentq on s(p, h) - s, bracket grown from h by doubling steps."""
    from scipy.optimize import brentq

    def f(hh):
        return medium.state(p, hh).s - s

    f0 = st.s - s
    width = max(abs(st.T * f0), 1e3)
    direction = -1.0 if f0 > 0 else 1.0
    a, fa = h, f0
    for _ in range(60):
        b = a + direction * width
        stb = _state(medium, p, b)
        if stb is None:
            break
        fb = stb.s - s
        if fa * fb <= 0:
            lo, hi = (a, b) if a < b else (b, a)
            return brentq(f, lo, hi, xtol=H_TOL_ABS, rtol=4 * 2.2e-16)
        a, fa = b, fb
        width *= 2.0
    raise PropertyError(
        medium.label,
        p,
        math.nan,
        "h_ps",
        f"no state at this pressure has the entropy s = {s:.6g} J/(kg K) within the range",
    )


def isentropic_exponent(st) -> float:
    """Isentropic exponent kappa_s = -(v/p) (dp/dv)_s = rho / (p (d rho/d p)_s) [-] of
    the state ``st`` (a :class:`~dnasim.media.state.FluidState`), from its (p, h)
    derivatives: at constant s, dh = v dp, so

        (d rho/d p)_s = (d rho/d p)_h + (d rho/d h)_p / rho                  [s2/m2]

    and kappa_s = rho w^2 / p with w the speed of sound. An ideal gas gives
    cp/(cp - R); inside the two-phase dome the derivatives are the homogeneous
    equilibrium mixture's (IF97: the equilibrium speed of sound; saturated steam at
    10 bar, x = 1: 1.140, cf. Zeuner's 1.035 + 0.1 x); a liquid gives a large value
    (water at 300 K, 10 bar: 2257). Checked against CoolProp's IF97 speed of sound in
    ``tests/test_valve_laws.py``."""
    drho_dp_s = st.drho_dp_h + st.drho_dh_p / st.rho
    return st.rho / (st.p * drho_dp_s)


def heat_capacity_ratio(st) -> float:
    """Ratio of the specific heats cp/cv [-] of the single-phase state ``st``, as the
    ratio of the isothermal and the isentropic compressibility (Reech):

        cp/cv = (d rho/d p)_T / (d rho/d p)_s
        (d rho/d p)_T = (d rho/d p)_h + (d rho/d h)_p (dh/dp)_T,
        (dh/dp)_T = v - T (dv/dT)_p = 1/rho + T cp (d rho/d h)_p / rho^2      [m3/kg]

    An ideal gas gives cp/(cp - R) = kappa_s. Inside the two-phase dome cp is infinite
    and the ratio is not defined: NaN."""
    if not math.isfinite(st.cp):
        return math.nan
    drho_dp_s = st.drho_dp_h + st.drho_dh_p / st.rho
    dh_dp_T = 1.0 / st.rho + st.T * st.cp * st.drho_dh_p / st.rho**2
    return (st.drho_dp_h + st.drho_dh_p * dh_dp_T) / drho_dp_s
