"""Output points between steps as accurate as those at steps (issue 20, item 8).

The Nordsieck polynomial of a step is exact at its ends only. A differential variable
is integrated by it, so the polynomial between the ends is as good as the method; an
algebraic variable is not: it is a function of the states (a valve's flow through
a pressure ramp, a node's enthalpy when a feed starts), and the polynomial through
its values at the steps does not follow that function in between. Measured on the
example plants with their output intervals (rtol 1e-6, the algebraic variables out
of the error test as ``dnasim run`` keeps them): the interpolated algebraic values
were off their solved values by a median of 0.04 (msl_drum_boiler), 0.16
(drum_boiler) and 2.5 (rankine) tolerance units, up to 9e5 (the node enthalpy of
-3e5 J/kg, NaN in its temperature, where the MSL drum boiler's feed starts).

``AlgebraicRefiner`` solves F(t, y, y') = 0 at such a point for the algebraic y and
the differential y' with the differential y as interpolated (the same unknowns as
a restart's ``solve_consistent``; the algebraic y' stay interpolated, F does not
read them). Modified Newton with a Jacobian dF/du kept across output points and
steps while it contracts (a fresh one when it does not, and ``solve_consistent``'s
globalised Newton as the last resort): a point costs one to three residual
evaluations, a Jacobian one per column group when taken. Converged when what is
left after an update (rate / (1 - rate) times it with the contraction rate of this
solve, DASSL's test; the first update only when it is itself below CONVERGED) is
below CONVERGED in units of the tolerance: the point is then as accurate as a step's.

Three things make it cheaper (benchmarks/refine_cost.py; issue 20 follow-up), and
one more accurate:

- ``ALGEBRAIC_TEST``: where the rows that read no y' (the algebraic equations
  G(y) = 0) are as many as the algebraic unknowns (every plant of plants/*.toml),
  the matrix is block triangular, [[dG/dy_a, 0], [B, dF/dy'_d]], and the update of
  the algebraic y is Newton's on G(y_d, y_a) = 0 alone, whatever the y' are. The
  test then measures the algebraic y alone (RMS over them, stricter than over all
  unknowns). Over all unknowns, as before, the h-weighted y' (their interpolation off
  by 10 to 100 tolerance units) set the iterations, and the RMS over n let an
  algebraic variable stay 1.65 tolerance units off (drum_boiler) after the test
  passed; with the algebraic test 0.16. Only with ``RATE_TRUSTED``: without it the
  fewer iterations showed the rate test's weakness (rankine 2.2 -> 15.7 units).
- ``WARM_START``: the Newton of a point starts from the interpolated point plus the
  correction expected from the points solved before it in the same step (the line
  through the last two corrections, ``EXTRAPOLATE``; the last one alone where there
  is one), with the kept matrix; when that fails, from the interpolated point as
  before. The correction is a smooth function of t inside a step: the first update
  is smaller, fewer iterations.
- ``SPLICE``: a kept matrix that fails from the interpolated point is given the
  columns of the algebraic y from the integrator's matrix when that one is newer,
  and refactorised (no residual evaluation; those columns are dF/dy_a in both, F
  reads no algebraic y'), before a fresh Jacobian is taken.
- ``RATE_TRUSTED``: the rate test only once the update itself is below 0.1 of the
  tolerance (as newton.py's full Newton): a large first update followed by a small
  one makes the rate look tiny while the slow directions are not yet done (rankine,
  the test over all unknowns: 2.21 -> 0.20 units off; over the algebraic y 0.75).

The RMS over the algebraic y; their max norm (``ALGEBRAIC_MAX``) kept every plant
within 0.06 tolerance units of the reference (rankine 0.75 -> 0.04), at a cost of
drum_boiler 1631 -> 1904 and rankine 4124 -> 4235 residual evaluations.

The solve is not always the better answer. Where an algebraic variable is much more
sensitive to the states than it varies along the solution, the solved value carries
the states' interpolation error amplified: tests/plants/pump_shutoff.toml, a shut pump
against its closed valve over a 20.7 s step, read -4.7e-3 kg/s solved where the flow
is +1.4e-5 kg/s (the line's mass interpolated 4e-4 of its tolerance off, the pump's
head curve flat at zero flow), while the flow's own polynomial was right. So each value
is then kept solved or interpolated, whichever has the smaller estimated error
(``driver.Driver._choose``): the polynomial's error at the point is
``nordsieck.interpolation_error`` times the step's Delta for every variable, the
solved value's is the states' share of it propagated through the solve
(``propagate``). Before solving, ``first_update`` (the solve's first Newton iteration
with the kept matrix, handed on to it as its start) tells the driver how far the
solve would move each value: a point where it moves none by more than a fraction of
its tolerance, or where the choice would keep the ones it moves interpolated, is not
solved (``driver.Driver._over``, ``_gains``).

Measured to end up less useful (benchmarks/refine_cost.py, 1200 s of each plant):
CONVERGED = 0.1 or 0.3 of the tolerance (with the algebraic test, before the warm
start: drum_boiler 2131 -> 1882 and 1614 residual evaluations, but its algebraic
variables 0.38 and 1.2 tolerance units off the reference, against 0.16), a fresh
matrix once the contraction rate at a point exceeded 0.3 or 0.15 (drum_boiler 2131
-> 2130 and 2171, msl_drum_boiler 1270 -> 1269 and 1293). The warm start along the
line rather than from the last correction: drum_boiler 1896 -> 1633, msl_drum_boiler
1276 -> 1314, feedwater_heater 752 both.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse

from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver.initial import solve_consistent
from dnasim.solver.linear_algebra import SQRT_EPS, IterationMatrix, SingularMatrixError
from dnasim.solver.newton import FULL_NEWTON_RATE_UPDATE, NEWTON_TOL

#: converged when what is left of ||d||_uw is below this: the corrector's NEWTON_TOL,
#: the accuracy of the algebraic variables at a step
CONVERGED = NEWTON_TOL
MAX_ITERS = 4
#: a kept Jacobian is given up when an update shrinks by less than this factor
RATE_MAX = 0.5
#: the rate test only once the update itself is below this (newton.py's
#: FULL_NEWTON_RATE_UPDATE): a first update of 88.6 tolerance units and a second of
#: 0.98 (rate 0.011) on plants/rankine.toml left economiser.cold_m[2] 15.7 units off
RATE_TRUSTED = FULL_NEWTON_RATE_UPDATE
#: start a point's Newton from the correction of the points before it in the step
WARM_START = True
#: ... extrapolated along the line through the last two (else the last one)
EXTRAPOLATE = True
#: the convergence test on the algebraic y alone where the matrix is block triangular
ALGEBRAIC_TEST = True
#: ... in the max norm over them rather than the RMS (module doc: off, measured)
ALGEBRAIC_MAX = False
#: when the kept matrix fails: its algebraic columns from the integrator's newer matrix
SPLICE = True
#: when the kept, spliced and fresh matrices all fail: the globalised Newton of
#: ``solve_consistent`` (True), or the point kept interpolated (False, a DAEError the
#: driver counts in ``output_solve_failures``)
GLOBALISED = True


def rate_factor(rate: float) -> float:
    """rate / (1 - rate): the sum of the updates left at contraction ``rate`` < 1."""
    return rate / (1.0 - rate)


class AlgebraicRefiner:
    """refine(t, y, yp, h, step=None) -> (y, yp): the algebraic y and differential y' at
    t solved from the differential y (module doc). ``h`` weights the y' unknowns (the
    step size: a change d of y' moves y by about h d); ``step`` names the step whose
    polynomial gave (y, yp) (the points of one step share their warm start; None: no
    warm start); ``start``: (y0, yp0, F there) of ``first_update``, where the Newton
    starts (its warm start). Raises DAEError when even the globalised Newton fails.

    ``matrix``: an ``IterationMatrix`` of its own (its colouring; the integrator's
    matrix and LU are never touched, so the steps do not depend on the output);
    ``source``: the integrator's ``IterationMatrix``, only read (``_splice``)."""

    def __init__(
        self, F, algebraic, rtol, atol, matrix: IterationMatrix, names, eq_names, stats, source=None
    ):
        self.F = F
        self.unknown_y = np.asarray(algebraic, dtype=bool)
        self.ymask = self.unknown_y.astype(float)
        self.ypmask = 1.0 - self.ymask
        self.rtol, self.atol = rtol, atol
        self.matrix = matrix
        self.names, self.eq_names = names, eq_names
        self.stats = stats
        self.kept = False  # the matrix holds a factorised dF/du
        # (step, [(t, dy, dyp), ...]): the corrections solved at the last one or two
        # points of the step ``step`` (the driver's count of accepted steps)
        self.carry = None
        self.alg = np.flatnonzero(self.unknown_y)
        self.block = False  # the kept matrix is block triangular (``_block_triangular``)
        self.warm = WARM_START
        # the integrator's IterationMatrix (its algebraic columns are dF/dy_a, whatever
        # its cj: ``_splice``), and the matrix of it last spliced in
        self.source = source if SPLICE and source is not None and source.jac is None else None
        self.spliced_from = None
        self._alg_entries = None  # the pattern's entries in algebraic columns
        self.stats_spliced = 0

    def __call__(self, t, y, yp, h, step=None, start=None):
        result = None
        if start is not None and self.kept:  # F at the start given (``first_update``)
            y0, yp0, f0 = start
            try:
                result = self._newton(t, y0, yp0, h, False, f=f0)
            except ResidualDomainError:
                result = None
            guess = None  # the start was the warm start
        else:
            guess = self._guess(t, step) if self.warm and step is not None and self.kept else None
        if result is None and guess is not None:
            try:
                result = self._newton(t, y + guess[0], yp + guess[1], h, False)
            except ResidualDomainError:
                result = None
        if result is None:
            result = self._solve(t, y, yp, h)
        if step is not None:
            c = (t, result[0] - y, result[1] - yp)
            last = self.carry[1][-1:] if self.carry is not None and self.carry[0] == step else []
            self.carry = (step, [*last, c])
        return result

    def first_update(self, t, y, yp, step=None):
        """The first Newton iteration of the solve at the point (y, yp), before it:
        ((y0, yp0, f), (dy, dy')) with (y0, yp0) the Newton's start (the warm start,
        ``_guess``, else the point), f = F there and (dy, dy') the start plus the
        update with the kept matrix less the point: to first order what the solve
        changes (one residual evaluation, the solve's first, handed to ``__call__`` as
        ``start``, and one back-substitution). None without a kept matrix or where F
        is not finite at the start."""
        if not self.kept:
            return None
        guess = self._guess(t, step) if self.warm and step is not None else None
        y0, yp0 = (y, yp) if guess is None else (y + guess[0], yp + guess[1])
        try:
            f = self.F(t, y0, yp0)
        except ResidualDomainError:
            return None
        if not np.all(np.isfinite(f)):
            return None
        d = self.matrix.solve(-f)
        return (y0, yp0, f), (y0 - y + d * self.ymask, yp0 - yp + d * self.ypmask)

    def propagate(self, t, y, yp, dx, h):
        """The change (dy, dy') of the solved unknowns (the algebraic y, the differential
        y') when the differential y move by ``dx`` (zero in the algebraic entries): one
        Newton step of the moved problem with the kept matrix, -M^-1 (F(y + dx) - F(y)),
        two residual evaluations and one back-substitution; without a kept matrix (the
        point was solved by ``solve_consistent``) a fresh one at (y, yp) first, ``h``
        weighting its y' columns. None where F cannot be evaluated or the matrix is
        singular."""
        try:
            f0 = self.F(t, y, yp)
            f1 = self.F(t, y + dx, yp)
        except ResidualDomainError:
            return None
        if not (np.all(np.isfinite(f0)) and np.all(np.isfinite(f1))):
            return None
        if not self.kept and not self._fresh_matrix(t, y, yp, f0, self._weights(y, h)):
            return None
        d = self.matrix.solve(f0 - f1)
        return d * self.ymask, d * self.ypmask

    def _guess(self, t, step):
        """The correction (dy, dy') expected at t from those solved at the last points of
        the same step: the last one, or the line through the last two."""
        if self.carry is None or self.carry[0] != step:
            return None
        points = self.carry[1]
        t2, dy2, dyp2 = points[-1]
        if len(points) == 1 or not EXTRAPOLATE:
            return dy2, dyp2
        t1, dy1, dyp1 = points[-2]
        r = (t - t2) / (t2 - t1)
        return dy2 + r * (dy2 - dy1), dyp2 + r * (dyp2 - dyp1)

    def _solve(self, t, y, yp, h):
        """From the interpolated point: with the kept matrix, then (``SPLICE``) with it
        and the integrator's newer algebraic columns, then with a fresh one."""
        for how in ("kept", "spliced", "fresh") if self.kept else ("fresh",):
            if how == "spliced" and not self._splice():
                continue
            try:
                result = self._newton(t, y, yp, h, how == "fresh")
            except ResidualDomainError:
                result = None
            if result is not None:
                return result
        self.kept = False
        if not GLOBALISED:
            raise DAEError(f"the output point at t = {t:.10g} was not solved locally")
        y, yp = solve_consistent(
            self.F,
            t,
            y,
            yp,
            self.unknown_y,
            rtol=self.rtol,
            atol=self.atol,
            h_scale=h,
            matrix=self.matrix,
            variable_names=self.names,
            equation_names=self.eq_names,
            what=f"the output point at t = {t:.10g}",
        )
        return y, yp

    def _block_triangular(self) -> bool:
        """True when the rows that read no y' (the algebraic equations G(y) = 0) are as
        many as the algebraic unknowns in the factorised matrix: it is then block lower
        triangular, [[dG/dy_a, 0], [B, dF_d/dy'_d]], and the update of the algebraic y
        is Newton's on G alone, whatever the y' (their accuracy is then tested alone)."""
        m = self.matrix.matrix
        cols = ~self.unknown_y
        if self.matrix.sparse:
            sub = m.tocsc()[:, np.flatnonzero(cols)]
            reading = np.unique(sub.nonzero()[0]).size
        else:
            reading = int(np.count_nonzero(np.any(m[:, cols] != 0.0, axis=1)))
        return m.shape[0] - reading == self.alg.size

    def _splice(self) -> bool:
        """The kept matrix with its algebraic columns taken from the integrator's matrix
        when that is newer (evaluated since this matrix was): True when factorised. The
        columns of an algebraic y are dF/dy_a in both (F reads no algebraic y', so the
        integrator's cj does not enter them); no residual evaluation."""
        src = None if self.source is None else self.source.matrix
        if src is None or src is self.spliced_from or self.matrix.matrix is None:
            return False
        self.spliced_from = src
        m = self.matrix.matrix
        if self.matrix.sparse:
            if not scipy.sparse.issparse(src) or src.data.shape != m.data.shape:
                return False
            if self._alg_entries is None:
                p = self.matrix.pattern
                cols = np.repeat(np.arange(p.shape[1]), np.diff(p.indptr))
                self._alg_entries = self.unknown_y[cols]
            data = np.where(self._alg_entries, src.data, m.data)
            spliced = type(m)((data, m.indices, m.indptr), shape=m.shape)
        else:
            if scipy.sparse.issparse(src) or getattr(src, "shape", None) != m.shape:
                return False
            spliced = m.copy()
            spliced[:, self.unknown_y] = src[:, self.unknown_y]
        self.matrix.matrix = spliced
        try:
            self.matrix.factorize()
        except SingularMatrixError:
            self.kept = False
            return False
        self.stats_spliced += 1
        return True

    def _fresh_matrix(self, t, y, yp, f, uw) -> bool:
        """dF/du at (y, yp) (f = F there, uw the weights), factorised and kept: True."""
        u = np.where(self.unknown_y, y, yp)
        inc = np.maximum(SQRT_EPS * np.abs(u), 1.0 / uw)
        inc = (u + inc) - u  # exactly representable
        tiny = inc == 0.0
        if np.any(tiny):
            inc[tiny] = np.spacing(np.abs(u[tiny])) * 2.0**20
        self.kept = False
        self.matrix.matrix = self.matrix.finite_difference(
            t, y, yp, f, inc, self.ymask, self.ypmask
        )
        try:
            self.matrix.factorize()
        except SingularMatrixError:
            return False
        self.kept = True
        if self.source is not None:
            self.spliced_from = self.source.matrix  # not newer than this one
        self.block = ALGEBRAIC_TEST and self._block_triangular()
        return True

    def _weights(self, y, h):
        return 1.0 / (self.rtol * np.abs(y) + self.atol) * (self.ymask + h * self.ypmask)

    def _newton(self, t, y, yp, h, fresh, f=None):
        """Modified Newton from (y, yp) (``f``: F there where known); (y, yp) when
        converged, else None."""
        y, yp = y.copy(), yp.copy()
        f = self.F(t, y, yp) if f is None else f
        if not np.all(np.isfinite(f)):
            return None
        uw = self._weights(y, h)
        if fresh and not self._fresh_matrix(t, y, yp, f, uw):
            return None
        previous = np.inf
        for k in range(MAX_ITERS):
            d = self.matrix.solve(-f)
            dw = d * uw
            if self.block and ALGEBRAIC_MAX:
                dnorm = float(np.max(np.abs(dw[self.alg])))
            else:
                dnorm = float(np.sqrt(np.mean((dw[self.alg] if self.block else dw) ** 2)))
            if not np.isfinite(dnorm) or dnorm > RATE_MAX * previous:
                return None
            y += d * self.ymask
            yp += d * self.ypmask
            # what is left after this update: about rate / (1 - rate) dnorm with the
            # contraction rate of this solve (the DASSL/IDA test; RATE_MAX = 0.5 keeps
            # the factor <= 1); after the first update only when that update itself is
            # below CONVERGED. Never with the rate of an earlier point: a matrix kept
            # from before the MSL drum boiler's feed started (no flow through the node)
            # gave a node enthalpy of -1.4e8 J/kg, accepted after one update.
            left = dnorm if k == 0 else rate_factor(dnorm / previous) * dnorm
            if left <= CONVERGED and dnorm <= RATE_TRUSTED:
                return y, yp
            previous = dnorm
            f = self.F(t, y, yp)
            if not np.all(np.isfinite(f)):
                return None
            uw = self._weights(y, h)
        return None


__all__ = ["AlgebraicRefiner", "DAEError"]
