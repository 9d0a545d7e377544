"""A parameter value as a user writes it -> its SI value, checked by ``Param``'s rules.

A number, a unit string ("120 bar", "540 degC", "3.6 t/h") or a time-function
table (``{ type = "step", t0 = "60 s", before = "540 degC", after = "560 degC" }``)
becomes an SI float, an int or a ``dnasim.core.timefunctions`` object; a problem is
added to a :class:`~dnasim.core.errors.Problems` (file, table, key, line) instead of
raised, so that a plant file reports all its problems at once.

One conversion for every way in: plant files (``dnasim.plant.plantfile``), sweep cases
(``dnasim.plant.cases``) and parameters given from Python in the unit of a linked signal
(``Component.resolve_signal_units``: a controller's gain "0.5 1/K"). The range
rules are ``Param.range_problem``'s (``dnasim.model.component``), called on the
parameter object passed in, so this module imports nothing above ``units``.

``LIMITS`` holds the upper limits of counts (volumes, sections, components,
output points, steps) in one place.
"""

from __future__ import annotations

import difflib
import math
import re
from typing import Any

import dnasim.core.timefunctions as tf
from dnasim.core.errors import Problems
from dnasim.core.units import UnitError, convert_quantity, parse_unit

__all__ = [
    "LIMITS",
    "TIME_FUNCTION_TYPES",
    "check_range",
    "example",
    "is_difference",
    "limit_message",
    "output_unit_of",
    "param_kind",
    "param_unit",
    "param_unit_for",
    "param_value",
    "per_output",
    "per_signal",
    "quantity",
    "suggest",
    "time_function",
    "type_name",
]

#: Upper limits of counts, in one place: a plant file asking for more is refused
#: before anything is allocated, with the value and the limit in the message.
#: ``count`` applies to every integer parameter not listed by name.
LIMITS: dict[str, int] = {
    "n_volumes": 5000,  # control volumes of one pipe
    "n_sections": 1000,  # sections of one heat exchanger
    "n_inlets": 64,  # inlets of one mixer
    "n_outlets": 64,  # outlets of one splitter
    "n_tubes": 1_000_000,  # parallel tubes of a pipe, exchanger or condenser (no allocation)
    "count": 10_000,  # any other integer parameter
    "cells": 20_000,  # volumes and sections of the whole plant together
    "components": 2_000,  # components of one plant
    "output_points": 10_000_000,  # rows of results.csv from output_interval
    "max_steps": 100_000_000,  # [simulation] max_steps / --max-steps
}


def limit_message(what: str, value, limit) -> str:
    """``n_volumes = 100000 is above the limit of 1000``."""
    return f"{what} = {value:g} is above the limit of {limit:g}"


#: time-function tables: type -> (required keys, optional keys); values of keys in
#: ``_TF_VALUE_KEYS`` are in the parameter's unit, the others are times [s]
TIME_FUNCTION_TYPES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "constant": (("value",), ()),
    "step": (("t0", "before", "after"), ()),
    "ramp": (("t0", "t1", "start", "end"), ()),
    "table": (("times", "values"), ()),
    "sine": (("mean", "amplitude", "period"), ("phase",)),
}


_TF_VALUE_KEYS = {"value", "before", "after", "start", "end", "values", "mean"}


_TF_DIFFERENCE_KEYS = {"amplitude"}


def suggest(word: str, choices) -> str:
    close = difflib.get_close_matches(str(word), list(choices), n=1, cutoff=0.6)
    if not close:
        low = {c.lower(): c for c in choices}
        if str(word).lower() in low:
            close = [low[str(word).lower()]]
    return f"; did you mean '{close[0]}'?" if close else ""


def type_name(v) -> str:
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, int | float):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


def param_kind(p) -> str:
    return getattr(p, "kind", "number") or "number"


def param_unit(p) -> str:
    return getattr(p, "unit", "1") or "1"


def example(unit: str) -> str:
    return {
        "Pa": "120 bar",
        "K": "540 degC",
        "kg/s": "3.6 t/h",
        "s": "15 min",
        "J/kg": "2800 kJ/kg",
        "m3": "2.5 m3",
        "m2": "30 m2",
        "m": "12 m",
        "W/(m2.K)": "50 W/(m2.K)",
        "1": "0.5",
    }.get(unit, f"1 {unit}")


def is_difference(cls, p) -> bool:
    """Whether parameter ``p`` of ``cls`` is a temperature difference (unit "delta_K")."""
    return param_unit(p).startswith("delta_")


