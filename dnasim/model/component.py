"""Declarations every component is built from, and the ``Component`` base class.

A component declares, in plain Python:

* ``PARAMS``: ``Param`` objects (name, SI unit, default, doc, bounds, whether the
  value may be a function of time);
* fluid ports (``FluidPort``): a fluid port is bound to a network node that carries
  the pressure ``p`` [Pa] and the specific enthalpy ``h`` [J/kg]; the component
  carries the mass flow through the port in one of its own variables;
* signal ports (``SignalPort``): a signal input reads one scalar owned by another
  component; a signal output exposes one of the component's own variables;
* variables (``Variable``): name, unit, nominal scale, optional vector size;
* equations (``Equation``): each one names the local variables it touches and the
  local variables whose time derivatives it touches. The global sparsity pattern
  of the DAE is built from these declarations alone.
  A vector equation (``Equation(..., size=n)``) declares n rows "name[0]" ...
  "name[n-1]" at once, each with its own dependencies (``y=lambda i: ...``), and
  one residual function returning the n values (a pipe's n mass balances);
* the residuals, in the order of ``equations()``, written once, in one of two ways:
  each ``Equation`` carries its residual function (``residual=f(t, x, xp)``;
  ``prepare(t, x, xp)`` computes once what several equations share, e.g. one
  property call for all volumes, and hands it to them as ``x.work``), or the
  component gives ``row_reads()`` (the local names it reads from y and y') and
  ``row_values(t, v, vp, modes)``, all its residuals on plain floats from those
  values, and its ``Equation`` declarations carry no functions (the boundaries,
  valves, sensors, controllers, attemperators and junctions: the System evaluates
  them together in one ``ScalarRows`` over plant-wide index arrays). In both ways
  ``residual(t, x, xp)`` is derived (a component may also override it, as the pipe
  does);
* switch functions (``Switch``) with their actions, for discrete state;
* ``initial_guess``: values for its variables before initialisation.

Local variable names seen by a component:

* ``"<port>.p"`` and ``"<port>.h"`` for each fluid port (the node's p and h);
* its own variables, a vector variable ``"M"`` of size n has elements
  ``"M[0]"`` ... ``"M[n-1]"``; ``x["M"]`` returns the whole vector;
* ``"<signal input>"`` for each signal input (an alias of another component's
  output variable).

The framework (``dnasim.compilation.system``) maps these local names into the global
vector. Components never see the solver.

Flows and enthalpies (stream variables, see ``dnasim.compilation.system``): a fluid port
is an ``"inlet"`` or an ``"outlet"``; this is only the sign convention of the
port's flow variable (positive in the design direction: into the component at
an inlet, out of it at an outlet). Flow may go either way. A node's ``h`` is the
mixed enthalpy of the fluid flowing *into* the node; each port declares
``h_out``, the local name of the enthalpy the component delivers when fluid
leaves it through that port (a storage volume: its own h; a valve: the node h at
its other port; a boundary: its supply enthalpy). Every energy flow at a port
is computed with ``dnasim.model.physics.energy_in`` (upwind by the actual
flow), which makes energy conservation across nodes exact.

The declarations are in ``dnasim.model.declarations`` (``Param``, ports,
``Variable``, ``Equation``, ``Switch``, ``Output``), the evaluation views in
``dnasim.model.evaluation`` (``LocalVector``, ``ScalarRows``); this module holds the
``Component`` base class and ``REGISTRY``, and re-exports every one of those names
(``from dnasim.model.component import Param`` works as before).

Adding a component: subclass ``Component`` in one file, import it in
``dnasim/library/__init__.py`` (or anywhere before use); the subclass
registers itself in ``REGISTRY`` under its class name.
"""

from __future__ import annotations

import inspect
import textwrap

import numpy as np

from dnasim.core.errors import PlantError, Problems
from dnasim.core.timefunctions import TimeFunction, as_time_function
from dnasim.model.declarations import (
    POSITIVE_UNITS,
    REQUIRED,
    Equation,
    FluidPort,
    Output,
    Param,
    SignalPort,
    Switch,
    Variable,
    flow_through_ports,
    shaft_work_equations,
)
from dnasim.model.evaluation import ROWS_KEY, LocalVector, ScalarRows
from dnasim.model.physics import M_EPS_REL

