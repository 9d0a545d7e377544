"""TOML plant files: read, validate (before any numerics), build a ``Plant``.

The schema is documented in ``docs/plant_files.md``. In short::

    [plant]
    name = "attemperator"

    [simulation]
    t_end = "20 min"
    output_interval = "1 s"      # optional; default: every accepted step
    rtol = 1e-6
    atol_scaled = 1e-8
    max_order = 4
    start = "steady"             # or "given"

    [components.steam]
    type = "PressureBoundary"
    p = "120 bar"
    T = { type = "step", t0 = "60 s", before = "540 degC", after = "560 degC" }
    ports = { outlet = "n1" }                 # fluid port -> node name

    [components.pi]
    type = "PIController"
    inputs = { measurement = "sensor.T" }     # signal input <- "component.output"

Every problem is reported as a :class:`~dnasim.core.errors.PlantError` whose message
names the file, the table, the key and (when it can be found) the line, one
paragraph per problem; all problems found are reported together.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dnasim.core.errors import PlantError, Problems
from dnasim.core.units import STANDARD_ATMOSPHERE, UnitError, parse_quantity, parse_unit
from dnasim.core.values import (
    LIMITS,
    TIME_FUNCTION_TYPES,
    example,
    limit_message,
    output_unit_of,
    param_kind,
    param_unit,
    param_value,
    per_signal,
    quantity,
    suggest,
    type_name,
)
from dnasim.plant.spec import (
    ComponentSpec,
    PlantSpec,
    SimulationSettings,
    build_plant,
    setting_problem,
)

__all__ = [
    "load_plant",
    "load",
    "loads",
    "LoadedPlant",
    "SimulationSettings",
    "ComponentSpec",
    "PlantSpec",
    "read_plant_file",
    "parse_plant",
    "build_plant",
    "component_info",
    "RESERVED_KEYS",
    "TIME_FUNCTION_TYPES",
]

#: keys of a component table that are not parameters
RESERVED_KEYS = ("type", "ports", "inputs", "description")


SIMULATION_KEYS = {
    "t_end": "end time of the simulation [s] (required)",
    "t_start": "start time [s] (default 0)",
    "output_interval": "time between rows of results.csv [s] (default: every accepted step)",
    "t_eval": 'the output times, a list such as ["0 s", "10 min", 1800] [s]: the rows are '
    "exactly these times (not with output_interval)",
    "rtol": "relative error tolerance (default 1e-6)",
    "atol_scaled": "absolute error tolerance per unit of each variable's scale: "
    "atol_i = atol_scaled * max(nominal_i, |y0_i|) (default 1e-6)",
    "max_order": "maximum BDF order, 1..5 (default 4)",
    "start": '"steady" (steady state at t_start) or "given" (initial states from parameters)',
    "max_step": "largest step size [s] (default: unlimited)",
    "max_steps": "most accepted steps before the run stops (default 500000)",
    "refine_output": "false: at output points between steps, interpolate the algebraic "
    "variables instead of solving them from the interpolated states where that is "
    "estimated to be more accurate (default true)",
}

_TOP_LEVEL = ("plant", "simulation", "components", "nodes")
#: the keys of a ``[nodes.<name>]`` table (guesses for the start) and their SI units
NODE_GUESS_KEYS = {"p": "Pa", "T": "K", "h": "J/kg"}


# --------------------------------------------------------------------------- data


@dataclass
class LoadedPlant:
    """What ``dnasim run`` works with: the plant, its settings and where it came from."""

    plant: Any
    simulation: SimulationSettings
    spec: PlantSpec
    path: str

    def simulate(self, **overrides):
        """Run ``plant.simulate`` with the file's settings (keywords override them)."""
        return simulate_plant(self.plant, self.simulation, **overrides)


# --------------------------------------------------------------------------- parts
# line index and reading (toml_reading), component metadata (component_info), the
# network check (network_check): split out of this module, re-exported here
from dnasim.plant.component_info import (  # noqa: E402
    _is_required,
    _names,
    _registry,
    component_info,
    fluid_ports,
    params_of,
    signal_inputs,
    signal_outputs,
)
from dnasim.plant.network_check import (  # noqa: E402
    _network,
    _port,
)
from dnasim.plant.toml_reading import (  # noqa: E402
    _decode,
    _LineIndex,
    read_plant_file,
)

# --------------------------------------------------------------------------- validation


def _as_text(v, errors: Problems, table, key) -> str | None:
    if not isinstance(v, str):
        errors.add(table, key, f"expected a string, got {type_name(v)} ({v!r})")
        return None
    return v


