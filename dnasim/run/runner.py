"""What ``dnasim run`` does between loading a plant and printing its summary.

``run_plant`` streams every output point to ``results.csv`` while the solver runs
(through the plant's ``callback``), then writes ``events.csv`` and ``steps.csv``.
A solver failure (``DAEError`` with ``.result``) or an interrupt leaves the CSV
valid up to the time reached, and the outcome says where and why the run stopped.
Usable from Python too::

    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant
    outcome = run_plant(load("plants/attemperator.toml"), "out/")
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from dnasim.core.interrupts import held
from dnasim.plant.plantinfo import describe_loaded, write_plant_json
from dnasim.run.output import clear_results, write_events_csv, write_steps_csv
from dnasim.run.progress import Progress as _Progress
from dnasim.run.sinks import RESTART_COLUMN, AtTimes, CSVSink, NetCDFSink, OutputRows

__all__ = [
    "FORMATS",
    "RESTART_COLUMN",
    "RunOutcome",
    "run_plant",
    "solve_streaming",
    "write_plots",
    "describe_report",
    "format_component",
    "plant_output_layout",
]


@dataclass
class RunOutcome:
    """How a run ended, and what it wrote."""

    success: bool
    status: str  # "finished", "failed", "interrupted"
    message: str
    t_end: float
    t_reached: float | None
    rows: int
    out_dir: Path
    files: list[Path] = field(default_factory=list)
    stats: dict = field(default_factory=dict)
    n_events: int = 0
    n_steps: int = 0
    wall_time: float = 0.0
    result: Any = None
    event_log: list = field(default_factory=list)
    step_history: Any = None
    warnings: list = field(default_factory=list)  # System.warnings(): the run's warnings
    #: the steady start's notes (a controller holding a limit at rest, a choked Valve)
    notes: list = field(default_factory=list)

    def failure_message(self) -> str:
        where = (
            "before the first output point"
            if self.t_reached is None
            else f"at t = {self.t_reached:.6g} s"
        )
        if self.status == "output-error":
            return self.message
        verb = "was interrupted" if self.status == "interrupted" else "failed"
        streamed = [str(f) for f in self.files if f.name in _STREAMED]
        streamed = streamed or [str(self.out_dir / "results.csv")]
        csv_note = (
            f"; {streamed[0]} holds the {self.rows} rows up to that time"
            + "".join(f", {f} the same rows" for f in streamed[1:])
            if self.rows
            else ""
        )
        return (
            f"the simulation {verb} {where} (end time {self.t_end:.6g} s): {self.message}{csv_note}"
        )

    def summary(self) -> str:
        s = self.stats or {}
        parts = [
            f"{self.status}: t = {self.t_reached:.6g} s of {self.t_end:.6g} s"
            if self.t_reached is not None
            else f"{self.status}: no output",
            f"steps {s.get('steps', self.n_steps)}",
        ]
        rej = (s.get("rejected_error") or 0) + (s.get("rejected_newton") or 0)
        if s:
            parts.append(f"rejected {rej}")
        parts.append(f"events {self.n_events}")
        if "residual_evals" in s:
            parts.append(f"residual evaluations {s['residual_evals']}")
        if "jac_evals" in s:
            parts.append(f"Jacobians {s['jac_evals']}")
        parts.append(f"wall time {self.wall_time:.2f} s")
        text = ", ".join(parts) + f"\nresults in {self.out_dir}"
        return "".join(f"note: {n}\n" for n in self.notes) + text


#: the result formats of ``run_plant(formats=...)`` and ``dnasim run --format``: the file
#: each writes while the run goes on
FORMATS = {"csv": "results.csv", "netcdf": "results.nc"}
_STREAMED = set(FORMATS.values())


def netcdf_attributes(loaded) -> dict:
    """Global attributes of results.nc: the plant's name, description and file, and
    the ``[simulation]`` settings (``simulation_<key>``, SI: times in s)."""
    sim = loaded.simulation
    spec = getattr(loaded, "spec", None)
    attrs = {
        "title": getattr(spec, "name", "") or getattr(loaded.plant, "name", ""),
        "description": getattr(spec, "description", "") or "",
        "plant_file": str(getattr(loaded, "path", "") or ""),
    }
    for key in (
        "t_start",
        "t_end",
        "output_interval",
        "t_eval",
        "rtol",
        "atol_scaled",
        "max_order",
        "start",
        "max_step",
        "max_steps",
    ):
        value = getattr(sim, key, None)
        if value is not None:
            attrs[f"simulation_{key}"] = value
    attrs["simulation_solver"] = "NordsieckBDF"
    return attrs


# --------------------------------------------------------------------------- plant adapters


def plant_output_layout(system) -> tuple[list[str], dict[str, str], Any]:
    """Names, units and a row function ``row(t, y, yp) -> values`` for streaming,
    from the System's ``output_names()``, ``output_units()`` and ``output_row()``."""
    names = list(system.output_names())
    units = dict(system.output_units())
    return names, units, system.output_row