def per_signal(cls, p) -> int:
    """The power of the measured signal's unit in ``p``'s unit (Kp: -1, setpoint: 1)."""
    return int(getattr(p, "per_signal", 0) or 0)


def per_output(cls, p) -> int:
    """The power of the component's output unit in ``p``'s unit (a PID's Kp, z_max: 1)."""
    return int(getattr(p, "per_output", 0) or 0)


def output_unit_of(cls, params) -> str | None:
    """The SI unit of the output of a ``cls`` component with the parameters ``params``
    (a plant file's table, a spec's or the Python keywords): the string parameter
    named by ``cls.OUTPUT_UNIT_PARAM`` (a PID's ``unit``), its default when not given.
    ``None`` when the class declares none or the value is not a unit (that parameter's
    own check reports it)."""
    name = getattr(cls, "OUTPUT_UNIT_PARAM", None)
    if not name:
        return None
    value = params.get(name) if params is not None else None
    if value is None:
        value = next((q.default for q in getattr(cls, "PARAMS", ()) if q.name == name), None)
    if not isinstance(value, str):
        return None
    try:
        parse_unit(value)
    except UnitError:
        return None
    return value


def param_unit_for(cls, p, signal_units=(), output_unit=None) -> str:
    """The SI unit a plant-file value of ``p`` is converted to: the declared unit,
    times the component's output unit (``output_unit``, :func:`output_unit_of`) when
    ``p.per_output``, times the measured signal's unit to the power ``per_signal``
    (Kp of a temperature controller: 1/K; of a pressure controller whose output is a
    heat flow in W: W/Pa)."""
    unit = param_unit(p)
    if unit.startswith("delta_"):
        unit = unit[len("delta_") :]
    if per_output(cls, p) and output_unit and parse_unit(output_unit).dims != parse_unit("1").dims:
        s_out = output_unit if re.fullmatch(r"[A-Za-z0-9/]+", output_unit) else f"({output_unit})"
        unit = s_out if unit == "1" else f"({unit}).{s_out}"
    k = per_signal(cls, p)
    su = next((u for u in signal_units if u), None)
    if k and su is not None and parse_unit(su).dims != parse_unit("1").dims:
        s_su = su if re.fullmatch(r"[A-Za-z]+", su) else f"({su})"
        if k > 0:
            unit = su if unit == "1" else f"({unit}).{s_su}"
        else:
            unit = f"{unit}/{s_su}" if re.fullmatch(r"[A-Za-z0-9/]+", unit) else f"({unit})/{s_su}"
    return unit


def _unit_hint(cls, p, signal_units=(), output_unit=None) -> str:
    """Where the unit of a parameter in the units of the component's signals comes
    from, for a message about a value in the wrong unit ("" for other parameters):
    a gain is in the output unit per the measured unit."""
    k_in, k_out = per_signal(cls, p), per_output(cls, p)
    if not (k_in or k_out):
        return ""
    measured = next((u for u in signal_units if u), None)
    name = getattr(cls, "OUTPUT_UNIT_PARAM", None)
    out = f"'{output_unit or '1'}'" + (f" (the parameter '{name}')" if name else "")
    inp = f"'{measured}' (the measured signal)" if measured else "the measured signal's unit"
    if k_in < 0:
        what = f"output unit per measured unit: {out} per {inp}"
    elif k_in > 0:
        what = f"the measured signal's unit, {inp}"
    else:
        what = f"the output unit, {out}"
    return f"; {p.name} is in {what}"


def quantity(
    v,
    unit,
    errors,
    table,
    key,
    *,
    difference=False,
    lenient_difference=False,
    atmosphere=None,
    hint="",
) -> float | None:
    """A number or unit string in ``unit`` (SI); ``None`` after reporting an error.

    ``difference``: the parameter is a difference (delta_K, delta_Pa): "2 K" and
    "2 delta_degC" are 2 K, "2 degC" (an absolute temperature, 275.15 K) is an error,
    and so is "2 barg" (a gauge pressure). ``lenient_difference``: a difference where
    "10 degC" may mean 10 K (the amplitude of a sine next to its mean in degC).
    ``atmosphere`` [Pa]: the zero of the gauge units ("5 barg"); ``None``: the
    standard atmosphere (``dnasim.core.units.STANDARD_ATMOSPHERE``). ``hint``: added
    to the message of a value in the wrong unit.
    """
    if isinstance(v, dict | list):
        errors.add(
            table,
            key,
            f"expected a number or a string with a unit such as '{example(unit)}', "
            f"got {type_name(v)}",
        )
        return None
    try:
        return convert_quantity(v, unit, difference, lenient_difference, atmosphere)
    except UnitError as exc:
        errors.add(table, key, str(exc) + hint)
        return None