def _simulation(data, errors: Problems) -> SimulationSettings:
    s = SimulationSettings()
    table = ("simulation",)
    sim = data.get("simulation")
    if sim is None:
        errors.add((), "simulation", "missing the [simulation] table (at least t_end = ...)")
        return s
    if not isinstance(sim, dict):
        errors.add((), "simulation", f"expected a table, got {type_name(sim)}")
        return s
    for k in sim:
        if k not in SIMULATION_KEYS:
            errors.add(
                table,
                k,
                "unknown key; [simulation] has "
                + ", ".join(SIMULATION_KEYS)
                + suggest(k, SIMULATION_KEYS),
            )
    if "t_end" not in sim:
        errors.add(table, "t_end", 'missing: the end time of the simulation, e.g. t_end = "15 min"')
    refused = set()
    for k in ("t_end", "t_start", "output_interval", "max_step"):
        if k in sim:
            x = quantity(sim[k], "s", errors, table, k)
            if x is not None:
                problem = setting_problem(k, x)
                if problem:
                    errors.add(table, k, problem)
                else:
                    setattr(s, k, x)
            if x is None or problem:
                refused.add(k)
    times_ok = not refused & {"t_end", "t_start"}
    if "t_end" in sim and "t_start" in sim and s.t_end <= s.t_start:
        errors.add(table, "t_end", f"must be after t_start ({s.t_end:g} s <= {s.t_start:g} s)")
        times_ok = False
    elif s.output_interval is not None:
        try:
            s.check_output_points()
        except PlantError as exc:
            errors.add(table, "output_interval", str(exc).removeprefix("[simulation] "))
    if "t_eval" in sim:
        _t_eval(sim, s, errors, table, times_ok)
    for k in ("rtol", "atol_scaled"):
        if k in sim:
            x = quantity(sim[k], "1", errors, table, k)
            if x is not None:
                problem = setting_problem(k, x)
                if problem:
                    errors.add(table, k, problem)
                else:
                    setattr(s, k, x)
    for k in ("max_steps", "max_order", "start", "refine_output"):
        if k in sim:
            problem = setting_problem(k, sim[k])
            if problem:
                errors.add(table, k, problem)
            else:
                setattr(s, k, sim[k].lower() if k == "start" else sim[k])
    return s


def _t_eval(sim, s: SimulationSettings, errors: Problems, table, times_ok: bool) -> None:
    """``[simulation] t_eval``: a literal list of times (numbers in s or strings with a
    unit), strictly increasing, within [t_start, t_end], not with output_interval.
    ``times_ok``: t_start and t_end were read without a problem (else the range is not
    checked, their own message stands)."""
    from dnasim.core.units import convert_quantity
    from dnasim.plant.spec import t_eval_problem

    v = sim["t_eval"]
    if not isinstance(v, list | tuple):  # a TOML array (a tuple: settings of a sweep case)
        errors.add(
            table,
            "t_eval",
            f'expected a list of times such as ["0 s", "10 min", 1800], got {type_name(v)}',
        )
        return
    times, bad = [], False
    for k, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, int | float | str):
            errors.add(
                table,
                "t_eval",
                f"t_eval[{k}]: expected a number [s] or a string with a unit such as "
                f'"10 min", got {type_name(x)} ({x!r})',
            )
            bad = True
            continue
        try:
            times.append(float(convert_quantity(x, "s")))
        except UnitError as exc:
            errors.add(table, "t_eval", f"t_eval[{k}] = {x!r}: {exc}")
            bad = True
    if bad:
        return
    if "output_interval" in sim:
        errors.add(
            table,
            "t_eval",
            "t_eval and output_interval are both given: the rows are either the times of "
            "t_eval or a grid every output_interval; remove one of them",
        )
        return
    problem = t_eval_problem(times, s.t_start if times_ok else -math.inf,
                             s.t_end if times_ok else math.inf)  # fmt: skip
    if problem:
        errors.add(table, "t_eval", problem)
        return
    s.t_eval = tuple(times)


_NAME_OK = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]*$")

#: called with the medium name before a medium with CoolProp property tables
#: (BICUBIC&..., TTSE&...) is first built; the command line prints a notice
TABULAR_NOTICE = None
_NOTIFIED: set[str] = set()


def _is_tabular(name: str) -> bool:
    backend = name.split("::", 1)[0].upper() if "::" in name else ""
    return backend.startswith(("BICUBIC", "TTSE"))


