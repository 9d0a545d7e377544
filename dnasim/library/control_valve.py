"""ControlValve (IEC 60534-2-1 flow equations) and CheckValve."""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.library.submodels.valve_laws import (
    EXPONENT_MODELS,
    critical_pressure_ratio,
    inlet_exponent,
    nozzle_factor,
    omega_critical_ratio,
    omega_factor,
    omega_subcooled_critical_ratio,
    omega_subcooled_factor,
)
from dnasim.media.isentropic import isentropic_exponent
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Output,
    Param,
    SignalPort,
    Variable,
    flow_through_ports,
)
from dnasim.model.physics import (
    M_EPS_REL,
    fixed_value,
    opening_band,
    softplus,
    upwind_mean,
    valve_flow,
)

#: Kv [m3/h] -> K [m2] in m = K sqrt(rho dp): Kv is the water flow in m3/h at
#: dp = 1 bar and rho_0 = 1000 kg/m3, so K = Kv / 3600 / sqrt(1e5 / 1000) [m2]
KV_TO_K = 1.0 / 36000.0
#: Kv = 0.865 Cv (IEC 60534-1; Cv in US gallons per minute at 1 psi)
KV_PER_CV = 0.865
#: width of the smooth min at the choking limit, relative to the limit
CHOKE_REG_REL = 1e-2
#: equal-percentage characteristic: linear to 0 below this opening
EQP_DELTA = 0.01


def smooth_step(s):
    """C1 step 0 (s <= 0) -> 1 (s >= 1): 3 s^2 - 2 s^3 in between."""
    s = min(max(s, 0.0), 1.0)
    return s * s * (3.0 - 2.0 * s)


def odd_limit(d, limit, width):
    """Smooth odd clip of d to [-limit, limit]:
    d - softplus(d - limit) + softplus(-d - limit) (widths ``width``); equals d for
    |d| << limit and +-limit for |d| >> limit (to width e^(-|d|-limit)/width)."""
    return d - float(softplus(d - limit, width)) + float(softplus(-d - limit, width))


def vapour_pressure(medium, T):
    """(p_v [Pa], p_c [Pa]): vapour pressure at T [K] (p_c above T_c) and the critical
    pressure, asked of the medium (``Medium.p_sat``, ``Medium.critical_point``)."""
    return medium.p_sat(T), medium.critical_point[1]


def hem_omega(medium, st):
    """The omega method at the upstream state ``st`` (``valve_laws``): (phi, eps_c) with
    phi(eps) [-] the factor at eps = dp/p_1 and eps_c = 1 - eta_c [-] its choking limit.

    A subcooled liquid (a condensable medium below its critical pressure, h < h'(p)):
    p_s = p_sat(T_1), eta_s = p_s/p_1, omega_s = 1/kappa_s of the saturated liquid
    (equilibrium, dome side) at p_s. Otherwise (two-phase, vapour, gas, supercritical):
    omega = 1/kappa_s of the state itself, smoothed across the dew line
    (``valve_laws.inlet_exponent``)."""
    p1 = st.p
    if getattr(medium, "condensable", False):
        h_l, _ = medium.saturation_enthalpies(np.array([p1]))
        h_l = float(h_l[0])
        if math.isfinite(h_l) and st.h < h_l:
            p_s, _ = vapour_pressure(medium, st.T)
            eta_s = min(p_s / p1, 1.0)
            hs, _ = medium.saturation_enthalpies(np.array([p_s]))
            omega_s = 1.0 / isentropic_exponent(medium.state(p_s, float(hs[0])))
            eta_c = omega_subcooled_critical_ratio(omega_s, eta_s)
            return (lambda e: omega_subcooled_factor(e, omega_s, eta_s)), 1.0 - eta_c
    omega = 1.0 / inlet_exponent(medium, st, "isentropic")
    eta_c = omega_critical_ratio(omega)
    return (lambda e: omega_factor(e, omega)), 1.0 - eta_c


