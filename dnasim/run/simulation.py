"""simulate(system, solver, sinks) -> Results: integrate a compiled plant.

Backends are in ``dnasim.run.backends``, sinks in ``dnasim.run.sinks``.

    system = compile(plant)
    res = simulate(system, t_end=100.0, solver=NordsieckBDF(rtol=1e-6, atol_scaled=1e-6),
                   sinks=[CSVSink("out/results.csv")])

Contracts
---------
* A solver is an object with ``name`` and ``solve(problem) -> DAEResult-like``
  (fields t, y, yp, success, status, message, event_log, stats, step_history,
  sol). It sees a ``Problem``: the residual, the sparsity, the algebraic mask,
  the switch functions, the tstops, the consistent start and the tolerances as
  arrays. It never sees components or the System.
* A sink is an object with ``open(names, units)``, ``write(t, row)`` and
  ``close()``; ``simulate`` streams every output point (t [s], the row of
  ``System.output_row`` and the restart flag: ``dnasim.run.sinks.OutputRows``) into
  every sink while the solver runs. ``dnasim run`` writes its results.csv
  through the same ``CSVSink`` and rows.
* Tolerances: ``rtol`` is relative; ``atol_scaled`` is an absolute tolerance
  relative to each variable's scale, atol_i = atol_scaled * max(nominal_i,
  |y0_i|) (``System.atol_vector``), so a pressure ~1e5 Pa gets 1e5 times the
  absolute tolerance of a valve opening ~1. One default everywhere:
  rtol = 1e-6, atol_scaled = 1e-6. (``dnasim.solve_dae`` works on a bare DAE
  with no scales; its ``atol`` is the absolute atol_i itself.)
* Failures: a solver failure ends the run with ``Results.success`` False and the
  reason in ``message``; ``throw=True`` raises ``DAEError`` with the Results as
  ``err.result``. ``dnasim.solve_dae`` has the same ``throw`` with the same
  default. A plant that cannot start (no consistent initial values)
  raises ``DAEError`` (there are no rows to return).
"""

from __future__ import annotations

import math
import time
from functools import partial

import numpy as np

from dnasim.core.errors import DAEError, PlantError
from dnasim.model.physics import forget_memos
from dnasim.run.backends import IDA, SOLVER_OPTIONS, NordsieckBDF, Problem
from dnasim.run.results import Results, strictly_increasing
from dnasim.run.sinks import CSVSink, OutputRows

__all__ = [
    "CSVSink",
    "IDA",
    "NordsieckBDF",
    "simulate",
    "simulation_keywords",
    "solver_options",
]


def solver_options(settings) -> dict:
    """The ``NordsieckBDF`` options of a plant file's ``SimulationSettings`` (rtol,
    atol_scaled, max_order, and max_step, max_steps where given): the one mapping from
    the settings to the solver, for ``simulate`` and ``dnasim run`` alike."""
    kw = {"rtol": settings.rtol, "atol_scaled": settings.atol_scaled}
    kw["max_order"] = settings.max_order
    if settings.max_step is not None:
        kw["max_step"] = settings.max_step
    if settings.max_steps is not None:
        kw["max_steps"] = int(settings.max_steps)
    if not getattr(settings, "refine_output", True):
        kw["refine_output"] = False
    return kw