def _check_medium(name: str, errors: Problems, table, key) -> None:
    """An unknown fluid name is reported here, with its place in the file."""
    try:
        from dnasim.media import get_medium
    except ImportError:  # pragma: no cover - media layer missing
        return
    if TABULAR_NOTICE is not None and _is_tabular(name) and name.upper() not in _NOTIFIED:
        _NOTIFIED.add(name.upper())
        TABULAR_NOTICE(name)
    try:
        get_medium(name)
    except PlantError as exc:
        errors.add(table, key, str(exc))
    except Exception as exc:  # the media layer's own failure: still the user's input
        errors.add(table, key, f"unknown fluid {name!r}: {exc}")


def _signal_units(comps: dict, registry) -> dict[str, list[str | None]]:
    """For each component, the units of the signal outputs linked into it (from the raw
    tables, before validation); ``None`` for a link that does not lead to a known
    signal output (reported later, by the network check)."""
    out: dict[str, list[str | None]] = {}
    for name, table in comps.items():
        if not isinstance(table, dict) or not isinstance(table.get("inputs"), dict):
            continue
        for src in _measured_first(table["inputs"]):
            unit = None
            if isinstance(src, str) and src.count(".") == 1:
                cname, oname = src.split(".")
                other = comps.get(cname)
                cls = None
                if isinstance(other, dict) and isinstance(other.get("type"), str):
                    cls = registry.get(other["type"])
                for port in getattr(cls, "SIGNAL_OUTPUTS", ()) or ():
                    if getattr(port, "name", None) == oname and getattr(port, "unit", None):
                        try:
                            parse_unit(port.unit)
                        except UnitError:
                            continue
                        unit = port.unit
            out.setdefault(name, []).append(unit)
    return out


def _measured_first(inputs: dict) -> list:
    """The sources of a component's inputs, the one of ``measured`` first: parameters
    in the unit of the signal (``Param.per_signal``) take the measured signal's."""
    keys = sorted(inputs, key=lambda k: k != "measured")
    return [inputs[k] for k in keys]


def _spec_builder(comps: dict, registry, errors: Problems, atmosphere: float | None = None):
    """``spec_of(name)``: the ComponentSpec of component ``name`` (None when invalid),
    built once. A component whose parameters are in the unit of its measured signal
    (a controller's Kp, set point) needs that unit first: a signal output's unit
    comes from the class; a variable's ("drum.level"), or a block output's that
    follows its input ("*"), from the source built first (``dnasim.plant.signals``); a
    node quantity's ("n_hdr.p") is fixed."""
    from dnasim.plant.signals import NODE_QUANTITIES, resolve, split_ref

    base_units = _signal_units(comps, registry)
    nodes = {
        n
        for t in comps.values()
        if isinstance(t, dict) and isinstance(t.get("ports"), dict)
        for n in t["ports"].values()
        if isinstance(n, str)
    }
    built: dict[str, ComponentSpec | None] = {}
    building: set[str] = set()

    def ref_unit(ref, seen=()):
        parts = split_ref(ref)
        if parts is None:
            return None
        c, v = parts
        if c not in comps:
            return NODE_QUANTITIES[v][0] if c in nodes and v in NODE_QUANTITIES else None
        if c in seen:
            return None
        other = spec_of(c)
        if other is None or other.instance is None:
            return None
        found = resolve(c, v, other.instance)
        if isinstance(found, str) or found is None:
            return None
        unit = found.unit
        if unit == "*":  # follows the block's inputs (Component.signal_output_unit)
            table = comps.get(c)
            inputs = table.get("inputs") if isinstance(table, dict) else None
            if not isinstance(inputs, dict) or not inputs:
                return None
            units = {k: ref_unit(r, (*seen, c)) or "*" for k, r in inputs.items()}
            unit = other.instance.signal_output_unit(found.variable, units)
            if unit == "*":
                return None
        try:
            parse_unit(unit)
        except UnitError:
            return None
        return unit

    def spec_of(cname):
        if cname in built:
            return built[cname]
        if cname in building:
            return None  # a loop of signals: its units stay unknown
        building.add(cname)
        table = comps[cname]
        units = list(base_units.get(cname, ()))
        tname = table.get("type") if isinstance(table, dict) else None
        cls = registry.get(tname) if isinstance(tname, str) else None
        needs = any(per_signal(cls, p) for p in params_of(cls)) if cls is not None else False
        if needs and None in units and isinstance(table.get("inputs"), dict):
            refs = _measured_first(table["inputs"])
            units = [
                u if u is not None else ref_unit(r, (cname,))
                for u, r in zip(units, refs, strict=False)
            ]
        built[cname] = _component(cname, table, registry, errors, tuple(units), atmosphere)
        building.discard(cname)
        return built[cname]

    return spec_of


