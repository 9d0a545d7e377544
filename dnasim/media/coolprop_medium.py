"""`CoolPropMedium`: any CoolProp fluid through the low-level ``AbstractState``.

Used for the Helmholtz-energy backend (``"HEOS"``) and the tabular backends
built on it (``"BICUBIC&HEOS"``, ``"TTSE&HEOS"``). Water by IAPWS-IF97 has its
own class, :class:`dnasim.media.if97.IF97Water`, because CoolProp's IF97
backend lacks the derivatives and its (p, h) flash is only as accurate as the
IF97 backward equations.

The low-level interface (``AbstractState.update(HmassP_INPUTS, h, p)`` and
then one call per output) is used instead of ``PropsSI``, which parses strings
and re-creates the state on every call and is 10 to 40 times slower.

At the interpreter's exit the ``AbstractState`` objects are released
(:func:`release_abstract_states`, an ``atexit`` handler): a medium held by a
module (the registry's shared instances) would otherwise still be alive when
CoolProp's nanobind module is torn down, and nanobind then prints some thirty
lines of "nanobind: leaked ... instances/types/functions" on stderr.
"""

from __future__ import annotations

import atexit
import math
import weakref

import CoolProp.CoolProp as CP
import numpy as np

from dnasim.media.base import (
    BACKEND_ERRORS,
    SATURATION_TRANSPORT_KEYS,
    Medium,
    _as_arrays,
    dome_reason,
    transport_result,
)
from dnasim.media.errors import PropertyError
from dnasim.media.state import FluidState

_HP = CP.HmassP_INPUTS
_PT = CP.PT_INPUTS
_PQ = CP.PQ_INPUTS
_QT = CP.QT_INPUTS
_iDmass = CP.iDmass
_iP = CP.iP
_iHmass = CP.iHmass
_TWOPHASE = CP.iphase_twophase
_INF = math.inf

#: every CoolPropMedium made in this process (weakly): released at exit
_LIVE: weakref.WeakSet = weakref.WeakSet()


def release_abstract_states() -> None:
    """Drop the ``AbstractState`` of every CoolPropMedium of this process (run at exit
    by ``atexit``, before CoolProp's module is torn down). A medium used afterwards
    makes a new one."""
    for medium in list(_LIVE):
        medium._AS = None


atexit.register(release_abstract_states)