# --------------------------------------------------------------------------- run


def solve_streaming(system, sim, callback, *, dense_output: bool = False, notes=None):
    """Integrate ``system`` (a compiled plant) with the settings ``sim`` and hand
    every output point to ``callback(t, y, yp)``; returns the solver's raw result
    (a ``DAEResult``).

    ``dense_output=True`` (``run_plant(keep_rows=True)``) keeps the rows and the
    dense output in the result; otherwise a solver that has ``keep_output`` is
    asked not to keep the rows at all.

    The same System, start and tolerances as ``dnasim.run.simulation.simulate``, but for streaming:
    no dense output (the Nordsieck pieces of every step), no ``Results``
    table, and ``sim.max_steps`` reaches ``solve_dae``. With ``output_interval`` the
    solver generates the grid as it goes and hands over both sides of every
    discontinuity (two points at the same t); with ``t_eval`` the solver's points at
    those times (both sides of a jump at one of them, the caller keeps the right one:
    ``dnasim.run.sinks.AtTimes``) and at the restarts between them (dropped by the
    caller); without either, every accepted step and, after a restart, the state right
    after it.
    """
    from dnasim.run.backends import NordsieckBDF
    from dnasim.run.simulation import consistent_start, problem_for, solver_options

    t0, t_end = sim.t_start, sim.t_end
    # the number of output points is checked against its limit; the grid itself is
    # generated by the solver as it goes (output_interval), never allocated
    sim.check_output_points()
    y0, yp0 = consistent_start(system, t0, sim.start, notes=notes)
    # the settings' solver, as simulate() builds it (simulation.solver_options);
    # without dense output the rows go to the callback only: nothing grows with them
    solver = NordsieckBDF(
        **solver_options(sim), dense_output=dense_output, keep_output=dense_output
    )
    t_eval = getattr(sim, "t_eval", None)
    problem = problem_for(
        system,
        t0,
        t_end,
        y0,
        yp0,
        sim.atol_scaled,
        output_interval=sim.output_interval,
        t_eval=t_eval,
        callback=callback,
    )
    return solver.solve(problem)


def _terminal_message(system, result) -> str | None:
    """The plain message of the terminal switch that stopped ``result`` (None if none)."""
    if getattr(result, "status", 0) != 1:
        return None
    events = system.events
    for e in reversed(list(getattr(result, "event_log", None) or [])):
        idx = e.get("event")
        if e.get("terminal") and idx is not None and 0 <= idx < len(events):
            return events[idx].message(e["t"]) or None
    return None


