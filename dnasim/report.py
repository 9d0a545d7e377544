"""``report.html`` of a run: one self-contained page that works offline.

Contents, from the files the run wrote and the plant:

- the run: plant, file, status, end time, solver statistics (steps, rejections,
  residual evaluations, Jacobians, LU factorisations, events, wall time);
- the plant's structure: components (type, ports -> nodes, signal inputs),
  nodes, signal links; equations, unknowns, differential states, algebraic variables;
- interactive plots (plotly, its JavaScript embedded in the page) of the main
  variables, one figure per quantity (:mod:`dnasim.plots` chooses and groups them,
  ``units="engineering"`` converts), with the discontinuities marked;
- the event table with the iterates of each location (the seed's Table 10.1);
- step size and order over time (the seed's Fig. 10.7).

Nothing is fetched from the network: no CDN script, no web font, no stylesheet link.
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

__all__ = ["write_report", "plant_structure", "render_report"]


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
    }


def _description(loaded) -> str:
    spec = getattr(loaded, "spec", None)
    for obj in (spec, getattr(spec, "plant", None)):
        d = getattr(obj, "description", None)
        if isinstance(d, str) and d:
            return d
    return ""


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

_CSS = """
body { font-family: sans-serif; margin: 1.5em 2em; color: #222; max-width: 1300px; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; } h2 { font-size: 1.2em; margin-top: 1.6em;
border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; font-size: 0.9em; margin: 0.5em 0; }
th, td { border: 1px solid #ccc; padding: 2px 8px; text-align: left; vertical-align: top; }
th { background: #eee; } td.num { text-align: right; font-family: monospace; }
.ok { color: #070; font-weight: bold; } .bad { color: #b00; font-weight: bold; }
.grid { display: flex; gap: 2em; flex-wrap: wrap; } .muted { color: #666; font-size: 0.9em; }
"""


def _table(header, rows, num_cols=()) -> str:
    out = ["<table><tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in header) + "</tr>"]
    for r in rows:
        cells = []
        for j, v in enumerate(r):
            cls = ' class="num"' if j in num_cols else ""
            cells.append(f"<td{cls}>{html.escape(str(v))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def _fmt(x) -> str:
    if isinstance(x, float):
        return "" if math.isnan(x) else f"{x:.10g}"
    return str(x)


def _figures(results_csv, units: str) -> list:
    """Plotly figures: one per quantity of the default selection, then steps."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    from dnasim.output import _time_axis
    from dnasim.plots import (
        NOT_PLOTTED,
        _components,
        _panels,
        axis_unit,
        curve_label,
        default_selection,
        display,
        read_run,
        y_limits,
    )

    names, unit_of, data, steps, events, restarts = read_run(results_csv)
    variables = [n for n in names[1:] if n not in NOT_PLOTTED]
    chosen = default_selection(variables, unit_of) or variables[:8]
    scale, t_label = _time_axis(data["time"])
    t = data["time"] / scale
    comps = _components(list(data))
    figs = []
    layout = {
        "margin": {"l": 70, "r": 20, "t": 40, "b": 40},
        "legend": {
            "orientation": "h",
            "y": 1.02,
            "yanchor": "bottom",
            "x": 0,
            "font": {"size": 11},
        },
    }

    def markers(fig, rows=None):
        for te in restarts:
            fig.add_vline(x=te / scale, line_dash="dot", line_color="#999", line_width=1)
        for te in events:
            fig.add_vline(x=te / scale, line_dash="dash", line_color="#d62728", line_width=1)

    for q, merged in _panels(chosen, unit_of, data, units):
        series, shown = {}, "-"
        for g in merged:
            series[g[0]], shown = display(data[g[0]], unit_of.get(g[0], ""), units)
        fig = go.Figure()
        for g in merged:
            fig.add_trace(go.Scatter(x=t, y=series[g[0]], mode="lines", name=curve_label(g, comps)))
        markers(fig)
        lim = y_limits([series[g[0]] for g in merged])
        if lim is not None:
            fig.update_yaxes(range=list(lim))
        fig.update_layout(
            xaxis_title=t_label,
            yaxis_title=f"{q} [{axis_unit(q, shown)}]",
            height=380,
            showlegend=True,  # also for one curve: its name
            **layout,
        )
        figs.append(fig)
    if steps:
        arr = np.array(steps, dtype=float)
        fig = make_subplots(rows=2, cols=1, shared_xaxes=True, vertical_spacing=0.06)
        fig.add_trace(
            go.Scatter(
                x=arr[:, 0] / scale,
                y=arr[:, 1],
                mode="lines+markers",
                marker_size=3,
                name="step size [s]",
            ),
            row=1,
            col=1,
        )
        fig.add_trace(
            go.Scatter(
                x=arr[:, 0] / scale, y=arr[:, 2], mode="lines", line_shape="hv", name="order"
            ),
            row=2,
            col=1,
        )
        fig.update_yaxes(type="log", title_text="step size [s]", row=1, col=1)
        fig.update_yaxes(title_text="order", dtick=1, row=2, col=1)
        fig.update_xaxes(title_text=t_label, row=2, col=1)
        markers(fig)
        fig.update_layout(height=520, showlegend=False, margin=layout["margin"])
        figs.append(fig)
    return figs


def render_report(outcome, loaded, out_dir, *, units: str = "si") -> str:
    """The HTML text of the report (see the module docstring)."""
    import csv

    out = Path(out_dir)
    results = out / "results.csv"
    st = plant_structure(loaded)
    desc = _description(loaded)
    stats = dict(outcome.stats or {})
    status_cls = "ok" if outcome.success else "bad"
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        f"<title>dnasim report: {html.escape(st['name'])}</title>",
        f"<style>{_CSS}</style></head><body>",
        f"<h1>{html.escape(st['name'])}</h1>",
        f"<div class='muted'>{html.escape(desc)}</div>" if desc else "",
        f"<p>Plant file <code>{html.escape(str(getattr(loaded, 'path', '')))}</code>; "
        f"results in <code>{html.escape(str(out))}</code>. Status: "
        f"<span class='{status_cls}'>{html.escape(outcome.status)}</span>"
        + (f" ({html.escape(outcome.message)})" if outcome.message else "")
        + "</p>",
    ]
    warnings = list(getattr(outcome, "warnings", []) or [])
    if warnings:  # the components' warnings of the run (a cavitating pump)
        parts.append(
            "<p class='bad'>Warnings:</p><ul>"
            + "".join(f"<li>{html.escape(w)}</li>" for w in warnings)
            + "</ul>"
        )
    parts += [
        "<h2>Run and solver statistics</h2><div class='grid'>",
    ]
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
                if k == "output_interval":
                    k, v = "output_interval [s]", "every accepted step" if v is None else v
                run_rows.append((k, _fmt(v)))
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
    parts.append("</div>")

    parts.append("<h2>Plant structure</h2><div class='grid'>")
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
    parts.append("</div>")
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
    )

    parts.append(
        "<h2>Main variables</h2><p class='muted'>Grouped by quantity"
        + (", engineering units" if units == "engineering" else ", SI units")
        + ". Grey dotted: time events and restarts; red dashed: located switches. "
        "Zoom with the mouse, double-click to reset; click a legend entry to hide it. "
        "Curves that coincide are drawn once, their names joined by '='.</p>"
    )
    figs = _figures(results, units)
    first = True
    plots_html = []
    for fig in figs:
        plots_html.append(
            fig.to_html(
                full_html=False,
                include_plotlyjs=True if first else False,  # embedded once, never a CDN
                config={"displaylogo": False, "responsive": True},
            )
        )
        first = False
    step_html = plots_html.pop() if (out / "steps.csv").exists() and plots_html else None
    parts.extend(plots_html)

    parts.append("<h2>Events: location of the switching points (seed Table 10.1)</h2>")
    ev_path = out / "events.csv"
    rows = []
    if ev_path.exists():
        with open(ev_path, newline="") as f:
            rdr = csv.reader(f)
            header = next(rdr, None)
            rows = list(rdr)
    if rows:
        parts.append(
            "<p class='muted'>Iteration 1 is the last accepted step before the sign change, "
            "2 the step that detected it, then the refinements; the last iterate is the "
            "switching time.</p>"
        )
        parts.append(
            _table(
                [{"time": "time [s]"}.get(h, h) for h in header],
                [[_fmt(float(v)) if j in (2, 3) else v for j, v in enumerate(r)] for r in rows],
                num_cols=(0, 1, 2, 3),
            )
        )
    else:
        parts.append("<p>No switch changed its state during the run.</p>")
    if step_html is not None:
        parts.append("<h2>Step size and order (seed Fig. 10.7)</h2>")
        parts.append(step_html)
    parts.append(
        "<p class='muted'>Written by dnasim; self-contained (plotly embedded), no network "
        "access needed.</p></body></html>"
    )
    return "\n".join(p for p in parts if p)


def write_report(outcome, loaded, out_dir, *, units: str = "si") -> Path:
    """Write ``report.html`` into ``out_dir`` (atomically) and return its path."""
    from dnasim.output import _atomic_write

    text = render_report(outcome, loaded, out_dir, units=units)
    path = Path(out_dir) / "report.html"
    _atomic_write(path, lambda f: f.write(text.encode("utf-8")))
    return path
