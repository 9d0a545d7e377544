"""Friction and heat transfer of a channel from its geometry (issue 22): the laws a
``Channel`` uses instead of the lumped k and kA when its tubes are described by
``dnasim.library.submodels.tube_geometry``. Not components by themselves. Every law is
evaluated on all volumes (or faces) of a channel at once, as numpy arrays: one
property call for the states' transport properties, no loop over volumes.

States and phases. A channel's states S_0..S_{n+1} (``dnasim.library.submodels.channel``)
have (p, h), and from the medium T and rho. ``fluid_properties`` adds, per state:
viscosity mu [Pa s], conductivity k [W/(m K)] and cp [J/(kg K)] of the single phase
(``medium.transport``), and for a condensable medium below its critical pressure the
quality x = (h - h')/(h'' - h') and the saturated properties
(``medium.saturation_transport``). A state takes the two-phase correlations with the
weight w2: 1 for a volume in the two-phase phase mode (IF97 with phase switches), 0
in the liquid or vapour mode; without modes w2 = s(x/0.01) s((1 - x)/0.01) (s the
cubic smoothstep: the two-phase laws fade in over the first and last 1 % of quality, so
a crossing of the saturation line changes no coefficient by a jump). A state inside the
dome weighted single-phase (a volume in the liquid mode past h', metastable) has the
saturated phase's transport properties.

Friction of face j (``TubeFriction``; per tube m_t = m/n_tubes, L_j = L/n):

    single phase   dp = (f Re)(Re_r) mu L_j m_t / (2 rho A_t D^2)      (Darcy-Weisbach)
                   Re_r = m_r D/(A_t mu),  m_r = sqrt(m_t^2 + m_reg,t^2)
                   (f Re: ``friction.darcy_friction_Re``: laminar 64, Colebrook (or
                   Haaland) from Re = 4000, the cubic blend between)
    two phase      dp = phi_lo^2 dp_lo   (Friedel; dp_lo: all the flow as saturated liquid)
                   or the single-phase law at the homogeneous density and McAdams'
                   viscosity ("homogeneous")
    mixed          dp = (1 - w2) dp_single + w2 dp_two

and on the face the upwind blend of the two states beside it,
dp_j = (w(m) dp(S_j) + w(-m) dp(S_{j+1}))/(w(m) + w(-m)) (exactly the upstream state's
for |m| >= m_eps, reverse flow included). The regularisation m_reg (the lumped law's,
1 % of m_nominal by default) replaces |m| in Re and in m|m|: for |m| >> m_reg it is
Darcy-Weisbach to (m_reg/m)^2/2; through zero flow dp is linear in m with the slope of
the law at m_reg, as the lumped law (a laminar slope alone, 32 mu L/(rho A D^2), leaves
the flows of a steam pipe at rest undetermined by tens of kg/s at rtol 1e-6:
``physics.M_REG_REL``). Where that slope is laminar the law is exact Hagen-Poiseuille.

Heat transfer of volume i, inside tubes (``TubeConvection``; G = m_r/A_t with the
volume's mean flow (m[i] + m[i+1])/2 regularised as above, A_i,vol = A_i/n):

    single phase   h = Nu k/D; Nu = ``heat_transfer.nusselt_tube`` (VDI G1:
                   Gnielinski, laminar 3.66 with the entrance term, linear between
                   Re 2300 and 1e4; d/L of the whole tube) or Dittus-Boelter
                   0.023 Re^0.8 Pr^n, n = 0.3 + 0.1 s, s = (1 + tanh((T_w - T)/1 K))/2
                   (0.4 heating the fluid, 0.3 cooling it, blended over a kelvin)
    two phase      h = s h_Chen + (1 - s) h_Shah, s = (1 + tanh((T_s - T_sat)/1 K))/2:
                   flow boiling by Chen with the dry-out quality x_dryout (``boiling``),
                   dT_sat = T_s - T_sat, dp_sat by Clausius-Clapeyron
                   (``boiling.clapeyron_dp_sat``); condensation by Shah 1979; Chen's h_l
                   (and vapour-only value) and Shah's h_lo by the single-phase Nu above
                   instead of their Dittus-Boelter, so that at x = 0 h = h_single + S
                   h_nb and at x = 1 the vapour's single-phase h: a volume changing its
                   phase sees no drop of its coefficient (a drop at boiling onset makes
                   the phase switch chatter: measured on an evaporator from geometry);
                   Shah's, which vanishes at x = 1, blended linearly from x_dryout into
                   the vapour's single-phase h (as Chen's after dry-out)
    mixed          h = (1 - w2) h_single + w2 h_two
    conductance    UA_i = 1 / (1/(h A_i,vol) + R_in,vol(lambda(T_w)))

R_in,vol: the inner half of the wall (``tube_geometry``: T_w is the wall's mean
temperature) at the metal's lambda(T_w); 0 without a wall thickness. T_s, the inner
surface temperature Chen's nucleate boiling needs, is T + (T_w - T) R_c/(R_c + R_in)
with R_c = 1/(h A_i,vol): two fixed-point steps from T_s = T_w (with R_in = 0: T_w
itself).

Heat transfer of the outside of a tube bank (``BankConvection``; section i of n, the
gas state its own volume's):

    convection     Nu = ``tube_banks.nusselt_zukauskas``(Re_max, Pr, n_rows, S_T, S_L)
                   (no Pr_wall correction), Re_max = (m_r/A_front) r_max D_o/mu with
                   r_max = V_max/V of ``tube_banks.max_velocity`` for the blocked width
                   D_eff (``tube_geometry``); h = Nu k/D_o
    fins           eta_0 = 1 - A_fin/A_out (1 - eta_fin), eta_fin Schmidt's
                   (``tube_banks.annular_fin_efficiency``) at lambda_fin(T_w); Zukauskas'
                   bare-tube h is taken for the finned surface (no finned-bank
                   correlation in the library: an approximation, stated)
    gas radiation  h_rad = (eps_w + 1)/2 sigma eps_g (T_g + T_w)(T_g^2 + T_w^2)  (optional;
                   ``radiation.gas_wall_heat_flux`` divided by T_g - T_w), eps_g by
                   WSGG (``radiation.gas_emissivity``) at the gas's H2O and CO2 partial
                   pressures and the mean beam length, on the bare tube area A_o
    conductance    UA_i = 1 / (1/((eta_0 h A_out + h_rad A_o)/n) + R_out,vol(lambda(T_w)))
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.correlations.boiling import X_DRYOUT, chen_boiling, clapeyron_dp_sat
from dnasim.correlations.condensation import shah_condensation
from dnasim.correlations.friction import (
    darcy_friction_Re,
    friedel_multiplier,
    haaland,
    homogeneous_density,
    mixture_density,
    void_fraction_zivi,
)
from dnasim.correlations.heat_transfer import nusselt_tube
from dnasim.correlations.radiation import SIGMA_SB, gas_emissivity
from dnasim.correlations.tube_banks import annular_fin_efficiency, max_velocity, nusselt_zukauskas
from dnasim.model.physics import is_condensable, saturation_enthalpies

#: phase branch codes of ``dnasim.media.if97_numba`` (as ``channel``)
AUTO, LIQUID, DOME, VAPOUR = 0, 1, 2, 3
#: [-] quality band over which the two-phase laws fade in at each end of the dome
X_BAND = 0.01
#: [K] temperature width of the heating/cooling blends (Dittus-Boelter's n, Chen/Shah)
DT_BLEND = 1.0

_SAT_KEYS = (
    "T", "rho_l", "rho_v", "h_l", "h_v", "mu_l", "mu_v", "k_l", "k_v", "cp_l", "cp_v", "sigma"
)  # fmt: skip


class ArrayMemo:
    """An array function of (p[, h]) that remembers its last inputs and outputs and
    recomputes only the points whose inputs changed (a finite-difference Jacobian moves
    a few states at a time; a Newton iteration all of them: one call as without).
    ``fn`` returns a tuple or a dict of arrays of the inputs' shape; the outputs are
    shared between calls and must not be changed in place."""

    def __init__(self, fn):
        self.fn = fn
        self.key = None
        self.out = None

    def __call__(self, *args):
        key = self.key
        if key is not None and key[0].shape == args[0].shape:
            changed = np.zeros(args[0].shape, dtype=bool)
            for a, k in zip(args, key, strict=True):
                changed |= a != k
            idx = np.flatnonzero(changed)
            if idx.size == 0:
                return self.out
            if idx.size < changed.size:
                sub = self.fn(*(a[idx] for a in args))
                out = self._merge(self.out, sub, idx)
                self.key, self.out = tuple(a.copy() for a in args), out
                return out
        out = self.fn(*args)
        self.key, self.out = tuple(a.copy() for a in args), out
        return out

    @staticmethod
    def _merge(old, sub, idx):
        if isinstance(old, dict):
            new = {k: v.copy() for k, v in old.items()}
            for k, v in new.items():
                v[idx] = sub[k]
            return new
        new = tuple(v.copy() for v in old)
        for v, w in zip(new, sub, strict=True):
            v[idx] = w
        return new


class PropertyMemos:
    """The ``ArrayMemo`` of each property call of one channel's states, for one medium.
    Pickles as its medium alone (the memos start empty again)."""

    def __init__(self, medium):
        self.medium = medium
        self.saturation = ArrayMemo(self._saturation)
        #: the same for a subset of the states (its size changes with the phase modes)
        self.saturation_some = ArrayMemo(self._saturation)
        self.transport = ArrayMemo(self._transport)
        self.sat_transport = ArrayMemo(medium.saturation_transport)
        self.condensable = is_condensable(medium)

    def _saturation(self, p):
        return saturation_enthalpies(self.medium, p)

    def _transport(self, p, h):
        return self.medium.transport(p, h, check=False)

    def __getstate__(self):
        return {"medium": self.medium}

    def __setstate__(self, state):
        self.__init__(state["medium"])


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


class FluidProperties:
    """Transport properties and phase weights of a set of states (module doc).

    Attributes (arrays over the states): ``p``, ``T``, ``rho``, ``mu``, ``k``, ``cp``
    (single phase), ``x`` (quality; nan where there is none), ``w2`` (two-phase
    weight), and ``sat`` (dict of the saturated properties of ``_SAT_KEYS`` plus
    ``h_lv``; nan where the state has no saturation line or does not need it)."""

    __slots__ = ("p", "T", "rho", "mu", "k", "cp", "x", "w2", "sat", "p_critical")

    def __init__(self, medium, p, h, T, rho, branch=None, memos=None):
        p = np.asarray(p, dtype=float)
        h = np.asarray(h, dtype=float)
        n = p.size
        if memos is None or memos.medium is not medium:
            memos = PropertyMemos(medium)
        self.p, self.T, self.rho = p, np.asarray(T, dtype=float), np.asarray(rho, dtype=float)
        self.p_critical = float(getattr(medium, "p_critical", math.nan))
        self.sat = None
        self.x = np.full(n, np.nan)
        self.w2 = np.zeros(n)
        if not memos.condensable:
            t = memos.transport(p, h)
            self.mu, self.k, self.cp = self._single_phase(medium, t, p, h, np.ones(n, bool))
            return
        t = memos.transport(p, h)
        if branch is None:  # the quality of every state
            hl, hv = memos.saturation(p)
        else:
            # with phase modes only the states in the dome mode, the nodes (no mode) and
            # the states the single-phase call refuses (inside the dome) need it
            branch = np.asarray(branch)
            finite = np.isfinite(t["mu"]) & np.isfinite(t["k"]) & np.isfinite(t["cp"])
            sel = np.flatnonzero((branch == DOME) | (branch == AUTO) | ~finite)
            hl, hv = np.full(n, np.nan), np.full(n, np.nan)
            if sel.size:
                hl[sel], hv[sel] = memos.saturation_some(p[sel])
        sub = np.isfinite(hl) & np.isfinite(hv)
        x = np.where(sub, (h - hl) / np.where(sub, hv - hl, 1.0), np.nan)
        self.x = x
        inside = sub & (x > 0.0) & (x < 1.0)
        ramp = np.where(sub, _smoothstep(x / X_BAND) * _smoothstep((1.0 - x) / X_BAND), 0.0)
        if branch is None:
            w2 = ramp
        else:
            w2 = np.where(branch == DOME, 1.0, np.where(branch == AUTO, ramp, 0.0))
            w2 = np.where(sub, w2, 0.0)
        self.w2 = w2
        mu, k, cp = self._single_phase(medium, t, p, h, ~inside)
        need = sub & (inside | (w2 > 0.0))
        if need.any():
            s = memos.sat_transport(p[need])  # remembered per point
            sat = {key: np.full(n, np.nan) for key in _SAT_KEYS}
            for key in _SAT_KEYS:
                sat[key][need] = s[key]
            sat["h_lv"] = sat["h_v"] - sat["h_l"]
            self.sat = sat
            if inside.any():  # single-phase values inside the dome: the saturated phase's
                vap = x >= 0.5
                if branch is not None:
                    vap = np.where(branch == VAPOUR, True, np.where(branch == LIQUID, False, vap))
                for arr, key in ((mu, "mu"), (k, "k"), (cp, "cp")):
                    side = np.where(vap, sat[key + "_v"], sat[key + "_l"])
                    arr[inside] = side[inside]
        self.mu, self.k, self.cp = mu, k, cp

    @staticmethod
    def _single_phase(medium, t, p, h, single):
        """(mu, k, cp) of the states from the transport call's dict t (NaN inside the
        dome); the medium's PropertyError for a single-phase state it cannot evaluate."""
        mu, k, cp = t["mu"].copy(), t["k"].copy(), t["cp"].copy()
        bad = single & ~(np.isfinite(mu) & np.isfinite(k) & np.isfinite(cp))
        if bad.any():  # raises the medium's own message for the first bad state
            medium.transport(p[bad], h[bad])
        return mu, k, cp


