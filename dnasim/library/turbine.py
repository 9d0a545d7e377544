"""SteamTurbine: Stodola's cone law and an isentropic efficiency (IF97 entropy)."""

from __future__ import annotations

import math

from dnasim.core.errors import PlantError, ResidualDomainError
from dnasim.media.isentropic import h_isentropic
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Param,
    SignalPort,
    Variable,
    flow_through_ports,
    shaft_work_equations,
)
from dnasim.model.physics import upwind_mean


class SteamTurbine(Component):
    """Steam turbine (a group of stages) between ``inlet`` and ``outlet``, no storage.

    Symbols: m [kg/s] mass flow (inlet -> outlet positive); p_in, h_in, p_out
    [Pa, J/kg] the node states; rho_in [kg/m3] inlet density; K_t [m2] the
    Stodola constant; eta [-] isentropic efficiency; h_s [J/kg] the isentropic
    outlet enthalpy; h_2 [J/kg] the outlet enthalpy.

      flow       m = K_t sqrt(rho_u/p_u) D / (D^2 + D_reg^2)^(1/4),   D = p_in^2 - p_out^2
                 (= K_t sqrt(p_in rho_in (1 - (p_out/p_in)^2)), Stodola's cone law, for
                 D >> D_reg = dp_reg (p_in + p_out); odd in D: reverse flow by the
                 same law with the ports exchanged; (rho/p)_u: smooth upwind by m of
                 rho_in/p_in and rho_out/p_out)
      expansion  h_2 = h_in - eta (h_in - h_s),   h_s = h(p_out, s(p_in, h_in))      [J/kg]
      power      P = w(m) (h_in - h_2)     (= m eta (h_in - h_s) for m > m_eps)      [W]
      work       dW/dt = P      (W [J]: work delivered over the run, for energy balances)

    K_t is given directly, or from a nominal point (``m_nominal``, ``p_in_nominal``,
    ``p_out_nominal`` and ``T_in_nominal`` or ``h_in_nominal``):
    K_t = m_nom / sqrt(p_in,nom rho(p_in,nom, h_in,nom) (1 - (p_out,nom/p_in,nom)^2)).

    The entropy and h(p, s) come from the port's medium (IF97 for water;
    ``dnasim.media.isentropic.h_ps``). Wet expansion is allowed: h_s and h_2 may
    lie in the two-phase region (the outlet quality is that of the outlet node).
    Fluid leaving through the outlet carries h_2; fluid leaving through the inlet
    (reverse flow) carries the outlet node's enthalpy, with no work exchanged.
    The energy flows at the ports and P balance exactly: E_in - E_out = P.

    Stages in series are turbines in series joined by nodes: each group has its
    own K_t and eta; a node between two groups needs no volume (the flow law of
    each group relates the node pressure to the flow, so the DAE stays index 1).
    An extraction is a Splitter or a second component at such a node.
    """

    PARAMS = (
        Param("K_t", "m2", None, "Stodola constant (otherwise from the nominal point)", min=0.0),
        Param("p_in_nominal", "Pa", None, "inlet pressure of the nominal point", min=0.0),
        Param("p_out_nominal", "Pa", None, "outlet pressure of the nominal point", min=0.0),
        Param("T_in_nominal", "K", None, "inlet temperature of the nominal point", min=0.0),
        Param("h_in_nominal", "J/kg", None, "inlet enthalpy of the nominal point (or T)"),
        Param("eta", "1", 0.85, "isentropic efficiency", min=0.0, max=1.0),
        Param(
            "dp_reg",
            "delta_Pa",
            100.0,
            "regularisation pressure difference near p_in = p_out",
            min=0.0,
        ),
        Param(
            "m_nominal",
            "kg/s",
            1.0,
            "nominal mass flow (the nominal point's; scales and tolerances)",
            min=0.0,
        ),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", "resistance", "live steam in"),
        FluidPort("outlet", "outlet", "m", "resistance", "exhaust (h_2 on forward flow)"),
    )
    SIGNAL_OUTPUTS = (SignalPort("P", "W", "power delivered to the shaft", variable="P"),)

    def setup(self):
        P = self.params
        self._K_t = P["K_t"]
        nominal = ("p_in_nominal", "p_out_nominal")
        if self._K_t is None:
            missing = [k for k in nominal if P[k] is None]
            if P["T_in_nominal"] is None and P["h_in_nominal"] is None:
                missing.append("T_in_nominal or h_in_nominal")
            if missing:
                raise PlantError(
                    f"component '{self.name}' (SteamTurbine): give K_t, or the nominal point "
                    f"m_nominal, p_in_nominal, p_out_nominal and T_in_nominal (or "
                    f"h_in_nominal); missing: {', '.join(missing)}"
                )
            if not P["p_out_nominal"] < P["p_in_nominal"]:
                raise PlantError(
                    f"component '{self.name}' (SteamTurbine): p_out_nominal must be below "
                    "p_in_nominal"
                )
        if P["T_in_nominal"] is not None and P["h_in_nominal"] is not None:
            raise PlantError(
                f"component '{self.name}' (SteamTurbine): give T_in_nominal or h_in_nominal, "
                "not both"
            )

    @property
    def K_t(self) -> float:
        """Stodola constant [m2] (from the nominal point on first use: needs the medium)."""
        if self._K_t is None:
            self._K_t = self._nominal_K_t()
        return self._K_t

    def _nominal_K_t(self) -> float:
        """K_t [m2] from the nominal point (m_nominal, p_in_nominal, p_out_nominal and
        T_in_nominal or h_in_nominal); a nominal inlet state outside the medium's range
        is a ``PlantError`` naming the key."""
        P = self.params
        p1, p2 = P["p_in_nominal"], P["p_out_nominal"]
        h1 = P["h_in_nominal"]
        key = "h_in_nominal" if h1 is not None else "T_in_nominal"
        try:
            if h1 is None:
                h1 = self.medium.h_pT(p1, P["T_in_nominal"])
            rho1 = self.medium.state(p1, h1).rho
        except ResidualDomainError as exc:  # a parameter's state: it never changes
            given = (
                f"T_in_nominal = {P['T_in_nominal']:.6g} K"
                if key == "T_in_nominal"
                else f"h_in_nominal = {h1:.6g} J/kg"
            )
            raise PlantError(
                f"component '{self.name}' (SteamTurbine), key '{key}': the nominal inlet "
                f"state (p_in_nominal = {p1 / 1e5:.6g} bar, {given}) is outside the "
                f"medium's range: {exc}"
            ) from None
        return P["m_nominal"] / math.sqrt(p1 * rho1 * (1.0 - (p2 / p1) ** 2))

    def fluid_ports(self):
        return flow_through_ports(self.m_eps, "h_2")

    def variables(self):
        mn = self.params["m_nominal"]
        return [
            Variable("m", "kg/s", mn, doc="mass flow, inlet -> outlet"),
            Variable("h_2", "J/kg", 1e6, doc="enthalpy of the steam leaving at the outlet"),
            Variable("P", "W", max(mn * 1e5, 1.0), doc="power delivered to the shaft"),
            Variable(
                "W",
                "J",
                max(mn * 1e5, 1.0),
                doc="work delivered to the shaft, integral of P dt",
                accumulator=True,
            ),
        ]

    def equations(self):
        nodes = ("inlet.p", "inlet.h", "outlet.p", "outlet.h")
        return [
            Equation(
                "flow",
                y=("m",) + nodes,
                unit="kg/s",
                doc="m = K_t sqrt(p_in rho_in (1 - (p_out/p_in)^2)) (regularised, odd)",
                residual=lambda t, x, xp: x["m"] - self.flow(x),
            ),
            Equation(
                "expansion",
                y=("h_2", "inlet.p", "inlet.h", "outlet.p"),
                unit="J/kg",
                doc="h_2 = h_in - eta (h_in - h(p_out, s_in))",
                residual=lambda t, x, xp: x["h_2"] - self.outlet_enthalpy(x),
            ),
        ] + shaft_work_equations(self, "h_2", "inlet.h")

    # --------------------------------------------------------------- physics
    def flow(self, x, m=None):
        """Stodola flow [kg/s] at the node states in x (upwind density by m)."""
        medium = self.medium
        p1, p2 = x["inlet.p"], x["outlet.p"]
        r1 = medium.state(p1, x["inlet.h"]).rho / p1
        r2 = medium.state(p2, x["outlet.h"]).rho / p2
        m = x["m"] if m is None else m
        ratio = float(upwind_mean(m, r1, r2, self.m_eps))
        D = p1 * p1 - p2 * p2
        D_reg = self.params["dp_reg"] * (p1 + p2)
        return self.K_t * math.sqrt(ratio) * D / (D * D + D_reg * D_reg) ** 0.25

    def outlet_enthalpy(self, x):
        """h_2 [J/kg] = h_in - eta (h_in - h_s)."""
        h1 = x["inlet.h"]
        h_s = h_isentropic(self.medium, x["inlet.p"], h1, x["outlet.p"])
        return h1 - self.params["eta"] * (h1 - h_s)

    def design_values(self, t0, x):
        """Shaft power into the fluid (minus the power delivered, P) [W], eta [-]."""
        return {"m": x["m"], "power": -x["P"], "efficiency": self.params["eta"]}

    def guess_nodes(self, t0):
        P = self.params
        out = {}
        if P["p_in_nominal"] is not None:
            out["inlet"] = (P["p_in_nominal"], None)
        if self._K_t is None and P["p_out_nominal"] is not None:
            out["outlet"] = (P["p_out_nominal"], None)
            if self.medium is not None:
                self._nominal_K_t()  # the nominal point's state, checked before any numerics
        return out

    def initial_guess(self, t0, x):
        x["m"] = self.flow(x, m=self.params["m_nominal"])
        try:
            x["h_2"] = self.outlet_enthalpy(x)
        except Exception:
            x["h_2"] = x["inlet.h"]
        x["P"] = max(x["m"], 0.0) * (x["inlet.h"] - x["h_2"])
        x["W"] = 0.0
