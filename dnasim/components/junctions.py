"""Junctions without volume: Mixer (n inlets, one outlet) and Splitter (one inlet, n outlets)."""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Component, Equation, FluidPort, Param, Variable


class Mixer(Component):
    """Adiabatic junction of n_inlets streams into one, without storage or friction.

      mass        m_out = sum_k m_in[k]
      energy      m_out h_out = sum_k m_in[k] h_in_k    (needs m_out != 0)
      pressure_k  p_in_k = p_out                        (k = 1..n)

    Ports inlet1..inlet<n>, outlet; m_in[k-1] is the flow through inlet<k>.
    """

    PARAMS = (
        Param("n_inlets", "1", 2, "number of inlets", min=2, kind="int"),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet1", "inlet", "m_in[0]", "equal", "first inlet (inlet2, ... likewise)"),
        FluidPort("outlet", "outlet", "m_out", "equal", "mixed stream"),
    )

    def fluid_ports(self):
        n = self.params["n_inlets"]
        return [FluidPort(f"inlet{k + 1}", "inlet", f"m_in[{k}]", "equal") for k in range(n)] + [
            FluidPort("outlet", "outlet", "m_out", "equal")
        ]

    def variables(self):
        mn = self.params["m_nominal"]
        return [
            Variable("m_in", "kg/s", mn, self.params["n_inlets"]),
            Variable("m_out", "kg/s", mn),
        ]

    def equations(self):
        n = self.params["n_inlets"]
        m_in = tuple(f"m_in[{k}]" for k in range(n))
        h_in = tuple(f"inlet{k + 1}.h" for k in range(n))
        eqs = [
            Equation("mass", y=("m_out",) + m_in),
            Equation("energy", y=("m_out", "outlet.h") + m_in + h_in),
        ]
        eqs += [Equation(f"pressure{k + 1}", y=(f"inlet{k + 1}.p", "outlet.p")) for k in range(n)]
        return eqs

    def residual(self, t, x, xp):
        n = self.params["n_inlets"]
        m_in = x["m_in"]
        h_in = np.array([x[f"inlet{k + 1}.h"] for k in range(n)])
        p_in = np.array([x[f"inlet{k + 1}.p"] for k in range(n)])
        return np.concatenate(
            (
                [x["m_out"] - m_in.sum(), x["m_out"] * x["outlet.h"] - np.dot(m_in, h_in)],
                p_in - x["outlet.p"],
            )
        )

    def initial_guess(self, t0, x):
        n = self.params["n_inlets"]
        x["m_in"] = self.params["m_nominal"] / n
        x["m_out"] = self.params["m_nominal"]
        x["outlet.h"] = np.mean([x[f"inlet{k + 1}.h"] for k in range(n)])


class Splitter(Component):
    """Junction of one stream into n_outlets, without storage or friction.

      mass         m_in = sum_k m_out[k]
      enthalpy_k   h_out_k = h_in
      pressure_k   p_out_k = p_in         (k = 1..n)

    The split ratio follows from the resistances downstream.
    """

    PARAMS = (
        Param("n_outlets", "1", 2, "number of outlets", min=2, kind="int"),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m_in", "equal", "incoming stream"),
        FluidPort("outlet1", "outlet", "m_out[0]", "equal", "first outlet (outlet2, ... likewise)"),
    )

    def fluid_ports(self):
        n = self.params["n_outlets"]
        return [FluidPort("inlet", "inlet", "m_in", "equal")] + [
            FluidPort(f"outlet{k + 1}", "outlet", f"m_out[{k}]", "equal") for k in range(n)
        ]

    def variables(self):
        mn = self.params["m_nominal"]
        return [
            Variable("m_in", "kg/s", mn),
            Variable("m_out", "kg/s", mn, self.params["n_outlets"]),
        ]

    def equations(self):
        n = self.params["n_outlets"]
        eqs = [Equation("mass", y=("m_in",) + tuple(f"m_out[{k}]" for k in range(n)))]
        eqs += [Equation(f"enthalpy{k + 1}", y=(f"outlet{k + 1}.h", "inlet.h")) for k in range(n)]
        eqs += [Equation(f"pressure{k + 1}", y=(f"outlet{k + 1}.p", "inlet.p")) for k in range(n)]
        return eqs

    def residual(self, t, x, xp):
        n = self.params["n_outlets"]
        h = np.array([x[f"outlet{k + 1}.h"] for k in range(n)])
        p = np.array([x[f"outlet{k + 1}.p"] for k in range(n)])
        return np.concatenate(([x["m_in"] - x["m_out"].sum()], h - x["inlet.h"], p - x["inlet.p"]))

    def initial_guess(self, t0, x):
        n = self.params["n_outlets"]
        x["m_in"] = self.params["m_nominal"]
        x["m_out"] = self.params["m_nominal"] / n
        for k in range(n):
            x[f"outlet{k + 1}.h"] = x["inlet.h"]
