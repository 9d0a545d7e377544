"""Signal blocks: gain, sum, product, division, first-order lag, limiter, rate limiter,
table, dead time; sources step, ramp, table and sine.

Each block reads signal inputs (``u``, or ``u1`` .. ``un``) and gives the signal
output ``y``. Inputs take any unit; the output has the unit of the first input,
unless the block's ``unit`` parameter names another (a ``Gain`` from a pressure
[Pa] to a valve opening: ``k = 1e-6``, ``unit = "1"``). Parameters in the unit of
the signal (limits, table values, y0) are plain numbers in SI units.

  Gain           y = k u
  Sum            y = bias + w1 u1 + ... + wn un                 (n = n_inputs, 1..4)
  Product        y = k u1 u2                  [unit of u1 times unit of u2]
  Division       y = k u1 u2 / (u2^2 + eps^2)  (= k u1/u2 for |u2| >> eps) [u1/u2]
  FirstOrderLag  T dy/dt = k u - y
  Limiter        y = u in [y_min, y_max], y = y_max above, y = y_min below
  RateLimiter    T dy/dt = u - y, its rate held within [-R_down, R_up]
  Table          y = f(u), piecewise linear through (x_i, y_i), flat outside
  DeadTime       n first-order lags of T_dead/n in series (approximation)

Sources (no input; ``dnasim.core.timefunctions``, their jumps are time events that the
integrator stops at):

  Step           y = before for t < t0, after for t >= t0
  Ramp           y = start before t0, end after t1, linear between
  TableSource    y = piecewise linear through (times_i, values_i), flat outside
  Sine           y = offset + amplitude sin(2 pi t/period + phase)   (no jumps)

A Sine has no breakpoints. So that the integrator's step-size control follows the
wave (the algebraic unknowns are not part of its error test, and a sine that only
drives algebraic relations, a valve between two boundaries, would otherwise be
stepped over by steps of a period or more), its output is a differential state
locked to the wave:

  T_w dy/dt = T_w df/dt + (f(t) - y),   T_w = period/(2 pi),  y(t0) = f(t0)

whose exact solution is y = f(t) (the error e = y - f obeys T_w de/dt = -e: the
integration error is damped, it does not accumulate over the periods); y is held
at f(t0) by a steady start (an accumulator). The steps then resolve the wave to
the run's tolerances (measured in tests/test_product_division_sine.py).

Division's protection near u2 = 0: the Tikhonov-regularised reciprocal
u2/(u2^2 + eps^2) is smooth, odd and bounded (|y| <= |k u1|/(2 eps)), and equals
1/u2 to the relative error (eps/u2)^2 (1e-6 at |u2| = 1000 eps). eps [unit of u2]
is the parameter ``eps`` (default 1e-6): set it well below the divisor's smallest
meaningful magnitude. A crossing of u2 through zero is a switch ("divisor sign")
that the integrator locates and logs in the results' events (events.csv), with
``stop_at_zero = true`` it ends the run there with that message.

Limits are switch functions with modes (as the controller's output limits: one
implementation, ``dnasim.library.submodels.limited_output``), never clips inside
Newton: in each mode the residual is smooth, and the integrator locates the crossing
and restarts at order 1.

Limiter modes: "free" (y = u), "high" (y = y_max), "low" (y = y_min); switch
"upper": free: y_max - u (enter "high" when it crosses zero), high: u - y_max
(back to "free"); "lower" likewise with u - y_min and y_min - u.

RateLimiter: the free mode is a lag of time constant T (default 0.1 s), whose
rate (u - y)/T is held within [-R_down, R_up]: mode "up" dy/dt = R_up, mode "down"
dy/dt = -R_down. Switches: free -> up when R_up - (u - y)/T crosses zero, up ->
free when (u - y)/T - R_up does (and down alike). A step of u by D > R_up T from
rest gives y(t) = y0 + R_up t until u - y = R_up T, then the lag's exponential
approach. (An ideal rate limiter, y = u when the rate is small, changes the
differential index between modes; the lag keeps every mode index 1.)

Table: the segment i (x_i <= u < x_{i+1}) is a discrete mode; in it y = y_i +
(y_{i+1} - y_i)(u - x_i)/(x_{i+1} - x_i), extended linearly beyond the segment
ends, and the vector switch (u - x_i, x_{i+1} - u) moves to the next segment
when u leaves it. Outside the table y is held at the end values.

DeadTime is an approximation of the delay e^{-s T_dead} by n lags 1/(1 + s T_dead/n)
in series (default n = 10): the step response has mean delay T_dead exactly and
standard deviation T_dead/sqrt(n) (an Erlang distribution), steady-state gain 1.
It is not a pure delay: a step comes out smoothed. Larger n is closer (and costs
n variables).
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import PlantError
from dnasim.core.timefunctions import Ramp as _RampFunction
from dnasim.core.timefunctions import Sine as _SineFunction
from dnasim.core.timefunctions import Step as _StepFunction
from dnasim.core.timefunctions import Table as _TableFunction
from dnasim.library.submodels.limited_output import LIMITED, RATE_LIMITED
from dnasim.model.component import Component, Equation, Param, SignalPort, Switch, Variable

__all__ = [
    "Gain",
    "Sum",
    "FirstOrderLag",
    "Limiter",
    "RateLimiter",
    "Table",
    "DeadTime",
    "Step",
    "Ramp",
    "TableSource",
    "Product",
    "Division",
    "Sine",
]


def _unit_param():
    return Param(
        "unit",
        "1",
        None,
        'unit of the output y (SI, e.g. "1", "Pa", "kg/s"; default: the unit of the input)',
        kind="string",
    )


class _Block(Component):
    """Base of the blocks: one input ``u`` (any unit), one output ``y``."""

    REGISTER = False
    USES_MEDIUM = False
    SIGNAL_INPUTS = (SignalPort("u", "*", "input signal (any unit)"),)
    SIGNAL_OUTPUTS = (SignalPort("y", "*", "output signal", variable="y"),)

    def setup(self):
        unit = self.params.get("unit")
        if unit is not None:
            from dnasim.core.units import UnitError, parse_unit

            try:
                parse_unit(unit)
            except UnitError as err:
                raise PlantError(f"component '{self.name}': parameter 'unit': {err}") from None

    @property
    def out_unit(self) -> str:
        """The output's unit: the ``unit`` parameter, else the first input's unit."""
        unit = self.params.get("unit")
        if unit is not None:
            return unit
        ins = getattr(self, "input_units", {})
        first = self.signal_inputs()[0].name if self.signal_inputs() else None
        return ins.get(first, "*") if first else "1"

    def signal_outputs(self):
        unit = self.params.get("unit") or "*"
        return [SignalPort("y", unit, "output signal", variable="y")]

    def variables(self):
        u = self.out_unit
        return [Variable("y", "1" if u == "*" else u, 1.0, doc="output")]


class Gain(_Block):
    """y = k u.  k [unit of y per unit of u]."""

    PARAMS = (Param("k", "1", 1.0, "gain [output unit per input unit]"), _unit_param())

    def equations(self):
        k = self.params["k"]
        return [
            Equation(
                "gain", y=("y", "u"), doc="y = k u", residual=lambda t, x, xp: x["y"] - k * x["u"]
            )
        ]


class Sum(_Block):
    """y = bias + w1 u1 + ... + wn un, n = ``n_inputs`` (1..4)."""

    PARAMS = (
        Param("n_inputs", "1", 2, "number of inputs u1 .. un", min=1, max=4, kind="int"),
        Param("w1", "1", 1.0, "weight of u1"),
        Param("w2", "1", 1.0, "weight of u2"),
        Param("w3", "1", 1.0, "weight of u3"),
        Param("w4", "1", 1.0, "weight of u4"),
        Param("bias", "1", 0.0, "constant added [unit of y]"),
        _unit_param(),
    )
    SIGNAL_INPUTS = tuple(SignalPort(f"u{i}", "*", f"input {i}") for i in range(1, 5))

    def signal_inputs(self):
        return list(self.SIGNAL_INPUTS[: self.params["n_inputs"]])

    def equations(self):
        n = self.params["n_inputs"]
        w = [self.params[f"w{i}"] for i in range(1, n + 1)]
        bias = self.params["bias"]
        names = [f"u{i}" for i in range(1, n + 1)]
        return [
            Equation(
                "sum",
                y=("y", *names),
                doc="y = bias + sum_i w_i u_i",
                residual=lambda t, x, xp: (
                    x["y"] - bias - sum(wi * x[nm] for wi, nm in zip(w, names, strict=True))
                ),
            )
        ]


def _wrapped(unit: str) -> str:
    """``unit`` as a factor of a product or a quotient: in parentheses when compound."""
    return unit if all(c.isalnum() or c == "_" for c in unit) else f"({unit})"


#: SI units a derived unit is written as when it is one of them ("(kg/s).(J/kg)" -> "W")
FAMILIAR_UNITS = (
    "1", "Pa", "K", "kg/s", "J/kg", "W", "J", "kg", "m", "m2", "m3", "s", "1/s", "kg/m3",
    "m3/s", "m/s", "N", "W/K", "J/K", "J/(kg.K)", "W/m2", "Pa/s", "K/s",
)  # fmt: skip


def _familiar(unit: str) -> str:
    """``unit``, or the member of FAMILIAR_UNITS with its dimension and scale 1."""
    from dnasim.core.units import UnitError, parse_unit

    try:
        u = parse_unit(unit)
    except UnitError:
        return unit
    if u.scale != 1.0 or u.offset != 0.0:
        return unit
    for name in FAMILIAR_UNITS:
        if parse_unit(name).dims == u.dims:
            return name
    return unit


def unit_product(a: str, b: str) -> str:
    """The unit string of a product of quantities in SI units a and b ("*" if either
    is): "a.b", or a familiar SI unit of that dimension ("(kg/s).(J/kg)" -> "W")."""
    if "*" in (a, b):
        return "*"
    if a == "1":
        return b
    if b == "1":
        return a
    return _familiar(f"{_wrapped(a)}.{_wrapped(b)}")


def unit_quotient(a: str, b: str) -> str:
    """The unit string of a quotient a/b of SI units ("*" if either is), as
    ``unit_product`` ("W"/"kg/s" -> "J/kg", "kg/s"/"kg/s" -> "1")."""
    if "*" in (a, b):
        return "*"
    if b == "1":
        return a
    if a == b:
        return "1"
    return _familiar(f"{_wrapped(a)}/{_wrapped(b)}")


class _TwoInputs(_Block):
    """Base of Product and Division: inputs u1, u2 (any units), output y in the unit the
    block derives from them (or its ``unit`` parameter)."""

    REGISTER = False
    SIGNAL_INPUTS = (
        SignalPort("u1", "*", "first input (any unit)"),
        SignalPort("u2", "*", "second input (any unit)"),
    )

    @staticmethod
    def combine(a: str, b: str) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def signal_output_unit(self, output, input_units):
        """y's unit from the units of u1 and u2 (``combine``); "*" until both are known."""
        unit = self.params.get("unit")
        if unit is not None:
            return unit
        return self.combine(input_units.get("u1", "*"), input_units.get("u2", "*"))

    @property
    def out_unit(self) -> str:
        ins = getattr(self, "input_units", {})
        return self.signal_output_unit("y", ins)


