"""Sweep cases: parse them (``--set``, CSV, TOML), check their names and units, and
apply one case to a ``PlantSpec``.

A case is a dict ``"COMPONENT.PARAMETER" -> value`` (``"valve.C" -> 0.01``,
``"steam.T" -> "520 degC"``, ``"simulation.t_end" -> "5 min"``); values are
what a plant file accepts for that key: numbers in SI, strings with a unit, a
time-function table, a string or a boolean. ``apply_case(spec, case)`` returns a
copy of the spec with the values validated and converted to SI by the same rules
as the plant files (``dnasim.core.values.param_value``, ``_simulation``), so an
out-of-range value fails that case with the plant file's message.

Sources of cases:

* ``product_cases({"valve.C": [0.01, 0.02], "steam.T": ["500 degC", "520 degC"]})``:
  the Cartesian product (the last key varies fastest), from repeated
  ``--set KEY=V1,V2,...`` options (:func:`parse_set_option`);
* ``read_cases(path)``: a CSV file (a header of keys, optionally with a unit,
  ``steam.T [degC]``, then one row per case) or a TOML file (``[[case]]`` tables,
  ``steam.T = "500 degC"`` or ``steam = { T = "500 degC" }``).
"""

from __future__ import annotations

import copy
import csv
import itertools
import re
import tomllib
from dataclasses import asdict
from pathlib import Path
from typing import Any

from dnasim.core.errors import PlantError

__all__ = [
    "CaseError",
    "apply_case",
    "check_cases",
    "case_units",
    "parse_set_option",
    "parse_value",
    "product_cases",
    "read_cases",
]

#: [simulation] keys a sweep may vary, as ``simulation.<key>``
SIMULATION_SWEEP_KEYS = (
    "t_end",
    "t_start",
    "output_interval",
    "rtol",
    "atol_scaled",
    "max_order",
    "max_step",
    "max_steps",
    "start",
)
_SIM_UNITS = {"t_end": "s", "t_start": "s", "output_interval": "s", "max_step": "s"}


class CaseError(PlantError):
    """A case names an unknown component or parameter, or gives a value whose unit
    does not fit the parameter: a mistake in the sweep's input, not in one case."""


# --------------------------------------------------------------------------- parsing


def parse_value(text: str) -> Any:
    """One value as typed on the command line or in a CSV cell: a TOML value when it
    is one (``0.01`` -> 0.01, ``4`` -> 4, ``true`` -> True, ``"a"`` -> "a",
    ``{ type = "step", ... }`` -> dict), else the text itself (``500 degC``)."""
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):
        return text


