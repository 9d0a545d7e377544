"""Plots for engineers from the files of a run (results.csv, steps.csv, events.csv,
plant.json).

``dnasim run --plot`` and ``dnasim plot`` both call :func:`write_run_plots` on the
files on disk, so they write the same ``variables.png`` and ``steps.png`` with the
same event markers; ``report.html`` draws the same panels (:func:`select_panels`).

- One unit per axis: a panel holds one quantity in one SI unit (:class:`Panel`);
  its axis is labelled with the quantity's name and the (display) unit. The
  quantity comes from a variable's unit and name (:func:`quantity_of`):
  pressure, level, temperature, mass flow, heat flow, power, quality, controller
  output, ...
- The default selection (:func:`select_panels`) is what an engineer looks at
  first, chosen by quantity: pressures (nodes, drums, condensers, sensors),
  levels, temperatures (component outlets, sensors, vessels, nodes), mass flows
  (boundaries, valves, pumps, turbines), heat flows (duties ``Q``, ``Q_total``,
  ``Q_in``), powers (``P`` of turbines and pumps), qualities (``x``), then one
  panel per controller with its measured value against its set point (same
  unit; the measured signal is found through ``plant.json``'s links), and the
  controllers' outputs on an axis spanning their limits. A boundary's flow is
  positive into the plant; a sink's is drawn as -m, "out of the plant".
- Constants get no curve and no panel: a candidate whose span over the run is
  within :data:`CONSTANT_REL` of its magnitude is listed in the figure's note
  ("constant over the run: n_sink.p = 1 bar, ...").
- Curves that coincide (within 0.2 % of the panel's span) are drawn once, their
  names joined with "="; curves of one quantity whose ranges are far apart
  (:func:`split_bands`) get panels of their own.
- ``units="engineering"`` converts for display (:data:`ENGINEERING`): K -> degC,
  Pa -> bar, kg/s -> t/h, J/kg -> kJ/kg, W -> MW, J -> MJ. The CSV stays SI.
- The title is the plant's name and description (from ``plant.json``; without
  it, the run directory's name).
- Discontinuities are marked: grey dotted lines at the rows flagged ``restart``
  (time events and switches), red dashed lines at the located switches of
  ``events.csv``.

matplotlib is imported inside the functions (Agg backend).
"""

from __future__ import annotations

import csv
import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "ENGINEERING",
    "QUANTITY_ORDER",
    "CONSTANT_REL",
    "Curve",
    "Panel",
    "quantity_of",
    "display",
    "default_selection",
    "select_panels",
    "panels_for",
    "merge_identical",
    "read_run",
    "write_run_plots",
    "plot_quantities",
    "plot_panels",
    "plant_title",
]

#: SI unit -> (display unit, scale, offset): display = SI * scale + offset
ENGINEERING = {
    "K": ("°C", 1.0, -273.15),
    "delta_K": ("K", 1.0, 0.0),  # a temperature difference: no offset
    "Pa": ("bar", 1e-5, 0.0),
    "kg/s": ("t/h", 3.6, 0.0),
    "J/kg": ("kJ/kg", 1e-3, 0.0),
    "W": ("MW", 1e-6, 0.0),
    "J": ("MJ", 1e-6, 0.0),
}

#: panel order, top to bottom ("controller": one panel per controller, its
#: measured value against its set point)
QUANTITY_ORDER = (
    "pressure",
    "level",
    "temperature",
    "mass flow",
    "heat flow",
    "power",
    "quality",
    "valve lift",
    "controller",
    "controller output",
    "control error",
    "specific enthalpy",
    "energy flow",
    "energy",
    "mass",
    "volume",
)

_BY_UNIT = {
    "K": "temperature",
    "delta_K": "temperature difference",
    "Pa": "pressure",
    "kg/s": "mass flow",
    "J/kg": "specific enthalpy",
    "W": "power",
    "J": "energy",
    "kg": "mass",
    "m3": "volume",
    "m": "length",
    "kg/m3": "density",
    "m3/s": "volume flow",
}
_SIGNAL_LEAVES = {
    "z": "controller output",
    "z_max": "controller output",
    "z_min": "controller output",
    "opening": "controller output",
    "m_p": "controller parts",
    "m_I": "controller parts",
    "m_D": "controller parts",
    "x": "quality",
    "x_s": "quality",
    "lift": "valve lift",
    "setpoint": "set point",
}
#: columns that are flags, never plotted
NOT_PLOTTED = ("restart",)

