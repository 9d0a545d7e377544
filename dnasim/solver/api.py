"""``solve_dae``: validates the input (``problem.Problem``), builds the counted
residual and the iteration matrix, and runs the driver (``driver.Driver``: the BDF
stepper ``bdf.NordsieckBDF`` with its ``controller.StepController``, the tstops
``stops.Stops``, the switch crossings ``crossings``, the output ``output.Output``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np

from dnasim.core.blas_threads import one_blas_thread
from dnasim.core.errors import DAEError  # noqa: F401 (re-exported: dnasim.solver.api.DAEError)
from dnasim.solver import nordsieck as nd
from dnasim.solver.bdf import CountedResidual, SolverStats
from dnasim.solver.driver import MAX_RESTARTS_AT_ONE_TIME, Driver, wrap_switches
from dnasim.solver.linear_algebra import IterationMatrix
from dnasim.solver.problem import Problem
from dnasim.solver.result import DAEResult


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
    residual_for_columns: Callable | None = None,
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
    refine_output: bool = True,
    output_residual: tuple | None = None,
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
    residual_for_columns : optional partial-residual channel, with jac_sparsity:
        residual_for_columns(cols) -> F_cols(t, y, yp, f0), F at a point that differs
        from f0's only in the columns ``cols``, the rows that read none of them taken
        from f0 (a compiled plant's ``System.residual_for_columns``). A column group
        of the finite-difference Jacobian then costs the rows it touches, with the
        same matrix as from whole evaluations. Each call counts as one residual
        evaluation. None: whole evaluations.
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
    refine_output : at output points between steps, solve the algebraic variables
        (and y') from the interpolated differential ones when the step corrected an
        algebraic variable by more than its tolerance (``driver.Driver.refine``); the
        points are then as accurate as those at steps. False: the step's polynomial
        for every variable. The dense output ``result.sol`` is the polynomial always.
    output_residual : optional (residual, residual_for_columns) the output points
        between steps are re-solved with (``refine_output``): the same F as ``residual``
        (and the same partial channel, or None), for a residual whose evaluations are
        not pure functions of their arguments to the bit (a plant's property memos,
        warm-started from their last points): evaluated there instead of ``residual``,
        the output asked for does not change the steps taken
        (``System.residual_aside``). None: ``residual`` itself.

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
    problem = Problem.validate(
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
        residual_for_columns,
        output_interval,
    )
    stats = SolverStats()
    F = CountedResidual(residual, problem.n, stats)
    switches = wrap_switches(events)
    kinks = [sw for sw in switches if sw.kink and sw.restarts]
    side = None
    if kinks and jac is None:
        # finite differences stay on the side of every restart switch (linear_algebra)
        def side(t, y, yp):
            return np.concatenate([sw.value(t, y, yp) for sw in kinks])

    matrix = IterationMatrix(
        F,
        problem.n,
        jac,
        problem.sparsity,
        variable_names,
        equation_names,
        residual_for_columns=problem.residual_for_columns,
        side=side,
        quadrature=problem.quadrature,
    )
    options = {
        "rtol": rtol,
        "max_order": max_order,
        "h0": h0,
        "max_step": max_step,
        "calc_initial": calc_initial,
        "exclude_algebraic_from_error": exclude_algebraic_from_error,
        "callback": callback,
        "dense_output": dense_output,
        "max_steps": max_steps,
        "keep_output": keep_output,
        "refine_output": refine_output,
        "output_residual": output_residual,
    }
    return Driver(problem, F, matrix, stats, switches, options).run(throw=throw)


__all__ = ["MAX_RESTARTS_AT_ONE_TIME", "solve_dae", "nd"]


@functools.wraps(_solve_dae)
def solve_dae(residual, t_span, y0, yp0=None, **options):
    # one BLAS thread while a large system is integrated (dnasim.core.blas_threads)
    with one_blas_thread(int(np.size(y0))):
        return _solve_dae(residual, t_span, y0, yp0, **options)