def _split_values(text: str) -> list[str]:
    """Split at commas outside quotes, brackets and braces."""
    parts, depth, quote, cur = [], 0, None, []
    for ch in text:
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{(":
            depth += 1
        elif ch in "]})":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    parts.append("".join(cur))
    return [p.strip() for p in parts]


_KEY_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]*\.[A-Za-z_][A-Za-z0-9_]*$")


def parse_set_option(text: str) -> tuple[str, list[Any]]:
    """``"valve.C=0.01,0.02"`` -> ``("valve.C", [0.01, 0.02])``; raises ``CaseError``."""
    key, sep, values = text.partition("=")
    key = key.strip()
    if not sep or not _KEY_RE.match(key):
        raise CaseError(
            f"expected COMPONENT.PARAMETER=V1,V2,... (e.g. valve.C=0.01,0.02 or "
            f'steam.T="500 degC,520 degC"), got {text!r}'
        )
    items = _split_values(values)
    if not values.strip() or any(not v for v in items):
        raise CaseError(f"{key}: an empty value in {values!r}")
    return key, [parse_value(v) for v in items]


def product_cases(values: dict[str, list]) -> list[dict[str, Any]]:
    """The Cartesian product of the values of each key, the last key fastest."""
    keys = list(values)
    return [dict(zip(keys, combo, strict=True)) for combo in itertools.product(*values.values())]


#: largest cases file read [bytes] (a million cases of a few values fit); larger
#: files, and endless ones such as /dev/zero, are refused after this many bytes
MAX_CASES_FILE_BYTES = 64 * 2**20
#: largest cell of a cases CSV [characters] (Python's csv module's limit)
MAX_CELL_CHARS = 128 * 1024


def read_cases(path: str | Path) -> list[dict[str, Any]]:
    """Cases from a CSV or TOML file (by its suffix; see the module docstring).

    The file must be UTF-8 text of at most ``MAX_CASES_FILE_BYTES`` (a bad byte is
    reported with its line and column; a longer file is refused without reading
    it whole), with cells of at most ``MAX_CELL_CHARS``; a column given twice is
    refused, as ``--set`` refuses a key given twice."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_CASES_FILE_BYTES + 1)
    except OSError as exc:
        raise CaseError(f"{path}: cannot read the cases file: {exc.strerror or exc}") from None
    if len(raw) > MAX_CASES_FILE_BYTES:
        raise CaseError(
            f"{path}: the cases file is larger than {MAX_CASES_FILE_BYTES // 2**20} MB; "
            "split the sweep into several files"
        )
    text = decode_text(raw, path)
    if "\x00" in text:
        line, col = _line_column(text, text.index("\x00"))
        raise CaseError(f"{path}, line {line}, column {col}: a NUL character; not a text file")
    if path.suffix.lower() == ".toml":
        return _toml_cases(text, path)
    return _csv_cases(text, path)


def decode_text(raw: bytes, path) -> str:
    """``raw`` as UTF-8 text (a byte-order mark dropped); raises ``CaseError`` with the
    line and column of the first byte that is not UTF-8."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        start = exc.start
        line = raw.count(b"\n", 0, start) + 1
        col = len(raw[raw.rfind(b"\n", 0, start) + 1 : start].decode("utf-8", "replace")) + 1
        raise CaseError(
            f"{path}, line {line}, column {col}: not UTF-8 text (byte 0x{raw[start]:02x}, "
            f"{exc.reason}); save the file as UTF-8"
        ) from None


def _line_column(text: str, pos: int) -> tuple[int, int]:
    return text.count("\n", 0, pos) + 1, pos - (text.rfind("\n", 0, pos) + 1) + 1


_HEADER_UNIT = re.compile(r"^(.*?)\s*\[([^\[\]]*)\]\s*$")


def _csv_rows(text: str, path: Path) -> list[tuple[int, list[str]]]:
    """(line number, cells) of every row that is not empty; raises ``CaseError`` for a
    cell over ``MAX_CELL_CHARS`` or a malformed row, with its line."""
    lines = text.splitlines()
    for i, line in enumerate(lines, start=1):
        if len(line) > MAX_CELL_CHARS:
            raise CaseError(
                f"{path}, line {i}: a line of {len(line)} characters, above the limit of "
                f"{MAX_CELL_CHARS} for a cases file"
            )
    reader = csv.reader(lines)
    rows = []
    try:
        for row in reader:
            if any(c.strip() for c in row):
                rows.append((reader.line_num, row))
    except csv.Error as exc:
        raise CaseError(f"{path}, line {reader.line_num}: malformed CSV: {exc}") from None
    return rows


def _csv_cases(text: str, path: Path) -> list[dict[str, Any]]:
    numbered = _csv_rows(text, path)
    if not numbered:
        raise CaseError(f"{path}: no header row (COMPONENT.PARAMETER columns)")
    head_line, head = numbered[0]
    keys, units = [], []
    for j, h in enumerate(head):
        m = _HEADER_UNIT.match(h.strip())
        key, unit = (m.group(1), m.group(2)) if m else (h.strip(), "")
        if not _KEY_RE.match(key):
            raise CaseError(
                f"{path}, line {head_line}, column {j + 1}: expected COMPONENT.PARAMETER "
                f"(optionally with a unit, 'steam.T [degC]'), got {h!r}"
            )
        if key in keys:
            raise CaseError(
                f"{path}, line {head_line}, columns {keys.index(key) + 1} and {j + 1}: "
                f"{key} is given twice; give each parameter one column"
            )
        keys.append(key)
        units.append("" if unit in ("", "-") else unit)
    cases = []
    for i, row in numbered[1:]:
        if len(row) != len(keys):
            raise CaseError(f"{path}, line {i}: {len(row)} cells for {len(keys)} columns")
        case = {}
        for key, unit, cell in zip(keys, units, row, strict=True):
            v = parse_value(cell)
            if unit and isinstance(v, int | float) and not isinstance(v, bool):
                v = f"{v!r} {unit}"
            case[key] = v
        cases.append(case)
    return cases


def _toml_cases(text: str, path: Path) -> list[dict[str, Any]]:
    try:
        data = tomllib.loads(text)
    except RecursionError:
        raise CaseError(f"{path}: malformed TOML: arrays or tables nested too deeply") from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"{path}: malformed TOML: {exc}") from None
    tables = data.get("case", data.get("cases"))
    if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        raise CaseError(f'{path}: expected [[case]] tables, e.g. [[case]] steam.T = "500 degC"')
    cases = []
    for i, table in enumerate(tables, start=1):
        case = {}
        for k, v in table.items():
            # steam.T = ... is the table steam = { T = ... }; "steam.T" = ... is one key
            items = (
                [(f"{k}.{p}", pv) for p, pv in v.items()]
                if isinstance(v, dict) and "." not in k and "type" not in v
                else [(k, v)]
            )
            for key, value in items:
                if key in case:
                    raise CaseError(
                        f"{path}, case {i}: {key} is given twice (as a dotted key and in a "
                        "table); give it once"
                    )
                case[key] = value
        for k in case:
            if not _KEY_RE.match(k):
                raise CaseError(f"{path}, case {i}: expected COMPONENT.PARAMETER, got {k!r}")
        cases.append(case)
    return cases