def _component(
    name, table_data, registry, errors: Problems, signal_units=(), atmosphere=None
) -> ComponentSpec | None:
    table = ("components", name)
    if not _NAME_OK.match(name):
        errors.add(
            table,
            None,
            f"invalid component name {name!r}: use letters, digits, '_' and '-', "
            "starting with a letter (a '.' would clash with 'component.port')",
        )
        return None
    if not isinstance(table_data, dict):
        errors.add(
            ("components",),
            name,
            f"expected a table [components.{name}], got {type_name(table_data)}",
        )
        return None
    if "type" not in table_data:
        errors.add(
            table,
            "type",
            'missing: every component needs type = "..."; known types: '
            + ", ".join(sorted(registry)),
        )
        return None
    tname = table_data["type"]
    if not isinstance(tname, str):
        errors.add(table, "type", f"expected the name of a component type, got {type_name(tname)}")
        return None
    cls = registry.get(tname)
    if cls is None:
        errors.add(
            table,
            "type",
            f"unknown component type {tname!r}{suggest(tname, registry)} "
            f"(known: {', '.join(sorted(registry))}; see `dnasim components`)",
        )
        return None
    spec = ComponentSpec(name=name, type=tname, cls=cls)
    desc = table_data.get("description", "")
    if not isinstance(desc, str):
        errors.add(table, "description", f"expected a string, got {type_name(desc)}")
    else:
        spec.description = desc
    params = {p.name: p for p in params_of(cls)}
    fports = fluid_ports(cls)
    sin = signal_inputs(cls)
    sout = signal_outputs(cls)
    n0 = len(errors.items)
    unchecked = False
    unchecked_keys: list[str] = []
    for key, value in table_data.items():
        if key in RESERVED_KEYS:
            continue
        p = params.get(key)
        if p is None:
            hint = suggest(key, list(params) + list(RESERVED_KEYS))
            if key in fports:
                hint = f"; '{key}' is a fluid port: write ports = {{ {key} = \"node\" }}"
            elif key in sin:
                hint = (
                    f"; '{key}' is a signal input: "
                    f'write inputs = {{ {key} = "component.output" }}'
                )
            errors.add(
                table,
                key,
                f"unknown parameter of {tname}{hint} (parameters: {', '.join(params) or 'none'})",
            )
            continue
        if per_signal(cls, p) and (not signal_units or None in signal_units):
            # in the unit of a signal that is not (properly) linked: the broken link is
            # reported by the network check; unit errors here would only follow from it
            unchecked = True
            unchecked_keys.append(key)
            continue
        spec.params[key] = param_value(
            value,
            p,
            errors,
            table,
            key,
            signal_units,
            cls,
            atmosphere=atmosphere,
            output_unit=output_unit_of(cls, table_data),
        )
        if key == "medium" and isinstance(spec.params[key], str):
            _check_medium(spec.params[key], errors, table, key)
    for pname, p in params.items():
        if pname not in table_data and _is_required(p):
            unit = param_unit(p)
            doc = getattr(p, "doc", "")
            errors.add(
                table,
                pname,
                f"missing required parameter of {tname}"
                + (f" ({doc})" if doc else "")
                + (f', e.g. {pname} = "{example(unit)}"' if param_kind(p) == "number" else ""),
            )
    if len(errors.items) == n0 and not unchecked:
        # the parameters are valid: build the component now (cheap, no numerics) so
        # that its own checks run and ports that depend on parameters are known
        try:
            spec.instance = cls(name, **spec.params)
        except PlantError as exc:
            msg = _strip_component_prefix(str(exc), name)
            errors.add(table, _key_named(msg, table_data), msg)
        except (TypeError, ValueError, KeyError, ArithmeticError) as exc:
            msg = f"{tname} refused its parameters: {exc}"
            errors.add(table, _key_named(str(exc), table_data), msg)
        else:
            inst = spec.instance
            fports = _names(inst.fluid_ports()) if hasattr(inst, "fluid_ports") else fports
            sin = _names(inst.signal_inputs()) if hasattr(inst, "signal_inputs") else sin
            sout = _names(inst.signal_outputs()) if hasattr(inst, "signal_outputs") else sout
    ports_known = spec.instance is not None
    if len(errors.items) == n0 and unchecked:
        # parameters in the unit of an unlinked signal: a probe with placeholder values
        # (1 in any unit) tells which ports the component has; it is not kept
        try:
            probe = cls(name, **{**spec.params, **dict.fromkeys(unchecked_keys, 1.0)})
        except Exception:  # the placeholders do not fit: the class's ports are used
            probe = None
        if probe is not None:
            ports_known = True
            fports = _names(probe.fluid_ports()) if hasattr(probe, "fluid_ports") else fports
            sin = _names(probe.signal_inputs()) if hasattr(probe, "signal_inputs") else sin
    spec.fluid_ports, spec.signal_inputs, spec.signal_outputs = fports, sin, sout
    # fluid ports
    ports = table_data.get("ports", {})
    if not isinstance(ports, dict):
        errors.add(
            table,
            "ports",
            f"expected a table like ports = {{ {_port_example(fports)} }}, got {type_name(ports)}",
        )
        ports = {}
    for port, node in ports.items():
        sub = table + ("ports",)
        if port not in fports:
            if port in sin or port in sout:
                errors.add(
                    sub,
                    port,
                    f"'{port}' is a signal port of {tname}, not a fluid port: a signal cannot be "
                    f'wired to a node; write inputs = {{ {port} = "component.output" }}'
                    if port in sin
                    else f"'{port}' is a signal output of {tname}, not a fluid port; link it from "
                    "the receiving component's inputs",
                )
            else:
                errors.add(
                    sub,
                    port,
                    f"{tname} has no fluid port '{port}'{suggest(port, fports)} "
                    f"(fluid ports: {', '.join(fports) or 'none'})",
                )
            continue
        if not isinstance(node, str) or not node:
            errors.add(sub, port, f"expected a node name (a string), got {type_name(node)}")
            continue
        if not _NAME_OK.match(node):
            errors.add(sub, port, f"invalid node name {node!r}: use letters, digits, '_' and '-'")
            continue
        spec.ports[port] = node
    # Without a built instance (its parameters are in error) the ports that depend on
    # parameters are unknown: an "unconnected port" would follow from that error only
    # (a controller's set_point and track inputs, a mixer's inlets).
    built = ports_known
    for port in fports if built else ():
        if port not in ports:
            errors.add(
                table,
                "ports",
                f"unconnected port: the fluid port '{port}' of {tname} is not connected; "
                f'add {port} = "<node>" to ports',
            )
    # signal inputs
    inputs = table_data.get("inputs", {})
    if not isinstance(inputs, dict):
        errors.add(
            table,
            "inputs",
            f'expected a table like inputs = {{ {sin[0] if sin else "u"} = "sensor.T" }}, '
            f"got {type_name(inputs)}",
        )
        inputs = {}
    for inp, src in inputs.items():
        sub = table + ("inputs",)
        if inp not in sin:
            if inp in fports:
                errors.add(
                    sub,
                    inp,
                    f"'{inp}' is a fluid port of {tname}: a signal cannot be wired to a fluid "
                    "port; "
                    f'fluid ports are connected to nodes in ports = {{ {inp} = "node" }}',
                )
            elif _port(getattr(cls, "SIGNAL_INPUTS", ()), inp) is not None:
                # the class has this input, this instance not: a parameter replaces it
                doc = getattr(_port(cls.SIGNAL_INPUTS, inp), "doc", "") or ""
                given = [q for q in re.findall(r"'([A-Za-z_]\w*)'", doc) if q in table_data]
                if given:
                    errors.add(
                        sub,
                        inp,
                        f"both the parameter '{given[0]}' and the signal input '{inp}' are "
                        f"given; {tname} takes one of them: a fixed {given[0]} = ..., or "
                        f'inputs = {{ {inp} = "component.output" }} to drive it',
                    )
                else:
                    errors.add(
                        sub,
                        inp,
                        f"{tname} has the signal input '{inp}' only with other parameters"
                        + (f" ({doc})" if doc else ""),
                    )
            else:
                errors.add(
                    sub,
                    inp,
                    f"{tname} has no signal input '{inp}'{suggest(inp, sin)} "
                    f"(signal inputs: {', '.join(sin) or 'none'})",
                )
            continue
        if not isinstance(src, str) or src.count(".") != 1:
            errors.add(
                sub,
                inp,
                f'expected "component.output" (e.g. "sensor.T"), got {src!r}',
            )
            continue
        spec.inputs[inp] = src
    for inp in sin if built else ():
        if inp not in inputs and None not in signal_units:  # else the broken link says it
            errors.add(
                table,
                "inputs",
                f"unconnected port: the signal input '{inp}' of {tname} is not linked; "
                f'add {inp} = "<component>.<output>" to inputs',
            )
    return spec