#: a variable whose span over the run (max - min) is at most this fraction of its
#: magnitude (or of 1e-3 of the largest magnitude of its quantity, for curves near
#: zero), or at most :data:`CONSTANT_ATOL` of its unit, is a constant: listed in the
#: note, not drawn. 1e-5: 1 mbar of 100 bar, 10 mK of 1000 K, 1/100 of the
#: narrowest axis the plots draw (:func:`y_limits`, 1e-3 of the magnitude), far
#: above round-off (1e-16)
CONSTANT_REL = 1e-5
#: SI unit -> a span that is no change at all for an engineer (a mW of heat, a
#: mg/s of flow, a mPa, a µK): the round-off of a quantity that is zero
CONSTANT_ATOL = {
    "W": 1e-3,
    "kg/s": 1e-6,
    "Pa": 1e-3,
    "K": 1e-6,
    "delta_K": 1e-6,
    "m": 1e-9,
    "m3": 1e-9,
    "J": 1e-3,
    "J/kg": 1e-3,
    "kg": 1e-9,
}


def _leaf(name: str) -> str:
    leaf = name.rsplit(".", 1)[-1]
    return leaf.split("[", 1)[0]


def quantity_of(name: str, unit: str) -> str:
    """The physical quantity of a results column (the name of its axis)."""
    unit = unit or "-"
    leaf = _leaf(name)
    if leaf == "e":
        return "control error"
    if unit in ("-", "1"):
        return _SIGNAL_LEAVES.get(leaf, "dimensionless")
    if unit == "m" and leaf in ("level", "l_s"):
        return "level"
    if unit == "m" and leaf == "H":
        return "head"
    if unit == "W":
        if leaf == "P":
            return "power"
        return "heat flow" if leaf.startswith("Q") else "energy flow"
    return _BY_UNIT.get(unit, unit)


#: engineering units for small magnitudes: SI unit -> (below this magnitude [SI],
#: display unit, scale); a 40 kW pipe is not drawn as 0.04 MW
ENGINEERING_SMALL = {"W": (1e6, "kW", 1e-3), "J": (1e6, "kJ", 1e-3)}


def display(values, unit: str, units: str = "si", magnitude: float | None = None):
    """(values, unit) for display: SI, or engineering units (:data:`ENGINEERING`;
    with ``magnitude``, the largest |value| [SI] of the axis, kW and kJ below
    1 MW and 1 MJ, :data:`ENGINEERING_SMALL`)."""
    unit = unit or "-"
    if units == "engineering" and unit in ENGINEERING:
        u, scale, offset = ENGINEERING[unit]
        small = ENGINEERING_SMALL.get(unit)
        if small is not None and magnitude is not None and magnitude < small[0]:
            u, scale = small[1], small[2]
        return np.asarray(values, dtype=float) * scale + offset, u
    return np.asarray(values, dtype=float), ("-" if unit == "1" else unit)


def magnitude(arrays) -> float:
    """The largest finite |value| of ``arrays`` (0 when there is none)."""
    best = 0.0
    for a in arrays:
        a = np.abs(np.asarray(a, dtype=float))
        a = a[np.isfinite(a)]
        if a.size:
            best = max(best, float(a.max()))
    return best


