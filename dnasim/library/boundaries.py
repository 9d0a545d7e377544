"""Boundary conditions: a prescribed pressure or a prescribed mass flow.

Each boundary has one fluid port ``port``; its flow ``m`` [kg/s] is positive
INTO the plant (out of the boundary), always: a boundary that takes fluid out of
the plant has m < 0. A boundary is source and sink at once:

* fluid flowing into the plant carries the supply enthalpy h_supply [J/kg],
  given in one of three ways (p is the boundary's pressure, or the node pressure
  for a mass-flow boundary):
    ``h``  h_supply = h(t)                                         [J/kg]
    ``T``  h_supply = h(p, T(t)), single phase only               [K]
    ``x``  h_supply = h_liq(p) + x(t) (h_vap(p) - h_liq(p))       [-, 0..1]
           (``medium.h_px``: a saturated supply, condensable media below the
           critical pressure);
* fluid flowing out of the plant is absorbed, whatever its state.

(p, T) does not fix a state at the saturation temperature T_sat(p): there h(p, T)
jumps by the latent heat (1 MJ/kg at 150 bar). A boundary given by ``T`` in a
condensable medium therefore has a terminal switch g = T(t) - T_sat(p) [K] (T_c
above the critical pressure): when the given T reaches T_sat(p) the run stops, at
the located time, with a message naming the boundary and the state ("boundary
'water' (PressureBoundary): at t = 98.85 s T = 342.16 °C is the saturation
temperature at 150 bar; ... give h or quality x for a saturated supply"). It
stops rather than restarting with the other phase's h because that jump is not
physics: a feed heated through saturation passes through the two-phase states
at constant T_sat (give h or x to model that), and a silent latent-heat step in
the supply would be an artefact of how the supply was written down. Any other
state the medium refuses (a T or x out of range, x for a gas) raises
:class:`BoundaryStateError`, a ``ResidualDomainError`` naming the boundary.

A boundary with none of ``h``, ``T``, ``x`` is a sink only. If flow ever goes into the
plant through it (m > 1e-3 m_nominal), a terminal switch stops the run with a
message naming the boundary and the time: give T or h for the reverse inflow.
No temperature is invented.

Energy flow into the plant (``physics.energy_in`` seen from the plant side):

    E = w(m) h_supply - w(-m) h_node        [W]

Both boundaries integrate what passes them, for balances (positive INTO the
plant, always): M_passed [kg] = integral of m dt, H_passed [J] = integral of E dt.
Values may be functions of time (``dnasim.core.timefunctions``); their breakpoints
become solver tstops.
"""

from __future__ import annotations

import numpy as np

from dnasim.core.errors import PlantError, ResidualDomainError
from dnasim.media.errors import PropertyError
from dnasim.model.component import (
    Component,
    Equation,
    FluidPort,
    Param,
    SignalPort,
    Switch,
    Variable,
)
from dnasim.model.physics import M_EPS_REL, energy_in, is_condensable

#: a sink-only boundary stops the run when more than this fraction of m_nominal
#: flows into the plant through it: the half-width of the upwind regularisation
#: band (``physics.M_EPS_REL``), inside which the flow direction does not decide
#: the enthalpy anyway. (1e-6 was tried: the solver's flow errors near zero flow,
#: at the end of a line draining to a sink, exceeded it.)
REVERSE_INFLOW_TOL = M_EPS_REL

#: the ways of giving the supply state (one of them, or none for a sink only)
SUPPLY_PARAMS = ("h", "T", "x")