class Product(_TwoInputs):
    """y = k u1 u2.  The unit of y: the unit of u1 times the unit of u2 (k [1]), or the
    ``unit`` parameter (k then in that unit per unit of u1 u2)."""

    PARAMS = (Param("k", "1", 1.0, "gain [output unit per unit of u1 u2]"), _unit_param())
    combine = staticmethod(unit_product)

    def equations(self):
        k = self.params["k"]
        return [
            Equation(
                "product",
                y=("y", "u1", "u2"),
                doc="y = k u1 u2",
                residual=lambda t, x, xp: x["y"] - k * x["u1"] * x["u2"],
            )
        ]

    def initial_guess(self, t0, x):
        x["y"] = self.params["k"] * x["u1"] * x["u2"]


class Division(_TwoInputs):
    """y = k u1 u2/(u2^2 + eps^2): k u1/u2, protected near u2 = 0 (module doc). The unit
    of y: the unit of u1 over the unit of u2, or the ``unit`` parameter.

    Switch "divisor sign": g = u2 (both directions), located and logged when the
    divisor crosses zero; with ``stop_at_zero`` the run ends there."""

    PARAMS = (
        Param("k", "1", 1.0, "gain [output unit per unit of u1/u2]"),
        Param("eps", "1", 1e-6, "protection of the divisor near 0 [unit of u2]", min=0.0),
        Param("stop_at_zero", "1", False, "end the run when u2 crosses zero", kind="bool"),
        _unit_param(),
    )
    combine = staticmethod(unit_quotient)

    def setup(self):
        super().setup()
        if not self.params["eps"] > 0:
            raise PlantError(
                f"component '{self.name}': eps must be > 0 (the divisor's protection near 0)"
            )

    def quotient(self, u1: float, u2: float) -> float:
        """k u1 u2/(u2^2 + eps^2) [unit of y]."""
        eps = self.params["eps"]
        return self.params["k"] * u1 * u2 / (u2 * u2 + eps * eps)

    def equations(self):
        return [
            Equation(
                "division",
                y=("y", "u1", "u2"),
                doc="y = k u1 u2/(u2^2 + eps^2)",
                residual=lambda t, x, xp: x["y"] - self.quotient(x["u1"], x["u2"]),
            )
        ]

    def switches(self):
        stop = bool(self.params["stop_at_zero"])
        return [
            Switch(
                "divisor sign",
                lambda t, x, xp: x["u2"],
                0,
                None,
                "the divisor u2 crosses zero",
                terminal=stop,
                message=(
                    (lambda t: f"the divisor u2 of '{self.name}' crossed zero at t = {t:.6g} s")
                    if stop
                    else None
                ),
            )
        ]

    def initial_guess(self, t0, x):
        x["y"] = self.quotient(x["u1"], x["u2"])


