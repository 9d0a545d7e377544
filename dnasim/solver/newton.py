"""The corrector of the BDF step: modified Newton on the BDF formula.

``NewtonCorrector`` is the part of ``bdf.NordsieckBDF`` that solves
G(y) = F(t_n, y, y'_pred + cj (y - y_pred)) = 0 for one step: with the kept
iteration matrix dF/dy + cj dF/dy' (and its LU) while it converges, a fresh one,
full Newton, and a last attempt from the algebraic unknowns' last accepted values
(``_correct``). Convergence is the DASSL/IDA rate test (``_newton``). It reads the
stepper's residual, matrix, stats, kernels and names (``bdf.NordsieckBDF.__init__``).
"""

from __future__ import annotations

import math

import numpy as np

from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver.linear_algebra import SingularMatrixError
from dnasim.solver.residual import StepFailure, _largest, all_finite

NEWTON_MAX_ITERS = 4  # IDA's maxcor
FULL_NEWTON_ITERS = 8  # full Newton after a fresh matrix failed by its count (see _correct)
# full Newton judges convergence by its observed rate once an update is below this
# fraction of the tolerance (see _full_newton)
FULL_NEWTON_RATE_UPDATE = 0.1
NEWTON_RATE_MAX = 0.9  # IDA's RATEMAX: give up when the contraction is slower
NEWTON_TOL = 0.03  # Newton converged at 0.03 of the error test (IDA: 0.33), see _choose_next
# refresh J when cj/cj_J leaves [0.25, 4]. IDA's window is narrower: [0.6, 1.67]
# ((1 - XRATE)/(1 + XRATE) with XRATE = 0.25). With IDA's window the Test Set of
# benchmarks/solver_vs_peers.py took 2.0 to 2.2 Newton iterations a step instead of 2.3
# to 2.8, for 1.7 to 2 times the Jacobians, no less CPU time, and 5 of 12 rows below
# IDA's digits (Robertson at 1e-4: -0.36; measured, benchmarks/README.md).
CJ_RATIO_REFRESH = 0.25


