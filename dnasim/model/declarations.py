"""What a component declares: its parameters (``Param``), fluid and signal ports
(``FluidPort``, ``SignalPort``), variables (``Variable``), equations (``Equation``),
switch functions (``Switch``) and derived outputs (``Output``), plus the declarations
several components share (``flow_through_ports``, ``shaft_work_equations``).

Plain frozen data with no behaviour beyond checking and converting a parameter's
value (``Param.range_problem``, ``Param.si_value``); the ``Component`` base class that
holds them is ``dnasim.model.component``, which re-exports every name here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

__all__ = [
    "REQUIRED",
    "POSITIVE_UNITS",
    "Param",
    "FluidPort",
    "flow_through_ports",
    "shaft_work_equations",
    "SignalPort",
    "Variable",
    "Equation",
    "Switch",
    "Output",
]


class _Required:
    def __repr__(self):
        return "REQUIRED"


REQUIRED = _Required()


#: units whose quantities must be > 0 (absolute temperature, pressure, ...)
POSITIVE_UNITS = {"Pa": "pressure", "m3": "volume", "m2": "area", "kg": "mass", "K": "temperature"}


@dataclass(frozen=True)
class Param:
    """A component parameter.

    ``unit`` is an SI unit string ("Pa", "K", "kg/s", "J/kg", "m3", "W/K", "1", "s").
    ``kind`` is "number", "string", "bool", "int" or "array" (a list of numbers,
    each in ``unit`` and within ``min``/``max``; a tuple of floats). With ``time_function=True`` the
    value may be a number or a ``dnasim.core.timefunctions`` function of time; the
    component then reads it as ``self.param_at("name", t)``.
    ``choices`` restricts a string parameter. ``default=REQUIRED`` means the user
    must give it; ``default=None`` means "not given" (optional).
    """

    name: str
    unit: str = "1"
    default: object = REQUIRED
    doc: str = ""
    min: float | None = None
    max: float | None = None
    time_function: bool = False
    kind: str = "number"
    choices: tuple | None = None
    #: the power of the measured signal's unit in this parameter's unit: a
    #: controller gain [output unit per measured unit] is -1, a set point 1
    per_signal: int = 0
    #: the power (0 or 1) of the component's output unit in this parameter's unit: the
    #: output unit is the string parameter the class names in ``OUTPUT_UNIT_PARAM``
    #: (a PID controller's ``unit``: "W" for a firing rate); its gain Kp "4 MW/bar"
    #: [W/Pa] and its limits "200 MW" [W] are 1
    per_output: int = 0

    def range_problem(self, x: float) -> tuple[str, str] | None:
        """The one range check of a parameter value x [SI], used by the Python API
        and the plant files alike: ``None`` when x is allowed, else (kind, text)
        with kind "physical" (a pressure, volume, area, mass or absolute
        temperature <= 0 when the parameter has no positive lower bound) or "range"
        (below ``min`` or above ``max``). A difference ("delta_Pa", "delta_K") may
        be <= 0 within its bounds."""
        what = POSITIVE_UNITS.get(self.unit)
        if what is not None and (self.min is None or self.min <= 0) and x <= 0:
            return (
                "physical",
                f"{self.name} is a {what} and must be greater than 0 {self.unit} "
                f"(got {x:g} {self.unit})",
            )
        if self.min is not None and x < self.min:
            return (
                "range",
                f"{self.name} = {x:g} {self.unit} is below its minimum {self.min:g} "
                f"(must be at least {self.min:g} {self.unit})",
            )
        if self.max is not None and x > self.max:
            return (
                "range",
                f"{self.name} = {x:g} {self.unit} is above its maximum {self.max:g} "
                f"(must be at most {self.max:g} {self.unit})",
            )
        return None

    def si_value(self, value, atmosphere: float | None = None):
        """A number or a unit string ("120 bar", "200 degC", "5 barg") in this
        parameter's SI unit; other values are returned as they are. Gauge pressures
        are read against ``atmosphere`` [Pa] (``None``: the standard atmosphere,
        101325 Pa). Raises ``UnitError``."""
        if not isinstance(value, str):
            return value
        from dnasim.core.units import convert_quantity

        unit = self.unit
        difference = unit.startswith("delta_")
        if difference:
            unit = unit[len("delta_") :]
        return convert_quantity(value, unit, difference, atmosphere=atmosphere)


@dataclass(frozen=True)
class FluidPort:
    """A fluid port bound to a node carrying p [Pa] and h [J/kg].

    role: "inlet" or "outlet" (the sign convention of ``flow``), or "probe"
    (reads p and h, carries no flow).
    flow: the local variable (or vector element, e.g. "m[0]") holding the mass flow
    through the port, positive in the design direction [kg/s]; None for probes.
    h_out: local name of the specific enthalpy [J/kg] the component delivers into
    the node when fluid leaves the component through this port ("h_v[3]",
    "inlet.h", "h_supply"); None for probes.
    h_source: True when ``h_out`` is set by the component itself (a storage
    volume's state, a given supply enthalpy); False when it is passed through
    from the component's other ports (valves, junctions) or is the node's own h
    (a sink). A group of nodes joined by pass-through components needs at least one
    source port, otherwise nothing sets its enthalpy.
    pressure: how the component ties the node pressure, used to explain
    structural problems in plain words:
      "storage"    the node pressure is the state of a storage volume of this component
                   (no flow resistance between the volume and the node);
      "fixed"      the node pressure is prescribed (pressure boundary);
      "equal"      the node pressure equals the pressure at the component's other
                   "equal" ports (junctions without resistance);
      "resistance" a flow resistance sits between the node and the component's interior;
      "none"       the component does not relate the node pressure to anything.
    pressure_param: the parameter whose zero value made the port "storage" instead
    of "resistance" (e.g. "k" of a Pipe with k = 0), named in structure messages.
    m_eps: flow scale [kg/s] of the smooth upwind weight w(m) at this port
    (``physics.upwind_weight``); the node's mixing equation uses the same value.
    band: None (the band of w is m_eps), or a narrower band [kg/s] for w's
    regularised part, the tail keeping m_eps's scale (``physics.upwind_weight``): a
    number, or the local name of a variable of the component that holds it (a
    control valve's band narrows with its opening: ``physics.opening_band``).
    """

    name: str
    role: str
    flow: str | None
    pressure: str = "resistance"
    doc: str = ""
    h_out: str | None = None
    h_source: bool = True
    pressure_param: str | None = None
    m_eps: float = 1e-6
    band: float | str | None = None


def flow_through_ports(
    m_eps: float, outlet_h: str = "inlet.h", band: float | str | None = None
) -> list[FluidPort]:
    """The inlet and outlet of a component without storage whose one mass flow
    variable ``m`` [kg/s] passes both ports (valves, pumps, turbines). Fluid leaving
    through the inlet (reverse flow) carries the outlet node's h; fluid leaving
    through the outlet carries ``outlet_h``: the inlet node's h for a throttle
    (isenthalpic), the component's own outlet enthalpy (e.g. "h_2") for a machine.
    ``m_eps`` [kg/s]: the flow scale of the upwind weight at both ports; ``band``:
    a narrower band of it (``FluidPort.band``), the same at both ports."""
    return [
        FluidPort(
            "inlet",
            "inlet",
            "m",
            "resistance",
            h_out="outlet.h",
            h_source=False,
            m_eps=m_eps,
            band=band,
        ),
        FluidPort(
            "outlet",
            "outlet",
            "m",
            "resistance",
            h_out=outlet_h,
            h_source=False,
            m_eps=m_eps,
            band=band,
        ),
    ]


def shaft_work_equations(comp, h_low: str, h_high: str) -> list[Equation]:
    """The shaft power P [W] and its integral W [J] of a machine with one mass flow
    ``m`` [kg/s] (pumps: work in, h_low = "inlet.h", h_high = "h_2"; turbines: work
    out, h_low = "h_2", h_high = "inlet.h"):

      power   P = w(m) (h_high - h_low)    w: smooth max(m, 0), physics.upwind_weight
      work    dW/dt = P
    """
    from dnasim.model.physics import upwind_weight

    return [
        Equation(
            "power",
            y=("P", "m", h_high, h_low),
            unit="W",
            doc=f"P = w(m) ({h_high} - {h_low})",
            residual=lambda t, x, xp: (
                x["P"] - float(upwind_weight(x["m"], comp.m_eps)) * (x[h_high] - x[h_low])
            ),
        ),
        Equation(
            "work",
            y=("P",),
            yp=("W",),
            unit="W",
            doc="dW/dt = P",
            residual=lambda t, x, xp: xp["W"] - x["P"],
        ),
    ]


@dataclass(frozen=True)
class SignalPort:
    """A signal port carrying one scalar. For an output, ``variable`` is the
    component variable exposed."""

    name: str
    unit: str = "1"
    doc: str = ""
    variable: str | None = None


@dataclass(frozen=True)
class Variable:
    """An internal variable of a component.

    nominal: a typical magnitude, in ``unit``; used for the absolute error
    tolerance (atol_i = atol * max(nominal_i, |y0_i|)) and for scaling Newton steps.
    size: None for a scalar, n for a vector with elements "name[0]".."name[n-1]".
    accumulator: a running integral (e.g. mass that has passed a boundary) that
    nothing else depends on; a steady-state start keeps it at its initial value
    instead of forcing its derivative to zero.
    min, max: the physical range, in ``unit`` (None: unbounded), e.g. a fluid mass
    M >= 0 kg. A run whose state reaches it stops there with a message naming the
    component, the variable, the limit and the time (``dnasim.compilation.limits``).
    Whether a variable is differential is not declared here: it is differential
    when some equation declares its derivative.
    """

    name: str
    unit: str
    nominal: float = 1.0
    size: int | None = None
    doc: str = ""
    accumulator: bool = False
    min: float | None = None
    max: float | None = None


@dataclass(frozen=True)
class Equation:
    """One scalar residual equation, declared once: its name, its dependencies and
    (for components that use the base ``residual``) the function that evaluates it.

    y:  local names of the variables it touches;
    yp: local names of the variables whose time derivative it touches;
    unit: the unit of the residual (e.g. "W", "kg/s");
    residual: ``f(t, x, xp) -> float``. When every equation of a component has one,
    ``Component.residual`` is derived from the list (in its order), so the docs
    (``dnasim components``), the sparsity and the residual come from one place.
    A component with ``row_reads`` gives none: its equations' residuals are written
    once, together, in ``Component.row_values``.

    A vector equation (``size=n``, e.g. the mass balance of each of a pipe's n
    volumes) stands for n scalar rows named "name[0]" ... "name[n-1]". Then ``y``
    and ``yp`` are functions ``i -> tuple of local names`` giving row i's own
    dependencies (a plain tuple means the same names in every row), and
    ``residual(t, x, xp)`` returns an array of n values, row i at index i. A
    scalar equation (``size=None``, the default) is exactly as described above.
    """

    name: str
    y: tuple[str, ...] | Callable = ()
    yp: tuple[str, ...] | Callable = ()
    doc: str = ""
    unit: str = ""
    residual: Callable | None = field(default=None, compare=False, repr=False)
    size: int | None = None

    @property
    def n_rows(self) -> int:
        """Number of scalar residual rows: 1, or ``size`` for a vector equation."""
        return 1 if self.size is None else int(self.size)

    def rows(self) -> list[tuple[str, tuple[str, ...], tuple[str, ...]]]:
        """The scalar rows as (name, y, yp): one for a scalar equation, ``size`` for a
        vector equation ("name[i]" with the dependencies of row i)."""
        if self.size is None:
            return [(self.name, tuple(self.y), tuple(self.yp))]
        y, yp = self.y, self.yp
        return [
            (
                f"{self.name}[{i}]",
                tuple(y(i)) if callable(y) else tuple(y),
                tuple(yp(i)) if callable(yp) else tuple(yp),
            )
            for i in range(int(self.size))
        ]


@dataclass
class Switch:
    """A switch function g(t, x, xp) of the component's local variables.

    The integrator locates the zero crossings of g in the given direction
    (-1: from positive to negative, +1: the reverse, 0: both) and then calls
    ``action(t, x, xp)``, which changes the component's discrete state (and so the
    form of its residual). Convention used here: g is positive while the current
    mode is valid and crosses to negative when the mode must change.

    size: 1 for a scalar g, else g returns an array of ``size`` values (a vector
    switch, e.g. one entry per volume and phase line); ``names`` then names each
    entry. restart: restart at order 1 at the located crossing although there is
    no action (a kink of the residual, e.g. a property crossing a phase line).
    terminal: stop the run at the crossing; ``message(t)`` then gives the plain
    reason (used by ``dnasim.run.results``). kink: g marks a kink of the residual (a
    phase line); the solver then takes finite differences on the side of the point
    and cuts a failed step at the predicted crossing (``dnasim.solver``). rearm: the
    action makes g positive again (a mode toggle whose new mode has its own g), so an
    entry found past zero after a restart and moving further has crossed again
    (``dnasim.solver.events.SwitchFunction.missed``). notice: the action only records a
    notice (a warning in the component's modes) and changes no equation, so the steady
    start does not treat it as a mode to balance; ``init_discrete_state`` reports the
    state at the start instead (a pump's cavitation warning).
    """

    name: str
    function: Callable
    direction: int = -1
    action: Callable | None = None
    doc: str = ""
    size: int = 1
    restart: bool = False
    terminal: bool = False
    names: list | None = None
    message: Callable | None = None
    kink: bool = False
    rearm: bool = False
    notice: bool = False


@dataclass(frozen=True)
class Output:
    """A derived output (not a variable), e.g. an outlet temperature [K]."""

    name: str
    unit: str
    doc: str = ""