def _components(names: Sequence[str]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for n in names:
        if "." in n:
            c, v = n.split(".", 1)
            out.setdefault(c, set()).add(v.split("[", 1)[0])
    return out


# --------------------------------------------------------------------------- selection


@dataclass
class Curve:
    """One line of a panel: the columns ``names`` (they coincide: drawn once, the
    first one's values), times ``sign`` (-1: a sink's flow, drawn out of the plant)."""

    names: list[str]
    label: str
    sign: float = 1.0
    dashed: bool = False


@dataclass
class Panel:
    """One axis: curves of one quantity in one SI unit. ``title``: the panel's own
    heading (a controller's name); ``limits``: a range in SI the axis spans at
    least (a controller's output limits)."""

    quantity: str
    unit: str
    curves: list[Curve] = field(default_factory=list)
    title: str = ""
    limits: tuple[float, float] | None = None

    @property
    def names(self) -> list[str]:
        return [n for c in self.curves for n in c.names]


@dataclass
class _Plant:
    """What the selection knows of the plant: from plant.json, else from the names."""

    nodes: set
    boundaries: set
    controllers: list  # [{"name", "measured", "setpoint", "output", "error"}]


def _plant_roles(names: Sequence[str], plant: dict | None) -> _Plant:
    comps = _components(names)
    have = set(names)
    if plant:
        nodes = set(plant.get("nodes", ()))
        boundaries = {c["name"] for c in plant.get("components", ()) if c.get("supply") is not None}
        ctrls = []
        for c in plant.get("controllers", ()):
            ctrls.append({k: (v if v in have else None) for k, v in c.items() if k != "name"})
            ctrls[-1]["name"] = c["name"]
        return _Plant(nodes, boundaries, ctrls)
    nodes = {c for c, v in comps.items() if v <= {"p", "h", "T"} and {"p", "h"} <= v}
    boundaries = {c for c, v in comps.items() if "M_passed" in v}
    ctrls = []
    for c, v in comps.items():
        if {"e", "z"} <= v and ("m_I" in v or "setpoint" in v):

            def col(leaf, c=c):
                n = f"{c}.{leaf}"
                return n if n in have else None

            ctrls.append(
                {
                    "name": c,
                    "measured": None,
                    "setpoint": col("setpoint"),
                    "output": col("z"),
                    "error": col("e"),
                }
            )
    return _Plant(nodes, boundaries, ctrls)


def _candidates(names: Sequence[str], units: dict[str, str], roles: _Plant) -> dict:
    """{(quantity, SI unit): [names]} of the default selection, before constants
    are taken out; components before nodes (a merged curve is named by its
    component first)."""
    out: dict[tuple[str, str], list[str]] = {}
    # a controller's columns have its own panels (the measured value against the set point)
    ctrl_cols = {
        c.get(k) for c in roles.controllers for k in ("measured", "setpoint", "output", "error")
    }
    for n in names:
        if "." not in n or "[" in n or "~" in n or n in ctrl_cols or _leaf(n) in NOT_PLOTTED:
            continue
        comp, leaf = n.split(".", 1)
        unit = units.get(n, "") or "-"
        node = comp in roles.nodes
        q = None
        if unit == "Pa" and (leaf == "p" or (not node and leaf in ("p_v", "p_s"))):
            q = "pressure"
        elif unit == "m" and leaf in ("level", "l_s"):
            q = "level"
        elif unit == "K" and (
            leaf == "T" or (not node and (leaf in ("T_s", "T_sat") or leaf.endswith("T_out")))
        ):
            q = "temperature"
        elif unit == "kg/s" and leaf in ("m", "m_s") and not node:
            q = "mass flow"
        elif unit == "W" and leaf in ("Q", "Q_total", "Q_in"):
            q = "heat flow"
        elif unit == "W" and leaf == "P":
            q = "power"
        elif unit in ("-", "1") and leaf in ("x", "x_s"):
            q = "quality"
        elif unit in ("-", "1") and leaf == "lift":
            q = "valve lift"
        if q is not None:
            out.setdefault((q, unit), []).append(n)
    for group in out.values():
        group.sort(key=lambda n: n.split(".", 1)[0] in roles.nodes)
    return out


def default_selection(names: Sequence[str], units: dict[str, str], plant=None) -> list[str]:
    """The names the default plots choose from (see the module docstring), in panel
    order, before constants are taken out (:func:`select_panels` does that)."""
    roles = _plant_roles(names, plant)
    cands = _candidates(names, units, roles)
    order = {q: i for i, q in enumerate(QUANTITY_ORDER)}
    chosen = []
    for key in sorted(cands, key=lambda k: order.get(k[0], len(order))):
        chosen += cands[key]
    for c in roles.controllers:
        chosen += [n for n in (c.get("measured"), c["setpoint"], c["output"]) if n]
        if not c.get("measured") and c["error"]:
            chosen.append(c["error"])
    return list(dict.fromkeys(chosen))


def is_constant(values, scale: float = 0.0, unit: str = "", rel: float = CONSTANT_REL) -> bool:
    """Whether ``values`` do not change over the run: span within ``rel`` of
    max(their magnitude, 1e-3 ``scale``) or within the ``unit``'s
    :data:`CONSTANT_ATOL` (see :data:`CONSTANT_REL`)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not v.size:
        return True
    mag = max(float(np.abs(v).max()), 1e-3 * scale)
    span = float(v.max() - v.min())
    return span <= rel * mag or span <= CONSTANT_ATOL.get(unit, 1e-12)


def _boundary_sign(name: str, values, roles: _Plant) -> float:
    """-1 for the flow of a boundary that lets fluid out of the plant (mean m < 0)."""
    if name.split(".", 1)[0] in roles.boundaries and _leaf(name) == "m":
        v = np.asarray(values, dtype=float)
        v = v[np.isfinite(v)]
        if v.size and float(v.mean()) < 0:
            return -1.0
    return 1.0


def _curve_label(group: Sequence[str], signs: dict[str, float], roles: _Plant) -> str:
    """``"stack_valve.m = -stack.m (out of the plant)"``: the names of coinciding
    curves, a sink's flow with its sign; a boundary's flow says which way it counts."""
    label = " = ".join(f"-{n}" if signs[n] < 0 else n for n in group)
    for n in group:
        if _leaf(n) == "m" and n.split(".", 1)[0] in roles.boundaries:
            return label + (" (out of the plant)" if signs[n] < 0 else " (into the plant)")
    return label


#: quantities whose curves are split into bands that do not overlap
#: (:func:`split_bands`): by the gap between their ranges (temperatures,
#: pressures, enthalpies: a few degrees of a control loop matter beside a line
#: 200 degC below) or, for all of them, by the ratio of their ranges (a 7 t/h
#: spray beside 110 t/h of steam; two turbines' 11 and 15 MW stay together)
BANDED = {
    "temperature": 0.2,
    "pressure": 0.2,
    "specific enthalpy": 0.2,
    "mass flow": None,
    "heat flow": None,
    "power": None,
    "level": None,
}


def _bands(q: str, merged, series) -> list:
    if q not in BANDED:
        return [merged]
    gap = BANDED[q]
    return split_bands(merged, series, gap=math.inf if gap is None else gap)


def _quantity_panels(q, unit, group, data, roles, constants, max_lines):
    signs = {n: _boundary_sign(n, data[n], roles) for n in group}
    series = {n: signs[n] * np.asarray(data[n], dtype=float) for n in group}
    finite = [np.abs(v[np.isfinite(v)]) for v in series.values()]
    scale = max((float(f.max()) for f in finite if f.size), default=0.0)
    moving = []
    for n in group:
        if is_constant(series[n], scale, unit):
            constants.append((n, _final(data[n]), unit))
        else:
            moving.append(n)
    if not moving:
        return []
    merged = merge_identical(None, {n: series[n] for n in moving})
    bands = _bands(q, merged, series)
    out = []
    for band in bands:
        for i in range(0, len(band), max_lines):
            curves = [
                Curve(list(g), _curve_label(g, signs, roles), signs[g[0]])
                for g in band[i : i + max_lines]
            ]
            out.append(Panel(q, unit, curves))
    return out


def _final(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(v[-1]) if v.size else math.nan


def select_panels(
    names: Sequence[str],
    units: dict[str, str],
    data: dict,
    plant: dict | None = None,
    *,
    max_lines: int = 8,
) -> tuple[list[Panel], list[tuple[str, float, str]]]:
    """The default panels of a run (see the module docstring) and the constants
    left out, ``[(name, value, SI unit)]``.

    ``names``, ``units``, ``data``: the results columns, their SI units and values;
    ``plant``: the description of ``plant.json`` (:mod:`dnasim.plant.plantinfo`), for
    the controllers' measured signals and the nodes and boundaries (without it,
    they are guessed from the names, and a controller's panel shows its set point
    and its error instead of the measured value)."""
    names = [n for n in names if n in data and n != "time"]
    roles = _plant_roles(names, plant)
    cands = _candidates(names, units, roles)
    order = {q: i for i, q in enumerate(QUANTITY_ORDER)}
    panels: list[Panel] = []
    constants: list[tuple[str, float, str]] = []
    keys = sorted(cands, key=lambda k: order.get(k[0], len(order)))
    before = [k for k in keys if order.get(k[0], len(order)) < order["controller"]]
    after = [k for k in keys if k not in before]
    for q, unit in before:
        panels += _quantity_panels(q, unit, cands[(q, unit)], data, roles, constants, max_lines)
    outputs: dict[str, list[str]] = {}
    limits: dict[str, list[float]] = {}
    for c in roles.controllers:
        m, w = c.get("measured"), c.get("setpoint")
        unit = units.get(m or w or "", "") or "-"
        curves = []
        if m:
            curves.append(Curve([m], f"{m} (measured)"))
        if w and (not m or units.get(w) == units.get(m)):
            curves.append(Curve([w], f"{w} (set point)", dashed=True))
        if curves and not all(is_constant(data[cv.names[0]], 0.0, unit) for cv in curves):
            q = quantity_of(m, unit) if m else quantity_of(w, unit)
            panels.append(Panel(q, unit, curves, title=c["name"]))
        else:
            constants += [(cv.names[0], _final(data[cv.names[0]]), unit) for cv in curves]
        e = c.get("error")
        if not m and e:
            if is_constant(data[e], 0.0, units.get(e, "")):
                constants.append((e, _final(data[e]), units.get(e, "-")))
            else:
                eu = units.get(e, "-") or "-"
                panels.append(Panel("control error", eu, [Curve([e], e)], title=c["name"]))
        z = c.get("output")
        if z:
            zu = units.get(z, "") or "-"
            if is_constant(data[z], 0.0, zu):
                constants.append((z, _final(data[z]), zu))
                continue
            outputs.setdefault(zu, []).append(z)
            for leaf in ("z_min", "z_max"):
                lim = f"{c['name']}.{leaf}"
                if lim in data:
                    limits.setdefault(zu, []).extend(np.asarray(data[lim], dtype=float).tolist())
    for zu, zs in outputs.items():
        lim = [v for v in limits.get(zu, []) if math.isfinite(v)]
        for i in range(0, len(zs), max_lines):
            panels.append(
                Panel(
                    "controller output",
                    zu,
                    [Curve([z], z) for z in zs[i : i + max_lines]],
                    limits=(min(lim), max(lim)) if lim else None,
                )
            )
    for q, unit in after:
        panels += _quantity_panels(q, unit, cands[(q, unit)], data, roles, constants, max_lines)
    return panels, constants


def panels_for(
    names: Sequence[str], units: dict[str, str], data: dict, *, max_lines: int = 10
) -> list[Panel]:
    """Panels of the variables asked for (``--vars``): one per quantity and SI unit,
    coinciding curves drawn once, far-apart ranges in panels of their own;
    constants are drawn too (they were asked for)."""
    groups: dict[tuple[str, str], list[str]] = {}
    for n in names:
        u = units.get(n, "") or "-"
        groups.setdefault((quantity_of(n, u), u), []).append(n)
    order = {q: i for i, q in enumerate(QUANTITY_ORDER)}
    out = []
    for (q, unit), group in sorted(groups.items(), key=lambda kv: order.get(kv[0][0], len(order))):
        merged = merge_identical(None, {n: np.asarray(data[n], dtype=float) for n in group})
        bands = _bands(q, merged, data)
        for band in bands:
            for i in range(0, len(band), max_lines):
                curves = [
                    Curve(
                        list(g), " = ".join(g), dashed=_leaf(g[0]) in ("setpoint", "z_max", "z_min")
                    )
                    for g in band[i : i + max_lines]
                ]
                out.append(Panel(q, unit, curves))
    return out


def merge_identical(t, series: dict[str, np.ndarray], rel: float = 2e-3) -> list[list[str]]:
    """Groups of names whose curves coincide on a plot: max |a - b| within ``rel`` of
    the span of all the curves given (0.2 %: less than a line width)."""
    names = list(series)
    if not names:
        return []
    allv = np.concatenate([np.asarray(v, dtype=float) for v in series.values()])
    allv = allv[np.isfinite(allv)]
    span = float(allv.max() - allv.min()) if allv.size else 0.0
    tol = rel * (span if span > 0 else max(1.0, float(np.abs(allv).max(initial=0.0))))
    groups: list[list[str]] = []
    for n in names:
        for g in groups:
            a, b = series[g[0]], series[n]
            if a.shape == b.shape and np.nanmax(np.abs(a - b), initial=0.0) <= tol:
                g.append(n)
                break
        else:
            groups.append([n])
    return groups


# --------------------------------------------------------------------------- files


def read_run(results_csv):
    """(names, units, data, step rows, event times, restart times) from a run's files;
    ``steps.csv`` and ``events.csv`` next to ``results_csv`` are optional."""
    from dnasim.run.output import read_results_csv

    path = Path(results_csv)
    names, units, data = read_results_csv(path)
    steps = []
    sp = path.with_name("steps.csv")
    if sp.exists():
        try:
            with open(sp, newline="") as f:
                steps = [
                    (
                        float(r["time"]),
                        float(r["step_size"]),
                        float(r["order"]) if r["order"] else math.nan,
                    )
                    for r in csv.DictReader(f)
                ]
        except (OSError, ValueError, KeyError):
            steps = []
    events = []
    ep = path.with_name("events.csv")
    if ep.exists():
        try:
            with open(ep, newline="") as f:
                last: dict[str, float] = {}
                for r in csv.DictReader(f):
                    last[r["event"]] = float(r["time"])  # the last iterate: the switch time
                events = sorted(last.values())
        except (OSError, ValueError, KeyError):
            events = []
    restarts = []
    if "restart" in data:
        restarts = sorted(set(data["time"][data["restart"] == 1].tolist()))
    return names, units, data, steps, events, restarts


def plant_title(plant: dict | None, results_csv) -> tuple[str, str]:
    """(title, subtitle) of a run's plots: the plant's name and description from
    ``plant.json``; without it, the name of the run's directory."""
    if plant and plant.get("name"):
        return str(plant["name"]), str(plant.get("description") or "")
    path = Path(results_csv).resolve()
    return path.parent.name or str(path.parent), ""