class NewtonCorrector:
    """The corrector's methods of ``bdf.NordsieckBDF`` (module doc)."""

    def _correct(self, t, z_pred, cj, h, weights, newton_weights, yp_pred=None):
        """Modified Newton for the corrector; returns (converged, y, yp).

        ``weights``: the error weights of every component (the finite-difference
        increments); ``newton_weights``: those of the convergence norm (0 for the
        quadratures: their Newton error is h times the error of the integrand, which
        the others' convergence bounds; nothing reads them back).

        Attempts: the kept matrix; a fresh one; and, when that still converges too
        slowly but does converge, full Newton (a fresh matrix every iteration, at most
        FULL_NEWTON_ITERS). The last is for correctors whose algebraic unknowns the
        predictor misses by far on a curved constraint: the flow between a liquid and a
        boiling volume, fixed by pressures that move by 1e9 Pa per kg of the volumes'
        masses, was predicted 3 kg/s off on tests/field/boiling_10bar.toml, and modified
        Newton needed more than 4 iterations where full Newton needed 5 (measured).

        When all of these fail, one more attempt starts the algebraic unknowns at
        their last accepted values instead of the predictor's (``_last_chance``).
        ``yp_pred``: z_pred[1] / h when already computed."""
        y_pred = z_pred[0]
        if yp_pred is None:
            yp_pred = z_pred[1] / h
        result = self._correct_from_predictor(t, y_pred, yp_pred, cj, h, weights, newton_weights)
        if not (result[0] or self.algebraic is None or not self.algebraic.any()):
            result = self._last_chance(t, y_pred, yp_pred, cj, h, weights, newton_weights)
        if result[0] and self.matrix.trailing is not None:
            self._settle_trailing(t, result[1], result[2], cj)
        return result

    def _settle_trailing(self, t, y, yp, cj) -> None:
        """The quadratures whose rows the matrix left out (``IterationMatrix``, with
        ``quadrature``), in place at the corrector's solution: where the whole matrix's
        Newton iteration would have put them.

        The other unknowns' updates d_k are the whole matrix's (block triangular); a
        quadrature's lacks the term b.d_k / J_qq of its row's entries b. Its gap to the
        whole matrix's iterate follows e_{k+1} = (1 - s r) e_k + b.d_k / J_qq (s the
        update's scale, r = cj / cj_J: 0 for a fresh matrix), where b.d_k is what the
        update moved F_q by through the others: F_q at the next iterate less F_q less
        dF_q/dy_q d_q (exact for a row linear in y, a sum of heat flows; a secant
        else). The iterations' residuals give it for all but the last update, one
        evaluation of the rows at the solution (``IterationMatrix.trailing_residual``)
        for that. Without it the invariant Q - sum y of
        tests/test_solver_trailing_quadrature.py was kept to 2e-5 (7e-7 of Q), with
        it to round-off, as with the whole matrix. Outside the residual's domain the
        quadratures keep their iterate (they are read by no equation)."""
        f_last, d, gap, rho, slope, diag = self._trail
        try:
            f_q = self.matrix.trailing_residual(t, y, yp)
        except ResidualDomainError:
            return
        gap = rho * gap + (f_q - f_last - slope * d) / diag
        cols = self.matrix.trailing_entries()[1]
        y[cols] -= gap
        yp[cols] -= cj * gap

    def _correct_from_predictor(self, t, y_pred, yp_pred, cj, h, weights, newton_weights):
        """The attempts of ``_correct`` that start at the predictor."""
        for attempt in range(2):
            y = y_pred.copy()
            yp = yp_pred.copy()
            try:
                f = self.residual(t, y, yp)
                refresh = (
                    self.matrix.matrix is None
                    or not (CJ_RATIO_REFRESH < cj / self.matrix.cj < 1.0 / CJ_RATIO_REFRESH)
                    or (attempt == 1)
                )
                if refresh:
                    if not all_finite(f):
                        self._note_nonfinite(t, f)
                        return False, None, None
                    self._new_matrix(t, y, yp, f, cj, h, weights)
                # with the kept matrix a non-finite f shows in the first update (_newton)
                converged, y, yp = self._newton(t, y, yp, f, cj, newton_weights, fresh=refresh)
                if self._f_nonfinite:
                    return False, None, None
            except ResidualDomainError as exc:
                self.failure = StepFailure(f"the residual could not be evaluated: {exc}")
                converged = False
                if self.jacobian_current:
                    return False, None, None
                self.jacobian_current = False
                continue
            if converged:
                return True, y, yp
            if self.jacobian_current:
                if self._slow_but_converging:
                    return self._full_newton_from(
                        t, y_pred, yp_pred, cj, h, weights, newton_weights
                    )
                return False, None, None
            # Slow or failed with an old matrix: retry once with a fresh one.
        return False, None, None

    def _last_chance(self, t, y_pred, yp_pred, cj, h, weights, newton_weights):
        """The corrector from the predictor with the algebraic unknowns at their last
        accepted values (y' moved with them along the BDF formula y' = y'_pred + cj
        (y - y_pred)): a fresh matrix, and full Newton when that converges too slowly.

        Their Nordsieck history is not error-controlled (outside the error test of
        plants) and carries the Newton and truncation noise of the states they follow
        with a large gain: an economiser's liquid flows, fixed by volume pressures that
        move 1.6e9 Pa per unit relative mass, were extrapolated at order 4 to -84 kg/s
        where the corrector's flow was 7.7 kg/s (plants/rankine.toml, t = 2 ms), and
        with dp = c m |m| full Newton from there halves m per iteration and fails.
        The last accepted value was 15 kg/s. Any start is valid: an algebraic y_i
        enters F only through y_i. plants/rankine.toml at 11 values of rtol from 0.9e-6
        to 1.1e-6, first 100 steps: without this attempt 6 runs crawled at h ~ 1e-5 s
        below t = 5 ms (main too, at 0.98e-6); with it all reached 0.40 to 0.64 s
        (measured). Only after the attempts from the predictor failed: as the first
        retry (instead of the predictor's start for the fresh matrix and full Newton) it
        took tests/field/boiling_10bar.toml into a step-size collapse at 36.4 s, where
        the predictor carries the volumes across the phase line and the last values lie
        on the other side (measured)."""
        a = self.algebraic
        y, yp = y_pred.copy(), yp_pred.copy()
        yp[a] += cj * (self.y[a] - y[a])
        y[a] = self.y[a]
        y_start, yp_start = y, yp
        try:
            f = self.residual(t, y, yp)
            if not all_finite(f):
                self._note_nonfinite(t, f)
                return False, None, None
            self._new_matrix(t, y, yp, f, cj, h, weights)
            converged, y, yp = self._newton(t, y, yp, f, cj, newton_weights, fresh=True)
        except ResidualDomainError as exc:
            self.failure = StepFailure(f"the residual could not be evaluated: {exc}")
            return False, None, None
        if converged:
            return True, y, yp
        if self._slow_but_converging:
            return self._full_newton_from(t, y_start, yp_start, cj, h, weights, newton_weights)
        return False, None, None

    def _full_newton_from(self, t, y_start, yp_start, cj, h, weights, newton_weights):
        """``_full_newton`` from (y_start, yp_start): (converged, y, yp)."""
        try:
            y, yp = y_start.copy(), yp_start.copy()
            f = self.residual(t, y, yp)
            converged, y, yp = self._full_newton(t, y, yp, f, cj, h, weights, newton_weights)
        except ResidualDomainError as exc:
            self.failure = StepFailure(f"the residual could not be evaluated: {exc}")
            return False, None, None
        if converged:
            return True, y, yp
        return False, None, None

    def _full_newton(self, t, y, yp, f, cj, h, weights, newton_weights):
        """Newton with a fresh matrix every iteration (see ``_correct``)."""
        previous = math.inf
        for _ in range(FULL_NEWTON_ITERS):
            self._new_matrix(t, y, yp, f, cj, h, weights)
            self.stats.full_newton_iters += 1
            converged, y, yp = self._newton(
                t, y, yp, f, cj, newton_weights, fresh=True, max_iters=1
            )
            if converged:
                return True, y, yp
            dnorm = self._last_dnorm
            if not self._slow_but_converging or not dnorm < previous:
                return False, y, yp  # not finite, or diverging
            # Each iteration above is judged with IDA's initial rate guess (newton_ss =
            # 20, the matrix being fresh). Once the update is small, the rate observed
            # between the last two updates is known: the DASSL/IDA test with it. (Not
            # while the update is large: a quadratic start makes the ratio tiny, 424 after
            # 6e6 on plants/rankine.toml, and says nothing of what is left.)
            rate = dnorm / previous
            if dnorm <= FULL_NEWTON_RATE_UPDATE and rate / (1.0 - rate) * dnorm <= NEWTON_TOL:
                return True, y, yp
            previous = dnorm
            f = self.residual(t, y, yp)
            if not all_finite(f):
                self._note_nonfinite(t, f)
                return False, y, yp
        self.failure = StepFailure(
            f"full Newton did not converge in {FULL_NEWTON_ITERS} iterations"
        )
        return False, y, yp

    def _new_matrix(self, t, y, yp, f, cj, h, weights) -> None:
        self.matrix.evaluate(t, y, yp, f, cj, h, weights)
        self.stats.jac_evals += 1
        self.stats.lu_decomps += 1
        try:
            self.matrix.factorize()
        except SingularMatrixError as exc:
            if self.matrix.nonfinite:
                # A predicted state outside the residual's domain (a square root of a
                # slightly negative value, say): recoverable by a smaller step.
                raise ResidualDomainError(str(exc)) from None
            raise DAEError(f"At t = {t:.10g}: {exc}") from None
        self.jacobian_current = True
        self.newton_ss = 20.0

    def _newton(self, t, y, yp, f, cj, weights, fresh=False, max_iters=NEWTON_MAX_ITERS):
        """Iterate y <- y - J^{-1} F with the DASSL/IDA rate test; returns (converged, y, yp)."""
        ratio = cj / self.matrix.cj
        scale = 2.0 / (1.0 + ratio) if ratio != 1.0 else 1.0
        # A matrix built for another cj contracts at best by |1 - r| / (1 + r) (the
        # dF/dy'-dominated limit); the stale rate from earlier steps must not claim better.
        c = abs(1.0 - ratio) / (1.0 + ratio)
        self.newton_ss = max(self.newton_ss, c / (1.0 - c))
        first_norm = None
        self._slow_but_converging = False
        self._f_nonfinite = False
        kernels = self._kernels
        lu = self.matrix.dense_lu() if self._small_dense else None
        # the quadratures of the rows the matrix left out (``_settle_trailing``): their
        # rows' values and updates, and how far their iterate is from the whole matrix's
        trail = self.matrix.trailing_entries()
        if trail is not None:
            t_rows, t_cols, t_diag = trail
            t_slope = cj * t_diag / self.matrix.cj  # dF_q/dy_q along the BDF formula
            t_rho = 1.0 - scale * ratio
            t_gap = np.zeros(t_rows.size)
            t_f_last = t_d = None  # the last iteration's (set below before their use)
        for m in range(max_iters):
            self.stats.newton_iters += 1
            if trail is not None:
                t_f = f[t_rows]
                if m > 0:  # what the last update moved F_q through the others
                    t_gap = t_rho * t_gap + (t_f - t_f_last - t_slope * t_d) / t_diag
                t_y = y[t_cols]
            if kernels is not None:  # the same numbers in one compiled loop
                y_new, yp_new, dw = np.empty(self.n), np.empty(self.n), self._dw
                if lu is not None:  # the dense LU solve in the loop too
                    ss = kernels.newton_update_lu(
                        lu[0], lu[1], f, scale, y, yp, cj, weights, y_new, yp_new, dw
                    )
                else:
                    ss = kernels.newton_update(
                        self.matrix.solve(f), scale, y, yp, cj, weights, y_new, yp_new, dw
                    )
                y, yp = y_new, yp_new
                if not self._dot_ok:
                    ss = dw.dot(dw)
            else:
                d = self.matrix.solve(-f)
                if scale != 1.0:
                    d *= scale
                y = y + d
                yp = yp + cj * d
                dw = d * weights
                ss = dw.dot(dw)
            dnorm = math.sqrt(ss / dw.size)  # self.norm(d, weights), inlined
            self._last_dnorm = dnorm
            if trail is not None:
                t_d, t_f_last = y[t_cols] - t_y, t_f
                self._trail = (t_f_last, t_d, t_gap, t_rho, t_slope, t_diag)
            if not math.isfinite(dnorm):
                # A NaN or inf in f makes the update non-finite (every x_i of the LU
                # solve involves b_i; 0 * inf is NaN): the residuals of the iterations
                # are checked here, not after each evaluation (0.6 us a call, measured).
                if not all_finite(f):
                    self._note_nonfinite(t, f)
                    self._f_nonfinite = m == 0  # the predictor's: no retry (``_correct``)
                else:
                    self.failure = StepFailure("the Newton update is not finite")
                return False, y, yp
            if m == 0:
                first_norm = dnorm
                if dnorm <= 1.0e-4 * NEWTON_TOL:
                    return True, y, yp
            else:
                rate = (dnorm / first_norm) ** (1.0 / m) if first_norm > 0 else 0.0
                if rate > NEWTON_RATE_MAX:
                    self.failure = StepFailure(
                        f"Newton converged too slowly (rate {rate:.2f})", _largest(dw)
                    )
                    return False, y, yp
                self.newton_ss = rate / (1.0 - rate)
            # With a matrix not built for this corrector (kept from earlier steps, or from
            # an attempt at another h), the rate estimate is stale: never accept after the
            # first iteration. On DAEs whose constraints amplify errors (a transistor
            # amplifier: gain ~100 from one node to the next) a stale rate accepted
            # leftovers far above the tolerance, and the next step could not pass the
            # error test at any h. Near a phase line the matrix of a failed attempt may
            # even belong to the other side of the kink (boiling_60bar: a leftover of
            # 0.9 Pa between two liquid volumes, 0.007 kg/s in their flow, accepted).
            # Measured again (sv11): accepting after one update where this matrix's
            # rate was measured on an earlier step (IDA's ss carried over) cut the Test
            # Set's iterations from 2.3-2.8 to 2.0-2.6 a step, and the transistor
            # amplifier at rtol 1e-4 stopped at t = 0.054 (error test failing at h = 3e-10).
            if self.newton_ss * dnorm <= NEWTON_TOL and (m > 0 or fresh):
                return True, y, yp
            if m + 1 < max_iters:
                f = self.residual(t, y, yp)  # its finiteness: see the update's above
        self.failure = StepFailure(
            f"Newton did not converge in {max_iters} iterations", _largest(dw)
        )
        # converging, only not fast enough: full Newton may finish it (``_correct``)
        self._slow_but_converging = (
            fresh and first_norm is not None and (m == 0 or dnorm < first_norm)
        )
        return False, y, yp

    def _note_nonfinite(self, t, f) -> None:
        bad = np.flatnonzero(~np.isfinite(f)).tolist()
        self.failure = StepFailure(
            f"the residual returned NaN or inf at t = {t:.10g} in equation(s) "
            + ", ".join(
                str(self.equation_names[i]) if self.equation_names is not None else str(i)
                for i in bad[:8]
            ),
            bad,
        )
