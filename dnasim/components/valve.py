"""Valve: flow through a restriction, m = C z sqrt(p_in - p_out) (seed eq. 10.13f)."""

from __future__ import annotations

import numpy as np

from dnasim.components.base import Component, Equation, FluidPort, Param, SignalPort, Variable
from dnasim.components.physics import valve_flow


class Valve(Component):
    """Valve with opening z from the signal input ``z`` or the parameter ``opening``.

      flow      m = C z (p_in - p_out) / ((p_in - p_out)^2 + dp_reg^2)^(1/4)
                  (= C z sqrt(p_in - p_out) for p_in - p_out >> dp_reg; odd in the
                  pressure difference, so reverse flow gives m < 0; finite slope at 0)
      enthalpy  h_out = h_in     (isenthalpic throttling, design direction)

    The mass flow m [kg/s] is the same at both ports (no storage).
    """

    PARAMS = (
        Param("C", "kg/(s.Pa0.5)", doc="flow coefficient", min=0.0),
        Param(
            "opening",
            "1",
            None,
            "fixed opening z (otherwise from the signal input 'z')",
            time_function=True,
        ),
        Param("dp_reg", "Pa", 10.0, "regularisation pressure difference near dp = 0", min=0.0),
        Param("m_nominal", "kg/s", 1.0, "typical mass flow (scales and tolerances)", min=0.0),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", "resistance", "fluid in"),
        FluidPort("outlet", "outlet", "m", "resistance", "fluid out"),
    )
    SIGNAL_INPUTS = (SignalPort("z", "1", "opening (when the parameter 'opening' is not given)"),)

    def setup(self):
        self.opening_from_signal = self.params["opening"] is None

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS) if self.opening_from_signal else []

    def variables(self):
        return [Variable("m", "kg/s", self.params["m_nominal"], doc="mass flow")]

    def equations(self):
        dep = ("m", "inlet.p", "outlet.p") + (("z",) if self.opening_from_signal else ())
        return [Equation("flow", y=dep), Equation("enthalpy", y=("outlet.h", "inlet.h"))]

    def opening(self, t, x):
        return x["z"] if self.opening_from_signal else self.param_at("opening", t)

    def residual(self, t, x, xp):
        dp = x["inlet.p"] - x["outlet.p"]
        m = valve_flow(self.params["C"], self.opening(t, x), dp, self.params["dp_reg"])
        return np.array([x["m"] - m, x["outlet.h"] - x["inlet.h"]])

    def initial_guess(self, t0, x):
        dp = x["inlet.p"] - x["outlet.p"]
        z = self.opening(t0, x) if not self.opening_from_signal else 0.5
        x["m"] = valve_flow(self.params["C"], z, dp, self.params["dp_reg"])
        x["outlet.h"] = x["inlet.h"]
