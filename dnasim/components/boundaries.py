"""Boundary conditions: a prescribed pressure or a prescribed mass flow.

Each boundary has one fluid port ``port``; its flow ``m`` [kg/s] is positive
INTO the plant (out of the boundary), always: a boundary that takes fluid out of
the plant has m < 0. A boundary is source and sink at once:

* fluid flowing into the plant carries the supply enthalpy h_supply [J/kg]:
  ``h`` given, or h(p, T) with ``T`` given (p the boundary's pressure, or the
  node pressure for a mass-flow boundary);
* fluid flowing out of the plant is absorbed, whatever its state.

A boundary with neither ``h`` nor ``T`` is a sink only. If flow ever goes into the
plant through it (m > 1e-3 m_nominal), a terminal switch stops the run with a
message naming the boundary and the time: give T or h for the reverse inflow.
No temperature is invented.

Energy flow into the plant (``physics.energy_in`` seen from the plant side):

    E = w(m) h_supply - w(-m) h_node        [W]

Both boundaries integrate what passes them, for balances (positive INTO the
plant, always): M_passed [kg] = integral of m dt, H_passed [J] = integral of E dt.
Values may be functions of time (``dnasim.timefunctions``); their breakpoints
become solver tstops.
"""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Component, Equation, FluidPort, Param, Switch, Variable
from dnasim.components.physics import M_EPS_REL, energy_in
from dnasim.errors import PlantError

#: a sink-only boundary stops the run when more than this fraction of m_nominal
#: flows into the plant through it: the half-width of the upwind regularisation
#: band (``physics.M_EPS_REL``), inside which the flow direction does not decide
#: the enthalpy anyway. (1e-6 was tried: the solver's flow errors near zero flow,
#: at the end of a line draining to a sink, exceeded it.)
REVERSE_INFLOW_TOL = M_EPS_REL