class FirstOrderLag(_Block):
    """T dy/dt = k u - y.  Step of u by D from rest: y = k D (1 - exp(-t/T))."""

    PARAMS = (
        Param("T", "s", doc="time constant", min=0.0),
        Param("k", "1", 1.0, "steady-state gain"),
        Param("y0", "1", None, "initial output (given start; default: k u at t0)"),
        _unit_param(),
    )

    def setup(self):
        super().setup()
        if not self.params["T"] > 0:
            raise PlantError(f"component '{self.name}': T must be > 0 s (use a Gain for T = 0)")

    def equations(self):
        T, k = self.params["T"], self.params["k"]
        return [
            Equation(
                "lag",
                y=("y", "u"),
                yp=("y",),
                doc="T dy/dt = k u - y",
                residual=lambda t, x, xp: T * xp["y"] - (k * x["u"] - x["y"]),
            )
        ]

    def initial_guess(self, t0, x):
        y0 = self.params["y0"]
        x["y"] = y0 if y0 is not None else self.params["k"] * x["u"]


class _Modes(_Block):
    """A block with a limited quantity (``LIMITS``: a ``LimitedOutput``)."""

    REGISTER = False
    LIMITS = LIMITED

    def reset_discrete_state(self, modes):
        self.LIMITS.reset(modes)

    def _mode(self, x):
        return self.LIMITS.mode(x.modes)


