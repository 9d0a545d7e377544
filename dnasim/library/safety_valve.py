"""SafetyValve: a spring-loaded safety (relief) valve with pop, blowdown and reseat."""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError, ResidualDomainError
from dnasim.library.control_valve import CHOKE_REG_REL, hem_omega, odd_limit, smooth_step
from dnasim.library.submodels.valve_laws import (
    critical_pressure_ratio,
    inlet_exponent,
    napier_flow,
    nozzle_factor,
)
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Output,
    Param,
    Switch,
    Variable,
    flow_through_ports,
)
from dnasim.model.physics import upwind_mean, valve_flow

#: the exponent of dry saturated steam [-] of Napier's law below the critical pressure
#: ratio (the usual 1.135; Napier's formula itself is for choked flow)
NAPIER_KAPPA = 1.135


class SafetyValve(Component):
    """Spring-loaded safety valve (ASME BPVC Section I; EN ISO 4126-1 terms).

    Terms: set pressure p_set [Pa] (the inlet pressure at which the valve opens;
    absolute, as every pressure in dnasim: the gauge set pressure plus the
    atmosphere's); overpressure [-] (the rise above p_set at which the valve reaches
    full lift, a fraction of p_set; ASME I certifies the capacity at 3 %, ISO 4126-1
    at up to 10 %); blowdown [-] (set minus reseating pressure, a fraction of p_set;
    ASME I 2 to 4 %, ISO 4126-1 2 to 15 % for steam); reseating pressure
    p_reseat = p_set (1 - blowdown); lift l [-] of the disc, 1 at full lift.

    Two discrete modes with hysteresis, changed by one switch function ("seat"),
    set the lift the disc moves to, l_t [-]:

      closed   l_t = 0 (the seat leaks ``leakage`` of the full flow);
               g = p_set - p_in: the valve pops when p_in rises to p_set
      open     l_t = l_pop + (1 - l_pop) S((p_in - p_set)/(overpressure p_set)),
               S(s) = 3 s^2 - 2 s^3 on [0, 1] (0 below, 1 above);
               g = p_in - p_reseat: it reseats when p_in falls to p_reseat
      lift     t_lift dl/dt = l_t - l                                           [1/s]

    so between p_reseat and p_set the valve is open or shut depending on where it
    came from. pop_lift l_pop = 1 (default) is the pop action of a full-lift valve
    (ASME I steam valves): full lift from the set pressure on, the rated capacity
    as soon as the disc has travelled; with l_pop < 1 it pops to l_pop and rises to
    full lift over the overpressure, and holds at least l_pop until it reseats. The
    disc travels with the time constant t_lift (default 0.05 s; real pops take some
    10 to 100 ms): the flow rises within a few t_lift after the pop instead of
    jumping, and falls so after the reseat (the jump of a flow from the leakage to
    the full capacity at one instant cannot be made consistent by Newton from the
    leakage state: the upwind weights at a node change by orders of magnitude).

    Flow m [kg/s] (inlet -> outlet positive), z_e = leakage + (1 - leakage) l,
    dp = p_in - p_out, eps = dp/p_1, p_1 and rho_1 the smooth upwind means of the
    two nodes' by dp over dp_reg; g(d) = d/(d^2 + dp_reg^2)^(1/4) (the valves'
    regularised sqrt, odd: reverse flow is the same law with the ports exchanged):

      capacity "iso4126" (default; EN ISO 4126-7, and API 520 Part I alike):
        gas, steam     m = z_e K_d A sqrt(2) phi(eps_e) sqrt(rho_1) g(eps_e p_1)
                       = z_e K_d A Psi(p_2/p_1, kappa) sqrt(2 rho_1 p_1) for dp >> dp_reg
                       (the nozzle flow function of ``valve_laws``; choked below
                       r_c = (2/(kappa + 1))^(kappa/(kappa - 1)): eps_e = clip(eps, 1 - r_c));
                       kappa the isentropic exponent of the inlet state (IF97 steam
                       ~1.3 superheated, 1.14 dry saturated at 10 bar), or ``kappa``
        liquid         m = z_e K_d A sqrt(2 rho_1) g(dp)   (a subcooled inlet)
      capacity "napier" (dry saturated steam, ASME I PG-69.2):
        m = z_e W_N(p_1) phi(eps_e) g(eps_e p_1) / (phi(eps_c) sqrt(eps_c p_1)),
        W_N = 1.4588e-3 [s/m] K_d A p_1 K_N: Napier's 51.5 K A P [lb/h, in2, psia]
        with its high-pressure factor K_N (``valve_laws.napier_flow``), the choked
        flow at a back pressure below the critical ratio (kappa 1.135); above it,
        scaled by the flow function so that the flow goes smoothly to 0 at dp = 0
      capacity "hem" (flashing two-phase, boiling liquid; the omega method of
        API 520 Annex C / ISO 4126-10 type): as ``DrainValve``'s law with
        K = sqrt(2) K_d A

    K_d [-] is the certified (derated) coefficient of discharge: ISO's K_dr =
    0.9 K_d (tested), ASME's K = 0.9 K_D. A [m2] the flow (bore) area. The rated
    capacity is the flow at p_in = p_set (1 + overpressure) and full lift.
    Throttling is isenthalpic (as ``Valve``). A back pressure above the inlet
    pressure while open would reverse the flow (the law is odd); a real valve's
    disc would close.
    """

    PARAMS = (
        Param("p_set", "Pa", doc="set pressure (absolute, at the inlet)", min=0.0),
        Param("A", "m2", doc="flow area of the valve (bore, orifice)", min=0.0),
        Param("K_d", "1", doc="certified coefficient of discharge (K_dr, ASME K)", min=0.0),
        Param(
            "blowdown",
            "1",
            0.04,
            "set minus reseating pressure, fraction of p_set",
            min=0.0,
            max=0.5,
        ),
        Param(
            "overpressure",
            "1",
            0.03,
            "pressure rise over p_set to full lift, fraction of p_set",
            min=0.0,
            max=0.5,
        ),
        Param("pop_lift", "1", 1.0, "lift at the pop (1: full lift at once)", min=0.0, max=1.0),
        Param("t_lift", "s", 0.05, "time constant of the disc's travel", min=0.0),
        Param(
            "capacity",
            "1",
            "iso4126",
            "flow law: iso4126 (gas, steam, liquid), napier (dry saturated steam, ASME I) "
            "or hem (flashing two-phase, omega method)",
            kind="string",
            choices=("iso4126", "napier", "hem"),
        ),
        Param("kappa", "1", None, "isentropic exponent (default: of the inlet state)", min=0.0),
        Param(
            "initially_open",
            "1",
            False,
            "start open when the initial pressure lies between p_reseat and p_set",
            kind="bool",
        ),
        Param("leakage", "1", 1e-6, "flow of the shut valve, fraction of full lift", min=0.0),
        Param(
            "dp_reg", "delta_Pa", 10.0, "regularisation pressure difference near dp = 0", min=0.0
        ),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", "resistance", "protected side (vessel, line)"),
        FluidPort("outlet", "outlet", "m", "resistance", "discharge (vent, blowdown tank)"),
    )

    def setup(self):
        P = self.params
        name = f"component '{self.name}' (SafetyValve)"
        for key in ("p_set", "A", "K_d", "t_lift"):
            if not P[key] > 0:
                raise PlantError(f"{name}: {key} must be > 0")
        if not P["leakage"] < 1.0:
            raise PlantError(f"{name}: leakage must be < 1 (a fraction of the full-lift flow)")
        if P["pop_lift"] < 1.0 and not P["overpressure"] > 0:
            raise PlantError(
                f"{name}: pop_lift = {P['pop_lift']} < 1 needs overpressure > 0 (the "
                "pressure rise over p_set to full lift)"
            )
        if P["capacity"] == "napier" and P["kappa"] is not None:
            raise PlantError(f"{name}: capacity 'napier' is for dry saturated steam: no kappa")

    # ----------------------------------------------------------- declarations
    @property
    def p_reseat(self) -> float:
        """Reseating pressure p_set (1 - blowdown) [Pa]."""
        return self.params["p_set"] * (1.0 - self.params["blowdown"])

    def fluid_ports(self):
        return flow_through_ports(self.m_eps, "inlet.h")

    def variables(self):
        return [
            Variable("m", "kg/s", self.params["m_nominal"], doc="mass flow"),
            Variable("lift", "1", 1.0, doc="disc lift l, 1 at full lift"),
        ]

    def equations(self):
        return [
            Equation(
                "flow",
                y=("m", "lift", "inlet.p", "inlet.h", "outlet.p", "outlet.h"),
                unit="kg/s",
                doc="m = z_e(l) K_d A Psi sqrt(2 rho_1 p_1) (iso4126), Napier's law, or the "
                "omega method (hem)",
                residual=lambda t, x, xp: x["m"] - self.flow(x),
            ),
            Equation(
                "lift",
                y=("lift", "inlet.p"),
                yp=("lift",),
                unit="1",
                doc="t_lift dl/dt = l_t - l; l_t = 0 shut, l_pop + (1 - l_pop) S(...) open",
                residual=lambda t, x, xp: (
                    self.params["t_lift"] * xp["lift"] - (self.target_lift(x) - x["lift"])
                ),
            ),
        ]

    def outputs(self):
        return [Output("open", "1", "1 while open (popped), 0 while shut")]

    def output_values(self, t, x, xp):
        return [1.0 if self._open(x) else 0.0]

    # ------------------------------------------------------------------ modes
    def reset_discrete_state(self, modes):
        modes["open"] = False

    @staticmethod
    def _open(x) -> bool:
        return bool(x.modes.get("open", False))

    def _seat(self, t, x, xp):
        """g [Pa], positive while the mode holds: closed p_set - p_in, open p_in - p_reseat."""
        p = x["inlet.p"]
        return p - self.p_reseat if self._open(x) else self.params["p_set"] - p

    def _toggle(self, t, x, xp):
        x.modes["open"] = not self._open(x)

    def switches(self):
        return [
            Switch(
                "seat",
                self._seat,
                -1,
                self._toggle,
                "pops at p_in = p_set (closed), reseats at p_in = p_set (1 - blowdown) (open)",
                rearm=True,
            )
        ]

    def _open_at(self, p: float) -> bool:
        """The mode of a start at the inlet pressure p [Pa]: open at or above p_set,
        shut at or below p_reseat, ``initially_open`` between."""
        if p >= self.params["p_set"]:
            return True
        if p <= self.p_reseat:
            return False
        return bool(self.params["initially_open"])

    def init_discrete_state(self, t0, x, xp):
        old = self._open(x)
        x.modes["open"] = mode = self._open_at(x["inlet.p"])
        return mode != old

    # ----------------------------------------------------------------- physics
    def target_lift(self, x) -> float:
        """l_t [-]: 0 shut; l_pop + (1 - l_pop) S((p_in - p_set)/(overpressure p_set)) open."""
        if not self._open(x):
            return 0.0
        P = self.params
        l_pop = P["pop_lift"]
        if l_pop >= 1.0:
            return 1.0
        s = (x["inlet.p"] - P["p_set"]) / (P["overpressure"] * P["p_set"])
        return l_pop + (1.0 - l_pop) * smooth_step(s)

    def flow(self, x) -> float:
        """m [kg/s] at the node states in x, in the current mode."""
        leak = self.params["leakage"]
        z_e = leak + (1.0 - leak) * x["lift"]
        return self.flow_at(x["inlet.p"], x["inlet.h"], x["outlet.p"], x["outlet.h"], z_e)

    def flow_at(self, p_in, h_in, p_out, h_out, z_e) -> float:
        """m [kg/s] of the capacity law (class doc) between the inlet state (p_in [Pa],
        h_in [J/kg]) and the outlet state at the effective opening z_e [-]."""
        P = self.params
        dp = p_in - p_out
        reg = P["dp_reg"]
        s_in = self.medium.state(p_in, h_in)
        s_out = self.medium.state(p_out, h_out)
        rho1 = float(upwind_mean(dp, s_in.rho, s_out.rho, reg))
        p1 = float(upwind_mean(dp, p_in, p_out, reg))
        up = s_in if dp >= 0 else s_out
        K = math.sqrt(2.0) * P["K_d"] * P["A"]
        if P["capacity"] == "hem":
            phi, eps_c = hem_omega(self.medium, up)
            eps = odd_limit(dp / p1, eps_c, CHOKE_REG_REL * eps_c) if eps_c < 1.0 else dp / p1
            return z_e * K * phi(eps) * math.sqrt(rho1) * valve_flow(1.0, 1.0, eps * p1, reg)
        if P["capacity"] == "napier":
            kappa = NAPIER_KAPPA
        elif self._subcooled(up):
            return z_e * K * math.sqrt(rho1) * valve_flow(1.0, 1.0, dp, reg)
        else:
            kappa = P["kappa"] if P["kappa"] is not None else self._kappa(up)
        eps_c = 1.0 - critical_pressure_ratio(kappa)
        eps = odd_limit(dp / p1, eps_c, CHOKE_REG_REL * eps_c)
        shape = nozzle_factor(eps, kappa) * valve_flow(1.0, 1.0, eps * p1, reg)
        if P["capacity"] == "napier":
            choked = nozzle_factor(eps_c, kappa) * math.sqrt(eps_c * p1)
            return z_e * napier_flow(P["A"], P["K_d"], p1) * shape / choked
        return z_e * K * math.sqrt(rho1) * shape

    def rated_capacity(self, h_in: float, p_back: float) -> float:
        """The rated capacity m [kg/s]: the flow at full lift with the inlet at
        p_set (1 + overpressure) [Pa] and h_in [J/kg], the outlet at p_back [Pa]."""
        p1 = self.params["p_set"] * (1.0 + self.params["overpressure"])
        return self.flow_at(p1, h_in, p_back, h_in, 1.0)

    def _kappa(self, st) -> float:
        return inlet_exponent(self.medium, st, "isentropic")

    def _subcooled(self, st) -> bool:
        """True for a liquid below its saturation enthalpy (condensable medium, p < p_c)."""
        if not getattr(self.medium, "condensable", False):
            return False
        h_l, _ = self.medium.saturation_enthalpies(np.array([st.p]))
        h_l = float(h_l[0])
        return math.isfinite(h_l) and st.h < h_l

    def initial_guess(self, t0, x):
        """The disc at rest in the mode of the initial pressure (``init_discrete_state``):
        l = l_t, and the flow at that lift."""
        x.modes["open"] = self._open_at(x["inlet.p"])
        x["lift"] = self.target_lift(x)
        leak = self.params["leakage"]
        try:
            x["m"] = self.flow(x)
        except ResidualDomainError:
            x["m"] = leak * self.params["m_nominal"]