def _constants_note(constants, units: str, limit: int = 14) -> str:
    if not constants:
        return ""
    items = []
    for name, value, unit in constants:
        if abs(value) <= CONSTANT_ATOL.get(unit, 1e-12):
            value = 0.0  # round-off of a zero: "0 MW", not "5.3e-26 MW"
        v, u = display(np.array([value]), unit, units, abs(value))
        items.append(f"{name} = {float(v[0]):.5g} {u}".rstrip(" -"))
    more = len(items) - limit
    text = ", ".join(items[:limit]) + (f" and {more} more" if more > 0 else "")
    return "constant over the run (not drawn): " + text


def write_run_plots(
    results_csv,
    patterns: Sequence[str] | None = None,
    *,
    units: str = "si",
    variables_path=None,
    steps_path=None,
) -> list[Path]:
    """``variables.png`` and ``steps.png`` next to ``results_csv`` (or at the paths
    given) from the run's files. Raises ``ValueError`` when no variable matches."""
    from dnasim.plant.plantinfo import read_plant_json
    from dnasim.run.output import plot_steps, select_variables

    path = Path(results_csv)
    names, unit_of, data, steps, events, restarts = read_run(path)
    plant = read_plant_json(path.parent)
    variables = [n for n in names[1:] if n not in NOT_PLOTTED]
    constants: list = []
    if patterns:
        chosen = select_variables(variables, patterns)
        if not chosen:
            raise ValueError(f"no variable matches {' '.join(patterns)}")
        panels = panels_for(chosen, unit_of, data)
    else:
        panels, constants = select_panels(variables, unit_of, data, plant)
        if not panels and not constants:
            panels = panels_for(variables[:8], unit_of, data)
    title, subtitle = plant_title(plant, path)
    target = Path(variables_path) if variables_path else path.with_name("variables.png")
    files = [
        plot_panels(
            data["time"],
            data,
            panels,
            target,
            units=units,
            events=events,
            restarts=restarts,
            title=title,
            subtitle=subtitle,
            note=_constants_note(constants, units),
        )
    ]
    if steps and (steps_path is not None or variables_path is None):
        target2 = Path(steps_path) if steps_path else path.with_name("steps.png")
        files.append(plot_steps(steps, target2, event_times=events, title=f"{title}: solver steps"))
    return files