def _plugin_imports(v, path, errors, allow_import: bool = False) -> list[str]:
    """``[plant] import = ["my_components"]``: import the component modules now
    (before the component types are looked up), next to the plant file first.

    Only with ``allow_import`` (``--allow-import``, ``load(path, allow_import=True)``):
    importing a module runs its code, and a plant file is data. Without it the
    modules are named in one problem (how to allow them), and nothing is imported."""
    from dnasim.plant.plugins import import_component_modules, module_origin

    names = [v] if isinstance(v, str) else v
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        errors.add(("plant",), "import", f"expected a list of module names, got {v!r}")
        return []
    p = Path(str(path))
    base = p.parent if p.suffix and p.parent.is_dir() else None
    if not allow_import:
        if names:
            found = ", ".join(f"'{n}' ({module_origin(n, base)})" for n in names)
            errors.add(
                ("plant",),
                "import",
                f"the plant file asks to import the Python module{'s' if len(names) > 1 else ''} "
                f"{found}; not imported: importing a module runs its code, and a plant file "
                "is data that runs no code by itself. If you trust the module, allow it with "
                "--allow-import (dnasim check/run/sweep --allow-import PLANT.toml; in Python "
                "dnasim.plant.plantfile.load(path, allow_import=True)), or install it as a plugin "
                "(entry point group 'dnasim.components'); otherwise remove the key",
            )
        return []
    try:
        return import_component_modules(names, base)
    except PlantError as exc:
        errors.add(("plant",), "import", str(exc).removeprefix("import: "))
        return []