class TubeFriction:
    """Darcy-Weisbach friction of the n faces of a tube channel (module doc)."""

    def __init__(self, tubes, n, law="colebrook", two_phase="friedel", m_reg=0.0,
                 void_fraction="homogeneous"):  # fmt: skip
        self.tubes = tubes
        self.turbulent = haaland if law == "haaland" else None
        self.friedel = two_phase == "friedel"
        self.zivi = void_fraction == "zivi"
        self.D, self.A_t, self.nt = tubes.D, tubes.A_tube, tubes.n_tubes
        self.L_j = tubes.length / n
        self.eps = tubes.roughness / tubes.D
        self.m_reg_t = m_reg / tubes.n_tubes

    def _single(self, mt, mr, mu, rho):
        Re = mr * self.D / (self.A_t * mu)
        fRe = darcy_friction_Re(Re, self.eps, self.turbulent)
        return fRe * mu * self.L_j * mt / (2.0 * rho * self.A_t * self.D * self.D)

    def dp(self, m, fp: FluidProperties, idx):
        """Friction pressure drop [Pa] at flows m [kg/s] (all tubes) of the states
        ``idx`` (indices into ``fp``, one per flow)."""
        mt = m / self.nt
        mr = np.sqrt(mt * mt + self.m_reg_t * self.m_reg_t)
        dp = self._single(mt, mr, fp.mu[idx], fp.rho[idx])
        w2 = fp.w2[idx]
        two = w2 > 0.0
        if two.any():
            j = idx[two]
            s = fp.sat
            x = np.clip(fp.x[j], 0.0, 1.0)
            rl, rv, ml, mv = s["rho_l"][j], s["rho_v"][j], s["mu_l"][j], s["mu_v"][j]
            if self.friedel:
                G = mr[two] / self.A_t
                phi2 = friedel_multiplier(
                    G, x, rl, rv, ml, mv, s["sigma"][j], self.D, self.tubes.roughness,
                    self.turbulent,
                )  # fmt: skip
                dp2 = phi2 * self._single(mt[two], mr[two], ml, rl)
            else:
                mu_h = 1.0 / (x / mv + (1.0 - x) / ml)
                dp2 = self._single(mt[two], mr[two], mu_h, homogeneous_density(x, rl, rv))
            dp[two] = (1.0 - w2[two]) * dp[two] + w2[two] * dp2
        return dp

    def head_density(self, fp: FluidProperties):
        """Density of the static head at each state [kg/m3]: rho (the homogeneous
        mixture's, as the mass balance's) or, with void_fraction = "zivi", the
        mixture density of Zivi's void fraction where the state is two-phase."""
        rho = fp.rho
        if not self.zivi or fp.sat is None:
            return rho
        two = fp.w2 > 0.0
        if not two.any():
            return rho
        s = fp.sat
        x = np.clip(fp.x[two], 0.0, 1.0)
        alpha = void_fraction_zivi(x, s["rho_l"][two], s["rho_v"][two])
        out = rho.copy()
        w = fp.w2[two]
        rho_m = mixture_density(alpha, s["rho_l"][two], s["rho_v"][two])
        out[two] = (1.0 - w) * rho[two] + w * rho_m
        return out