_STATE_PARAMS = (
    Param(
        "h",
        "J/kg",
        None,
        "enthalpy of fluid flowing into the plant (source; also for reverse inflow at a sink)",
        time_function=True,
    ),
    Param(
        "T",
        "K",
        None,
        "temperature of fluid flowing into the plant (source; also for reverse inflow at a sink)",
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
        self.has_supply = self.params["h"] is not None or self.params["T"] is not None

    def fluid_ports(self):
        h_out = "h_supply" if self.has_supply else "port.h"
        return [
            FluidPort(
                "port",
                "outlet",
                "m",
                self.PRESSURE_ROLE,
                "m > 0 into the plant",
                h_out=h_out,
                h_source=self.has_supply,
                m_eps=self.m_eps,
            )
        ]

    def variables(self):
        m_nom = self.params["m_nominal"]
        out = [Variable("m", "kg/s", m_nom, doc="mass flow into the plant (< 0: out of it)")]
        if self.has_supply:
            out.append(
                Variable("h_supply", "J/kg", 1e5, doc="enthalpy of fluid entering the plant")
            )
        out += [
            Variable(
                "M_passed", "kg", m_nom, doc="integral of m dt (into the plant)", accumulator=True
            ),
            Variable(
                "H_passed",
                "J",
                m_nom * 1e5,
                doc="integral of E dt (into the plant)",
                accumulator=True,
            ),
        ]
        return out

    def supply_h(self, t, p):
        """Enthalpy of the entering fluid [J/kg] (h given, or h(p, T))."""
        if self.params["h"] is not None:
            return self.param_at("h", t)
        return self.medium.h_pT(p, self.param_at("T", t))

    def supply_equations(self, p_dep):
        if not self.has_supply:
            return []
        dep = ("h_supply",) if self.params["h"] is not None else ("h_supply",) + p_dep
        return [Equation("supply", y=dep, doc="h_supply = h or h(p, T)")]

    def energy_flow(self, x):
        """E [W] into the plant (see the module doc)."""
        h_own = x["h_supply"] if self.has_supply else x["port.h"]
        # energy_in gives the flow into the boundary (flow -m into it); the plant
        # receives minus that
        return -float(energy_in(-x["m"], x["port.h"], h_own, self.m_eps))

    def accumulator_equations(self):
        dep = ("m", "port.h") + (("h_supply",) if self.has_supply else ())
        return [
            Equation("mass_passed", y=("m",), yp=("M_passed",), doc="dM_passed/dt = m"),
            Equation("energy_passed", y=dep, yp=("H_passed",), doc="dH_passed/dt = E"),
        ]

    def accumulator_residuals(self, x, xp):
        return [xp["M_passed"] - x["m"], xp["H_passed"] - self.energy_flow(x)]

    def switches(self):
        if self.has_supply:
            return []
        tol = REVERSE_INFLOW_TOL * self.params["m_nominal"]
        name = self.name
        kind = type(self).__name__

        def message(t):
            return (
                f"boundary '{name}' ({kind}): flow reversed into the plant at t = {t:.6g} s, "
                "but it is a sink only; give T or h for the reverse inflow"
            )

        return [
            Switch(
                "reverse_inflow",
                lambda t, x, xp: tol - x["m"],
                direction=-1,
                terminal=True,
                message=message,
                doc="m > tol: fluid would enter the plant with no given state",
            )
        ]

    def initial_guess(self, t0, x):
        x["M_passed"] = 0.0
        x["H_passed"] = 0.0
        if self.has_supply:
            x["h_supply"] = self.supply_h(t0, self.supply_pressure(t0, x))

    def flow_guess(self):
        return self.params["m_nominal"] if self.has_supply else -self.params["m_nominal"]


class PressureBoundary(_Boundary):
    """Prescribed pressure; with h or T given also the state of fluid entering the plant.

      pressure       p_node = p(t)
      supply         h_supply = h(t), or h(p(t), T(t))          (h or T given)
      mass_passed    dM_passed/dt = m                            (m > 0 into the plant)
      energy_passed  dH_passed/dt = w(m) h_supply - w(-m) h_node
    The flow m follows from the rest of the network, in either direction.
    """

    PRESSURE_ROLE = "fixed"
    PARAMS = (Param("p", "Pa", doc="pressure", min=0.0, time_function=True),) + _STATE_PARAMS
    FLUID_PORTS = (
        FluidPort("port", "outlet", "m", "fixed", "m > 0 into the plant; h or T: inflow state"),
    )

    def supply_pressure(self, t, x):
        return self.param_at("p", t)

    def equations(self):
        return (
            [Equation("pressure", y=("port.p",))]
            + self.supply_equations(())
            + self.accumulator_equations()
        )

    def residual(self, t, x, xp):
        r = [x["port.p"] - self.param_at("p", t)]
        if self.has_supply:
            r.append(x["h_supply"] - self.supply_h(t, self.param_at("p", t)))
        return np.array(r + self.accumulator_residuals(x, xp))

    def guess_nodes(self, t0):
        p = self.param_at("p", t0)
        if not self.has_supply:
            return {"port": (p, None)}
        return {"port": (p, self.supply_h(t0, p))}

    def initial_guess(self, t0, x):
        x["m"] = self.flow_guess()
        super().initial_guess(t0, x)


class MassFlowBoundary(_Boundary):
    """Prescribed mass flow into the plant (m < 0: out of it); with h or T given also
    the state of fluid entering the plant.

      flow           m = m(t)
      supply         h_supply = h(t), or h(p_node, T(t))         (h or T given)
      mass_passed    dM_passed/dt = m
      energy_passed  dH_passed/dt = w(m) h_supply - w(-m) h_node
    The node pressure follows from the rest of the network.
    """

    PRESSURE_ROLE = "none"
    PARAMS = (
        Param(
            "m", "kg/s", doc="mass flow into the plant (negative: out of it)", time_function=True
        ),
    ) + _STATE_PARAMS
    FLUID_PORTS = (
        FluidPort("port", "outlet", "m", "none", "m > 0 into the plant; h or T: inflow state"),
    )

    def supply_pressure(self, t, x):
        return x["port.p"]

    def equations(self):
        return (
            [Equation("flow", y=("m",))]
            + self.supply_equations(("port.p",))
            + self.accumulator_equations()
        )

    def residual(self, t, x, xp):
        r = [x["m"] - self.param_at("m", t)]
        if self.has_supply:
            r.append(x["h_supply"] - self.supply_h(t, x["port.p"]))
        return np.array(r + self.accumulator_residuals(x, xp))

    def guess_nodes(self, t0):
        if not self.has_supply or self.params["h"] is None:
            return {}
        return {"port": (None, self.param_at("h", t0))}

    def initial_guess(self, t0, x):
        x["m"] = self.param_at("m", t0)
        super().initial_guess(t0, x)
        if self.has_supply and self.params["h"] is None and x["m"] > 0:
            x["port.h"] = x["h_supply"]
