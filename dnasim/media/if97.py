"""`IF97Water`: water and steam by IAPWS-IF97, on CoolProp's ``IF97`` backend.

CoolProp's IF97 backend evaluates the IF97 *forward* equations (Gibbs or
Helmholtz functions of the regions, T and p as inputs) exactly, but

1. its (p, h) flash returns T from the IF97 *backward* equation T(p, h),
   which is only within about 25 mK of the forward solution (the other
   outputs are then evaluated at that T, so they are inconsistent with the
   given h by up to about 100 J/kg);
2. its (p, h) flash fails ("Pressure out of range") in region 3 above the
   critical pressure (CoolProp 8.0);
3. it implements none of the partial derivatives (``first_partial_deriv``,
   ``first_two_phase_deriv`` raise "not implemented").

This class therefore uses the backend as follows.

* Phase: for 611.213 Pa <= p < p_c, the saturation enthalpies h_L(p), h_V(p)
  (``PQ_INPUTS``) decide: h < h_L liquid, h > h_V vapour, otherwise two-phase.
* Single phase: T solves h_IF97(p, T) = h by a safeguarded Newton iteration on
  the forward equations (bracketed; bisection when a step leaves the bracket
  or does not halve the previous one), started from the backward-equation T
  (or, where CoolProp's backward equation fails, from the bracket). It stops
  at rounding level, |h(p, T) - h| <= 2e-15 |h| + 1e-10 J/kg or a Newton step
  below the resolution of T, which takes three or four (p, T) evaluations:
  a looser tolerance would leave noise of that size in rho(p, h), which the
  DAE solver sees as an inconsistent residual (1e-12 in rho times a 1000 kg
  water volume is 1e-9 kg). The bracket is [273.15 K, T_sat(p)) for a liquid,
  (T_sat(p), T_max] for a vapour and [273.15 K, T_max] above p_c, with
  T_max = 2273.15 K up to 50 MPa (region 5) and 1073.15 K above. The IF97
  regions are not exactly consistent on their boundaries (h jumps by up to
  about 130 J/kg at the region 2/3 boundary at 60 MPa, about 90 J/kg at
  1073.15 K): a given h inside such a jump is accepted at the boundary
  temperature when |h(p, T) - h| <= 500 J/kg.
* Derivatives, single phase, **analytic** from outputs the backend computes
  from the same fundamental equation (isobaric expansion coefficient
  alpha = (1/v) dv/dT|p, speed of sound w, cp, cv)::

      alpha**2  = cp (cp - cv) / (cv T w**2)          (from cp - cv = T v alpha**2 / kappa_T,
                                                       kappa_T = cp / (cv rho w**2))
      drho/dh|p = -rho alpha / cp
      drho/dp|h = 1 / w**2 + alpha / cp              (= drho/dp|s - drho/dh|p / rho)

  alpha < 0 only in cold liquid water (below about 277 K, the density
  maximum); for T < 278 K the sign is taken from one forward difference of
  rho in T with a step of 1 mK.
* Two-phase (homogeneous mixture at T_sat(p)): with x = (h - h_L) / (h_V - h_L),
  v = v_L + x (v_V - v_L)::

      drho/dh|p = -rho**2 (v_V - v_L) / (h_V - h_L)
      drho/dp|h = -rho**2 [v_L' + x (v_V' - v_L')
                           - (v_V - v_L) (h_L' + x (h_V' - h_L')) / (h_V - h_L)]

  where ' is the derivative along the saturation line, computed by a
  centred finite difference in p with step dp = 1e-5 p (one-sided second
  order near p_c, near the region 1/3 saturation boundary at 16.529 MPa,
  and near the lowest IF97 saturation pressure), which is accurate to about
  1e-9 relative.
* ``u = h - p / rho`` exactly; ``s`` from the forward equation (single phase)
  or ``s_L + x (s_V - s_L)``; ``cp = inf`` and ``T = T_sat(p)`` in the dome.

Range: 611.213 Pa <= p <= 100 MPa (saturation and the backward equations need
p >= 611.213 Pa), 273.15 K <= T <= 1073.15 K, and up to 2273.15 K for
p <= 50 MPa. Outside, :class:`PropertyError`.

``h_pT(p, T)``: the forward IF97 h(p, T). Raises :class:`PropertyError` when
T is within 1e-6 K of T_sat(p) (h is not fixed by p and T there; use
``h_pQ``).
"""

from __future__ import annotations

import math

import CoolProp.CoolProp as CP

from dnasim.media.base import BACKEND_ERRORS, Medium
from dnasim.media.errors import PropertyError
from dnasim.media.state import FluidState

_HP = CP.HmassP_INPUTS
_PT = CP.PT_INPUTS
_PQ = CP.PQ_INPUTS
_INF = math.inf
_sqrt = math.sqrt