class _WallHalf:
    """Conduction through one half of the tube wall, per volume [K/W] at lambda(T_w)."""

    def __init__(self, tubes, n, part):
        self.tubes, self.n, self.part = tubes, n, part
        self.metal = tubes.metal if tubes.has_wall else None

    def resistance(self, T_w):
        if self.metal is None:
            return 0.0
        lam = self.metal.conductivity(T_w)
        return self.n * self.tubes.conduction_resistance(lam, self.part)


class TubeConvection:
    """Heat transfer inside tubes, fluid to wall, per volume (module doc)."""

    def __init__(self, tubes, n, single="gnielinski", x_dryout=X_DRYOUT, m_reg=0.0,
                 wall_resistance=True):  # fmt: skip
        self.tubes, self.n = tubes, n
        self.dittus = single == "dittus_boelter"
        self.x_dryout = x_dryout
        self.D, self.A_t, self.nt = tubes.D, tubes.A_tube, tubes.n_tubes
        self.A_vol = tubes.A_inner / n
        self.d_over_L = tubes.D / tubes.length
        self.m_reg_t = m_reg / tubes.n_tubes
        self.wall = _WallHalf(tubes, n, "inner") if wall_resistance else None

    def _h_single(self, G, mu, k, cp, T, T_w):
        Re = G * self.D / mu
        Pr = mu * cp / k
        if self.dittus:
            s = 0.5 * (1.0 + np.tanh((T_w - T) / DT_BLEND))
            Nu = 0.023 * Re**0.8 * Pr ** (0.3 + 0.1 * s)
        else:
            Nu = nusselt_tube(Re, Pr, self.d_over_L, "T")
        return Nu * k / self.D

    def _nusselt(self, Re, Pr):
        """The single-phase Nu(Re, Pr) of this law, for Chen's h_l and Shah's h_lo: the
        two-phase coefficients then join the single-phase one at x = 0 and 1."""
        if self.dittus:
            return 0.023 * Re**0.8 * Pr**0.4
        return nusselt_tube(Re, Pr, self.d_over_L, "T")

    def _h_two(self, G, x, sat, p, p_critical, T_s):
        dT = T_s - sat["T"]
        dp_sat = clapeyron_dp_sat(dT, sat["T"], p, sat["h_lv"], sat["rho_l"], sat["rho_v"])
        args = (G, x, self.D, sat["rho_l"], sat["rho_v"], sat["mu_l"], sat["mu_v"], sat["k_l"],
                sat["cp_l"], sat["h_lv"], sat["sigma"])  # fmt: skip
        tail = (self.x_dryout, sat["k_v"], sat["cp_v"], self._nusselt)
        h_b = chen_boiling(*args, dT, dp_sat, *tail)
        # the nucleate term S h_nb fades in over the first X_BAND of quality: at x = 0
        # Chen's coefficient is the liquid's, whatever the wall superheat (no jump
        # where a volume enters the dome; subcooled boiling is not modelled)
        h_conv = chen_boiling(*args, 0.0, 0.0, *tail)
        h_b = h_conv + _smoothstep(x / X_BAND) * (h_b - h_conv)
        # Shah's coefficient vanishes at x = 1 (the film's formula): above x_dryout it is
        # blended linearly into the vapour's single-phase one, as Chen's after dry-out
        xc = self.x_dryout
        h_c = shah_condensation(G, np.minimum(x, xc), self.D, sat["mu_l"], sat["k_l"], sat["cp_l"],
                                p / p_critical, self._nusselt)  # fmt: skip
        h_v = self._nusselt(G * self.D / sat["mu_v"], sat["mu_v"] * sat["cp_v"] / sat["k_v"])
        h_v = h_v * sat["k_v"] / self.D
        w = np.clip((x - xc) / max(1.0 - xc, 1e-12), 0.0, 1.0)
        h_c = (1.0 - w) * h_c + w * h_v
        s = 0.5 * (1.0 + np.tanh(dT / DT_BLEND))
        return s * h_b + (1.0 - s) * h_c

    def h(self, m_vol, T_w, fp: FluidProperties, idx):
        """(h [W/(m2 K)], R_in [K/W]) per volume at its mean flow m_vol [kg/s], wall
        temperature T_w [K] and state ``idx`` (indices into ``fp``)."""
        mt = m_vol / self.nt
        G = np.sqrt(mt * mt + self.m_reg_t * self.m_reg_t) / self.A_t
        T = fp.T[idx]
        h = self._h_single(G, fp.mu[idx], fp.k[idx], fp.cp[idx], T, T_w)
        R_w = self.wall.resistance(T_w) if self.wall is not None else 0.0
        w2 = fp.w2[idx]
        two = w2 > 0.0
        if two.any():
            j = idx[two]
            sat = {key: v[j] for key, v in fp.sat.items()}
            x = np.clip(fp.x[j], 0.0, 1.0)
            Tw2, T2 = T_w[two], T[two]
            R2 = R_w[two] if np.ndim(R_w) else 0.0
            T_s = Tw2
            h2 = self._h_two(G[two], x, sat, fp.p[j], fp.p_critical, T_s)
            if np.ndim(R_w):
                for _ in range(2):  # the inner surface temperature (module doc)
                    R_c = 1.0 / (h2 * self.A_vol)
                    T_s = T2 + (Tw2 - T2) * R_c / (R_c + R2)
                    h2 = self._h_two(G[two], x, sat, fp.p[j], fp.p_critical, T_s)
            h[two] = (1.0 - w2[two]) * h[two] + w2[two] * h2
        return h, R_w

    def conductance(self, m_vol, T_w, fp: FluidProperties, idx):
        """UA [W/K] per volume, fluid to the wall's mean temperature."""
        h, R_w = self.h(m_vol, T_w, fp, idx)
        return 1.0 / (1.0 / (h * self.A_vol) + R_w)