def run_plant(
    loaded,
    out_dir,
    *,
    progress: bool = False,
    interrupt_types: tuple = (KeyboardInterrupt,),
    flush_rows: int = 200,
    flush_seconds: float = 1.0,
    keep_rows: bool = False,
    system=None,
    formats=("csv",),
) -> RunOutcome:
    """Simulate ``loaded`` (a ``dnasim.plant.plantfile.LoadedPlant``), streaming into ``out_dir``.

    The previous run's result files are removed first (:func:`clear_results`), so
    whatever is in ``out_dir`` afterwards belongs to this run; ``plant.json`` (the
    plant's graph, :mod:`dnasim.plant.plantinfo`) is written before the run starts. Rows go to
    ``results.csv`` as they are computed and are not kept in memory; with
    ``keep_rows=True`` the solver's result (``outcome.result``, a ``DAEResult``)
    also holds them (t, y, yp) and its dense output. ``system``: the compiled
    ``loaded.plant`` when the caller has compiled it already (the command line, to
    check ``--vars`` against the outputs before the run); else it is compiled here.
    ``formats``: the result files written while the run goes on, any of ``FORMATS``:
    "csv" (results.csv, :class:`~dnasim.run.sinks.CSVSink`) and "netcdf" (results.nc,
    :class:`~dnasim.run.sinks.NetCDFSink`, with :func:`netcdf_attributes`).

    Returns a :class:`RunOutcome`; failures of the simulation (``DAEError``),
    interrupts and a result file that cannot be written (status "output-error":
    disk full, file size limit) are reported in it, never raised. ``PlantError``
    (a plant that cannot be assembled) and ``OutputError`` from clearing the
    directory are raised.
    """
    from dnasim.core.errors import DAEError, OutputError

    formats = [formats] if isinstance(formats, str) else list(formats)
    unknown = [f for f in formats if f not in FORMATS]
    if unknown or not formats:
        raise ValueError(f"formats: {unknown or formats!r}; choose from {', '.join(FORMATS)}")
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(
            f"cannot create the output directory {out}: {exc.strerror or exc}", path=out
        ) from None
    clear_results(out)
    from dnasim.compilation.compiler import compile as compile_plant

    sim = loaded.simulation
    if system is None:
        system = compile_plant(loaded.plant)
    write_plant_json(out, describe_loaded(loaded, system))
    t_start = time.perf_counter()

    state: dict[str, Any] = {
        "writer": None,  # the first of the sinks (results.csv if written), opened at the first row
        "sinks": [],
        "last_t": None,
        "prev_t": None,
        "steps": [],
        "output_error": None,
    }
    bar = _Progress(sim.t_start, sim.t_end, progress)
    paths = [out / FORMATS[f] for f in formats]
    # without an output interval the rows are the accepted steps: their spacing is the
    # step size, kept (3 floats a step) for steps.csv in case the solver hands nothing over
    t_eval = getattr(sim, "t_eval", None)
    rows_are_steps = sim.output_interval is None and t_eval is None

    rows = OutputRows(system, sim.t_start, sim.t_end)
    # with t_eval the rows are exactly its times (the right limit of a jump at one)
    at_times = None if t_eval is None else AtTimes(t_eval, lambda t, _, row: put(t, row))

    def put(t, row):
        # every file gets the row or none does: a signal between two sinks' writes
        # would leave results.csv one row ahead of results.nc (and of the message)
        with held():
            for sink in state["sinks"]:
                sink.write(t, row)

    def write(t, y, yp):
        try:
            sinks = state["sinks"]
            if not sinks:  # the result files appear with the first row, not before
                for fmt, path in zip(formats, paths, strict=True):
                    if fmt == "csv":
                        sink = CSVSink(path, flush_rows=flush_rows, flush_seconds=flush_seconds)
                    else:
                        sink = NetCDFSink(
                            path,
                            flush_rows=flush_rows,
                            flush_seconds=flush_seconds,
                            attrs=netcdf_attributes(loaded),
                            expected_rows=sim.output_points(),
                        )
                    sinks.append(sink)
                    sink.open(rows.names, rows.units)
                state["writer"] = sinks[0]
            row = rows.row(t, y, yp)
            if at_times is None:
                put(t, row)
            else:
                at_times(t, row)
        except OutputError as exc:
            state["output_error"] = exc
            # a DAEError stops the solver, which then hands over its partial result
            raise DAEError(str(exc)) from exc
        t = float(t)
        prev = state["prev_t"]
        if rows_are_steps and prev is not None and t > prev:
            state["steps"].append((t, t - prev, math.nan))
        state["prev_t"] = t
        bar.update(t)

    def callback(t, y, yp):
        write(t, y, yp)

    status, message, result = "finished", "", None
    notes: list[str] = []
    try:
        try:
            result = solve_streaming(system, sim, callback, dense_output=keep_rows, notes=notes)
            if at_times is not None:
                try:
                    at_times.flush()  # the last row
                except OutputError as exc:
                    state["output_error"] = exc
            success = bool(getattr(result, "success", True))
            if not success:
                status = "failed"
                message = str(getattr(result, "message", "the solver stopped"))
            else:
                message = str(getattr(result, "message", "") or "")
                stop = _terminal_message(system, result)
                if stop is not None:
                    # a terminal switch that stands for a modelling error (flow into the
                    # plant through a sink-only boundary, a (p, T) supply at saturation)
                    # ends the run as a failure with the component's own message, as in
                    # ``dnasim.run.results``
                    status, success, message = "failed", False, stop
        except DAEError as exc:
            status, success = "failed", False
            message = str(exc)
            result = getattr(exc, "result", None)
        except interrupt_types as exc:
            status, success = "interrupted", False
            message = "interrupted by the user (Ctrl-C or SIGTERM)"
            result = getattr(exc, "result", None)
    finally:
        bar.close()
        for w in state["sinks"]:
            if isinstance(w, NetCDFSink):
                w.final_attrs = {"status": status, "message": message}
                for k, v in (getattr(result, "stats", None) or {}).items():
                    if isinstance(v, int | float) and not isinstance(v, bool):
                        w.final_attrs[f"stats_{k}"] = v  # the solver's counters
            try:
                w.close()
            except OutputError as exc:
                if state["output_error"] is None:
                    state["output_error"] = exc
        if state["sinks"]:
            # the last row on disk in every file
            reached = [w.last_time for w in state["sinks"]]
            state["last_t"] = None if None in reached else min(reached)
    if state["output_error"] is not None:
        status, success = "output-error", False
        message = str(state["output_error"])
    wall = time.perf_counter() - t_start

    event_log = list(getattr(result, "event_log", None) or [])
    step_history = getattr(result, "step_history", None)
    if (step_history is None or len(step_history) == 0) and status != "finished":
        # the solver handed nothing over (an interrupt before it could)
        step_history = state["steps"]
    elif rows_are_steps and status != "finished" and state["last_t"] is not None:
        # an interrupt inside the callback: the step is accepted but its row is not
        # on disk; steps.csv and results.csv end at the same step
        step_history = [r for r in step_history if r[0] <= state["last_t"]]
    if not keep_rows and result is not None and hasattr(result, "y"):
        result.y = result.yp = None  # the rows are in results.csv
    files = []
    write_errors = []
    n_steps = 0
    for name, write in (
        ("events.csv", lambda p: write_events_csv(p, event_log)),
        (
            "steps.csv",
            lambda p: write_steps_csv(p, step_history if step_history is not None else []),
        ),
    ):
        try:
            n = write(out / name)
        except OutputError as exc:
            write_errors.append(str(exc))
            continue
        files.append(out / name)
        if name == "steps.csv":
            n_steps = n
    if write_errors:
        if state["output_error"] is None:
            status, success = "output-error", False
            message = "; ".join(write_errors)
        else:
            message += "; " + "; ".join(write_errors)
    elif status == "output-error":
        message += "; events.csv and steps.csv were written"
    for path in reversed(paths[: len(state["sinks"])]):
        files.insert(0, path)
    stats = dict(getattr(result, "stats", None) or {})
    return RunOutcome(
        success=success,
        status=status,
        message=message,
        t_end=sim.t_end,
        t_reached=state["last_t"],
        rows=state["writer"].rows if state["writer"] is not None else 0,
        out_dir=out,
        files=files,
        stats=stats,
        n_events=len(event_log),
        n_steps=n_steps,
        wall_time=wall,
        result=result,
        event_log=event_log,
        step_history=step_history,
        warnings=system.warnings(),
        notes=notes,
    )