P_CRIT = 22.064e6  # [Pa]
P_MAX = 100e6  # [Pa]
P_SAT_MIN = 611.213  # [Pa] lowest pressure of CoolProp's IF97 saturation / backward functions
P_R13_SAT = 16.529164252605e6  # [Pa] p_sat(623.15 K): saturated liquid/vapour leave regions 1/2
T_MIN = 273.15  # [K]
T_MAX_HIGH_P = 1073.15  # [K] above 50 MPa
T_MAX_LOW_P = 2273.15  # [K] up to 50 MPa (region 5)
P_REGION5_MAX = 50e6  # [Pa]
T_ALPHA_SIGN = 278.0  # [K] below it the sign of alpha is checked
GAP_TOL = 500.0  # [J/kg] accepted h mismatch at an IF97 region boundary
SAT_REL_STEP = 1e-5  # relative step in p for saturation-line derivatives
T_R13 = 623.15  # [K] boundary of regions 1 and 3


def _T_B23(p: float) -> float:
    """Temperature [K] of the IF97 region 2/3 boundary (B23 equation) at p [Pa] >= 16.529 MPa."""
    return 0.57254459862746e3 + _sqrt((p * 1e-6 - 0.1391883977870e2) / 0.10192970039326e-2)


class IF97Water(Medium):
    """Water and steam by IAPWS-IF97 (see the module docstring for the method).

    ``get_medium("Water")`` returns the shared instance.
    """

    def __init__(self, *, cache_size: int = 4096) -> None:
        super().__init__("Water", "IF97", cache_size=cache_size)
        self._AS = CP.AbstractState("IF97", "Water")
        self.p_critical = P_CRIT
        self.T_critical = 647.096
        #: number of forward (p, T) evaluations in the T(p, h) iterations (for tests)
        self.n_pT_evaluations = 0

    # ------------------------------------------------------------- state
    def _compute_state(self, p: float, h: float) -> FluidState:
        AS = self._AS
        if p > P_MAX:
            raise PropertyError(self.label, p, h, "state", "p above the IF97 limit of 100 MPa")
        T_hi = T_MAX_LOW_P if p <= P_REGION5_MAX else T_MAX_HIGH_P
        if P_SAT_MIN <= p < P_CRIT:
            AS.update(_PQ, p, 0.0)
            Tsat = AS.T()
            hL = AS.hmass()
            if h < hL:
                lo, hi = T_MIN, Tsat * (1.0 - 1e-11)
            else:
                AS.update(_PQ, p, 1.0)
                hV = AS.hmass()
                if h <= hV:
                    return self._two_phase(p, h, Tsat)
                lo, hi = Tsat * (1.0 + 1e-11), T_hi
        else:
            lo, hi = T_MIN, T_hi
        try:
            AS.update(_HP, h, p)
            T0 = AS.T()
        except BACKEND_ERRORS:
            T0 = None  # e.g. region 3 above p_c: solve from the bracket alone
        T, cp = self._solve_T(p, h, T0, lo, hi)
        # the backend now holds the forward state at (p, T)
        rho = AS.rhomass()
        cv = AS.cvmass()
        w = AS.speed_sound()
        s = AS.smass()
        alpha = _sqrt(max(cp * (cp - cv), 0.0) / (cv * T)) / w
        if T < T_ALPHA_SIGN:
            AS.update(_PT, p, T + 1e-3)
            if AS.rhomass() > rho:
                alpha = -alpha
        return FluidState(
            p,
            h,
            T,
            rho,
            h - p / rho,
            s,
            cp,
            -1.0,
            1.0 / (w * w) + alpha / cp,
            -rho * alpha / cp,
        )

    def _solve_T(self, p: float, h: float, T0: float | None, lo: float, hi: float):
        """Solve h(p, T) = h for T in [lo, hi]; return (T, cp) with the backend at (p, T).

        Newton's method safeguarded by bisection (as ``rtsafe`` in Numerical
        Recipes): a Newton step that leaves the bracket or does not halve the
        previous step is replaced by a bisection.
        """
        AS = self._AS
        lo0, hi0 = lo, hi
        tol = 2e-15 * abs(h) + 1e-10
        if T0 is None:
            # No starting value (the backward equation failed). Above p_c try
            # region 3 first, [623.15 K, T_B23(p)], where CoolProp 8's backward
            # equation fails; else the whole range. Start by linear interpolation.
            g_lo = g_hi = None
            if p > P_CRIT:
                T_b23 = _T_B23(p)
                AS.update(_PT, p, T_R13)
                g1 = AS.hmass() - h
                AS.update(_PT, p, T_b23)
                g2 = AS.hmass() - h
                self.n_pT_evaluations += 2
                if g1 <= 0.0 <= g2:
                    lo, hi, g_lo, g_hi = T_R13, T_b23, g1, g2
            if g_lo is None:
                AS.update(_PT, p, lo)
                g_lo = AS.hmass() - h
                AS.update(_PT, p, hi)
                g_hi = AS.hmass() - h
                self.n_pT_evaluations += 2
                if g_lo > GAP_TOL or g_hi < -GAP_TOL:
                    raise PropertyError(
                        self.label,
                        p,
                        h,
                        "state",
                        "h outside the IF97 range at this p "
                        f"(T would be outside [{lo0:.6g}, {hi0:.6g}] K)",
                    )
            T = lo - g_lo * (hi - lo) / (g_hi - g_lo) if g_hi > g_lo else 0.5 * (lo + hi)
        else:
            T = min(max(T0, lo), hi)
        g = _INF
        cp = math.nan
        dx_old = dx = hi - lo
        for _ in range(200):
            AS.update(_PT, p, T)
            g = AS.hmass() - h
            cp = AS.cpmass()
            self.n_pT_evaluations += 1
            if abs(g) <= tol:
                return T, cp
            if g < 0.0:
                lo = T
            else:
                hi = T
            if hi - lo <= 4e-16 * hi:
                break  # bracket collapsed: a region-boundary jump, or h out of range
            step = g / cp
            if abs(step) <= 2.3e-16 * T:
                return T, cp  # converged to the resolution of T
            Tn = T - step
            if not (lo < Tn < hi) or abs(2.0 * step) > abs(dx_old):
                dx_old = dx
                dx = 0.5 * (hi - lo)
                Tn = lo + dx
            else:
                dx_old = dx
                dx = step
            T = Tn
        if abs(g) <= GAP_TOL:
            return T, cp
        raise PropertyError(
            self.label,
            p,
            h,
            "state",
            f"h outside the IF97 range at this p (T would be outside [{lo0:.6g}, {hi0:.6g}] K)",
        )

    def _sat(self, p: float):
        """(h_L, h_V, v_L, v_V) [J/kg, m3/kg] on the saturation line at p [Pa]."""
        AS = self._AS
        AS.update(_PQ, p, 0.0)
        hL = AS.hmass()
        vL = 1.0 / AS.rhomass()
        AS.update(_PQ, p, 1.0)
        return hL, AS.hmass(), vL, 1.0 / AS.rhomass()

    def _two_phase(self, p: float, h: float, Tsat: float) -> FluidState:
        AS = self._AS
        AS.update(_PQ, p, 0.0)
        hL = AS.hmass()
        vL = 1.0 / AS.rhomass()
        sL = AS.smass()
        AS.update(_PQ, p, 1.0)
        hV = AS.hmass()
        vV = 1.0 / AS.rhomass()
        sV = AS.smass()
        dh = hV - hL
        dv = vV - vL
        x = (h - hL) / dh
        x = 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)
        v = vL + x * dv
        rho = 1.0 / v
        # derivatives along the saturation line by finite differences in p
        d = SAT_REL_STEP * p
        if p + d >= P_CRIT or (p < P_R13_SAT <= p + d):
            # one-sided, backward, second order
            a = self._sat(p - d)
            b = self._sat(p - 2.0 * d)
            c = (hL, hV, vL, vV)
            der = [(3.0 * c[i] - 4.0 * a[i] + b[i]) / (2.0 * d) for i in range(4)]
        elif p - 2.0 * d < P_SAT_MIN or (p - d < P_R13_SAT <= p):
            a = self._sat(p + d)
            b = self._sat(p + 2.0 * d)
            c = (hL, hV, vL, vV)
            der = [(-3.0 * c[i] + 4.0 * a[i] - b[i]) / (2.0 * d) for i in range(4)]
        else:
            a = self._sat(p + d)
            b = self._sat(p - d)
            der = [(a[i] - b[i]) / (2.0 * d) for i in range(4)]
        dhL, dhV, dvL, dvV = der
        dv_dp = dvL + x * (dvV - dvL) - dv * (dhL + x * (dhV - dhL)) / dh
        rho2 = rho * rho
        return FluidState(
            p,
            h,
            Tsat,
            rho,
            h - p * v,
            sL + x * (sV - sL),
            _INF,
            x,
            -rho2 * dv_dp,
            -rho2 * dv / dh,
        )

    # ------------------------------------------------------------ h(p, T)
    def _compute_h_pT(self, p: float, T: float) -> float:
        AS = self._AS
        if p > P_MAX:
            raise PropertyError(
                self.label, p, math.nan, "h_pT", "p above the IF97 limit of 100 MPa", T=T
            )
        if P_SAT_MIN <= p < P_CRIT:
            AS.update(_PQ, p, 0.0)
            Tsat = AS.T()
            self._refuse_saturated(p, T, Tsat)
        AS.update(_PT, p, T)
        return AS.hmass()

    def _compute_h_pQ(self, p: float, x: float) -> float:
        if not (P_SAT_MIN <= p < P_CRIT):
            raise PropertyError(
                self.label,
                p,
                math.nan,
                "h_pQ",
                "p outside the IF97 saturation range [611.213 Pa, p_c)",
            )
        AS = self._AS
        AS.update(_PQ, p, x)
        return AS.hmass()
