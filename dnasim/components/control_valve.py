"""ControlValve (IEC 60534-2-1 flow equations) and CheckValve."""

from __future__ import annotations

import math

import numpy as np

from dnasim.components.base import (
    Component,
    Equation,
    FluidPort,
    Output,
    Param,
    SignalPort,
    Variable,
    flow_through_ports,
)
from dnasim.components.physics import M_EPS_REL, softplus, upwind_mean, valve_flow
from dnasim.errors import PlantError

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
    """(p_v [Pa], p_c [Pa]): vapour pressure at T [K] (p_c above T_c) and the critical pressure."""
    if getattr(medium, "backend", "") == "IF97":
        from dnasim.media import if97_kernel as K

        return float(K.p_sat(min(T, K.T_C))), float(K.P_C)
    import CoolProp.CoolProp as CP

    fluid = f"{medium.backend}::{medium.name}" if "HEOS" in medium.backend else medium.name
    T_c = CP.PropsSI("Tcrit", fluid)
    p_c = CP.PropsSI("pcrit", fluid)
    return (p_c if T >= T_c else CP.PropsSI("P", "T", T, "Q", 0, fluid)), p_c


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
      z_e           = leakage + (1 - leakage) f(z)
      f(z)          linear z; equal_percentage R^(z - 1) (for z < 0.01 linear to 0);
                    quick_opening 1 - (1 - z)^2; table: PCHIP through (char_z, char_f)

    clip(d, L) = d - softplus(d - L) + softplus(-d - L), width 1e-2 L: a smooth odd
    limit, exact to 1e-13 beyond 1.3 L. The valve's coefficient: ``Kv`` [m3/h]
    (K = Kv/36000 m2), ``Cv`` [US gpm/psi^0.5] (Kv = 0.865 Cv), or the nominal
    point (``m_nominal``, ``dp_nominal``, ``rho_nominal``, and for gas ``p_nominal``):
    K = m_nom / (Y_nom sqrt(rho_nom dp_nom)) so that the open valve passes m_nom
    there. For law = "linear": ``C_lin`` [kg/(s Pa)] or C_lin = m_nom/dp_nom.

    Service: "liquid" or "gas" (steam is "gas"); by default a condensable medium
    is "liquid" when the upstream state is subcooled liquid and "gas" otherwise
    (the law changes at the saturation line: a kink), a gas medium "gas". gamma
    defaults to cp/(cp - R) for an ideal-gas medium, 1.3 otherwise (steam).

    Throttling is isenthalpic both ways (fluid leaves through the outlet with the
    inlet node's h and vice versa), the flow is odd in dp with a finite slope at
    dp = 0 (index 1 at zero flow), and a closed valve keeps its leakage. A signal
    z is used as given, not clipped (as in ``Valve``): limit the driving
    controller's output to [0, 1].
    """

    PARAMS = (
        Param("Kv", "1", None, "flow coefficient Kv [m3/h at 1 bar, water], full open", min=0.0),
        Param("Cv", "1", None, "flow coefficient Cv [US gpm at 1 psi], full open", min=0.0),
        Param("dp_nominal", "delta_Pa", None, "pressure drop of the nominal point", min=0.0),
        Param("rho_nominal", "kg/m3", None, "inlet density of the nominal point", min=0.0),
        Param("p_nominal", "Pa", None, "inlet pressure of the nominal point (gas)", min=0.0),
        Param("C_lin", "kg/(s.Pa)", None, "flow coefficient of the linear law", min=0.0),
        Param(
            "law",
            "1",
            "iec",
            "flow law: IEC 60534 (turbulent) or linear (laminar)",
            kind="string",
            choices=("iec", "linear"),
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
        given = [k for k in ("Kv", "Cv", "dp_nominal") if P[k] is not None]
        if P["law"] == "linear":
            if P["C_lin"] is None and P["dp_nominal"] is None:
                raise PlantError(
                    f"{name}: the linear law needs C_lin, or dp_nominal (and m_nominal)"
                )
        elif len(given) != 1:
            raise PlantError(
                f"{name}: give exactly one of Kv, Cv or the nominal point (dp_nominal with "
                f"rho_nominal and m_nominal){'; got ' + ', '.join(given) if given else ''}"
            )
        elif P["dp_nominal"] is not None and P["rho_nominal"] is None:
            raise PlantError(f"{name}: the nominal point needs rho_nominal with dp_nominal")
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
        return flow_through_ports(self.m_eps, "inlet.h")

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.opening_from_signal else []

    def variables(self):
        return [Variable("m", "kg/s", self.params["m_nominal"], doc="mass flow")]

    def equations(self):
        dep = ("m", "inlet.p", "inlet.h", "outlet.p", "outlet.h")
        dep += ("z",) if self.opening_from_signal else ()
        return [
            Equation(
                "flow",
                y=dep,
                unit="kg/s",
                doc="m = K z_e Y sqrt(rho_1 dp_e) (IEC 60534) or C_lin z_e dp",
                residual=lambda t, x, xp: x["m"] - self.flow(t, x),
            )
        ]

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
        if self.params["gamma"] is not None:
            return self.params["gamma"]
        R, cp = getattr(self.medium, "R", None), getattr(self.medium, "cp", None)
        if isinstance(R, float) and isinstance(cp, float) and cp > R:
            return cp / (cp - R)
        return 1.3

    @property
    def K(self) -> float:
        """Full-open coefficient K [m2] (IEC law)."""
        if self._K is None:
            P = self.params
            if P["Kv"] is not None:
                self._K = P["Kv"] * KV_TO_K
            elif P["Cv"] is not None:
                self._K = P["Cv"] * KV_PER_CV * KV_TO_K
            else:
                Y = 1.0
                if P["p_nominal"] is not None and self.params["service"] != "liquid":
                    Fg_xT = self.gamma() / 1.4 * P["x_T"]
                    x = min(P["dp_nominal"] / P["p_nominal"], Fg_xT)
                    Y = 1.0 - x / (3.0 * Fg_xT)
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
        return self.K * z_e * self.iec_factor(x, dp)

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
            Fg_xT = self.gamma() / 1.4 * P["x_T"]
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
    is fully open (its cracking band).
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
