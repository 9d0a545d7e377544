"""The design-point table of a plant at rest: what an engineer checks first (``dnasim
steady``; after TESPy's ``print_results``).

    dp = design_point(system, rest, t0)          # rest: dnasim.start.steady_state.SteadyState
    print(format_design_point(dp, units="si"))   # or "engineering"
    write_design_point(dp, "out/")               # nodes.csv, components.csv, totals.csv

Nodes: p [Pa], T [K], h [J/kg], the phase (quality x = (h - h')/(h'' - h') in the
two-phase region, "subcooled", "superheated", "supercritical", "gas"), and the mass
flow through the node [kg/s] (the sum of the flows into it).

Components (``Component.design_values``): mass flow [kg/s], duty [W] (heat into the
component's fluid), power [W] (shaft power into the fluid: a pump > 0, a turbine < 0),
opening [-] (a valve's z, a controller's output), efficiency [-].

Totals: heat in [W] (the components' ``heat_in``: a furnace, a prescribed wall, flue
gas into water), net power [W] (minus the sum of the powers: turbines less pumps),
the cycle efficiency (net power / heat in, only when both are positive), and the heat
rejected (the negative duties: a condenser).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dnasim.tools.plots import ENGINEERING

__all__ = ["DesignPoint", "design_point", "format_design_point", "write_design_point"]

#: node columns: (key, SI unit, header)
NODE_COLUMNS = (
    ("p", "Pa", "p"),
    ("T", "K", "T"),
    ("h", "J/kg", "h"),
    ("phase", "", "x / phase"),
    ("m", "kg/s", "m"),
)
#: component columns: (key, SI unit, header)
COMPONENT_COLUMNS = (
    ("m", "kg/s", "m"),
    ("duty", "W", "duty"),
    ("power", "W", "power"),
    ("opening", "1", "opening"),
    ("efficiency", "1", "efficiency"),
)
#: totals: (key, SI unit, text)
TOTAL_ROWS = (
    ("heat_in", "W", "heat in"),
    ("heat_rejected", "W", "heat rejected"),
    ("net_power", "W", "net power"),
    ("efficiency", "1", "cycle efficiency"),
)


#: a node within this fraction of h'' (or h') of a saturation line is on it [-]
SATURATED_BAND = 1e-9
#: significant digits of the CSV files (the printed tables show 6)
CSV_DIGITS = 12


@dataclass
class DesignPoint:
    """The tables of one state at rest: ``nodes`` and ``components`` (lists of dicts in
    SI, keyed as NODE_COLUMNS and COMPONENT_COLUMNS, with "name", "medium"/"type"),
    ``totals`` (TOTAL_ROWS' keys), the start's ``notes``, ``saturated`` controllers and
    ``stats``."""

    plant: str
    t0: float
    nodes: list = field(default_factory=list)
    components: list = field(default_factory=list)
    totals: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    saturated: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)


def design_point(system, rest, t0: float = 0.0) -> DesignPoint:
    """The tables of ``rest`` (a ``SteadyState``, or anything with y and yp)."""
    y = np.asarray(rest.y, dtype=float)
    stats = getattr(rest, "stats", None)
    dp = DesignPoint(
        plant=system.name,
        t0=t0,
        notes=list(getattr(rest, "notes", [])),
        saturated=list(getattr(rest, "saturated", [])),
        stats=stats.as_dict() if hasattr(stats, "as_dict") else {},
    )
    inflow = system._mix_sign * y[system._mix_flow]
    through = np.bincount(
        system._mix_node, weights=np.maximum(inflow, 0.0), minlength=system.n_nodes
    )
    for j, node in enumerate(system.node_names):
        k = system.node_index[node]
        p, h = float(y[k]), float(y[k + 1])
        medium = system.node_media.get(node)
        row = {"name": node, "medium": medium.label if medium is not None else "", "p": p, "h": h}
        row["T"], row["phase"] = _temperature_and_phase(medium, p, h)
        row["m"] = float(through[j])
        dp.nodes.append(row)
    heat_in = heat_rejected = power = 0.0
    has_power = has_heat = False
    for b in system.blocks:
        x = b.local(y)
        try:
            values = dict(b.comp.design_values(t0, x))
        except Exception:  # noqa: BLE001 - one component's table entry must not hide the rest
            values = {}
        values = {k: float(v) for k, v in values.items() if v is not None and np.isfinite(v)}
        if not values:
            continue
        row = {"name": b.comp.name, "type": type(b.comp).__name__}
        row.update({k: values[k] for k, _, _ in COMPONENT_COLUMNS if k in values})
        dp.components.append(row)
        if "heat_in" in values:
            heat_in += values["heat_in"]
            has_heat = True
        if values.get("duty", 0.0) < 0.0:
            heat_rejected -= values["duty"]
        if "power" in values:
            power += values["power"]
            has_power = True
    if has_heat:
        dp.totals["heat_in"] = heat_in
    if heat_rejected > 0.0:
        dp.totals["heat_rejected"] = heat_rejected
    if has_power:
        dp.totals["net_power"] = -power
    if has_heat and has_power and heat_in > 0.0 and -power > 0.0:
        dp.totals["efficiency"] = -power / heat_in
    return dp


def _temperature_and_phase(medium, p, h):
    """(T [K], phase): the quality in the two-phase region, else the phase's name."""
    if medium is None:
        return math.nan, ""
    try:
        T = float(medium.state(p, h).T)
    except Exception:  # noqa: BLE001 - a state outside the range: shown as nan
        return math.nan, "out of range"
    if not getattr(medium, "condensable", False):
        return T, "gas"
    try:
        hl, hv = (float(np.asarray(a).reshape(-1)[0]) for a in medium.saturation_enthalpies([p]))
    except Exception:  # noqa: BLE001
        return T, ""
    if not (np.isfinite(hl) and np.isfinite(hv)):
        return T, "supercritical"
    band = SATURATED_BAND * hv  # a drum's steam at h''(p) to round-off is saturated
    if h < hl - band:
        return T, "subcooled"
    if h > hv + band:
        return T, "superheated"
    return T, f"{min(max((h - hl) / (hv - hl), 0.0), 1.0):.4f}"


# ------------------------------------------------------------------------------ output


def _unit(unit: str, units: str) -> tuple[str, float, float]:
    """(shown unit, scale, offset) of an SI unit: shown = SI * scale + offset."""
    if units == "engineering" and unit in ENGINEERING:
        return ENGINEERING[unit]
    return ("-" if unit == "1" else unit), 1.0, 0.0


def _cell(value, unit: str, units: str, digits: int = 6) -> str:
    """A value in the shown unit, ``digits`` significant digits ("" for none)."""
    if isinstance(value, str):
        return value
    if value is None or not np.isfinite(value):
        return ""
    shown, scale, offset = _unit(unit, units)
    return f"{value * scale + offset:.{digits}g}"


def _table(rows, columns, first, units) -> list[str]:
    head = [first[1]] + [f"{h} [{_unit(u, units)[0]}]" if u else h for _, u, h in columns]
    body = [[r[first[0]]] + [_cell(r.get(k), u, units) for k, u, _ in columns] for r in rows]
    keep = [0] + [
        i + 1 for i, (k, _, _) in enumerate(columns) if any(r.get(k) is not None for r in rows)
    ]
    head = [head[i] for i in keep]
    body = [[line[i] for i in keep] for line in body]
    widths = [max(len(x) for x in col) for col in zip(head, *body, strict=True)]
    out = [
        "  ".join(
            x.ljust(w) if i == 0 else x.rjust(w)
            for i, (x, w) in enumerate(zip(line, widths, strict=True))
        )
        for line in [head] + body
    ]
    out.insert(1, "  ".join("-" * w for w in widths))
    return out


def format_design_point(dp: DesignPoint, units: str = "si") -> str:
    """The three tables as aligned text with units (SI, or ``"engineering"``: degC,
    bar, kJ/kg, t/h, MW)."""
    lines = [f"Design point of plant '{dp.plant}' at rest (t = {dp.t0:g} s)", ""]
    lines += ["Nodes"] + _table(dp.nodes, NODE_COLUMNS, ("name", "node"), units) + [""]
    comps = [dict(r, name=f"{r['name']} ({r['type']})") for r in dp.components]
    lines += ["Components"] + _table(comps, COMPONENT_COLUMNS, ("name", "component"), units)
    if dp.totals:
        lines += ["", "Plant totals"]
        for key, unit, text in TOTAL_ROWS:
            if key in dp.totals:
                shown = _unit(unit, units)[0]
                value = _cell(dp.totals[key], unit, units)
                lines.append(f"  {text:<18} {value:>12} {shown if shown != '-' else ''}".rstrip())
    if dp.saturated or dp.notes:
        lines += ["", "Notes"] + [f"  - {n}" for n in dp.notes]
    return "\n".join(lines)


def write_design_point(dp: DesignPoint, out_dir, units: str = "si") -> list[Path]:
    """nodes.csv, components.csv and totals.csv in ``out_dir`` (units in the headers)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = []
    for fname, rows, columns, extra in (
        ("nodes.csv", dp.nodes, NODE_COLUMNS, ("name", "medium")),
        ("components.csv", dp.components, COMPONENT_COLUMNS, ("name", "type")),
    ):
        path = out / fname
        with path.open("w", newline="") as f:
            w = csv.writer(f)
            w.writerow(
                list(extra) + [f"{h} [{_unit(u, units)[0]}]" if u else h for _, u, h in columns]
            )
            for r in rows:
                w.writerow(
                    [r[e] for e in extra]
                    + [_cell(r.get(k), u, units, CSV_DIGITS) for k, u, _ in columns]
                )
        files.append(path)
    path = out / "totals.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["quantity", "value", "unit"])
        for key, unit, text in TOTAL_ROWS:
            if key in dp.totals:
                value = _cell(dp.totals[key], unit, units, CSV_DIGITS)
                w.writerow([text, value, _unit(unit, units)[0]])
    files.append(path)
    return files
