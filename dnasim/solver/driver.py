"""The driver of ``solve_dae``: steps the BDF stepper from t0 to t_end.

Its pieces, each with one job (as scipy's ``OdeSolver`` and diffrax keep them):

- the stepper ``bdf.NordsieckBDF`` (one accepted step at a time, its hooks given
  at construction) with its step and order controller ``controller.StepController``;
- ``stops.Stops``: the tstops, landed on exactly;
- ``crossings``: the switch crossings of a step located, logged (``EventLog``) and
  acted on; ``Driver.handle_crossing`` is the one place a located crossing is
  handled, ``Driver.restart`` the one restart path (after a switch or a tstop);
- ``output.Output``: the output points, the callback and the dense output.

Around each step the driver

- never steps past a tstop: the step lands on it exactly, with the residual
  evaluated at the left limit, and integration restarts there at order 1 from
  values made consistent at the right limit; a switch that the jump carried across
  its zero fires at the tstop itself;
- watches the switch functions; on a sign change it locates the zero on the
  step's interpolant, cuts the step there, runs the switch's action, makes the
  state consistent again and restarts at order 1 (the seed's Fig. 10.7); several
  switches in one step: the earliest wins; a vector switch brackets only the
  elements that changed sign and locates the earliest;
- emits the output points (every step, or the output times). A point between two
  steps takes its differential variables from the step's Nordsieck polynomial and,
  when the step corrected an algebraic variable by more than its tolerance, its
  algebraic variables (and y') solved from them (``Driver.refine``), each value then
  kept solved or interpolated by their estimated errors (``Driver._choose``); not
  solved where no value can gain from it (``Driver._over``, ``Driver._gains``).
"""

from __future__ import annotations

import functools

import numpy as np

from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver import nordsieck as nd
from dnasim.solver.bdf import NordsieckBDF
from dnasim.solver.crossings import (
    Crossing,
    EventLog,
    locate_crossings,
    old_side,
    predicted_crossing,
    run_action,
    terminal_past_zero,
)
from dnasim.solver.events import SwitchFunction
from dnasim.solver.initial import detect_algebraic, solve_consistent
from dnasim.solver.linear_algebra import IterationMatrix
from dnasim.solver.output import Output, OutputGrid
from dnasim.solver.refine import AlgebraicRefiner
from dnasim.solver.residual import CountedResidual
from dnasim.solver.result import DAEResult
from dnasim.solver.stops import Stops

MAX_RESTARTS_AT_ONE_TIME = 50
#: ``Driver.refine`` keeps the interpolated point when no algebraic variable was corrected
#: by more than this many tolerance units in the step (benchmarks/refine_cost.py sets it
#: to -inf for its reference)
REFINE_SKIP_BELOW = 1.0
#: keep each value between steps solved or interpolated by their estimated errors
#: (``Driver._choose``); False: the solved ones (benchmarks/refine_cost.py's ``solve``)
CHOOSE = True
#: ... both estimates with this many tolerance units added (the solve's convergence)
CHOOSE_FLOOR = 0.1
#: decide before the solve whether any value at the point can gain from it
#: (``Driver._over``, ``Driver._gains``); False: solve every point, then choose
#: (benchmarks/refine_cost.py's ``choose0``)
PRESKIP = True
#: ... none can where the solve's first Newton iteration moves none by more than this
#: many tolerance units (benchmarks/README.md: 1.0 and 0.3 measured)
PRESKIP_WITHIN = 0.5


