"""Two-phase vessels at saturation: the equilibrium ``Drum`` (Astrom and Bell 2000)
and the ``FeedwaterTank`` (deaerator).

Both are one lumped volume V_t [m3] of saturated liquid (V_l) and saturated vapour
(V_v = V_t - V_l) at one pressure p, with the vessel metal m_D c_p,D at the
saturation temperature (Astrom, K. J., Bell, R. D.: Drum-boiler dynamics,
Automatica 36 (2000) 363-378, section 3; the same equations as the Modelica
Standard Library's DrumBoiler.BaseClasses.EquilibriumDrumBoiler).

Symbols (all SI): p [Pa]; T_s(p) [K] saturation temperature; rho_l, rho_v [kg/m3],
u_l, u_v [J/kg], h_l, h_v [J/kg] saturated liquid and vapour at p; M [kg] fluid
mass; U [J] fluid internal energy plus metal energy; m_k [kg/s] the port flows
(positive in the design direction); E_k [W] the port energy flows
(``physics.energy_in``, upwind by the actual flow: inflow carries the node's h,
outflow the vessel's h_l at a liquid port and h_v at a vapour port); Q [W] heat
input.

  mass       dM/dt = sum_in m_k - sum_out m_k                                    [kg/s]
  energy     dU/dt = sum_in E_k - sum_out E_k + Q                                [W]
  mass_def   M = rho_l V_l + rho_v (V_t - V_l)                                   [kg]
  energy_def U = rho_l V_l u_l + rho_v (V_t - V_l) u_v + m_D c_p,D T_s(p)        [J]
             (= rho_l V_l h_l + rho_v V_v h_v - p V_t + m_D c_p,D T_s, Astrom-Bell)
  h_l, h_v   h_l = h'(p),  h_v = h''(p)                                          [J/kg]
  port p     p_port = p for every port (no resistance inside the vessel)         [Pa]

M and U are the differential states (so mass and energy are conserved to the
Newton tolerance, as in ``Pipe``); p and V_l follow from mass_def and energy_def.
The state must stay sub-critical with 0 < V_l < V_t.

Physical limits (terminal switches: the run stops at the located crossing, with a
message naming the vessel, its level, liquid volume and pressure, and the time;
``dnasim run`` exits with 1 and results.csv keeps the rows up to it):

  dry       g = V_l / V_t                      the water is used up: V_l = 0       [-]
  full      g = (V_t - A level) / V_t          the level reaches the top of the
                                               vessel, V_t/A (V_l + V_b = V_t)     [-]
  critical  g = (p_c - dp_c - p) / p_c         the pressure comes within dp_c =
                                               CRITICAL_MARGIN of the critical
                                               pressure p_c, where the two phases
                                               become one                          [-]

Beyond them the equations hold no meaning (a negative liquid volume or vapour
space, no saturation state), and without the stop the integration went on there:
a drum without feed held M = -3568 kg for many rows before Newton failed, a feed
stuck open gave V_l = 839 m3 in a 100 m3 drum, and a drum driven towards p_c
failed with a Newton message naming its V_l and the level controller.

Shrink and swell (Drum with tau_b > 0). In the equilibrium model V_l alone falls
when the steam flow rises (flashing turns liquid into vapour). The level a gauge
shows also contains the steam bubbles below the surface, V_b [m3] (Astrom and
Bell's V_sd, section 5, here with one residence time tau_b [s]): steam is
generated in the water at the rate q_e = m_liquid_in - dM_l/dt [kg/s]
(M_l = rho_l V_l) and leaves the water after tau_b on average, so the bubble
volume is tau_b q_e / rho_v. dM_l/dt is taken through a first-order filter
with the same time constant (state z [kg]):

  filter     tau_b dz/dt = M_l - z                                              [kg/s]
  bubbles    V_b = tau_b q_e / rho_v,  q_e = m_liquid_in - (M_l - z)/tau_b       [m3]
  level      level = (V_l + V_b) / A                                             [m]

The bubbles are saturated vapour and part of V_v, so they change neither mass
nor energy; they only lift the level. A rise of the steam flow lowers p, the
water flashes, q_e jumps and the level first rises (swell) before the lost mass
lowers it; a rise of the cold feed flow condenses steam, q_e falls and the level
first drops (shrink). With tau_b = 0 (the FeedwaterTank) level = V_l / A.

Heat: Q [W] from the parameter ``Q`` (a number or a time function) or, when it is
not given, from the signal input ``Q``. The accumulator Q_passed [J] integrates
-Q (the heat leaving the fluid, ``Pipe``'s sign), for balances:
d(M)/dt = sum of port flows, d(U)/dt = sum of port energy flows - dQ_passed/dt.
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError, ResidualDomainError
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
from dnasim.model.physics import energy_in, saturation_enthalpies

#: the vessel stops this far below the critical pressure p_c [Pa], as MSL's
#: EquilibriumDrumBoiler asserts (p < p_c - 0.1 bar): at p_c the two phases of the
#: equilibrium model become one (rho' = rho'', no saturation state above it). Without
#: the stop, tests/plants/limits/drum_to_critical.toml failed in Newton at 219.8 bar
#: with a message naming drum.V_l and the level controller; with it, the run reaches
#: the limit and stops there (measured with margins of 0.1, 0.5 and 1 bar).
CRITICAL_MARGIN = 1e4


def saturation_properties(medium, p: float):
    """(T_s [K], rho_l, rho_v [kg/m3], u_l, u_v [J/kg], h_l, h_v [J/kg]) at p [Pa]."""
    hl, hv = saturation_enthalpies(medium, p)
    hl, hv = float(hl[0]), float(hv[0])
    if not (np.isfinite(hl) and np.isfinite(hv)):
        raise ResidualDomainError(
            f"{medium.label}: no saturation state at p = {p / 1e5:.6g} bar "
            "(a two-phase vessel needs a sub-critical pressure)"
        )
    sl = medium.state(p, hl)
    sv = medium.state(p, hv)
    return sl.T, sl.rho, sv.rho, sl.u, sv.u, hl, hv


def _tidy(value: float, scale: float) -> float:
    """``value``, or 0 when it is round-off (below 1e-9 of ``scale``), or ``scale`` when
    it is that within round-off: a limit's value in a message."""
    for limit in (0.0, scale):
        if abs(value - limit) < 1e-9 * abs(scale):
            return limit
    return value