# --------------------------------------------------------------------------- checks


def _parameter(spec, key: str):
    """(ComponentSpec, component class, Param) for "comp.param"; raises ``CaseError``."""
    from dnasim.core.values import suggest as _suggest
    from dnasim.plant.plantfile import params_of

    cname, _, pname = key.partition(".")
    comps = {c.name: c for c in spec.components}
    c = comps.get(cname)
    if c is None:
        raise CaseError(
            f"{key}: no component '{cname}' in {spec.path}{_suggest(cname, comps)} "
            f"(components: {', '.join(comps)}; [simulation] keys as simulation.t_end)"
        )
    cls = c.component_class()
    params = {p.name: p for p in params_of(cls)}
    p = params.get(pname)
    if p is None:
        raise CaseError(
            f"{key}: {c.type} '{cname}' has no parameter '{pname}'{_suggest(pname, params)} "
            f"(parameters: {', '.join(params) or 'none'})"
        )
    return c, cls, p


def _signal_units(spec, c) -> tuple:
    """Units of the signal outputs linked into component ``c`` (for parameters in the
    measured signal's unit, such as a controller's gain)."""
    from dnasim.core.units import UnitError, parse_unit

    comps = {x.name: x for x in spec.components}
    out = []
    for src in c.inputs.values():
        cname, _, oname = src.partition(".")
        unit = None
        other = comps.get(cname)
        if other is not None:
            for port in getattr(other.component_class(), "SIGNAL_OUTPUTS", ()) or ():
                if getattr(port, "name", None) == oname and getattr(port, "unit", None):
                    try:
                        parse_unit(port.unit)
                    except UnitError:
                        continue
                    unit = port.unit
        out.append(unit)
    return tuple(out)


def case_units(spec, keys) -> dict[str, str]:
    """The SI unit of each case key ("steam.T" -> "K"); "" for strings and booleans."""
    from dnasim.core.values import output_unit_of, param_unit_for
    from dnasim.core.values import param_kind as _param_kind

    units = {}
    for key in keys:
        cname, _, pname = key.partition(".")
        if cname == "simulation":
            units[key] = _SIM_UNITS.get(pname, "1" if pname != "start" else "")
            continue
        c, cls, p = _parameter(spec, key)
        kind = _param_kind(p)
        units[key] = (
            param_unit_for(cls, p, _signal_units(spec, c), output_unit_of(cls, c.params))
            if kind in ("number", "float", "int", "integer")
            else ""
        )
    return units


