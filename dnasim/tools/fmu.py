"""FMU export: a plant as an FMI 2.0 co-simulation FMU (``dnasim fmu PLANT.toml``).

    from dnasim.tools.fmu import build_fmu
    build_fmu("plants/attemperator.toml", "attemperator.fmu",
              inputs=["pi.setpoint", "steam.T"], outputs=["sensor.T_s", "pi.z"])

The FMU is a pythonfmu FMU (https://github.com/NTNU-IHB/PythonFMU): its binary is a
small C wrapper that calls Python, and its resources hold the plant file, the chosen
interface (``dnasim_fmu.json``) and a two-line slave class. At run time the importing
tool needs a Python (the one whose ``libpython`` the process has loaded) in which
``dnasim`` is installed: the FMU carries the plant, not the simulator (docs/fmu.md).

Interface (chosen as ``dnasim linearize``'s inputs and outputs, by name):

- inputs: numeric parameters of components, ``component.parameter`` (``steam.T``,
  ``pi.setpoint``, ``turbine_valve.opening``, ``water.p``), in SI units. Default: every
  parameter set in the plant that may be a time function (boundary values, set
  points, openings, heat inputs) and that the residual reads during the run. An
  input replaces the plant file's value or time function for that parameter by the
  number the master sets (its start value: the file's value at the start time).
- outputs: any column of ``results.csv`` (names or shell patterns, as ``dnasim run
  --vars``). Default: every signal output (sensors, controllers, signal blocks).

Time stepping (:class:`CoSimulation`): the plant is integrated by dnasim's own
solver (``NordsieckBDF`` of the plant's ``[simulation]`` settings, the master's
tolerance as rtol when it sets one) on the output grid t0 + k h of the
communication step h, in a worker thread that stops at each communication point
until the master asks for the next one. While the inputs and h stay the same the
integration goes on as one run (no restart at communication points; the values at
them come from the solver's interpolating polynomial, as ``--output-interval``
rows). When an input has changed (or h, or the master goes back or past the end),
the integration is restarted at the communication point as at a discontinuity:
values made consistent with the new inputs (the differential states kept),
order 1.
"""

from __future__ import annotations

import difflib
import json
import keyword
import queue
import re
import shutil
import tempfile
import threading
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from dnasim.core.errors import DAEError, DnasimError

__all__ = [
    "CoSimulation",
    "FmuError",
    "FmuInterface",
    "build_fmu",
    "fmu_interface",
    "read_interface",
]

#: the interface file in the FMU's resources
INTERFACE_FILE = "dnasim_fmu.json"
#: relative tolerance for matching a communication point with the solver's grid
_GRID_MATCH = 1e-9
#: relative change of an input below which it counts as unchanged (round-off)
_INPUT_ROUNDOFF = 1e-12


class FmuError(DnasimError, ValueError):
    """An FMU that cannot be built as asked (unknown input or output, no pythonfmu)."""


# --------------------------------------------------------------------------- interface


@dataclass
class FmuInterface:
    """The FMU's variables: names (dnasim's), units (SI) and input start values."""

    inputs: list[str]
    input_units: list[str]
    input_starts: list[float]
    outputs: list[str]
    output_units: list[str]
    model_name: str = "plant"
    description: str = ""
    t_start: float = 0.0
    t_end: float = 1.0
    rtol: float = 1e-6
    notes: list[str] = field(default_factory=list)


def _plant_and_settings(loaded):
    plant = loaded.plant
    sim = loaded.simulation
    return plant, sim


def _suggest(name: str, names) -> str:
    close = difflib.get_close_matches(name, list(names), n=4, cutoff=0.6)
    return f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""


def _input_candidates(plant) -> list[tuple[str, object, object]]:
    """(name, component, Param) of every parameter set in the plant that may be a
    time function (boundary values, set points, openings, heat inputs)."""
    out = []
    for comp in plant.components.values():
        for p in comp.PARAMS:
            if p.time_function and comp.params.get(p.name) is not None:
                out.append((f"{comp.name}.{p.name}", comp, p))
    return out


