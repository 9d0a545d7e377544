"""`IdealGas`: a perfect gas with constant specific heat (air by default)."""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.media.base import Medium, _as_arrays, transport_result
from dnasim.media.errors import PropertyError
from dnasim.media.gas_mixture import DRY_AIR, GasMixture
from dnasim.media.state import FluidState, FluidStates

_log = math.log


class IdealGas(Medium):
    """Ideal gas with constant isobaric specific heat.

    Closed forms, with R [J/(kg K)], cp [J/(kg K)] constant, T_ref [K], p_ref [Pa]::

        T   = T_ref + h / cp                 [K]       (so h = cp (T - T_ref), h(T_ref) = 0)
        rho = p / (R T)                      [kg/m3]
        u   = h - p / rho = h - R T          [J/kg]    (h = u + p v exactly, no extra constant)
        s   = cp ln(T / T_ref) - R ln(p / p_ref)   [J/(kg K)]   (s = 0 at T_ref, p_ref)
        cp  = cp,  cv = cp - R
        drho/dp|h = 1 / (R T)                [kg/(m3 Pa)]
        drho/dh|p = -rho / (cp T)            [kg2/(m3 J)]
        quality = -1 (no two-phase region)

    ``u`` carries no arbitrary constant on purpose: storage terms use ``u``
    while flows carry ``h``, and they must satisfy ``h = u + p/rho``. A state
    with T <= 0 K (``h <= -cp T_ref``) raises :class:`PropertyError`.

    ``get_medium("Air")`` returns the shared instance with the default
    parameters (dry air, R = 287.05 J/(kg K), cp = 1006 J/(kg K),
    T_ref = 273.15 K, p_ref = 101325 Pa), as in the DNA lecture notes' pipe
    example; ``get_medium("Air", backend="HEOS")`` gives CoolProp's real-gas
    air instead. For another gas construct ``IdealGas(name, R=..., cp=...)``
    directly (it is then not shared through ``get_medium``).

    Parameters
    ----------
    name : str
        Name used in messages.
    R : float
        Specific gas constant [J/(kg K)], > 0.
    cp : float
        Isobaric specific heat [J/(kg K)], > R.
    T_ref : float
        Temperature [K] at which h = 0 and s = 0 (with ``p_ref``).
    p_ref : float
        Pressure [Pa] at which s = 0 (with ``T_ref``).

    Raises
    ------
    dnasim.core.errors.PlantError
        For a non-positive or non-finite parameter, or cp <= R.
    """

    def __init__(
        self,
        name: str = "Air",
        R: float = 287.05,
        cp: float = 1006.0,
        T_ref: float = 273.15,
        p_ref: float = 101325.0,
        *,
        cache_size: int = 4096,
    ) -> None:
        super().__init__(name, "IdealGas", cache_size=cache_size)
        R = float(R)
        cp = float(cp)
        if not (0.0 < R < math.inf):
            raise PlantError(f"IdealGas {name}: R must be finite and > 0, got {R}")
        if not (R < cp < math.inf):
            raise PlantError(f"IdealGas {name}: cp must be finite and > R = {R}, got {cp}")
        if not (0.0 < T_ref < math.inf and 0.0 < p_ref < math.inf):
            raise PlantError(f"IdealGas {name}: T_ref and p_ref must be finite and > 0")
        self.R = R
        self.cp = cp
        self.T_ref = float(T_ref)
        self.p_ref = float(p_ref)

    @property
    def cv(self) -> float:
        """Isochoric specific heat cv = cp - R [J/(kg K)]."""
        return self.cp - self.R

    @property
    def gamma(self) -> float:
        """Heat capacity ratio cp / cv [-]."""
        return self.cp / (self.cp - self.R)

    def T_h(self, h: float) -> float:
        """Temperature [K] from specific enthalpy h [J/kg] (independent of p)."""
        return self.T_ref + h / self.cp

    def _compute_state(self, p: float, h: float) -> FluidState:
        cp = self.cp
        R = self.R
        T = self.T_ref + h / cp
        if not T > 0.0:
            raise PropertyError(self.label, p, h, "T", f"temperature T = {T} K is not positive")
        rho = p / (R * T)
        return FluidState(
            p,
            h,
            T,
            rho,
            h - p / rho,
            cp * _log(T / self.T_ref) - R * _log(p / self.p_ref),
            cp,
            -1.0,
            1.0 / (R * T),
            -rho / (cp * T),
        )

    def states(self, p, h, *, check: bool = True) -> FluidStates:
        """Vectorised :meth:`state` (the closed forms above on arrays, numpy).

        A state with p not finite and > 0, h not finite, or T <= 0 K raises
        :class:`PropertyError` (``check=True``) or gets ``ok = False`` and NaN fields.
        """
        p, h = _as_arrays(p, h)
        cp = self.cp
        R = self.R
        T = self.T_ref + h / cp
        ok = (p > 0.0) & (p < math.inf) & np.isfinite(h) & (T > 0.0)
        if not ok.all():
            if check:
                i = int(np.flatnonzero(~ok.ravel())[0])
                pi, hi, Ti = float(p.flat[i]), float(h.flat[i]), float(T.flat[i])
                reason = (
                    "pressure must be finite and > 0"
                    if not (0.0 < pi < math.inf)
                    else "enthalpy must be finite"
                    if not math.isfinite(hi)
                    else f"temperature T = {Ti} K is not positive"
                )
                raise PropertyError(self.label, pi, hi, "state", reason)
            T = np.where(ok, T, np.nan)
        with np.errstate(invalid="ignore", divide="ignore"):
            rho = p / (R * T)
            s = cp * np.log(T / self.T_ref) - R * np.log(p / self.p_ref)
        self.n_evaluations += p.size
        nan = np.full(p.shape, np.nan)
        return FluidStates(
            p,
            h,
            T,
            rho,
            h - p / rho,
            s,
            np.where(ok, cp, np.nan),
            nan,
            1.0 / (R * T),
            -rho / (cp * T),
            np.zeros(p.shape, dtype=np.int8),
            ok,
        )

    def T_rho_u(self, p, h, branch=None, memo=None):
        """(T [K], rho [kg/m3], u [J/kg]) arrays at 1-D float arrays p [Pa], h [J/kg]: the
        numbers of :meth:`states` without its other fields, for a residual's property
        call (``dnasim.model.physics.PropertyArrays``); ``branch`` and ``memo`` are
        not used (no phase branches; nothing to remember for closed forms). Raises
        :class:`PropertyError` as :meth:`states` does."""
        T = self.T_ref + h / self.cp
        if not ((p > 0.0) & (p < math.inf) & np.isfinite(h) & (T > 0.0)).all():
            self.states(p, h)  # raises the error of the first bad state
        rho = p / (self.R * T)
        self.n_evaluations += p.size
        return T, rho, h - p / rho

    def _compute_h_pT(self, p: float, T: float) -> float:
        return self.cp * (T - self.T_ref)

    def transport(self, p, h, *, check: bool = True) -> dict:
        """Viscosity, conductivity, cp and Pr at (p [Pa], h [J/kg]) (see
        :meth:`Medium.transport`), for the gas named ``"Air"`` only: dry air
        (:data:`dnasim.media.gas_mixture.DRY_AIR`: N2, O2, Ar, CO2 by mole) at this
        medium's T = T_ref + h / cp, by :mod:`dnasim.media.gas_transport` (Wilke,
        Wassiljewa/Mason-Saxena). ``"cp"`` (and so ``"Pr"``) is the physical cp(T) of
        dry air from the NASA polynomials, not this medium's constant cp: a
        heat-transfer correlation needs the real Prandtl number (0.707 at 300 K, 0.73
        at 1000 K, where the constant cp = 1006 J/(kg K) would give 0.64). Another
        IdealGas has no transport data: PropertyError."""
        p, h = _as_arrays(p, h)
        if self.name != "Air":
            raise PropertyError(
                self.label, float(p.flat[0]) if p.size else math.nan,
                float(h.flat[0]) if h.size else math.nan, "transport",
                "no transport data for this ideal gas (only 'Air' has them); use a "
                "GasMixture or a CoolProp fluid",
            )  # fmt: skip
        air = getattr(self, "_air_mixture", None)
        if air is None:
            air = self._air_mixture = GasMixture("Air", mole_fractions=DRY_AIR)
        T = self.T_ref + h / self.cp
        ok = (p > 0.0) & (p < math.inf) & np.isfinite(h) & (T >= air.T_min) & (T <= air.T_max)
        Tf = np.where(ok, T, air.T_ref).ravel()
        ha = air.h_T(Tf)
        out = air.transport(np.full(Tf.shape, 1e5), ha)
        pf, hf, Tb = p.ravel(), h.ravel(), T.ravel()

        def reason(i):
            if not (0.0 < pf[i] < math.inf):
                return "pressure must be finite and > 0"
            if not math.isfinite(hf[i]):
                return "enthalpy must be finite"
            return (
                f"T = {Tb[i]:.6g} K is outside {air.T_min:g} K..{air.T_max:g} K, the range "
                "of the transport data"
            )

        return transport_result(
            self.label, p, h, out["mu"], out["k"], out["cp"], ~ok.ravel(), reason, check
        )
