"""`Medium`: the common interface of every fluid, with the (p, h) state cache.

A subclass implements two methods, :meth:`Medium._compute_state` and
:meth:`Medium._compute_h_pT`, on already checked float inputs. Everything a
caller relies on lives here: input checks (NaN, inf, p <= 0), the
bounded cache, the translation of any backend exception into
:class:`~dnasim.media.errors.PropertyError`, and the check of the outputs for
NaN.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from dnasim.media.errors import PropertyError
from dnasim.media.state import FluidState, FluidStates

_INF = math.inf

#: Exception types a CoolProp call may raise for a state it cannot evaluate
#: (C++ exceptions arrive as ValueError, IndexError or RuntimeError depending
#: on their type; the IF97 backend raises IndexError for "out of range").
BACKEND_ERRORS = (ValueError, IndexError, RuntimeError, ArithmeticError)


class Medium(ABC):
    """A fluid whose state is given by pressure p [Pa] and specific enthalpy h [J/kg].

    Obtain instances through :func:`dnasim.media.get_medium`, which shares one
    instance per (fluid, backend) so that all components share its cache.

    Attributes
    ----------
    name : str
        Canonical fluid name, e.g. ``"Water"``, ``"Air"``, ``"R134a"``.
    backend : str
        ``"IF97"``, ``"HEOS"``, ``"BICUBIC&HEOS"``, ``"TTSE&HEOS"`` or ``"IdealGas"``.
    n_evaluations : int
        Number of states actually computed (cache misses that reached the
        backend). Tests and benchmarks read it; nothing else depends on it.
    cache_size : int
        The cache is emptied when it reaches this many entries.

    Notes
    -----
    **Cache.** ``state(p, h)`` is memoised on the exact pair of floats
    ``(p, h)``: the second call with the same numbers returns the same
    :class:`FluidState` object without calling the backend. A plant node shared
    by several components therefore costs one flash per residual evaluation.
    The cache is a plain dict cleared when it reaches ``cache_size`` entries
    (default 4096), so memory is bounded and a cache hit costs a dict lookup.
    ``h_pT`` has its own cache of the same kind. A medium instance, like the
    CoolProp ``AbstractState`` inside it, is not thread-safe.
    """

    name: str
    backend: str
    #: True for media with a two-phase region (they implement
    #: :meth:`saturation_enthalpies` and :meth:`h_px`).
    condensable: bool = False
    #: the critical point: temperature [K] and pressure [Pa] (nan for a medium
    #: without a two-phase region; a condensable medium sets both)
    T_critical: float = math.nan
    p_critical: float = math.nan

    #: ``(get_medium, (fluid, backend))`` when the instance came from ``get_medium``
    #: (set there, so that this module need not import the registry): it then pickles
    #: as that call and unpickles as the shared instance (no backend state pickled)
    registry_call: tuple | None = None

    def __reduce_ex__(self, protocol):
        if self.registry_call is not None:
            return self.registry_call
        return super().__reduce_ex__(protocol)

    def __deepcopy__(self, memo):
        """A medium copies as itself: one instance per fluid, shared with its cache
        (``dnasim.compilation.compiler.own_components`` deep-copies the components of a
        plant, and any medium one of them holds stays the shared one)."""
        return self

    def __init__(self, name: str, backend: str, *, cache_size: int = 4096) -> None:
        self.name = name
        self.backend = backend
        self.cache_size = int(cache_size)
        self.n_evaluations = 0
        self._cache: dict[tuple[float, float], FluidState] = {}
        self._cache_hpT: dict[tuple[float, float], float] = {}

    # ------------------------------------------------------------------ API
    @property
    def label(self) -> str:
        """``"Water (IF97)"``: how error messages name this medium."""
        return f"{self.name} ({self.backend})"

    def state(self, p: float, h: float) -> FluidState:
        """Return the state at pressure ``p`` [Pa] and specific enthalpy ``h`` [J/kg].

        Cached on the exact ``(p, h)`` floats (see the class notes).

        Raises
        ------
        PropertyError
            If ``p`` is not finite and positive, ``h`` is not finite, the
            backend cannot evaluate the state, or an output is NaN.
        """
        st = self._cache.get((p, h))
        if st is not None:
            return st
        return self._state_miss(p, h)

    def states(self, p, h, *, check: bool = True) -> FluidStates:
        """All properties at arrays of pressure ``p`` [Pa] and specific enthalpy ``h`` [J/kg].

        ``p`` and ``h`` are broadcast against each other; every field of the returned
        :class:`FluidStates` has their broadcast shape. Not cached (one call is meant to
        cover all points of a plant that use this medium).

        With ``check=True`` (default) the first state that cannot be evaluated raises
        :class:`PropertyError` (as :meth:`state` would); with ``check=False`` such
        states get ``ok = False`` and NaN fields, and no exception is raised.

        This base implementation calls :meth:`state` for each point (CoolProp media);
        IF97 water and the ideal gas override it with array code.
        """
        p, h = _as_arrays(p, h)
        n = p.size
        out = {k: np.full(n, np.nan) for k in _ARRAY_FIELDS}
        region = np.zeros(n, dtype=np.int8)
        ok = np.ones(n, dtype=bool)
        pf, hf = p.ravel(), h.ravel()
        for i in range(n):
            try:
                st = self.state(float(pf[i]), float(hf[i]))
            except PropertyError:
                if check:
                    raise
                ok[i] = False
                continue
            out["T"][i] = st.T
            out["rho"][i] = st.rho
            out["u"][i] = st.u
            out["s"][i] = st.s
            out["cp"][i] = st.cp
            out["drho_dp_h"][i] = st.drho_dp_h
            out["drho_dh_p"][i] = st.drho_dh_p
            if st.quality >= 0.0:
                out["x"][i] = st.quality
                region[i] = 4
        shape = p.shape
        return FluidStates(
            p,
            h,
            *(out[k].reshape(shape) for k in _ARRAY_FIELDS),
            region.reshape(shape),
            ok.reshape(shape),
        )

    def saturation_enthalpies(self, p):
        """(h_liq, h_vap) [J/kg]: saturated liquid and vapour enthalpy at pressures ``p`` [Pa].

        Arrays of the shape of ``p``; NaN at and above the critical pressure. Only for
        ``condensable`` media; others raise :class:`PropertyError`.
        """
        raise PropertyError(
            self.label, _first(p), math.nan, "saturation_enthalpies", "no two-phase region"
        )

    def h_px(self, p, x):
        """Specific enthalpy [J/kg] of the saturated mixture at pressures ``p`` [Pa] and
        vapour qualities ``x`` [-] in [0, 1] (arrays, broadcast): h_liq + x (h_vap - h_liq).

        Raises :class:`PropertyError` for a quality outside [0, 1], a pressure at or
        above the critical pressure (or outside the backend's saturation range), and
        for media without a two-phase region.
        """
        p, x = _as_arrays(p, x)
        if not self.condensable:
            raise PropertyError(self.label, _first(p), math.nan, "h_px", "no two-phase region")
        bad = ~((x >= 0.0) & (x <= 1.0))
        if bad.any():
            i = int(np.flatnonzero(bad.ravel())[0])
            raise PropertyError(
                self.label,
                float(p.flat[i]),
                math.nan,
                "h_px",
                f"quality {float(x.flat[i])!r} not in [0, 1]",
            )
        hl, hv = self.saturation_enthalpies(p)
        bad = ~np.isfinite(hl + hv)
        if bad.any():
            i = int(np.flatnonzero(bad.ravel())[0])
            raise PropertyError(
                self.label,
                float(p.flat[i]),
                math.nan,
                "h_px",
                "no saturated state at this pressure (at or above the critical pressure, "
                "or outside the saturation range of the backend)",
            )
        return hl + x * (hv - hl)

    def transport(self, p, h, *, check: bool = True) -> dict:
        """Transport properties at arrays of pressure ``p`` [Pa] and specific enthalpy
        ``h`` [J/kg] (broadcast; not cached), for heat-transfer and friction correlations.

        Returns a dict of float arrays of the broadcast shape:

        - ``"mu"``: dynamic viscosity [Pa s];
        - ``"k"``: thermal conductivity [W/(m K)];
        - ``"cp"``: isobaric specific heat [J/(kg K)] (the one ``Pr`` is made with);
        - ``"Pr"``: Prandtl number mu cp / k [-].

        Single-phase states only. A state strictly inside the two-phase dome
        (0 < x < 1) has no single viscosity or conductivity: it raises
        :class:`PropertyError` (``check=True``) or gets NaN (``check=False``); the
        saturated liquid and vapour values that two-phase correlations need come from
        :meth:`saturation_transport`. A state on the saturation line (x = 0 or 1) gets
        its saturated phase's values. States that cannot be evaluated raise (or get
        NaN) as in :meth:`states`. Which formulation each medium uses is said in its
        ``transport`` docstring (docs/correlations.md has the list).
        """
        raise PropertyError(
            self.label, _first(p), _first(h), "transport", "no transport properties for this medium"
        )

    def saturation_transport(self, p) -> dict:
        """Saturated liquid (``_l``) and vapour (``_v``) properties at pressures ``p``
        [Pa] for two-phase correlations: a dict of arrays of the shape of ``p`` with
        ``"T"`` (T_sat [K]), ``"rho_l"``, ``"rho_v"`` [kg/m3], ``"h_l"``, ``"h_v"``
        [J/kg], ``"mu_l"``, ``"mu_v"`` [Pa s], ``"k_l"``, ``"k_v"`` [W/(m K)],
        ``"cp_l"``, ``"cp_v"`` [J/(kg K)], ``"Pr_l"``, ``"Pr_v"`` [-] and ``"sigma"``
        (surface tension [N/m]).

        Raises :class:`PropertyError` for a pressure without a saturated state (at or
        above the critical pressure, below the triple point) and for media without a
        two-phase region.
        """
        raise PropertyError(
            self.label, _first(p), math.nan, "saturation_transport", "no two-phase region"
        )

    def h_pT(self, p: float, T: float) -> float:
        """Return the specific enthalpy h [J/kg] at pressure ``p`` [Pa] and temperature ``T`` [K].

        Single-phase states only: (p, T) does not fix a state inside the
        two-phase dome, so a ``T`` within 1e-6 K of the saturation temperature of
        ``p`` raises :class:`PropertyError` ("T = 342.16 °C is the saturation
        temperature at 150 bar: the state is not defined by p and T; give h or the
        quality"; the caller adds its component name); use :meth:`h_pQ` or
        :meth:`h_px` for saturated states. Cached like :meth:`state`.
        """
        hv = self._cache_hpT.get((p, T))
        if hv is not None:
            return hv
        pf = float(p)
        Tf = float(T)
        if not (0.0 < pf < _INF):
            raise PropertyError(
                self.label, pf, math.nan, "h_pT", "pressure must be finite and > 0", T=Tf
            )
        if not (0.0 < Tf < _INF):
            raise PropertyError(
                self.label, pf, math.nan, "h_pT", "temperature must be finite and > 0", T=Tf
            )
        try:
            hv = float(self._compute_h_pT(pf, Tf))
        except PropertyError:
            raise
        except BACKEND_ERRORS as exc:
            raise PropertyError(self.label, pf, math.nan, "h_pT", str(exc), T=Tf) from exc
        if not (-_INF < hv < _INF):
            raise PropertyError(
                self.label, pf, math.nan, "h_pT", f"backend returned h = {hv}", T=Tf
            )
        cache = self._cache_hpT
        if len(cache) >= self.cache_size:
            cache.clear()
        cache[(p, T)] = hv
        return hv

    def h_pQ(self, p: float, quality: float) -> float:
        """Return h [J/kg] of the saturated mixture at ``p`` [Pa] and vapour quality [-] in [0, 1].

        Raises :class:`PropertyError` for media without a two-phase region
        (the ideal gas) and for ``p`` at or above the critical pressure.
        """
        pf = float(p)
        x = float(quality)
        if not (0.0 < pf < _INF):
            raise PropertyError(self.label, pf, math.nan, "h_pQ", "pressure must be finite and > 0")
        if not (0.0 <= x <= 1.0):
            raise PropertyError(self.label, pf, math.nan, "h_pQ", f"quality {x!r} not in [0, 1]")
        try:
            hv = float(self._compute_h_pQ(pf, x))
        except PropertyError:
            raise
        except BACKEND_ERRORS as exc:
            raise PropertyError(self.label, pf, math.nan, "h_pQ", str(exc)) from exc
        if not (-_INF < hv < _INF):
            raise PropertyError(self.label, pf, math.nan, "h_pQ", f"backend returned h = {hv}")
        return hv

    @property
    def critical_point(self) -> tuple[float, float]:
        """(T_c [K], p_c [Pa]), the end of the saturation line; (nan, nan) for a medium
        without a two-phase region."""
        return self.T_critical, self.p_critical

    def p_sat(self, T: float) -> float:
        """The vapour pressure [Pa] at the temperature T [K]: the saturation pressure
        below the critical temperature, the critical pressure at and above it (a
        component asks for the flashing limit of a liquid: a control valve's choked
        flow, a pump's NPSH). Only a condensable medium has one; the others raise
        ``PropertyError`` naming the medium."""
        self._no_two_phase_region("p_sat", T)

    def _no_two_phase_region(self, prop: str, T: float):
        raise PropertyError(
            self.label, math.nan, math.nan, prop, "the medium has no two-phase region", T=T
        )

    def cache_clear(self) -> None:
        """Empty the ``state`` and ``h_pT`` caches."""
        self._cache.clear()
        self._cache_hpT.clear()

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.label}>"

    # ------------------------------------------------------- implementation
    def _state_miss(self, p: float, h: float) -> FluidState:
        key = (p, h)
        pf = float(p)
        hf = float(h)
        if not (0.0 < pf < _INF):
            raise PropertyError(self.label, pf, hf, "state", "pressure must be finite and > 0")
        if not (-_INF < hf < _INF):
            raise PropertyError(self.label, pf, hf, "state", "enthalpy must be finite")
        try:
            st = self._compute_state(pf, hf)
        except PropertyError:
            raise
        except BACKEND_ERRORS as exc:
            raise PropertyError(self.label, pf, hf, "state", str(exc)) from exc
        self.n_evaluations += 1
        _check_outputs(self.label, st)
        cache = self._cache
        if len(cache) >= self.cache_size:
            cache.clear()
        cache[key] = st
        return st

    def _refuse_saturated(self, p: float, T: float, T_sat: float) -> None:
        """Raise PropertyError when T is (within ``T_SAT_BAND`` = 1e-6 K) T_sat(p).

        There h is not fixed by (p, T): any point of the two-phase dome has it.
        """
        if abs(T - T_sat) <= T_SAT_BAND:
            raise PropertyError(self.label, p, math.nan, "h_pT", saturation_message(p, T), T=T)

    @abstractmethod
    def _compute_state(self, p: float, h: float) -> FluidState:
        """Compute the state at checked ``p`` > 0 [Pa] and finite ``h`` [J/kg].

        May raise :class:`PropertyError` or any of ``BACKEND_ERRORS``.
        """

    @abstractmethod
    def _compute_h_pT(self, p: float, T: float) -> float:
        """h [J/kg] at checked ``p`` > 0 [Pa] and ``T`` > 0 [K]."""

    def _compute_h_pQ(self, p: float, x: float) -> float:
        raise PropertyError(self.label, p, math.nan, "h_pQ", "this medium has no two-phase region")


#: [K] a T this close to T_sat(p) is "at saturation" for h_pT
T_SAT_BAND = 1e-6

_ARRAY_FIELDS = ("T", "rho", "u", "s", "cp", "x", "drho_dp_h", "drho_dh_p")


def saturation_message(p: float, T: float) -> str:
    """ "T = 342.16 °C is the saturation temperature at 150 bar: ..." for h_pT errors."""
    return (
        f"T = {T - 273.15:.6g} °C is the saturation temperature at {p / 1e5:.6g} bar: the "
        "state is not defined by p and T; give h or the quality"
    )


def _as_arrays(a, b):
    a, b = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    return a.copy(), b.copy()


def _first(p) -> float:
    return float(np.ravel(np.asarray(p, dtype=float))[0]) if np.size(p) else math.nan


def _check_outputs(label: str, st: FluidState) -> None:
    """Raise PropertyError if an output of ``st`` is NaN or unphysical."""
    T, rho = st.T, st.rho
    if not (0.0 < T < _INF):
        raise PropertyError(label, st.p, st.h, "T", f"backend returned T = {T} K")
    if not (0.0 < rho < _INF):
        raise PropertyError(label, st.p, st.h, "rho", f"backend returned rho = {rho} kg/m3")
    if not (
        -_INF < st.u < _INF
        and -_INF < st.s < _INF
        and -_INF < st.drho_dp_h < _INF
        and -_INF < st.drho_dh_p < _INF
    ):
        for prop in ("u", "s", "drho_dp_h", "drho_dh_p"):
            val = getattr(st, prop)
            if not (-_INF < val < _INF):
                raise PropertyError(label, st.p, st.h, prop, f"backend returned {prop} = {val}")
    cp = st.cp
    if not (0.0 < cp <= _INF):  # inf is the documented two-phase value; NaN fails
        raise PropertyError(label, st.p, st.h, "cp", f"backend returned cp = {cp} J/(kg K)")
    q = st.quality
    if not (q == -1.0 or 0.0 <= q <= 1.0):
        raise PropertyError(label, st.p, st.h, "quality", f"backend returned quality = {q}")


#: keys of :meth:`Medium.saturation_transport`
SATURATION_TRANSPORT_KEYS = (
    "T", "rho_l", "rho_v", "h_l", "h_v", "mu_l", "mu_v", "k_l", "k_v",
    "cp_l", "cp_v", "Pr_l", "Pr_v", "sigma",
)  # fmt: skip


def transport_result(label, p, h, mu, k, cp, bad, reasons, check: bool) -> dict:
    """The dict of :meth:`Medium.transport` from flat arrays (``bad``: points that
    could not be evaluated, ``reasons``: their messages, a callable index -> str).

    With ``check`` the first bad point raises :class:`PropertyError` (property
    "transport"); otherwise bad points get NaN. Arrays are reshaped to ``p.shape``.
    """
    if bad.any():
        if check:
            i = int(np.flatnonzero(bad)[0])
            raise PropertyError(label, float(p.flat[i]), float(h.flat[i]), "transport", reasons(i))
        mu = np.where(bad, np.nan, mu)
        k = np.where(bad, np.nan, k)
        cp = np.where(bad, np.nan, cp)
    shape = p.shape
    with np.errstate(invalid="ignore", divide="ignore"):
        Pr = mu * cp / k
    return {
        "mu": mu.reshape(shape),
        "k": k.reshape(shape),
        "cp": cp.reshape(shape),
        "Pr": Pr.reshape(shape),
    }


def dome_reason(x: float) -> str:
    """Why :meth:`Medium.transport` refuses a two-phase state of quality ``x``."""
    return (
        f"the state is inside the two-phase dome (quality x = {x:.6g}): a mixture has no "
        "single viscosity or conductivity; two-phase correlations take the saturated "
        "liquid and vapour values of saturation_transport(p)"
    )