def _resolve_input(plant, ref: str):
    """(component, Param) for ``component.parameter``; FmuError naming what is wrong."""
    if ref.count(".") != 1:
        raise FmuError(f"input {ref!r}: expected 'component.parameter' (e.g. 'steam.T')")
    cname, pname = ref.split(".")
    comp = plant.components.get(cname)
    if comp is None:
        raise FmuError(
            f"input {ref!r}: no component named '{cname}'{_suggest(cname, plant.components)}"
        )
    link = plant.links.get((cname, pname))
    if link is not None:
        raise FmuError(
            f"input {ref!r}: '{pname}' is a signal input of '{cname}' linked to "
            f"'{link[0]}.{link[1]}'; an FMU input replaces a parameter: remove the link "
            f"and give the component's parameter for it in the plant file (a valve's "
            "'opening' instead of inputs.z), then export that parameter"
        )
    params = {p.name: p for p in comp.PARAMS}
    p = params.get(pname)
    if p is None or p.kind != "number":
        numeric = [q.name for q in comp.PARAMS if q.kind == "number"]
        raise FmuError(
            f"input {ref!r}: '{pname}' is not a numeric parameter of component '{cname}' "
            f"({type(comp).__name__}){_suggest(pname, numeric)}"
        )
    if comp.params.get(pname) is None:
        raise FmuError(f"input {ref!r}: the parameter is not set in this plant")
    return comp, p


def _live(system, comp, p, t0, y, yp) -> bool:
    """Does a change of the parameter change the residual at (t0, y, yp)? (A parameter
    precomputed in the component's setup does not: it cannot be an input.) The System's
    own copy of the component is changed (compile does not write into the plant)."""
    comp = system.components[comp.name]
    orig = comp.params[p.name]
    v = float(comp.param_at(p.name, t0))
    try:
        f0 = np.asarray(system.residual(t0, y, yp), dtype=float).copy()
        _set_param(comp, p, v * (1 + 1e-4) + 1e-4)
        f1 = np.asarray(system.residual(t0, y, yp), dtype=float)
    except Exception:  # a guess outside the media's range: no verdict, keep the input
        return True
    finally:
        comp.params[p.name] = orig
    return bool(np.any(f1 != f0))


def _set_param(comp, p, value: float) -> None:
    from dnasim.core.timefunctions import as_time_function

    value = float(value)
    comp.params[p.name] = as_time_function(value) if p.time_function else value


def model_identifier(name: str) -> str:
    """The plant's name as a C and Python identifier (the FMU's modelIdentifier)."""
    ident = re.sub(r"\W", "_", name, flags=re.ASCII) or "plant"
    if ident[0].isdigit() or keyword.iskeyword(ident):
        ident = "plant_" + ident
    return ident


def _input_unit(comp, p) -> str:
    """The SI unit of parameter ``p`` of ``comp`` as an FMU input ("" when it is in
    the measured signal's unit; the output unit for a PID's z_manual)."""
    if p.per_signal:
        return ""
    if getattr(p, "per_output", 0):
        from dnasim.core.values import output_unit_of

        return output_unit_of(type(comp), comp.params) or p.unit
    return p.unit