def simulation_keywords(settings, t_end: float | None = None, **overrides):
    """``(t_end, keywords)`` for ``simulate`` from a plant file's ``SimulationSettings``,
    with ``overrides`` (the caller's keywords) on top: the one place where settings and
    keywords are merged (``Plant.simulate``, ``LoadedPlant.simulate``,
    ``simulate_plant``).

    The solver options rtol, atol_scaled, max_order, max_step, max_steps build the
    default ``NordsieckBDF`` (left out when the caller gives a ``solver`` object: it
    brings its own); ``output_interval`` is handed to the solver, which generates the
    output grid as it goes, both sides of every discontinuity included, exactly as in
    ``dnasim run`` (the grid is never built here); the file's ``t_eval`` (its list of
    output times) becomes ``t_eval``. A ``t_eval`` or ``output_interval`` among the
    overrides replaces the file's output settings (both of them).
    """
    kw = {
        **solver_options(settings),
        "t0": settings.t_start,
        "start": settings.start,
        "output_interval": settings.output_interval,
    }
    if getattr(settings, "t_eval", None) is not None:
        kw["t_eval"] = list(settings.t_eval)
        kw.pop("output_interval")
    if overrides.get("solver") is not None:
        kw = {k: v for k, v in kw.items() if k not in SOLVER_OPTIONS}
    if overrides.get("t_eval") is not None or overrides.get("output_interval") is not None:
        kw.pop("output_interval", None)
        kw.pop("t_eval", None)
    kw.update(overrides)
    if t_end is None:
        t_end = settings.t_end
    if kw.get("output_interval") is not None:
        # the file's row limit, for the t_end of this run (checked before any numerics)
        from dataclasses import replace

        replace(settings, t_end=t_end, t_start=kw.get("t0", settings.t_start)).check_output_points()
    return t_end, kw


def simulate(
    system,
    *,
    t_end: float,
    solver=None,
    sinks=(),
    t0: float = 0.0,
    start: str = "steady",
    initial=None,
    t_eval=None,
    output_interval: float | None = None,
    callback=None,
    throw: bool = False,
    progress: bool = False,
    **solver_options,
) -> Results:
    """Integrate ``system`` from t0 to t_end [s]; returns ``Results``.

    solver: a backend object (default ``NordsieckBDF()``); keywords not listed
    here (rtol, atol_scaled, max_order, max_step, h0, ...) build the default
    backend instead. start: "steady" or "given" (``dnasim.start.initial``); initial: an
    already consistent (y0, yp0).

    Output points (the rows of the Results and of every sink):

    * ``t_eval``: times [s], strictly increasing, within [t0, t_end]; the rows are
      exactly these times, followed literally: no row at the switches and time events
      between them. At a t_eval time where the solution jumps (a set-point step, a
      located switch) the row is the right limit, the state right after the jump,
      flagged in ``Results.restart`` (and the sinks' ``restart`` column). Values
      between steps are the solver's interpolation (``NordsieckBDF`` also solves the
      algebraic variables there, ``solve_dae``'s ``refine_output``; ``IDA``: its own
      IDAGetDky). A run that stops early (a failure, a terminal switch) holds the
      t_eval times it reached.
    * ``output_interval`` [s]: the grid t0, t0 + dt, ..., t_end generated by the
      solver as it goes, both sides of every discontinuity (as ``dnasim run`` writes
      it; the Results keep the state after each jump).
    * neither: every accepted step.

    sinks: output writers (``CSVSink``, ...); callback(t, y, yp): called at every
    output point (with t_eval one point late: the next point says whether the state
    after a jump at that time follows). progress: a progress bar (tqdm,
    ``dnasim.run.progress``: percentage of t_end reached, simulated time, an estimate
    of the time left): one line on stderr redrawn in place, the notebook's widget in
    Jupyter with ipywidgets. throw: raise ``DAEError`` (with ``err.result``)
    instead of returning Results with success False.
    """
    from dnasim.start.initial import reinitialise

    if solver is None:
        solver = NordsieckBDF(**solver_options)
    elif solver_options:
        raise PlantError(
            f"simulate(): give the options {', '.join(sorted(solver_options))} to the solver "
            f"object ({type(solver).__name__}(...)), not next to it"
        )
    if not t_end > t0:
        raise PlantError(f"t_end ({t_end}) must be greater than t0 ({t0})")
    if t_eval is not None and output_interval is not None:
        raise PlantError("simulate(): give t_eval or output_interval, not both")
    if output_interval is not None and not (output_interval > 0 and math.isfinite(output_interval)):
        raise PlantError(
            f"simulate(): output_interval must be a positive time [s], got {output_interval!r}"
        )
    if t_eval is not None:
        t_eval = _checked_t_eval(t_eval, t0, t_end)
    t_start = time.perf_counter()
    y0, yp0 = consistent_start(system, t0, start, initial)
    t_init = time.perf_counter() - t_start

    sinks = list(sinks)
    rows = OutputRows(system, t0, t_end)
    if sinks:
        for s in sinks:
            s.open(rows.names, rows.units)

    # with output_interval or t_eval the solver hands each output point to the callback
    # (its own t, y record holds the accepted steps): the Results are those points, the
    # rows the sinks get; with t_eval only the points at its times (``AtTimes``)
    grid: list | None = [] if (output_interval is not None or t_eval is not None) else None
    flags: list = []  # with t_eval: the restart flag of each point in ``grid``
    bar = None  # the progress line, from the start of the integration

    def deliver(t, restart, y, yp, row):
        if grid is not None:
            grid.append((float(t), np.array(y, dtype=float), np.array(yp, dtype=float)))
            flags.append(restart)
        if sinks:
            for s in sinks:
                s.write(t, row)
        if callback is not None:
            callback(t, y, yp)

    at_times = None
    if t_eval is not None:
        from dnasim.run.sinks import AtTimes

        at_times = AtTimes(t_eval, deliver)

    def point(t, y, yp):
        # every point goes through OutputRows (which tells the right limit of a jump
        # from the left one by the repeated time)
        row = rows.row(t, y, yp) if sinks else None
        if at_times is not None:
            at_times(t, np.array(y, dtype=float), np.array(yp, dtype=float), row)
        else:
            deliver(t, False, y, yp, row)
        if bar is not None:
            bar.update(float(t))

    pb = problem_for(
        system,
        t0,
        t_end,
        y0,
        yp0,
        solver.atol_scaled,
        t_eval=t_eval,
        output_interval=output_interval,
        callback=point if (sinks or callback is not None or grid is not None or progress) else None,
        reinitialise=partial(reinitialise, system),
    )
    if progress:
        from dnasim.run.progress import Progress as _Progress

        bar = _Progress(t0, t_end, True)
    t_start = time.perf_counter()
    try:
        raw = solver.solve(pb)
        if at_times is not None:
            at_times.flush()
    finally:
        if bar is not None:
            bar.close()
        for s in sinks:
            s.close()
    wall = time.perf_counter() - t_start
    res = results_from(
        system,
        raw,
        solver.name,
        wall_time=wall,
        init_time=t_init,
        points=grid,
        restart=flags if at_times is not None else None,
    )
    if throw and not res.success:
        err = DAEError(res.message)
        err.result = res
        raise err
    return res