class BoundaryStateError(ResidualDomainError):
    """The supply state of a boundary cannot be evaluated; the message names the
    boundary, the time and the state. A ``ResidualDomainError``: inside a Newton
    iteration the solver cuts the step, and reports it when it persists."""


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
        "x",
        "1",
        None,
        "vapour quality of fluid flowing into the plant, 0 (saturated liquid) to 1 (saturated "
        "vapour): a saturated supply at the boundary's pressure (condensable media)",
        min=0.0,
        max=1.0,
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
        given = [k for k in SUPPLY_PARAMS if self.params[k] is not None]
        if len(given) > 1:
            raise PlantError(
                f"component '{self.name}': give one of 'h', 'T' or 'x' for the supply state, "
                f"not {' and '.join(repr(k) for k in given)}"
            )
        self.supply_by = given[0] if given else None
        self.has_supply = self.supply_by is not None

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
        """Enthalpy of the entering fluid [J/kg]: h given, h(p, T) or h_px(p, x).

        Raises :class:`BoundaryStateError` (naming this boundary, the time and the
        state) when the medium cannot evaluate it."""
        if self.supply_by == "h":
            return self.param_at("h", t)
        try:
            if self.supply_by == "x":
                x = self.param_at("x", t)
                return float(np.asarray(self.medium.h_px(p, x)).reshape(-1)[0])
            return self.medium.h_pT(p, self.param_at("T", t))
        except PropertyError as exc:
            raise BoundaryStateError(self._state_message(t, p, exc)) from None

    def _state_message(self, t, p, exc=None) -> str:
        where = f"boundary '{self.name}' ({type(self).__name__}) at t = {t:.6g} s"
        if self.supply_by == "T":
            T = self.param_at("T", t)
            T_sat = saturation_temperature(self.medium, p)
            if T_sat is not None and abs(T - T_sat) <= 1e-3:
                return (
                    f"{where}: T = {T - 273.15:.2f} °C is the saturation temperature at "
                    f"{p / 1e5:.6g} bar; (p, T) does not fix the supply state there (h jumps by "
                    "the latent heat between saturated liquid and vapour); give h or quality x "
                    "for a saturated supply"
                )
            state = f"p = {p / 1e5:.6g} bar, T = {T - 273.15:.6g} °C"
        elif self.supply_by == "x":
            state = f"p = {p / 1e5:.6g} bar, x = {self.param_at('x', t):.6g}"
        else:
            state = f"p = {p / 1e5:.6g} bar"
        reason = f": {exc}" if exc is not None else ""
        return f"{where}: cannot evaluate the supply enthalpy at {state}{reason}"

    def supply_equations(self, p_dep):
        """The supply equation (none for a sink only): h_supply = h(t), h(p, T(t)) or
        h_px(p, x(t)) [J/kg], at the boundary's pressure (``supply_pressure``)."""
        if not self.has_supply:
            return []
        dep = ("h_supply",) if self.supply_by == "h" else ("h_supply",) + p_dep
        return [
            Equation(
                "supply",
                y=dep,
                unit="J/kg",
                doc="h_supply = h, h(p, T) or h_px(p, x)",
            )
        ]

    def supply_pressure(self, t, x):
        """The pressure of the supply state [Pa] (``supply_p``), the node's from x."""
        return self.supply_p(t, x["port.p"])

    def supply_p(self, t, p_node) -> float:
        """The pressure of the supply state [Pa] at the node pressure p_node [Pa]."""
        raise NotImplementedError

    def own_reads(self) -> tuple[str, ...]:
        """The names the first equation (``first_row``) reads besides m and port.p (the
        last of ``row_reads``)."""
        return ()

    def first_row(self, t, m, p_node, v) -> float:
        """The residual of the class's first equation (pressure or flow) from m [kg/s],
        the node pressure [Pa] and v, the values of ``row_reads`` (``own_reads`` last)."""
        raise NotImplementedError

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``)."""
        supply = ("h_supply",) if self.has_supply else ()
        return ("m", "port.p", "port.h") + supply + self.own_reads(), ("M_passed", "H_passed")

    def row_values(self, t, v, vp, modes):
        """The equations of the class doc, in their order, their residuals:

        first          ``first_row``: pressure [Pa] or flow [kg/s]
        supply         h_supply - h_supply(t, p)                        [J/kg]
                       (h or T or x given; p from ``supply_p``)
        mass_passed    dM_passed/dt - m                                 [kg/s]
        energy_passed  dH_passed/dt - E,  E = w(m) h_supply - w(-m) h_node   [W]
        """
        m, p_node, h_node = v[0], v[1], v[2]
        out = [self.first_row(t, m, p_node, v)]
        if self.has_supply:
            out.append(v[3] - self.supply_h(t, self.supply_p(t, p_node)))
        h_own = v[3] if self.has_supply else h_node
        # energy_in gives the flow into the boundary (flow -m into it); the plant
        # receives minus that
        energy = -float(energy_in(-m, h_node, h_own, self.m_eps))
        return out + [vp[0] - m, vp[1] - energy]

    def accumulator_equations(self):
        dep = ("m", "port.h") + (("h_supply",) if self.has_supply else ())
        return [
            Equation(
                "mass_passed",
                y=("m",),
                yp=("M_passed",),
                unit="kg/s",
                doc="dM_passed/dt = m",
            ),
            Equation(
                "energy_passed",
                y=dep,
                yp=("H_passed",),
                unit="W",
                doc="dH_passed/dt = E = w(m) h_supply - w(-m) h_node",
            ),
        ]

    def switches(self):
        if self.supply_by == "T" and is_condensable(self.medium):
            return [self._saturation_switch()]
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

    def _saturation_switch(self) -> Switch:
        """Terminal switch g = T(t) - T_sat(p) [K] (see the module doc)."""
        last = {}

        def g(t, x, xp):
            p = float(self.supply_pressure(t, x))
            last["t"], last["p"] = t, p
            T_sat = saturation_temperature(self.medium, p)
            if T_sat is None:  # at or above the critical pressure: compare with T_c
                T_sat = getattr(self.medium, "T_critical", None) or 0.0
            return float(self.param_at("T", t)) - T_sat

        def message(t):
            p = last.get("p")
            if p is None:
                p = float(self.param_at("p", t)) if "p" in self.params else float("nan")
            T = self.param_at("T", t)
            T_sat = saturation_temperature(self.medium, p)
            T_txt = f"{T_sat - 273.15:.2f}" if T_sat is not None else f"{T - 273.15:.2f}"
            return (
                f"boundary '{self.name}' ({type(self).__name__}): at t = {t:.6g} s the given "
                f"supply temperature reaches T = {T_txt} °C, the saturation temperature at "
                f"{p / 1e5:.6g} bar; (p, T) does not fix the supply state there (h jumps by the "
                "latent heat between saturated liquid and vapour); give h or quality x for a "
                "saturated supply"
            )

        return Switch(
            "saturation",
            g,
            direction=0,
            terminal=True,
            message=message,
            doc="T(t) - T_sat(p) [K]: the given supply T reaches saturation",
        )

    def steady_problems(self, t0, x):
        """A sink-only boundary through which fluid enters the plant at rest (more than
        the reverse_inflow switch's tolerance): no state of that fluid is given, and a
        run would stop at once (``Component.steady_problems``)."""
        if self.has_supply:
            return []
        m, tol = x["m"], REVERSE_INFLOW_TOL * self.params["m_nominal"]
        if m <= tol:
            return []
        return [
            f"boundary '{self.name}' ({type(self).__name__}) is a sink only, but at rest "
            f"{m:.4g} kg/s would enter the plant through it (node pressure "
            f"{x['port.p'] / 1e5:.6g} bar): a sink gives no state for fluid entering the plant. "
            "Check its pressure or flow against the plant's (a sink above the pressure "
            "upstream feeds the plant), or give T or h if fluid may enter there"
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

    def supply_p(self, t, p_node):
        return self.param_at("p", t)

    def first_row(self, t, m, p_node, v):
        """pressure: p_node - p(t) [Pa]."""
        return p_node - self.param_at("p", t)

    def equations(self):
        """The equations of the class doc (their residuals: ``row_values``)."""
        return (
            [Equation("pressure", y=("port.p",), unit="Pa", doc="p_node = p(t)")]
            + self.supply_equations(())
            + self.accumulator_equations()
        )

    def guess_nodes(self, t0):
        p = self.param_at("p", t0)
        if not self.has_supply:
            self._check_sink_pressure(t0, p)
            return {"port": (p, None)}
        return {"port": (p, self.supply_h(t0, p))}

    #: temperatures [K] at which a sink's pressure is tried in its medium: a pressure
    #: that none of them accepts is outside the medium's range for any state
    PROBE_T = (300.0, 600.0, 1000.0)

    def _check_sink_pressure(self, t, p):
        """Raise BoundaryStateError when no state at pressure p [Pa] exists in the
        medium (e.g. 0.001 bar for IF97 water, whose range starts at 611.2 Pa): the
        fluid leaving the plant there could never be evaluated."""
        medium = getattr(self, "medium", None)
        if medium is None:
            return
        first = None
        for T in self.PROBE_T:
            try:
                medium.h_pT(p, T)
                return
            except PropertyError as exc:
                first = first or exc
        raise BoundaryStateError(
            f"boundary '{self.name}' ({type(self).__name__}) at t = {t:.6g} s: the pressure "
            f"p = {p / 1e5:.6g} bar ({p:.6g} Pa) is outside the range of {medium.label}: no "
            f"state of the fluid leaving the plant there can be evaluated ({first})"
        )

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
            "m",
            "kg/s",
            None,
            "mass flow into the plant (negative: out of it); otherwise m_scale times the "
            "signal input 'm_in'",
            time_function=True,
        ),
        Param("m_scale", "kg/s", 1.0, "flow per unit of the signal input m_in: m = m_scale m_in"),
    ) + _STATE_PARAMS
    SIGNAL_INPUTS = (
        SignalPort("m_in", "1", "flow demand: m = m_scale m_in (parameter m not given)"),
    )
    FLUID_PORTS = (
        FluidPort("port", "outlet", "m", "none", "m > 0 into the plant; h or T: inflow state"),
    )

    def supply_p(self, t, p_node):
        return p_node

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.params["m"] is None else []

    def flow_set(self, t, m_in=None):
        """The prescribed flow m(t) [kg/s]: the parameter, or m_scale times the signal
        input's value m_in [1]."""
        if self.params["m"] is None:
            return self.params["m_scale"] * m_in
        return self.param_at("m", t)

    def own_reads(self):
        return ("m_in",) if self.params["m"] is None else ()

    def first_row(self, t, m, p_node, v):
        """flow: m - m(t) [kg/s] (``flow_set``; m_in the last value of v)."""
        return m - self.flow_set(t, v[-1] if self.params["m"] is None else None)

    def equations(self):
        """The equations of the class doc (their residuals: ``row_values``)."""
        return (
            [
                Equation(
                    "flow",
                    y=("m",) + self.own_reads(),
                    unit="kg/s",
                    doc="m = m(t), or m = m_scale m_in from the signal",
                )
            ]
            + self.supply_equations(("port.p",))
            + self.accumulator_equations()
        )

    def guess_nodes(self, t0):
        if not self.has_supply or self.params["h"] is None:
            return {}
        return {"port": (None, self.param_at("h", t0))}

    def initial_guess(self, t0, x):
        x["m"] = self.flow_set(t0, *(x[n] for n in self.own_reads()))
        super().initial_guess(t0, x)
        if self.has_supply and self.params["h"] is None and x["m"] > 0:
            x["port.h"] = x["h_supply"]


def saturation_temperature(medium, p):
    """T_sat(p) [K] of a condensable medium: the temperature of saturated liquid,
    T(p, h_liq(p)); None at or above the critical pressure or for a medium without
    a two-phase region."""
    f = getattr(medium, "saturation_enthalpies", None)
    if f is None or not is_condensable(medium):
        return None
    try:
        hl, _ = f(np.atleast_1d(float(p)))
        hl = float(np.asarray(hl).reshape(-1)[0])
        if not np.isfinite(hl):
            return None
        return float(medium.state(float(p), hl).T)
    except PropertyError:
        return None