class CoolPropMedium(Medium):
    """A CoolProp fluid evaluated with ``AbstractState(backend, fluid)``.

    Parameters
    ----------
    fluid : str
        Canonical CoolProp fluid name (``"Water"``, ``"R134a"``, ``"Air"``, ...).
    backend : str
        ``"HEOS"`` (multiparameter Helmholtz equation of state, the reference
        accuracy, about 100 to 200 us per (p, h) flash), or ``"BICUBIC&HEOS"`` /
        ``"TTSE&HEOS"`` (interpolation in tables generated from HEOS; a few us
        per call, but the first use of a fluid builds the tables, which takes
        some seconds, and CoolProp caches them under ``~/.CoolProp/Tables``).

    Notes
    -----
    Outputs of :meth:`state`:

    - ``T``, ``rho``, ``s`` from the backend; ``u = h - p / rho``.
    - Single phase: ``cp`` from the backend, ``quality = -1``,
      ``drho_dp_h = first_partial_deriv(iDmass, iP, iHmass)``,
      ``drho_dh_p = first_partial_deriv(iDmass, iHmass, iP)`` (analytic in
      HEOS; from the table's interpolant in the tabular backends).
    - Inside the two-phase dome (the backend reports ``iphase_twophase``):
      ``quality`` = the backend's Q in [0, 1], ``cp = inf``, and the
      derivatives from ``first_two_phase_deriv`` (the homogeneous-mixture
      derivatives; the plain partial derivative is not defined there).

    ``h_pT`` at (or within the backend's band of about 1e-4 % in saturation
    pressure of) the saturation temperature raises :class:`PropertyError`,
    as does ``T`` within 1e-6 K of ``Tsat(p)``: (p, T) does not fix h in the
    dome. Use :meth:`h_pQ` for saturated states.
    """

    def __init__(self, fluid: str, backend: str = "HEOS", *, cache_size: int = 4096) -> None:
        super().__init__(fluid, backend, cache_size=cache_size)
        self._AS = CP.AbstractState(backend, fluid)
        _LIVE.add(self)
        try:
            self.p_critical = float(self._AS.p_critical())
            self.T_critical = float(self._AS.T_critical())
        except BACKEND_ERRORS:  # pseudo-pure fluids without a true critical point
            self.p_critical = math.nan
            self.T_critical = math.nan
        #: a fluid with a critical point has a two-phase region below it
        self.condensable = math.isfinite(self.p_critical)

    def _abstract_state(self):
        """A new ``AbstractState`` after :func:`release_abstract_states` dropped it."""
        self._AS = CP.AbstractState(self.backend, self.name)
        return self._AS

    def saturation_enthalpies(self, p):
        """(h_liq, h_vap) [J/kg] at pressures p [Pa] (arrays of the shape of p), by the
        backend's (p, Q) flash; NaN at and above the critical pressure or where the
        backend has no saturated state."""
        if not self.condensable:
            return super().saturation_enthalpies(p)
        p = np.asarray(p, dtype=float)
        hl = np.full(p.shape, np.nan)
        hv = np.full(p.shape, np.nan)
        AS = self._AS or self._abstract_state()
        for i, pi in enumerate(p.flat):
            if not (0.0 < pi < self.p_critical):
                continue
            try:
                AS.update(_PQ, pi, 0.0)
                hl.flat[i] = AS.hmass()
                AS.update(_PQ, pi, 1.0)
                hv.flat[i] = AS.hmass()
            except BACKEND_ERRORS:
                hl.flat[i] = hv.flat[i] = np.nan
        return hl, hv

    def transport(self, p, h, *, check: bool = True) -> dict:
        """Viscosity, conductivity, cp and Pr at (p [Pa], h [J/kg]) (see
        :meth:`Medium.transport`): CoolProp's own transport correlations for this fluid
        (``AbstractState.viscosity()``, ``conductivity()``, ``cpmass()`` after a (p, h)
        flash; the tabular backends interpolate them). A fluid without transport data,
        a state CoolProp cannot evaluate, or one inside the two-phase dome raises
        :class:`PropertyError` (or gets NaN with ``check=False``)."""
        p, h = _as_arrays(p, h)
        pf, hf = p.ravel(), h.ravel()
        n = pf.size
        mu = np.full(n, np.nan)
        k = np.full(n, np.nan)
        cp = np.full(n, np.nan)
        reasons: dict[int, str] = {}
        AS = self._AS
        for i in range(n):
            pi, hi = float(pf[i]), float(hf[i])
            if not (0.0 < pi < _INF and -_INF < hi < _INF):
                reasons[i] = "p must be finite and > 0 and h finite"
                continue
            try:
                AS.update(_HP, hi, pi)
                if AS.phase() == _TWOPHASE:
                    q = AS.Q()
                    if 0.0 < q < 1.0:
                        reasons[i] = dome_reason(q)
                        continue
                    AS.update(_PQ, pi, q)  # on the saturation line: that phase
                mu[i] = AS.viscosity()
                k[i] = AS.conductivity()
                cp[i] = AS.cpmass()
            except BACKEND_ERRORS as exc:
                reasons[i] = str(exc)
                continue
            if not (mu[i] > 0.0 and k[i] > 0.0 and cp[i] > 0.0):
                reasons[i] = f"CoolProp returned mu = {mu[i]}, k = {k[i]}, cp = {cp[i]}"
        bad = np.zeros(n, dtype=bool)
        bad[list(reasons)] = True
        return transport_result(self.label, p, h, mu, k, cp, bad, reasons.__getitem__, check)

    def saturation_transport(self, p) -> dict:
        """Saturated liquid and vapour properties at p [Pa] (see
        :meth:`Medium.saturation_transport`), by CoolProp's (p, Q) flashes at Q = 0
        and 1 and its transport and surface-tension correlations."""
        if not self.condensable:
            return super().saturation_transport(p)
        p = np.asarray(p, dtype=float)
        pf = p.ravel()
        out = {key: np.full(pf.size, np.nan) for key in SATURATION_TRANSPORT_KEYS}
        AS = self._AS
        for i, pi in enumerate(pf):
            try:
                if not (0.0 < pi < self.p_critical):
                    raise ValueError("p is not below the critical pressure")
                for q, s in ((0.0, "_l"), (1.0, "_v")):
                    AS.update(_PQ, float(pi), q)
                    out["rho" + s][i] = AS.rhomass()
                    out["h" + s][i] = AS.hmass()
                    out["mu" + s][i] = AS.viscosity()
                    out["k" + s][i] = AS.conductivity()
                    out["cp" + s][i] = AS.cpmass()
                    if q == 0.0:
                        out["T"][i] = AS.T()
                        out["sigma"][i] = AS.surface_tension()
            except BACKEND_ERRORS as exc:
                raise PropertyError(
                    self.label, float(pi), math.nan, "saturation_transport", str(exc)
                ) from exc
        out["Pr_l"] = out["mu_l"] * out["cp_l"] / out["k_l"]
        out["Pr_v"] = out["mu_v"] * out["cp_v"] / out["k_v"]
        return {key: v.reshape(p.shape) for key, v in out.items()}

    def _compute_state(self, p: float, h: float) -> FluidState:
        AS = self._AS or self._abstract_state()
        AS.update(_HP, h, p)
        T = AS.T()
        rho = AS.rhomass()
        s = AS.smass()
        if AS.phase() == _TWOPHASE:
            q = AS.Q()
            cp = _INF
            d_p = AS.first_two_phase_deriv(_iDmass, _iP, _iHmass)
            d_h = AS.first_two_phase_deriv(_iDmass, _iHmass, _iP)
            if not (0.0 <= q <= 1.0):
                raise PropertyError(self.label, p, h, "quality", f"two-phase state with Q = {q}")
        else:
            q = -1.0
            cp = AS.cpmass()
            d_p = AS.first_partial_deriv(_iDmass, _iP, _iHmass)
            d_h = AS.first_partial_deriv(_iDmass, _iHmass, _iP)
        return FluidState(p, h, T, rho, h - p / rho, s, cp, q, d_p, d_h)

    def _compute_h_pT(self, p: float, T: float) -> float:
        AS = self._AS or self._abstract_state()
        if p < self.p_critical:
            try:
                AS.update(_PQ, p, 0.0)
                Tsat = AS.T()
            except BACKEND_ERRORS:
                Tsat = math.nan
            self._refuse_saturated(p, T, Tsat)
        AS.update(_PT, p, T)
        return AS.hmass()

    def p_sat(self, T: float) -> float:
        """The vapour pressure [Pa] at T [K] by the backend's (Q = 0, T) flash; the
        critical pressure at and above the critical temperature (``Medium.p_sat``)."""
        if not self.condensable:
            self._no_two_phase_region("p_sat", T)
        if T >= self.T_critical:
            return self.p_critical
        AS = self._AS or self._abstract_state()
        try:
            AS.update(_QT, 0.0, T)
            return float(AS.p())
        except BACKEND_ERRORS as exc:
            raise PropertyError(self.label, math.nan, math.nan, "p_sat", str(exc), T=T) from exc

    def _compute_h_pQ(self, p: float, x: float) -> float:
        AS = self._AS or self._abstract_state()
        AS.update(_PQ, p, x)
        return AS.hmass()
