"""Banded LU for a sparse iteration matrix whose matched and reordered pattern is banded.

Ordering (once per pattern):

1. match equations to unknowns (Hopcroft-Karp,
   ``scipy.sparse.csgraph.maximum_bipartite_matching``): row r_j is the equation
   matched to unknown j, so B = A[r, :] has a structurally non-zero diagonal;
2. reverse Cuthill-McKee (``scipy.sparse.csgraph.reverse_cuthill_mckee``) on the
   symmetrised pattern B + B^T and on B^T B (unknowns that share an equation are
   neighbours) gives two permutations p; the one with the narrower LAPACK band
   (2 kl + ku + 1) is kept, and the reordered matrix is A' = A[r[p], :][:, p]. On
   the steam pipe B^T B gives kl, ku = 11, 15 at 1000 volumes where B + B^T gives
   19, 20.

A' has kl sub- and ku super-diagonals. A chain of volumes (a pipe) gives a band
whatever the order the components were declared in (kl, ku = 11, 12 for the
steam pipe at 100 volumes, 11, 15 at 1000). LAPACK's band LU with partial
pivoting (dgbtrf) then costs about
2 n kl (kl + ku) flops and a solve (dgbtrs) about 2 n (2 kl + ku), against
SuperLU's symbolic work and its fill-in outside the band.

Choice (``BandOrdering.worthwhile``): the band solver is used when kl + ku <=
BAND_NARROW (128), or else when the band with the room pivoting needs,
n (2 kl + ku + 1) entries, holds at most BAND_FILL_MAX (12) times the stored
entries of the pattern; SuperLU otherwise. Measured (CPU time, random values on
the plants' patterns; LU, then one solve):

    plant                    n   kl  ku   SuperLU           band (dgbtrf/dgbtrs)
    air_pipe                22   10  10   0.034 / 0.005 ms  0.006 / 0.003 ms
    attemperator            67   19  19   0.052 / 0.008 ms  0.018 / 0.005 ms
    superheater_line       357   54  53   0.325 / 0.027 ms  0.326 / 0.020 ms
    steam pipe N = 100     715   11  12   0.72 / 0.058 ms   0.16 / 0.033 ms
    steam pipe N = 1000   7015   11  15   4.1 / 0.44 ms     1.2 / 0.25 ms

The band LU costs about 2 n kl (kl + ku) flops, SuperLU about the same inside its
fill plus its symbolic work; past kl + ku ~ 128 a band wide enough to hold a
plant's long-range couplings holds mostly zeros, and SuperLU's fill-reducing
ordering (COLAMD) wins.

Solving A x = b: b' = b[r[p]], A' x' = b', x[p] = x'.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
from scipy.linalg.lapack import dgbtrf, dgbtrs
from scipy.sparse.csgraph import maximum_bipartite_matching, reverse_cuthill_mckee

BAND_NARROW = 128  # kl + ku at or below this: always banded
BAND_FILL_MAX = 12.0  # band storage / stored pattern entries at or below this: banded


class BandOrdering:
    """The matched, RCM-reordered band structure of a CSC pattern (or None if none exists).

    Attributes: ``rows`` (equation order), ``cols`` (unknown order), ``kl``, ``ku``,
    and ``flat``: for every stored entry of the CSC pattern (in ``pattern.data``
    order) its position in the Fortran-ordered LAPACK band array of shape
    (2 kl + ku + 1, n).
    """

    def __init__(self, rows, cols, kl, ku, flat, n, nnz, outside=None):
        #: stored entries (positions in the pattern's data) left out of the band: they
        #: must be zero (``IterationMatrix.factorize`` checks); None when there are none.
        #: ``inside``: the others, in the order of ``flat``
        self.outside = outside
        self.inside = None
        self.rows = rows
        self.cols = cols
        self.kl = kl
        self.ku = ku
        self.flat = flat
        self.n = n
        self.nnz = nnz
        self.ldab = 2 * kl + ku + 1

    @classmethod
    def of(cls, pattern: scipy.sparse.csc_matrix, structural=None) -> BandOrdering | None:
        """The ordering of a square CSC pattern; None when it is structurally singular.

        ``structural``: the entries that can be non-zero, a sub-pattern of ``pattern``
        (default: all of it). The matching and the ordering are computed from them;
        the other stored entries of ``pattern`` (stored zeros: the diagonal that
        ``linear_algebra.KEEP_DIAGONAL`` adds) that fall outside the band are marked
        ``outside`` and not stored in it. The added diagonal pairs equation i with
        unknown i, which the plant's layout does not relate: on the steam pipe it
        joined volume k's heat equation to volume k - 7's pressure, and RCM of the
        pattern with it gave kl, ku = 158, 157 at every N >= 100 (without it: 11, 15
        at N = 1000), so SuperLU was used."""
        n = pattern.shape[0]
        if structural is not None:
            ordering = cls.of(scipy.sparse.csc_matrix(structural))
            if ordering is None:
                return None
            # where every entry of ``pattern`` lands in that ordering
            new_row = np.empty(n, dtype=np.intp)
            new_row[ordering.rows] = np.arange(n)
            new_col = np.empty(n, dtype=np.intp)
            new_col[ordering.cols] = np.arange(n)
            i = new_row[pattern.indices]
            j = new_col[np.repeat(np.arange(n), np.diff(pattern.indptr))]
            kl, ku = ordering.kl, ordering.ku
            out = (i - j > kl) | (j - i > ku)
            ldab = 2 * kl + ku + 1
            if not out.any():
                flat = (kl + ku + i - j) + j * ldab
                return cls(ordering.rows, ordering.cols, kl, ku, flat, n, pattern.nnz)
            inside = np.flatnonzero(~out)
            flat = (kl + ku + i[inside] - j[inside]) + j[inside] * ldab
            o = cls(ordering.rows, ordering.cols, kl, ku, flat, n, pattern.nnz, np.flatnonzero(out))
            o.inside = inside
            return o
        csr = scipy.sparse.csr_matrix(pattern)
        match = maximum_bipartite_matching(csr, perm_type="column")  # column of each row
        if np.any(match < 0):
            return None
        row_of_col = np.empty(n, dtype=np.intp)
        row_of_col[match] = np.arange(n)
        matched = csr[row_of_col, :]
        matched.data[:] = 1.0
        entry_cols = np.repeat(np.arange(n), np.diff(pattern.indptr))
        best = None
        for graph in (matched + matched.T, matched.T @ matched):
            p = np.asarray(reverse_cuthill_mckee(graph.tocsr(), symmetric_mode=True), np.intp)
            rows = row_of_col[p]
            new_row = np.empty(n, dtype=np.intp)
            new_row[rows] = np.arange(n)
            new_col = np.empty(n, dtype=np.intp)
            new_col[p] = np.arange(n)
            i = new_row[pattern.indices]
            j = new_col[entry_cols]
            kl = int(max(np.max(i - j, initial=0), 0))
            ku = int(max(np.max(j - i, initial=0), 0))
            if best is None or 2 * kl + ku < 2 * best[2] + best[3]:
                best = (rows, p, kl, ku, i, j)
        rows, cols, kl, ku, i, j = best
        ldab = 2 * kl + ku + 1
        flat = (kl + ku + i - j) + j * ldab
        return cls(rows, cols, kl, ku, flat, n, pattern.nnz)

    @property
    def worthwhile(self) -> bool:
        """The band LU pays: a narrow band, or a band not much larger than the pattern."""
        if self.kl + self.ku <= BAND_NARROW:
            return True
        return self.n * self.ldab <= BAND_FILL_MAX * max(self.nnz, 1)


class BandLU:
    """LAPACK band LU (dgbtrf) of a CSC matrix with a pattern ordered by ``BandOrdering``."""

    def __init__(self, ordering: BandOrdering, data: np.ndarray):
        o = ordering
        buf = np.zeros(o.ldab * o.n)
        buf[o.flat] = data if o.inside is None else data[o.inside]
        ab = buf.reshape((o.ldab, o.n), order="F")
        self.lu, self.piv, info = dgbtrf(ab, o.kl, o.ku, overwrite_ab=1)
        self.ordering = o
        self.info = info

    def diagonal_u(self) -> np.ndarray:
        """The diagonal of U (the pivots), in the reordered sequence."""
        o = self.ordering
        return self.lu[o.kl + o.ku]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        o = self.ordering
        x_perm, _ = dgbtrs(self.lu, o.kl, o.ku, rhs[o.rows], self.piv, overwrite_b=1)
        x = np.empty_like(x_perm)
        x[o.cols] = x_perm
        return x
