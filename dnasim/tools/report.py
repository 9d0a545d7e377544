"""``report.html`` of a run: a page to explore the results, offline.

Contents, from the files the run wrote and the plant:

- the run in one line: plant, file, status, end time, steps, events, wall time;
- the plant schematic (:mod:`dnasim.tools.schematic`): an SVG drawn from the network
  graph, components by type, nodes, fluid lines by medium, signal links dashed;
  hovering a symbol shows the final value, minimum and maximum of its
  variables, clicking it lists them beside the drawing and selects them in the
  variable browser; the values of the main quantities are written under the
  symbols;
- the variable browser: every column of ``results.csv``, grouped by component
  (or node) or by quantity and unit, with a search box (words, or shell
  patterns like ``*.T_out``; Enter plots the first match); a click plots a
  variable; a plot takes two units at most (left and right axis), a variable of
  a third unit opens the next plot;
- the main variables: the panels of ``variables.png`` (:func:`dnasim.tools.plots.select_panels`),
  interactive, with the constants listed;
- the event table (the seed's Table 10.1), collapsed when long, under a summary
  line: the number of located switches and how often each switch fired;
- step size and order over time (the seed's Fig. 10.7);
- solver statistics and the plant's structure (equations, unknowns, components,
  nodes, links).

The page holds its data (each column as base64 float32 differences from its
first value, constants as one number; rows are thinned beyond
:data:`MAX_VALUES` values, the restarts kept) and its own script; plotly is the
file ``plotly.min.js`` beside it (:func:`write_plotly_js`: written once per
folder, left alone when already there and identical), referenced by a relative
path, so the page works offline and from a copied folder. Nothing is fetched
from the network: no CDN, no web font, no stylesheet link.

Every string from the plant (names, description, path, event rows) is escaped:
in HTML with ``html.escape``, in the embedded JSON with ``<``, ``>``, ``&``
written as ``\\u003c`` ..., and the script builds the page with ``textContent``
only, so no plant file can put markup or script into the page.
"""

from __future__ import annotations

import base64
import csv
import hashlib
import html
import json
import math
from importlib import resources
from pathlib import Path

import numpy as np

__all__ = [
    "MAX_VALUES",
    "PLOTLY_JS",
    "write_report",
    "write_plotly_js",
    "plant_structure",
    "render_report",
    "report_data",
    "event_summary",
]

#: values of the results table embedded in the page at most (about 5.3 bytes each);
#: beyond it, rows are thinned (restarts and the last row kept)
MAX_VALUES = 1_500_000
#: the plotting library's file beside report.html
PLOTLY_JS = "plotly.min.js"
#: an event table longer than this is collapsed under its summary line
EVENTS_OPEN_MAX = 20


# --------------------------------------------------------------------------- adapters


def plant_structure(loaded) -> dict:
    """Components, nodes, links and counts of a ``LoadedPlant`` (or a ``Plant``)."""
    plant = getattr(loaded, "plant", loaded)
    dae = plant.compile()
    comps = []
    for name, comp in plant.components.items():
        ports = {p: node for (c, p), node in plant.connections.items() if c == name}
        inputs = {i: f"{s}.{o}" for (c, i), (s, o) in plant.links.items() if c == name}
        comps.append({"name": name, "type": type(comp).__name__, "ports": ports, "inputs": inputs})
    n_diff = int(np.count_nonzero(~dae.algebraic))
    return {
        "name": plant.name,
        "components": comps,
        "nodes": list(plant.node_names()),
        "links": [f"{s}.{o} -> {c}.{i}" for (c, i), (s, o) in plant.links.items()],
        "n_equations": int(dae.n_equations),
        "n_unknowns": int(dae.n),
        "n_differential": n_diff,
        "n_algebraic": int(dae.n) - n_diff,
        "n_switches": len(dae.events),
        "system": dae,
    }


def _description(loaded) -> str:
    spec = getattr(loaded, "spec", None)
    for obj in (spec, getattr(spec, "plant", None)):
        d = getattr(obj, "description", None)
        if isinstance(d, str) and d:
            return d
    return ""


