"""Junctions without volume: Mixer (n inlets, one outlet) and Splitter (one inlet,
n outlets).

Both are the same adiabatic junction without storage or friction; they differ
only in the sign convention of their flow variables. Flow may go either way at
every port. Symbols: m_k [kg/s] the flow INTO the junction at port k, h_k [J/kg]
the node enthalpy at port k, w the smooth upwind weight
(``physics.upwind_weight``), h_mix [J/kg] the mixed enthalpy of the inflows:

  mass         sum_k m_k = 0
  mixing       sum_k w(m_k) (h_k - h_mix) = 0
  pressure_k   p_k = p_last                 (all ports at one pressure)

Fluid leaving through any port carries h_mix. The energy flows into the
junction, E_k = w(m_k) h_k - w(-m_k) h_mix, sum to h_mix sum_k m_k = 0 exactly.
"""

from __future__ import annotations

import numpy as np

from dnasim.model.component import Component, Equation, FluidPort, Param, Variable
from dnasim.model.physics import upwind_weight


class _Junction(Component):
    REGISTER = False

    def port_names(self) -> list[str]:
        raise NotImplementedError

    def flow_names(self) -> list[str]:
        raise NotImplementedError

    def flows_in(self, m) -> np.ndarray:
        """The flows into the junction [kg/s] at each port (order of port_names), from
        the values m of ``flow_names`` (an inlet's flow counts in, an outlet's out)."""
        into = self.__dict__.get("_into")
        if into is None:  # per port: its flow variable counts into the junction
            into = self._into = [p.role == "inlet" for p in self.fluid_ports()]
        return np.array([m_k if inward else -m_k for m_k, inward in zip(m, into, strict=True)])

    def equations(self):
        """The equations of the module doc (their residuals: ``row_values``)."""
        ports = self.port_names()
        flows = tuple(self.flow_names())
        hs = tuple(f"{p}.h" for p in ports)
        last = ports[-1]
        eqs = [
            Equation("mass", y=flows, unit="kg/s", doc="sum_k m_k = 0 (m_k into the junction)"),
            Equation(
                "mixing",
                y=flows + hs + ("h_mix",),
                unit="W",
                doc="sum_k w(m_k) (h_k - h_mix) = 0",
            ),
        ]
        eqs += [
            Equation(f"pressure_{p}", y=(f"{p}.p", f"{last}.p"), unit="Pa", doc=f"p_{p} = p_{last}")
            for p in ports[:-1]
        ]
        return eqs

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``): the flows, the
        ports' enthalpies, h_mix and the ports' pressures."""
        ports = self.port_names()
        return (
            tuple(self.flow_names())
            + tuple(f"{p}.h" for p in ports)
            + ("h_mix",)
            + tuple(f"{p}.p" for p in ports)
        ), ()

    def row_values(self, t, v, vp, modes):
        """The equations of the module doc, their residuals:

        mass         sum_k m_k                      [kg/s]
        mixing       sum_k w(m_k) (h_k - h_mix)     [W]
        pressure_k   p_k - p_last                   [Pa]   (every port but the last)
        """
        n = len(self.port_names())
        m = self.flows_in(v[:n])
        h = np.array(v[n : 2 * n])
        h_mix = v[2 * n]
        p = v[2 * n + 1 :]
        mixing = np.dot(upwind_weight(m, self.m_eps), h - h_mix)
        return [m.sum(), mixing] + [p_k - p[-1] for p_k in p[:-1]]

    def initial_guess(self, t0, x):
        ports = self.port_names()
        m = self.flows_in([x[n] for n in self.flow_names()])
        w = upwind_weight(m, self.m_eps)
        h = np.array([x[f"{p}.h"] for p in ports])
        x["h_mix"] = float(np.dot(w, h) / w.sum())


class Mixer(_Junction):
    """Adiabatic junction of n_inlets streams into one, without storage or friction.

      mass        m_out = sum_k m_in[k]
      mixing      sum_k w(m_in[k]) (h_in_k - h_mix) + w(-m_out) (h_out - h_mix) = 0
      pressure_k  p_in_k = p_out                        (k = 1..n)

    Ports inlet1..inlet<n>, outlet; m_in[k-1] is the flow through inlet<k>
    (positive into the mixer), m_out the flow out. Any port may carry reverse
    flow; fluid leaves through every port with h_mix (see the module doc).
    """

    PARAMS = (
        Param("n_inlets", "1", 2, "number of inlets", min=2, max=64, kind="int"),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet1", "inlet", "m_in[0]", "equal", "first inlet (inlet2, ... likewise)"),
        FluidPort("outlet", "outlet", "m_out", "equal", "mixed stream"),
    )

    def port_names(self):
        return [f"inlet{k + 1}" for k in range(self.params["n_inlets"])] + ["outlet"]

    def flow_names(self):
        return [f"m_in[{k}]" for k in range(self.params["n_inlets"])] + ["m_out"]

    def fluid_ports(self):
        n = self.params["n_inlets"]
        eps = self.m_eps
        return [
            FluidPort(
                f"inlet{k + 1}",
                "inlet",
                f"m_in[{k}]",
                "equal",
                h_out="h_mix",
                h_source=False,
                m_eps=eps,
            )
            for k in range(n)
        ] + [
            FluidPort(
                "outlet", "outlet", "m_out", "equal", h_out="h_mix", h_source=False, m_eps=eps
            )
        ]

    def variables(self):
        mn = self.params["m_nominal"]
        return [
            Variable("m_in", "kg/s", mn, self.params["n_inlets"], "flow into the mixer at inlet k"),
            Variable("m_out", "kg/s", mn, doc="flow out of the mixer"),
            Variable("h_mix", "J/kg", 1e5, doc="mixed enthalpy of the inflows"),
        ]

    def initial_guess(self, t0, x):
        n = self.params["n_inlets"]
        x["m_in"] = self.params["m_nominal"] / n
        x["m_out"] = self.params["m_nominal"]
        super().initial_guess(t0, x)


class Splitter(_Junction):
    """Junction of one stream into n_outlets, without storage or friction.

      mass         m_in = sum_k m_out[k]
      mixing       w(m_in) (h_in - h_mix) + sum_k w(-m_out[k]) (h_out_k - h_mix) = 0
      pressure_k   p_out_k = p_in         (k = 1..n)

    The split ratio follows from the resistances downstream. Any port may carry
    reverse flow; fluid leaves through every port with h_mix (see the module doc).
    """

    PARAMS = (
        Param("n_outlets", "1", 2, "number of outlets", min=2, max=64, kind="int"),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m_in", "equal", "incoming stream"),
        FluidPort("outlet1", "outlet", "m_out[0]", "equal", "first outlet (outlet2, ... likewise)"),
    )

    def port_names(self):
        return ["inlet"] + [f"outlet{k + 1}" for k in range(self.params["n_outlets"])]

    def flow_names(self):
        return ["m_in"] + [f"m_out[{k}]" for k in range(self.params["n_outlets"])]

    def fluid_ports(self):
        n = self.params["n_outlets"]
        eps = self.m_eps
        return [
            FluidPort("inlet", "inlet", "m_in", "equal", h_out="h_mix", h_source=False, m_eps=eps)
        ] + [
            FluidPort(
                f"outlet{k + 1}",
                "outlet",
                f"m_out[{k}]",
                "equal",
                h_out="h_mix",
                h_source=False,
                m_eps=eps,
            )
            for k in range(n)
        ]

    def variables(self):
        mn = self.params["m_nominal"]
        return [
            Variable("m_in", "kg/s", mn, doc="flow into the splitter"),
            Variable("m_out", "kg/s", mn, self.params["n_outlets"], "flow out at outlet k"),
            Variable("h_mix", "J/kg", 1e5, doc="mixed enthalpy of the inflows"),
        ]

    def initial_guess(self, t0, x):
        n = self.params["n_outlets"]
        x["m_in"] = self.params["m_nominal"]
        x["m_out"] = self.params["m_nominal"] / n
        super().initial_guess(t0, x)
