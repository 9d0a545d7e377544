"""Plots for engineers from the files of a run (results.csv, steps.csv, events.csv).

``dnasim run --plot`` and ``dnasim plot`` both call :func:`write_run_plots` on the
files on disk, so they write the same ``variables.png`` and ``steps.png`` with the
same event markers.

- Quantities, not units, make the panels: each variable gets a quantity from its
  unit and name (:func:`quantity_of`): temperature, pressure, mass flow, specific
  enthalpy, power, energy, mass, opening / controller output, control error, ...
  Different quantities never share an axis; each axis is labelled with the
  quantity's name and unit.
- ``units="engineering"`` converts for display (:data:`ENGINEERING`): K -> degC,
  Pa -> bar, kg/s -> t/h, J/kg -> kJ/kg, W -> MW, J -> MJ. The CSV stays SI.
- The default selection (:func:`default_selection`) shows what an engineer looks
  at first: component outlet and sensor temperatures (node temperatures too, but
  curves that coincide on the plot are drawn once, their names joined with "="),
  controller outputs, errors, set points and limits (``*.setpoint``, ``*.z_max``,
  ``*.z_min`` when the results hold them), and the flows at the boundaries.
- Discontinuities are marked: grey dotted lines at the rows flagged ``restart``
  (time events and switches), red dashed lines at the located switches of
  ``events.csv``.

matplotlib is imported inside the functions (Agg backend).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

__all__ = [
    "ENGINEERING",
    "QUANTITY_ORDER",
    "quantity_of",
    "display",
    "default_selection",
    "merge_identical",
    "read_run",
    "write_run_plots",
    "plot_quantities",
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

#: panel order, top to bottom
QUANTITY_ORDER = (
    "temperature",
    "set point",
    "pressure",
    "mass flow",
    "specific enthalpy",
    "power",
    "controller output",
    "control error",
    "energy",
    "mass",
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
}
_SIGNAL_LEAVES = {
    "z": "controller output",
    "z_max": "controller output",
    "z_min": "controller output",
    "opening": "controller output",
    "m_p": "controller parts",
    "m_I": "controller parts",
    "e": "control error",
    "setpoint": "set point",
}
#: columns that are flags, never plotted
NOT_PLOTTED = ("restart",)


def _leaf(name: str) -> str:
    leaf = name.rsplit(".", 1)[-1]
    return leaf.split("[", 1)[0]


def quantity_of(name: str, unit: str) -> str:
    """The physical quantity of a results column (its panel)."""
    unit = unit or "-"
    if unit in ("-", "1"):
        return _SIGNAL_LEAVES.get(_leaf(name), "dimensionless")
    if _leaf(name) == "setpoint":
        return "temperature" if unit == "K" else "set point"
    if _leaf(name) == "e":
        return "control error"
    return _BY_UNIT.get(unit, unit)


def display(values, unit: str, units: str = "si"):
    """(values, unit) for display: SI, or engineering units (:data:`ENGINEERING`)."""
    unit = unit or "-"
    if units == "engineering" and unit in ENGINEERING:
        u, scale, offset = ENGINEERING[unit]
        return np.asarray(values, dtype=float) * scale + offset, u
    return np.asarray(values, dtype=float), ("-" if unit == "1" else unit)


def _components(names: Sequence[str]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for n in names:
        if "." in n:
            c, v = n.split(".", 1)
            out.setdefault(c, set()).add(v.split("[", 1)[0])
    return out


def default_selection(names: Sequence[str], units: dict[str, str]) -> list[str]:
    """The interesting columns of a results table (see the module docstring)."""
    comps = _components(names)
    nodes = {c for c, v in comps.items() if v <= {"p", "h", "T"} and {"p", "h"} <= v}
    boundaries = {c for c, v in comps.items() if "M_passed" in v}
    controllers = {c for c, v in comps.items() if {"e", "z", "m_I"} <= v}
    chosen = []
    for n in names:
        if "." not in n or _leaf(n) in NOT_PLOTTED or "[" in n:
            continue
        comp, leaf = n.split(".", 1)
        unit = units.get(n, "")
        if unit == "K" and (leaf in ("T_out", "T_s", "T") or leaf == "setpoint"):
            chosen.append(n)  # outlet, sensor, component and node temperatures
        elif comp in controllers and leaf in ("z", "e", "setpoint", "z_max", "z_min"):
            chosen.append(n)
        elif comp in boundaries and leaf == "m":
            chosen.append(n)
    # component temperatures before node temperatures: the merged legend names
    # the component first
    chosen.sort(key=lambda n: n.split(".", 1)[0] in nodes)
    return chosen


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
    from dnasim.output import read_results_csv

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
    from dnasim.output import plot_steps, select_variables

    path = Path(results_csv)
    names, unit_of, data, steps, events, restarts = read_run(path)
    variables = [n for n in names[1:] if n not in NOT_PLOTTED]
    if patterns:
        chosen = select_variables(variables, patterns)
        if not chosen:
            raise ValueError(f"no variable matches {' '.join(patterns)}")
    else:
        chosen = default_selection(variables, unit_of) or variables[:8]
    target = Path(variables_path) if variables_path else path.with_name("variables.png")
    files = [
        plot_quantities(
            data["time"],
            data,
            chosen,
            unit_of,
            target,
            units=units,
            events=events,
            restarts=restarts,
            title=f"{path.parent.name}/{path.name}",
        )
    ]
    if steps and (steps_path is not None or variables_path is None):
        target2 = Path(steps_path) if steps_path else path.with_name("steps.png")
        files.append(plot_steps(steps, target2, event_times=events))
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


#: quantities whose curves are split into bands that do not overlap
BANDED = ("temperature", "pressure", "specific enthalpy")


def split_bands(groups: Sequence[Sequence[str]], data: dict, gap: float = 0.2) -> list[list]:
    """Curves (groups of coinciding names, drawn once) of one quantity in bands that
    do not overlap: a new band starts where the gap between the ranges of
    consecutive curves (sorted by their minimum) is more than ``gap`` of the whole
    span (a 200 degC water line does not squeeze a 440 degC control loop into a
    few pixels). Highest band first; the curves keep their order within a band."""
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
        if ranges[i][0] - top > gap * span:
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


def _panels(names, unit_of, data, units=None):
    """(quantity, [group, ...]) per panel, a group being the names of coinciding
    curves (:func:`merge_identical`, over the whole quantity); quantities in
    :data:`QUANTITY_ORDER`, temperatures and pressures split into bands
    (:func:`split_bands`)."""
    panels: dict[str, list[str]] = {}
    for n in names:
        panels.setdefault(quantity_of(n, unit_of.get(n, "")), []).append(n)
    order = {q: i for i, q in enumerate(QUANTITY_ORDER)}
    out = []
    for q, group in sorted(panels.items(), key=lambda kv: order.get(kv[0], len(order))):
        merged = merge_identical(None, {n: np.asarray(data[n], dtype=float) for n in group})
        bands = split_bands(merged, data) if q in BANDED else [merged]
        out.extend((q, band) for band in bands)
    return out


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
    """One panel per quantity, curves that coincide drawn once, event markers."""
    from dnasim.output import _atomic_write, _pyplot, _time_axis

    plt = _pyplot()
    t = np.asarray(t, dtype=float)
    panels = []
    for q, merged in _panels(names, unit_of, data, units):
        series = {}
        shown_unit = None
        for g in merged:
            v, u = display(data[g[0]], unit_of.get(g[0], ""), units)
            series[g[0]] = v
            shown_unit = shown_unit or u
        for i in range(0, len(merged), max_lines):
            panels.append((q, shown_unit, merged[i : i + max_lines], series))
    if not panels:
        panels = [("", "-", [], {})]
    t_scale, t_label = _time_axis(t)
    fig, axes = plt.subplots(
        len(panels), 1, sharex=True, figsize=(10, 2.5 * len(panels) + 1.0), squeeze=False
    )
    for ax, (q, u, groups, series) in zip(axes[:, 0], panels, strict=True):
        comps = _components(list(data))
        for g in groups:
            dashed = _leaf(g[0]) in ("setpoint", "z_max", "z_min")
            label = curve_label(g, comps)
            ax.plot(t / t_scale, series[g[0]], label=label, lw=1.3, ls="--" if dashed else "-")
        for te in restarts:
            ax.axvline(te / t_scale, color="0.55", ls=":", lw=0.8)
        for te in events:
            ax.axvline(te / t_scale, color="tab:red", ls="--", lw=0.8)
        ax.set_ylabel(f"{q}\n[{axis_unit(q, u)}]")
        ax.ticklabel_format(axis="y", useOffset=False)
        lim = y_limits([series[g[0]] for g in groups])
        if lim is not None:
            ax.set_ylim(*lim)
        ax.grid(True, alpha=0.3)
        if groups:
            ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.01, 0.5))
    axes[-1, 0].set_xlabel(t_label)
    note = (
        "dotted grey: time events and restarts; dashed red: located switches"
        if events or restarts
        else ""
    )
    if title or note:
        fig.suptitle("\n".join(x for x in (title, note) if x), fontsize=9)
    fig.tight_layout()
    path = Path(path)
    try:
        _atomic_write(
            path, lambda f: fig.savefig(f, dpi=110, format=path.suffix.lstrip(".") or "png")
        )
    finally:
        plt.close(fig)
    return path