def fmu_interface(loaded, inputs=None, outputs=None, system=None) -> FmuInterface:
    """Resolve the FMU's inputs and outputs of a ``LoadedPlant`` (see the module
    docstring for the defaults). ``outputs`` are names or shell patterns. Raises
    ``FmuError`` for an unknown input or an output pattern that matches nothing."""
    from dnasim.run.output import select_variables
    from dnasim.start.guess import initial_guess

    plant, sim = _plant_and_settings(loaded)
    system = system if system is not None else plant.compile()
    names = [n for n in system.output_names() if n != "restart"]
    units = dict(system.output_units())
    t0 = sim.t_start
    try:
        y = initial_guess(system, t0)
        yp = np.zeros(system.n)
    except Exception:
        y = None
    notes = []
    dead = (
        "a small change of it changes no equation at the start (a parameter the "
        "component reads only when the plant is built, or a switch such as a "
        "controller's 'active' away from its threshold)"
    )
    if inputs is None:
        chosen = []
        for ref, comp, p in _input_candidates(plant):
            if y is None or _live(system, comp, p, t0, y, yp):
                chosen.append(ref)
            else:
                notes.append(f"{ref} is not an input by default: {dead}")
    else:
        chosen = list(dict.fromkeys(inputs))
        for ref in chosen:
            comp, p = _resolve_input(plant, ref)
            if y is not None and not _live(system, comp, p, t0, y, yp):
                notes.append(f"input {ref}: {dead}; it may have no effect")
    from dnasim.core.timefunctions import Constant

    in_units, in_starts = [], []
    for ref in chosen:
        comp, p = _resolve_input(plant, ref)
        in_units.append(units.get(ref, _input_unit(comp, p)))
        in_starts.append(float(comp.param_at(p.name, t0)))
        v = comp.params[p.name]
        if callable(v) and not isinstance(v, Constant):
            notes.append(
                f"input {ref}: the plant file's time function ({type(v).__name__.lower()}) "
                f"is replaced by the FMU input (start value {in_starts[-1]:.6g} "
                f"{in_units[-1] if in_units[-1] not in ('', '1') else '-'}); the master drives it"
            )
    if outputs is None:
        outs = []
        for comp in plant.components.values():
            for port in comp.signal_outputs():
                n = f"{comp.name}.{port.variable or port.name}"
                if n in units and n not in outs:
                    outs.append(n)
    else:
        bad = [q for q in outputs if not select_variables(names, [q])]
        if bad:
            raise FmuError(
                "; ".join(
                    f"output {q!r} matches no output of the plant{_suggest(q, names)}" for q in bad
                )
                + " (a name as in results.csv, 'att.T', a component, 'att', or a shell "
                "pattern, 'att.*')"
            )
        outs = select_variables(names, list(outputs))
    if not outs:
        raise FmuError("the FMU would have no outputs: give them with --vars")
    return FmuInterface(
        inputs=chosen,
        input_units=in_units,
        input_starts=in_starts,
        outputs=outs,
        output_units=[units.get(n, "") for n in outs],
        model_name=model_identifier(plant.name),
        description=getattr(plant, "description", "") or "",
        t_start=float(t0),
        t_end=float(sim.t_end),
        rtol=float(sim.rtol),
        notes=notes,
    )


# --------------------------------------------------------------------------- run time


class _Abort(DAEError):
    """Raised in the worker's output callback: the master abandons the segment."""


_ABORT = object()


class _Segment:
    """One integration from (t0, y0, yp0) on the grid t0 + k h, in a worker thread
    that waits at each communication point until the master asks for the next."""

    def __init__(self, cosim, t0, y0, yp0, h, t_end):
        self.t0, self.h, self.t_end = float(t0), float(h), float(t_end)
        self.cmd: queue.Queue = queue.Queue()
        self.out: queue.Queue = queue.Queue()
        self.target = None
        self.stats: dict = {}  # the solver's counters, when the integration has ended
        self._args = (cosim, y0, yp0)
        self.thread = threading.Thread(target=self._run, name="dnasim-fmu", daemon=True)
        self.thread.start()

    def _tol(self) -> float:
        return _GRID_MATCH * self.h + 1e-12 * abs(self.t_end)

    def _run(self):
        from functools import partial

        from dnasim.run.backends import NordsieckBDF
        from dnasim.run.simulation import problem_for
        from dnasim.start.initial import reinitialise

        cosim, y0, yp0 = self._args
        try:
            cmd = self.cmd.get()
            if cmd is _ABORT:
                return
            self.target = cmd
            system = cosim.system
            solver = NordsieckBDF(
                rtol=cosim.rtol,
                atol_scaled=cosim.atol_scaled,
                max_order=cosim.max_order,
                dense_output=False,
                keep_output=False,
                **cosim.solver_options,
            )
            pb = problem_for(
                system,
                self.t0,
                self.t_end,
                y0,
                yp0,
                solver.atol_scaled,
                output_interval=self.h,
                callback=self._point,
                reinitialise=partial(reinitialise, system),
            )
            res = solver.solve(pb)
            self.stats = dict(getattr(res, "stats", {}) or {})
            self.out.put(("end", res))
        except BaseException as exc:  # handed to the master, never lost in the thread
            self.out.put(("error", exc))

    def _point(self, t, y, yp):
        if t < self.target - self._tol():
            return  # the right limit of a restart at the last communication point
        self.out.put(("point", float(t), np.array(y), np.array(yp)))
        cmd = self.cmd.get()
        if cmd is _ABORT:
            raise _Abort("abandoned by the master")
        self.target = cmd

    def advance(self, target):
        """Integrate to ``target``: ("point", t, y, yp), ("end", result) or ("error", exc)."""
        self.cmd.put(target)
        return self.out.get()

    def close(self):
        if self.thread.is_alive():
            self.cmd.put(_ABORT)
            self.thread.join()