#: the range of a site's atmospheric pressure [Pa] that ``[plant] atmosphere`` accepts:
#: 0.2 bar (above the highest mountains) to 1.2 bar (below the deepest mines)
ATMOSPHERE_RANGE = (2e4, 1.2e5)


def _atmosphere(v, errors: Problems) -> float:
    """``[plant] atmosphere = "0.95 bar"``: the site's ambient pressure [Pa], the zero
    of the gauge units ("5 barg", "70 psig"); the standard atmosphere when invalid."""
    x = quantity(v, "Pa", errors, ("plant",), "atmosphere")
    if x is None:
        return STANDARD_ATMOSPHERE
    if isinstance(v, str) and parse_quantity(v)[1].gauge:
        errors.add(
            ("plant",),
            "atmosphere",
            f"the atmosphere is an absolute pressure, the zero of the gauge units; write it in "
            f'an absolute unit, e.g. atmosphere = "1.013 bar", not {v!r}',
        )
        return STANDARD_ATMOSPHERE
    lo, hi = ATMOSPHERE_RANGE
    if not lo <= x <= hi:
        errors.add(
            ("plant",),
            "atmosphere",
            f"the atmosphere is the site's absolute ambient pressure, between {lo / 1e5:g} and "
            f"{hi / 1e5:g} bar (got {x:g} Pa); write it with a unit, e.g. "
            f'atmosphere = "1.013 bar" or "14.7 psi"',
        )
        return STANDARD_ATMOSPHERE
    return x


def parse_plant(
    data: dict, path: str = "<plant>", text: str | None = None, *, allow_import: bool = False
) -> PlantSpec:
    """Validate decoded TOML; every problem becomes part of one ``PlantError``.

    ``allow_import``: import the modules of ``[plant] import`` (they run code);
    without it such a key is refused, alone, before anything else is read."""
    errors = Problems(str(path), _LineIndex(text) if text is not None else None)
    if not isinstance(data, dict):
        errors.add((), None, "a plant file is a TOML document of tables")
        errors.raise_if_any()
    for k in data:
        if k not in _TOP_LEVEL:
            errors.add(
                (),
                k,
                f"unknown top-level key or table; expected [plant], [simulation], "
                f"[components.<name>] and [nodes.<name>]{suggest(k, _TOP_LEVEL)}",
            )
    name = Path(str(path)).stem
    description = ""
    medium = None
    imports: list[str] = []
    atmosphere = STANDARD_ATMOSPHERE
    meta = data.get("plant", {})
    if not isinstance(meta, dict):
        errors.add((), "plant", f"expected a table [plant], got {type_name(meta)}")
        meta = {}
    for k, v in meta.items():
        if k == "name":
            name = _as_text(v, errors, ("plant",), k) or name
        elif k == "description":
            description = _as_text(v, errors, ("plant",), k) or ""
        elif k == "medium":
            medium = _as_text(v, errors, ("plant",), k)
            if medium is not None:
                _check_medium(medium, errors, ("plant",), k)
        elif k == "import":
            imports = _plugin_imports(v, path, errors, allow_import)
            if not allow_import:
                errors.raise_if_any()  # one paragraph: nothing of the file is used
        elif k == "atmosphere":
            atmosphere = _atmosphere(v, errors)
        elif k == "format":  # decoded data not read by _decode: the version checked only
            from dnasim.plant.migrations import file_format

            file_format(data, path, errors.lines)
        else:
            errors.add(
                ("plant",),
                k,
                "unknown key; [plant] has format, name, description, medium, atmosphere and "
                "import"
                + suggest(k, ("format", "name", "description", "medium", "atmosphere", "import")),
            )
    sim = _simulation(data, errors)
    comps = data.get("components")
    specs: list[ComponentSpec] = []
    if comps is None:
        errors.add(
            (), "components", 'no components: add tables [components.<name>] with type = "..."'
        )
    elif not isinstance(comps, dict):
        errors.add((), "components", f"expected tables [components.<name>], got {type_name(comps)}")
    else:
        if not comps:
            errors.add(
                (), "components", 'no components: add tables [components.<name>] with type = "..."'
            )
        registry = _registry()
        if len(comps) > LIMITS["components"]:
            errors.add(
                (),
                "components",
                limit_message("the number of components", len(comps), LIMITS["components"]),
            )
            errors.raise_if_any()
        spec_of = _spec_builder(comps, registry, errors, atmosphere)
        broken = {}
        for cname, ctable in comps.items():
            spec = spec_of(cname)
            if spec is not None:
                specs.append(spec)
            else:
                broken[cname] = ctable
        _network(specs, errors, broken)
        cells = sum(
            v
            for c in specs
            for k, v in c.params.items()
            if k in ("n_volumes", "n_sections") and isinstance(v, int)
        )
        if cells > LIMITS["cells"]:
            errors.add(
                ("components",),
                None,
                limit_message(
                    "the number of volumes and sections in the plant", cells, LIMITS["cells"]
                ),
            )
    nodes = _node_guesses(data.get("nodes"), specs, comps, errors)
    errors.raise_if_any()
    return PlantSpec(
        path=str(path),
        name=name,
        description=description,
        simulation=sim,
        components=specs,
        medium=medium,
        imports=imports,
        atmosphere=atmosphere,
        nodes=nodes,
    )