# --------------------------------------------------------------------------- data


def _b64(arr, dtype: str) -> str:
    """Little-endian ``dtype`` ("float32", "float64") bytes of ``arr``, base64."""
    le = {"float32": "<f4", "float64": "<f8"}[dtype]
    return base64.b64encode(np.ascontiguousarray(arr, dtype=le).tobytes()).decode("ascii")


def _num(x):
    """A float for JSON (None for NaN and infinities)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _rows_kept(t, restart, limit_rows: int) -> np.ndarray:
    """Indices of the rows embedded: all when they fit, else every k-th row, the
    first and last, and both sides of every restart."""
    n = len(t)
    if n <= limit_rows:
        return np.arange(n)
    step = math.ceil(n / max(limit_rows, 2))
    keep = set(range(0, n, step)) | {0, n - 1}
    if restart is not None:
        for i in np.flatnonzero(np.asarray(restart) == 1):
            keep.update((max(i - 1, 0), int(i)))
    return np.array(sorted(keep))


def _series(values) -> dict:
    """One column for the page: a constant as ``{"c": v}``, else ``{"b": first,
    "d": base64 float32 of v - first}`` (the differences keep seven digits of the
    variation, not of the magnitude: 0.01 Pa of a 100 bar curve)."""
    v = np.asarray(values, dtype=float)
    finite = v[np.isfinite(v)]
    if finite.size == v.size and (v.size == 0 or float(finite.max()) == float(finite.min())):
        return {"c": _num(finite[0]) if finite.size else None}
    base = float(finite[0]) if finite.size else 0.0
    return {"b": base, "d": _b64(v - base, "float32")}


def _stats(values) -> dict:
    v = np.asarray(values, dtype=float)
    f = v[np.isfinite(v)]
    if not f.size:
        return {"first": None, "final": None, "min": None, "max": None}
    return {
        "first": _num(f[0]),
        "final": _num(f[-1]),
        "min": _num(f.min()),
        "max": _num(f.max()),
    }


def report_data(results_csv, plant: dict | None, *, units: str = "si") -> dict:
    """The data the page's script works on (JSON-ready): time, every variable with
    its unit, quantity, group, statistics and values, the default panels, the
    constants, events, restarts and steps. ``plant``: the description of
    :mod:`dnasim.plant.plantinfo` (None: the groups follow the names)."""
    from dnasim.tools.plots import (
        CONSTANT_ATOL,
        ENGINEERING,
        ENGINEERING_SMALL,
        NOT_PLOTTED,
        quantity_of,
        read_run,
        select_panels,
    )

    names, unit_of, data, steps, events, restarts = read_run(results_csv)
    t = np.asarray(data["time"], dtype=float)
    variables = [n for n in names[1:] if n not in NOT_PLOTTED]
    limit_rows = max(MAX_VALUES // max(len(variables), 1), 200)
    rows = _rows_kept(t, data.get("restart"), limit_rows)
    comps = {c["name"]: c for c in (plant or {}).get("components", ())}
    nodes = set((plant or {}).get("nodes", ()))
    out_vars = []
    for n in variables:
        owner = n.split(".", 1)[0] if "." in n else ""
        unit = unit_of.get(n, "") or "-"
        kind = "node" if owner in nodes else ("component" if owner in comps else "")
        out_vars.append(
            {
                "name": n,
                "unit": "-" if unit == "1" else unit,
                "quantity": quantity_of(n, unit),
                "owner": owner,
                "kind": kind,
                **_stats(data[n]),
                "data": _series(np.asarray(data[n], dtype=float)[rows]),
            }
        )
    panels, constants = select_panels(variables, unit_of, data, plant)
    step_arr = np.array(steps, dtype=float).reshape(-1, 3)
    return {
        "plant": {
            "name": (plant or {}).get("name", ""),
            "description": (plant or {}).get("description", ""),
        },
        "units": units,
        "engineering": {k: list(v) for k, v in ENGINEERING.items()},
        "engineering_small": {k: list(v) for k, v in ENGINEERING_SMALL.items()},
        "zero": dict(CONSTANT_ATOL),
        "time": _b64(t[rows], "float64"),
        "rows": {"shown": int(len(rows)), "of": int(len(t))},
        "vars": out_vars,
        "components": {
            name: {"type": c.get("type", ""), "kind": _kind(c.get("type", ""))}
            for name, c in comps.items()
        },
        "nodes": sorted(nodes),
        "panels": [
            {
                "title": p.title,
                "quantity": p.quantity,
                "unit": p.unit,
                "limits": list(p.limits) if p.limits else None,
                "curves": [
                    {"name": c.names[0], "label": c.label, "sign": c.sign, "dashed": c.dashed}
                    for c in p.curves
                ],
            }
            for p in panels
        ],
        "constants": [{"name": n, "value": _num(v), "unit": u} for n, v, u in constants],
        "events": [float(x) for x in events],
        "restarts": [float(x) for x in restarts],
        "steps": {
            "t": _b64(step_arr[:, 0], "float64"),
            "h": _b64(step_arr[:, 1], "float64"),
            "order": _b64(step_arr[:, 2], "float32"),
        },
    }


def _kind(type_name: str) -> str:
    from dnasim.tools.schematic import symbol_kind

    return symbol_kind(type_name)


def _json_for_script(obj) -> str:
    """JSON that is safe inside ``<script type="application/json">``: no ``<``,
    ``>`` or ``&`` (no ``</script>``, no ``<!--``), no line separators."""
    text = json.dumps(obj, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
    for a, b in (("<", "\\u003c"), (">", "\\u003e"), ("&", "\\u0026")):
        text = text.replace(a, b)
    return text.replace("\u2028", "\\u2028").replace("\u2029", "\\u2029")


# --------------------------------------------------------------------------- events


def _read_events(path: Path) -> tuple[list[str], list[list[str]]]:
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rdr = csv.reader(f)
            header = next(rdr, None) or []
            return header, [r for r in rdr if r]
    except OSError:
        return [], []


def event_summary(header, rows) -> tuple[int, list[tuple[str, int]]]:
    """(number of located switches, [(switch "component: name", times it fired)])
    of the rows of ``events.csv`` (one row per iterate of each location); the
    elements of a vector switch count together ("cold_h_v[i] saturated liquid")."""
    import re

    col = {h: i for i, h in enumerate(header)}
    if "event" not in col:
        return 0, []
    seen, counts = set(), {}
    for r in rows:
        ev = r[col["event"]]
        if ev in seen:
            continue
        seen.add(ev)
        comp = r[col["component"]] if "component" in col else ""
        sw = re.sub(r"\[\d+\]", "[i]", r[col["switch"]]) if "switch" in col else ""
        key = f"{comp}: {sw}" if comp else sw
        counts[key] = counts.get(key, 0) + 1
    return len(seen), sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))


# --------------------------------------------------------------------------- html

_STAT_NAMES = {
    "steps": "accepted steps",
    "rejected_error": "steps rejected by the error test",
    "rejected_newton": "steps rejected by Newton failure",
    "residual_evals": "residual evaluations",
    "jac_evals": "Jacobian evaluations",
    "lu_decomps": "LU factorisations",
    "newton_iters": "Newton iterations",
}


def _asset(name: str) -> str:
    return (
        resources.files("dnasim.tools").joinpath("report_assets", name).read_text(encoding="utf-8")
    )


def _table(header, rows, num_cols=(), cls="") -> str:
    c = f' class="{cls}"' if cls else ""
    out = [f"<table{c}><tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) + "</tr>"]
    for r in rows:
        cells = []
        for j, v in enumerate(r):
            klass = ' class="num"' if j in num_cols else ""
            cells.append(f"<td{klass}>{html.escape(str(v))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _fmt(x) -> str:
    if isinstance(x, float):
        return "" if math.isnan(x) else f"{x:.10g}"
    return str(x)


def _boundary_flows(data_vars, plant) -> dict:
    """Mean flow [kg/s] of each boundary over the run (its direction in the drawing)."""
    out = {}
    byname = {v["name"]: v for v in data_vars}
    for c in (plant or {}).get("components", ()):
        if c.get("supply") is None:
            continue
        v = byname.get(f"{c['name']}.m")
        if v is not None and v["final"] is not None and v["first"] is not None:
            out[c["name"]] = (v["final"] + v["first"]) / 2 or v["max"] or 0.0
    return out


def render_report(outcome, loaded, out_dir, *, units: str = "si") -> str:
    """The HTML text of the report (see the module docstring)."""
    from dnasim.plant.plantinfo import describe_loaded, read_plant_json
    from dnasim.tools.schematic import schematic_svg

    out = Path(out_dir)
    results = out / "results.csv"
    st = plant_structure(loaded)
    plant = read_plant_json(out) or describe_loaded(loaded, st["system"])
    desc = _description(loaded) or plant.get("description", "")
    data = report_data(results, plant, units=units)
    unit_of = {v["name"]: ("1" if v["unit"] == "-" else v["unit"]) for v in data["vars"]}
    svg = schematic_svg(plant, _boundary_flows(data["vars"], plant), unit_of)
    stats = dict(outcome.stats or {})
    status_cls = "ok" if outcome.success else "bad"
    name = html.escape(st["name"])
    ev_header, ev_rows = _read_events(out / "events.csv")
    n_events, per_switch = event_summary(ev_header, ev_rows)

    facts = [
        ("status", outcome.status),
        ("t reached", f"{_fmt(outcome.t_reached)} s of {_fmt(outcome.t_end)} s"),
        ("rows", f"{outcome.rows}"),
        ("steps", f"{outcome.n_steps}"),
        ("events", f"{n_events}"),
        ("unknowns", f"{st['n_unknowns']} ({st['n_differential']} states)"),
        ("wall time", f"{outcome.wall_time:.2f} s"),
    ]
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<meta name='viewport' content='width=device-width, initial-scale=1'>",
        f"<title>{name}: dnasim report</title>",
        f"<style>{_asset('report.css')}</style></head><body>",
        "<header class='top'>",
        f"<div class='title'><span class='plant'>{name}</span>"
        + (f"<span class='desc'>{html.escape(desc)}</span>" if desc else "")
        + "</div>",
        "<nav><a href='#plant'>Plant</a><a href='#browser'>Variables</a>"
        "<a href='#main'>Main plots</a><a href='#events'>Events</a>"
        "<a href='#solver'>Solver</a><a href='#structure'>Structure</a></nav>",
        "<div class='unitswitch' role='group' aria-label='units'>"
        "<button type='button' data-units='si'>SI</button>"
        "<button type='button' data-units='engineering'>engineering</button></div>",
        "</header><main>",
        "<div id='noplotly' class='warn' hidden>plotly.min.js was not found beside this "
        "file: the plots cannot be drawn (the schematic, the variable list and the tables "
        "work). Copy the whole results folder, not report.html alone.</div>",
        "<div class='facts'>"
        + "".join(
            f"<div class='fact{' ' + status_cls if k == 'status' else ''}'><span>{html.escape(k)}"
            f"</span><b>{html.escape(v)}</b></div>"
            for k, v in facts
        )
        + "</div>",
        "<p class='muted'>Plant file <code>"
        + html.escape(str(getattr(loaded, "path", "")))
        + "</code>; results in <code>"
        + html.escape(str(out))
        + "</code>"
        + (f". {html.escape(outcome.message)}" if outcome.message else "")
        + "</p>",
        _warnings_html(getattr(outcome, "warnings", None)),
        # ---- plant
        "<section id='plant'><h2>Plant</h2>",
        "<div class='plantwrap'><div class='svgbox'>",
        svg,
        "</div><aside id='card' class='card'><p class='muted'>Point at a component or a "
        "node for its values; click it to list its variables here and in the variable "
        "browser.</p></aside></div>",
        "<div class='legend'><span class='lg water'>water / steam</span>"
        "<span class='lg gas'>gas</span><span class='lg other'>other fluid</span>"
        "<span class='lg signal'>signal</span><span class='lg tap'>instrument tap</span>"
        "<label><input type='checkbox' id='shownodes' checked> node names</label>"
        "<label><input type='checkbox' id='showvalues' checked> final values</label></div>",
        "</section>",
        # ---- browser
        "<section id='browser'><h2>Variables</h2>",
        "<div class='browser'><aside class='varlist'>",
        "<div class='controls'><input id='search' type='search' autocomplete='off' "
        "placeholder='Search: drum level, *.T_out, bar, Valve … (Enter plots the first)'>",
        "<div class='seg' role='group' aria-label='group by'>group by "
        "<button type='button' data-group='component' class='on'>component</button>"
        "<button type='button' data-group='quantity'>quantity</button></div>",
        "<div id='count' class='muted'></div></div>",
        "<div id='tree' class='tree'></div></aside>",
        "<div class='plots'><div class='plotbar'>"
        "<button type='button' id='newplot'>+ new plot</button>"
        "<button type='button' id='clearplots'>clear</button>"
        "<span class='muted'>A click on a variable adds it to the active plot (two units at "
        "most, left and right axis; a third unit opens a new plot). Drag to zoom, double-click "
        "to reset.</span></div><div id='plotstack'></div></div></div>",
        "</section>",
        # ---- main plots
        "<section id='main'><h2>Main variables</h2>",
        "<p class='muted'>Chosen by quantity, one unit per axis; grey dotted: time events "
        "and restarts; red dashed: located switches. Coinciding curves are drawn once, their "
        "names joined by '='.</p>",
        "<div id='panels' class='panels'></div><p id='constants' class='muted'></p></section>",
    ]
    # ---- events
    parts.append("<section id='events'><h2>Events</h2>")
    if ev_rows:
        summary = f"{n_events} located switch{'es' if n_events != 1 else ''}"
        if per_switch:
            summary += ": " + ", ".join(f"{k} × {v}" for k, v in per_switch)
        summary += f" ({len(ev_rows)} rows of iterates)"
        opened = " open" if len(ev_rows) <= EVENTS_OPEN_MAX else ""
        parts.append(
            f"<details class='events'{opened}><summary>{html.escape(summary)}</summary>"
            "<p class='muted'>The location of the switching points (the seed's Table 10.1): "
            "iteration 1 is the last accepted step before the sign change, 2 the step that "
            "detected it, then the refinements; the last iterate is the switching time.</p>"
        )
        parts.append(
            _table(
                [{"time": "time [s]"}.get(h, h) for h in ev_header],
                [
                    [_fmt(float(v)) if j in (2, 3) and _isfloat(v) else v for j, v in enumerate(r)]
                    for r in ev_rows
                ],
                num_cols=(0, 1, 2, 3),
            )
        )
        parts.append("</details>")
    else:
        parts.append("<p>No switch changed its state during the run.</p>")
    parts.append("</section>")
    # ---- solver
    parts.append("<section id='solver'><h2>Solver</h2>")
    parts.append("<div id='steps' class='stepsplot'></div>")
    parts.append("<p class='muted'>Step size and order over time (the seed's Fig. 10.7).</p>")
    sim = getattr(loaded, "simulation", None)
    run_rows = [
        ("end time reached [s]", _fmt(outcome.t_reached)),
        ("end time [s]", _fmt(outcome.t_end)),
        ("rows in results.csv", outcome.rows),
        ("accepted steps", outcome.n_steps),
        ("located switches (events)", outcome.n_events),
        ("wall time [s]", f"{outcome.wall_time:.3f}"),
    ]
    if sim is not None:
        for k in ("rtol", "atol_scaled", "max_order", "output_interval", "start"):
            if hasattr(sim, k):
                v = getattr(sim, k)
                if k == "output_interval" and getattr(sim, "t_eval", None) is not None:
                    te = sim.t_eval  # the rows are exactly these times
                    k, v = "t_eval [s]", f"{len(te)} times, {te[0]:g} to {te[-1]:g}"
                elif k == "output_interval":
                    k, v = "output_interval [s]", "every accepted step" if v is None else v
                run_rows.append((k, _fmt(v)))
    parts.append("<div class='grid'>")
    parts.append(_table(("run", "value"), run_rows, num_cols=(1,)))
    parts.append(
        _table(
            ("solver statistic", "count"),
            [(_STAT_NAMES.get(k, k), v) for k, v in stats.items()],
            num_cols=(1,),
        )
        if stats
        else "<p>no solver statistics</p>"
    )
    parts.append("</div></section>")
    # ---- structure
    parts.append("<section id='structure'><h2>Structure</h2><div class='grid'>")
    parts.append(
        _table(
            ("equations", "unknowns", "differential states", "algebraic", "switches"),
            [
                (
                    st["n_equations"],
                    st["n_unknowns"],
                    st["n_differential"],
                    st["n_algebraic"],
                    st["n_switches"],
                )
            ],
            num_cols=(0, 1, 2, 3, 4),
        )
    )
    parts.append("</div><details><summary>components, nodes and signal links</summary>")
    parts.append(
        _table(
            ("component", "type", "fluid ports -> nodes", "signal inputs"),
            [
                (
                    c["name"],
                    c["type"],
                    ", ".join(f"{p} -> {n}" for p, n in c["ports"].items()),
                    ", ".join(f"{i} <- {s}" for i, s in c["inputs"].items()),
                )
                for c in st["components"]
            ],
        )
    )
    parts.append(
        f"<p>Nodes ({len(st['nodes'])}): {html.escape(', '.join(st['nodes']))}<br>"
        f"Signal links ({len(st['links'])}): {html.escape('; '.join(st['links']) or 'none')}</p>"
        "</details></section>"
    )
    parts.append(
        "</main><footer class='muted'>Written by dnasim. Works offline: the data and the "
        f"script are in this page, the plotting library is {PLOTLY_JS} beside it.</footer>"
    )
    parts.append(
        f"<script type='application/json' id='dnasim-data'>{_json_for_script(data)}</script>"
    )
    parts.append(f"<script src='{PLOTLY_JS}'></script>")
    parts.append(f"<script>{_asset('report.js')}</script>")
    parts.append("</body></html>")
    return "\n".join(p for p in parts if p)


def _isfloat(v) -> bool:
    try:
        float(v)
    except (TypeError, ValueError):
        return False
    return True


def _plotly_source() -> bytes:
    try:
        files = resources.files("plotly")
    except ModuleNotFoundError:
        raise ImportError(
            "report.html needs plotly, an optional dependency: pip install 'dnasim[report]'"
        ) from None
    return files.joinpath("package_data", PLOTLY_JS).read_bytes()


def write_plotly_js(out_dir) -> tuple[Path, bool]:
    """``plotly.min.js`` beside the report: written when missing or different
    (another plotly version), left alone when already there and identical (one
    copy per folder, shared by the reports in it). Returns (path, written)."""
    from dnasim.run.output import _atomic_write

    path = Path(out_dir) / PLOTLY_JS
    src = _plotly_source()
    try:
        if path.is_file() and not path.is_symlink() and path.stat().st_size == len(src):
            if hashlib.sha256(path.read_bytes()).digest() == hashlib.sha256(src).digest():
                return path, False
    except OSError:
        pass
    _atomic_write(path, lambda f: f.write(src))
    return path, True


def write_report(outcome, loaded, out_dir, *, units: str = "si") -> Path:
    """Write ``report.html`` into ``out_dir`` (atomically), and ``plotly.min.js``
    beside it when it is not there yet (:func:`write_plotly_js`); returns the
    report's path."""
    from dnasim.run.output import _atomic_write

    text = render_report(outcome, loaded, out_dir, units=units)
    write_plotly_js(out_dir)
    path = Path(out_dir) / "report.html"
    _atomic_write(path, lambda f: f.write(text.encode("utf-8")))
    return path


def _warnings_html(warnings) -> str:
    """The components' warnings of the run (a cavitating pump), or nothing."""
    if not warnings:
        return ""
    return (
        "<div class='warn'><b>Warnings</b><ul>"
        + "".join(f"<li>{html.escape(str(w))}</li>" for w in warnings)
        + "</ul></div>"
    )