class ControlValve(Component):
    """Control valve after IEC 60534-2-1, liquids and gases/steam, either flow direction.

    Symbols: m [kg/s] mass flow (inlet -> outlet positive); dp = p_in - p_out [Pa];
    subscript 1 the upstream side (the inlet for dp > 0, the outlet for dp < 0:
    reverse flow is the same law with the ports exchanged; rho_1, p_1 are smooth
    upwind means by dp over the band dp_reg); z [-] the opening (parameter
    ``opening`` or signal ``z``); f(z) [-] the characteristic; K [m2] the full-open
    flow coefficient.

      flow (IEC)    m = K z_e Y sqrt(rho_1) g(dp_e),  g(d) = d / (d^2 + dp_reg^2)^(1/4)
                    (= K z_e Y sqrt(rho_1 dp_e) for dp_e >> dp_reg)               [kg/s]
      liquid        Y = 1,  dp_e = clip(dp, dp_max),  dp_max = F_L^2 (p_1 - F_F p_v)
                    F_F = 0.96 - 0.28 sqrt(p_v/p_c), p_v = p_sat(T_1)   (choked flow)
      gas, steam    x = dp/p_1,  x_e = clip(x, F_g x_T),  F_g = gamma/1.4,
                    Y = 1 - |x_e|/(3 F_g x_T),  dp_e = x_e p_1          (choked at x >= F_g x_T)
      flow (linear) m = C_lin z_e dp          (law = "linear": laminar)              [kg/s]
      flow function m = K z_e phi sqrt(rho_1) g(eps_e p_1)    (law = "flow_function")
                    gas: eps = dp/p_1, eps_e = clip(eps, 1 - r_c), phi = nozzle_factor
                    (the isentropic nozzle, ClaRa's Quadratic_FlowFunction: m = K_d A
                    Psi(p_2/p_1, gamma) sqrt(2 rho_1 p_1), choked at r_c =
                    (2/(gamma + 1))^(gamma/(gamma - 1))); liquid: phi = 1 (Bernoulli)
      HEM           m = K z_e phi sqrt(rho_1) g(eps_e p_1)    (law = "hem", drains)
                    the omega method (homogeneous equilibrium flashing flow, API 520
                    Annex C) for every inlet state: subcooled liquid (flashing at the
                    throat when p_2 < p_sat(T_1)), two-phase mixture (rho_1 the
                    homogeneous density, omega = 1/kappa_s of the equilibrium mixture),
                    steam or gas (omega = 1/kappa_s); choked at eps_c = 1 - eta_c
      z_e           = leakage + (1 - leakage) f(z)
      f(z)          linear z; equal_percentage R^(z - 1) (for z < 0.01 linear to 0,
                    for z > 1 its tangent);
                    quick_opening 1 - (1 - z)^2; table: PCHIP through (char_z, char_f)

    clip(d, L) = d - softplus(d - L) + softplus(-d - L), width 1e-2 L: a smooth odd
    limit, exact to 1e-13 beyond 1.3 L. The valve's coefficient: ``Kv`` [m3/h]
    (K = Kv/36000 m2), ``Cv`` [US gpm/psi^0.5] (Kv = 0.865 Cv), or the nominal
    point (``m_nominal``, ``dp_nominal``, ``rho_nominal``, and for gas ``p_nominal``):
    K = m_nom / (Y_nom sqrt(rho_nom dp_nom)) so that the open valve passes m_nom
    there (Y_nom with the constant gamma; 1 for the HEM law), or a flow area ``A``
    [m2] with discharge coefficient ``K_d`` (K = sqrt(2) K_d A: K sqrt(rho dp) =
    K_d A sqrt(2 rho dp); ClaRa's zeta [1/m4] is 1/(K_d A)^2). For law = "linear":
    ``C_lin`` [kg/(s Pa)] or C_lin = m_nom/dp_nom. The laws of
    ``dnasim.library.submodels.valve_laws`` (equations, sources) give phi.

    Service: "liquid" or "gas" (steam is "gas"); by default a condensable medium
    is "liquid" when the upstream state is subcooled liquid and "gas" otherwise
    (the law changes at the saturation line: a kink), a gas medium "gas". The HEM
    law covers every phase itself (no ``service``).

    gamma, the exponent of the gas laws, by ``gamma_model``: "fixed" (default) the
    parameter ``gamma``, else cp/(cp - R) for an ideal-gas medium, 1.3 otherwise (the
    usual value for superheated steam; dry saturated steam: 1.135); "isentropic"
    kappa_s = -(v/p)(dp/dv)_s of the real fluid at the upstream state (IF97 steam:
    1.24 to 1.33 superheated, 1.14 dry saturated at 10 bar, 1.04 at x = 0.5; an
    ideal gas: cp/(cp - R) at its temperature); "cp_cv" the ratio cp/cv of the
    upstream state (IEC 60534-2-1's "specific heat ratio", ClaRa's
    GenericValveVLE_L1; wet steam and liquid: the dew-line value), which near
    saturation at high pressure is far from the expansion's exponent (100 bar: 2.30);
    see ``valve_laws.inlet_exponent``.

    Throttling is isenthalpic both ways (fluid leaves through the outlet with the
    inlet node's h and vice versa), the flow is odd in dp with a finite slope at
    dp = 0 (index 1 at zero flow), and a closed valve keeps its leakage. A signal
    z is used as given, not clipped (as in ``Valve``): limit the driving
    controller's output to [0, 1]. The upwind band at both ports narrows with the
    opening, m_eps = 1e-3 m_nominal sqrt(z_e^2 + 1e-6) [kg/s]
    (``physics.opening_band``; a variable when the opening changes): a closed
    valve exchanges nothing but its leakage
    between its nodes, so a stagnant node behind it (a pump's discharge against a
    shut feed valve) keeps the state of the side it receives fluid from.
    """

    PARAMS = (
        Param("Kv", "1", None, "flow coefficient Kv [m3/h at 1 bar, water], full open", min=0.0),
        Param("Cv", "1", None, "flow coefficient Cv [US gpm at 1 psi], full open", min=0.0),
        Param("dp_nominal", "delta_Pa", None, "pressure drop of the nominal point", min=0.0),
        Param("rho_nominal", "kg/m3", None, "inlet density of the nominal point", min=0.0),
        Param("p_nominal", "Pa", None, "inlet pressure of the nominal point (gas)", min=0.0),
        Param("C_lin", "kg/(s.Pa)", None, "flow coefficient of the linear law", min=0.0),
        Param("A", "m2", None, "flow area (with K_d, instead of Kv: K = sqrt(2) K_d A)", min=0.0),
        Param("K_d", "1", 1.0, "discharge coefficient of the flow area A", min=0.0, max=1.0),
        Param(
            "law",
            "1",
            "iec",
            "flow law: IEC 60534 (turbulent), linear (laminar), flow_function (isentropic "
            "nozzle, ClaRa) or hem (flashing two-phase, omega method: drains)",
            kind="string",
            choices=("iec", "linear", "flow_function", "hem"),
        ),
        Param(
            "service",
            "1",
            None,
            "liquid or gas/steam equations (default: from the upstream state)",
            kind="string",
            choices=("liquid", "gas"),
        ),
        Param(
            "characteristic",
            "1",
            "linear",
            "inherent characteristic f(z)",
            kind="string",
            choices=("linear", "equal_percentage", "quick_opening", "table"),
        ),
        Param("rangeability", "1", 50.0, "R of the equal-percentage characteristic", min=1.0),
        Param("char_z", "1", None, "openings [-] of the tabulated characteristic", kind="array"),
        Param("char_f", "1", None, "relative flow coefficients f [-] of the table", kind="array"),
        Param("F_L", "1", 0.9, "liquid pressure recovery factor", min=0.0, max=1.0),
        Param("x_T", "1", 0.7, "pressure differential ratio factor at choked flow", min=0.0),
        Param("gamma", "1", None, "isentropic exponent of the gas (default: see above)", min=1.0),
        Param(
            "gamma_model",
            "1",
            "fixed",
            "exponent of the gas laws: fixed (gamma), isentropic (kappa_s of the upstream "
            "state) or cp_cv (its cp/cv)",
            kind="string",
            choices=EXPONENT_MODELS,
        ),
        Param(
            "opening",
            "1",
            None,
            "fixed opening z in [0, 1] (otherwise from the signal input 'z')",
            min=0.0,
            max=1.0,
            time_function=True,
        ),
        Param(
            "leakage",
            "1",
            1e-6,
            "flow coefficient of the closed valve, fraction of K",
            min=0.0,
            max=1.0,
        ),
        Param(
            "dp_reg", "delta_Pa", 10.0, "regularisation pressure difference near dp = 0", min=0.0
        ),
        Param("m_nominal", "kg/s", 1.0, "nominal mass flow (scales; nominal point)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", "resistance", "fluid in (design direction)"),
        FluidPort("outlet", "outlet", "m", "resistance", "fluid out"),
    )
    SIGNAL_INPUTS = (SignalPort("z", "1", "opening (when the parameter 'opening' is not given)"),)
    #: False in subclasses whose opening is not a parameter or signal (CheckValve)
    HAS_OPENING = True

    # ------------------------------------------------------------------ set-up
    def setup(self):
        P = self.params
        name = f"component '{self.name}' ({type(self).__name__})"
        self.opening_from_signal = self.HAS_OPENING and P["opening"] is None
        #: the band follows an opening that changes (signal or time function) in the
        #: variable m_eps; a fixed opening's band is a number (a check valve: none)
        self.band_variable = self.HAS_OPENING and (
            self.opening_from_signal or not fixed_value(P["opening"])
        )
        given = [k for k in ("Kv", "Cv", "A", "dp_nominal") if P[k] is not None]
        if P["law"] == "linear":
            if P["C_lin"] is None and P["dp_nominal"] is None:
                raise PlantError(
                    f"{name}: the linear law needs C_lin, or dp_nominal (and m_nominal)"
                )
        elif len(given) != 1:
            raise PlantError(
                f"{name}: give exactly one of Kv, Cv, A (with K_d) or the nominal point "
                f"(dp_nominal with rho_nominal and m_nominal)"
                f"{'; got ' + ', '.join(given) if given else ''}"
            )
        elif P["dp_nominal"] is not None and P["rho_nominal"] is None:
            raise PlantError(f"{name}: the nominal point needs rho_nominal with dp_nominal")
        if P["gamma_model"] != "fixed" and P["gamma"] is not None:
            raise PlantError(
                f"{name}: gamma = {P['gamma']} is a constant exponent, but gamma_model = "
                f"'{P['gamma_model']}' takes it from the medium; give one of them"
            )
        if P["law"] == "hem" and P["service"] is not None:
            raise PlantError(
                f"{name}: law 'hem' covers liquid, two-phase and gas inlets itself; "
                "'service' applies to the iec and flow_function laws"
            )
        self._table = None
        if P["characteristic"] == "table":
            if P["char_z"] is None or P["char_f"] is None:
                raise PlantError(f"{name}: characteristic 'table' needs char_z and char_f")
            z, f = np.asarray(P["char_z"]), np.asarray(P["char_f"])
            if z.size != f.size or z.size < 2 or np.any(np.diff(z) <= 0):
                raise PlantError(
                    f"{name}: char_z must rise strictly and have as many (>= 2) entries as char_f"
                )
            from scipy.interpolate import PchipInterpolator

            self._table = PchipInterpolator(z, f, extrapolate=True)
        self._K = None

    def fluid_ports(self):
        if self.band_variable:
            return flow_through_ports(self.m_eps, "inlet.h", band="m_eps")
        if not self.HAS_OPENING:  # a check valve: the full band (see CheckValve)
            return flow_through_ports(self.m_eps, "inlet.h")
        band = opening_band(self.m_eps, self.effective_opening(0.0, {}))
        return flow_through_ports(self.m_eps, "inlet.h", band=band)

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.opening_from_signal else []

    def variables(self):
        out = [Variable("m", "kg/s", self.params["m_nominal"], doc="mass flow")]
        if self.band_variable:
            out.append(
                Variable(
                    "m_eps",
                    "kg/s",
                    # scale m_nominal: the band matters only where the flow is within
                    # it; on its own 1e-3 m_nominal scale it held Newton's convergence
                    # test to what the node pressures do not resolve (a band following
                    # a check valve's dp stalled Newton at dp ~ 1e-3 Pa)
                    self.params["m_nominal"],
                    doc="upwind band at the ports, 1e-3 m_nominal z_e (physics.opening_band)",
                )
            )
        return out

    #: what the opening depends on (the band equation's dependencies besides m_eps)
    def _opening_reads(self):
        return ("z",) if self.opening_from_signal else ()

    def equations(self):
        dep = ("m", "inlet.p", "inlet.h", "outlet.p", "outlet.h")
        dep += ("z",) if self.opening_from_signal else ()
        out = [
            Equation(
                "flow",
                y=dep,
                unit="kg/s",
                doc="m = K z_e Y sqrt(rho_1 dp_e) (IEC 60534), K z_e phi sqrt(rho_1 dp_e) "
                "(flow_function, hem) or C_lin z_e dp",
                residual=lambda t, x, xp: x["m"] - self.flow(t, x),
            )
        ]
        if self.band_variable:
            out.append(
                Equation(
                    "band",
                    y=("m_eps",) + self._opening_reads(),
                    unit="kg/s",
                    doc="m_eps = 1e-3 m_nominal sqrt(z_e^2 + 1e-6)",
                    residual=lambda t, x, xp: x["m_eps"] - self.band(t, x),
                )
            )
        return out

    def band(self, t, x) -> float:
        """m_eps [kg/s] at the ports: ``physics.opening_band`` of the effective opening."""
        return opening_band(self.m_eps, self.effective_opening(t, x))

    def outputs(self):
        return [
            Output("z_e", "1", "effective relative flow coefficient leakage + (1-leakage) f(z)")
        ]

    def output_values(self, t, x, xp):
        return [self.effective_opening(t, x)]

    # --------------------------------------------------------------- physics
    def characteristic(self, z):
        """f(z) [-] of the inherent characteristic."""
        kind = self.params["characteristic"]
        if kind == "linear":
            return z
        if kind == "quick_opening":
            return 1.0 - (1.0 - z) ** 2
        if kind == "equal_percentage":
            R = self.params["rangeability"]
            if z < EQP_DELTA:
                return z / EQP_DELTA * R ** (EQP_DELTA - 1.0)
            if z > 1.0:  # beyond full opening (an iterate, or z_max > 1): the tangent at
                return 1.0 + math.log(R) * (z - 1.0)  # z = 1, so R**(z-1) cannot overflow
            return R ** (z - 1.0)
        return float(self._table(z))

    def opening(self, t, x):
        """z [-]."""
        return x["z"] if self.opening_from_signal else self.param_at("opening", t)

    def effective_opening(self, t, x):
        """z_e = leakage + (1 - leakage) f(z) [-]."""
        leak = self.params["leakage"]
        return leak + (1.0 - leak) * self.characteristic(self.opening(t, x))

    def service(self, state1):
        """ "liquid" or "gas" for the upstream state."""
        if self.params["service"] is not None:
            return self.params["service"]
        if not getattr(self.medium, "condensable", False):
            return "gas"
        hl, _ = self.medium.saturation_enthalpies(np.array([state1.p]))
        return "liquid" if np.isfinite(hl[0]) and state1.h < hl[0] else "gas"

    def gamma(self):
        """The constant exponent [-] (gamma_model "fixed"): the parameter gamma, else
        cp/(cp - R) of an ideal-gas medium, 1.3 otherwise."""
        if self.params["gamma"] is not None:
            return self.params["gamma"]
        R, cp = getattr(self.medium, "R", None), getattr(self.medium, "cp", None)
        if isinstance(R, float) and isinstance(cp, float) and cp > R:
            return cp / (cp - R)
        return 1.3

    def exponent(self, state1):
        """gamma [-] of the gas laws at the upstream state ``state1`` (``gamma_model``)."""
        model = self.params["gamma_model"]
        if model == "fixed":
            return self.gamma()
        return inlet_exponent(self.medium, state1, model)

    @property
    def K(self) -> float:
        """Full-open coefficient K [m2] (IEC law)."""
        if self._K is None:
            P = self.params
            if P["Kv"] is not None:
                self._K = P["Kv"] * KV_TO_K
            elif P["Cv"] is not None:
                self._K = P["Cv"] * KV_PER_CV * KV_TO_K
            elif P["A"] is not None:
                self._K = math.sqrt(2.0) * P["K_d"] * P["A"]
            else:
                Y = 1.0
                gas = P["p_nominal"] is not None and P["service"] != "liquid"
                if gas and P["law"] == "iec":
                    Fg_xT = self.gamma() / 1.4 * P["x_T"]
                    x = min(P["dp_nominal"] / P["p_nominal"], Fg_xT)
                    Y = 1.0 - x / (3.0 * Fg_xT)
                elif gas and P["law"] == "flow_function":
                    g = self.gamma()
                    x = min(P["dp_nominal"] / P["p_nominal"], 1.0 - critical_pressure_ratio(g))
                    Y = nozzle_factor(x, g) * math.sqrt(x * P["p_nominal"] / P["dp_nominal"])
                self._K = P["m_nominal"] / (Y * math.sqrt(P["rho_nominal"] * P["dp_nominal"]))
        return self._K

    def flow(self, t, x):
        """m [kg/s] at the node states in x."""
        P = self.params
        dp = x["inlet.p"] - x["outlet.p"]
        z_e = self.effective_opening(t, x)
        if P["law"] == "linear":
            C = P["C_lin"] if P["C_lin"] is not None else P["m_nominal"] / P["dp_nominal"]
            return C * z_e * dp
        if P["law"] == "flow_function":
            return self.K * z_e * self.flow_function_factor(x, dp)
        if P["law"] == "hem":
            return self.K * z_e * self.hem_factor(x, dp)
        return self.K * z_e * self.iec_factor(x, dp)

    def _upstream(self, x, dp):
        """(inlet state, outlet state, rho_1 [kg/m3], p_1 [Pa]): rho_1 and p_1 smooth
        upwind means by dp over dp_reg."""
        s_in = self.medium.state(x["inlet.p"], x["inlet.h"])
        s_out = self.medium.state(x["outlet.p"], x["outlet.h"])
        reg = self.params["dp_reg"]
        rho1 = float(upwind_mean(dp, s_in.rho, s_out.rho, reg))
        p1 = float(upwind_mean(dp, s_in.p, s_out.p, reg))
        return s_in, s_out, rho1, p1

    def flow_function_factor(self, x, dp):
        """phi sqrt(rho_1) g(eps_e p_1) [sqrt(kg/m3) Pa^0.5]: the flow per unit K z_e of
        the nozzle flow function (gas), or Bernoulli's sqrt(rho_1) g(dp) (liquid)."""
        reg = self.params["dp_reg"]
        s_in, s_out, rho1, p1 = self._upstream(x, dp)
        up = s_in if dp >= 0 else s_out
        if self.service(up) == "liquid":
            return math.sqrt(rho1) * valve_flow(1.0, 1.0, dp, reg)
        kappa = self.exponent(up)
        eps_c = 1.0 - critical_pressure_ratio(kappa)
        eps = odd_limit(dp / p1, eps_c, CHOKE_REG_REL * eps_c)
        return nozzle_factor(eps, kappa) * math.sqrt(rho1) * valve_flow(1.0, 1.0, eps * p1, reg)

    def hem_factor(self, x, dp):
        """phi sqrt(rho_1) g(eps_e p_1) [sqrt(kg/m3) Pa^0.5]: the flow per unit K z_e of
        the omega method (HEM) from the upstream state (``hem_omega``)."""
        reg = self.params["dp_reg"]
        s_in, s_out, rho1, p1 = self._upstream(x, dp)
        up = s_in if dp >= 0 else s_out
        phi, eps_c = hem_omega(self.medium, up)
        eps = odd_limit(dp / p1, eps_c, CHOKE_REG_REL * eps_c) if eps_c < 1.0 else dp / p1
        return phi(eps) * math.sqrt(rho1) * valve_flow(1.0, 1.0, eps * p1, reg)

    def iec_factor(self, x, dp):
        """Y sqrt(rho_1) g(dp_e) [sqrt(kg/m3) Pa^0.5]: the flow per unit K z_e."""
        P = self.params
        medium = self.medium
        s_in = medium.state(x["inlet.p"], x["inlet.h"])
        s_out = medium.state(x["outlet.p"], x["outlet.h"])
        reg = P["dp_reg"]
        rho1 = float(upwind_mean(dp, s_in.rho, s_out.rho, reg))
        p1 = float(upwind_mean(dp, s_in.p, s_out.p, reg))
        up = s_in if dp >= 0 else s_out
        if self.service(up) == "liquid":
            T1 = float(upwind_mean(dp, s_in.T, s_out.T, reg))
            p_v, p_c = vapour_pressure(medium, T1)
            F_F = 0.96 - 0.28 * math.sqrt(min(p_v / p_c, 1.0))
            dp_max = max(P["F_L"] ** 2 * (p1 - F_F * p_v), 1e-6 * p1)
            dp_e = odd_limit(dp, dp_max, CHOKE_REG_REL * dp_max)
            Y = 1.0
        else:
            Fg_xT = self.exponent(up) / 1.4 * P["x_T"]
            x_e = odd_limit(dp / p1, Fg_xT, CHOKE_REG_REL * Fg_xT)
            Y = 1.0 - abs(x_e) / (3.0 * Fg_xT)
            dp_e = x_e * p1
        return Y * math.sqrt(rho1) * valve_flow(1.0, 1.0, dp_e, reg)

    def design_values(self, t0, x):
        return {"m": x["m"], "opening": self.opening(t0, x)}

    def initial_guess(self, t0, x):
        try:
            x["m"] = self.flow(t0, x) if not self.opening_from_signal else 0.0
        except Exception:
            x["m"] = self.params["m_nominal"]
        if self.opening_from_signal:
            x["m"] = 0.5 * self.params["m_nominal"]
        if self.band_variable:
            try:
                x["m_eps"] = self.band(t0, x)
            except Exception:
                x["m_eps"] = self.m_eps


