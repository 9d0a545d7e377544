"""Sensors: a measured quantity with an optional first-order lag, as a signal output.

Every sensor has the lag

    T_lag dy/dt = q - y     (T_lag > 0)         y = q     (T_lag = 0, ideal)

where q is the quantity measured and y [unit of q] the signal output. A step of q
from q0 to q1 at t = 0 gives y(t) = q1 + (q0 - q1) exp(-t/T_lag).

Node sensors (a ``probe`` port: they carry no flow and read the node's p [Pa]
and h [J/kg], the mixed state of the fluid flowing into the node, i.e. the
upstream fluid in either direction):

  PressureSensor     q = p                                   output ``p`` [Pa]
  EnthalpySensor     q = h                                   output ``h`` [J/kg]
  TemperatureSensor  q = T(p, h) of the node's medium        output ``T`` [K]
  QualitySensor      q = (h - h'(p)) / (h''(p) - h'(p))      output ``x`` [1]

The quality is the thermodynamic (equilibrium) quality from the saturated liquid
and vapour enthalpies h', h'' at p: smooth in (p, h), below 0 for subcooled
liquid and above 1 for superheated vapour (no clipping inside Newton), for a
fluid with a two-phase region below its critical pressure.

Signal sensors (a signal input linked to any variable, see ``dnasim.plant.signals``):

  MassFlowSensor     q = the linked flow variable  ("valve.m", "pipe.m[3]")   output ``m`` [kg/s]
  LevelSensor        q = the linked level variable ("drum.level")             output ``level`` [m]

A mass-flow sensor reads a component's own flow variable rather than sitting
between two nodes: a zero-resistance component between two nodes would tie their
pressures and, next to storage volumes, make the DAE index 2.
"""

from __future__ import annotations

from dnasim.core.errors import PlantError
from dnasim.model.component import Component, Equation, FluidPort, Param, SignalPort, Variable

__all__ = [
    "TemperatureSensor",
    "PressureSensor",
    "EnthalpySensor",
    "QualitySensor",
    "MassFlowSensor",
    "LevelSensor",
]


def _lag_param():
    return Param("T_lag", "s", 0.0, "time constant of the first-order lag (0: none)", min=0.0)


class _Sensor(Component):
    """Base: y = q or T_lag dy/dt = q - y; subclasses give the quantity ``_q``."""

    REGISTER = False
    #: (variable, unit, nominal, doc) of the measured value y
    Y = ("y", "1", 1.0, "measured value")
    #: local names the quantity reads
    READS: tuple[str, ...] = ()

    @property
    def T_lag(self) -> float:
        return self.params["T_lag"]

    def variables(self):
        name, unit, nominal, doc = self.Y
        return [Variable(name, unit, nominal, doc=doc)]

    def equations(self):
        """The lag of the module doc (its residual: ``row_values``)."""
        y = self.Y[0]
        if self.T_lag > 0:
            return [
                Equation(
                    "lag",
                    y=(y, *self.READS),
                    yp=(y,),
                    unit=self.Y[1],
                    doc=f"T_lag d{y}/dt = q - {y}",
                )
            ]
        return [Equation("lag", y=(y, *self.READS), unit=self.Y[1], doc=f"{y} = q (T_lag = 0)")]

    def row_reads(self):
        """The names ``row_values`` reads (``Component.row_reads``): ``READS``, then y."""
        y = self.Y[0]
        return (*self.READS, y), (y,)

    def row_values(self, t, v, vp, modes):
        """The lag of the module doc, its residual [unit of q, times s/s]:
        lag  T_lag dy/dt - (q - y)   (T_lag > 0),   y - q   (T_lag = 0),
        q = ``_q`` of the values of ``READS`` (the first of v)."""
        y = v[-1]
        q = self._q(t, v)
        tau = self.T_lag
        if tau > 0:
            return [tau * vp[0] - (q - y)]
        return [y - q]

    def _q(self, t, values) -> float:  # pragma: no cover - abstract
        """The quantity measured, q [unit of y], from the values of ``READS``, the
        first of ``values`` (in order; more may follow)."""
        raise NotImplementedError

    def initial_guess(self, t0, x):
        y0 = self.params.get("y0")
        x[self.Y[0]] = y0 if y0 is not None else self._q(t0, [x[n] for n in self.READS])


class _NodeSensor(_Sensor):
    REGISTER = False
    READS = ("port.p", "port.h")
    FLUID_PORTS = (FluidPort("port", "probe", None, "none", "node to measure"),)


