"""Boundary conditions: a prescribed pressure or a prescribed mass flow.

Each boundary has one fluid port ``port``. With an enthalpy (``h``) or a
temperature (``T``) given it is a *source*: fluid enters the plant at the given
state, the port is an outlet and fixes its node's enthalpy. Without them it is a
*sink*: fluid leaves the plant, the port is an inlet. Values may be functions of
time (``dnasim.timefunctions``); their breakpoints become solver tstops.

Both boundaries integrate what passes them, for balances:
M_passed [kg] = integral of m dt and H_passed [J] = integral of m h dt, where
m is positive in the design direction (into the plant for a source, out of it
for a sink) and h is the node enthalpy.
"""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Component, Equation, FluidPort, Param, Variable
from dnasim.errors import PlantError

_STATE_PARAMS = (
    Param(
        "h",
        "J/kg",
        None,
        "enthalpy of the fluid entering the plant (makes it a source)",
        time_function=True,
    ),
    Param(
        "T",
        "K",
        None,
        "temperature of the fluid entering the plant (makes it a source)",
        min=0.0,
        time_function=True,
    ),
    Param(
        "medium",
        "1",
        None,
        "fluid name, e.g. 'Air', 'Water' (default: from the network)",
        kind="string",
    ),
    Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
)


class _Boundary(Component):
    REGISTER = False

    def setup(self):
        if self.params["h"] is not None and self.params["T"] is not None:
            raise PlantError(f"component '{self.name}': give either 'h' or 'T', not both")
        self.is_source = self.params["h"] is not None or self.params["T"] is not None

    def fluid_ports(self):
        role = "outlet" if self.is_source else "inlet"
        return [FluidPort("port", role, "m", self.PRESSURE_ROLE, "source (h or T given) or sink")]

    def variables(self):
        m_nom = self.params["m_nominal"]
        return [
            Variable(
                "m", "kg/s", m_nom, doc="mass flow, into the plant (source) or out of it (sink)"
            ),
            Variable("M_passed", "kg", m_nom, doc="integral of m dt", accumulator=True),
            Variable("H_passed", "J", m_nom * 1e5, doc="integral of m h dt", accumulator=True),
        ]

    def source_h(self, t, x):
        """Enthalpy of the entering fluid [J/kg] (h given, or h(p_node, T))."""
        if self.params["h"] is not None:
            return self.param_at("h", t)
        return self.medium.h_pT(x["port.p"], self.param_at("T", t))

    def accumulator_equations(self):
        return [
            Equation("mass_passed", y=("m",), yp=("M_passed",), doc="dM_passed/dt = m"),
            Equation(
                "energy_passed", y=("m", "port.h"), yp=("H_passed",), doc="dH_passed/dt = m h"
            ),
        ]

    def accumulator_residuals(self, x, xp):
        return [xp["M_passed"] - x["m"], xp["H_passed"] - x["m"] * x["port.h"]]


class PressureBoundary(_Boundary):
    """Prescribed pressure (and, for a source, enthalpy or temperature).

      pressure       p_node = p(t)
      enthalpy       h_node = h(t), or h_node = h(p(t), T(t))        (source only)
      mass_passed    dM_passed/dt = m
      energy_passed  dH_passed/dt = m h_node
    The flow m follows from the rest of the network.
    """

    PRESSURE_ROLE = "fixed"
    PARAMS = (Param("p", "Pa", doc="pressure", min=0.0, time_function=True),) + _STATE_PARAMS
    FLUID_PORTS = (
        FluidPort(
            "port", "outlet|inlet", "m", "fixed", "outlet if h or T given (source), else inlet"
        ),
    )

    def equations(self):
        eqs = [Equation("pressure", y=("port.p",))]
        if self.is_source:
            eqs.append(Equation("enthalpy", y=("port.h",)))
        return eqs + self.accumulator_equations()

    def residual(self, t, x, xp):
        r = [x["port.p"] - self.param_at("p", t)]
        if self.is_source:
            if self.params["h"] is not None:
                r.append(x["port.h"] - self.param_at("h", t))
            else:
                r.append(
                    x["port.h"] - self.medium.h_pT(self.param_at("p", t), self.param_at("T", t))
                )
        return np.array(r + self.accumulator_residuals(x, xp))

    def guess_nodes(self, t0):
        p = self.param_at("p", t0)
        if not self.is_source:
            return {"port": (p, None)}
        if self.params["h"] is not None:
            return {"port": (p, self.param_at("h", t0))}
        return {"port": (p, self.medium.h_pT(p, self.param_at("T", t0)))}

    def initial_guess(self, t0, x):
        x["m"] = self.params["m_nominal"]
        x["M_passed"] = 0.0
        x["H_passed"] = 0.0


class MassFlowBoundary(_Boundary):
    """Prescribed mass flow (and, for a source, enthalpy or temperature).

      flow           m = m(t)          (into the plant for a source, out of it for a sink)
      enthalpy       h_node = h(t), or h_node = h(p_node, T(t))      (source only)
      mass_passed    dM_passed/dt = m
      energy_passed  dH_passed/dt = m h_node
    The node pressure follows from the rest of the network.
    """

    PRESSURE_ROLE = "none"
    PARAMS = (Param("m", "kg/s", doc="mass flow", time_function=True),) + _STATE_PARAMS
    FLUID_PORTS = (
        FluidPort(
            "port", "outlet|inlet", "m", "none", "outlet if h or T given (source), else inlet"
        ),
    )

    def equations(self):
        eqs = [Equation("flow", y=("m",))]
        if self.is_source:
            dep = ("port.h",) if self.params["h"] is not None else ("port.h", "port.p")
            eqs.append(Equation("enthalpy", y=dep))
        return eqs + self.accumulator_equations()

    def residual(self, t, x, xp):
        r = [x["m"] - self.param_at("m", t)]
        if self.is_source:
            r.append(x["port.h"] - self.source_h(t, x))
        return np.array(r + self.accumulator_residuals(x, xp))

    def guess_nodes(self, t0):
        if not self.is_source or self.params["h"] is None:
            return {}
        return {"port": (None, self.param_at("h", t0))}

    def initial_guess(self, t0, x):
        x["m"] = self.param_at("m", t0)
        x["M_passed"] = 0.0
        x["H_passed"] = 0.0
        if self.is_source and self.params["h"] is None:
            x["port.h"] = self.medium.h_pT(x["port.p"], self.param_at("T", t0))
