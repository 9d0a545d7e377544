"""One BDF step at a time: the Nordsieck BDF stepper for F(t, y, y') = 0.

``NordsieckBDF`` owns the Nordsieck array, the step size h and the order q.
Its ``step`` advances the solution by one accepted step:

1. predict: z_pred = P z (Pascal matrix, seed eq. 10.10);
2. correct: modified Newton on G(y) = F(t_n, y, z_pred[1]/h + cj (y - y_pred)) = 0,
   cj = l1(q) / h, with the iteration matrix dF/dy + cj dF/dy' kept (and its LU)
   across steps while it converges (the DASSL/IDA convergence-rate test);
3. error: Milne's estimate E = Delta / ((q + 1) l1 + 1), Delta = y_n - y_pred,
   in the weighted RMS norm with weights 1 / (rtol |y| + atol);
4. accept, and choose the next h and q: h_new = h * eta, eta = 1 / (c (d)^(1/(k+1)))
   for k = q - 1, q, q + 1 (d the error estimate of order k, c a safety factor),
   after q + 1 steps at constant h; on rejection shrink h (and the order).

The corrector (2) is ``newton.NewtonCorrector``'s, the choice of h and q (4) is
``controller.StepController``'s: the stepper feeds it the error estimates and
applies its answer to the Nordsieck array. It knows nothing of events, output or
stop times: the driver (``driver.Driver``) handles those. The method is the
fixed-coefficient ("interpolation") form of Gear's Nordsieck BDF as in LSODE; see
``nordsieck.py`` for the algebra.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from dnasim.core.errors import DAEError
from dnasim.solver import nordsieck as nd
from dnasim.solver.controller import ERROR_TARGET, StepController  # noqa: F401 (re-exported)
from dnasim.solver.controller import eta as _eta
from dnasim.solver.linear_algebra import IterationMatrix
from dnasim.solver.newton import (  # noqa: F401 (re-exported: bdf.NEWTON_TOL, ...)
    CJ_RATIO_REFRESH,
    FULL_NEWTON_ITERS,
    FULL_NEWTON_RATE_UPDATE,
    NEWTON_MAX_ITERS,
    NEWTON_RATE_MAX,
    NEWTON_TOL,
    NewtonCorrector,
)
from dnasim.solver.residual import (  # noqa: F401 (re-exported)
    CountedResidual,
    SolverStats,
    StepFailure,
    _largest,
    all_finite,
)

EPS = float(np.finfo(float).eps)

MAX_NEWTON_FAILURES = 10
MAX_ERROR_FAILURES = 10
REINIT_AFTER_FAILURES = 3  # failed attempts in one step before the point is made consistent
REINIT_STEP_RATIO = 0.01  # ... when h has also fallen below 0.01 of the last step's
# restart step from the solution (True) or IDA's rule (False, the default), see restart_step
RESTART_FROM_SOLUTION = False
RESTART_JUMP_FACTOR = 10.0  # ... but at most 10 times IDA's rule, see restart_step
# compiled loops of the step (``kernels``, bit-identical to the numpy code), loaded once
# they pay. They save 10 to 14 us a step on small problems (benchmarks/step_overhead.py)
# and replace some 20 numpy passes over arrays of n elements a step. Where numba is
# loaded (water plants) loading them costs about 10 ms of CPU: at once for n >=
# KERNELS_MIN_N, else once the process has taken KERNELS_AFTER_STEPS_LOADED steps.
# Importing numba first costs about 0.3 s: only for runs without a sparsity pattern,
# after KERNELS_AFTER_STEPS steps in the process; plants of ideal gases never load it.
KERNELS = True  # False: the numpy step only (benchmarks/solver_vs_peers.py --numpy-step)
KERNELS_MIN_N = 1000
KERNELS_AFTER_STEPS_LOADED = 2000
KERNELS_AFTER_STEPS = 40000
# ``kernels.wrms`` once loaded and checked against numpy's dot (``NordsieckBDF.norm``)
_compiled_wrms = [None]
# [steps of the earlier runs of the process, the counters of the last run]
_runs = [0, None]


class NordsieckBDF(NewtonCorrector):
    """The BDF integrator's state and its single-step method.

    Parameters
    ----------
    residual : CountedResidual
    t0 : float, start time [time unit of the problem]
    y0, yp0 : consistent initial values and derivatives
    rtol, atol : tolerances (atol scalar or per component)
    max_order : 1..5
    h0 : initial step size (None: estimated as in IDA)
    max_step : largest step
    error_mask : 1 for the components counted in the error test, 0 for excluded ones
    norm_mask : 1 for the components counted in the Newton convergence norm, 0 for
        quadratures (None: all counted)
    algebraic : mask of the algebraic components (None: not known); the corrector's
        last attempt starts them at their last accepted values (``_last_chance``)
    matrix : IterationMatrix
    fixed_order, fixed_step : for order-verification tests only: keep q and h constant
    reinitialize : optional hook reinitialize(t, y, yp, h) -> consistent (y, yp) at t,
        the differential y kept (the driver's), used after repeated failures in one
        step (``_reinitialize``)
    track_algebraic_correction : keep ``algebraic_correction``, the largest correction
        |y_n - y_pred| of an algebraic component in the last step in units of its
        tolerance (the driver's output re-solves the algebraic variables between steps
        when it exceeds 1, ``driver.Driver.refine``)
    predicted_crossing : optional hook predicted_crossing(stepper, t_a, t_b) -> the
        earliest time in (t_a, t_b] at which a restart switch changes sign on the
        predictor polynomial (``stepper.interpolate`` beyond stepper.t), or None; a
        Newton failure then shortens the step to end just past it
        (``StepController.after_newton_failure``)

    The step-size and order decisions are ``self.controller``'s (``StepController``),
    fed with the error estimates of each step.
    """

    def __init__(
        self,
        residual: CountedResidual,
        t0: float,
        y0: np.ndarray,
        yp0: np.ndarray,
        *,
        rtol: float,
        atol: np.ndarray,
        max_order: int,
        h0: float | None,
        max_step: float,
        error_mask: np.ndarray,
        matrix: IterationMatrix,
        stats: SolverStats,
        t_scale: float,
        names=None,
        equation_names=None,
        fixed_order: bool = False,
        fixed_step: bool = False,
        norm_mask: np.ndarray | None = None,
        algebraic: np.ndarray | None = None,
        reinitialize=None,
        predicted_crossing=None,
        track_algebraic_correction: bool = False,
    ):
        self.residual = residual
        self.n = y0.size
        self.rtol = rtol
        self.atol = atol
        self.max_order = max_order
        self.max_step = max_step
        self.error_mask = error_mask
        self.norm_mask = np.ones(self.n) if norm_mask is None else norm_mask
        self.algebraic = None if algebraic is None else np.asarray(algebraic, dtype=bool)
        self.matrix = matrix
        self.stats = stats
        self.t_scale = t_scale
        self.names = names
        self.equation_names = equation_names
        self.fixed_order = fixed_order
        self.fixed_step = fixed_step
        self.z = np.zeros((nd.MAX_ORDER + 2, self.n))
        # work arrays of the hot path (``step``): the predicted array and a product
        self._z_pred = np.zeros_like(self.z)
        self._z_work = np.zeros_like(self.z)
        # masks of ones: the weights are used as they are (x * 1.0 == x, bit for bit)
        self._error_all = bool(np.all(self.error_mask == 1.0))
        self._norm_all = bool(np.all(self.norm_mask == 1.0))
        self._dw = np.zeros(self.n)  # the weighted Newton update
        self._kernels = None  # the ``kernels`` module once loaded
        self._predict = None  # its ``predict`` where it matches numpy's product
        self._small_dense = False  # its dense solve where it matches LAPACK's
        self._dot_ok = False  # its dot products match numpy's
        if _runs[1] is not None:  # the last run of the process is over
            _runs[0] += _runs[1].steps
        _runs[1] = stats
        atol_ok = isinstance(atol, np.ndarray) and atol.shape == (self.n,)
        if not atol_ok or not KERNELS:
            self._kernels_at = math.inf
        elif "numba" in sys.modules:
            at = 0 if self.n >= KERNELS_MIN_N else KERNELS_AFTER_STEPS_LOADED
            self._kernels_at = max(at - _runs[0], 0)
        elif not matrix.sparse:
            self._kernels_at = max(KERNELS_AFTER_STEPS - _runs[0], 0)
        else:
            self._kernels_at = math.inf
        self.newton_ss = 20.0  # IDA's initial convergence-rate factor
        self._f_nonfinite = False  # the last _newton met a non-finite predictor residual
        self.jacobian_current = False
        self.failure = StepFailure()
        self.predicted_crossing = predicted_crossing  # hooks: see the class doc
        self.reinitialize = reinitialize
        self.controller = StepController(max_order, fixed_order, fixed_step)
        # max_i |y_n - y_pred|_i w_i over the algebraic components of the last step (the
        # driver's output reads it, ``track_algebraic_correction``); inf: not tracked
        self.algebraic_correction = math.inf
        self._track = None
        # Delta = y_n - y_pred of the last step where tracked (the driver's output
        # estimates the interpolation errors between steps from it, ``driver.Driver.refine``)
        self.step_delta = None
        if track_algebraic_correction and self.algebraic is not None and self.algebraic.any():
            self._track = np.flatnonzero(self.algebraic)
        self.restart(t0, y0, yp0, h0)

    # -- starting and restarting -----------------------------------------------------------
    def initial_step(self, y, yp) -> float:
        """IDA's choice: 0.001 of the span, and no more than 0.5 / ||y'||.

        The quadratures are not counted, at the start nor after a tstop or switch (as
        IDA's with errconQ = false: they take part in no step-size decision). Their
        y' with their atol (atol_scaled times a nominal value) gave h0 = 1.6e-13 s on
        tests/field/closed_form_water.toml, where a liquid volume's Newton cannot
        converge; after the inlet step of tests/field/hx_inlet_step.toml and of
        tests/plants/lag_sensor.toml they set the restart step (7.8e-6 s on the
        lag sensor, where its state allowed ~0.1 s), the step sequence after it
        and with it the final errors: the hx's steady heat balance 1.3e-6 against
        6e-8 without them, the lag's reading 2.6e-3 K against 7.9e-4 K from the
        closed form (measured)."""
        h = 1.0e-3 * self.t_scale
        ypnorm = self.norm(yp, self.weights_for(y) * self.norm_mask)
        if ypnorm * h > 0.5:
            h = 0.5 / ypnorm
        # Not below a few hundred ulp of t: a restart at a large t with a fast-growing
        # accumulator would otherwise start below the round-off limit of the step size.
        h = max(h, min(1.0e3 * EPS * abs(self.t), 1.0e-3 * self.t_scale))
        return min(h, self.max_step)

    def restart(self, t, y, yp, h0=None) -> None:
        """(Re)start at order 1 from consistent (y, yp): after the start, an event or a tstop."""
        self.t = float(t)
        self.q = 1
        self.h = float(h0) if h0 is not None else self.initial_step(y, yp)
        self.z[:] = 0.0
        self.z[0] = y
        self.z[1] = self.h * yp
        self.y = np.array(y, dtype=float)
        self.yp = np.array(yp, dtype=float)
        self.delta_prev = None
        self.h_used, self.q_used = self.h, 1
        self.controller.restart(self.h)

    def restart_step(self, t: float, y_new, yp_new, t_next_stop: float) -> float:
        """The first step size after a restart at self.t (a tstop or a located switch).

        IDA's rule (``initial_step``: 0.5 / ||y'||) knows nothing of the steps before
        the restart: on the plants of ``benchmarks/restart_steps.py`` it restarts at
        3e-4 to 7e-4 s where the transient after the jump allows 1e-3 to 4e-2 s, and
        the order-1 steps after it grow by at most 1 + pi/2 a step. Here the step is the
        one the BDF of order 1 would take on the polynomial of the steps before the
        restart: its local error at step h is ||h^2 y''/2||, estimated from the
        Nordsieck row z[2] = h^2 y''/2 (order >= 2), or from Milne's estimate of the
        last step (order 1, ``delta_prev``):

            err_1 = ||z[2]||_w   or   ||Delta|| / 3,   h_1 = h (ERROR_TARGET / err_1)^(1/2),

        bounded above by the step before the restart (order 1 never takes longer
        steps than the order chosen there), the distance to the next tstop and
        max_step, and below by IDA's rule. The polynomial before the restart knows
        nothing of the transient the jump starts (a spray valve opening, an inlet
        step): h_1 alone was rejected 1 to 11 times per plant run by the first
        steps' error tests, and each rejection also ends the fast growth allowed
        after a first step. So the step is at most RESTART_JUMP_FACTOR times IDA's
        rule (y moves by at most 5 tolerance units along the new y'); with it one
        step in the four plant runs of ``benchmarks/restart_steps.py`` was rejected.

        Off by default (RESTART_FROM_SOLUTION = False: IDA's rule). Measured with it on
        (2026-11-22, third session): the field plants take fewer steps where they
        restart often (boiling_10bar 2006 -> 1860, boiling_60bar 1185 -> 1057,
        boiling_190bar 988 -> 875, condensing_pipe 1154 -> 1100; all finish, balances
        unchanged), but tests/test_plant_defaults.py::
        test_inlet_valve_closes_fully_and_the_line_drains[5-True] stops at 10.54 s: the
        drained line's flows near zero are set by pressure differences below the
        pressures' tolerance, and the longer steps after the restart put the computed
        sink flow past its reverse-flow threshold (the same plant stops at 10.52 s with
        IDA's rule when the algebraic variables stay in the error test). Off until such
        near-zero flows are robust to the step size. (The failure documented here
        before, tests/test_plant_reverse_flow.py::
        test_sink_without_temperature_stops_at_reverse_inflow, now passes with it on.)
        """
        h_ida = self.initial_step(y_new, yp_new)
        if self.fixed_step or self.fixed_order or not RESTART_FROM_SOLUTION:
            return h_ida
        weights = self.weights_for(y_new) * self.error_mask
        if self.q >= 2:
            err1 = nd.lower_order_error_coefficient(2) * self.norm(self.z[2], weights)
        elif self.delta_prev is not None:
            err1 = nd.error_coefficient(1) * self.norm(self.delta_prev, weights)
        else:
            return h_ida
        h1 = self.h * _eta(err1, 1)
        h1 = min(h1, self.h, self.max_step, max(t_next_stop - t, 0.0))
        return max(min(h1, RESTART_JUMP_FACTOR * h_ida), h_ida)

    def set_order(self, q: int, z: np.ndarray, h: float) -> None:
        """Start from a given Nordsieck array (used by order-verification tests)."""
        self.q = q
        self.h = h
        self.z[:] = 0.0
        self.z[: q + 1] = z
        self.controller.first_step = False

    # -- norms -----------------------------------------------------------------------------
    def weights_for(self, y) -> np.ndarray:
        return 1.0 / (self.rtol * np.abs(y) + self.atol)

    @staticmethod
    def norm(v, w) -> float:
        """Weighted RMS norm sqrt(mean((v_i w_i)^2))."""
        if _compiled_wrms[0] is not None:  # the same number in one compiled call
            return _compiled_wrms[0](v, w)
        vw = v * w
        return math.sqrt(vw.dot(vw) / vw.size)

    # -- one step --------------------------------------------------------------------------
    def step(self, t_stop: float | None = None, left_limit: bool = False) -> None:
        """Take one accepted step, not passing t_stop; raise DAEError when that is impossible.

        With ``left_limit``, a step that lands on t_stop evaluates the residual
        an ulp before it: t_stop is a discontinuity and the step must see the
        values from its left (a boundary that steps at t_stop, say).
        """
        if self._kernels is None and self.stats.steps >= self._kernels_at:
            self._load_kernels()
        if self._kernels is not None:
            weights = np.empty(self.n)
            self._kernels.weights(self.y, self.rtol, self.atol, weights)
        else:
            weights = self.weights_for(self.y)
        error_weights = weights if self._error_all else weights * self.error_mask
        newton_weights = weights if self._norm_all else weights * self.norm_mask
        n_newton_fail = 0
        n_error_fail = 0
        reinitialized = False
        failed_this_step = False
        while True:
            q, h = self.q, self.h
            if (
                n_newton_fail + n_error_fail >= REINIT_AFTER_FAILURES
                and not reinitialized
                and self.reinitialize is not None
                and h < REINIT_STEP_RATIO * self.h_used
            ):
                reinitialized = True
                self._reinitialize(h)
                q, h = self.q, self.h
            if t_stop is not None and self.t + h >= t_stop - 4 * EPS * abs(t_stop):
                new_h = t_stop - self.t
                nd.rescale(self.z, q, new_h / h)
                self.h = h = new_h
                t_new = t_stop
            else:
                t_new = self.t + h
            if h <= 4.0 * EPS * max(abs(self.t), abs(t_new)) or not math.isfinite(h):
                self._step_size_failure(h, t_new)
            if self._predict is not None:
                yp_pred = np.empty(self.n)
                self._predict(nd.pascal_matrix(q), self.z, q, h, self._z_pred, yp_pred)
                z_pred = self._z_pred[: q + 1]
            else:
                z_pred = nd.predict(self.z, q, out=self._z_pred)
                yp_pred = None
            cj = nd.harmonic(q) / h
            t_res = np.nextafter(t_new, -np.inf) if (left_limit and t_new == t_stop) else t_new
            converged, y, yp = self._correct(t_res, z_pred, cj, h, weights, newton_weights, yp_pred)
            if not converged:
                self.stats.rejected_newton += 1
                n_newton_fail += 1
                failed_this_step = True
                if n_newton_fail >= MAX_NEWTON_FAILURES:
                    raise DAEError(self._failure_message(t_new, h, "Newton failed to converge"))
                if self.fixed_step:
                    raise DAEError(self._failure_message(t_new, h, "Newton failed (fixed step)"))
                self._change_step(self._eta_after_newton_failure(t_new, h))
                continue
            if self._dot_ok:  # Delta and its norm in one compiled call, the same numbers
                delta = np.empty(self.n)
                enorm = self._kernels.delta_wrms(y, z_pred[0], error_weights, delta)
            else:
                delta = y - z_pred[0]
                enorm = self.norm(delta, error_weights)
            error = nd.error_coefficient(q) * enorm
            if error > 1.0 and not self.fixed_step:
                self.stats.rejected_error += 1
                n_error_fail += 1
                failed_this_step = True
                if n_error_fail >= MAX_ERROR_FAILURES:
                    raise DAEError(
                        self._failure_message(
                            t_new, h, "the error test failed repeatedly", delta * error_weights
                        )
                    )
                self._after_error_failure(error, n_error_fail)
                continue
            if self._track is not None:
                a = self._track
                self.algebraic_correction = float(np.max(np.abs(delta[a]) * weights[a]))
                # a copy: ``_change_step`` scales delta_prev in place
                self.step_delta = delta.copy()
            self._accept(t_new, z_pred, delta, y, yp)
            self.h_used, self.q_used = h, q
            self._choose_next(error, delta, error_weights, failed_this_step)
            return

    def _load_kernels(self) -> None:
        """Import the compiled loops (``kernels``); without numba, go on in numpy."""
        self._kernels_at = math.inf
        try:
            from dnasim.solver import kernels
        except ImportError:  # pragma: no cover - numba is a dependency
            return
        self._kernels = kernels  # each loop is loaded from numba's cache at its first call
        nd.compiled_rescale = kernels.rescale
        if kernels.predict_matches_numpy():
            self._predict = kernels.predict
        self._dot_ok = kernels.dot_matches_numpy()
        if self._dot_ok:
            _compiled_wrms[0] = kernels.wrms
        self._small_dense = (
            not self.matrix.sparse
            and self.n <= kernels.SMALL_DENSE
            and kernels.dense_solve_matches_lapack()
        )

    def _reinitialize(self, h: float) -> None:
        """Make the last accepted point consistent again and restart there at order 1.

        The corrector accepts y_n when the Newton update is below NEWTON_TOL of the
        error tolerance; an algebraic constraint may be left with a residual r of
        that size. At the step sizes of the accepted steps it is harmless, but once
        failures have cut h far below them (a step into a phase line), the predictor
        inherits r and the corrector must remove it within the new step: a kick of
        r / h in the derivatives that no step size passes. boiling_60bar: a density
        residual of 8e-10 kg (4e-10 of the volume's mass) in the last liquid volume
        became a jump of 0.002 kg/s in the flow into it at h = 1e-9 s, and the error
        test failed down to h = 1e-11 s. Solving F = 0 afresh at t_n (differential y
        kept, algebraic y and y' solved, with y' weighted by the step size now
        wanted) removes r; integration restarts at order 1 with that step size.
        """
        try:
            y, yp = self.reinitialize(self.t, self.y, self.yp, h)
        except DAEError:
            return  # not better than the accepted point: go on with the step cuts
        self.restart(self.t, y, yp, h)
        self.controller.first_step = False  # no fast growth: h was cut for a reason
        self.jacobian_current = False
        self.matrix.matrix = None
        self.stats.reinitializations += 1

    def _eta_after_newton_failure(self, t_new: float, h: float) -> float:
        """Step ratio after a Newton failure (``StepController.after_newton_failure``),
        with the restart switches' crossing predicted in the step when there is a hook."""
        t_c = None
        if self.predicted_crossing is not None and not self.fixed_step:
            t_c = self.predicted_crossing(self, self.t, t_new)
        return self.controller.after_newton_failure(self.t, h, t_c)

    def _step_size_failure(self, h, t_new) -> None:
        raise DAEError(
            self._failure_message(t_new, h, f"the step size fell to round-off level (h = {h:.3g})")
        )

    def _accept(self, t_new, z_pred, delta, y, yp) -> None:
        q = self.q
        if self._kernels is not None:
            self._kernels.correct(z_pred, nd.l_vector(q), delta, q, self.z)
        else:
            work = self._z_work[: q + 1]
            np.multiply(nd.l_vector(q)[:, None], delta, out=work)
            np.add(z_pred, work, out=self.z[: q + 1])  # z = z_pred + l Delta, in place
        self.t = t_new
        self.y = y
        self.yp = yp
        self.stats.steps += 1
        self.controller.accepted()
        self.jacobian_current = False

    # -- step-size and order control -------------------------------------------------------
    def _change_step(self, eta: float) -> None:
        eta = min(eta, self.max_step / self.h)
        nd.rescale(self.z, self.q, eta)
        self.h *= eta
        if self.delta_prev is not None:
            # Delta ~ h^(q+1) y^(q+1): express the previous one at the new h, so the
            # order-raise estimate (Delta - Delta_prev) stays valid across h changes.
            self.delta_prev *= eta ** (self.q + 1)  # in place: no one else holds it

    def _set_order(self, new_q: int, delta=None) -> None:
        """Raise (with this step's Delta) or lower the order of the Nordsieck array."""
        while self.q > new_q:
            nd.decrease_order(self.z, self.q)
            self.q -= 1
            self.delta_prev = None
        if new_q == self.q + 1:
            nd.increase_order(self.z, self.q, delta)
            self.q = new_q
            self.delta_prev = None

    def _after_error_failure(self, error: float, n_fail: int) -> None:
        q = self.q
        new_q, eta = self.controller.after_error_failure(
            q,
            error,
            n_fail,
            lambda: (
                nd.lower_order_error_coefficient(q)
                * self.norm(self.z[q], self.weights_for(self.y) * self.error_mask)
            ),
        )
        self._set_order(new_q)
        self._change_step(eta)

    def _choose_next(self, error, delta, error_weights, failed_this_step) -> None:
        """After an accepted step: the error estimates of orders q - 1 and q + 1 for the
        controller (``StepController.choose``), and its order and step size applied."""
        q = self.q
        delta_prev = self.delta_prev
        self.delta_prev = delta
        ctrl = self.controller
        err_down = err_up = None
        if not (ctrl.fixed_step or ctrl.first_step) and ctrl.wants_order_estimates(q):
            if q > 1 and delta_prev is not None and self._dot_ok:
                # both norms in one compiled call, the same numbers as the two below
                n_down, n_up = self._kernels.wrms_order_errors(
                    self.z[q], delta, delta_prev, error_weights
                )
                err_down = nd.lower_order_error_coefficient(q) * n_down
                err_up = nd.higher_order_error_coefficient(q) * n_up
            else:
                if q > 1:
                    err_down = nd.lower_order_error_coefficient(q) * self.norm(
                        self.z[q], error_weights
                    )
                if delta_prev is not None:
                    err_up = nd.higher_order_error_coefficient(q) * self.norm(
                        delta - delta_prev, error_weights
                    )
        new_q, eta = ctrl.choose(q, self.h, error, err_down, err_up, failed_this_step)
        if new_q != q:
            self._set_order(new_q, delta)
            ctrl.order_changed()
        if eta != 1.0:
            self._change_step(eta)

    # -- dense output ----------------------------------------------------------------------
    def interpolate(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """y and y' at t within the last step, from its Nordsieck polynomial.

        The step-size and order choice after a step rescales the array; the
        polynomial is the same, expressed with the new h.
        """
        s = (t - self.t) / self.h
        return nd.interpolate(self.z, self.q, self.h, s)

    def nordsieck_snapshot(self) -> tuple[float, float, int, np.ndarray]:
        """(t_n, h, q, z[:q+1]): the polynomial of the last step, for dense output."""
        return self.t, self.h, self.q, self.z[: self.q + 1].copy()

    # -- messages --------------------------------------------------------------------------
    def _failure_message(self, t, h, what, scaled_error=None) -> str:
        msg = f"The integration stopped at t = {self.t:.10g} (trying a step to {t:.10g}, " + (
            f"h = {h:.3g}): {what}"
        )
        if self.failure.reason:
            msg += f"; last problem: {self.failure.reason}"
        comps = self.failure.bad_components
        if scaled_error is not None:
            comps = _largest(scaled_error)
        if comps:
            msg += ". The variables most involved: " + ", ".join(self._name(i) for i in comps[:5])
        return msg + "."

    def _name(self, i: int) -> str:
        if self.names is not None and i < len(self.names):
            return f"{self.names[i]} (index {i})"
        return f"y[{i}]"