def curve_label(group: Sequence[str], comps: dict[str, set[str]]) -> str:
    """Legend text of a curve drawn for the names in ``group`` (coinciding curves);
    a boundary's flow says its sign convention."""
    label = " = ".join(group)
    if _leaf(group[0]) == "m" and "M_passed" in comps.get(group[0].split(".")[0], ()):
        label += " (into the plant)"
    return label


def axis_unit(quantity: str, unit: str) -> str:
    """The unit shown on an axis (the controller error's is not in the CSV yet)."""
    if quantity == "control error" and unit in ("-", "1", ""):
        return "unit of the measured signal"
    return unit


def split_bands(
    groups: Sequence[Sequence[str]], data: dict, gap: float = 0.2, ratio: float = 4.0
) -> list[list]:
    """Curves (groups of coinciding names, drawn once) of one quantity in bands that
    do not overlap: a new band starts where the gap between the ranges of
    consecutive curves (sorted by their minimum) is more than ``gap`` of the whole
    span (a 200 degC water line does not squeeze a 440 degC control loop into a
    few pixels), or where both ranges are positive and the next starts above
    ``ratio`` times the top so far (a condenser at 0.08 bar beside a flue-gas duct
    at 1 bar). Highest band first; the curves keep their order within a band."""
    ranges = []
    for g in groups:
        v = np.asarray(data[g[0]], dtype=float)
        v = v[np.isfinite(v)]
        ranges.append((float(v.min()), float(v.max())) if v.size else (0.0, 0.0))
    lo = min((r[0] for r in ranges), default=0.0)
    hi = max((r[1] for r in ranges), default=0.0)
    span = hi - lo
    if len(groups) < 2 or span <= 0:
        return [list(groups)]
    order = sorted(range(len(groups)), key=lambda i: ranges[i][0])
    bands, top = [[order[0]]], ranges[order[0]][1]
    for i in order[1:]:
        start = ranges[i][0]
        if start - top > gap * span or (top > 0 and start > ratio * top):
            bands.append([i])
        else:
            bands[-1].append(i)
        top = max(top, ranges[i][1])
    return [[list(groups[i]) for i in sorted(b)] for b in reversed(bands)]