class PressureSensor(_NodeSensor):
    """Pressure of a node, with an optional first-order lag.

    T_lag dp_s/dt = p - p_s   (p_s = p for T_lag = 0)        [Pa]
    """

    PARAMS = (
        _lag_param(),
        Param("y0", "Pa", None, "initial reading (given start; default: the node pressure)"),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    SIGNAL_OUTPUTS = (SignalPort("p", "Pa", "measured pressure", variable="p_s"),)
    Y = ("p_s", "Pa", 1e5, "measured pressure")

    def _q(self, t, values):
        p = values[0]
        return p


class EnthalpySensor(_NodeSensor):
    """Specific enthalpy of the fluid flowing into a node, with an optional lag.

    T_lag dh_s/dt = h - h_s   (h_s = h for T_lag = 0)        [J/kg]
    """

    PARAMS = PressureSensor.PARAMS[:1] + (
        Param("y0", "J/kg", None, "initial reading (given start; default: the node enthalpy)"),
        PressureSensor.PARAMS[2],
    )
    SIGNAL_OUTPUTS = (SignalPort("h", "J/kg", "measured specific enthalpy", variable="h_s"),)
    Y = ("h_s", "J/kg", 1e5, "measured specific enthalpy")

    def _q(self, t, values):
        h = values[1]
        return h


class TemperatureSensor(_NodeSensor):
    """Temperature of a node, T(p, h) of the node's medium, with an optional lag.

      T_lag dT_s/dt = T(p, h) - T_s   (T_s = T(p, h) for T_lag = 0)        [K]

    ``tau`` is the former name of ``T_lag`` (give one of them); ``T0`` the initial
    reading of a given start.
    """

    PARAMS = (
        Param("T_lag", "s", None, "time constant of the first-order lag (0: none)", min=0.0),
        Param("tau", "s", None, "time constant (former name of T_lag; default 1 s)", min=0.0),
        Param(
            "T0", "K", None, "initial reading (given start; default: the node temperature)", min=0.0
        ),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    SIGNAL_OUTPUTS = (SignalPort("T", "K", "measured temperature", variable="T_s"),)
    Y = ("T_s", "K", 300.0, "measured temperature")

    def setup(self):
        if self.params["T_lag"] is not None and self.params["tau"] is not None:
            raise PlantError(
                f"component '{self.name}': give T_lag or tau (its former name), not both"
            )

    @property
    def T_lag(self) -> float:
        for key in ("T_lag", "tau"):
            if self.params[key] is not None:
                return self.params[key]
        return 1.0

    def _q(self, t, values):
        # one point: the medium's cached state (what ``physics.properties`` does for a
        # single point, without the arrays)
        p, h = values[0], values[1]
        return self.medium.state(p, h).T

    def initial_guess(self, t0, x):
        T0 = self.params["T0"]
        x["T_s"] = T0 if T0 is not None else self._q(t0, [x["port.p"], x["port.h"]])


class QualitySensor(_NodeSensor):
    """Thermodynamic quality of the fluid flowing into a node, with an optional lag.

      x = (h - h'(p)) / (h''(p) - h'(p))                                [1]
      T_lag dx_s/dt = x - x_s   (x_s = x for T_lag = 0)

    h'(p), h''(p): saturated liquid and vapour enthalpies of the node's medium
    [J/kg]. x < 0: subcooled, x > 1: superheated (not clipped). Only below the
    critical pressure.
    """

    PARAMS = (
        _lag_param(),
        Param("y0", "1", None, "initial reading (given start; default: the node quality)"),
        Param("medium", "1", None, "fluid name (default: from the network)", kind="string"),
    )
    SIGNAL_OUTPUTS = (SignalPort("x", "1", "measured quality", variable="x_s"),)
    Y = ("x_s", "1", 1.0, "measured thermodynamic quality")

    def _q(self, t, values):
        p, h = values[0], values[1]
        hl, hv = self.medium.saturation_enthalpies([p])
        hl, hv = float(hl[0]), float(hv[0])
        return (h - hl) / (hv - hl)


class _SignalSensor(_Sensor):
    REGISTER = False
    USES_MEDIUM = False
    READS = ("u",)

    def _q(self, t, values):
        u = values[0]
        return u


class MassFlowSensor(_SignalSensor):
    """Mass flow of a component's flow variable, with an optional lag.

      T_lag dm_s/dt = m - m_s   (m_s = m for T_lag = 0)        [kg/s]

    Link the flow: ``inputs = { u = "valve.m" }`` (or "pipe.m[3]", "pump.m").
    """

    PARAMS = (
        _lag_param(),
        Param("y0", "kg/s", None, "initial reading (given start; default: the flow)"),
        Param("m_nominal", "kg/s", 1.0, "typical flow (scales the error tolerance)", min=0.0),
    )
    SIGNAL_INPUTS = (SignalPort("u", "kg/s", 'the flow measured, e.g. "valve.m"'),)
    SIGNAL_OUTPUTS = (SignalPort("m", "kg/s", "measured mass flow", variable="m_s"),)
    Y = ("m_s", "kg/s", 1.0, "measured mass flow")

    def variables(self):
        return [Variable("m_s", "kg/s", self.params["m_nominal"], doc="measured mass flow")]


class LevelSensor(_SignalSensor):
    """Level of a vessel's level variable, with an optional lag.

      T_lag dl_s/dt = level - l_s   (l_s = level for T_lag = 0)        [m]

    Link the level: ``inputs = { u = "drum.level" }``.
    """

    PARAMS = (
        _lag_param(),
        Param("y0", "m", None, "initial reading (given start; default: the level)"),
    )
    SIGNAL_INPUTS = (SignalPort("u", "m", 'the level measured, e.g. "drum.level"'),)
    SIGNAL_OUTPUTS = (SignalPort("level", "m", "measured level", variable="l_s"),)
    Y = ("l_s", "m", 1.0, "measured level")