class Driver:
    """One integration of a validated ``Problem`` (``run`` returns its DAEResult).

    ``F``: the counted residual; ``matrix``: the ``IterationMatrix``; ``options``:
    the stepper's and the driver's settings (``solve_dae``'s keywords).
    """

    def __init__(self, problem, F, matrix, stats, switches, options: dict):
        self.problem = problem
        self.F = F
        self.matrix = matrix
        self.stats = stats
        self.switches = switches
        self.opt = options
        self.t0, self.t_end = problem.t0, problem.t_end
        self.kinks = [sw for sw in switches if sw.kink and sw.restarts]
        grid = OutputGrid.of(problem.t_eval, problem.output_interval, self.t0, self.t_end)
        self.out = Output(
            grid,
            options["callback"],
            options["dense_output"],
            self.t0,
            keep=options["keep_output"],
            refine=self.refine if options.get("refine_output", True) else None,
        )
        self._refiner = None  # ``refine``'s AlgebraicRefiner, made at first use
        self._estimate = None  # (step, propagated Delta, matrix, solved): ``_step_estimate``
        # ``_choose``'s counts: [algebraic y kept interpolated, differential y' kept
        # interpolated, points chosen at]
        self.stats_chosen = [0, 0, 0]
        # the points between steps not solved: [the solve would move no value by more
        # than PRESKIP_WITHIN of its tolerance (``_over``), the choice would keep those
        # interpolated (``_gains``)]
        self.stats_skipped = [0, 0]
        self.events = EventLog(switches)
        self.stops = Stops(problem.tstops, self.t0, self.t_end)
        self.status, self.message = 0, "The solver reached the end of the interval."
        self.restarts_here, self.last_restart_t = 0, None
        self.solver = None
        self.algebraic = None
        self.g_old = None  # the switch functions' values at the solver's time

    # -- the result --------------------------------------------------------------------
    def result(self, success, status, message) -> DAEResult:
        n = self.problem.n
        t_events, y_events = self.events.arrays(n)
        return DAEResult(
            *self.out.arrays(n),
            success,
            status,
            message,
            t_events,
            y_events,
            self.events.entries,
            self.stats.as_dict(),
            self.out.step_history(),
            self.out.solution(),
        )

    # -- consistent values -------------------------------------------------------------
    def consistent(self, t, y, yp, what, h_scale=None):
        """(y, yp) solved for F(t, y, yp) = 0 with the differential y kept."""
        pb, opt = self.problem, self.opt
        yp = np.array(yp, dtype=float)
        yp[self.algebraic] = 0.0  # not determined by F; the predictor starts them flat
        return solve_consistent(
            self.F,
            t,
            y,
            yp,
            self.algebraic,
            rtol=opt["rtol"],
            atol=pb.atol,
            h_scale=self.ic_scale if h_scale is None else h_scale,
            matrix=self.matrix,
            variable_names=pb.names,
            equation_names=pb.equation_names,
            what=what,
        )

    def _reinitialize(self, t, y, yp, h):
        """The stepper's hook after repeated failures in one step."""
        return self.consistent(t, y, yp, "the values at a step that failed repeatedly", h_scale=h)

    def refine(self, t, y, yp):
        """An output point (y, yp) interpolated at t inside the last step, with its
        algebraic variables solved for: F(t, y, y') = 0 for the algebraic y and the
        differential y', the differential y kept as interpolated (``solve_consistent``,
        as at a restart; the algebraic y' stay interpolated, F does not read them).

        The step's polynomial is exact at the step's ends only. An algebraic variable
        that is a nonlinear function of the states (a valve's flow through a pressure
        ramp, a node's enthalpy when a feed starts) is interpolated by the polynomial
        through its values at the steps, which does not follow the function between
        them: a straight line through a square-root law in a plant without storage,
        where the whole ramp is one step (50 % off, issue 20), a node enthalpy of
        -3e5 J/kg where the feed starts in plants/msl_drum_boiler.toml (NaN in the
        node temperature). Skipped (the interpolated point returned) when no
        algebraic variable was corrected by more than its tolerance in the step
        (``NordsieckBDF.algebraic_correction`` <= 1): the polynomial then follows
        them to the tolerance. When the solve fails the interpolated point is kept
        (``stats["output_solve_failures"]``). ``refine.AlgebraicRefiner`` with an
        iteration matrix of its own: the integrator's is left as it is, so the steps
        do not depend on the output. The points of one step (named by the count of
        accepted steps) share the refiner's warm start (``refine.WARM_START``).

        Before the solve (``PRESKIP``): the interpolated point is kept where the solve's
        first Newton iteration moves no value by more than PRESKIP_WITHIN of its
        tolerance (``_over``), or where the values it moves more would all be kept
        interpolated by the choice (``_gains``): tests/plants/pump_shutoff.toml 10707 ->
        1645 residual evaluations of the run, the same TRUE deviations
        (benchmarks/README.md).
        """
        solver = self.solver
        if solver.algebraic_correction <= REFINE_SKIP_BELOW:
            return y, yp
        pre = self._interpolation_estimate(t) if CHOOSE and PRESKIP else None
        if self._refiner is None:
            m = self.matrix
            F, F_cols = self.F, self.problem.residual_for_columns
            aside = self.opt.get("output_residual")
            if aside is not None:  # the same F, leaving the integration's path alone
                F = CountedResidual(aside[0], self.problem.n, self.stats)
                F_cols = aside[1] if F_cols is not None else None
            matrix = IterationMatrix(
                F,
                self.problem.n,
                m.jac,
                self.problem.sparsity,
                m.names,
                m.equation_names,
                residual_for_columns=F_cols,
                side=m.side,
                quadrature=m.quadrature,  # the same pattern (``refine`` splices columns)
            )
            self._refiner = AlgebraicRefiner(
                F,
                self.algebraic,
                self.opt["rtol"],
                self.problem.atol,
                matrix,
                self.problem.names,
                self.problem.equation_names,
                self.stats,
                source=m,
            )
        start = None
        if pre is not None:
            over, start = self._over(t, y, yp)
            if not over.any():
                self.stats_skipped[0] += 1
                return y, yp
            if not self._gains(t, y, yp, pre, over):
                self.stats_skipped[1] += 1
                return y, yp
        try:
            y_new, yp_new = self._refiner(
                t, y, yp, solver.h_used, step=self.stats.steps, start=start
            )
        except DAEError:
            self.stats.output_solve_failures += 1
            return y, yp
        self.stats.output_solves += 1
        if CHOOSE:
            return self._choose(t, y, yp, y_new, yp_new)
        return y_new, yp_new

    def _choose(self, t, y, yp, y_new, yp_new):
        """Per value, the solved one (y_new, yp_new) or the interpolated one (y, yp),
        whichever has the smaller estimated error at t = t_n + s h of the step:

        - interpolated: the polynomial's error, a Delta in y and b Delta / h in y'
          (``nordsieck.interpolation_error(q, s)``, Delta = y_n - y_pred of the step);
        - solved: the differential y's share of that error carried through the solve,
          (dy_a, dy'_d) = -M^-1 (F(y + dx) - F(y)) with dx = a_max Delta_d, the largest
          in the step (``AlgebraicRefiner.propagate``: once a step, at its first solved
          point; a fresh matrix there where the point needed ``solve_consistent``),
          times |a| / a_max at the point.

        Both with CHOOSE_FLOOR of the tolerance added (the solve's and the corrector's
        own convergence; ties keep the solved value). A linear algebraic relation gives
        the two the same value and the same estimate; they part where the variable is a
        nonlinear function of the states or of t: a valve's square-root law through a
        ramp inside the step (the solved one kept), a flow at the flat top of a pump
        curve at shut-off, LAM times more sensitive to the states than it changes along
        the solution (the interpolated one kept; tests/test_output_between_steps.py).
        Without Delta or an estimate (F not finite at y + dx, a singular matrix) the
        solved values are returned.
        """
        pre = self._interpolation_estimate(t)
        if pre is None:
            return y_new, yp_new
        a, b, amax, delta = pre
        h = self.solver.h_used
        du = self._step_estimate(t, y_new, yp_new)
        if du is None:
            return y_new, yp_new
        tol = self.opt["rtol"] * np.abs(y_new) + self.problem.atol
        use_y, use_p = self._interpolated_better(a, b, amax, h, delta, du, tol)
        self.stats_chosen[0] += int(np.count_nonzero(use_y))
        self.stats_chosen[1] += int(np.count_nonzero(use_p))
        self.stats_chosen[2] += 1
        if not (use_y.any() or use_p.any()):
            return y_new, yp_new
        return np.where(use_y, y, y_new), np.where(use_p, yp, yp_new)

    def _step_estimate(self, t, y, yp, solved=True):
        """The states' share of the step's interpolation error carried through the solve
        (``_choose``), once a step: -M^-1 (F(y + dx) - F(y)), dx = a_max Delta_d, at the
        step's first point that asks (``solved`` False: (y, yp) interpolated, before a
        solve, ``_gains``; True: solved) with the refiner's matrix. One formed before a
        solve is formed again after a solve that changed the matrix (a fresh one or a
        splice: the kept one no longer served). None where it cannot be formed."""
        step, m = self.stats.steps, self._refiner.matrix
        est = self._estimate
        if est is not None and est[0] == step and (est[3] or not solved or est[2] is m.matrix):
            return est[1]
        solver = self.solver
        amax = nd.largest_interpolation_error(solver.q_used)
        dx = np.where(self.algebraic, 0.0, solver.step_delta) * amax
        du = self._refiner.propagate(t, y, yp, dx, solver.h_used)
        self._estimate = (step, du, m.matrix, solved) if du is not None else None
        return du

    def _interpolated_better(self, a, b, amax, h, delta, du, tol):
        """(algebraic y, differential y') where the interpolated value has the smaller
        estimated error (``_choose``; CHOOSE_FLOOR of the tolerance added to both)."""
        alg = self.algebraic
        r = abs(a) / amax
        e_int_y = abs(a) * np.abs(delta) + CHOOSE_FLOOR * tol
        e_res_y = r * np.abs(du[0]) + CHOOSE_FLOOR * tol
        e_int_p = abs(b) / h * np.abs(delta) + CHOOSE_FLOOR * tol / h
        e_res_p = r * np.abs(du[1]) + CHOOSE_FLOOR * tol / h
        return alg & (e_int_y < e_res_y), ~alg & (e_int_p < e_res_p)

    def _interpolation_estimate(self, t):
        """(a, b, amax, delta) at the point t of the last step: the polynomial's error
        coefficients there and their largest |a| in the step
        (``nordsieck.interpolation_error``), and the step's Delta; None without it."""
        solver = self.solver
        delta = solver.step_delta
        if delta is None:
            return None
        q = solver.q_used
        a, b = nd.interpolation_error(q, (t - solver.t) / solver.h_used)
        return a, b, nd.largest_interpolation_error(q), delta

    def _over(self, t, y, yp):
        """(over, start) at the point (y, yp) interpolated at t: ``over``, the values
        the solve would move by more than PRESKIP_WITHIN of their tolerance, estimated
        by the solve's first Newton iteration with the refiner's kept matrix (from its
        warm start; ``AlgebraicRefiner.first_update``; to first order the solved value
        less the interpolated one, d): |d| > PRESKIP_WITHIN (rtol |y| + atol) for an
        algebraic y, h |d| for a differential y'; ``start``: that iteration's start and
        residual, handed to the solve (the check costs a back-substitution). Without a
        kept matrix or a finite residual every value is over and ``start`` None.

        The polynomial's own estimate |a Delta| was measured to be less reliable for
        this: m = tanh(50 (x - 1/2)) interpolated 14 tolerance units off F where |a
        Delta| said 1 (tests/test_output_between_steps.py; with the update: 0.94)."""
        first = self._refiner.first_update(t, y, yp, step=self.stats.steps)
        if first is None:
            return np.ones(y.shape, dtype=bool), None
        start, d = first
        tol = self.opt["rtol"] * np.abs(y) + self.problem.atol
        e = np.where(self.algebraic, np.abs(d[0]), self.solver.h_used * np.abs(d[1]))
        return e > PRESKIP_WITHIN * tol, start

    def _gains(self, t, y, yp, pre, over) -> bool:
        """Before the solve at the point (y, yp) interpolated at t: can any value gain
        from it? Only one the solve moves by more than its tolerance (``over``,
        ``_over``) and which the choice would then keep solved: the states' propagated
        error (``_step_estimate``, formed here from the interpolated point, once a step,
        with the refiner's kept matrix) below its interpolation error (``pre``,
        ``_interpolation_estimate``). For an algebraic y that comparison is the same at
        every point of the step (both estimates scale with |a|). True (solve) where the
        estimate cannot be formed."""
        a, b, amax, delta = pre
        du = self._step_estimate(t, y, yp, solved=False)
        if du is None:
            return True
        h = self.solver.h_used
        tol = self.opt["rtol"] * np.abs(y) + self.problem.atol
        use_y, use_p = self._interpolated_better(a, b, amax, h, delta, du, tol)
        return bool(np.any(over & ~(use_y | use_p)))

    # -- set-up ------------------------------------------------------------------------
    def _start(self):
        """Masks, consistent initial values and the stepper; (y, yp) at t0."""
        pb, opt, F, t0 = self.problem, self.opt, self.F, self.t0
        y, yp = pb.y0, pb.yp0
        try:
            F(t0, y, yp)
        except ResidualDomainError as exc:
            raise DAEError(
                f"The residual cannot be evaluated at the initial values: {exc}"
            ) from None
        algebraic = pb.algebraic
        if algebraic is None:
            algebraic = detect_algebraic(F, t0, y, yp, self.matrix)
        self.algebraic = algebraic
        error_mask = np.ones(pb.n)
        if opt["exclude_algebraic_from_error"]:
            error_mask[algebraic] = 0.0
        norm_mask = np.ones(pb.n)  # Newton's convergence norm
        if pb.quadrature is not None:
            error_mask[pb.quadrature] = 0.0
            norm_mask[pb.quadrature] = 0.0
        span = self.t_end - t0
        h0, max_step = opt["h0"], opt["max_step"]
        self.ic_scale = h0 if h0 is not None else min(1e-3 * span, max_step)
        if opt["calc_initial"]:
            y, yp = self.consistent(t0, y, yp, "the initial values")
        self.solver = NordsieckBDF(
            F,
            t0,
            y,
            yp,
            rtol=opt["rtol"],
            atol=pb.atol,
            max_order=opt["max_order"],
            h0=h0,
            max_step=max_step,
            error_mask=error_mask,
            norm_mask=norm_mask,
            algebraic=algebraic,
            matrix=self.matrix,
            stats=self.stats,
            t_scale=span,
            names=pb.names,
            equation_names=pb.equation_names,
            reinitialize=self._reinitialize,
            predicted_crossing=(
                functools.partial(predicted_crossing, self.kinks) if self.kinks else None
            ),
            track_algebraic_correction=self.out.refine is not None,
        )
        return y, yp

    # -- the run -----------------------------------------------------------------------
    def run(self, throw: bool = False) -> DAEResult:
        try:
            if self._begin():
                while self.solver.t < self.t_end:
                    if self.stats.steps >= self.opt["max_steps"]:
                        raise DAEError(
                            f"The solver took {self.opt['max_steps']} steps and reached only "
                            f"t = {self.solver.t:.10g}; raise max_steps or check the model for "
                            "fast oscillations."
                        )
                    if self.step():
                        break
        except DAEError as exc:
            result = self.result(False, -1, str(exc))
            if not throw and self.solver is not None:  # the integration had started
                return result
            error = DAEError(str(exc))
            error.result = result
            raise error from exc.__cause__
        except KeyboardInterrupt as exc:
            # Ctrl-C: hand the caller what was computed (it may write it to disk).
            t_reached = self.solver.t if self.solver is not None else self.t0
            exc.result = self.result(False, -2, f"Interrupted at t = {t_reached:.10g}.")
            raise
        return self.result(True, self.status, self.message)

    def _begin(self) -> bool:
        """Start at t0; False when a terminal switch is already past its zero there."""
        y, yp = self._start()
        t0, switches = self.t0, self.switches
        self.g_old = [sw.value(t0, y, yp) for sw in switches]
        past = terminal_past_zero(switches, self.g_old)
        if past is not None:
            # a limit already crossed at the start: the run cannot begin (no output)
            k, j = past
            g = float(self.g_old[k][j])
            self.events.record(Crossing(k, t0, y, yp, np.array([j]), j, [(t0, g)], True))
            self.status = 1
            self.message = (
                f"A terminal switch, {switches[k].names[j]!r}, is past its zero at t = {t0:.10g}."
            )
            return False
        self.out.initial(t0, y, yp)
        for k, sw in enumerate(switches):
            sw.arm(self.g_old[k])  # a switch at its zero at t0 (SwitchFunction.arm)
        return True

    def step(self) -> bool:
        """One accepted step and what follows it; True when the run has ended."""
        solver, switches = self.solver, self.switches
        next_stop = self.stops.next(solver.t)
        t_prev = solver.t
        solver.step(next_stop, left_limit=next_stop < self.t_end)
        if switches:
            g_new = [sw.value(solver.t, solver.y, solver.yp) for sw in switches]
            cut = locate_crossings(solver, switches, self.g_old, g_new, t_prev)
        else:
            g_new, cut = self.g_old, ()
        for c in cut:
            self.events.record(c)
        if cut and cut[-1].restarts:
            return self.handle_crossing(cut[-1], t_prev)
        self.out.step(solver, t_prev, solver.t)
        self.g_old = g_new
        for k, sw in enumerate(switches):
            sw.keep_armed(g_new[k])
        if self.stops.reached(solver.t):
            self.at_tstop(g_new)
        return False

    def handle_crossing(self, c: Crossing, t_prev: float) -> bool:
        """The earliest restarting crossing of the last step, located at c.t: the run ends
        (a terminal switch; True) or the step is cut there, the switch acts, and the
        integration restarts."""
        sw = self.switches[c.switch]
        t_star = c.t
        if sw.terminal:
            # the run ends with the last state on the old side of the switch (a vessel's
            # level at its limit, not a round-off beyond it), which is the last output
            # point, also between output times
            self.out.step(self.solver, t_prev, old_side(c, self.g_old[c.switch]))
            self.out.final()
            self.status = 1
            self.message = (
                f"A terminal switch, {sw.names[c.located]!r}, fired at t = {t_star:.10g}."
            )
            return True
        self.out.step(self.solver, t_prev, t_star)
        if t_star == self.last_restart_t:
            self.restarts_here += 1
            if self.restarts_here > MAX_RESTARTS_AT_ONE_TIME:
                raise DAEError(
                    f"The switch {sw.names[c.located]!r} fires again and again at "
                    f"t = {t_star:.10g} (chattering): its action does not move the state "
                    "to the other side."
                )
        else:
            self.restarts_here, self.last_restart_t = 0, t_star
        # an armed element (at its zero since t0) that acted: the new mode's elements at
        # their zero are armed again (SwitchFunction.arm)
        from_start = sw.armed is not None and t_star == t_prev and sw.armed[c.located]
        y_new, yp_new = self.act(c)
        self.restart(t_star, y_new, yp_new, arm=from_start)
        return False

    def act(self, c: Crossing):
        """The switch's action at the crossing, and the values made consistent after it."""
        sw = self.switches[c.switch]
        y_new, yp_new = run_action(sw, c, self.problem.n)
        return self.consistent(
            c.t, y_new, yp_new, f"the values after the switch {sw.names[c.located]!r}"
        )

    def at_tstop(self, g_left):
        """At a tstop just reached: values consistent at its right limit, the switches
        that the jump carried across their zero acted on, and the restart."""
        solver, switches = self.solver, self.switches
        t = solver.t
        y_new, yp_new = self.consistent(
            t, solver.y, solver.yp, "the values after the time event (tstop)"
        )
        # a switch that the jump carried across its zero (a set-point step taking a
        # controller past its limit) fires at the tstop itself
        for _ in range(MAX_RESTARTS_AT_ONE_TIME):
            g_plus = [sw.value(t, y_new, yp_new) for sw in switches]
            k = next(
                (
                    k
                    for k, sw in enumerate(switches)
                    if sw.action is not None and np.any(sw.crossed(g_left[k], g_plus[k]))
                ),
                None,
            )
            if k is None:
                break
            which = np.flatnonzero(switches[k].crossed(g_left[k], g_plus[k]))
            c = Crossing(k, t, y_new, yp_new, which, int(which[0]), [], True)
            self.events.record(c)
            y_new, yp_new = self.act(c)
            g_left = g_plus
        self.restart(t, y_new, yp_new)

    def restart(self, t, y, yp, arm: bool = False) -> None:
        """The one restart path: order 1 from consistent (y, yp) at t, the state after the
        discontinuity output, the switch functions re-evaluated there (``arm``: the
        elements at their zero armed again, ``SwitchFunction.arm``)."""
        solver = self.solver
        solver.restart(t, y, yp, solver.restart_step(t, y, yp, self.stops.next(t)))
        self.out.restart(t, y, yp)
        self.g_old = [sw.value(t, y, yp) for sw in self.switches]
        for k, sw in enumerate(self.switches):
            if arm:
                sw.arm(self.g_old[k])
            else:
                sw.keep_armed(self.g_old[k])


def wrap_switches(events) -> list[SwitchFunction]:
    return [SwitchFunction.wrap(g, i) for i, g in enumerate(events)]
