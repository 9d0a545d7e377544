"""Attemperator: a mixing volume where spray water cools superheated steam."""

from __future__ import annotations

import numpy as np

from dnasim.library.submodels.channel import (
    initial_phase_modes,
    phase_switch_values,
    toggle_phase_modes,
)
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Param,
    SignalPort,
    Switch,
    Variable,
)
from dnasim.model.physics import (
    M_REG_REL,
    PropertyArrays,
    energy_in,
    friction_dp,
    has_phase_branches,
    properties,
    upwind_mean,
)


class Attemperator(Component):
    """Fully mixed control volume V with a steam inlet, a spray-water inlet and an outlet.

    The volume has its own state p_v [Pa], h_v [J/kg]. Symbols: m_steam, m_water
    [kg/s] flows into the volume, m_out [kg/s] flow out (each may reverse);
    M [kg], U [J] fluid mass and internal energy; T [K] volume temperature;
    E_in(m, h_node, h_v) = w(m) h_node - w(-m) h_v the upwind port energy flow
    (``physics.energy_in``); fluid leaves through every port with h_v.

      mass             dM/dt = m_steam + m_water - m_out
      energy           dU/dt = E_in(m_steam, h_steam) + E_in(m_water, h_water)
                               + E_in(-m_out, h_outlet_node)
      density          M = V rho(p_v, h_v)
      internal_energy  U = M u(p_v, h_v)
      steam_friction   p_steam - p_v = k m_steam sqrt(m_steam^2 + m_reg^2) / rho_f
                       (rho_f: smooth upwind of the steam node's and the volume's density)
      water_pressure   p_water = p_v      (the spray valve upstream is the resistance)
      outlet_pressure  p_out = p_v
      temperature      T = T(p_v, h_v)    (signal output T_out)

    At steady state h_v = (m_steam h_steam + m_water h_water)/(m_steam + m_water).
    The outlet and the water inlet are storage volumes: lead them to a valve or
    another resistance.

    Phase mode (IF97 water, ``phase_switches``, default on): the volume keeps its phase
    (liquid, two-phase, vapour) as a discrete mode and is evaluated on that branch
    between located crossings of the saturation lines, as a pipe volume
    (``dnasim.library.submodels.channel``, "Phase modes"). Without it, the steam of a line
    whose flow has stopped (turbine valve shut) cooled by the spray to saturation put
    the kink of rho(p, h) at h'' inside a step, and Newton failed there
    (tests/field/superheater_turbine_closed.toml stopped at 67.7 s, h_v 0.1 kJ/kg
    above h'' at 130 bar).
    """

    PARAMS = (
        Param("V", "m3", doc="volume", min=0.0),
        Param("k", "1/m4", doc="friction coefficient of the steam inlet: dp = k m|m|/rho", min=0.0),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param(
            "m_reg", "kg/s", None, "friction regularisation flow (default 1e-2 m_nominal)", min=0.0
        ),
        Param(
            "phase_switches",
            "1",
            True,
            "keep the volume's phase as a discrete mode between located crossings of the "
            "saturation lines (IF97 water; see dnasim.library.submodels.channel)",
            kind="bool",
        ),
        Param("p0", "Pa", None, "initial pressure (given start)", min=0.0),
        Param("T0", "K", None, "initial temperature (given start)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort(
            "steam_in", "inlet", "m_steam", "resistance", "superheated steam in (with friction)"
        ),
        FluidPort(
            "water_in", "inlet", "m_water", "storage", "spray water in (pressure = volume pressure)"
        ),
        FluidPort("outlet", "outlet", "m_out", "storage", "mixed steam out (pressure = volume's)"),
    )
    SIGNAL_OUTPUTS = (SignalPort("T_out", "K", "outlet temperature", variable="T"),)

    def setup(self):
        mn = self.params["m_nominal"]
        self.m_reg = self.params["m_reg"] if self.params["m_reg"] is not None else M_REG_REL * mn
        self._props = PropertyArrays()

    def fluid_ports(self):
        eps = self.m_eps
        steam_role = "resistance" if self.params["k"] > 0 else "storage"
        return [
            FluidPort(
                "steam_in",
                "inlet",
                "m_steam",
                steam_role,
                h_out="h_v",
                pressure_param="k",
                m_eps=eps,
            ),
            FluidPort("water_in", "inlet", "m_water", "storage", h_out="h_v", m_eps=eps),
            FluidPort("outlet", "outlet", "m_out", "storage", h_out="h_v", m_eps=eps),
        ]

    def variables(self):
        mn = self.params["m_nominal"]
        M_nom = self.params["V"] * 1e-3
        return [
            Variable("m_steam", "kg/s", mn, doc="steam flow in"),
            Variable("m_water", "kg/s", 0.1 * mn, doc="spray water flow in"),
            Variable("m_out", "kg/s", mn, doc="flow out"),
            Variable("M", "kg", M_nom, doc="fluid mass", min=0.0),
            Variable("U", "J", M_nom * 1e3, doc="fluid internal energy"),
            Variable("p_v", "Pa", 1e5, doc="pressure of the volume"),
            Variable("h_v", "J/kg", 1e5, doc="specific enthalpy of the volume"),
            Variable("T", "K", 300.0, doc="temperature of the volume (outlet temperature)"),
        ]

    def equations(self):
        """The equations of the class doc (their residuals: ``row_values``)."""
        flows = ("m_steam", "m_water", "m_out")
        return [
            Equation(
                "mass", y=flows, yp=("M",), unit="kg/s", doc="dM/dt = m_steam + m_water - m_out"
            ),
            Equation(
                "energy",
                y=flows + ("steam_in.h", "water_in.h", "outlet.h", "h_v"),
                yp=("U",),
                unit="W",
                doc="dU/dt = E_in(m_steam) + E_in(m_water) + E_in(-m_out)",
            ),
            Equation("density", y=("M", "p_v", "h_v"), unit="kg", doc="M = V rho(p_v, h_v)"),
            Equation(
                "internal_energy", y=("U", "M", "p_v", "h_v"), unit="J", doc="U = M u(p_v, h_v)"
            ),
            Equation(
                "steam_friction",
                y=("steam_in.p", "steam_in.h", "p_v", "h_v", "m_steam"),
                unit="Pa",
                doc="p_steam - p_v = k m_steam sqrt(m_steam^2 + m_reg^2) / rho_f",
            ),
            Equation("water_pressure", y=("water_in.p", "p_v"), unit="Pa", doc="p_water = p_v"),
            Equation("outlet_pressure", y=("outlet.p", "p_v"), unit="Pa", doc="p_out = p_v"),
            Equation("temperature", y=("T", "p_v", "h_v"), unit="K", doc="T = T(p_v, h_v)"),
        ]

    #: the names ``row_values`` reads from y, in its order
    ROW_READS = (
        "m_steam",
        "m_water",
        "m_out",
        "M",
        "U",
        "p_v",
        "h_v",
        "T",
        "steam_in.p",
        "steam_in.h",
        "water_in.p",
        "water_in.h",
        "outlet.p",
        "outlet.h",
    )

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``)."""
        return self.ROW_READS, ("M", "U")

    def row_values(self, t, v, vp, modes):
        """The equations of the class doc, in their order, their residuals: mass [kg/s],
        energy [W], density [kg], internal_energy [J], steam_friction [Pa],
        water_pressure [Pa], outlet_pressure [Pa], temperature [K]. One property call
        (``PropertyArrays``) for the steam node [0] and the volume [1]."""
        m_s, m_w, m_o, M, U, p_v, h_v, T, p_s, h_s, p_w, h_w, p_o, h_o = v
        dM, dU = vp
        mode = modes.get("phase") if self._phase_modes_on() else None
        branch = None if mode is None else np.array([0, mode[0]], dtype=np.int64)
        T_st, rho, u = self._props(self.medium, np.array([p_s, p_v]), np.array([h_s, h_v]), branch)
        eps = self.m_eps
        E_in = (
            energy_in(m_s, h_s, h_v, eps)
            + energy_in(m_w, h_w, h_v, eps)
            + energy_in(-m_o, h_o, h_v, eps)
        )
        rho_f = upwind_mean(m_s, rho[0], rho[1], eps)
        return [
            dM - (m_s + m_w - m_o),
            dU - E_in,
            M - self.params["V"] * rho[1],
            U - M * u[1],
            p_s - p_v - friction_dp(self.params["k"], m_s, rho_f, self.m_reg),
            p_w - p_v,
            p_o - p_v,
            T - T_st[1],
        ]

    def design_values(self, t0, x):
        return {"m": x["m_out"]}

    # ------------------------------------------------------------ phase mode
    def _phase_modes_on(self) -> bool:
        """The volume's phase kept as a discrete mode (class doc): IF97 water."""
        return bool(self.params["phase_switches"]) and has_phase_branches(self.medium)

    def switches(self):
        if not self._phase_modes_on():
            return []
        medium, V = self.medium, self.params["V"]

        def g(t, x, xp):
            mode = x.modes.get("phase")
            if mode is None:
                return np.ones(2)
            return phase_switch_values(medium, mode, x["p_v"], x["h_v"], x["M"], x["U"], V)

        def action(t, x, xp, which):
            x.modes["phase"] = toggle_phase_modes(x.modes["phase"], which)

        return [
            Switch(
                "phase",
                g,
                direction=-1,
                action=action,
                size=2,
                restart=True,
                names=["h_v saturated liquid", "h_v saturated vapour"],
                rearm=True,
                doc="phase mode of the volume: liquid <-> two-phase at h', two-phase <-> "
                "vapour at h''",
            )
        ]

    def init_discrete_state(self, t0, x, xp) -> bool:
        if not self._phase_modes_on():
            return False
        mode = initial_phase_modes(self.medium, [x["p_v"]], [x["h_v"]])
        old = x.modes.get("phase")
        x.modes["phase"] = mode
        return old is None or not np.array_equal(old, mode)

    def guess_nodes(self, t0):
        P = self.params
        if P["p0"] is not None and P["T0"] is not None:
            return {"outlet": (P["p0"], self.medium.h_pT(P["p0"], P["T0"]))}
        return {}

    def initial_guess(self, t0, x):
        P = self.params
        p = P["p0"] if P["p0"] is not None else x["outlet.p"]
        h = self.medium.h_pT(p, P["T0"]) if P["T0"] is not None else x["outlet.h"]
        self._fill_guess(x, p, h)

    def steady_guess(self, t0, x):
        """The steady start's guess (``Component.steady_guess``): without T0, the volume
        holds the mix of its guessed inflows, h_v = (m_steam h_steam + m_water h_water) /
        (m_steam + m_water) [J/kg] (the steady state of the class doc)."""
        if self.params["T0"] is not None:
            return
        ms, mw = x["m_steam"], x["m_water"]
        if not ms + mw > 0.0:  # no inflow guessed (or a reversed one): nothing to mix
            return
        h = (ms * x["steam_in.h"] + mw * x["water_in.h"]) / (ms + mw)
        self._fill_guess(x, x["p_v"], h)

    def _fill_guess(self, x, p, h):
        """Every guess from the volume's p [Pa] and h [J/kg]."""
        P = self.params
        x["outlet.p"], x["outlet.h"] = p, h
        x["p_v"], x["h_v"] = p, h
        x["water_in.p"] = p
        T, rho, u = properties(self.medium, [p], [h])
        x["M"] = P["V"] * rho[0]
        x["U"] = x["M"] * u[0]
        x["T"] = T[0]
        x["m_steam"] = P["m_nominal"]
        x["m_water"] = 0.05 * P["m_nominal"]
        x["m_out"] = 1.05 * P["m_nominal"]
