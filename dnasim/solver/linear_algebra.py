"""The Newton iteration matrix J = dF/dy + cj dF/dy': finite differences, colouring, LU.

Finite differences follow SUNDIALS IDA's difference-quotient Jacobian: column j
is perturbed by

    inc_j = max(sqrt(u) * max(|y_j|, |h y'_j|), 1 / w_j)   (signed like h y'_j)

in y_j and by cj * inc_j in y'_j at the same time, so one residual evaluation
yields the column of dF/dy + cj dF/dy' directly (u: unit round-off, w: the
error weights). With a sparsity pattern the columns are grouped so that no two
columns of a group share a row (greedy colouring of the column intersection
graph, Curtis-Powell-Reid); each group costs one residual evaluation. The
pattern is that of dF/dy + dF/dy' plus the diagonal (``KEEP_DIAGONAL``: the
stored zeros are still needed, see there). The matrix is factorised by LAPACK's
band LU when the pattern, matched and reverse-Cuthill-McKee ordered, is banded
(``dnasim.solver.band``, with the rule for the choice), by sparse LU (SuperLU via
scipy.sparse.linalg.splu) otherwise. Without a pattern the matrix is dense and
factorised by LAPACK (lu_factor).

One-sided differences never straddle a switch. A restart switch (a phase
line, say) marks where the residual has a kink: on the saturated-liquid line
dρ/dp of water jumps by a factor of about 440 (60 bar). The increment
floor 1 / w_j is rtol |h| + atol, about 1.2 J/kg for an enthalpy at rtol 1e-6,
so a volume closer than that to the line got a secant across the kink as its
column, and the Newton diverged at every step size (it "converged too slowly"
down to h = 1e-12). With ``side(t, y, yp)`` set (the signs of the restart
switches), a group whose perturbed state changes a sign is evaluated again
with the increments reversed: the difference is taken on the side of the
kink where the point lies, the derivative of the smooth piece it is on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg
from scipy.sparse.csgraph import maximum_bipartite_matching

from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver.band import BandLU, BandOrdering
from dnasim.solver.callbacks import call_user, user_error

SQRT_EPS = float(np.sqrt(np.finfo(float).eps))
#: add the diagonal to the pattern (stored zeros where dF/dy + dF/dy' has none). Kept
#: on: without it tests/test_plant_reverse_flow.py::test_air_pipe_reversal fails (a
#: node temperature of 205 K through the flow reversal, below the isentropic bound of
#: 256 K), not yet understood; with the band LU the zeros cost only band storage.
KEEP_DIAGONAL = True
# LAPACK directly: scipy's wrappers (lu_factor, lu_solve) cost more than the work here
_GETRF, _GETRS = scipy.linalg.get_lapack_funcs(("getrf", "getrs"), (np.zeros(1),))


def colour_columns(pattern: scipy.sparse.csc_matrix, order_by=None) -> list[np.ndarray]:
    """Group the columns of a sparsity pattern so no two in a group share a row.

    Greedy colouring of the column intersection graph, the columns taken in
    "largest first" order (most columns sharing a row with them first, ties in
    natural order). The number of groups is at least the largest number of entries
    in a row; largest first reaches that bound on the small plants, where natural
    order needed up to 2 more groups (attemperator.toml 13 -> 11 = bound, the
    1000-volume steam pipe 17 -> 13, bound 11). Which columns share a group does not
    change a column of the matrix: row i sees one perturbed column of its own.
    ``order_by``: the pattern whose column degrees set the order (default: ``pattern``).
    """
    n_rows, n_cols = pattern.shape
    indptr, indices = pattern.indptr, pattern.indices
    if order_by is None:
        order_by = pattern
    structure = scipy.sparse.csc_matrix(
        (np.ones(order_by.indices.size), order_by.indices, order_by.indptr), shape=order_by.shape
    )
    degree = np.diff((structure.T @ structure).tocsr().indptr)
    order = np.argsort(-degree, kind="stable")
    # per row: the groups that already hold a column with an entry in it, as the bits
    # of an integer; a column goes to the lowest group none of its rows has (first
    # fit), a new one when there is none. Bit operations on Python integers: at 7015
    # columns 10 ms, where a boolean row mask per group and numpy tests took 90 ms.
    row_groups = [0] * n_rows
    ptr, idx = indptr.tolist(), indices.tolist()
    group_of = np.empty(n_cols, dtype=np.intp)
    n_groups = 0
    for j in order.tolist():
        rows = idx[ptr[j] : ptr[j + 1]]
        taken = 0
        for r in rows:
            taken |= row_groups[r]
        g = (~taken & (taken + 1)).bit_length() - 1  # the lowest group not taken
        bit = 1 << g
        for r in rows:
            row_groups[r] |= bit
        group_of[j] = g
        n_groups = max(n_groups, g + 1)
    return [np.flatnonzero(group_of == g) for g in range(n_groups)]


def trailing_rows(pattern, sparsity, quadrature):
    """The equations of quadratures that the Jacobian may keep to their quadrature's
    entry (``IterationMatrix``, class doc), or None when there are none.

    ``pattern``: the CSC pattern the matrix is stored on (the diagonal added);
    ``sparsity``: the entries that can be non-zero; ``quadrature``: mask or indices of
    the quadratures. A row r qualifies when it is the only row of some quadrature's
    column c in ``sparsity`` (and of no second one), and it has more entries than
    every row that does not qualify (it would raise the colouring's lower bound).
    Returns (reduced, constraint, {r: c}): ``pattern`` without row r's entries but
    (r, c) and the diagonal (r, r) (set to zero), and the colouring's pattern,
    ``reduced`` with a row {c, j} for every other column j of row r (c's group must
    hold no column that F_r reads, or its entry would be polluted; the others may
    share groups)."""
    q = np.asarray(quadrature)
    q = np.flatnonzero(q) if q.dtype == bool else q.astype(np.intp)
    if q.size == 0:
        return None
    structural = scipy.sparse.csc_matrix(sparsity, dtype=float, copy=True)
    structural.data[:] = 1.0
    structural.eliminate_zeros()
    count = np.diff(structural.indptr)
    q = q[count[q] == 1]
    if q.size == 0:
        return None
    rows = structural.indices[structural.indptr[q]]
    unique, times = np.unique(rows, return_counts=True)
    single = np.isin(rows, unique[times == 1])
    rows, q = rows[single], q[single]
    csr = structural.tocsr()
    row_nnz = np.diff(csr.indptr)
    others = np.ones(row_nnz.size, dtype=bool)
    others[rows] = False
    largest_other = int(np.max(row_nnz[others], initial=0))
    keep = row_nnz[rows] > largest_other
    rows, q = rows[keep], q[keep]
    if rows.size == 0:
        return None
    col_of_row = np.full(row_nnz.size, -1, dtype=np.intp)
    col_of_row[rows] = q
    coo = pattern.tocoo()
    # (r, r), the added diagonal's, stays (zero: ``IterationMatrix.finite_difference``):
    # without it the matching of the band ordering took 2.9 s instead of 0.2 ms
    kept = (col_of_row[coo.row] < 0) | (coo.col == col_of_row[coo.row]) | (coo.row == coo.col)
    n = pattern.shape[0]
    reduced = scipy.sparse.csc_matrix(
        (np.ones(int(kept.sum())), (coo.row[kept], coo.col[kept])), shape=pattern.shape
    )
    reduced.sort_indices()
    # the rows {c, j}: c's group shares no column with row r
    extra_rows, extra_cols = [], []
    k = 0
    for r, c in zip(rows.tolist(), q.tolist(), strict=True):
        others_r = csr.indices[csr.indptr[r] : csr.indptr[r + 1]]
        others_r = others_r[others_r != c]
        ids = np.arange(k, k + others_r.size)
        extra_rows += [ids, ids]
        extra_cols += [np.full(others_r.size, c), others_r]
        k += others_r.size
    extra = scipy.sparse.csc_matrix(
        (np.ones(2 * k), (np.concatenate(extra_rows), np.concatenate(extra_cols))), shape=(k, n)
    )
    constraint = scipy.sparse.vstack([reduced, extra], format="csc")
    constraint.sort_indices()
    return reduced, constraint, dict(zip(rows.tolist(), q.tolist(), strict=True))


class SingularMatrixError(DAEError):
    """The iteration matrix could not be factorised."""


class IterationMatrix:
    """Builds and factorises J = dF/dy + cj dF/dy' for the modified Newton iteration.

    ``residual`` is the counted residual function; ``jac`` an optional user
    Jacobian ``jac(t, y, yp, cj)``; ``sparsity`` an optional (n, n) pattern of
    dF/dy + dF/dy' (anything scipy.sparse accepts, or a dense 0/1 array).

    ``residual_for_columns`` (optional, with a pattern only): the partial-residual
    channel, given by the caller (a compiled plant's
    ``dnasim.compilation.system.System.residual_for_columns``). ``residual_for_columns(cols)``
    returns F_cols(t, y, yp, f0): F at a point that differs from the point of
    f0 = F(t, y0, yp0) only in the columns ``cols``, with the rows that read none of
    them taken from f0. A column group's Jacobian entries are rows that read the
    group's columns, so the matrix is the same as from whole evaluations
    (tests/test_jacobian_partial.py), at the cost of the components the group
    touches: a Jacobian of attemperator.toml costs 0.90 of its whole-plant
    evaluations (its pipe is in 11 of the 11 groups, the boundaries and valves in 3
    to 5), of superheater_line.toml also 0.90 (each pipe in 12 or 13 of 13). None:
    every group is a whole evaluation of ``residual``.

    ``side`` (optional): side(t, y, yp) -> array whose signs mark the smooth piece of
    the residual (the restart switches, module doc); None: no kinks known.

    ``quadrature`` (optional, with a pattern only): mask of the unknowns whose Newton
    update may trail by one iteration (the quadratures, out of every convergence
    norm). The equation of a quadrature q (its column read by that equation alone)
    that reads more columns than any other equation keeps only its entry in column
    q (``trailing_rows``): the heat to a fixed wall, dQ_passed/dt = sum_i Q_i over a
    pipe's 1000 volumes, needed 1002 column groups (each a residual evaluation) and
    broke the band, for 13 without it. Column q is read by no other equation, so the
    matrix is block triangular and the other unknowns' update is unchanged (to the
    bit: their entries are the same); only q's update lags, by the others' last one.
    """

    def __init__(
        self,
        residual: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
        n: int,
        jac: Callable | None = None,
        sparsity=None,
        names: Sequence[str] | None = None,
        equation_names: Sequence[str] | None = None,
        *,
        residual_for_columns: Callable | None = None,
        side: Callable | None = None,
        quadrature=None,
    ):
        self.residual = residual
        self.n = n
        self.jac = jac
        self.names = names
        self.equation_names = equation_names
        self.sparse = sparsity is not None
        self.band = None
        self.trailing = None  # {row: its quadrature's column} (``trailing_rows``)
        if sparsity is not None:
            pattern = scipy.sparse.csc_matrix(sparsity, dtype=float, copy=True)
            if pattern.shape != (n, n):
                raise DAEError(
                    f"jac_sparsity has shape {pattern.shape}, but the system has {n} unknowns: "
                    f"it must be ({n}, {n})."
                )
            if KEEP_DIAGONAL:
                pattern = pattern + scipy.sparse.eye(n, format="csc")
            pattern.data[:] = 1.0
            pattern.eliminate_zeros()
            pattern.sum_duplicates()
            pattern.sort_indices()
            groups = None
            if quadrature is not None and jac is None:
                found = trailing_rows(pattern, sparsity, quadrature)
                if found is not None:
                    reduced, constraint, trailing = found
                    groups = colour_columns(constraint, order_by=reduced)
                    # the largest row is a lower bound of the whole pattern's groups
                    if len(groups) < int(np.max(np.diff(pattern.tocsr().indptr))):
                        pattern, self.trailing = reduced, trailing
                        # the trailing rows' entries but their quadrature's: zero
                        cols = np.repeat(np.arange(n), np.diff(pattern.indptr))
                        col_of = np.full(n, -1, dtype=np.intp)
                        col_of[list(trailing)] = list(trailing.values())
                        c = col_of[pattern.indices]
                        self._trailing_zero = np.flatnonzero((c >= 0) & (cols != c))
                        self._trailing_rows = np.array(list(trailing), dtype=np.intp)
                        self._trailing_cols = np.array(list(trailing.values()), dtype=np.intp)
                        self._trailing_pos = np.array(
                            [
                                np.flatnonzero((pattern.indices == r) & (cols == q))[0]
                                for r, q in trailing.items()
                            ],
                            dtype=np.intp,
                        )
                        # the rows' values alone (``trailing_residual``): the components
                        # that read the rows' columns
                        read = scipy.sparse.csr_matrix(sparsity)[self._trailing_rows]
                        self._trailing_partial = (
                            None
                            if residual_for_columns is None
                            else residual_for_columns(np.unique(read.indices))
                        )
                    else:
                        groups = None
            self.pattern = pattern
            self.band = BandOrdering.of(pattern)
            if self.band is None or not self.band.worthwhile:
                # the ordering from the entries that can be non-zero: the added
                # diagonal's stored zeros can widen the band (band.BandOrdering.of; the
                # steam pipe: kl, ku = 158, 157 -> 11, 15). Only then: on the air pipe
                # reversal (tests/test_plant_reverse_flow.py) the other LU's round-off
                # took the run into a Newton failure at 110 s (issue 7's reverse flow)
                structural = scipy.sparse.csc_matrix(sparsity, dtype=float, copy=True)
                structural.data[:] = 1.0
                structural.eliminate_zeros()
                if self.trailing is not None:
                    structural = structural.multiply(pattern).tocsc()
                self.band = BandOrdering.of(pattern, structural) or self.band
            if self.band is not None and not self.band.worthwhile:
                self.band = None
            self.groups = groups if groups is not None else colour_columns(pattern)
            # For each group: the positions in pattern.data, their rows and columns.
            cols_of_entry = np.repeat(np.arange(n), np.diff(pattern.indptr))
            self._group_entries = []
            group_of_col = np.empty(n, dtype=np.intp)
            for g, cols in enumerate(self.groups):
                group_of_col[cols] = g
            group_of_entry = group_of_col[cols_of_entry]
            for g, cols in enumerate(self.groups):
                pos = np.flatnonzero(group_of_entry == g)
                self._group_entries.append((cols, pos, pattern.indices[pos], cols_of_entry[pos]))
            # per group: F at a point perturbed in the group's columns, evaluating only
            # the rows that read them (``residual_for_columns``, class doc), or None
            self._group_residuals = [
                None if residual_for_columns is None else residual_for_columns(cols)
                for cols in self.groups
            ]
        self.matrix = None
        self.cj = None
        self._lu = None
        self.side = side  # the signs of the restart switches (class doc), or None
        self.quadrature = quadrature  # as given (class doc): for a matrix on the same pattern
        self.flipped_groups = 0  # groups differenced backwards to stay on one side

    # -- building ---------------------------------------------------------------------------
    def evaluate(self, t, y, yp, f0, cj, h, weights) -> None:
        """Compute J = dF/dy + cj dF/dy' at (t, y, yp); f0 = F(t, y, yp) already evaluated."""
        if self.jac is not None:
            matrix = call_user(self.jac, "the Jacobian function jac", t, t, y, yp, cj)
            if scipy.sparse.issparse(matrix):
                self.sparse = True
                matrix = scipy.sparse.csc_matrix(matrix)
            else:
                self.sparse = False
                matrix = np.asarray(matrix, dtype=float)
            if matrix.shape != (self.n, self.n):
                raise DAEError(f"jac returned shape {matrix.shape}; expected ({self.n}, {self.n}).")
        else:
            inc = SQRT_EPS * np.maximum(np.abs(y), np.abs(h * yp))
            inc = np.maximum(inc, 1.0 / weights)
            inc = np.where(h * yp < 0.0, -inc, inc)
            inc = (y + inc) - y  # exactly representable increments
            matrix = self.finite_difference(t, y, yp, f0, inc, 1.0, cj)
        self.matrix = matrix
        self.cj = cj
        self._lu = None

    def finite_difference(self, t, y, yp, f0, inc, dy_coef, dyp_coef):
        """Columns (F(y + a_j inc_j e_j, yp + b_j inc_j e_j) - f0) / inc_j (a, b: the coefficients).

        With a = 1, b = cj this is dF/dy + cj dF/dy'; with a and b 0/1 masks it is the
        Jacobian of F with respect to a mix of y and y' components (used to make the
        initial values consistent). Grouped by the column colouring when sparse.
        """
        dy = inc * dy_coef
        dyp = inc * dyp_coef
        side0 = None if self.side is None else np.sign(self.side(t, y, yp))

        def perturbed(cols, partial=None):
            """F at the perturbed point and the increments used (reversed across a kink)."""
            y_pert, yp_pert = y.copy(), yp.copy()
            y_pert[cols] += dy[cols]
            yp_pert[cols] += dyp[cols]
            sign = 1.0
            if side0 is not None and np.any(np.sign(self.side(t, y_pert, yp_pert)) != side0):
                self.flipped_groups += 1
                y_pert[cols] = y[cols] - dy[cols]
                yp_pert[cols] = yp[cols] - dyp[cols]
                sign = -1.0
            if partial is None:
                return self.residual(t, y_pert, yp_pert), sign
            return self._partial(partial, t, y_pert, yp_pert, f0), sign

        if self.sparse:
            data = np.empty_like(self.pattern.data)
            for k, (cols, pos, rows, entry_cols) in enumerate(self._group_entries):
                f_pert, sign = perturbed(cols, self._group_residuals[k])
                data[pos] = (f_pert - f0)[rows] / (sign * inc[entry_cols])
            if self.trailing is not None:
                data[self._trailing_zero] = 0.0  # left out (class doc)
            p = self.pattern
            return scipy.sparse.csc_matrix((data, p.indices, p.indptr), shape=p.shape)
        n = self.n
        matrix = np.empty((n, n))
        if side0 is None:  # no kinks: one element perturbed, indexed as a scalar
            for j in range(n):
                y_pert, yp_pert = y.copy(), yp.copy()
                y_pert[j] += dy[j]
                yp_pert[j] += dyp[j]
                matrix[:, j] = (self.residual(t, y_pert, yp_pert) - f0) / inc[j]
            return matrix
        for j in range(n):
            f_pert, sign = perturbed(np.array([j]))
            matrix[:, j] = (f_pert - f0) / (sign * inc[j])
        return matrix

    def trailing_entries(self):
        """(rows, quadrature columns, their entries J_qq in the current matrix) of the
        rows left out (class doc), or None."""
        if self.trailing is None or self.matrix is None:
            return None
        return self._trailing_rows, self._trailing_cols, self.matrix.data[self._trailing_pos]

    def trailing_residual(self, t, y, yp) -> np.ndarray:
        """The rows left out (class doc) at (t, y, yp), counted as one evaluation: by the
        partial channel, only the components that read them, when there is one."""
        if self._trailing_partial is not None:
            f = self._partial(self._trailing_partial, t, y, yp, np.zeros(self.n))
        else:
            f = self.residual(t, y, yp)
        return f[self._trailing_rows]

    def _partial(self, partial, t, y, yp, f0):
        """``partial(t, y, yp, f0)`` counted and with errors reported as a whole
        evaluation of the (counted) residual would report them."""
        stats = getattr(self.residual, "stats", None)
        if stats is not None:
            stats.residual_evals += 1
        try:
            return partial(t, y, yp, f0)
        except (ResidualDomainError, DAEError):
            raise
        except Exception as exc:
            raise user_error("the residual", t, exc) from exc

    @property
    def evaluations_per_jacobian(self) -> int:
        """Residual evaluations one finite-difference Jacobian costs."""
        if self.jac is not None:
            return 0
        return len(self.groups) if self.sparse else self.n

    # -- factorising and solving -------------------------------------------------------------
    def factorize(self) -> None:
        """LU-factorise the current matrix; raise SingularMatrixError if singular."""
        self.nonfinite = not np.all(np.isfinite(self.matrix.data if self.sparse else self.matrix))
        if self.nonfinite:
            raise SingularMatrixError(
                "The iteration matrix dF/dy + cj*dF/dy' has non-finite entries"
                + self._describe_nonfinite()
            )
        if self.sparse and self._banded() and self._zero_outside_band():
            self._lu = BandLU(self.band, self.matrix.data)
            diag_u = self._lu.diagonal_u()
        elif self.sparse:
            try:
                self._lu = scipy.sparse.linalg.splu(self.matrix)
            except RuntimeError as exc:
                raise SingularMatrixError(self._describe_singular(str(exc))) from None
            diag_u = self._lu.U.diagonal()
        else:
            # getrf as scipy.linalg.lu_factor calls it (a copy of the matrix is factorised);
            # a zero pivot (info > 0) is caught below
            lu, piv, _ = _GETRF(self.matrix)
            self._lu = (lu, piv)
            diag_u = np.diag(lu)
        if np.any(diag_u == 0.0) or not np.all(np.isfinite(diag_u)):
            raise SingularMatrixError(self._describe_singular("a zero pivot in LU"))

    def _zero_outside_band(self) -> bool:
        """The stored entries the band leaves out (the added diagonal's) are zero."""
        out = self.band.outside
        return out is None or not np.any(self.matrix.data[out])

    def _banded(self) -> bool:
        """The current matrix is stored on the pattern whose band ordering is kept."""
        m = self.matrix
        return (
            self.band is not None
            and m.nnz == self.pattern.nnz
            and np.array_equal(m.indptr, self.pattern.indptr)
            and np.array_equal(m.indices, self.pattern.indices)
        )

    def dense_lu(self):
        """(lu, piv) of LAPACK's getrf for a dense matrix (None when sparse)."""
        return None if self.sparse else self._lu

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve J x = rhs with the stored LU factors."""
        if self.sparse:
            return self._lu.solve(rhs)
        lu, piv = self._lu
        x, info = _GETRS(lu, piv, rhs)  # LAPACK directly: scipy's wrapper costs more here
        return x

    # -- diagnostics -------------------------------------------------------------------------
    def _name(self, i: int) -> str:
        if self.names is not None and i < len(self.names):
            return f"{self.names[i]} (index {i})"
        return f"index {i}"

    def _eq(self, i: int) -> str:
        if self.equation_names is not None and i < len(self.equation_names):
            return f"equation {self.equation_names[i]}"
        return f"equation {i}"

    def _describe_nonfinite(self) -> str:
        dense = self.matrix.toarray() if self.sparse else self.matrix
        rows, cols = np.nonzero(~np.isfinite(dense))
        eqs = ", ".join(self._eq(r) for r in sorted(set(rows.tolist()))[:5])
        var = ", ".join(self._name(c) for c in sorted(set(cols.tolist()))[:5])
        return f": in {eqs}, with respect to {var}."

    def _describe_singular(self, detail: str) -> str:
        """Name the equations and variables that make the matrix singular."""
        pattern = scipy.sparse.csr_matrix(self.matrix != 0)
        match = maximum_bipartite_matching(pattern, perm_type="column")
        unmatched_rows = np.flatnonzero(match < 0)
        matched_cols = set(match[match >= 0].tolist())
        unmatched_cols = [j for j in range(self.n) if j not in matched_cols]
        head = f"The iteration matrix dF/dy + cj*dF/dy' is singular ({detail}). "
        if unmatched_rows.size:
            eqs = ", ".join(self._eq(i) for i in unmatched_rows[:8])
            var = ", ".join(self._name(j) for j in unmatched_cols[:8])
            return (
                head + f"It is structurally singular: {eqs} cannot be paired with a variable of "
                f"its own, and {var} appear in no equation that is not needed elsewhere. Check "
                "that every variable is determined by exactly one equation (an algebraic loop "
                "with no algebraic variable, or an index above 1, gives this)."
            )
        dense = self.matrix.toarray() if self.sparse else self.matrix
        if self.n <= 3000:
            u, s, vt = np.linalg.svd(dense)
            var_idx = np.argsort(-np.abs(vt[-1]))[:4]
            eq_idx = np.argsort(-np.abs(u[:, -1]))[:4]
            var = ", ".join(self._name(j) for j in var_idx)
            eqs = ", ".join(self._eq(i) for i in eq_idx)
            return (
                head + f"It is numerically singular (smallest singular value {s[-1]:.3g}). "
                f"The variables most involved: {var}; the equations most involved: {eqs}."
            )
        return head + "It is numerically singular."