class CoSimulation:
    """A compiled plant stepped from outside: inputs set between communication points.

        cs = CoSimulation(loaded, inputs=["pi.setpoint"], outputs=["sensor.T_s"])
        cs.start(0.0)
        cs.set_input("pi.setpoint", 713.15)   # [K], acts from the next step on
        cs.step(0.0, 1.0); cs.value("sensor.T_s")

    ``rtol`` defaults to the plant file's; ``stop_time`` (the master's) bounds the
    first integration segment (the default first step is 1e-3 of a segment)."""

    def __init__(
        self,
        loaded,
        inputs=None,
        outputs=None,
        *,
        rtol: float | None = None,
        stop_time: float | None = None,
        interface: FmuInterface | None = None,
    ):
        plant, sim = _plant_and_settings(loaded)
        self.system = plant.compile()
        if interface is None:  # (an FMU brings its interface, resolved when it was built)
            interface = fmu_interface(loaded, inputs, outputs, system=self.system)
        self.interface = interface
        self.start_mode = sim.start
        self.rtol = float(rtol if rtol is not None else sim.rtol)
        self.atol_scaled = float(sim.atol_scaled)
        self.max_order = int(sim.max_order)
        self.solver_options = {}
        if sim.max_step is not None:
            self.solver_options["max_step"] = sim.max_step
        if sim.max_steps is not None:
            self.solver_options["max_steps"] = sim.max_steps
        self.stop_time = stop_time
        comps = self.system.components
        self._inputs = {}
        for ref, u0 in zip(self.interface.inputs, self.interface.input_starts, strict=True):
            cname, pname = ref.split(".")
            comp = comps[cname]
            p = next(q for q in comp.PARAMS if q.name == pname)
            self._inputs[ref] = [comp, p, float(u0)]
        self._changed = True
        names = self.system.output_names()
        self._col = {n: names.index(n) for n in self.interface.outputs}
        self.t = None
        self.y = self.yp = None
        self._row = None
        self._segment = None
        self._fresh = self._restart = False
        self.restarts = 0  # integrations started (the first one included)
        #: the solver's counters summed over the finished integrations (steps, ...)
        self.stats: dict = {}
        self.message = ""

    # -- inputs and outputs
    def set_input(self, name: str, value: float) -> None:
        """Set an input [SI]; it acts from the current communication point on. A
        change within 1e-12 of the value (a master's interpolation round-off: FMPy
        gives 723.15 +- 1 ulp between equal table points) is ignored, so that it does
        not restart the integration."""
        slot = self._inputs[name]
        value = float(value)
        if abs(value - slot[2]) > _INPUT_ROUNDOFF * max(abs(value), abs(slot[2])):
            slot[2] = value
            self._changed = True

    def input(self, name: str) -> float:
        return self._inputs[name][2]

    def value(self, name: str) -> float:
        """Output ``name`` at the last communication point [SI], with the inputs as set
        (after a change: the right limit, the algebraic variables solved for the new
        inputs, so that an output with direct feedthrough shows it at once)."""
        if self._changed and self.y is not None:
            self._consistent_with_inputs()
        k = self._col[name]
        if k < self.system.n:  # an unknown of the DAE: the row's first n entries are y
            return float(self.y[k])
        if self._row is None:
            self._row = np.asarray(self.system.output_row(self.t, self.y, self.yp), dtype=float)
        return float(self._row[k])

    def _apply_inputs(self) -> None:
        for comp, p, v in self._inputs.values():
            _set_param(comp, p, v)
        self._changed = False

    def _consistent_with_inputs(self) -> None:
        """Apply changed inputs at the current point: consistent values for them (the
        differential states kept); the next step restarts there at order 1."""
        from dnasim.start.initial import reinitialise

        self.close()
        self._apply_inputs()
        self.y, self.yp = reinitialise(self.system, self.t, self.y, self.yp)
        self._row = None
        self._restart = True

    # -- time
    def start(self, t0: float | None = None) -> None:
        """The state at t0 (default: the plant's start time), with the inputs as set:
        at rest (``start = "steady"``) or from the given initial values."""
        from dnasim.start.initial import initial_values

        t0 = self.interface.t_start if t0 is None else float(t0)
        self._apply_inputs()
        self.y, self.yp = initial_values(self.system, t0, self.start_mode)
        self.t = t0
        self._row = None
        self._fresh = True
        self._restart = False

    def step(self, t: float, h: float) -> bool:
        """Advance from the communication point t by h [s]; False (with ``message``)
        when the simulation fails or stops before t + h."""
        if self.y is None:
            self.start(t)
        if abs(t - self.t) > _GRID_MATCH * h + 1e-12 * abs(t):
            self.message = (
                f"doStep at t = {t:.10g} s, but the FMU is at t = {self.t:.10g} s "
                "(the master must step on from the last communication point)"
            )
            return False
        if self._changed:
            self._consistent_with_inputs()
        target = t + h
        seg = self._segment
        if (
            seg is None
            or self._restart
            or abs(h - seg.h) > _GRID_MATCH * h
            or target > seg.t_end + seg._tol()
        ):
            self.close()
            if not self._fresh and not self._restart:
                # from a point interpolated on the last segment (h changed, or past
                # its end): consistent values there first
                from dnasim.start.initial import reinitialise

                self.y, self.yp = reinitialise(self.system, t, self.y, self.yp)
            self._fresh = self._restart = False
            end = self.stop_time
            if end is None or end < target + _GRID_MATCH * h:
                end = t + 1000.0 * h
            seg = self._segment = _Segment(self, t, self.y, self.yp, h, end)
            self.restarts += 1
        msg = seg.advance(target)
        if msg[0] == "point":
            _, _t, self.y, self.yp = msg
            self.t = target
            self._row = None
            return True
        seg.thread.join()
        self._count(seg)
        self._segment = None
        if msg[0] == "error":
            exc = msg[1]
            self.message = f"{type(exc).__name__}: {exc}"
        else:
            res = msg[1]
            self.message = _stop_message(self.system, res)
        return False

    def close(self) -> None:
        if self._segment is not None:
            self._segment.close()
            self._count(self._segment)
            self._segment = None

    def _count(self, seg) -> None:
        for k, v in seg.stats.items():
            if isinstance(v, (int, float)) and k not in ("wall_time", "init_time"):
                self.stats[k] = self.stats.get(k, 0) + v