class BankConvection:
    """Heat transfer outside the tubes of a bank in cross flow, per section (module doc)."""

    def __init__(self, bank, n, m_reg=0.0, radiation=False, wall_emissivity=0.8,
                 beam_length=None, wall_resistance=True):  # fmt: skip
        self.bank, self.n = bank, n
        t = bank.tubes
        self.D_o = bank.D_o
        self.A_out_vol = bank.A_out / n
        self.A_o_vol = t.A_outer / n
        self.fin_share = bank.A_fin / bank.A_out if bank.A_out > 0 else 0.0
        self.m_reg = m_reg
        D_eff = bank.D_eff
        self.r_max = float(max_velocity(1.0, D_eff, bank.S_T, bank.S_L, bank.staggered))
        self.radiation = radiation
        self.eps_w = wall_emissivity
        self.L_m = bank.beam_length if beam_length is None else beam_length
        self.x_rad = None  # (x_H2O, x_CO2) mole fractions, from the medium (``check_medium``)
        self.wall = _WallHalf(t, n, "outer") if wall_resistance else None
        self.fin_metal = bank.fin_metal

    def check_medium(self, medium, owner):
        """With gas radiation: the gas must give its composition (H2O, CO2)."""
        if not self.radiation:
            return
        x = getattr(medium, "mole_fractions", None)
        if x is None:
            raise PlantError(
                f"component '{owner}': gas_radiation needs a gas mixture with H2O and CO2 "
                f"mole fractions (e.g. 'FlueGas'); the bank side's medium "
                f"{getattr(medium, 'label', medium)!r} has no composition"
            )
        self.x_rad = (float(x.get("H2O", 0.0)), float(x.get("CO2", 0.0)))

    def conductance(self, m_vol, T_w, fp: FluidProperties, idx):
        """UA [W/K] per section, gas to the wall's mean temperature."""
        bank = self.bank
        mr = np.sqrt(m_vol * m_vol + self.m_reg * self.m_reg)
        mu, k, cp = fp.mu[idx], fp.k[idx], fp.cp[idx]
        Re = mr / bank.A_front * self.r_max * self.D_o / mu
        Nu = nusselt_zukauskas(Re, mu * cp / k, bank.n_rows, bank.S_T, bank.S_L, bank.staggered)
        h = Nu * k / self.D_o
        if bank.finned and self.fin_metal is not None:
            eta = annular_fin_efficiency(
                h, self.fin_metal.conductivity(T_w), bank.fin_thickness, bank.r_1, bank.r_2
            )
            eta0 = 1.0 - self.fin_share * (1.0 - eta)
        else:
            eta0 = 1.0
        G_conv = eta0 * h * self.A_out_vol
        if self.radiation and self.x_rad is not None:
            Tg, p = fp.T[idx], fp.p[idx]
            eps_g = gas_emissivity(Tg, self.x_rad[0] * p, self.x_rad[1] * p, self.L_m)
            h_rad = 0.5 * (self.eps_w + 1.0) * SIGMA_SB * eps_g * (Tg + T_w) * (Tg * Tg + T_w * T_w)
            G_conv = G_conv + h_rad * self.A_o_vol
        R_w = self.wall.resistance(T_w) if self.wall is not None else 0.0
        return 1.0 / (1.0 / G_conv + R_w)