def _node_guesses(data, specs, comps, errors: Problems) -> dict[str, dict[str, float]]:
    """The ``[nodes.<name>]`` tables: guesses of a node's state for the start, ``p``
    [Pa] and ``T`` [K] or ``h`` [J/kg] (numbers in SI or unit strings), in SI. The node
    must be one the components' ports name."""
    if data is None:
        return {}
    if not isinstance(data, dict):
        errors.add((), "nodes", f"expected tables [nodes.<name>], got {type_name(data)}")
        return {}
    known = {n for c in specs for n in c.ports.values()}
    for table in (comps or {}).values():  # the nodes of components reported as invalid
        ports = table.get("ports") if isinstance(table, dict) else None
        if isinstance(ports, dict):
            known.update(n for n in ports.values() if isinstance(n, str))
    out = {}
    for node, table in data.items():
        where = ("nodes", node)
        if node not in known:
            errors.add(
                where,
                None,
                f"unknown node '{node}': no component's ports name it"
                + suggest(node, sorted(known)),
            )
            continue
        if not isinstance(table, dict):
            errors.add(where, None, f"expected a table with p and T or h, got {type_name(table)}")
            continue
        guess = {}
        for key, v in table.items():
            unit = NODE_GUESS_KEYS.get(key)
            if unit is None:
                errors.add(
                    where,
                    key,
                    "unknown key; a node guess has p (pressure), T (temperature) or h (specific "
                    f"enthalpy){suggest(key, tuple(NODE_GUESS_KEYS))}",
                )
                continue
            x = quantity(v, unit, errors, where, key)
            if x is None:
                continue
            if not math.isfinite(x) or (key != "h" and not x > 0):
                errors.add(
                    where, key, f"{v!r} must be {'finite' if key == 'h' else 'finite and > 0'}"
                )
                continue
            guess[key] = x
        if "T" in guess and "h" in guess:
            errors.add(where, "h", "give T or h as the guess, not both")
            continue
        if not guess and not [k for k in table if k not in NODE_GUESS_KEYS]:
            errors.add(where, None, 'empty node guess: give p = "... bar" and T = "... degC" or h')
            continue
        out[node] = guess
    return out


# --------------------------------------------------------------------------- building


def notices(spec: PlantSpec, text: str | None = None) -> list[str]:
    """Notes ``dnasim check`` prints about choices that are valid but not physical,
    located like problems: a pipe with ``internal_energy = "mean"`` (the seed's eq.
    10.12c: after a step of the inflow the outflow first jumps the other way, and a
    gas may leave colder than anything in the plant)."""
    errors = Problems(str(spec.path), _LineIndex(text) if text is not None else None)
    for c in spec.components:
        if c.params.get("internal_energy") == "mean":
            errors.add(
                ("components", c.name),
                "internal_energy",
                'internal_energy = "mean" is the seed\'s U = M (u_in + u_out)/2 '
                "(eq. 10.12c), kept as its option but not physical: after a step of the "
                "inflow the outflow first jumps the other way, and a gas may leave colder "
                'than anything in the plant; "outlet" (the default, a mixed volume) has '
                "neither artefact",
            )
    return errors.items