def y_limits(curves, rel: float = 1e-3):
    """Axis limits that do not blow round-off up: at least ``rel`` of the largest
    magnitude (0.36 degC around 360 degC), centred on the data; None when the data
    span more than that (let the plotting library choose)."""
    vals = np.concatenate([np.asarray(c, dtype=float).ravel() for c in curves] or [[]])
    vals = vals[np.isfinite(vals)]
    if not vals.size:
        return None
    lo, hi = float(vals.min()), float(vals.max())
    min_span = max(rel * float(np.abs(vals).max()), 1e-12)
    if hi - lo >= min_span:
        return None
    mid = (lo + hi) / 2
    return mid - min_span / 2, mid + min_span / 2


def plot_quantities(
    t,
    data: dict,
    names: Sequence[str],
    unit_of: dict[str, str],
    path,
    *,
    units: str = "si",
    events: Sequence[float] = (),
    restarts: Sequence[float] = (),
    title: str | None = None,
    max_lines: int = 10,
) -> Path:
    """The variables ``names``: one panel per quantity and unit (:func:`panels_for`)."""
    panels = panels_for(names, unit_of, data, max_lines=max_lines)
    return plot_panels(
        t, data, panels, path, units=units, events=events, restarts=restarts, title=title
    )


def panel_label(panel: Panel, unit: str) -> str:
    """The axis label of a panel: its heading, quantity and (display) unit."""
    head = f"{panel.title}: " if panel.title else ""
    return f"{head}{panel.quantity} [{axis_unit(panel.quantity, unit)}]"