class CheckValve(ControlValve):
    """Check (non-return) valve: the IEC 60534 law of ``ControlValve`` with an
    opening set by the pressure difference instead of a signal.

      z   = smooth_step(dp / dp_open),  smooth_step(s) = 3 s^2 - 2 s^3 on [0, 1]   [-]
      z_e = leakage + (1 - leakage) z          (f = linear)
      m   = K z_e Y sqrt(rho_1) g(dp_e)      (as ControlValve; dp = p_in - p_out)

    Forward flow (dp >= dp_open): the full-open valve. Reverse pressure
    difference: the valve is shut and passes its leakage (default 1e-6 of the open
    flow, in the reverse direction), so the node pressures stay determined and
    the DAE index 1. dp_open [Pa] is the pressure difference at which the valve
    is fully open (its cracking band). Its upwind band is the full m_eps =
    1e-3 m_nominal at any opening (not ``ControlValve``'s narrowing band): a check
    valve shut in series with a shut control valve then still ties the node
    between them to the pump's side (tests/field/feed_line_level_control.toml);
    with both bands narrowed that node had no regular mixing equation at Newton
    iterates whose small flows leave it, and the run stopped.
    """

    HAS_OPENING = False
    PARAMS = tuple(
        p
        for p in ControlValve.PARAMS
        if p.name not in ("opening", "characteristic", "rangeability", "char_z", "char_f")
    ) + (
        Param("dp_open", "delta_Pa", 1e3, "pressure difference at which it is fully open", min=0.0),
    )
    SIGNAL_INPUTS = ()

    def setup(self):
        self.params.setdefault("characteristic", "linear")
        super().setup()

    def opening(self, t, x):
        dp = x["inlet.p"] - x["outlet.p"]
        return smooth_step(dp / self.params["dp_open"])

    def initial_guess(self, t0, x):
        """Guessed half open (dp = dp_open/2: the outlet node's pressure guess lowered
        to that), whatever the nodes' guesses say: where the valve is shut or just shut
        (dp <= 0) its opening does not change with dp (dz/d(dp) = 0), and a Newton
        iteration started there does not see that the valve opens. Measured: a feed
        line's given start, the discharge guessed 7 bar below the line behind the
        valve, crept for 60 iterations towards zero flow and failed."""
        dp_half = 0.5 * self.params["dp_open"]
        if x["inlet.p"] - x["outlet.p"] < dp_half:
            x["outlet.p"] = x["inlet.p"] - dp_half
        x["m"] = self.flow(t0, x)

    #: reverse flow through the closed valve beyond this multiple of its leakage flow at
    #: the reverse pressure difference is outside its range (``steady_problems``)
    REVERSE_LEAK_FACTOR = 10.0

    def steady_problems(self, t0, x):
        """Reverse flow (m < 0) above REVERSE_LEAK_FACTOR times the leakage flow at rest
        (``Component.steady_problems``); the valve's law gives at most its leakage, so
        this flags a state the solver found outside the model's range."""
        m = x["m"]
        if m >= -M_EPS_REL * self.params["m_nominal"]:
            return []
        try:
            leak = (
                self.params["leakage"]
                * self.K
                * abs(self.iec_factor(x, x["inlet.p"] - x["outlet.p"]))
            )
        except Exception:  # noqa: BLE001 - a range check must not hide the state
            leak = 0.0
        if abs(m) <= self.REVERSE_LEAK_FACTOR * leak:
            return []
        return [
            f"check valve '{self.name}' passes {-m:.4g} kg/s in reverse at rest, more than its "
            "leakage"
        ]