__all__ = [
    "REQUIRED",
    "REGISTRY",
    "Param",
    "FluidPort",
    "flow_through_ports",
    "shaft_work_equations",
    "SignalPort",
    "Variable",
    "Equation",
    "Switch",
    "Output",
    "LocalVector",
    "Component",
    "ScalarRows",
    "ROWS_KEY",
    "POSITIVE_UNITS",
]

#: type name -> component class, filled automatically by ``Component.__init_subclass__``.
REGISTRY: dict[str, type[Component]] = {}


def _has_unit_text(value) -> bool:
    """A unit string, or a time function (dict) with one among its values."""
    if isinstance(value, str):
        return True
    return isinstance(value, dict) and any(
        isinstance(v, str) for k, v in value.items() if k != "type"
    )


def _atmosphere_value(name: str, atmosphere) -> float | None:
    """A component's ``atmosphere`` argument as a pressure [Pa] > 0 (or None)."""
    if atmosphere is None:
        return None
    from dnasim.core.units import UnitError, parse_quantity, to_si

    try:
        x = to_si(atmosphere, "Pa")
    except UnitError as err:
        raise PlantError(f"component '{name}': atmosphere: {err}") from None
    if isinstance(atmosphere, str) and parse_quantity(atmosphere)[1].gauge:
        raise PlantError(
            f"component '{name}': the atmosphere is an absolute pressure (the zero of the "
            f"gauge units), not {atmosphere!r}"
        )
    if not x > 0:
        raise PlantError(f"component '{name}': the atmosphere must be > 0 Pa (got {x:g} Pa)")
    return x


def _check_number(comp, param, value):
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise PlantError(
            f"component '{comp}': parameter '{param.name}' must be a number [{param.unit}], got "
            f"{value!r}"
        )
    value = float(value)
    if not np.isfinite(value):
        raise PlantError(f"component '{comp}': parameter '{param.name}' is not finite ({value!r})")
    problem = param.range_problem(value)
    if problem is not None:
        kind, text = problem
        lead = "is below its minimum: " if kind == "physical" else ""
        raise PlantError(f"component '{comp}': parameter '{param.name}' {lead}{text}")
    return value