def check_range(x: float, p, errors, table, key, shown) -> None:
    """``Param.range_problem``: the same check as the Python API's."""
    problem = p.range_problem(x)
    if problem is not None:
        kind, text = problem
        what = "out of the physical range" if kind == "physical" else "out of range"
        errors.add(table, key, f"{shown} is {what}: {text}")


def time_function(
    v: dict, p, errors: Problems, table, key, unit: str, difference=False, atmosphere=None
):
    """Build a time function from an inline table ``{type = "step", ...}``; its
    values are in ``unit`` (gauge pressures against ``atmosphere`` [Pa])."""
    sub = tuple(table) + (key,)
    kind = v.get("type")
    if kind is None:
        errors.add(
            sub,
            "type",
            "a time function needs 'type', one of " + ", ".join(TIME_FUNCTION_TYPES),
        )
        return None
    if not isinstance(kind, str) or kind.lower() not in TIME_FUNCTION_TYPES:
        errors.add(
            sub,
            "type",
            f"unknown time function {kind!r}; known: "
            + ", ".join(TIME_FUNCTION_TYPES)
            + (suggest(kind, TIME_FUNCTION_TYPES) if isinstance(kind, str) else ""),
        )
        return None
    kind = kind.lower()
    required, optional = TIME_FUNCTION_TYPES[kind]
    n0 = len(errors.items)
    for k in v:
        if k != "type" and k not in required and k not in optional:
            errors.add(
                sub,
                k,
                f"unknown key for a {kind} time function; expected "
                + ", ".join(required + optional)
                + suggest(k, required + optional),
            )
    for k in required:
        if k not in v:
            errors.add(sub, k, f"missing: a {kind} time function needs " + ", ".join(required))
    if len(errors.items) > n0:
        return None

    def conv(k, x):
        if k in ("times",) or k in ("t0", "t1", "period"):
            return quantity(x, "s", errors, sub, k)
        if k == "phase":
            return quantity(x, "1", errors, sub, k)
        return quantity(
            x,
            unit,
            errors,
            sub,
            k,
            difference=difference,
            lenient_difference=k in _TF_DIFFERENCE_KEYS and not difference,
            atmosphere=atmosphere,
        )

    vals: dict[str, Any] = {}
    for k in required + optional:
        if k not in v:
            continue
        x = v[k]
        if k in ("times", "values"):
            if not isinstance(x, list) or not x:
                errors.add(sub, k, f"expected a non-empty array, got {type_name(x)}")
                continue
            vals[k] = [conv(k, xi) for xi in x]
        else:
            vals[k] = conv(k, x)
    if len(errors.items) > n0:
        return None
    shown = f"the {kind} time function"
    try:
        if kind == "constant":
            f = tf.Constant(vals["value"])
            checks = [vals["value"]]
        elif kind == "step":
            if vals["t0"] < 0:
                errors.add(sub, "t0", f"the step time must not be negative (got {vals['t0']:g} s)")
                return None
            f = tf.Step(vals["t0"], vals["before"], vals["after"])
            checks = [vals["before"], vals["after"]]
        elif kind == "ramp":
            if not vals["t1"] > vals["t0"]:
                errors.add(
                    sub,
                    "t1",
                    f"a ramp needs t1 > t0 (got t0 = {vals['t0']:g} s, t1 = {vals['t1']:g} s)",
                )
                return None
            f = tf.Ramp(vals["t0"], vals["t1"], vals["start"], vals["end"])
            checks = [vals["start"], vals["end"]]
        elif kind == "table":
            times, values = vals["times"], vals["values"]
            if len(times) != len(values):
                errors.add(
                    sub,
                    "values",
                    f"'times' has {len(times)} entries but 'values' has {len(values)}",
                )
                return None
            if any(b <= a for a, b in zip(times, times[1:], strict=False)):
                errors.add(sub, "times", "the times of a table must increase strictly")
                return None
            f = tf.Table(times, values)
            checks = list(values)
        else:  # sine
            if not vals["period"] > 0:
                errors.add(sub, "period", f"the period must be positive (got {vals['period']:g} s)")
                return None
            args = (vals["mean"], vals["amplitude"], vals["period"])
            f = tf.Sine(*args, vals.get("phase", 0.0) or 0.0)
            checks = [vals["mean"] - abs(vals["amplitude"]), vals["mean"] + abs(vals["amplitude"])]
    except (ValueError, TypeError) as exc:  # the time function's own validation
        errors.add(table, key, f"invalid {kind} time function: {exc}")
        return None
    for x in checks:
        n1 = len(errors.items)
        check_range(x, p, errors, table, key, f"a value of {shown}")
        if len(errors.items) > n1:
            break
    return f