class _SaturatedVessel(Component):
    """Base of Drum and FeedwaterTank (see the module doc)."""

    REGISTER = False
    #: (port, role, phase delivered on outflow "liquid"/"vapour", doc)
    PORTS: tuple = ()
    HAS_BUBBLES = False
    TWO_PHASE_GROUPS = ("fluid",)  # saturated liquid and vapour: a condensable medium

    def signal_range(self, name):
        """The level and V_l stay inside the vessel: 0 < V_l < V_t, level < V_t/A."""
        V_t, A = self.params["V_t"], self.params["A"]
        if name == "V_l":
            return 0.0, V_t, "m3", f"the vessel's volume V_t = {V_t:.6g} m3"
        if name == "level":
            return (
                0.0,
                V_t / A,
                "m",
                f"its top, V_t/A = {V_t:.6g} m3 / {A:.6g} m2 = {V_t / A:.6g} m",
            )
        return None

    COMMON_PARAMS = (
        Param("V_t", "m3", doc="total inner volume V_t", min=0.0),
        Param("A", "m2", 1.0, "water surface area: level = (V_l + V_b)/A", min=0.0),
        Param("m_D", "kg", 0.0, "vessel metal mass (at the saturation temperature)", min=0.0),
        Param("cp_D", "J/(kg.K)", 500.0, "specific heat capacity of the metal", min=0.0),
        Param("p0", "Pa", None, "initial pressure (given start)", min=0.0),
        Param("V_l0", "m3", None, "initial liquid volume (given start), default V_t/2", min=0.0),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (a condensable medium)", kind="string"),
    )

    def setup(self):
        P = self.params
        if P["V_t"] <= 0:
            raise PlantError(f"component '{self.name}': V_t must be > 0 m3")
        if P["V_l0"] is not None and not 0 < P["V_l0"] < P["V_t"]:
            raise PlantError(
                f"component '{self.name}': V_l0 = {P['V_l0']:g} m3 must lie between 0 and "
                f"V_t = {P['V_t']:g} m3"
            )
        self.heat_from_signal = P["Q"] is None
        self.tau_b = P.get("tau_b", 0.0) or 0.0

    # ------------------------------------------------------------ declarations
    def fluid_ports(self):
        out = []
        for name, role, phase, doc in self.PORTS:
            out.append(
                FluidPort(
                    name,
                    role,
                    f"m_{name}",
                    "storage",
                    doc,
                    h_out="h_l" if phase == "liquid" else "h_v",
                    m_eps=self.m_eps,
                )
            )
        return out

    def signal_inputs(self):
        return [SignalPort("Q", "W", "heat input")] if self.heat_from_signal else []

    def signal_outputs(self):
        return list(self.SIGNAL_OUTPUTS)

    SIGNAL_OUTPUTS = (
        SignalPort("level", "m", "level (V_l + V_b)/A", variable="level"),
        SignalPort("V_l", "m3", "liquid volume", variable="V_l"),
        SignalPort("p", "Pa", "pressure", variable="p"),
    )

    def variables(self):
        P = self.params
        m_nom = P["m_nominal"]
        out = [
            Variable("M", "kg", P["V_t"] * 100.0, doc="fluid mass", min=0.0),
            Variable("U", "J", P["V_t"] * 1e8, doc="fluid internal energy + metal m_D cp_D T_s"),
            Variable("p", "Pa", 1e6, doc="pressure"),
            Variable("V_l", "m3", P["V_t"] / 2, doc="liquid volume"),
            Variable("h_l", "J/kg", 1e6, doc="saturated liquid enthalpy h'(p)"),
            Variable("h_v", "J/kg", 2.7e6, doc="saturated vapour enthalpy h''(p)"),
            Variable("level", "m", P["V_t"] / 2 / P["A"], doc="level (V_l + V_b)/A"),
        ]
        if self.tau_b > 0:
            out.append(Variable("z", "kg", P["V_t"] * 500.0, doc="filtered liquid mass M_l"))
        out += [Variable(f"m_{n}", "kg/s", m_nom, doc=doc) for n, _, _, doc in self.PORTS]
        out.append(
            Variable(
                "Q_passed",
                "J",
                1e6,
                doc="integral of -Q dt: heat leaving the fluid (Pipe's sign)",
                accumulator=True,
            )
        )
        return out

    def _port_terms(self):
        """Local names the balances touch: flows, node enthalpies, own enthalpies."""
        dep = []
        for n, _, _, _ in self.PORTS:
            dep += [f"m_{n}", f"{n}.h"]
        return tuple(dep)

    def equations(self):
        P = self.params
        flows = tuple(f"m_{n}" for n, _, _, _ in self.PORTS)
        heat = ("Q",) if self.heat_from_signal else ()
        eqs = [
            Equation(
                "mass",
                y=flows,
                yp=("M",),
                unit="kg/s",
                doc="dM/dt = sum m_in - sum m_out",
                residual=lambda t, x, xp: xp["M"] - self.net_inflow(x),
            ),
            Equation(
                "energy",
                y=self._port_terms() + ("h_l", "h_v") + heat,
                yp=("U",),
                unit="W",
                doc="dU/dt = sum E_in - sum E_out + Q",
                residual=lambda t, x, xp: xp["U"] - (sum(self.port_energy(x)) + self.heat(t, x)),
            ),
            Equation(
                "mass_def",
                y=("M", "p", "V_l"),
                unit="kg",
                doc="M = rho_l V_l + rho_v (V_t - V_l)",
                residual=lambda t, x, xp: (
                    x["M"] - (x.work["rho_l"] * x["V_l"] + x.work["rho_v"] * x.work["V_v"])
                ),
            ),
            Equation(
                "energy_def",
                y=("U", "p", "V_l"),
                unit="J",
                doc="U = rho_l V_l u_l + rho_v V_v u_v + m_D cp_D T_s(p)",
                residual=lambda t, x, xp: (
                    x["U"]
                    - (
                        x.work["rho_l"] * x["V_l"] * x.work["u_l"]
                        + x.work["rho_v"] * x.work["V_v"] * x.work["u_v"]
                        + P["m_D"] * P["cp_D"] * x.work["T_s"]
                    )
                ),
            ),
            Equation(
                "liquid_enthalpy",
                y=("h_l", "p"),
                unit="J/kg",
                doc="h_l = h'(p)",
                residual=lambda t, x, xp: x["h_l"] - x.work["h_l"],
            ),
            Equation(
                "vapour_enthalpy",
                y=("h_v", "p"),
                unit="J/kg",
                doc="h_v = h''(p)",
                residual=lambda t, x, xp: x["h_v"] - x.work["h_v"],
            ),
        ]
        liquid_in = tuple(
            f"m_{n}" for n, role, ph, _ in self.PORTS if role == "inlet" and ph == "liquid"
        )
        if self.tau_b > 0:
            eqs.append(
                Equation(
                    "filter",
                    y=("z", "p", "V_l"),
                    yp=("z",),
                    unit="kg/s",
                    doc="tau_b dz/dt = M_l - z",
                    residual=lambda t, x, xp: (
                        self.tau_b * xp["z"] - (x.work["rho_l"] * x["V_l"] - x["z"])
                    ),
                )
            )
            eqs.append(
                Equation(
                    "level",
                    y=("level", "V_l", "p", "z") + liquid_in,
                    unit="m",
                    doc="level = (V_l + V_b)/A, V_b = tau_b q_e/rho_v",
                    residual=lambda t, x, xp: (
                        x["level"]
                        - (x["V_l"] + self._bubble_volume(x, x.work["rho_l"], x.work["rho_v"]))
                        / P["A"]
                    ),
                )
            )
        else:
            eqs.append(
                Equation(
                    "level",
                    y=("level", "V_l"),
                    unit="m",
                    doc="level = V_l/A",
                    residual=lambda t, x, xp: x["level"] - x["V_l"] / P["A"],
                )
            )
        for n, _, _, _ in self.PORTS:
            eqs.append(
                Equation(
                    f"pressure_{n}",
                    y=(f"{n}.p", "p"),
                    unit="Pa",
                    doc="p_port = p",
                    residual=lambda t, x, xp, n=n: x[f"{n}.p"] - x["p"],
                )
            )
        eqs.append(
            Equation(
                "heat_passed",
                y=heat,
                yp=("Q_passed",),
                unit="W",
                doc="dQ_passed/dt = -Q",
                residual=lambda t, x, xp: xp["Q_passed"] + self.heat(t, x),
            )
        )
        return eqs

    # ---------------------------------------------------------------- residual
    def prepare(self, t, x, xp):
        """The saturation properties at p (one property call per evaluation) and V_v."""
        T_s, rho_l, rho_v, u_l, u_v, h_l, h_v = saturation_properties(self.medium, x["p"])
        return {
            "T_s": T_s,
            "rho_l": rho_l,
            "rho_v": rho_v,
            "u_l": u_l,
            "u_v": u_v,
            "h_l": h_l,
            "h_v": h_v,
            "V_v": self.params["V_t"] - x["V_l"],
        }

    def heat(self, t, x):
        """Heat input Q [W]."""
        return x["Q"] if self.heat_from_signal else self.param_at("Q", t)

    def net_inflow(self, x):
        """sum m_in - sum m_out [kg/s]."""
        m_net = 0.0
        for n, role, _, _ in self.PORTS:
            m_net += x[f"m_{n}"] if role == "inlet" else -x[f"m_{n}"]
        return m_net

    def port_energy(self, x):
        """Energy flows INTO the vessel at each port [W], in PORTS order."""
        out = []
        for n, role, phase, _ in self.PORTS:
            m_in = x[f"m_{n}"] if role == "inlet" else -x[f"m_{n}"]
            h_own = x["h_l"] if phase == "liquid" else x["h_v"]
            out.append(float(energy_in(m_in, x[f"{n}.h"], h_own, self.m_eps)))
        return out

    def liquid_inflow(self, x):
        """Mass flow into the liquid through the liquid inlets [kg/s]."""
        return sum(
            x[f"m_{n}"] for n, role, ph, _ in self.PORTS if role == "inlet" and ph == "liquid"
        )

    def _bubble_volume(self, x, rho_l, rho_v):
        q_e = self.liquid_inflow(x) - (rho_l * x["V_l"] - x["z"]) / self.tau_b
        return self.tau_b * q_e / rho_v

    # ----------------------------------------------------------------- limits
    def _kind(self) -> str:
        return "drum" if isinstance(self, Drum) else "tank"

    def switches(self):
        """The vessel's physical limits as terminal switches (module doc: dry, full,
        critical); ``message`` gives the reason with the state at the crossing."""
        P = self.params
        V_t, A = P["V_t"], P["A"]
        last: dict = {}  # the state of the last evaluation (the located crossing)

        def remember(x):
            last.update(p=x["p"], V_l=x["V_l"], level=x["level"])

        def dry(t, x, xp):
            remember(x)
            return x["V_l"] / V_t

        def full(t, x, xp):
            remember(x)
            return (V_t - A * x["level"]) / V_t

        def critical(t, x, xp):
            remember(x)
            p_c = self.medium.p_critical
            return (p_c - CRITICAL_MARGIN - x["p"]) / p_c

        def where(t):
            # round-off at a limit (V_l = -6e-15 m3 when dry) is shown as the limit
            V_l = _tidy(last.get("V_l", math.nan), V_t)
            level = _tidy(last.get("level", math.nan), V_t / A)
            return (
                f"at t = {t:.6g} s (p = {last.get('p', math.nan) / 1e5:.6g} bar, liquid volume "
                f"V_l = {V_l:.6g} m3 of V_t = {V_t:g} m3, level {level:.4g} m of {V_t / A:.4g} m)"
            )

        head = f"{self._kind()} '{self.name}' ({type(self).__name__})"

        def dry_message(t):
            return (
                f"{head} ran dry: its liquid volume reached 0 {where(t)}; more water leaves "
                "(as steam or water) than the feed brings: check the feed flow and its "
                "level control"
            )

        def full_message(t):
            return (
                f"{head} is full: the level reached the top of the vessel, {V_t / A:.4g} m "
                f"(V_t/A) {where(t)}; the feed brings more water than leaves: check the "
                "feed flow and its level control (a vessel full of water is not modelled)"
            )

        def critical_message(t):
            p_c = self.medium.p_critical
            return (
                f"{head}: the pressure reached {(p_c - CRITICAL_MARGIN) / 1e5:.6g} bar, "
                f"{CRITICAL_MARGIN / 1e5:g} bar below the critical point of "
                f"{self.medium.label} ({p_c / 1e5:.6g} bar), {where(t)}; a vessel of "
                "saturated water and steam has no two phases at and above it: check the "
                "heat input against the steam outlet"
            )

        out = [
            Switch("dry", dry, -1, terminal=True, message=dry_message, doc="V_l reaches 0"),
            Switch(
                "full",
                full,
                -1,
                terminal=True,
                message=full_message,
                doc="the level reaches the top of the vessel, V_t/A",
            ),
        ]
        if math.isfinite(getattr(self.medium, "p_critical", math.nan)):
            out.append(
                Switch(
                    "critical",
                    critical,
                    -1,
                    terminal=True,
                    message=critical_message,
                    doc="p reaches p_c - CRITICAL_MARGIN",
                )
            )
        return out

    # ----------------------------------------------------------------- outputs
    def outputs(self):
        return [
            Output("T", "K", "saturation temperature"),
            Output("V_b", "m3", "steam bubbles below the level"),
            Output("rho_l", "kg/m3", "saturated liquid density"),
            Output("rho_v", "kg/m3", "saturated vapour density"),
            Output("Q_in", "W", "heat input"),
        ]

    def output_values(self, t, x, xp):
        T_s, rho_l, rho_v, *_ = saturation_properties(self.medium, x["p"])
        V_b = self._bubble_volume(x, rho_l, rho_v) if self.tau_b > 0 else 0.0
        return [T_s, V_b, rho_l, rho_v, self.heat(t, x)]

    # ---------------------------------------------------------- initialisation
    def _start(self, x=None):
        P = self.params
        p = P["p0"]
        if p is None:
            p = x["p"] if x is not None and "p" in x and x["p"] > 0 else 1e6
        V_l = P["V_l0"] if P["V_l0"] is not None else P["V_t"] / 2
        return p, V_l

    def steady_problems(self, t0, x):
        """A liquid volume outside (0, V_t) at rest (``Component.steady_problems``)."""
        V_l, V_t = x["V_l"], self.params["V_t"]
        if 0.0 < V_l < V_t:
            return []
        return [
            f"{type(self).__name__.lower()} '{self.name}' would hold V_l = {V_l:.4g} m3 of "
            f"liquid at rest, outside the vessel's volume 0 .. {V_t:g} m3"
        ]

    def design_values(self, t0, x):
        """The heat input Q [W] (heat from outside: a furnace, when positive) and the
        flow of the first outlet (the steam of a drum, the feed water of a tank)."""
        Q = self.heat(t0, x)
        out = {"duty": Q}
        if Q > 0.0:
            out["heat_in"] = Q
        first_out = next((n for n, role, _, _ in self.PORTS if role == "outlet"), None)
        if first_out is not None:
            out["m"] = x[f"m_{first_out}"]
        return out

    def guess_nodes(self, t0):
        if self.params["p0"] is None:
            return {}
        p, _ = self._start()
        _, _, _, _, _, h_l, h_v = saturation_properties(self.medium, p)
        out = {}
        for n, _, phase, _ in self.PORTS:
            out[n] = (p, h_l if phase == "liquid" else h_v)
        return out

    def initial_guess(self, t0, x):
        P = self.params
        if P["p0"] is not None:
            p = P["p0"]
        else:
            p = x[f"{self.PORTS[0][0]}.p"]
        _, V_l = self._start()
        T_s, rho_l, rho_v, u_l, u_v, h_l, h_v = saturation_properties(self.medium, p)
        V_v = P["V_t"] - V_l
        x["p"], x["V_l"], x["h_l"], x["h_v"] = p, V_l, h_l, h_v
        x["M"] = rho_l * V_l + rho_v * V_v
        x["U"] = rho_l * V_l * u_l + rho_v * V_v * u_v + P["m_D"] * P["cp_D"] * T_s
        x["level"] = V_l / P["A"]
        if self.tau_b > 0:
            x["z"] = rho_l * V_l
        for n, _, _, _ in self.PORTS:
            x[f"m_{n}"] = P["m_nominal"]
        x["Q_passed"] = 0.0