_COMPONENT_MESSAGE = re.compile(
    r"^(?P<lead>\s*(?:- )?)component '(?P<name>[^']+)'(?: \((?P<type>[\w.]+)\))?"
    r"(?:, key '(?P<key>[^']+)')?: (?P<rest>.*)$",
    re.S,
)


def locate_messages(path, messages: Sequence[str]) -> list[str]:
    """Messages of the later stages (compiler, start) that begin with ``component
    'NAME' (Type)[, key 'KEY']: ...``, located in the plant file as the file's own
    problems are: ``plant.toml, [components.NAME], key 'KEY', line N: (Type) ...``.
    Other messages, and a file that cannot be read, are left as they are."""
    try:
        text = Path(str(path)).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return list(messages)
    lines = _LineIndex(text)
    out = []
    for msg in messages:
        m = _COMPONENT_MESSAGE.match(msg)
        if m is None:
            out.append(msg)
            continue
        errors = Problems(str(path), lines)
        kind = f"{m['type']} '{m['name']}': " if m["type"] else ""
        errors.add(("components", m["name"]), m["key"], kind + m["rest"])
        out.append(m["lead"] + errors.items[0])
    return out


def _port_example(ports) -> str:
    return ", ".join(f'{q} = "n{i}"' for i, q in enumerate(ports, 1)) or 'inlet = "n1"'


def _key_named(msg: str, table_data: dict) -> str | None:
    """The parameter of the component's table that its own message names first
    ("z_max must be greater than z_min" -> 'z_max'), for the key and line; None
    when it names none."""
    best = None
    for key in table_data:
        if key in RESERVED_KEYS or not isinstance(key, str):
            continue
        m = re.search(rf"(?<![\w.]){re.escape(key)}(?![\w])", msg)
        if m and (best is None or m.start() < best[0]):
            best = (m.start(), key)
    return best[1] if best else None


def _strip_component_prefix(msg: str, name: str) -> str:
    """The component's own message names it; the table already does."""
    return re.sub(rf"^component '{re.escape(name)}'( \(\w+\))?: ", "", msg)


def load(path: str | Path, *, allow_import: bool = False) -> LoadedPlant:
    """Read, validate and build: the plant, its ``[simulation]`` settings and its spec.

    ``allow_import=True`` imports the modules a ``[plant] import`` key names (their
    code runs); without it such a file is refused with a ``PlantError`` saying so."""
    data, text = read_plant_file(path)
    spec = parse_plant(data, str(path), text, allow_import=allow_import)
    plant = build_plant(spec)
    return LoadedPlant(plant=plant, simulation=spec.simulation, spec=spec, path=str(path))


def loads(text: str, path: str = "<string>", *, allow_import: bool = False) -> LoadedPlant:
    """Like :func:`load` for TOML text."""
    data = _decode(text, path)
    spec = parse_plant(data, path, text, allow_import=allow_import)
    return LoadedPlant(plant=build_plant(spec), simulation=spec.simulation, spec=spec, path=path)


def load_plant(path: str | Path, *, allow_import: bool = False):
    """The ``Plant`` described by a TOML plant file, the same object the Python API builds.

    The file's ``[simulation]`` settings are attached as ``plant.simulation``
    (a :class:`SimulationSettings`); ``simulate_plant(plant)`` runs with them::

        plant = dnasim.load_plant("plants/attemperator.toml")
        res = plant.simulate(plant.simulation.t_end, rtol=1e-6, atol_scaled=1e-8)
        df = res.to_dataframe()
    """
    return load(path, allow_import=allow_import).plant


def simulate_plant(plant, settings: SimulationSettings | None = None, **overrides):
    """``dnasim.simulate(compile(plant))`` with a file's settings; keyword arguments
    override them (merged once, by ``dnasim.run.simulation.simulation_keywords``)."""
    from dnasim.compilation.compiler import compile as compile_plant
    from dnasim.run.simulation import simulate, simulation_keywords

    s = settings or getattr(plant, "simulation", None) or SimulationSettings()
    t_end, kwargs = simulation_keywords(s, overrides.pop("t_end", None), **overrides)
    return simulate(compile_plant(plant), t_end=t_end, **kwargs)