class Limiter(_Modes):
    """y = u (mode free), y = y_max (high), y = y_min (low).

    Switches, positive while the mode holds: upper: free: y_max - u (enter high),
    high: u - y_max (back to free); lower: free: u - y_min, low: y_min - u.
    """

    PARAMS = (
        Param("y_min", "1", doc="lower limit [unit of u]"),
        Param("y_max", "1", doc="upper limit [unit of u]"),
    )

    def setup(self):
        if not self.params["y_max"] > self.params["y_min"]:
            raise PlantError(f"component '{self.name}': y_max must be greater than y_min")

    def equations(self):
        return [
            Equation(
                "limit",
                y=("y", "u"),
                doc="y = u (free), y_max (high), y_min (low)",
                residual=self._limit,
            )
        ]

    def _limit(self, t, x, xp):
        P = self.params
        return x["y"] - LIMITED.target(self._mode(x), x["u"], P["y_min"], P["y_max"])

    def switches(self):
        P = self.params
        return LIMITED.switches(
            lambda t, x, xp: x["u"],
            lambda t, x: P["y_min"],
            lambda t, x: P["y_max"],
            docs=("enter/leave y = y_max", "enter/leave y = y_min"),
        )

    def init_discrete_state(self, t0, x, xp):
        return LIMITED.start(x.modes, x["u"], self.params["y_min"], self.params["y_max"])