class Drum(_SaturatedVessel):
    """Equilibrium drum boiler after Astrom and Bell (2000) with the level's swell
    (equations in ``dnasim.library.drum``).

      mass        dM/dt = m_feed - m_steam (- m_water)                       [kg/s]
      energy      dU/dt = E_feed - E_steam (- E_water) + Q                   [W]
      mass_def    M = rho_l V_l + rho_v (V_t - V_l)                          [kg]
      energy_def  U = rho_l V_l u_l + rho_v (V_t - V_l) u_v + m_D cp_D T_s(p)  [J]
      filter      tau_b dz/dt = rho_l V_l - z                                [kg/s]
      level       level = (V_l + tau_b q_e/rho_v)/A,
                  q_e = m_feed - (rho_l V_l - z)/tau_b                       [m]
      ports       p_feed = p_steam (= p_water) = p                           [Pa]

    Steam leaves at h''(p), water (the optional port ``water``, e.g. a blow-down
    or a downcomer to a separate evaporator) at h'(p). Heat Q [W] from the parameter
    or the signal input ``Q``. Given start: p0, V_l0 (the metal at T_s(p0)).
    """

    PORTS = (
        ("feed", "inlet", "liquid", "feedwater in (m_feed > 0 into the drum)"),
        ("steam", "outlet", "vapour", "saturated steam out (m_steam > 0 out of the drum)"),
    )
    HAS_BUBBLES = True
    PARAMS = _SaturatedVessel.COMMON_PARAMS + (
        Param("Q", "W", None, "heat input (otherwise the signal input 'Q')", time_function=True),
        Param(
            "tau_b",
            "s",
            0.0,
            "residence time of steam bubbles below the level (0: level = V_l/A)",
            min=0.0,
        ),
        Param("water_outlet", "1", False, "add the liquid outlet port 'water'", kind="bool"),
    )
    FLUID_PORTS = (
        FluidPort("feed", "inlet", "m_feed", "storage", "feedwater in"),
        FluidPort("steam", "outlet", "m_steam", "storage", "saturated steam out"),
        FluidPort("water", "outlet", "m_water", "storage", "saturated water out (water_outlet)"),
    )
    SIGNAL_INPUTS = (SignalPort("Q", "W", "heat input (when the parameter Q is not given)"),)

    def setup(self):
        if self.params["water_outlet"]:
            self.PORTS = type(self).PORTS + (("water", "outlet", "liquid", "saturated water out"),)
        super().setup()