# --------------------------------------------------------------------------- plots


def write_plots(outcome: RunOutcome, out_dir, patterns, units: str = "si") -> list[Path]:
    """``variables.png`` and ``steps.png`` from the files the run wrote (the same
    function as ``dnasim plot``: :func:`dnasim.tools.plots.write_run_plots`)."""
    from dnasim.tools.plots import write_run_plots

    return write_run_plots(Path(out_dir) / "results.csv", patterns, units=units)


# --------------------------------------------------------------------------- check / components


def describe_report(report) -> tuple[str, bool]:
    """Text of a ``StructureReport`` (equations, unknowns, states, matching, problems)
    and whether it is free of errors."""
    if report is None:
        return "no structural report", True
    ok = bool(getattr(report, "ok", not getattr(report, "errors", None)))
    n_eq = getattr(report, "n_equations", None)
    if n_eq is None:
        return str(report), ok
    n_unk = report.n_unknowns
    n_diff = report.n_differential
    if n_eq == 0 and n_unk == 0 and not ok:  # the analysis stopped before counting
        lines = [f"error: {e}" for e in getattr(report, "errors", [])]
        lines += [f"warning: {w}" for w in getattr(report, "warnings", []) or []]
        return "\n".join(lines), ok
    lines = [
        f"equations:  {n_eq}",
        f"unknowns:   {n_unk} ({n_diff} differential states, {n_unk - n_diff} algebraic)",
    ]
    ue = list(getattr(report, "unmatched_equations", []) or [])
    uv = list(getattr(report, "unmatched_variables", []) or [])
    if not ue and not uv and n_eq == n_unk:
        lines.append(f"matching:   complete, every equation matched to one unknown ({n_eq})")
    else:
        lines.append(
            f"matching:   incomplete, {len(ue)} equations and {len(uv)} unknowns unmatched"
        )
        if ue:
            lines.append("  unmatched equations: " + ", ".join(map(str, ue[:20])))
        if uv:
            lines.append("  unmatched unknowns:  " + ", ".join(map(str, uv[:20])))
    for e in getattr(report, "errors", []) or []:
        lines.append(f"error: {e}")
    for w in getattr(report, "warnings", []) or []:
        lines.append(f"warning: {w}")
    return "\n".join(lines), ok