class RateLimiter(_Modes):
    """Rate limiter: T dy/dt = u - y (mode free), dy/dt = R_up (up), dy/dt = -R_down (down).

    Switches, positive while the mode holds: up: free: R_up - (u - y)/T (enter),
    up: (u - y)/T - R_up (leave); down alike. A step of u by D > R_up T from rest
    gives y = y0 + R_up t until u - y = R_up T, then the lag's exponential
    approach. T (default 0.1 s) keeps every mode index 1 (an ideal y = u would not).
    """

    LIMITS = RATE_LIMITED

    PARAMS = (
        Param("R_up", "1/s", doc="largest rising rate [unit of u per second]", min=0.0),
        Param("R_down", "1/s", None, "largest falling rate [unit of u per second]; default R_up"),
        Param("T", "s", 0.1, "time constant of the free mode", min=0.0),
        Param("y0", "1", None, "initial output (given start; default: u at t0)"),
    )

    def setup(self):
        P = self.params
        if P["R_down"] is None:
            P["R_down"] = P["R_up"]
        if not (P["R_up"] > 0 and P["R_down"] > 0 and P["T"] > 0):
            raise PlantError(f"component '{self.name}': R_up, R_down and T must be > 0")

    def equations(self):
        return [
            Equation(
                "rate",
                y=("y", "u"),
                yp=("y",),
                doc="T dy/dt = u - y (free), dy/dt = R_up (up), -R_down (down)",
                residual=self._rate,
            )
        ]

    def _rate(self, t, x, xp):
        P, mode = self.params, self._mode(x)
        if mode == "up":
            return xp["y"] - P["R_up"]
        if mode == "down":
            return xp["y"] + P["R_down"]
        return P["T"] * xp["y"] - (x["u"] - x["y"])

    def _free_rate(self, x):
        return (x["u"] - x["y"]) / self.params["T"]

    def switches(self):
        P = self.params
        return RATE_LIMITED.switches(
            lambda t, x, xp: self._free_rate(x),
            lambda t, x: -P["R_down"],
            lambda t, x: P["R_up"],
            names=("up", "down"),
            docs=("enter/leave dy/dt = R_up", "enter/leave dy/dt = -R_down"),
        )

    def init_discrete_state(self, t0, x, xp):
        P = self.params
        return RATE_LIMITED.start(x.modes, self._free_rate(x), -P["R_down"], P["R_up"])

    def initial_guess(self, t0, x):
        y0 = self.params["y0"]
        x["y"] = y0 if y0 is not None else x["u"]