class FeedwaterTank(_SaturatedVessel):
    """Feedwater tank / deaerator: a vessel at saturation heated by steam
    (equations in ``dnasim.library.drum``; no bubbles: level = V_l/A).

      mass        dM/dt = m_water_in + m_steam_in - m_water_out              [kg/s]
      energy      dU/dt = E_water_in + E_steam_in - E_water_out + Q          [W]
      mass_def    M = rho_l V_l + rho_v (V_t - V_l)                          [kg]
      energy_def  U = rho_l V_l u_l + rho_v (V_t - V_l) u_v + m_D cp_D T_s(p)  [J]
      level       level = V_l / A                                            [m]
      ports       p_water_in = p_steam_in = p_water_out = p                  [Pa]

    The heating steam condenses and the feed water is heated to saturation; the
    pressure settles where the steam's enthalpy surplus balances the subcooling of
    the water (plus Q, a heat loss when negative). Water leaves at h'(p). A reverse
    flow at the steam inlet takes out saturated vapour h''(p), at the water inlet
    saturated liquid. Given start: p0, V_l0.
    """

    PORTS = (
        ("water_in", "inlet", "liquid", "condensate / feed water in"),
        ("steam_in", "inlet", "vapour", "heating steam in"),
        ("water_out", "outlet", "liquid", "saturated feed water out"),
    )
    PARAMS = _SaturatedVessel.COMMON_PARAMS + (
        Param(
            "Q",
            "W",
            0.0,
            "heat input (negative: heat loss), a number or a time function",
            time_function=True,
        ),
    )
    FLUID_PORTS = tuple(FluidPort(n, role, f"m_{n}", "storage", doc) for n, role, _, doc in PORTS)
