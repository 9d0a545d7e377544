"""TemperatureSensor: measures a node temperature with a first-order lag."""

from __future__ import annotations

from dnasim.components.base import Component, Equation, FluidPort, Param, SignalPort, Variable
from dnasim.components.physics import properties


class TemperatureSensor(Component):
    """First-order temperature sensor on a node (a probe: it carries no flow).

      lag    tau dT_s/dt = T(p, h) - T_s       (tau > 0)
             T_s = T(p, h)                     (tau = 0, ideal sensor)

    T_s [K] is the signal output ``T``. The node's (p, h) is the mixed state of the
    fluid flowing into the node, so the sensor reads the upstream fluid in either
    flow direction.
    """

    PARAMS = (
        Param("tau", "s", 1.0, "time constant (0: no lag)", min=0.0),
        Param(
            "T0", "K", None, "initial reading (given start; default: the node temperature)", min=0.0
        ),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    FLUID_PORTS = (FluidPort("port", "probe", None, "none", "node to measure"),)
    SIGNAL_OUTPUTS = (SignalPort("T", "K", "measured temperature", variable="T_s"),)

    def variables(self):
        return [Variable("T_s", "K", 300.0, doc="measured temperature")]

    def equations(self):
        tau = self.params["tau"]
        if tau > 0:
            return [
                Equation(
                    "lag",
                    y=("T_s", "port.p", "port.h"),
                    yp=("T_s",),
                    unit="K",
                    doc="tau dT_s/dt = T(p, h) - T_s",
                    residual=lambda t, x, xp: tau * xp["T_s"] - (self._T(x) - x["T_s"]),
                )
            ]
        return [
            Equation(
                "lag",
                y=("T_s", "port.p", "port.h"),
                unit="K",
                doc="T_s = T(p, h) (tau = 0)",
                residual=lambda t, x, xp: x["T_s"] - self._T(x),
            )
        ]

    def _T(self, x):
        """The fluid temperature at the port [K]."""
        T, _, _ = properties(self.medium, [x["port.p"]], [x["port.h"]])
        return T[0]

    def initial_guess(self, t0, x):
        if self.params["T0"] is not None:
            x["T_s"] = self.params["T0"]
        else:
            T, _, _ = properties(self.medium, [x["port.p"]], [x["port.h"]])
            x["T_s"] = T[0]