def _points(comp, xs, ys, xname, yname):
    try:
        x = np.asarray(xs, dtype=float).reshape(-1)
        y = np.asarray(ys, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise PlantError(
            f"component '{comp}': '{xname}' and '{yname}' must be lists of numbers"
        ) from None
    if x.size < 2 or x.size != y.size:
        raise PlantError(
            f"component '{comp}': '{xname}' and '{yname}' need the same number of points, at "
            f"least 2 (got {x.size} and {y.size})"
        )
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise PlantError(f"component '{comp}': '{xname}' and '{yname}' must be finite")
    if np.any(np.diff(x) <= 0):
        raise PlantError(f"component '{comp}': '{xname}' must be strictly increasing")
    return x, y


class Table(_Block):
    """y = f(u), piecewise linear through (x_i, y_i), held flat outside.

    The segment i (x_i <= u < x_{i+1}) is a mode: y = y_i + (y_{i+1} - y_i)(u - x_i)
    / (x_{i+1} - x_i); the vector switch (u - x_i, x_{i+1} - u) moves to the
    neighbouring segment when u leaves it (no kink inside Newton).
    """

    PARAMS = (
        Param("x", "1", doc="input values x_i, strictly increasing [unit of u]", kind="array"),
        Param("y", "1", doc="output values y_i [unit of y]", kind="array"),
        _unit_param(),
    )

    def setup(self):
        super().setup()
        self.xs, self.ys = _points(self.name, self.params["x"], self.params["y"], "x", "y")

    def reset_discrete_state(self, modes):
        modes["segment"] = 0

    def _segment(self, x) -> int:
        """-1: below x_0; n-1: above x_{n-1}; else the segment i in [x_i, x_{i+1})."""
        return x.modes.get("segment", 0)

    def _f(self, i, u):
        xs, ys = self.xs, self.ys
        if i < 0:
            return ys[0]
        if i >= xs.size - 1:
            return ys[-1]
        return ys[i] + (ys[i + 1] - ys[i]) * (u - xs[i]) / (xs[i + 1] - xs[i])

    def equations(self):
        return [
            Equation(
                "table",
                y=("y", "u"),
                doc="y = y_i + (y_{i+1} - y_i)(u - x_i)/(x_{i+1} - x_i) in segment i",
                residual=lambda t, x, xp: x["y"] - self._f(self._segment(x), x["u"]),
            )
        ]

    def _edges(self, t, x, xp):
        i, u, xs = self._segment(x), x["u"], self.xs
        lo = u - xs[i] if i >= 0 else 1.0
        hi = xs[i + 1] - u if i < xs.size - 1 else 1.0
        if i < 0:
            hi = xs[0] - u
        if i >= xs.size - 1:
            lo = u - xs[-1]
        return np.array([lo, hi])

    def _move(self, t, x, xp):
        """To the neighbouring segment across the edge whose distance crossed zero."""
        lo, hi = self._edges(t, x, xp)
        i = self._segment(x) + (-1 if lo <= hi else 1)
        x.modes["segment"] = min(max(i, -1), self.xs.size - 1)

    def _locate(self, u) -> int:
        xs = self.xs
        if u < xs[0]:
            return -1
        if u >= xs[-1]:
            return xs.size - 1
        return int(np.searchsorted(xs, u, side="right") - 1)

    def switches(self):
        return [
            Switch(
                "segment",
                self._edges,
                -1,
                self._move,
                "u leaves the table segment (lower edge, upper edge)",
                size=2,
                names=["segment lower edge", "segment upper edge"],
            )
        ]

    def init_discrete_state(self, t0, x, xp):
        old = self._segment(x)
        x.modes["segment"] = self._locate(x["u"])
        return x.modes["segment"] != old


class DeadTime(_Block):
    """Dead time T_dead approximated by n lags of T_dead/n in series (see the module doc).

    (T_dead/n) dz_1/dt = u - z_1,  (T_dead/n) dz_k/dt = z_{k-1} - z_k,  y = z_n
    """

    PARAMS = (
        Param("T_dead", "s", doc="dead time (mean delay of the approximation)", min=0.0),
        Param("n_stages", "1", 10, "number of lags in series", min=1, max=200, kind="int"),
    )

    def setup(self):
        if not self.params["T_dead"] > 0:
            raise PlantError(f"component '{self.name}': T_dead must be > 0 s")

    def variables(self):
        u = self.out_unit
        n = self.params["n_stages"]
        unit = "1" if u == "*" else u
        out = [Variable("z", unit, 1.0, size=n - 1, doc="inner stages")] if n > 1 else []
        return out + [Variable("y", unit, 1.0, doc="output (last stage)")]

    def equations(self):
        n = self.params["n_stages"]
        tau = self.params["T_dead"] / n
        names = ["u"] + [f"z[{k}]" for k in range(n - 1)] + ["y"]
        eqs = []
        for k in range(1, n + 1):
            a, b = names[k - 1], names[k]
            eqs.append(
                Equation(
                    f"stage{k}",
                    y=(a, b),
                    yp=(b,),
                    doc=f"(T_dead/n) d{b}/dt = {a} - {b}",
                    residual=lambda t, x, xp, a=a, b=b: tau * xp[b] - (x[a] - x[b]),
                )
            )
        return eqs

    def initial_guess(self, t0, x):
        n = self.params["n_stages"]
        u = x["u"]
        if n > 1:
            x["z"] = np.full(n - 1, u)
        x["y"] = u


class _Source(Component):
    """Base of the sources: y = f(t), output ``y`` in the unit of ``unit``."""

    REGISTER = False
    USES_MEDIUM = False

    def setup(self):
        _Block.setup(self)
        self.function = self._function()

    def _function(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def signal_outputs(self):
        return [SignalPort("y", self.params["unit"], "source signal", variable="y")]

    def variables(self):
        return [Variable("y", self.params["unit"], 1.0, doc="output")]

    def breakpoints(self):
        return [float(b) for b in self.function.breakpoints]

    def equations(self):
        f = self.function
        return [
            Equation("source", y=("y",), doc="y = f(t)", residual=lambda t, x, xp: x["y"] - f(t))
        ]

    def initial_guess(self, t0, x):
        x["y"] = self.function(t0)


def _source_unit():
    return Param(
        "unit", "1", "1", 'unit of the output y (SI: "1", "Pa", "K", "kg/s", ...)', kind="string"
    )


class Step(_Source):
    """y = before for t < t0, after for t >= t0 (values in SI units of ``unit``)."""

    PARAMS = (
        Param("t0", "s", 0.0, "time of the step"),
        Param("before", "1", 0.0, "value before t0"),
        Param("after", "1", 1.0, "value from t0 on"),
        _source_unit(),
    )

    def _function(self):
        P = self.params
        return _StepFunction(P["t0"], P["before"], P["after"])


class Ramp(_Source):
    """y = start before t0, end after t1, linear between (SI units of ``unit``)."""

    PARAMS = (
        Param("t0", "s", 0.0, "start of the ramp"),
        Param("t1", "s", doc="end of the ramp"),
        Param("start", "1", 0.0, "value up to t0"),
        Param("end", "1", 1.0, "value from t1 on"),
        _source_unit(),
    )

    def _function(self):
        P = self.params
        if not P["t1"] > P["t0"]:
            raise PlantError(f"component '{self.name}': t1 must be later than t0")
        return _RampFunction(P["t0"], P["t1"], P["start"], P["end"])


class TableSource(_Source):
    """y piecewise linear through (times_i, values_i), held flat outside."""

    PARAMS = (
        Param("times", "s", doc="times, strictly increasing [s]", kind="array"),
        Param("values", "1", doc="values [SI unit of ``unit``]", kind="array"),
        _source_unit(),
    )

    def _function(self):
        t, v = _points(self.name, self.params["times"], self.params["values"], "times", "values")
        return _TableFunction(list(t), list(v))


class Sine(_Source):
    """y = offset + amplitude sin(2 pi t/period + phase) (SI units of ``unit``); give
    ``period`` [s] or ``frequency`` [Hz]. No breakpoints; y is a differential state
    locked to the wave, T_w dy/dt = T_w df/dt + (f - y), T_w = period/(2 pi) (module
    doc), so that the step size follows the wave."""

    PARAMS = (
        Param("amplitude", "1", doc="amplitude [unit of y]"),
        Param("period", "s", None, "period (or give frequency)", min=0.0),
        Param("frequency", "Hz", None, "frequency 1/period (or give period)", min=0.0),
        Param("phase", "rad", 0.0, "phase at t = 0"),
        Param("offset", "1", 0.0, "mean value [unit of y]"),
        _source_unit(),
    )

    def _function(self):
        P = self.params
        given = [k for k in ("period", "frequency") if P[k] is not None]
        if len(given) != 1:
            raise PlantError(
                f"component '{self.name}': give exactly one of period and frequency"
                + (f" (got {' and '.join(given)})" if given else "")
            )
        period = P["period"] if P["period"] is not None else 1.0 / P["frequency"]
        if not (period > 0 and math.isfinite(period)):
            raise PlantError(f"component '{self.name}': the period must be > 0 s")
        return _SineFunction(P["offset"], P["amplitude"], period, P["phase"])

    def variables(self):
        P = self.params
        nominal = max(abs(P["amplitude"]) + abs(P["offset"]), 1e-300)
        return [
            Variable(
                "y",
                self.params["unit"],
                nominal,
                doc="output (a state locked to the wave)",
                accumulator=True,
            )
        ]

    def equations(self):
        f = self.function
        T_w = f.period / (2.0 * math.pi)
        amp, phase = f.amplitude, f.phase

        def rate(t):  # df/dt
            return amp / T_w * math.cos(t / T_w + phase)

        return [
            Equation(
                "source",
                y=("y",),
                yp=("y",),
                doc="T_w dy/dt = T_w df/dt + (f(t) - y), T_w = period/(2 pi)",
                residual=lambda t, x, xp: T_w * (xp["y"] - rate(t)) - (f(t) - x["y"]),
            )
        ]