def _bold(text: str) -> str:
    """``text`` in bold mathtext when it is made of plain characters, else as it is
    (a plant's name may hold anything; mathtext would read $, ^, { as markup)."""
    import re

    if not re.fullmatch(r"[A-Za-z0-9_ .,:()-]+", text):
        return text
    return r"$\bf{" + text.replace("_", r"\_").replace(" ", r"\ ") + "}$"


def plot_panels(
    t,
    data: dict,
    panels: Sequence[Panel],
    path,
    *,
    units: str = "si",
    events: Sequence[float] = (),
    restarts: Sequence[float] = (),
    title: str | None = None,
    subtitle: str = "",
    note: str = "",
) -> Path:
    """Draw ``panels`` (one axis each, sharing the time axis; two columns beyond
    four panels) into the PNG ``path``: title and subtitle on top, the marker
    legend and ``note`` (the constants) at the bottom."""
    from dnasim.run.output import _atomic_write, _pyplot, _time_axis

    plt = _pyplot()
    t = np.asarray(t, dtype=float)
    t_scale, t_label = _time_axis(t)
    n = max(len(panels), 1)
    ncols = 1 if n <= 4 else 2
    nrows = math.ceil(n / ncols)
    width = 11.0 if ncols == 1 else 18.0
    wrap = 150 if ncols == 1 else 250
    foot = [x for x in (note,) if x]
    if events or restarts:
        foot.insert(0, "grey dotted: time events and restarts; red dashed: located switches")
    foot_lines = sum(len(textwrap.wrap(x, wrap)) for x in foot)
    head_h = 0.75 if subtitle else 0.5
    foot_h = 0.2 + 0.18 * foot_lines
    height = 2.35 * nrows + head_h + foot_h + 0.4
    fig, axes = plt.subplots(
        nrows, ncols, sharex=True, figsize=(width, height), squeeze=False, layout="constrained"
    )
    flat = list(axes.T.ravel()) if ncols > 1 else list(axes[:, 0])
    for k, ax in enumerate(flat):
        if k >= len(panels):
            ax.set_visible(False)
            continue
        panel = panels[k]
        shown = "-"
        drawn = []
        mag = magnitude(data[c.names[0]] for c in panel.curves)
        for c in panel.curves:
            v, shown = display(
                c.sign * np.asarray(data[c.names[0]], dtype=float), panel.unit, units, mag
            )
            ax.plot(t / t_scale, v, label=c.label, lw=1.4, ls="--" if c.dashed else "-")
            drawn.append(v)
        if panel.limits is not None:
            lo, hi = (display(np.array(panel.limits), panel.unit, units, mag)[0]).tolist()
            pad = 0.04 * (hi - lo) if hi > lo else 0.05
            dlo = min([lo] + [float(np.nanmin(v)) for v in drawn])
            dhi = max([hi] + [float(np.nanmax(v)) for v in drawn])
            ax.set_ylim(dlo - pad, dhi + pad)
            for y in (lo, hi):
                ax.axhline(y, color="0.6", lw=0.8, ls="-.")
        else:
            lim = y_limits(drawn)
            if lim is not None:
                ax.set_ylim(*lim)
        for te in restarts:
            ax.axvline(te / t_scale, color="0.55", ls=":", lw=0.8)
        for te in events:
            ax.axvline(te / t_scale, color="tab:red", ls="--", lw=0.8)
        ax.set_ylabel(panel_label(panel, shown).replace(": ", ":\n", 1).replace(" [", "\n[", 1))
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, alpha=0.3)
        if panel.curves:
            ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    for ax in axes[-1, :]:
        ax.set_xlabel(t_label)
        ax.xaxis.set_tick_params(labelbottom=True)
    if ncols > 1 and len(panels) % 2 == 1:
        # the shorter column's last panel carries the time labels too
        ax = axes[nrows - 2, 1] if nrows >= 2 else axes[0, 1]
        ax.set_xlabel(t_label)
        ax.xaxis.set_tick_params(labelbottom=True)
    if not panels:
        flat[0].set_visible(True)
        flat[0].text(0.5, 0.5, "nothing changes over the run", ha="center", va="center")
        flat[0].set_axis_off()
    if title:
        fig.suptitle(_bold(title) + (f"\n{subtitle}" if subtitle else ""), fontsize=11)
    if foot:
        fig.supxlabel(
            "\n".join(line for x in foot for line in textwrap.wrap(x, wrap)),
            fontsize=8,
            ha="left",
            x=0.01,
            color="0.25",
        )
    path = Path(path)
    try:
        _atomic_write(
            path, lambda f: fig.savefig(f, dpi=110, format=path.suffix.lstrip(".") or "png")
        )
    finally:
        plt.close(fig)
    return path