def format_component(info: dict) -> str:
    """The text of ``dnasim components NAME``: description and equations (from the
    docstring), ports, parameters with units, defaults and ranges, a TOML skeleton."""
    lines = [info["type"], ""]
    if info["doc"]:
        lines += [("  " + line).rstrip() for line in info["doc"].splitlines()]
    if info["equations"]:
        lines += ["", "  equations:"] + [f"    {e}" for e in info["equations"]]

    def ports(title, items, show_unit):
        if not items:
            return []
        w = max(len(p["name"]) for p in items)
        out = ["", f"  {title}:"]
        for p in items:
            extra = f"[{p['unit']}]" if show_unit and p["unit"] else p["role"]
            out.append(f"    {p['name']:<{w}}  {extra:<12} {p['doc']}".rstrip())
        return out

    lines += ports('fluid ports (ports = { port = "node" })', info.get("fluid_port_info"), False)
    lines += ports(
        'signal inputs (inputs = { input = "component.output" })',
        info.get("signal_input_info"),
        True,
    )
    lines += ports("signal outputs", info.get("signal_output_info"), True)
    if info["params"]:
        lines += ["", "  parameters:"]
        w = max(len(p["name"]) for p in info["params"])
        for p in info["params"]:
            if p["required"]:
                d = "required"
            elif p["default"] is None:
                d = "optional"
            else:
                d = f"default {p['default']!r}"
            rng = ""
            if p["min"] is not None or p["max"] is not None:
                lo = "-inf" if p["min"] is None else f"{p['min']:g}"
                hi = "inf" if p["max"] is None else f"{p['max']:g}"
                rng = f", range [{lo}, {hi}]"
            tf = ", may be a time function" if p["time_function"] else ""
            ch = f", one of {', '.join(map(repr, p['choices']))}" if p.get("choices") else ""
            unit = f"[{p['unit']}]" if p["kind"] in ("number", "int") else f"({p['kind']})"
            lines.append(f"    {p['name']:<{w}}  {unit:<10} {d}{rng}{ch}{tf}")
            if p["doc"]:
                lines.append(f"    {'':<{w}}  {p['doc']}")
    # a skeleton to paste into a plant file
    lines += ["", "  in a plant file:", "    [components.<name>]", f'    type = "{info["type"]}"']
    for p in info["params"]:
        if p["required"]:
            lines.append(f"    {p['name']} = ...  # [{p['unit']}]")
    if info["fluid_ports"]:
        lines.append(
            "    ports = { " + ", ".join(f'{q} = "<node>"' for q in info["fluid_ports"]) + " }"
        )
    if info["signal_inputs"]:
        lines.append(
            "    inputs = { "
            + ", ".join(f'{q} = "<component>.<output>"' for q in info["signal_inputs"])
            + " }"
        )
    return "\n".join(lines)