def _checked_t_eval(t_eval, t0: float, t_end: float) -> np.ndarray:
    """``t_eval`` as a float array [s], or ``PlantError`` naming what is wrong with it
    (``dnasim.core.values.t_eval_problem``: finite, strictly increasing, in [t0, t_end])."""
    from dnasim.core.values import t_eval_problem

    try:
        times = np.array(t_eval, dtype=float).ravel()
    except (TypeError, ValueError):
        raise PlantError(
            f"simulate(): t_eval must be a sequence of times [s] (numbers), got {t_eval!r}"
        ) from None
    problem = t_eval_problem(times.tolist(), t0, t_end)
    if problem:
        raise PlantError(f"simulate(): t_eval: {problem}")
    return times


def consistent_start(system, t0: float, start: str = "steady", initial=None, notes=None):
    """(y0, y'0) of ``system`` at t0 [s]: ``initial`` when given (already consistent),
    else the steady or given start (``dnasim.start.initial.initial_values``); with a
    ``notes`` list the steady start's notes (a controller holding a limit at rest, a
    choked valve) are appended to it. The one start of ``simulate`` and ``dnasim run``.
    The property memos start afresh (``physics.forget_memos``): a System simulated
    again in one process takes the same steps."""
    forget_memos()
    if initial is not None:
        return tuple(np.array(v, dtype=float) for v in initial)
    if start == "steady" and notes is not None:
        from dnasim.start.steady_state import find_steady_state

        rest = find_steady_state(system, t0)
        notes.extend(rest.notes)
        return rest.y, rest.yp
    from dnasim.start.initial import initial_values

    return initial_values(system, t0, start)