def check_cases(spec, cases) -> None:
    """Raise ``CaseError`` for an unknown component or parameter, or a value whose unit
    does not fit (the sweep's input, before anything runs). Values out of range are
    left to the case, which then fails with the plant file's message."""
    from dnasim.core.units import UnitError, convert_quantity
    from dnasim.core.values import is_difference
    from dnasim.core.values import param_kind as _param_kind

    seen = set()
    for case in cases:
        for key, value in case.items():
            if (key, repr(value)) in seen:
                continue
            seen.add((key, repr(value)))
            cname, _, pname = key.partition(".")
            if cname == "simulation":
                if pname not in SIMULATION_SWEEP_KEYS:
                    raise CaseError(
                        f"{key}: [simulation] has no key '{pname}' that a sweep can vary "
                        f"(keys: {', '.join(SIMULATION_SWEEP_KEYS)})"
                    )
                unit = _SIM_UNITS.get(pname, "1")
                if pname not in ("start", "max_order", "max_steps") and not isinstance(value, dict):
                    try:
                        convert_quantity(value, unit)
                    except UnitError as exc:
                        raise CaseError(f"{key} = {value!r}: {exc}") from None
                continue
            c, cls, p = _parameter(spec, key)
            if _param_kind(p) not in ("number", "float", "int", "integer"):
                continue
            if isinstance(value, dict | list | bool):
                continue  # time functions and type errors: the case reports them
            unit = case_units(spec, [key])[key]
            try:
                convert_quantity(value, unit, is_difference(cls, p), atmosphere=spec.atmosphere)
            except UnitError as exc:
                from dnasim.core.values import _unit_hint, output_unit_of

                hint = _unit_hint(cls, p, _signal_units(spec, c), output_unit_of(cls, c.params))
                raise CaseError(f"{key} = {value!r}: {exc}{hint}") from None


# --------------------------------------------------------------------------- applying


def apply_case(spec, case: dict[str, Any]):
    """A copy of ``spec`` with the case's values (validated and converted to SI as in
    a plant file); raises ``PlantError`` naming the component and key, e.g.
    ``plant.toml, [components.valve], key 'C': -1 is out of the physical range``."""
    from dnasim.core.errors import Problems
    from dnasim.core.values import output_unit_of
    from dnasim.core.values import param_value as _param_value
    from dnasim.plant.plantfile import _simulation

    new = copy.deepcopy(spec)
    errors = Problems(f"{spec.path} (case {_case_text(case)})", None)
    sim_values = {k.partition(".")[2]: v for k, v in case.items() if k.startswith("simulation.")}
    if sim_values:
        raw = {k: v for k, v in asdict(new.simulation).items() if v is not None}
        if "output_interval" in sim_values:
            raw.pop("t_eval", None)  # a case's output interval replaces the file's times
        raw.update(sim_values)
        new.simulation = _simulation({"simulation": raw}, errors)
    for key, value in case.items():
        if key.startswith("simulation."):
            continue
        cname, _, pname = key.partition(".")
        c, cls, p = _parameter(new, key)
        x = _param_value(
            value,
            p,
            errors,
            ("components", cname),
            pname,
            _signal_units(new, c),
            cls,
            atmosphere=new.atmosphere,
            output_unit=output_unit_of(cls, {**c.params, **_case_params(case, cname)}),
        )
        c.params[pname] = x
        c.instance = None  # built again from the new parameters
    errors.raise_if_any()
    return new


def _case_params(case: dict[str, Any], cname: str) -> dict[str, Any]:
    """The case's values of component ``cname``'s parameters, by parameter name."""
    return {k.partition(".")[2]: v for k, v in case.items() if k.partition(".")[0] == cname}


def _case_text(case: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v}" for k, v in case.items())