def _stop_message(system, res) -> str:
    """Why an integration ended before the communication point: the component's own
    message for a terminal switch (a drum that ran dry), as ``dnasim run`` prints it,
    else the solver's."""
    events = system.events
    for e in reversed(list(getattr(res, "event_log", ()) or ())):
        idx = e.get("event")
        if e.get("terminal") and idx is not None and 0 <= idx < len(events):
            text = events[idx].message(e["t"])
            if text:
                return text
            break
    return str(getattr(res, "message", "")) or "the integration ended early"


# --------------------------------------------------------------------------- the slave


def _interface_from_resources(resources) -> tuple[Path, dict]:
    base = Path(resources)
    spec = json.loads((base / INTERFACE_FILE).read_text(encoding="utf-8"))
    return base / spec["plant_file"], spec


class SlaveMixin:
    """The FMI 2.0 co-simulation slave of a plant (mixed into pythonfmu's
    ``Fmi2Slave`` by the FMU's generated script). Reads the plant file and the
    interface from the FMU's resources."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        from pythonfmu import Fmi2Causality, Fmi2Variability, Real
        from pythonfmu.default_experiment import DefaultExperiment

        from dnasim.plant.plantfile import load

        plant_file, spec = _interface_from_resources(self.resources)
        self._loaded = load(plant_file)
        iface = spec["interface"]
        self.description = spec.get("description") or None
        self.author = "dnasim"
        self.default_experiment = DefaultExperiment(
            start_time=iface["t_start"], stop_time=iface["t_end"], tolerance=iface["rtol"]
        )
        self._spec = iface
        self._values = dict(zip(iface["inputs"], iface["input_starts"], strict=True))
        self._cosim = None
        self._start_time = iface["t_start"]
        self._stop_time = None
        self._rtol = None
        for name, unit in zip(iface["inputs"], iface["input_units"], strict=True):
            self.register_variable(
                Real(
                    fmi_name(name),
                    causality=Fmi2Causality.input,
                    variability=Fmi2Variability.continuous,
                    description=f"{name} [{unit or '-'}]",
                    getter=lambda n=name: self._input_value(n),
                    setter=lambda v, n=name: self._set_input(n, v),
                ),
                nested=False,
            )
        for name, unit in zip(iface["outputs"], iface["output_units"], strict=True):
            self.register_variable(
                Real(
                    fmi_name(name),
                    causality=Fmi2Causality.output,
                    variability=Fmi2Variability.continuous,
                    description=f"{name} [{unit or '-'}]",
                    getter=lambda n=name: self._output_value(n),
                ),
                nested=False,
            )

    def _input_value(self, name):
        return self._values[name]

    def _set_input(self, name, value):
        self._values[name] = float(value)
        if self._cosim is not None:
            self._cosim.set_input(name, value)

    def _output_value(self, name):
        if self._cosim is None or self._cosim.y is None:
            return 0.0  # before initialisation: no state yet
        return self._cosim.value(name)

    def setup_experiment(self, start_time, stop_time, tolerance):
        self._start_time = float(start_time)
        self._stop_time = None if stop_time is None else float(stop_time)
        self._rtol = None if tolerance is None else float(tolerance)

    def exit_initialization_mode(self):
        fields = FmuInterface.__dataclass_fields__
        iface = FmuInterface(**{k: v for k, v in self._spec.items() if k in fields})
        self._cosim = CoSimulation(
            self._loaded, rtol=self._rtol, stop_time=self._stop_time, interface=iface
        )
        for n, v in self._values.items():
            self._cosim.set_input(n, v)
        try:
            self._cosim.start(self._start_time)
        except DnasimError as exc:
            self.log(f"dnasim: the plant cannot start: {exc}", status=_fmi2_error())
            raise

    def do_step(self, current_time, step_size):
        ok = self._cosim.step(float(current_time), float(step_size))
        if not ok:
            self.log(f"dnasim: {self._cosim.message}", status=_fmi2_error())
        return ok

    def terminate(self):
        if self._cosim is not None:
            self._cosim.close()


def _fmi2_error():
    from pythonfmu import Fmi2Status

    return Fmi2Status.error


_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+\])?$")


def fmi_name(name: str) -> str:
    """A results name as an FMI 2.0 structured name: each part an identifier with an
    optional [index], else quoted ('n_hdr~T')."""
    parts = []
    for part in name.split("."):
        if _IDENT.match(part):
            parts.append(part)
        else:
            q = part.replace("\\", "\\\\").replace("'", "\\'")
            parts.append(f"'{q}'")
    return ".".join(parts)


# --------------------------------------------------------------------------- build


_SCRIPT = '''"""The FMI 2.0 slave of dnasim plant {name!r} (generated by dnasim fmu)."""

if locals() is not globals():
    # pythonfmu's native wrapper (findClass, 0.6.4 to 0.7.0 at least) runs this file a
    # second time with this module's __dict__ as globals, then calls Py_DECREF on that
    # dict, a borrowed reference (PyModule_GetDict): the dict is freed while the module
    # still uses it, which corrupts the heap (FMPy's process crashing at exit) and
    # breaks a second instantiation (NTNU-IHB/PythonFMU#228). One reference taken here
    # balances it (were the wrapper fixed, the dict would live until the exit).
    try:
        import ctypes

        ctypes.pythonapi.Py_IncRef(ctypes.py_object(globals()))
        del ctypes
    except (AttributeError, OSError):  # no Python C API in the host's symbols
        pass

from pythonfmu import Fmi2Slave

from dnasim.tools.fmu import SlaveMixin


class {ident}(SlaveMixin, Fmi2Slave):
    """dnasim plant {name!r}: {description}"""
'''


def _finish_model_description(fmu: Path) -> None:
    """InitialUnknowns (the outputs, calculated at initialisation) in the
    ModelStructure: rewrite modelDescription.xml in the zip. The units are in each
    variable's description, not as FMI units: with UnitDefinitions FMPy 0.3.32's
    process crashed at exit more often, before the slave script balanced pythonfmu's
    freeing of the slave module's dict (``_SCRIPT``, docs/fmu.md)."""
    with zipfile.ZipFile(fmu) as z:
        entries = [(i, z.read(i.filename)) for i in z.infolist()]
    root = ET.fromstring(dict((i.filename, d) for i, d in entries)["modelDescription.xml"])
    structure = root.find("ModelStructure")
    outs = structure.find("Outputs") if structure is not None else None
    if outs is not None and structure.find("InitialUnknowns") is None:
        init = ET.SubElement(structure, "InitialUnknowns")
        for u in outs:
            ET.SubElement(init, "Unknown", index=u.get("index"))
    ET.indent(root)
    xml = ET.tostring(root, encoding="UTF-8", xml_declaration=True)
    tmp = fmu.with_name(fmu.name + ".tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for info, data in entries:
            z.writestr(info, xml if info.filename == "modelDescription.xml" else data)
    tmp.replace(fmu)


def build_fmu(plant_file, out, inputs=None, outputs=None, *, loaded=None) -> Path:
    """Write the FMI 2.0 co-simulation FMU of ``plant_file`` to ``out`` (a ``.fmu``
    path). ``inputs``: ``component.parameter`` names (default: see the module
    docstring); ``outputs``: names or patterns (default: the signal outputs).
    Returns the path. Raises ``FmuError`` (bad interface, no pythonfmu) and
    ``PlantError`` (a plant file that does not load)."""
    try:
        from pythonfmu import FmuBuilder
    except ImportError:
        raise FmuError(
            "FMU export needs pythonfmu, which is not installed: pip install 'dnasim[fmu]'"
        ) from None
    from dnasim.plant.plantfile import load

    plant_file = Path(plant_file)
    if loaded is None:
        loaded = load(plant_file)
    if getattr(loaded.spec, "imports", None):
        raise FmuError(
            f"{plant_file}: a plant with [plant] import cannot be exported (the FMU "
            "would have to run the imported module's code)"
        )
    iface = fmu_interface(loaded, inputs, outputs)
    out = Path(out)
    if out.suffix != ".fmu":
        raise FmuError(f"the FMU's file name must end in .fmu, got {str(out)!r}")
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="dnasim_fmu_") as tmp:
        tmp = Path(tmp)
        project = tmp / "project"
        project.mkdir()
        shutil.copy2(plant_file, project / "plant.toml")
        spec = {
            "dnasim_version": _version(),
            "plant_file": "plant.toml",
            "description": iface.description,
            "interface": {
                "inputs": iface.inputs,
                "input_units": iface.input_units,
                "input_starts": iface.input_starts,
                "outputs": iface.outputs,
                "output_units": iface.output_units,
                "t_start": iface.t_start,
                "t_end": iface.t_end,
                "rtol": iface.rtol,
                "model_name": iface.model_name,
                "description": iface.description,
                "notes": iface.notes,
            },
        }
        (project / INTERFACE_FILE).write_text(json.dumps(spec, indent=1), encoding="utf-8")
        ident = iface.model_name
        script = tmp / f"dnasim_fmu_{ident}.py"
        script.write_text(
            _SCRIPT.format(
                name=loaded.plant.name,
                ident=ident,
                description=(iface.description or "").replace('"', "'").replace("\\", "/"),
            ),
            encoding="utf-8",
        )
        files = [project / "plant.toml", project / INTERFACE_FILE]
        built = FmuBuilder.build_FMU(
            script,
            dest=out,
            project_files=files,
            needsExecutionTool="true",
            canHandleVariableCommunicationStepSize="true",
            # pythonfmu 0.7 cannot instantiate an FMU again in a process that has
            # freed one (NTNU-IHB/PythonFMU#228)
            canBeInstantiatedOnlyOncePerProcess="true",
        )
    built = Path(built)
    if built.resolve() != out.resolve():
        shutil.move(built, out)
    _finish_model_description(out)
    return out


def read_interface(fmu) -> dict:
    """The interface an FMU built here carries (inputs, outputs, units, start values)."""
    with zipfile.ZipFile(fmu) as z:
        spec = json.loads(z.read(f"resources/{INTERFACE_FILE}"))
    return spec["interface"]


def _version() -> str:
    """dnasim's version (from the installed distribution: the package root is the
    command-line stage and is not imported from here)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("dnasim")
    except PackageNotFoundError:
        return "unknown"