class ChannelLaws:
    """The correlation laws of one channel: friction (``TubeFriction`` or None: the
    lumped law) and heat (``TubeConvection``/``BankConvection`` or None: the lumped kA).
    ``bind`` evaluates the states' transport properties once per residual."""

    def __init__(self, n, friction=None, heat=None):
        self.n = n
        self.friction = friction
        self.heat = heat
        self.memos = None  # ``PropertyMemos`` of the medium last bound

    def bind(self, medium, p, h, T, rho, branch=None):
        """The laws at the states S_0..S_{n+1} (arrays of n + 2; ``branch``: the phase
        branch per state or None). The outlet node S_{n+1} enters no law: it is left
        out of the property call."""
        k = self.n + 1
        if self.memos is None or self.memos.medium is not medium:
            self.memos = PropertyMemos(medium)
        fp = FluidProperties(medium, p[:k], h[:k], T[:k], rho[:k],
                             None if branch is None else branch[:k], self.memos)  # fmt: skip
        return BoundLaws(self, fp)


class BoundLaws:
    """``ChannelLaws`` at one evaluation's states (``ChannelRows.residuals`` calls it)."""

    __slots__ = ("laws", "fp")

    def __init__(self, laws, fp):
        self.laws, self.fp = laws, fp

    def friction(self, mf, wp, wm):
        """dp [Pa] of faces 0..n-1 at flows mf, the upwind blend of the states beside."""
        n = self.laws.n
        f = self.laws.friction
        idx = np.concatenate((np.arange(n), np.arange(1, n + 1)))
        both = f.dp(np.concatenate((mf, mf)), self.fp, idx)
        return (wp * both[:n] + wm * both[n:]) / (wp + wm)

    def head_density(self, wp, wm):
        """Upwind density of the static head on faces 0..n-1 [kg/m3]."""
        n = self.laws.n
        rho = self.laws.friction.head_density(self.fp)
        return (wp * rho[:n] + wm * rho[1 : n + 1]) / (wp + wm)

    def conductance(self, m_in, m_out, T_wall):
        """UA [W/K] of volumes 0..n-1 at their mean flows and wall temperatures."""
        n = self.laws.n
        T_w = np.broadcast_to(np.asarray(T_wall, dtype=float), (n,))
        return self.laws.heat.conductance(0.5 * (m_in + m_out), T_w, self.fp, np.arange(1, n + 1))