def param_value(
    value, p, errors, table, key, signal_units=(), cls=None, atmosphere=None, output_unit=None
):
    """``value`` of parameter ``p`` as its SI value (a float, int, string, bool or time
    function), checked by ``p``'s rules; ``None`` after adding a problem to ``errors``.
    ``atmosphere`` [Pa]: the zero of gauge pressures ("5 barg"), ``None`` the standard
    atmosphere. ``output_unit``: the component's output unit (``output_unit_of``), for
    the parameters in it (``Param.per_output``)."""
    kind = param_kind(p)
    unit = param_unit_for(cls, p, signal_units, output_unit)
    difference = is_difference(cls, p)
    if kind == "string":
        if not isinstance(value, str):
            errors.add(table, key, f"expected a string, got {type_name(value)} ({value!r})")
            return None
        choices = getattr(p, "choices", None)
        if choices and value not in choices:
            errors.add(
                table,
                key,
                f"expected one of {', '.join(map(str, choices))}, "
                f"got {value!r}{suggest(value, choices)}",
            )
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            errors.add(table, key, f"expected true or false, got {type_name(value)} ({value!r})")
            return None
        return value
    if kind not in ("number", "float", "int", "integer"):
        return value  # unknown kind: hand over as it is, the component validates
    if isinstance(value, dict):
        if not getattr(p, "time_function", False):
            errors.add(
                table,
                key,
                f"{p.name} is a constant parameter; a time function ({{ type = ... }}) is "
                "allowed only for boundary values and setpoints",
            )
            return None
        return time_function(value, p, errors, table, key, unit, difference, atmosphere)
    x = quantity(
        value,
        unit,
        errors,
        table,
        key,
        difference=difference,
        atmosphere=atmosphere,
        hint=_unit_hint(cls, p, signal_units, output_unit),
    )
    if x is None:
        return None
    if kind in ("int", "integer"):
        if x != int(x):
            errors.add(table, key, f"expected an integer, got {value!r}")
            return None
        x = int(x)
        limit = LIMITS.get(p.name, LIMITS["count"])
        if x > limit:
            errors.add(table, key, limit_message(p.name, x, limit))
            return None
    check_range(x, p, errors, table, key, repr(value) if isinstance(value, str) else f"{x:g}")
    return x


def t_eval_problem(times, t_start: float, t_end: float) -> str | None:
    """What is wrong with the output times ``times`` [s] (``t_eval``: a sequence of SI
    numbers), or None: the one statement of the rules (here, in the foundation, because
    the simulation and the plant file both use it), for the plant file's
    ``[simulation] t_eval`` (``plantfile`` adds the file, table, key and line) and for
    ``simulate(..., t_eval=...)``. They must be finite, strictly increasing and within
    [t_start, t_end]; at most ``LIMITS["output_points"]`` of them."""
    times = list(times)
    if not times:
        return "must hold at least one time"
    if len(times) > LIMITS["output_points"]:
        return f"holds {len(times)} times, above the limit of {LIMITS['output_points']:g} rows"
    for k, x in enumerate(times):
        if not math.isfinite(x):
            return f"t_eval[{k}] = {x!r} is not a finite time"
    for k in range(1, len(times)):
        if not times[k] > times[k - 1]:
            return (
                f"must be strictly increasing: t_eval[{k}] = {times[k]:g} s follows "
                f"t_eval[{k - 1}] = {times[k - 1]:g} s"
            )
    if times[0] < t_start:
        return f"t_eval[0] = {times[0]:g} s is before t_start = {t_start:g} s"
    if times[-1] > t_end:
        return f"t_eval[{len(times) - 1}] = {times[-1]:g} s is after t_end = {t_end:g} s"
    return None
