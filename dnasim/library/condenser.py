"""Condenser: a two-phase volume at saturation with a hotwell, cooled by a second stream
or by a given duty."""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.correlations.condensation import nusselt_horizontal_tube
from dnasim.library.submodels.tube_geometry import Tubes, tube_params, tubes_from_params
from dnasim.library.submodels.tube_laws import (
    FluidProperties,
    PropertyMemos,
    TubeConvection,
    TubeFriction,
)
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Output,
    Param,
    SignalPort,
    Switch,
    Variable,
)
from dnasim.model.physics import (
    M_REG_REL,
    G,
    energy_in,
    friction_dp,
    softplus,
    upwind_weight,
)

#: fixed-point steps of the film temperature difference of a condenser from geometry
#: (contraction below 1/4 per step: 12 steps leave < 1e-7 of it)
FILM_STEPS = 12

#: width [J/kg] of the smooth min(h_v, h') of the condensate drawn from the hotwell
H_MIN_WIDTH = 1.0


class Condenser(Component):
    """Steam condenser: one fully mixed volume V of water and steam in equilibrium
    (the shell), fed by exhaust steam, drained as condensate from its hotwell, and
    cooled by a cooling-water stream (ports cw_in, cw_out; a medium of its own) or
    by a given duty Q(t).

    Shell state p_v [Pa], h_v [J/kg] with M [kg], U [J]; saturation at p_v: h', h''
    [J/kg], rho', rho'' [kg/m3], T_sat [K]; quality x = (h_v - h')/(h'' - h');
    m_s [kg/s] steam in, m_c [kg/s] condensate out, Q [W] heat to the cooling water.

      mass             dM/dt = m_s - m_c
      energy           dU/dt = E_in(m_s, h_steam_node, h_v) - E_out(m_c, h_c) - Q
      density          M = V rho(p_v, h_v)
      internal_energy  U = M u(p_v, h_v)
      steam_pressure   p_steam_in = p_v                         (exhaust side: the volume)
      condensate       h_c = h' - softplus(h' - h_v)            (saturated liquid; the
                       volume's h when it is subcooled; width 1 J/kg)
      level            level = V_l / A_hotwell,  V_l = M (1 - x)/rho' (clipped to [0, V])  [m]
      hotwell_pressure p_condensate_out = p_v + rho' g level     (static head of the hotwell)
    Cooling water (cooling = "water"): counter-current against the condensing steam
    at T_sat, no storage on the water side, m_w [kg/s], cp_w at the water inlet:
      cw_friction      p_cw_in - p_cw_out = cw_k m_w sqrt(m_w^2 + m_reg^2)/rho_w
                       (cw_k from cw_dp_nominal at cw_m_nominal when not given)
      cw_outlet        h_w2 = h_w1 + eps cp_w (T_sat - T_w1),  eps = 1 - exp(-NTU),
                       NTU = UA / (cp_w sqrt(m_w^2 + m_reg^2))      (epsilon-NTU, C_r = 0)
      heat             Q = w(m_w) (h_w2 - h_w1)        (= m_w (h_w2 - h_w1) for m_w > m_eps)
    Given duty (cooling = "duty"):
      heat             Q = Q(t)
      heat_passed      dQ_passed/dt = Q      (the heat leaving the plant [J], for balances)

    Fluid leaves the shell through the steam port (reverse flow) with h_v and
    through the condensate port with h_c; cooling water leaves at cw_out with h_w2
    and, on reverse flow, at cw_in with the cw_out node's h (not heated). The
    energy flows balance exactly: d(U)/dt + (water side out - in) = E_steam - E_c.
    Signal outputs: p (shell pressure), level, Q, T_sat.

    Given start (start = "given"): pressure p0 and hotwell level level0 (default
    0.2 V / A_hotwell); the shell is saturated liquid below the level and saturated
    steam above it. A steady start fixes the level only through the hotwell's
    static head (weakly): prefer a given start or a level controller.

    From geometry (D given; ``dnasim.library.submodels.tube_geometry``, ``tube_laws``): the
    cooling water flows through n_tubes tubes of inner diameter D, length ``length``
    per pass, in n_passes passes (n_tubes/n_passes tubes per pass, the water's path
    n_passes length), wall wall_thickness of wall_material. UA is then computed each
    evaluation (UA and cw_k are not given) as the series of three resistances at the
    water's inlet state and the shell's saturation state:
      water     1/(h_w A_i), h_w by convection = "gnielinski" (VDI G1, default) or
                "dittus_boelter" at the water's flow per tube
      wall      ln(D_o/D)/(2 pi lambda n_tubes length), lambda at (T_sat + T_w1)/2
      shell     1/(h_c A_o), h_c = Nusselt's film condensation on horizontal tubes with
                Kern's row correction N^(-1/6) (``condensation.nusselt_horizontal_tube``;
                N = n_rows, default round(sqrt(n_tubes))), saturated liquid properties
                at p_v, at the film's temperature difference dT_f = dT_m R_c/R_total,
                dT_m = Q/UA the mean difference of the epsilon-NTU solution (a fixed
                point in dT_f, FILM_STEPS steps)
    and cw_friction is Darcy-Weisbach over the path (friction = "colebrook", default,
    or "haaland"), the upwind blend of the inlet's and the outlet's state. Outputs
    UA [W/K] and h_shell [W/(m2 K)]. A clean condenser's numbers: no fouling, no air.

    Physical limits, terminal switches on the liquid volume V_l = M (1 - x)/rho'
    (not clipped): the run stops at the located crossing with a message naming the
    condenser, its level and the time, when the hotwell runs dry (g = V_l/V, the
    condensate pump would draw steam) or the shell fills with water (g = (V - V_l)/V,
    the exhaust would be flooded); neither is modelled beyond.
    """

    PARAMS = (
        Param("V", "m3", doc="shell volume (steam space and hotwell)", min=0.0),
        Param("A_hotwell", "m2", doc="free surface of the hotwell", min=0.0),
        Param(
            "cooling",
            "1",
            "water",
            "cooling-water stream (ports cw_in, cw_out) or a given duty Q",
            kind="string",
            choices=("water", "duty"),
        ),
        Param("UA", "W/K", None, "overall heat transfer coefficient times area", min=0.0),
        Param("cw_k", "1/m4", None, "cooling-water friction coefficient", min=0.0),
        Param(
            "cw_dp_nominal",
            "delta_Pa",
            5e4,
            "cooling-water pressure drop at cw_m_nominal (when cw_k is not given)",
            min=0.0,
        ),
        Param("cw_m_nominal", "kg/s", 100.0, "typical cooling-water flow", min=0.0),
        Param("Q", "W", None, "heat removed (cooling = 'duty')", time_function=True),
        *tube_params("cooling-water tube length of one pass (geometry)"),
        Param("n_passes", "1", 1, "cooling-water passes (geometry)", min=1, kind="int"),
        Param(
            "n_rows",
            "1",
            None,
            "tube rows one above the other, for the condensate's row correction (geometry; "
            "default round(sqrt(n_tubes)))",
            min=1,
            kind="int",
        ),
        Param(
            "friction",
            "1",
            "colebrook",
            "cooling-water friction from geometry: colebrook or haaland",
            kind="string",
            choices=("colebrook", "haaland"),
        ),
        Param(
            "convection",
            "1",
            "gnielinski",
            "cooling-water heat transfer from geometry: gnielinski (VDI G1) or dittus_boelter",
            kind="string",
            choices=("gnielinski", "dittus_boelter"),
        ),
        Param("p0", "Pa", None, "initial shell pressure (given start)", min=0.0),
        Param("level0", "m", None, "initial hotwell level (given start)", min=0.0),
        Param("m_nominal", "kg/s", 1.0, "typical steam flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid of the shell (default: from the network)", kind="string"),
        Param(
            "cw_medium",
            "1",
            None,
            "cooling-water fluid (default: from the network)",
            kind="string",
        ),
    )
    FLUID_PORTS = (
        FluidPort("steam_in", "inlet", "m_s", "storage", "exhaust steam in (pressure = shell's)"),
        FluidPort("condensate_out", "outlet", "m_c", "storage", "condensate out of the hotwell"),
        FluidPort("cw_in", "inlet", "m_w", "resistance", "cooling water in (cooling = 'water')"),
        FluidPort("cw_out", "outlet", "m_w", "resistance", "cooling water out"),
    )
    SIGNAL_OUTPUTS = (
        SignalPort("p", "Pa", "shell pressure", variable="p_v"),
        SignalPort("level", "m", "hotwell level", variable="level"),
        SignalPort("Q", "W", "heat removed", variable="Q"),
        SignalPort("T_sat", "K", "saturation temperature of the shell", variable="T_sat"),
    )

    def setup(self):
        P = self.params
        name = f"component '{self.name}' (Condenser)"
        self.water = P["cooling"] == "water"
        self.tubes = tubes_from_params(self.name, P)
        if self.tubes is not None:
            if not self.water:
                raise PlantError(f"{name}: tubes (D, ...) carry cooling water: cooling = 'water'")
            for key, default in (("UA", None), ("cw_k", None), ("cw_dp_nominal", 5e4)):
                if P[key] != default:
                    raise PlantError(
                        f"{name}: '{key}' follows from the tubes' geometry (D, length, n_tubes, "
                        "...): leave it out, or leave out D for the lumped condenser"
                    )
        elif self.water and P["UA"] is None:
            raise PlantError(f"{name}: cooling = 'water' needs UA [W/K]")
        if not self.water and P["Q"] is None:
            raise PlantError(f"{name}: cooling = 'duty' needs the duty Q [W]")
        if P["level0"] is not None and not 0 <= P["level0"] * P["A_hotwell"] < P["V"]:
            raise PlantError(
                f"{name}: level0 = {P['level0']:g} m must lie from 0 up to below the shell's "
                f"height V/A_hotwell = {P['V'] / P['A_hotwell']:g} m"
            )
        mw = P["cw_m_nominal"]
        self.m_reg_w = M_REG_REL * mw
        self.cw_k = P["cw_k"]  # with cw_dp_nominal: k = dp_nom rho / m_nom^2, rho at run time
        if self.tubes is not None:
            t = self.tubes
            # the water's path: n_tubes/n_passes tubes in parallel, n_passes lengths long
            self.path = Tubes(t.D, P["n_passes"] * t.length, t.n_tubes / P["n_passes"],
                              t.wall_thickness, t.metal, t.roughness)  # fmt: skip
            self.cw_friction = TubeFriction(
                self.path, 1, P["friction"], "homogeneous", self.m_reg_w
            )
            self.cw_convection = TubeConvection(
                self.path, 1, P["convection"], m_reg=self.m_reg_w, wall_resistance=False
            )
            self.n_rows = P["n_rows"] or max(1, round(math.sqrt(t.n_tubes)))
            self._memos = {}

    def fluid_ports(self):
        eps = self.m_eps
        out = [
            FluidPort("steam_in", "inlet", "m_s", "storage", h_out="h_v", m_eps=eps),
            FluidPort("condensate_out", "outlet", "m_c", "storage", h_out="h_c", m_eps=eps),
        ]
        if self.water:
            eps_w = M_EPS_W * self.params["cw_m_nominal"]
            param = "cw_k" if self.cw_k is not None else "cw_dp_nominal"
            if self.tubes is not None:
                param = "D"
            out += [
                FluidPort(
                    "cw_in",
                    "inlet",
                    "m_w",
                    "resistance",
                    h_out="cw_out.h",
                    h_source=False,
                    pressure_param=param,
                    m_eps=eps_w,
                ),
                FluidPort(
                    "cw_out",
                    "outlet",
                    "m_w",
                    "resistance",
                    h_out="h_w2",
                    h_source=False,
                    pressure_param=param,
                    m_eps=eps_w,
                ),
            ]
        return out

    TWO_PHASE_GROUPS = ("shell",)  # steam condensing in its shell: a condensable medium

    def signal_range(self, name):
        """The hotwell level stays inside the shell: level < V/A_hotwell."""
        if name != "level":
            return None
        V, A = self.params["V"], self.params["A_hotwell"]
        return 0.0, V / A, "m", f"the shell's top, V/A_hotwell = {V / A:.6g} m"

    def medium_groups(self):
        groups = [("shell", "medium", ["steam_in", "condensate_out"])]
        if self.water:
            groups.append(("cooling", "cw_medium", ["cw_in", "cw_out"]))
        return groups

    @property
    def shell_medium(self):
        return self.port_media.get("steam_in", self.medium)

    @property
    def water_medium(self):
        return self.port_media.get("cw_in", self.medium)

    def variables(self):
        P = self.params
        mn, mw = P["m_nominal"], P["cw_m_nominal"]
        M_nom = P["V"] * 10.0
        out = [
            Variable("m_s", "kg/s", mn, doc="steam flow in"),
            Variable("m_c", "kg/s", mn, doc="condensate flow out"),
            Variable("M", "kg", M_nom, doc="mass in the shell", min=0.0),
            Variable("U", "J", M_nom * 1e5, doc="internal energy in the shell"),
            Variable("p_v", "Pa", 1e4, doc="shell pressure"),
            Variable("h_v", "J/kg", 1e5, doc="specific enthalpy of the shell's mixture"),
            Variable("h_c", "J/kg", 1e5, doc="enthalpy of the condensate drawn"),
            Variable("level", "m", 1.0, doc="hotwell level"),
            Variable("T_sat", "K", 300.0, doc="saturation temperature of the shell"),
            Variable("Q", "W", max(mn * 2e6, 1.0), doc="heat removed"),
        ]
        if self.water:
            out += [
                Variable("m_w", "kg/s", mw, doc="cooling-water flow"),
                Variable("h_w2", "J/kg", 1e5, doc="cooling-water outlet enthalpy"),
            ]
        else:
            out.append(
                Variable(
                    "Q_passed",
                    "J",
                    max(mn * 2e6, 1.0),
                    doc="heat removed, integral of Q dt",
                    accumulator=True,
                )
            )
        return out

    def equations(self):
        P = self.params
        shell = ("p_v", "h_v")
        eqs = [
            Equation(
                "mass",
                y=("m_s", "m_c"),
                yp=("M",),
                unit="kg/s",
                doc="dM/dt = m_s - m_c",
                residual=lambda t, x, xp: xp["M"] - (x["m_s"] - x["m_c"]),
            ),
            Equation(
                "energy",
                y=("m_s", "m_c", "steam_in.h", "h_v", "condensate_out.h", "h_c", "Q"),
                yp=("U",),
                unit="W",
                doc="dU/dt = E_in(m_s) - E_out(m_c) - Q",
                residual=lambda t, x, xp: xp["U"] - (x.work["E"] - x["Q"]),
            ),
            Equation(
                "density",
                y=("M",) + shell,
                unit="kg",
                doc="M = V rho(p_v, h_v)",
                residual=lambda t, x, xp: x["M"] - P["V"] * x.work["state"].rho,
            ),
            Equation(
                "internal_energy",
                y=("U", "M") + shell,
                unit="J",
                doc="U = M u(p_v, h_v)",
                residual=lambda t, x, xp: x["U"] - x["M"] * x.work["state"].u,
            ),
            Equation(
                "steam_pressure",
                y=("steam_in.p", "p_v"),
                unit="Pa",
                doc="p_steam_in = p_v",
                residual=lambda t, x, xp: x["steam_in.p"] - x["p_v"],
            ),
            Equation(
                "condensate",
                y=("h_c",) + shell,
                unit="J/kg",
                doc="h_c = h' - softplus(h' - h_v)",
                residual=lambda t, x, xp: (
                    x["h_c"]
                    - (x.work["hl"] - float(softplus(x.work["hl"] - x["h_v"], H_MIN_WIDTH)))
                ),
            ),
            Equation(
                "level",
                y=("level", "M") + shell,
                unit="m",
                doc="level = V_l/A_hotwell, V_l = M (1 - x)/rho'",
                residual=lambda t, x, xp: x["level"] - x.work["level"],
            ),
            Equation(
                "hotwell_pressure",
                y=("condensate_out.p", "level") + shell,
                unit="Pa",
                doc="p_condensate_out = p_v + rho' g level",
                residual=lambda t, x, xp: (
                    x["condensate_out.p"] - (x["p_v"] + x.work["rho_l"] * G * x["level"])
                ),
            ),
            Equation(
                "saturation",
                y=("T_sat", "p_v"),
                unit="K",
                doc="T_sat = T_s(p_v)",
                residual=lambda t, x, xp: x["T_sat"] - x.work["T_sat"],
            ),
        ]
        if self.water:
            cw = ("m_w", "cw_in.p", "cw_in.h", "cw_out.p", "cw_out.h")
            eqs += [
                Equation(
                    "cw_friction",
                    y=cw,
                    unit="Pa",
                    doc="p_cw_in - p_cw_out = cw_k m_w sqrt(m_w^2 + m_reg^2)/rho_w"
                    if self.tubes is None
                    else "p_cw_in - p_cw_out = dp_Darcy-Weisbach(m_w) over the tubes' path",
                    residual=lambda t, x, xp: x["cw_in.p"] - x["cw_out.p"] - x.work["cw_dp"],
                ),
                Equation(
                    "cw_outlet",
                    y=("h_w2", "T_sat") + cw + (("p_v",) if self.tubes is not None else ()),
                    unit="J/kg",
                    doc="h_w2 = h_w1 + eps cp_w (T_sat - T_w1)",
                    residual=lambda t, x, xp: (
                        x["h_w2"]
                        - (
                            x["cw_in.h"]
                            + self.water_heating(x["m_w"], x.work["s1"], x["T_sat"], x.work["UA"])
                        )
                    ),
                ),
                Equation(
                    "heat",
                    y=("Q", "m_w", "h_w2", "cw_in.h"),
                    unit="W",
                    doc="Q = w(m_w) (h_w2 - h_w1)",
                    residual=lambda t, x, xp: (
                        x["Q"]
                        - float(upwind_weight(x["m_w"], M_EPS_W * P["cw_m_nominal"]))
                        * (x["h_w2"] - x["cw_in.h"])
                    ),
                ),
            ]
        else:
            eqs += [
                Equation(
                    "heat",
                    y=("Q",),
                    unit="W",
                    doc="Q = Q(t)",
                    residual=lambda t, x, xp: x["Q"] - self.param_at("Q", t),
                ),
                Equation(
                    "heat_passed",
                    y=("Q",),
                    yp=("Q_passed",),
                    unit="W",
                    doc="dQ_passed/dt = Q",
                    residual=lambda t, x, xp: xp["Q_passed"] - x["Q"],
                ),
            ]
        return eqs

    # --------------------------------------------------------------- physics
    def saturation(self, p):
        """(h', h'', rho', rho'', T_sat) at the shell pressure p [Pa]."""
        medium = self.shell_medium
        hl, hv = medium.saturation_enthalpies(np.array([p]))
        hl, hv = float(hl[0]), float(hv[0])
        if not (math.isfinite(hl) and math.isfinite(hv)):
            from dnasim.media.errors import PropertyError

            raise PropertyError(
                medium.label, p, math.nan, "saturation", "condenser pressure above critical"
            )
        sl, sv = medium.state(p, hl), medium.state(p, hv)
        return hl, hv, sl.rho, sv.rho, sl.T

    def liquid_volume(self, M, h, hl, hv, rho_l):
        """V_l [m3] = M (1 - x)/rho', x = (h - h')/(h'' - h'), clipped to [0, V]."""
        x = (h - hl) / (hv - hl)
        V_l = M * (1.0 - x) / rho_l
        return min(max(V_l, 0.0), self.params["V"])

    def prepare(self, t, x, xp):
        """Shared per evaluation: the shell state, the saturation properties at p_v (one
        property call each), the port energy flows, the level; the cooling water's
        inlet and outlet states, its density upwind and cw_k."""
        P = self.params
        p, h = x["p_v"], x["h_v"]
        st = self.shell_medium.state(p, h)
        hl, hv, rho_l, _, T_sat = self.saturation(p)
        eps = self.m_eps
        E = energy_in(x["m_s"], x["steam_in.h"], h, eps) + energy_in(
            -x["m_c"], x["condensate_out.h"], x["h_c"], eps
        )
        work = {
            "state": st,
            "hl": hl,
            "rho_l": rho_l,
            "T_sat": T_sat,
            "E": float(E),
            "level": self.liquid_volume(x["M"], h, hl, hv, rho_l) / P["A_hotwell"],
        }
        if self.water:
            medium = self.water_medium
            s1 = medium.state(x["cw_in.p"], x["cw_in.h"])
            s2 = medium.state(x["cw_out.p"], x["cw_out.h"])
            if self.tubes is not None:
                UA, h_c = self.geometry_ua(p, T_sat, x["cw_in.p"], x["cw_in.h"], s1, x["m_w"])
                work.update(s1=s1, UA=UA, h_shell=h_c, cw_dp=self.cw_pressure_drop(x, s1, s2))
                return work
            k = self.cw_k
            if k is None:
                k = P["cw_dp_nominal"] * s1.rho / P["cw_m_nominal"] ** 2
            rho_w = s1.rho if x["m_w"] >= 0 else s2.rho
            work.update(s1=s1, UA=P["UA"], cw_dp=friction_dp(k, x["m_w"], rho_w, self.m_reg_w))
        return work

    def water_heating(self, mw, s1, T_sat, UA=None):
        """eps cp_w (T_sat - T_w1) [J/kg], the epsilon-NTU rise of the water's enthalpy
        (UA [W/K]: the parameter's, or from geometry)."""
        m_abs = math.sqrt(mw * mw + self.m_reg_w * self.m_reg_w)
        ntu = (self.params["UA"] if UA is None else UA) / (s1.cp * m_abs)
        return -math.expm1(-ntu) * s1.cp * (T_sat - s1.T)

    # ----------------------------------------------------------- geometry
    def _fluid(self, key, medium, p, h, s):
        """``tube_laws.FluidProperties`` of one water state (memo per port)."""
        memos = self._memos.get(key)
        if memos is None or memos.medium is not medium:
            memos = self._memos[key] = PropertyMemos(medium)
        return FluidProperties(
            medium, np.array([p]), np.array([h]), np.array([s.T]), np.array([s.rho]), None, memos
        )

    def geometry_ua(self, p_shell, T_sat, p_w, h_w, s1, m_w):
        """(UA [W/K], h_c [W/(m2 K)]) of the condenser from geometry (class doc) at the
        shell pressure p_shell [Pa] (T_sat [K]), the water's inlet state (p_w [Pa], h_w
        [J/kg], its state s1) and flow m_w [kg/s]."""
        t = self.tubes
        fp = self._fluid("cw_in", self.water_medium, p_w, h_w, s1)
        T_w = np.array([T_sat])
        h_w_, _ = self.cw_convection.h(np.array([m_w]), T_w, fp, np.array([0]))
        R_i = 1.0 / (float(h_w_[0]) * t.A_inner)
        T_wall = 0.5 * (T_sat + s1.T)
        lam = t.metal.conductivity(T_wall) if t.has_wall else 1.0
        R_w = float(t.conduction_resistance(lam)) if t.has_wall else 0.0
        sat = self.shell_medium.saturation_transport(np.array([p_shell]))
        rl, rv = float(sat["rho_l"][0]), float(sat["rho_v"][0])
        mul, kl, cpl = float(sat["mu_l"][0]), float(sat["k_l"][0]), float(sat["cp_l"][0])
        h_lv = float(sat["h_v"][0] - sat["h_l"][0])
        C = s1.cp * math.sqrt(m_w * m_w + self.m_reg_w * self.m_reg_w)
        dT_in = T_sat - s1.T
        A_o = t.A_outer
        dT_f = max(abs(dT_in), 1e-3) * 0.5
        for _ in range(FILM_STEPS):
            # |dT_f| regularised at 0.1 K: the film coefficient stays finite and smooth
            dT_r = math.sqrt(dT_f * dT_f + 0.01)
            h_c = float(nusselt_horizontal_tube(t.D_out, dT_r, rl, rv, mul, kl, cpl, h_lv,
                                                self.n_rows))  # fmt: skip
            R_c = 1.0 / (h_c * A_o)
            UA = 1.0 / (R_c + R_w + R_i)
            eps = -math.expm1(-UA / C)
            dT_m = eps * C * dT_in / UA  # Q/UA: the mean temperature difference
            dT_f = dT_m * R_c * UA
        return UA, h_c

    def cw_pressure_drop(self, x, s1, s2):
        """Darcy-Weisbach friction of the cooling water [Pa], the upwind blend of its
        inlet and outlet state (class doc)."""
        mw = x["m_w"]
        f1 = self._fluid("cw_in", self.water_medium, x["cw_in.p"], x["cw_in.h"], s1)
        f2 = self._fluid("cw_out", self.water_medium, x["cw_out.p"], x["cw_out.h"], s2)
        m = np.array([mw])
        dp1 = float(self.cw_friction.dp(m, f1, np.array([0]))[0])
        dp2 = float(self.cw_friction.dp(m, f2, np.array([0]))[0])
        eps = M_EPS_W * self.params["cw_m_nominal"]
        a, b = float(upwind_weight(mw, eps)), float(upwind_weight(-mw, eps))
        return (a * dp1 + b * dp2) / (a + b)

    # ----------------------------------------------------------------- limits
    def switches(self):
        """Terminal switches at the hotwell's limits (class doc): ``hotwell_dry`` and
        ``full``, on the unclipped liquid volume V_l [m3] relative to V."""
        P = self.params
        V, A = P["V"], P["A_hotwell"]
        last: dict = {}

        def liquid(x):
            hl, hv, rho_l, _, _ = self.saturation(x["p_v"])
            V_l = x["M"] * (1.0 - (x["h_v"] - hl) / (hv - hl)) / rho_l
            last.update(p=x["p_v"], V_l=V_l)
            return V_l

        def where(t):
            V_l = last.get("V_l", math.nan)
            V_l = 0.0 if abs(V_l) < 1e-9 * V else V if abs(V_l - V) < 1e-9 * V else V_l
            return (
                f"at t = {t:.6g} s (shell pressure {last.get('p', math.nan) / 1e5:.6g} bar, "
                f"water V_l = {V_l:.6g} m3 of V = {V:g} m3, level {V_l / A:.4g} m)"
            )

        head = f"condenser '{self.name}' (Condenser)"

        def dry_message(t):
            return (
                f"{head}: the hotwell ran dry {where(t)}; the condensate drawn exceeds the "
                "steam condensed: check the condensate pump and its level control"
            )

        def full_message(t):
            return (
                f"{head} is full of water {where(t)}: the condensate drawn falls short of "
                "the steam condensed: check the condensate pump and its level control (a "
                "flooded condenser is not modelled)"
            )

        return [
            Switch(
                "hotwell_dry",
                lambda t, x, xp: liquid(x) / V,
                -1,
                terminal=True,
                message=dry_message,
                doc="the hotwell's water V_l reaches 0",
            ),
            Switch(
                "full",
                lambda t, x, xp: (V - liquid(x)) / V,
                -1,
                terminal=True,
                message=full_message,
                doc="the water V_l fills the shell volume V",
            ),
        ]

    def outputs(self):
        out = [
            Output("x", "1", "quality of the shell's mixture"),
            Output("M_total", "kg", "mass in the shell"),
            Output("U_total", "J", "internal energy in the shell"),
        ]
        if self.tubes is not None:
            out += [
                Output("UA", "W/K", "overall heat transfer coefficient times area (geometry)"),
                Output("h_shell", "W/(m2.K)", "film condensation coefficient (geometry)"),
            ]
        return out

    def output_values(self, t, x, xp):
        hl, hv, _, _, T_sat = self.saturation(x["p_v"])
        out = [(x["h_v"] - hl) / (hv - hl), x["M"], x["U"]]
        if self.tubes is not None:
            s1 = self.water_medium.state(x["cw_in.p"], x["cw_in.h"])
            out += list(self.geometry_ua(x["p_v"], T_sat, x["cw_in.p"], x["cw_in.h"], s1,
                                         x["m_w"]))  # fmt: skip
        return out

    # ---------------------------------------------------------- initialisation
    def design_values(self, t0, x):
        """The steam flow condensed and the heat removed from it (duty -Q) [W]."""
        return {"m": x["m_s"], "duty": -x["Q"]}

    def guess_nodes(self, t0):
        p0 = self.params["p0"]
        if p0 is None:
            return {}
        hl, _ = self.shell_medium.saturation_enthalpies(np.array([p0]))
        return {"steam_in": (p0, None), "condensate_out": (p0, float(hl[0]))}

    def initial_guess(self, t0, x):
        P = self.params
        p = P["p0"] if P["p0"] is not None else x["steam_in.p"]
        hl, hv, rho_l, rho_v, T_sat = self.saturation(p)
        level = P["level0"] if P["level0"] is not None else 0.2 * P["V"] / P["A_hotwell"]
        V_l = min(level * P["A_hotwell"], P["V"])
        M = rho_l * V_l + rho_v * (P["V"] - V_l)
        h = (rho_l * V_l * hl + rho_v * (P["V"] - V_l) * hv) / M
        x["p_v"], x["h_v"], x["M"] = p, h, M
        x["U"] = M * self.shell_medium.state(p, h).u
        x["h_c"] = hl
        x["level"] = V_l / P["A_hotwell"]
        x["T_sat"] = T_sat
        x["steam_in.p"] = p
        x["condensate_out.p"] = p + rho_l * G * x["level"]
        x["condensate_out.h"] = hl
        mn = P["m_nominal"]
        x["m_s"] = x["m_c"] = mn
        if self.water:
            x["m_w"] = P["cw_m_nominal"]
            s1 = self.water_medium.state(x["cw_in.p"], x["cw_in.h"])
            UA = None
            if self.tubes is not None:
                UA, _ = self.geometry_ua(p, T_sat, x["cw_in.p"], x["cw_in.h"], s1, x["m_w"])
            x["h_w2"] = x["cw_in.h"] + self.water_heating(x["m_w"], s1, T_sat, UA)
            x["Q"] = x["m_w"] * (x["h_w2"] - x["cw_in.h"])
        else:
            x["Q"] = self.param_at("Q", t0)
            x["Q_passed"] = 0.0


#: upwind band of the cooling-water ports, relative to cw_m_nominal
M_EPS_W = 1e-3