class Component:
    """Base class of every component. See the module docstring for the contract.

    Subclasses set ``PARAMS``, ``FLUID_PORTS``, ``SIGNAL_INPUTS``, ``SIGNAL_OUTPUTS``
    (the full lists, used by ``describe()``), and implement ``variables()``,
    ``equations()``, ``residual()``, and usually ``initial_guess()``. When the set
    of ports depends on the parameters, override ``fluid_ports()`` /
    ``signal_inputs()`` too.
    """

    PARAMS: tuple[Param, ...] = ()
    FLUID_PORTS: tuple[FluidPort, ...] = ()
    SIGNAL_INPUTS: tuple[SignalPort, ...] = ()
    SIGNAL_OUTPUTS: tuple[SignalPort, ...] = ()
    #: set to False in a subclass that must not appear in REGISTRY (tests, bases)
    REGISTER = True
    #: True when the component needs a fluid (a medium) at its ports
    USES_MEDIUM = True

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("REGISTER", True):
            old = REGISTRY.get(cls.__name__)
            same = old is not None and (old.__module__, old.__qualname__) == (
                cls.__module__,
                cls.__qualname__,
            )
            if old is not None and not same:  # the same class re-imported is no clash
                raise PlantError(
                    f"component type '{cls.__name__}' ({cls.__module__}) clashes with "
                    f"'{cls.__name__}' from {old.__module__}: component types need unique "
                    "class names; rename the class, or set REGISTER = False for a base class"
                )
            REGISTRY[cls.__name__] = cls

    # ------------------------------------------------------------------ set-up
    def __init__(self, name: str, *, atmosphere: float | str | None = None, **params):
        """``params``: numbers [SI], unit strings ("120 bar", "540 degC"), time
        functions, strings. ``atmosphere``: the ambient pressure [Pa] (or a unit string
        such as "0.95 bar") against which gauge pressures ("5 barg", "70 psig") are
        read; ``None``: the standard atmosphere, 101325 Pa (a plant's ``PlantSpec``
        passes its own)."""
        if not isinstance(name, str) or not name or "." in name or name != name.strip():
            raise PlantError(
                f"{type(self).__name__}: component name must be a non-empty string without '.' or "
                f"spaces, got {name!r}"
            )
        self.name = name
        #: the zero of the gauge pressures in ``params`` [Pa]; None: the standard atmosphere
        self.atmosphere = _atmosphere_value(name, atmosphere)
        known = {p.name: p for p in self.PARAMS}
        unknown = sorted(set(params) - set(known))
        if unknown:
            raise PlantError(
                f"component '{name}' ({type(self).__name__}): unknown parameter(s) "
                f"{', '.join(unknown)}; "
                f"known: {', '.join(known) or 'none'}"
            )
        self.params: dict[str, object] = {}
        #: parameters in the unit of a linked signal given with a unit ("0.5 1/K",
        #: "440 degC"): converted by ``resolve_signal_units`` once the link is known
        self.signal_unit_values: dict[str, object] = {}
        for p in self.PARAMS:
            value = params.get(p.name, p.default)
            if value is REQUIRED:
                raise PlantError(
                    f"component '{name}' ({type(self).__name__}): parameter '{p.name}' [{p.unit}] "
                    "is required" + (f" ({p.doc})" if p.doc else "")
                )
            if p.per_signal and _has_unit_text(value):
                self.signal_unit_values[p.name] = value
                self.params[p.name] = None
                continue
            if p.per_output and _has_unit_text(value):
                # in the output unit ("200 MW" for a PID whose unit is "W"): known now
                value = self._in_output_unit(p, value, params)
            self.params[p.name] = self._validate(p, value)
        self.medium = None  # set by dnasim.compilation.compiler (dnasim.media medium object)
        self.medium_name = self.params.get("medium")
        #: port name -> medium object, set by the compiler (media may differ per port)
        self.port_media: dict = {}
        self.setup()

    def _validate(self, p: Param, value):
        if value is None:
            return None
        if p.kind == "array":
            return self._validate_array(p, value)
        if p.kind not in ("string", "bool") and isinstance(value, str):
            from dnasim.core.units import UnitError

            try:
                # "120 bar" from Python as from a plant file
                value = p.si_value(value, self.atmosphere)
            except UnitError as err:
                raise PlantError(
                    f"component '{self.name}': parameter '{p.name}' [{p.unit}]: {err}"
                ) from None
            if p.kind == "int" and value == int(value):
                value = int(value)
        if p.kind == "string":
            if not isinstance(value, str):
                raise PlantError(
                    f"component '{self.name}': parameter '{p.name}' must be a string, got {value!r}"
                )
            if p.choices is not None and value not in p.choices:
                raise PlantError(
                    f"component '{self.name}': parameter '{p.name}' = {value!r} is not one of "
                    f"{', '.join(map(repr, p.choices))}"
                )
            return value
        if p.kind == "bool":
            if not isinstance(value, (bool, np.bool_)):
                raise PlantError(
                    f"component '{self.name}': parameter '{p.name}' must be true or false, got "
                    f"{value!r}"
                )
            return bool(value)
        if p.kind == "int":
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise PlantError(
                    f"component '{self.name}': parameter '{p.name}' must be an integer, got "
                    f"{value!r}"
                )
            _check_number(self.name, p, value)
            return int(value)
        if p.time_function and not isinstance(value, (int, float, np.integer, np.floating)):
            try:
                f = as_time_function(value)
            except TypeError:
                raise PlantError(
                    f"component '{self.name}': parameter '{p.name}' must be a number [{p.unit}] "
                    f"or a time function, got {value!r}"
                ) from None
            for tt in (0.0, *f.breakpoints):
                _check_number(self.name, p, f(tt))
            return f
        v = _check_number(self.name, p, value)
        return as_time_function(v) if p.time_function else v

    def _in_output_unit(self, p: Param, value, params: dict):
        """``value`` of a parameter in the component's output unit (``Param.per_output``)
        in SI, converted as a plant file's; PlantError naming component and parameter."""
        from dnasim.core.values import output_unit_of, param_value

        errors = Problems(f"component '{self.name}' ({type(self).__name__})")
        x = param_value(
            value,
            p,
            errors,
            (),
            p.name,
            (),
            type(self),
            self.atmosphere,
            output_unit=output_unit_of(type(self), params),
        )
        errors.raise_if_any()
        return x

    def resolve_signal_units(self, signal_units) -> None:
        """Convert the parameters given with a unit whose SI unit depends on the linked
        signal (``Param.per_signal``: a controller's gain "0.5 1/K" or "2 %/bar", its
        set point "440 degC"), now that ``signal_units`` (the units of the signals
        linked into this component) are known. The same conversion and checks as a
        plant file's (``dnasim.core.values.param_value``): "0.02 degC" for a gain is refused.
        Raises PlantError naming the component and the parameter."""
        if not self.signal_unit_values:
            return
        from dnasim.core.values import output_unit_of, param_value

        known = {p.name: p for p in self.PARAMS}
        errors = Problems(f"component '{self.name}' ({type(self).__name__})")
        out_unit = output_unit_of(type(self), self.params)
        for name, raw in self.signal_unit_values.items():
            p = known[name]
            x = param_value(
                raw,
                p,
                errors,
                (),
                name,
                list(signal_units),
                type(self),
                self.atmosphere,
                output_unit=out_unit,
            )
            if x is not None:
                self.params[name] = self._validate(p, x)
        errors.raise_if_any()
        self.signal_unit_values = {}
        # the component's own checks and derived values (a PID's Kp from Kc and
        # measured_span) again, now with these values
        self.setup()

    def _validate_array(self, p: Param, value):
        """A non-empty list of numbers (or unit strings) in ``p.unit``, each checked
        like a number parameter; returned as a tuple of floats [SI]."""
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) == 0:
            raise PlantError(
                f"component '{self.name}': parameter '{p.name}' must be a non-empty list of "
                f"numbers [{p.unit}], got {value!r}"
            )
        out = []
        for v in value:
            if isinstance(v, str):
                from dnasim.core.units import UnitError

                try:
                    v = p.si_value(v, self.atmosphere)
                except UnitError as err:
                    raise PlantError(
                        f"component '{self.name}': parameter '{p.name}' [{p.unit}]: {err}"
                    ) from None
            out.append(_check_number(self.name, p, v))
        return tuple(out)

    def setup(self):
        """Hook: check parameter combinations, precompute derived constants."""

    # ------------------------------------------------------------- parameters
    def param_at(self, name: str, t: float) -> float:
        """Value of parameter ``name`` at time t (time functions are evaluated)."""
        v = self.params[name]
        return v(t) if isinstance(v, TimeFunction) or callable(v) else v

    @property
    def m_eps(self) -> float:
        """Flow scale of the smooth upwind weight at this component's ports [kg/s]:
        ``physics.M_EPS_REL`` times the parameter m_nominal (1 kg/s without one)."""
        m_nom = self.params.get("m_nominal") or 1.0
        return M_EPS_REL * float(m_nom)

    def structure_problems(self) -> list[str]:
        """Hook: plain-words problems of the parameter set that make the DAE
        index 2 inside the component (reported by ``Plant.check()``)."""
        return []

    def breakpoints(self) -> list[float]:
        """Times at which a time-function parameter or its slope jumps."""
        out = []
        for v in self.params.values():
            if isinstance(v, TimeFunction) or (callable(v) and hasattr(v, "breakpoints")):
                out.extend(float(b) for b in v.breakpoints)
        return out

    # ----------------------------------------------------------- declarations
    def fluid_ports(self) -> list[FluidPort]:
        return list(self.FLUID_PORTS)

    def signal_inputs(self) -> list[SignalPort]:
        return list(self.SIGNAL_INPUTS)

    def signal_outputs(self) -> list[SignalPort]:
        return list(self.SIGNAL_OUTPUTS)

    def signal_output_unit(self, output: str, input_units: dict) -> str:
        """The unit of the signal output ``output`` declared with unit "*" (it follows
        the inputs), from ``input_units`` (input name -> unit of the linked source, in
        link order; "*" where that is not known yet): by default the first input's
        (a ``Gain``, a ``Limiter``). A block whose output unit is a function of several
        inputs' (``Product``: u1 u2, ``Division``: u1/u2) overrides this; the compiler
        and the System ask it when they resolve a link's unit. "*" when unknown."""
        return next(iter(input_units.values()), "*")

    def variables(self) -> list[Variable]:
        return []

    def equations(self) -> list[Equation]:
        return []

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("_declared", None)  # closures; rebuilt from equations() on first use
        return state

    def residual(self, t: float, x: LocalVector, xp: LocalVector) -> np.ndarray:
        """F of the component's equations, in the order of ``equations()``.

        A component with ``row_reads`` (its equations written once, in ``row_values``):
        the values of the names of ``row_reads()`` looked up in x and xp, then
        ``row_values``; the System evaluates it without this look-up, in a
        ``ScalarRows``, from the same function. Otherwise each declared
        ``Equation.residual`` (a component whose equations carry no functions
        overrides this method)."""
        declared = self.__dict__.get("_declared")
        if declared is None:
            declared = self._declared = self._declare_residuals()
        reads, eqs, functions, total = declared
        if reads is not None:
            return np.array(
                self.row_values(t, [x[n] for n in reads[0]], [xp[n] for n in reads[1]], x.modes),
                dtype=float,
            )
        x.work = self.prepare(t, x, xp)
        if functions is not None:  # scalar equations only: one value each
            return np.array([f(t, x, xp) for f in functions], dtype=float)
        out = np.empty(total)
        k = 0
        for e in eqs:
            r = e.residual(t, x, xp)
            n = e.n_rows
            if np.size(r) != n:
                raise PlantError(
                    f"component '{self.name}' ({type(self).__name__}): equation '{e.name}' "
                    f"returned {np.size(r)} residuals but declares {n}"
                )
            out[k : k + n] = r if np.ndim(r) <= 1 else np.ravel(r)
            k += n
        return out

    def _declare_residuals(self):
        """(``row_reads()``, equations, their residual functions when every one is
        scalar, else None, the number of rows), made once per component
        (``residual``'s per-call work is the calls alone)."""
        reads = self.rows_checked()
        eqs = self.equations()
        total = sum(e.n_rows for e in eqs)
        if reads is not None:
            return reads, eqs, None, total
        missing = [e.name for e in eqs if e.residual is None]
        if missing:
            raise NotImplementedError(
                f"component '{self.name}' ({type(self).__name__}): equation(s) "
                f"{', '.join(missing)} declare no residual function"
            )
        scalar = all(e.size is None for e in eqs)
        return None, eqs, (tuple(e.residual for e in eqs) if scalar else None), total

    # ------------------------------------------------------------ scalar rows
    def row_reads(self) -> tuple[tuple[str, ...], tuple[str, ...]] | None:
        """The local names ``row_values`` reads from y and from y', or None (the
        default): the component's equations carry their residual functions
        (``Equation.residual``) and it is evaluated alone by ``residual``.

        A component that gives them writes its equations once, in ``row_values``
        (its ``Equation`` declarations keep the names, dependencies, units and docs,
        without residual functions). The System evaluates it with the others that
        do in one ``ScalarRows`` unit (``batch_key``): their values gathered from the
        plant-wide vectors through index arrays made once, no ``LocalVector`` and no
        name look-up per value; ``residual`` looks the same names up in x, xp and
        calls the same ``row_values``."""
        return None

    def row_values(self, t: float, v: list, vp: list, modes: dict) -> list:
        """The residuals of ``equations()`` in their order, from v and vp: the values
        [SI] of the names of ``row_reads()`` (y and y'), and the component's discrete
        ``modes``. Only with ``row_reads``."""
        raise NotImplementedError

    def rows_checked(self):
        """``row_reads()``, after checking that the equations are written once: a
        component with ``row_reads`` (e.g. a subclass of one) whose ``equations()``
        carry residual functions would have two definitions; PlantError. Checked once
        per component (the System asks for each set of blocks it evaluates)."""
        if "_checked_reads" in self.__dict__:
            return self._checked_reads
        reads = self.row_reads()
        if reads is not None:
            twice = [e.name for e in self.equations() if e.residual is not None]
            if twice:
                raise PlantError(
                    f"component '{self.name}' ({type(self).__name__}): equation(s) "
                    f"{', '.join(twice)} carry residual functions, but the class writes its "
                    "equations in row_values (it has row_reads); write them in one place: "
                    "override row_values, or return None from row_reads"
                )
        self._checked_reads = reads
        return reads

    def batch_key(self):
        """Components with equal keys are evaluated together by ``batch(blocks)``
        (``dnasim.compilation.system.evaluation_units``); ``ROWS_KEY`` for a component with
        ``row_reads`` (all of them in one ``ScalarRows``, whatever their class: a
        subclass that overrides ``row_values`` is evaluated by its own, on both
        paths), else None: alone, by ``residual``."""
        return None if self.rows_checked() is None else ROWS_KEY

    @staticmethod
    def batch(blocks):
        """The ``ScalarRows`` of the System blocks of components with ``row_reads``."""
        return ScalarRows(blocks)

    def prepare(self, t: float, x: LocalVector, xp: LocalVector):
        """Hook: what several equations share, computed once per residual evaluation
        (e.g. one property call for all volumes of a pipe). The base ``residual``
        stores the result in ``x.work`` before calling the equations. Default: None."""
        return None

    def switches(self) -> list[Switch]:
        return []

    def outputs(self) -> list[Output]:
        return []

    def output_values(self, t: float, x: LocalVector, xp: LocalVector) -> list[float]:
        return []

    # ---------------------------------------------------------- initialisation
    def guess_nodes(self, t0: float) -> dict[str, tuple[float | None, float | None]]:
        """Guesses {port: (p, h)} for the nodes at the component's ports (None = no idea)."""
        return {}

    def initial_guess(self, t0: float, x: LocalVector) -> None:
        """Fill guesses of the component's own variables; node values in x are set.

        For a start from given states the differential variables filled here are
        the initial state (the parameters that define it, e.g. a pipe's T0, are
        documented per component)."""

    def steady_guess(self, t0: float, x: LocalVector) -> None:
        """Hook for the steady start only: move the guesses of ``initial_guess`` towards
        the steady state (a heated pipe marches its enthalpies from the inlet, a mixing
        volume takes the mix of its inflows), so that the start's Newton iteration needs
        fewer steps. Called right after ``initial_guess``, in flow order (the node values
        in x are the upstream components' guesses). Not called for a given start, whose
        initial state ``initial_guess`` defines. Default: nothing."""

    def free_at_rest(self, t0: float, x: LocalVector) -> tuple[str, ...]:
        """Hook for the steady start: the differential variables (local names) that a
        state at rest leaves undetermined in the current discrete mode, because no
        equation reads them there: the held integral of a PI controller saturated at a
        limit (its output is the limit, whatever the integral). The steady start keeps
        their values and solves their derivatives instead, as for accumulators
        (``dnasim.start.steady_state``). Default: none."""
        return ()

    def steady_problems(self, t0: float, x: LocalVector) -> list[str]:
        """Hook for the steady start: why the state at rest x lies outside this
        component's stated range, one sentence each in plant terms (a sink-only boundary
        that would feed the plant, a check valve passing reverse flow, a vessel level
        outside the vessel); the steady start then stops with them
        (``dnasim.start.steady_state``). Default: none."""
        return []

    def design_values(self, t0: float, x: LocalVector) -> dict[str, float]:
        """Hook for the design-point table (``dnasim steady``): what an engineer checks
        first at a state x, by key (each only where the component has it):

          m           mass flow through the component [kg/s]
          duty        heat into the component's fluid [W] (< 0: heat out of it)
          heat_in     the part of duty that is heat from outside the plant's working
                      fluid (a furnace, a fixed wall, flue gas) [W]
          power       shaft power into the fluid [W] (a pump > 0, a turbine < 0)
          opening     a valve's opening z, a controller's output z [-]
          efficiency  a machine's efficiency [-]

        Default: ``m`` when the component has a variable of that name."""
        return {"m": x["m"]} if "m" in x.index and not isinstance(x.index["m"], slice) else {}

    def reset_discrete_state(self, modes: dict) -> None:
        """Hook: put the discrete modes back to their default before a simulation.

        ``modes`` is this component's dict in ``System.modes`` (the same object as
        ``LocalVector.modes`` in ``residual`` and the switch functions); a component
        keeps no mode on itself, so one component may serve several Systems."""

    def init_discrete_state(self, t0: float, x: LocalVector, xp: LocalVector) -> bool:
        """Hook: choose the discrete state that fits the initial values.

        Return True when it changed (the plant then re-solves the initial state)."""
        return False

    # ------------------------------------------------------------------ media
    #: medium groups (``medium_groups``) that hold a liquid and its vapour in
    #: equilibrium and so need a two-phase (condensable) medium; the compiler refuses
    #: a gas there with a message naming the component (a drum: ("fluid",))
    TWO_PHASE_GROUPS: tuple[str, ...] = ()

    def signal_range(self, name: str):
        """Bounds of the signal output ``name`` that the component's geometry sets:
        ``(lo, hi, unit, words)`` with ``lo < value < hi`` in SI, or None (the
        default: no bounds). A drum's level lies below its top V_t/A; ``dnasim
        check`` compares controllers' set points with it (``compiler._vessel_problems``)."""
        return None

    def medium_groups(self) -> list[tuple[str, str, list[str]]]:
        """Groups of fluid ports that carry one fluid: [(group, parameter, ports)].

        ``parameter`` names the string parameter that may fix the group's fluid
        (otherwise it comes from the nodes, see ``dnasim.compilation.compiler.resolve_media``).
        Default: one group "fluid" of all fluid ports, fixed by ``medium``. A
        component with two separate streams (a heat exchanger) returns two groups,
        and its ``port_media`` then holds different media on different ports."""
        if not self.USES_MEDIUM:
            return []
        ports = [p.name for p in self.fluid_ports()]
        return [("fluid", "medium", ports)] if ports else []

    def port_medium(self, port: str):
        """The medium object at fluid port ``port`` (set by ``dnasim.compilation.compiler``)."""
        return self.port_media[port]

    # ---------------------------------------------------------------- helpers
    def port(self, name: str) -> FluidPort:
        for p in self.fluid_ports():
            if p.name == name:
                return p
        raise KeyError(name)

    @classmethod
    def describe(cls) -> str:
        """A text summary: ports, parameters (units, defaults), equations."""
        lines = [f"{cls.__name__}"]
        doc = inspect.cleandoc(cls.__doc__ or "")
        if doc:
            lines += ["", textwrap.indent(doc, "  ")]
        if cls.FLUID_PORTS:
            lines += ["", "  fluid ports:"]
            for p in cls.FLUID_PORTS:
                lines.append(f"    {p.name:<12} {p.role:<7} {p.doc}")
        if cls.SIGNAL_INPUTS or cls.SIGNAL_OUTPUTS:
            lines += ["", "  signal ports:"]
            for p in cls.SIGNAL_INPUTS:
                lines.append(f"    {p.name:<12} in      [{p.unit}] {p.doc}")
            for p in cls.SIGNAL_OUTPUTS:
                lines.append(f"    {p.name:<12} out     [{p.unit}] {p.doc}")
        if cls.PARAMS:
            lines += ["", "  parameters:"]
            for p in cls.PARAMS:
                if p.default is REQUIRED:
                    d = "required"
                elif p.default is None:
                    d = "optional"
                else:
                    d = f"default {p.default!r}"
                tf = ", may vary in time" if p.time_function else ""
                lines.append(f"    {p.name:<12} [{p.unit}] {d}{tf}. {p.doc}")
        return "\n".join(lines)

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r})"