def problem_for(system, t0, t_end, y0, yp0, atol_scaled, **options) -> Problem:
    """The ``Problem`` a solver backend integrates for ``system`` from consistent
    (y0, yp0) at t0 to t_end [s]: residual, sparsity, switches, tstops, names and
    atol_i = atol_scaled * scale_i (``System.atol_vector``); ``options`` are the
    output settings (t_eval, output_interval, callback, reinitialise)."""
    return Problem(
        residual=system.residual,
        t_span=(float(t0), float(t_end)),
        y0=y0,
        yp0=yp0,
        algebraic=system.algebraic,
        jac_sparsity=system.jac_sparsity,
        residual_for_columns=system.residual_for_columns,
        output_residual=(system.residual_aside, system.residual_for_columns_aside),
        events=system.events,
        tstops=system.tstops(t0, t_end),
        atol=system.atol_vector(atol_scaled, y0),
        quadrature=system.quadrature,
        variable_names=list(system.names),
        equation_names=list(system.eq_names),
        **options,
    )


def results_from(
    system, raw, solver_name="", wall_time=None, init_time=None, points=None, restart=None
) -> Results:
    """``Results`` from a solver's raw result (strictly increasing t, named events).

    points: the output points [(t, y, yp), ...] handed to the callback, when they and
    not the solver's record of its steps are the rows (``output_interval``, ``t_eval``).
    restart: the restart flag of each point (``t_eval``: one point per time, the
    right limit of a jump flagged); None: a repeated time is the state after a restart."""
    if points is not None:
        n = system.n
        t = np.array([p[0] for p in points], dtype=float)
        y = np.array([p[1] for p in points], dtype=float).T.reshape(n, -1)
        yp = np.array([p[2] for p in points], dtype=float).T.reshape(n, -1)
    else:
        t = np.asarray(raw.t, dtype=float)
        y = np.asarray(raw.y, dtype=float)
        yp = np.asarray(raw.yp, dtype=float)
    keep, repeated = strictly_increasing(t)
    restart = repeated if restart is None else np.asarray(restart, dtype=bool)[keep]
    t, y, yp = t[keep], y[:, keep], yp[:, keep]
    names = system.output_names()

    def values():
        rows = np.array([system.output_row(t[k], y[:, k], yp[:, k]) for k in range(t.size)])
        return rows.T if rows.size else np.zeros((len(names), 0))

    stats = dict(raw.stats)
    if wall_time is not None:
        stats["wall_time"] = wall_time
    if init_time is not None:
        stats["init_time"] = init_time
    events = system.events
    log = []
    for entry in raw.event_log:
        e = dict(entry)
        idx = e.get("event")
        if idx is not None and 0 <= idx < len(events):
            ev = events[idx]
            e["component"] = ev.component
            e["switch"] = ev.switch.name
            e.setdefault("name", ev.name)
        log.append(e)
    success, message = bool(raw.success), str(raw.message)
    # a terminal switch that stands for a modelling error (e.g. flow into the
    # plant through a sink-only boundary) ends the run as a failure with the
    # component's own plain message
    for e in reversed(log if getattr(raw, "status", 1) == 1 else []):
        idx = e.get("event")
        if e.get("terminal") and idx is not None and 0 <= idx < len(events):
            text = events[idx].message(e["t"])
            if text:
                success, message = False, text
            break
    return Results(
        t,
        names,
        system.output_units(),
        values,
        y=y,
        yp=yp,
        variable_names=list(system.names),
        restart=restart,
        events=log,
        steps=np.asarray(raw.step_history),
        stats=stats,
        success=success,
        message=message,
        solver=solver_name,
        sol=getattr(raw, "sol", None),
        warnings=system.warnings(),
    )
