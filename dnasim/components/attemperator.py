"""Attemperator: a mixing volume where spray water cools superheated steam."""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Component, Equation, FluidPort, Param, SignalPort, Variable
from dnasim.components.physics import friction_dp, properties


class Attemperator(Component):
    """Fully mixed control volume V with a steam inlet, a spray-water inlet and an outlet.

    The volume's state is the outlet node (p, h). Symbols: m_steam, m_water,
    m_out [kg/s]; M [kg], U [J] fluid mass and internal energy; T [K] outlet temperature.

      mass             dM/dt = m_steam + m_water - m_out
      energy           dU/dt = m_steam h_steam + m_water h_water - m_out h
      density          M = V rho(p, h)
      internal_energy  U = M u(p, h)
      steam_friction   p_steam - p = k m_steam sqrt(m_steam^2 + m_reg^2) / rho_steam
      water_pressure   p_water = p      (the spray valve upstream is the resistance)
      temperature      T = T(p, h)      (signal output T_out)

    At steady state h = (m_steam h_steam + m_water h_water)/(m_steam + m_water).
    The outlet is a storage volume: lead it to a valve or another resistance.
    """

    PARAMS = (
        Param("V", "m3", doc="volume", min=0.0),
        Param("k", "1/m4", doc="friction coefficient of the steam inlet: dp = k m|m|/rho", min=0.0),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param(
            "m_reg", "kg/s", None, "friction regularisation flow (default 1e-4 m_nominal)", min=0.0
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
        FluidPort(
            "outlet", "outlet", "m_out", "storage", "mixed steam out; its node is the volume state"
        ),
    )
    SIGNAL_OUTPUTS = (SignalPort("T_out", "K", "outlet temperature", variable="T"),)

    def setup(self):
        mn = self.params["m_nominal"]
        self.m_reg = self.params["m_reg"] if self.params["m_reg"] is not None else 1e-4 * mn

    def variables(self):
        mn = self.params["m_nominal"]
        M_nom = self.params["V"] * 1e-3
        return [
            Variable("m_steam", "kg/s", mn, doc="steam flow in"),
            Variable("m_water", "kg/s", 0.1 * mn, doc="spray water flow in"),
            Variable("m_out", "kg/s", mn, doc="flow out"),
            Variable("M", "kg", M_nom, doc="fluid mass"),
            Variable("U", "J", M_nom * 1e3, doc="fluid internal energy"),
            Variable("T", "K", 300.0, doc="outlet temperature"),
        ]

    def equations(self):
        return [
            Equation("mass", y=("m_steam", "m_water", "m_out"), yp=("M",)),
            Equation(
                "energy",
                y=("m_steam", "m_water", "m_out", "steam_in.h", "water_in.h", "outlet.h"),
                yp=("U",),
            ),
            Equation("density", y=("M", "outlet.p", "outlet.h")),
            Equation("internal_energy", y=("U", "M", "outlet.p", "outlet.h")),
            Equation("steam_friction", y=("steam_in.p", "steam_in.h", "outlet.p", "m_steam")),
            Equation("water_pressure", y=("water_in.p", "outlet.p")),
            Equation("temperature", y=("T", "outlet.p", "outlet.h")),
        ]

    def residual(self, t, x, xp):
        T, rho, u = properties(
            self.medium, [x["steam_in.p"], x["outlet.p"]], [x["steam_in.h"], x["outlet.h"]]
        )
        ms, mw, mo = x["m_steam"], x["m_water"], x["m_out"]
        h = x["outlet.h"]
        return np.array(
            [
                xp["M"] - (ms + mw - mo),
                xp["U"] - (ms * x["steam_in.h"] + mw * x["water_in.h"] - mo * h),
                x["M"] - self.params["V"] * rho[1],
                x["U"] - x["M"] * u[1],
                x["steam_in.p"]
                - x["outlet.p"]
                - friction_dp(self.params["k"], ms, rho[0], self.m_reg),
                x["water_in.p"] - x["outlet.p"],
                x["T"] - T[1],
            ]
        )

    def guess_nodes(self, t0):
        P = self.params
        if P["p0"] is not None and P["T0"] is not None:
            return {"outlet": (P["p0"], self.medium.h_pT(P["p0"], P["T0"]))}
        return {}

    def initial_guess(self, t0, x):
        P = self.params
        p = P["p0"] if P["p0"] is not None else x["outlet.p"]
        h = self.medium.h_pT(p, P["T0"]) if P["T0"] is not None else x["outlet.h"]
        x["outlet.p"], x["outlet.h"] = p, h
        x["water_in.p"] = p
        T, rho, u = properties(self.medium, [p], [h])
        x["M"] = P["V"] * rho[0]
        x["U"] = x["M"] * u[0]
        x["T"] = T[0]
        x["m_steam"] = P["m_nominal"]
        x["m_water"] = 0.0
        x["m_out"] = P["m_nominal"]
