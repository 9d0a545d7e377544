"""`IF97Water`: water and steam by IAPWS-IF97, on the vectorised kernel of this package.

All numbers come from :mod:`dnasim.media.if97_kernel` (numpy; no CoolProp), or its
compiled twin :mod:`dnasim.media.if97_numba` (the default when numba is present): regions
1, 2, 3, 5 and the saturation line, (p, h) solved on the forward equations to
round-off (h(p, T(p, h)) = h), continuous and monotone across every region boundary
(narrow blending bands, see the kernel's docstring), with analytic derivatives.

* ``state(p, h)`` -> :class:`FluidState` (cached), ``states(p, h)`` ->
  :class:`FluidStates` (arrays, one kernel call, not cached).
* ``h_pT(p, T)``: the forward h(p, T) of the same (blended) formulation, so
  ``state(p, h_pT(p, T)).T == T`` to round-off. A ``T`` within 1e-6 K of T_sat(p)
  raises :class:`PropertyError` ("T = 342.16 °C is the saturation temperature at
  150 bar: the state is not defined by p and T; give h or the quality").
* ``saturation_enthalpies(p)`` -> (h', h'') arrays [J/kg], NaN at and above p_c;
  ``h_px(p, x)`` and ``h_pQ(p, x)`` for saturated mixtures.

Range: 611.213 Pa <= p <= 100 MPa, 273.15 K <= T <= 1073.15 K, and up to
2273.15 K for p <= 50 MPa. Outside, :class:`PropertyError` naming the state and the
limit.
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.media import if97_kernel as K
from dnasim.media import if97_numba as NB
from dnasim.media import kernel_cache as KC
from dnasim.media import water_transport as WT
from dnasim.media.base import (
    SATURATION_TRANSPORT_KEYS,
    Medium,
    dome_reason,
    saturation_message,
    transport_result,
)
from dnasim.media.errors import PropertyError
from dnasim.media.state import FluidState, FluidStates

P_CRIT = K.P_C  # [Pa]
P_MAX = K.P_MAX  # [Pa]
P_SAT_MIN = K.P_MIN  # [Pa]


class IF97Water(Medium):
    """Water and steam by IAPWS-IF97 (see the module docstring).

    ``get_medium("Water")`` returns the shared instance.

    Parameters
    ----------
    kernel : str
        ``"numba"`` (default when numba is importable: :mod:`if97_numba`, 0.7 to 1.1 us
        per state in ``states``, 3 us per ``state`` call; the first use on a machine
        compiles the parts a run calls, 6 to 9 s CPU, saying so on stderr, and later
        processes load them from numba's cache in about 0.3 s:
        :mod:`dnasim.media.kernel_cache`) or ``"numpy"`` (:mod:`if97_kernel`: no
        compilation, but 0.3 to 1 ms for a single state and 1.3 to 9 us per state in
        calls of 1000 states).
    """

    condensable = True

    def __init__(self, *, cache_size: int = 4096, kernel: str | None = None) -> None:
        super().__init__("Water", "IF97", cache_size=cache_size)
        self.p_critical = P_CRIT
        self.T_critical = K.T_C
        if kernel is None:
            kernel = "numba" if NB.available() else "numpy"
        if kernel not in ("numba", "numpy"):
            raise ValueError(f"kernel must be 'numba' or 'numpy', not {kernel!r}")
        self.kernel = kernel  # the compiled kernels load at their first call (kernel_cache)

    # ------------------------------------------------------------- state
    def _compute_state(self, p: float, h: float) -> FluidState:
        if self.kernel == "numba":
            KC.ensure("state")
            T, rho, u, s, cp, x, d_p, d_h, _, code = NB.ph_scalar(p, h)
            if code != 0:
                raise PropertyError(self.label, p, h, "state", K.STATUS_TEXT[code])
            return FluidState(p, h, T, rho, u, s, cp, -1.0 if x != x else x, d_p, d_h)
        r = K.ph(p, h)
        if not r.ok[()]:
            r.raise_first_bad(self.label)
        x = float(r.x)
        return FluidState(
            p,
            h,
            float(r.T),
            float(r.rho),
            float(r.u),
            float(r.s),
            float(r.cp),
            -1.0 if x != x else x,
            float(r.drho_dp_h),
            float(r.drho_dh_p),
        )

    def states_memo(self):
        """A new memo for ``states(..., memo=)`` (:class:`dnasim.media.if97_numba.PhMemo`:
        one per fixed set of points, e.g. a pipe's volumes), or None with the numpy
        kernel."""
        return NB.PhMemo() if self.kernel == "numba" else None

    @property
    def phase_branches(self) -> bool:
        """True when ``states`` takes ``branch=`` (the compiled kernel)."""
        return self.kernel == "numba"

    def states(self, p, h, *, check: bool = True, branch=None, memo=None) -> FluidStates:
        """Vectorised :meth:`state` (see :meth:`Medium.states`): one kernel call.

        branch: None, or per point a forced phase branch (0 auto, 1 liquid, 2 dome,
        3 vapour: :func:`dnasim.media.if97_numba.ph_branch_scalar`), compiled kernel
        only. memo: None, or the caller's :meth:`states_memo` for this set of points
        (unchanged points are copied, moved ones warm-started; compiled kernel only)."""
        if self.kernel == "numba" and (branch is not None or memo is not None):
            KC.ensure("memo" if memo is not None else "states")
            r = NB.ph_arrays(p, h, branch, memo)
        else:
            if self.kernel == "numba":
                KC.ensure("states")
            r = NB.ph_arrays(p, h) if self.kernel == "numba" else K.ph(p, h)
        if check:
            r.raise_first_bad(self.label)
        self.n_evaluations += r.p.size if memo is None else memo.computed
        return FluidStates(
            r.p,
            r.h,
            r.T,
            r.rho,
            r.u,
            r.s,
            r.cp,
            r.x,
            r.drho_dp_h,
            r.drho_dh_p,
            r.region,
            r.ok,
        )

    def T_rho_u(self, p, h, branch, memo):
        """(T [K], rho [kg/m3], u [J/kg]) arrays at 1-D float arrays p [Pa], h [J/kg]
        with a :meth:`states_memo` (compiled kernel): the numbers of ``states(p, h,
        branch=branch, memo=memo)`` without its other fields, for a residual's call
        (``dnasim.model.physics.PropertyArrays``). Raises :class:`PropertyError`
        for the first state out of range, as ``states`` does."""
        KC.ensure("memo")
        T, rho, u, status = NB.ph_memo_T_rho_u(p, h, branch, memo)
        if status.any():
            i = int(np.flatnonzero(status)[0])
            raise PropertyError(
                self.label,
                float(p[i]),
                float(h[i]),
                "state",
                K.STATUS_TEXT.get(int(status[i]), "invalid state") + f" (state index {i})",
            )
        self.n_evaluations += memo.computed
        return T, rho, u

    # ---------------------------------------------------------- transport
    def transport(self, p, h, *, check: bool = True) -> dict:
        """Viscosity, conductivity, cp and Pr at (p [Pa], h [J/kg]) (see
        :meth:`Medium.transport`): T, rho, cp and the derivatives from this medium's
        IF97 states, then IAPWS R12-08 (viscosity, industrial: no critical
        enhancement) and IAPWS R15-11 (conductivity, industrial form with its critical
        enhancement) by :mod:`dnasim.media.water_transport`. Inside the dome:
        :class:`PropertyError` (or NaN with ``check=False``); on the saturation line
        the saturated phase's values."""
        st = self.states(p, h, check=False)
        shape = st.p.shape
        pf, hf = st.p.ravel(), st.h.ravel()
        x = st.x.ravel()
        T, rho, cp = st.T.ravel(), st.rho.ravel(), st.cp.ravel()
        d_p, d_h = st.drho_dp_h.ravel(), st.drho_dh_p.ravel()
        on_line = (x == 0.0) | (x == 1.0)
        if on_line.any():
            T, rho, cp, d_p, d_h = (a.copy() for a in (T, rho, cp, d_p, d_h))
            for side, edge in ((0, x == 0.0), (1, x == 1.0)):
                if edge.any():
                    sat = self._saturated_sides(pf[edge])[side]
                    T[edge], rho[edge], cp[edge], d_p[edge], d_h[edge] = sat
        if NB.available():
            KC.ensure("transport")
        mu, k = WT.mu_k_ph(T, rho, cp, d_p, d_h)
        dome = (x > 0.0) & (x < 1.0)
        bad = ~st.ok.ravel() | dome | ~(np.isfinite(mu) & np.isfinite(k))

        def reason(i):
            if dome[i]:
                return dome_reason(float(x[i]))
            try:
                self.state(float(pf[i]), float(hf[i]))
            except PropertyError as exc:
                return exc.reason
            return "the transport correlations returned NaN"  # pragma: no cover

        return transport_result(
            self.label, pf.reshape(shape), hf.reshape(shape), mu, k, cp, bad, reason, check
        )

    def saturation_transport(self, p) -> dict:
        """Saturated liquid and vapour properties at p [Pa] (see
        :meth:`Medium.saturation_transport`): IF97 saturated states, IAPWS R12-08 and
        R15-11 as in :meth:`transport`, surface tension by IAPWS R1-76(2014).
        PropertyError outside [611.213 Pa, p_c)."""
        p = np.asarray(p, dtype=float)
        pf = p.ravel()
        bad = ~((pf >= P_SAT_MIN) & (pf < P_CRIT))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise PropertyError(
                self.label,
                float(pf[i]),
                math.nan,
                "saturation_transport",
                "p outside the IF97 saturation range [611.213 Pa, p_c = 22.064 MPa)",
            )
        (TL, rL, cL, pL, hL), (TV, rV, cV, pV, hV) = self._saturated_sides(pf)
        if NB.available():
            KC.ensure("transport")
        muL, kL = WT.mu_k_ph(TL, rL, cL, pL, hL)
        muV, kV = WT.mu_k_ph(TV, rV, cV, pV, hV)
        hl, hv = self.saturation_enthalpies(pf)
        values = (
            TL, rL, rV, hl, hv, muL, muV, kL, kV, cL, cV,
            muL * cL / kL, muV * cV / kV, WT.surface_tension(TL),
        )  # fmt: skip
        return {
            key: v.reshape(p.shape)
            for key, v in zip(SATURATION_TRANSPORT_KEYS, values, strict=True)
        }

    def _saturated_sides(self, p):
        """((T, rho, cp, (d rho/d p)_h, (d rho/d h)_p) of the saturated liquid, the same
        of the vapour) at 1-D p [Pa] in the saturation range: single-phase values on
        each side (the forced phase branch of the compiled kernel, or the saturated
        records of the numpy kernel)."""
        if self.kernel == "numba":
            KC.ensure("saturation")
            KC.ensure("states")
            hl, hv = NB.saturation_arrays(p)
            out = []
            for hs, branch in ((hl, NB.LIQUID), (hv, NB.VAPOUR)):
                r = NB.ph_arrays(p, hs, branch)
                out.append((r.T, r.rho, r.cp, r.drho_dp_h, r.drho_dh_p))
            return tuple(out)
        Ts, _, recL, recV, _ = K._saturation(p)
        out = []
        for rec in (recL, recV):
            # record: v, h, s, (dv/dT)_p, (dv/dp)_T, cp, (dh/dp)_T
            v, cp = rec[0], rec[5]
            rho = 1.0 / v
            rho_h = -rec[3] / (v * v * cp)  # (d rho/d T)_p / cp
            rho_p = -rec[4] / (v * v) - rho_h * rec[6]  # (d rho/d p)_T - rho_h (dh/dp)_T
            out.append((Ts, rho, cp, rho_p, rho_h))
        return tuple(out)

    # ------------------------------------------------------------ h(p, T)
    def _compute_h_pT(self, p: float, T: float) -> float:
        if self.kernel == "numba":
            KC.ensure("h_pT")
            hv, code = NB.h_pT_scalar(p, T)
        else:
            r = K.pT(p, T)
            hv, code = float(r.h), int(r.status)
        if code == 6:
            raise PropertyError(self.label, p, math.nan, "h_pT", saturation_message(p, T), T=T)
        if code != 0:
            raise PropertyError(self.label, p, math.nan, "h_pT", K.STATUS_TEXT[code], T=T)
        return hv

    # ---------------------------------------------------------- saturation
    def p_sat(self, T: float) -> float:
        """The vapour pressure [Pa] at T [K] (IF97 region 4), T capped at the critical
        temperature (``Medium.p_sat``)."""
        return float(K.p_sat(min(T, K.T_C)))

    def saturation_enthalpies(self, p):
        """(h', h'') [J/kg] at p [Pa] (arrays of the shape of p); NaN outside [611.213 Pa, p_c)."""
        p = np.asarray(p, dtype=float)
        if self.kernel == "numba":
            KC.ensure("saturation")
            return NB.saturation_arrays(p)
        hl, hv = K.saturation_enthalpies(p)
        return hl.reshape(p.shape), hv.reshape(p.shape)

    def _compute_h_pQ(self, p: float, x: float) -> float:
        if not (P_SAT_MIN <= p < P_CRIT):
            raise PropertyError(
                self.label,
                p,
                math.nan,
                "h_pQ",
                "p outside the IF97 saturation range [611.213 Pa, p_c = 22.064 MPa)",
            )
        return float(self.h_px(p, x))


#: [s] CPU of compiling the transport kernel (water_transport._kernel), as measured
TRANSPORT_CPU_S = 1.0


def _register_kernel_groups() -> None:
    """The compiled entry points by kind of call, each loaded (or compiled, first use on
    a machine) at its first call in a process: :mod:`dnasim.media.kernel_cache`. The
    CPU seconds are each group's own compile beyond the code they share (kernel_cache.
    SHARED_CPU_S), measured with an empty NUMBA_CACHE_DIR (benchmarks/cold_start.py)."""
    p, h = np.array([1e6]), np.array([1e6])
    KC.register("state", (NB.ph_scalar,), lambda: NB.ph_scalar(1e6, 1e6), 0.5)
    KC.register("states", (NB._ph_branch_loop,), lambda: NB.ph_arrays(p, h), 0.6)
    KC.register("memo", (NB._ph_memo_loop,), lambda: NB.ph_arrays(p, h, memo=NB.PhMemo()), 1.2)
    KC.register("h_pT", (NB.h_pT_scalar,), lambda: NB.h_pT_scalar(1e6, 400.0), 0.3)
    KC.register("saturation", (NB._sat_loop,), lambda: NB.saturation_arrays(p), 0.6)
    KC.register(
        "transport",
        (WT._kernel,),
        lambda: WT.mu_k_ph(*(np.array([v]) for v in (400.0, 900.0, 4e3, 1e-6, -1e-3))),
        TRANSPORT_CPU_S,
        label="IAPWS transport",
    )


if NB.available():
    _register_kernel_groups()
