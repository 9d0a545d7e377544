"""``solve_dae``: the driver around the BDF stepper.

It validates the input, makes the initial values consistent, and steps with
``NordsieckBDF`` from t0 to t_end. Around each step it

- never steps past a ``tstop`` (a known time discontinuity): the step lands on
  it exactly, with the residual evaluated at the left limit, and integration
  restarts there at order 1 from values made consistent at the right limit;
- watches the switch functions; on a sign change it locates the zero on the
  step's interpolant (``events.locate_zero``), cuts the step there, runs the
  switch's action, makes the state consistent again and restarts at order 1
  (the seed's Fig. 10.7); several switches in one step: the earliest wins;
  a vector switch (many elements, one call per step) brackets only the elements
  that changed sign and locates the earliest (``events.locate_earliest``);
- emits the output points (every step, or ``t_eval``) to the result and to an
  optional ``callback`` that can stream them to disk.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from dnasim.core.blas_threads import one_blas_thread
from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver import nordsieck as nd
from dnasim.solver.bdf import CountedResidual, NordsieckBDF, SolverStats
from dnasim.solver.callbacks import call_user
from dnasim.solver.events import SwitchFunction, locate_earliest, locate_zero
from dnasim.solver.initial import detect_algebraic, solve_consistent
from dnasim.solver.linear_algebra import IterationMatrix
from dnasim.solver.result import DAEResult, NordsieckSolution

MAX_RESTARTS_AT_ONE_TIME = 50


def _solve_dae(
    residual: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
    t_span: Sequence[float],
    y0,
    yp0=None,
    *,
    algebraic=None,
    quadrature=None,
    rtol: float = 1e-6,
    atol=1e-8,
    max_order: int = 4,
    h0: float | None = None,
    max_step: float = np.inf,
    jac: Callable | None = None,
    jac_sparsity=None,
    events: Sequence[Callable] = (),
    tstops: Sequence[float] = (),
    t_eval=None,
    calc_initial: bool = True,
    exclude_algebraic_from_error: bool = False,
    callback: Callable | None = None,
    variable_names: Sequence[str] | None = None,
    equation_names: Sequence[str] | None = None,
    dense_output: bool = True,
    max_steps: int = 500_000,
    output_interval: float | None = None,
    keep_output: bool = True,
    throw: bool = False,
) -> DAEResult:
    """Solve the index-1 DAE F(t, y, y') = 0 from t_span[0] to t_span[1].

    Parameters
    ----------
    residual : F(t, y, yp) -> array of shape (n,). dF/dy' may be singular; a
        differential equation may hold derivatives of other variables.
        It may raise ``dnasim.core.errors.ResidualDomainError`` for a state outside
        its domain: the step is then cut, like a failed Newton iteration.
    t_span : (t0, t_end), t_end > t0.
    y0, yp0 : initial values; yp0 defaults to zeros.
    algebraic : indices or boolean mask of the components whose derivative
        appears nowhere. None: found by probing dF/dy'.
    quadrature : indices or boolean mask of quadrature components (None: none):
        y_i' = f_i(t, other y, y') set by one equation, y_i read by no equation
        (a running integral such as the mass that has passed a boundary). As
        SUNDIALS IDA's quadratures with errconQ = false they are left out of the
        error test, the Newton convergence norm and the first step after the start,
        a tstop or a switch (0.5/||y'||): they take part in no step-size decision; they
        are still integrated by the same BDF formula (in the Newton system, so a
        linear invariant tying them to the states holds to round-off).
    rtol, atol : error tolerances; weights 1 / (rtol |y_i| + atol_i); atol
        scalar or per component, > 0.
    max_order : highest BDF order, 1..5 (default 4, as the seed argues).
    h0 : first step (default as IDA: 0.001 of the span, at most 0.5/||y'||).
    max_step : largest step.
    jac : optional jac(t, y, yp, cj) -> dF/dy + cj dF/dy', dense or sparse.
    jac_sparsity : optional pattern of dF/dy + dF/dy'; finite differences are
        then grouped by column colouring and the LU is sparse.
    events : switch functions, scalar or vector (see ``dnasim.solver.events``).
        Scalar: g(t, y, yp) -> float, with optional attributes ``direction``
        (-1, 0, 1), ``terminal`` (bool), ``restart`` (bool), ``action(t, y, yp)``
        returning new (y, yp) or None, and ``name``.
        Vector: an object with an integer attribute ``size``, called once per
        step as g(t, y, yp) -> array of shape (size,); ``direction`` a scalar or
        an array of -1/0/+1, ``names`` (size strings), ``terminal``, ``restart``
        and optional ``action(t, y, yp, which)``, ``which`` the int array of the
        elements that crossed at the located time. A switch with an action, or
        terminal, or with ``restart = True`` cuts the step at its earliest
        crossing, is made consistent there and restarts at order 1; otherwise its
        crossings are only located and logged. The event log names the element.
    tstops : known discontinuity times, hit exactly; restart at order 1.
    t_eval : output times (default: every accepted step). With output times, both
        sides of every restart (tstop, located switch) are output points too: two
        points at the same t, the state before and after the discontinuity.
    output_interval : output times t0, t0 + dt, ..., t_end generated as the
        integration reaches them (no grid is allocated); not with ``t_eval``.
    calc_initial : make (y0, yp0) consistent first (keep the differential y0).
    exclude_algebraic_from_error : leave algebraic components out of the error test.
    callback : callback(t, y, yp) for every output point, in order (streaming).
    variable_names : names of the unknowns y_i ("water.flow"), used in error messages.
    equation_names : names of the equations F_i ("water.mass"), used in error messages.
    dense_output : keep the Nordsieck polynomials for ``result.sol(t)``.
    max_steps : give up after this many steps.
    keep_output : False: output points go to ``callback`` only and are not kept
        in the result (``result.t`` is then empty): memory does not grow with them.

    throw : what a failure during the integration does (a step that fails
        repeatedly, max_steps, a chattering switch, an exception in a callback,
        the event functions or an action). False (the default, as in
        ``dnasim.simulate``): return the result with ``success`` False, ``status``
        -1 and the reason in ``message``, holding the solution up to the last
        accepted step. True: raise ``DAEError`` with that result as its ``result``
        attribute (the original exception chained).

    Returns
    -------
    DAEResult (``success`` False after a failure during the integration, see
    ``throw``). Invalid input, and initial values that cannot be made consistent,
    raise ``DAEError`` whatever ``throw`` says: there is no solution to return
    (as ``simulate`` raises for a plant that cannot start). Ctrl-C raises
    ``KeyboardInterrupt`` with the solution so far as its ``result`` attribute.
    """
    problem = _Problem.validate(
        residual,
        t_span,
        y0,
        yp0,
        algebraic,
        quadrature,
        rtol,
        atol,
        max_order,
        h0,
        max_step,
        jac_sparsity,
        events,
        tstops,
        t_eval,
        variable_names,
        equation_names,
    )
    stats = SolverStats()
    F = CountedResidual(residual, problem.n, stats)
    matrix = IterationMatrix(F, problem.n, jac, problem.sparsity, variable_names, equation_names)
    t0, t_end = problem.t0, problem.t_end
    y, yp = problem.y0, problem.yp0
    grid = None
    if problem.t_eval is not None and output_interval is not None:
        raise DAEError("give t_eval or output_interval, not both.")
    if problem.t_eval is not None:
        grid = _Grid(t_eval=problem.t_eval)
    elif output_interval is not None:
        dt = output_interval
        if isinstance(dt, bool) or not (
            isinstance(dt, (int, float, np.integer, np.floating)) and np.isfinite(dt) and dt > 0
        ):
            raise DAEError(f"output_interval must be a positive number; got {dt!r}.")
        grid = _Grid(interval=float(dt), t0=t0, t_end=t_end)
    out = _Output(grid, callback, dense_output, t0, keep=keep_output)
    switches = [SwitchFunction.wrap(g, i) for i, g in enumerate(events)]
    kinks = [sw for sw in switches if sw.kink and sw.restarts]
    if kinks and jac is None:
        # finite differences stay on the side of every restart switch (linear_algebra)
        def side(t, y, yp):
            return np.concatenate([sw.value(t, y, yp) for sw in kinks])

        matrix.side = side
    event_log: list[dict] = []
    t_events: list[list] = [[] for _ in switches]
    y_events: list[list] = [[] for _ in switches]
    stops = [s for s in problem.tstops if t0 < s < t_end]
    status, message = 0, "The solver reached the end of the interval."
    restarts_here, last_restart_t = 0, None
    solver = None

    def partial_result(success, status, message):
        return DAEResult(
            *out.arrays(problem.n),
            success,
            status,
            message,
            [np.array(v) for v in t_events],
            [np.array(v).reshape(-1, problem.n) for v in y_events],
            event_log,
            stats.as_dict(),
            out.step_history(),
            out.solution(),
        )

    try:
        try:
            F(t0, y, yp)
        except ResidualDomainError as exc:
            raise DAEError(
                f"The residual cannot be evaluated at the initial values: {exc}"
            ) from None
        algebraic_mask = problem.algebraic
        if algebraic_mask is None:
            algebraic_mask = detect_algebraic(F, t0, y, yp, matrix)
        error_mask = np.ones(problem.n)
        if exclude_algebraic_from_error:
            error_mask[algebraic_mask] = 0.0
        norm_mask = np.ones(problem.n)  # Newton's convergence norm
        if problem.quadrature is not None:
            error_mask[problem.quadrature] = 0.0
            norm_mask[problem.quadrature] = 0.0
        span = t_end - t0
        ic_scale = h0 if h0 is not None else min(1e-3 * span, max_step)

        def consistent(t, y, yp, what, h_scale=None):
            yp = np.array(yp, dtype=float)
            yp[algebraic_mask] = 0.0  # not determined by F; the predictor starts them flat
            return solve_consistent(
                F,
                t,
                y,
                yp,
                algebraic_mask,
                rtol=rtol,
                atol=problem.atol,
                h_scale=ic_scale if h_scale is None else h_scale,
                matrix=matrix,
                variable_names=variable_names,
                equation_names=equation_names,
                what=what,
            )

        if calc_initial:
            y, yp = consistent(t0, y, yp, "the initial values")
        solver = NordsieckBDF(
            F,
            t0,
            y,
            yp,
            rtol=rtol,
            atol=problem.atol,
            max_order=max_order,
            h0=h0,
            max_step=max_step,
            error_mask=error_mask,
            norm_mask=norm_mask,
            algebraic=algebraic_mask,
            matrix=matrix,
            stats=stats,
            t_scale=span,
            names=variable_names,
            equation_names=equation_names,
        )
        g_old = [sw.value(t0, y, yp) for sw in switches]
        past = _terminal_past_zero(switches, g_old)
        if past is not None:
            # a limit already crossed at the start: the run cannot begin (no output)
            k, j = past
            sw = switches[k]
            event_log.append(
                {
                    "event": k,
                    "name": sw.names[j],
                    "element": int(j),
                    "t": t0,
                    "iterates": [(t0, float(g_old[k][j]))],
                    "terminal": True,
                }
            )
            t_events[k].append(t0)
            y_events[k].append(y)
            return partial_result(
                True, 1, f"A terminal switch, {sw.names[j]!r}, is past its zero at t = {t0:.10g}."
            )
        out.initial(t0, y, yp)
        for k, sw in enumerate(switches):
            sw.arm(g_old[k])  # a switch at its zero at t0 (SwitchFunction.arm)
        solver.reinitialize = lambda t, y, yp, h: consistent(
            t, y, yp, "the values at a step that failed repeatedly", h_scale=h
        )
        if kinks:
            solver.predicted_crossing = lambda t_a, t_b: _predicted_crossing(
                solver, kinks, t_a, t_b
            )
        while solver.t < t_end:
            if stats.steps >= max_steps:
                raise DAEError(
                    f"The solver took {max_steps} steps and reached only t = {solver.t:.10g}; "
                    "raise max_steps or check the model for fast oscillations."
                )
            next_stop = stops[0] if stops and stops[0] > solver.t else t_end
            t_prev = solver.t
            solver.step(next_stop, left_limit=next_stop < t_end)
            if switches:
                g_new = [sw.value(solver.t, solver.y, solver.yp) for sw in switches]
                cut = _crossings(solver, switches, g_old, g_new, t_prev)
            else:
                g_new, cut = g_old, ()
            for c in cut:
                sw = switches[c.switch]
                for j in c.which:
                    event_log.append(
                        {
                            "event": c.switch,
                            "name": sw.names[j],
                            "element": int(j),
                            "t": c.t,
                            "iterates": c.iterates if j == c.located else [],
                            "terminal": sw.terminal,
                        }
                    )
                    t_events[c.switch].append(c.t)
                    y_events[c.switch].append(c.y)
            if cut and cut[-1].restarts:
                c = cut[-1]
                sw = switches[c.switch]
                t_star = c.t
                if sw.terminal:
                    # the run ends with the last state on the old side of the switch (a
                    # vessel's level at its limit, not a round-off beyond it), which is
                    # the last output point, also between output times
                    out.step(solver, t_prev, _old_side(c, g_old[c.switch]))
                    out.final()
                    status, message = (
                        1,
                        f"A terminal switch, {sw.names[c.located]!r}, fired at t = {t_star:.10g}.",
                    )
                    break
                out.step(solver, t_prev, t_star)
                if t_star == last_restart_t:
                    restarts_here += 1
                    if restarts_here > MAX_RESTARTS_AT_ONE_TIME:
                        raise DAEError(
                            f"The switch {sw.names[c.located]!r} fires again and again at "
                            f"t = {t_star:.10g} (chattering): its action does not move the state "
                            "to the other side."
                        )
                else:
                    restarts_here, last_restart_t = 0, t_star
                # an armed element (at its zero since t0) that acted: the new mode's
                # elements at their zero are armed again (SwitchFunction.arm)
                from_start = sw.armed is not None and t_star == t_prev and sw.armed[c.located]
                y_new, yp_new = _run_action(sw, c, problem.n)
                y_new, yp_new = consistent(
                    t_star, y_new, yp_new, f"the values after the switch {sw.names[c.located]!r}"
                )
                next_stop = stops[0] if stops and stops[0] > t_star else t_end
                solver.restart(
                    t_star, y_new, yp_new, solver.restart_step(t_star, y_new, yp_new, next_stop)
                )
                out.restart(t_star, y_new, yp_new)
                g_old = [sw.value(t_star, y_new, yp_new) for sw in switches]
                for k, s_k in enumerate(switches):
                    if from_start:
                        s_k.arm(g_old[k])
                    else:
                        s_k.keep_armed(g_old[k])
                continue
            out.step(solver, t_prev, solver.t)
            g_old = g_new
            for k, sw in enumerate(switches):
                sw.keep_armed(g_new[k])
            if stops and solver.t == stops[0]:
                stops.pop(0)
                y_new, yp_new = consistent(
                    solver.t, solver.y, solver.yp, "the values after the time event (tstop)"
                )
                # a switch that the jump carried across its zero (a set-point step taking
                # a controller past its limit) fires at the tstop itself
                for _ in range(MAX_RESTARTS_AT_ONE_TIME):
                    g_plus = [sw.value(solver.t, y_new, yp_new) for sw in switches]
                    k = next(
                        (
                            k
                            for k, sw in enumerate(switches)
                            if sw.action is not None and np.any(sw.crossed(g_new[k], g_plus[k]))
                        ),
                        None,
                    )
                    if k is None:
                        break
                    sw = switches[k]
                    which = np.flatnonzero(sw.crossed(g_new[k], g_plus[k]))
                    for j in which:
                        event_log.append(
                            {
                                "event": k,
                                "name": sw.names[j],
                                "element": int(j),
                                "t": solver.t,
                                "iterates": [],
                                "terminal": sw.terminal,
                            }
                        )
                        t_events[k].append(solver.t)
                        y_events[k].append(y_new)
                    c = _Crossing(k, solver.t, y_new, yp_new, which, int(which[0]), [], True)
                    y_new, yp_new = _run_action(sw, c, problem.n)
                    y_new, yp_new = consistent(
                        solver.t, y_new, yp_new, f"the values after the switch {sw.names[j]!r}"
                    )
                    g_new = g_plus
                next_stop = stops[0] if stops else t_end
                solver.restart(
                    solver.t, y_new, yp_new, solver.restart_step(solver.t, y_new, yp_new, next_stop)
                )
                out.restart(solver.t, y_new, yp_new)
                g_old = [sw.value(solver.t, y_new, yp_new) for sw in switches]
                for k, sw in enumerate(switches):
                    sw.keep_armed(g_old[k])
    except DAEError as exc:
        result = partial_result(False, -1, str(exc))
        if not throw and solver is not None:  # the integration had started
            return result
        error = DAEError(str(exc))
        error.result = result
        raise error from exc.__cause__
    except KeyboardInterrupt as exc:
        # Ctrl-C: hand the caller what was computed (it may write it to disk).
        t_reached = solver.t if solver is not None else t0
        exc.result = partial_result(False, -2, f"Interrupted at t = {t_reached:.10g}.")
        raise
    return partial_result(True, status, message)


@dataclass
class _Crossing:
    """A located crossing in the last step: switch index, time, state, elements."""

    switch: int
    t: float
    y: np.ndarray
    yp: np.ndarray
    which: np.ndarray  # the elements that crossed at t (one for a scalar switch)
    located: int  # the element whose zero was located (the iterates are its)
    iterates: list
    restarts: bool


def _crossings(solver, switches, g_old, g_new, t_prev) -> list[_Crossing]:
    """Locate the crossings in the last step; return those up to the first that restarts.

    A restarting switch (terminal, with an action or ``restart``) gives its
    earliest crossing only (elements crossing at the same located time are
    reported together); an observing switch gives every crossed element, each
    located on its own. Crossings of observing switches before the first
    restarting one are all returned; later ones are dropped (found again after
    the restart).
    """
    found = []
    for k, sw in enumerate(switches):
        crossed = sw.crossed(g_old[k], g_new[k])
        if not crossed.any():
            continue

        def values(t, sw=sw):
            y, yp = solver.interpolate(t)
            return sw.value(t, y, yp)

        if sw.restarts:
            t_star, _, which, j, iterates = locate_earliest(
                values, sw, t_prev, g_old[k], solver.t, g_new[k]
            )
            y_star, yp_star = solver.interpolate(t_star)
            found.append(_Crossing(k, t_star, y_star, yp_star, which, j, iterates, True))
            continue
        for j in np.flatnonzero(crossed):

            def element(t, values=values, j=j):
                return float(values(t)[j])

            t_star, _, iterates, _ = locate_zero(
                element, t_prev, g_old[k][j], solver.t, g_new[k][j]
            )
            y_star, yp_star = solver.interpolate(t_star)
            found.append(
                _Crossing(k, t_star, y_star, yp_star, np.array([j]), int(j), iterates, False)
            )
    found.sort(key=lambda c: c.t)
    result = []
    for c in found:
        result.append(c)
        if c.restarts:
            break
    return result


def _terminal_past_zero(switches, g0) -> tuple[int, int] | None:
    """(switch, element) of the first directed terminal switch that is strictly past its
    zero (on the side its direction reports) at the start, or None."""
    for k, sw in enumerate(switches):
        if not sw.terminal:
            continue
        past = np.flatnonzero((sw.direction != 0) & (-sw.direction * g0[k] < 0.0))
        if past.size:
            return k, int(past[0])
    return None


def _old_side(c: _Crossing, g_a: np.ndarray) -> float:
    """The latest time of the located element's iterates before ``c.t`` on the side of
    its value ``g_a`` at the start of the step (the old-side end of the final bracket,
    a few ulp before the crossing); ``c.t`` when g is exactly zero there (the search
    stopped on the zero itself) or when there is none (a crossing at the step's start)."""
    if any(t == c.t and v == 0.0 for t, v in c.iterates):
        return c.t
    old = np.sign(g_a[c.located])
    return max((t for t, v in c.iterates if t < c.t and np.sign(v) == old), default=c.t)


def _predicted_crossing(solver, kinks, t_a, t_b):
    """Earliest crossing of a restart switch on the predictor polynomial in (t_a, t_b].

    The predictor is the last accepted step's Nordsieck polynomial extrapolated
    (``solver.interpolate`` beyond solver.t); t_a is the solver's time. Returns the
    located time, or None when no restart switch changes sign on the prediction.
    """
    best = None
    for sw in kinks:
        g_a = sw.value(t_a, solver.y, solver.yp)
        y_b, yp_b = solver.interpolate(t_b)
        try:
            g_b = sw.value(t_b, y_b, yp_b)
        except DAEError:  # the prediction is outside the switch's domain
            continue
        if not sw.crossed(g_a, g_b).any():
            continue

        def values(t, sw=sw):
            y, yp = solver.interpolate(t)
            return sw.value(t, y, yp)

        try:
            t_c = locate_earliest(values, sw, t_a, g_a, t_b, g_b)[0]
        except DAEError:
            continue
        if t_c <= t_a:  # a missed crossing (SwitchFunction.missed): acted on after the step
            continue
        best = t_c if best is None else min(best, t_c)
    return best


def _run_action(sw, c: _Crossing, n: int):
    """The switch's action at the crossing: new (y, yp), checked, or the located state."""
    if sw.action is None:
        return c.y, c.yp
    args = (c.t, c.y.copy(), c.yp.copy()) + ((c.which.copy(),) if sw.vector else ())
    changed = call_user(sw.action, f"the action of switch {sw.name!r}", c.t, *args)
    if changed is None:
        return c.y, c.yp
    try:
        y_new, yp_new = changed
        y_new = np.asarray(y_new, dtype=float)
        yp_new = np.asarray(yp_new, dtype=float)
    except (TypeError, ValueError):
        raise DAEError(
            f"The action of switch {sw.name!r} returned {type(changed).__name__}; it must "
            f"return None or a pair (y, yp) of arrays of {n} numbers."
        ) from None
    if y_new.shape != (n,) or yp_new.shape != (n,):
        raise DAEError(
            f"The action of switch {sw.name!r} returned arrays of shapes {y_new.shape} and "
            f"{yp_new.shape}; it must return None or (y, yp) of shape ({n},) each."
        )
    if not (np.all(np.isfinite(y_new)) and np.all(np.isfinite(yp_new))):
        raise DAEError(f"The action of switch {sw.name!r} returned NaN or inf at t = {c.t:.10g}.")
    return y_new, yp_new


class _Grid:
    """Output times, consumed in order: an array (``t_eval``) or the lazy grid
    t0 + k dt, k = 0, 1, ..., closed by t_end (``output_interval``): nothing of
    the size of the grid is allocated."""

    def __init__(self, t_eval=None, interval=None, t0=0.0, t_end=0.0):
        self.array = t_eval
        self.interval = interval
        self.t0, self.t_end = t0, t_end
        self.k = 0
        self.done = False

    def peek(self) -> float | None:
        if self.array is not None:
            return float(self.array[self.k]) if self.k < len(self.array) else None
        if self.done:
            return None
        t = self.t0 + self.k * self.interval
        if t >= self.t_end - 1e-9 * (self.t_end - self.t0):
            return self.t_end
        return t

    def advance(self) -> None:
        if self.array is None and self.peek() == self.t_end:
            self.done = True
        self.k += 1


class _Output:
    """Collects output points (and dense-output pieces) and forwards them to the callback.

    Without output times every accepted step is an output point, and after a
    restart (tstop or located switch) the state right after it is a second point
    at the same t. With output times (``t_eval`` or ``output_interval``) both
    sides of every restart are output points as well (two points at the same t), so
    that integrals over the output are exact across the discontinuity.
    ``keep=False``: points go to the callback only and nothing grows with them.
    """

    def __init__(self, grid, callback, dense_output, t0, keep=True):
        self.grid = grid
        self.callback = callback
        self.dense = dense_output
        self.keep = keep
        self.t, self.y, self.yp = [], [], []
        self.history = []
        self.pieces = []
        self.t0 = t0
        self.last_t = None
        self.left = None  # (t, y, yp) at the end of the last step, for a restart there

    def _emit(self, t, y, yp):
        if self.keep:
            self.t.append(t)
            self.y.append(y.copy() if type(y) is np.ndarray else np.array(y))
            self.yp.append(yp.copy() if type(yp) is np.ndarray else np.array(yp))
        self.last_t = t
        if self.callback is not None:
            call_user(self.callback, "the output callback", t, t, y, yp)

    def initial(self, t, y, yp):
        if self.grid is None:
            self._emit(t, y, yp)
            return
        te = self.grid.peek()
        while te is not None and te <= t:
            self._emit(te, y, yp)
            self.grid.advance()
            te = self.grid.peek()

    def step(self, solver, t_prev, t_until):
        """Output of the step just taken, on (t_prev, t_until] (t_until <= solver.t)."""
        self.history.append((t_until, t_until - t_prev, solver.q_used))
        if self.dense:
            t_ref, h, q, z = solver.nordsieck_snapshot()
            self.pieces.append((t_until, t_ref, h, q, z))
        if t_until == solver.t:
            self.left = (t_until, solver.y, solver.yp)
        else:
            self.left = (t_until, *solver.interpolate(t_until))
        if self.grid is None:
            self._emit(*self.left)
            return
        te = self.grid.peek()
        while te is not None and te <= t_until:
            if te == t_until:
                self._emit(*self.left)
            else:
                self._emit(te, *solver.interpolate(te))
            self.grid.advance()
            te = self.grid.peek()

    def final(self):
        """The state at the end of the last step as the last output point (a run stopped
        by a terminal switch between output times)."""
        if self.left is not None and self.last_t != self.left[0]:
            self._emit(*self.left)

    def restart(self, t, y, yp):
        """After a discontinuity at t: the state right after it, an extra point at the
        same t (with output times, preceded by the state right before it)."""
        if self.grid is not None and self.last_t != t and self.left is not None:
            self._emit(*self.left)
        self._emit(t, y, yp)

    def arrays(self, n):
        if not self.t:
            return np.empty(0), np.empty((n, 0)), np.empty((n, 0))
        return np.array(self.t), np.array(self.y).T, np.array(self.yp).T

    def step_history(self):
        return np.array(self.history, dtype=float).reshape(-1, 3)

    def solution(self):
        return NordsieckSolution(self.pieces, self.t0) if self.dense and self.pieces else None


class _Problem:
    """Validated problem data; every check raises DAEError with a plain message."""

    @classmethod
    def validate(
        cls,
        residual,
        t_span,
        y0,
        yp0,
        algebraic,
        quadrature,
        rtol,
        atol,
        max_order,
        h0,
        max_step,
        sparsity,
        events,
        tstops,
        t_eval,
        names,
        equation_names=None,
    ):
        p = cls()
        if not callable(residual):
            raise DAEError("residual must be a function F(t, y, yp) -> array.")
        span = _real_array(t_span, "t_span").ravel()
        if span.size != 2:
            raise DAEError(f"t_span must be two numbers (t0, t_end); got {t_span!r}.")
        t0, t_end = float(span[0]), float(span[1])
        if not (np.isfinite(t0) and np.isfinite(t_end)) or t_end <= t0:
            raise DAEError(f"t_span must be finite with t_end > t0; got ({t0}, {t_end}).")
        p.t0, p.t_end = t0, t_end
        p.y0 = _vector(y0, "y0")
        p.n = n = p.y0.size
        p.yp0 = np.zeros(n) if yp0 is None else _vector(yp0, "yp0", n)
        if not (_is_real(rtol) and np.isfinite(rtol) and 0.0 < rtol < 1.0):
            raise DAEError(f"rtol must be one number between 0 and 1; got {rtol!r}.")
        a = _real_array(atol, "atol")
        if a.ndim == 0:
            a = np.full(n, float(a))
        if a.shape != (n,) or not np.all(np.isfinite(a)) or np.any(a <= 0.0):
            raise DAEError(
                f"atol must be a positive number or {n} positive numbers; got shape {a.shape} "
                f"with minimum {np.min(a) if a.size else 'n/a'}."
            )
        p.atol = a
        if max_order not in (1, 2, 3, 4, 5):
            raise DAEError(f"max_order must be 1, 2, 3, 4 or 5; got {max_order!r}.")
        if h0 is not None and not (_is_real(h0) and np.isfinite(h0) and h0 > 0):
            raise DAEError(f"h0 must be a positive number; got {h0!r}.")
        if not (_is_real(max_step) and max_step > 0):
            raise DAEError(f"max_step must be positive; got {max_step!r}.")
        p.algebraic = _mask(algebraic, n, "algebraic")
        p.quadrature = _mask(quadrature, n, "quadrature")
        p.sparsity = sparsity
        if sparsity is not None and getattr(sparsity, "shape", None) != (n, n):
            raise DAEError(
                f"jac_sparsity must have shape ({n}, {n}); got {getattr(sparsity, 'shape', None)}."
            )
        p.tstops = sorted(float(s) for s in np.atleast_1d(_real_array(tstops, "tstops")))
        if any(not np.isfinite(s) for s in p.tstops):
            raise DAEError("tstops must be finite times.")
        p.t_eval = None
        if t_eval is not None:
            te = _real_array(t_eval, "t_eval").ravel()
            if not np.all(np.isfinite(te)):
                bad = np.flatnonzero(~np.isfinite(te))[:5].tolist()
                raise DAEError(f"t_eval holds NaN or inf at index(es) {bad}.")
            if np.any(np.diff(te) < 0) or te.size == 0:
                raise DAEError("t_eval must be a non-empty, increasing sequence of times.")
            if te[0] < t0 or te[-1] > t_end:
                raise DAEError(f"t_eval must lie within t_span [{t0}, {t_end}].")
            p.t_eval = te
        if names is not None and len(names) != n:
            raise DAEError(f"variable_names has {len(names)} names for {n} unknowns.")
        if equation_names is not None and len(equation_names) != n:
            raise DAEError(f"equation_names has {len(equation_names)} names for {n} equations.")
        for i, g in enumerate(events):
            SwitchFunction.wrap(g, i)
        return p


def _mask(v, n, what) -> np.ndarray | None:
    """A boolean mask of n entries from indices or a mask (None stays None)."""
    if v is None:
        return None
    arr = np.asarray(v)
    mask = np.zeros(n, dtype=bool)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise DAEError(f"{what} as a mask must have {n} entries; got {arr.shape}.")
        return arr.copy()
    if arr.size:
        if not np.issubdtype(arr.dtype, np.integer) or arr.min() < -n or arr.max() >= n:
            raise DAEError(
                f"{what} must hold indices in 0..{n - 1} or a boolean mask; got {arr!r}."
            )
        mask[arr] = True
    return mask


def _is_real(v) -> bool:
    """A real number (bool excluded), as Python or numpy scalar."""
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _real_array(v, what) -> np.ndarray:
    """v as a float array; strings, complex numbers, None or objects are refused."""
    try:
        raw = np.asarray(v)
    except (TypeError, ValueError):
        raise DAEError(f"{what} must be an array of real numbers.") from None
    if raw.dtype.kind not in "biuf":
        kinds = {"U": "strings", "S": "bytes", "c": "complex numbers", "O": "non-numbers"}
        got = kinds.get(raw.dtype.kind, f"values of type {raw.dtype}")
        raise DAEError(f"{what} must hold real numbers; it holds {got}.")
    return raw.astype(float)


def _vector(v, what, n=None) -> np.ndarray:
    arr = np.array(_real_array(v, what), dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise DAEError(f"{what} must be a one-dimensional array; got shape {arr.shape}.")
    if n is not None and arr.size != n:
        raise DAEError(f"{what} has {arr.size} entries but y0 has {n}.")
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.isfinite(arr))[:5].tolist()
        raise DAEError(f"{what} holds NaN or inf at index(es) {bad}.")
    return arr


__all__ = ["solve_dae", "nd"]


@functools.wraps(_solve_dae)
def solve_dae(residual, t_span, y0, yp0=None, **options):
    # one BLAS thread while a large system is integrated (dnasim.core.blas_threads)
    with one_blas_thread(int(np.size(y0))):
        return _solve_dae(residual, t_span, y0, yp0, **options)
