"""SUNDIALS IDA (scikit-sundae) as a second backend with dnasim's semantics:
``solve_ida`` returns a ``DAEResult`` like ``solve_dae``. Needs the optional
dependency ``scikit-sundae``. (``dnasim.testing.ida`` runs a bare residual
through IDA in one call; this driver adds time events, switches and restarts.)

The driver stops exactly at every tstop and re-initialises there, stops at
every switch crossing, runs the switch's action and re-initialises.
Re-initialisation is the caller's ``reinitialise(t, y, yp) -> (y, yp)``
(consistent y' and algebraic y with the differential y kept; for plants the
damped Newton of ``dnasim.start.consistent``, as in ``dnasim.run.backends.IDA``):
IDACalcIC fails on the large jumps a step of a boundary value causes.

``linsolver``: "dense", "sparse" (SuperLU_MT on ``jac_sparsity``) or "band":
IDA's band solver with the equations matched to the unknowns and both put in
reverse Cuthill-McKee order (``dnasim.solver.band.BandOrdering``, the ordering
dnasim's own band LU uses); the permutation is applied at the boundary to IDA
(residual, switches, results), so callers see the original order.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse


def solve_ida(
    residual,
    t_span,
    y0,
    yp0,
    *,
    algebraic,
    reinitialise,
    jac_sparsity=None,
    rtol=1e-6,
    atol=1e-8,
    max_order=4,
    max_step=np.inf,
    h0=None,
    events=(),
    tstops=(),
    t_eval=None,
    callback=None,
    linsolver=None,
    max_num_steps=100000,
    output_interval=None,
):
    """Integrate F(t, y, y') = 0 with IDA from t_span[0] to t_span[1]; returns a
    ``DAEResult``.

    Output points, as ``solve_dae``'s: ``t_eval`` (times [s], increasing, within
    t_span) or ``output_interval`` [s] (t0, t0 + dt, ..., t_end, generated as the run
    goes), not both; the values at an output time inside a step are IDA's own
    interpolation (IDAGetDky, through IDASolve in IDA_NORMAL mode: the step sequence is
    the one without output times). With output times both sides of every restart
    (tstop, switch) are output points too (two points at the same t, the state before
    and after). Without: every accepted step, and after a restart the state right
    after it at the same t. ``callback(t, y, yp)`` gets every output point in order.
    """
    try:
        from sksundae.ida import IDA
    except ImportError:
        raise ImportError(
            "the IDA backend needs scikit-sundae, an optional dependency: pip install 'dnasim[ida]'"
        ) from None

    from dnasim.solver.result import DAEResult

    t0, t_end = map(float, t_span)
    n = len(y0)
    algebraic = np.asarray(algebraic, dtype=bool)
    if linsolver is None:
        linsolver = "dense" if n < 200 or jac_sparsity is None else "sparse"
    # IDA sees the unknowns u = y[cols] and the equations F[rows]: for the band solver
    # the equations matched to the unknowns and both reverse-Cuthill-McKee ordered
    # (dnasim.solver.band), so that dF/du + cj dF/du' has kl, ku diagonals; identity
    # orders otherwise.
    rows = cols = np.arange(n)
    band = {}
    if linsolver == "band":
        from dnasim.solver.band import BandOrdering

        pattern = scipy.sparse.csc_matrix(jac_sparsity, dtype=float)
        ordering = BandOrdering.of(pattern)
        if ordering is None:
            raise ValueError("the sparsity pattern is structurally singular: no band ordering")
        rows, cols = ordering.rows, ordering.cols
        band = {"lband": ordering.kl, "uband": ordering.ku}

    def to_y(u):
        y = np.empty(n)
        y[cols] = u
        return y

    events = list(events)
    # Scalar switches count 1, vector switches (attribute ``size``) their size.
    sizes = [int(g.size) if hasattr(g, "size") else 1 for g in events]
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(int) if events else []
    n_events = int(sum(sizes))
    directions = [_directions(g, m) for g, m in zip(events, sizes, strict=True)]
    directions = np.concatenate(directions) if events else np.zeros(0)
    alg_idx = np.flatnonzero(algebraic[cols])
    stats = {"steps": 0, "residual_evals": 0, "restarts": 0}
    counter = [0]

    # The stop IDA is stepping to. A step that lands on it must see the residual at its
    # left limit (a boundary that steps there must still have its old value), as
    # dnasim's solver does; otherwise IDA meets the jump on the last step and creeps
    # towards the tstop with ever smaller steps.
    current_stop = [np.inf]

    def resfn(t, u, up, res):
        counter[0] += 1
        if t >= current_stop[0]:
            t = np.nextafter(current_stop[0], -np.inf)
        res[:] = residual(t, to_y(u), to_y(up))[rows]

    def make(calc):
        opts = dict(
            rtol=rtol,
            atol=(np.asarray(atol, dtype=float) * np.ones(n))[cols],
            algebraic_idx=alg_idx,
            max_order=min(max_order, 5),
            max_num_steps=max_num_steps,
            linsolver=linsolver,
            **band,
        )
        if linsolver == "sparse":
            opts["sparsity"] = jac_sparsity
        if np.isfinite(max_step):
            opts["max_step"] = max_step
        if h0:
            opts["first_step"] = h0
        if calc:
            opts["calc_initcond"] = "yp0"
            opts["calc_init_dt"] = 1e-3 * (t_end - t0)
        if events:

            def eventsfn(t, u, up, out):
                y, yp = to_y(u), to_y(up)
                for g, k, m in zip(events, offsets, sizes, strict=True):
                    if hasattr(g, "size"):
                        out[k : k + m] = g(t, y, yp)
                    else:
                        out[k] = g(t, y, yp)

            eventsfn.terminal = [True] * n_events
            eventsfn.direction = [int(d) for d in directions]
            opts["eventsfn"] = eventsfn
            opts["num_events"] = n_events
        return IDA(resfn, **opts)

    from dnasim.core.errors import DAEError
    from dnasim.solver.output import OutputGrid

    if t_eval is not None:
        t_eval = np.asarray(t_eval, dtype=float).ravel()
        if t_eval.size == 0 or not np.all(np.isfinite(t_eval)) or np.any(np.diff(t_eval) < 0):
            raise DAEError("t_eval must be a non-empty, increasing sequence of finite times.")
        if t_eval[0] < t0 or t_eval[-1] > t_end:
            raise DAEError(f"t_eval must lie within t_span [{t0}, {t_end}].")
        if output_interval is not None:
            raise DAEError("give t_eval or output_interval, not both.")
    if output_interval is not None and not (np.isfinite(output_interval) and output_interval > 0):
        raise DAEError(f"output_interval must be a positive number; got {output_interval!r}.")
    grid = OutputGrid.of(t_eval, output_interval, t0, t_end)
    ts, ys, yps, log, hist = [], [], [], [], []

    def emit(t_out, y_out, yp_out):
        ts.append(t_out)
        ys.append(np.array(y_out, float))
        yps.append(np.array(yp_out, float))
        if callback:
            callback(t_out, ys[-1], yps[-1])

    def interpolated(t_out):
        """(y, yp) at t_out inside IDA's last step: IDASolve in IDA_NORMAL mode, which
        interpolates there without stepping. Right after a root return IDA hands that
        root over once more first (its close-root check), so it is asked again."""
        for _ in range(3):
            r = solver.step(t_out, method="normal", tstop=None)
            if r.success and float(np.atleast_1d(r.t)[-1]) == t_out:
                return to_y(np.array(r.y).reshape(-1)[-n:]), to_y(np.array(r.yp).reshape(-1)[-n:])
        raise DAEError(f"IDA could not interpolate its solution at the output time t = {t_out} s")

    t, y, yp = t0, np.array(y0, float), np.array(yp0, float)
    if grid is None:
        emit(t, y, yp)
    else:
        while grid.peek() is not None and grid.peek() <= t:
            emit(grid.peek(), y, yp)
            grid.advance()
    stops = sorted(s for s in tstops if t0 < s < t_end) + [t_end]
    solver = make(False)
    solver.init_step(t, y[cols], yp[cols])
    success, message = True, "reached t_end"
    while t < t_end * (1 - 1e-15) - 1e-300:
        stop = next(s for s in stops if s > t + 1e-12 * max(1.0, abs(t)))
        current_stop[0] = stop if stop < t_end else np.inf
        res = solver.step(stop, method="onestep", tstop=stop)
        if not res.success:
            success, message = False, res.message
            break
        t_new = float(np.atleast_1d(res.t)[-1])
        if t_new <= t:
            # after an interpolation IDA first hands its last step's end over again
            continue
        u = np.array(res.y).reshape(-1)[-n:] if np.ndim(res.y) == 1 else np.array(res.y)[-1]
        up = np.array(res.yp).reshape(-1)[-n:] if np.ndim(res.yp) == 1 else np.array(res.yp)[-1]
        y, yp = to_y(u), to_y(up)
        hist.append((t_new, t_new - t, 0))
        t = t_new
        stats["steps"] += 1
        if grid is None:
            emit(t, y, yp)
        else:
            while grid.peek() is not None and grid.peek() <= t:
                t_out = grid.peek()
                if t_out == t:
                    emit(t, y, yp)
                else:
                    try:
                        emit(t_out, *interpolated(t_out))
                    except DAEError as exc:
                        success, message = False, str(exc)
                        break
                grid.advance()
            if not success:
                break
        y_left, yp_left = y.copy(), yp.copy()  # the state before a jump at t
        fired = res.i_events is not None and np.any(np.asarray(res.i_events) != 0)
        at_stop = abs(t - stop) <= 1e-10 * max(1.0, abs(stop))
        if fired:
            ie = np.asarray(res.i_events).reshape(-1, n_events)[-1]
            for i, (g, k, m) in enumerate(zip(events, offsets, sizes, strict=True)):
                which = np.flatnonzero(ie[k : k + m])
                if which.size == 0:
                    continue
                vector = hasattr(g, "size")
                for j in which:
                    name = g.names[j] if vector else getattr(g, "name", str(i))
                    log.append(
                        {"event": i, "name": name, "element": int(j), "iterates": [], "t": t}
                    )
                act = getattr(g, "action", None)
                if act is not None:
                    out = act(t, y, yp, which) if vector else act(t, y, yp)
                    if out is not None:
                        y, yp = out
        if fired or (at_stop and stop < t_end):
            # consistent values after the jump, keeping the differential variables
            stats["restarts"] += 1
            if grid is not None and (not ts or ts[-1] != t):
                emit(t, y_left, yp_left)  # both sides of the jump are output points
            y, yp = reinitialise(t, y, yp)
            emit(t, y, yp)  # the state right after it, at the same t
            solver = make(False)
            solver.init_step(t, y[cols], yp[cols])
    stats["residual_evals"] = counter[0]
    return DAEResult(
        t=np.array(ts),
        y=np.array(ys).reshape(-1, n).T,
        yp=np.array(yps).reshape(-1, n).T,
        success=success,
        status=0 if success else -1,
        message=message,
        t_events=[],
        y_events=[],
        event_log=log,
        stats=stats,
        step_history=np.array(hist).reshape(-1, 3),
        sol=None,
    )


def _directions(g, size) -> np.ndarray:
    """A switch's direction (-1, 0, +1) for each of its ``size`` elements."""
    d = getattr(g, "direction", None)
    return np.broadcast_to(np.sign(np.asarray(0 if d is None else d, dtype=float)), (size,))
