"""The band LU after matching and reverse Cuthill-McKee (dnasim.solver.band), the pattern
without stored zeros, IDA's band solver on the same ordering, and the restart step."""

import math

import numpy as np
import pytest
import scipy.sparse as sp

from dnasim.solver import band as band_module
from dnasim.solver import bdf, linear_algebra, solve_dae
from dnasim.solver.band import BandLU, BandOrdering
from dnasim.solver.linear_algebra import IterationMatrix

EPS = np.finfo(float).eps


def shuffled_chain(n, seed=0):
    """A chain (x_i coupled to x_{i-1}, x_{i+1}) whose equations and unknowns are shuffled,
    with equation i's own unknown NOT on the diagonal: returns (pattern, perm_rows, perm_cols)."""
    rng = np.random.default_rng(seed)
    rows, cols = [], []
    for i in range(n):
        for j in (i - 1, i, i + 1):
            if 0 <= j < n:
                rows.append(i)
                cols.append(j)
    pr, pc = rng.permutation(n), rng.permutation(n)
    chain = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)).tocsr()
    return sp.csc_matrix(chain[pr][:, pc]), pr, pc


def test_band_ordering_recovers_the_chain_and_solves_like_dense():
    n = 60
    pattern, _, _ = shuffled_chain(n)
    pattern.sort_indices()
    o = BandOrdering.of(pattern)
    assert o is not None
    # a chain is tridiagonal in its own order; the matching may pair an equation with a
    # neighbour's unknown (a shift by one), so RCM finds at most 2 diagonals each side,
    # whatever the shuffle (a shuffled chain of 60 has a band of ~40 as it is given)
    assert o.kl <= 2 and o.ku <= 2
    rng = np.random.default_rng(1)
    values = rng.uniform(-1.0, 1.0, pattern.nnz)
    a = sp.csc_matrix((values, pattern.indices, pattern.indptr), shape=(n, n)).toarray()
    a += 4.0 * (pattern.toarray() != 0) * np.sign(a) * (np.abs(a) > 0.0)
    matrix = sp.csc_matrix(a)
    matrix.sort_indices()
    lu = BandLU(o, matrix.data)
    b = rng.standard_normal(n)
    x = lu.solve(b.copy())
    ref = np.linalg.solve(a, b)
    # both are backward stable: the difference is cond(A) * eps (cond ~ 1e1 to 1e3 here)
    assert np.max(np.abs(x - ref)) <= 1e4 * EPS * np.max(np.abs(ref))


def test_structurally_singular_pattern_has_no_band_ordering():
    pattern = sp.csc_matrix(np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 0.0]]))
    assert BandOrdering.of(pattern) is None


def chain_residual(k, pr, pc):
    """F = y' + k y - 0.5 y_prev - 0.25 y_next on a chain of first-order lags, in the
    chain's order, with unknowns and equations shuffled like ``shuffled_chain``'s
    pattern (pc: the unknowns' places, pr: the equations')."""
    n = k.size

    def residual(t, y, yp):
        x = np.empty(n)
        x[pc] = y
        xp = np.empty(n)
        xp[pc] = yp
        f = xp + k * x
        f[1:] -= 0.5 * x[:-1]
        f[:-1] -= 0.25 * x[1:]
        return f[pr]

    return residual


def test_iteration_matrix_stores_the_pattern_only_and_uses_the_band():
    n = 40
    pattern, pr, pc = shuffled_chain(n, seed=3)
    k = np.linspace(1.0, 2.0, n)

    residual = chain_residual(k, pr, pc)

    m = IterationMatrix(residual, n, sparsity=pattern)
    # the pattern of dF/dy + dF/dy', plus the diagonal only while KEEP_DIAGONAL is on
    expected = pattern + sp.eye(n) if linear_algebra.KEEP_DIAGONAL else pattern
    assert m.pattern.nnz == sp.csc_matrix(expected).nnz
    assert m.band is not None
    y, yp = np.ones(n), np.zeros(n)
    f0 = residual(0.0, y, yp)
    m.evaluate(0.0, y, yp, f0, 10.0, 0.1, np.ones(n))
    m.factorize()
    assert isinstance(m._lu, BandLU)
    rhs = np.arange(n, dtype=float)
    x = m.solve(rhs)
    ref = np.linalg.solve(m.matrix.toarray(), rhs)
    # a diagonally dominant matrix (cond < 10): agreement to a few eps
    assert np.max(np.abs(x - ref)) <= 100 * EPS * np.max(np.abs(ref))


def test_band_ordering_ignores_the_added_diagonal(monkeypatch):
    # KEEP_DIAGONAL stores zeros at (i, i), pairing equation i with unknown i, which a
    # shuffled layout does not relate: ordered with them the band is wide (the steam
    # pipe: kl, ku = 158, 157 instead of 11, 15); the ordering of the entries that can
    # be non-zero keeps the chain's 2 + 2 diagonals and leaves those zeros out
    n = 40
    pattern, pr, pc = shuffled_chain(n, seed=3)
    with_diagonal = sp.csc_matrix(pattern + sp.eye(n))
    wide = BandOrdering.of(with_diagonal)
    k = np.linspace(1.0, 2.0, n)

    residual = chain_residual(k, pr, pc)

    if not linear_algebra.KEEP_DIAGONAL:
        pytest.skip("no diagonal added")
    # the matrix orders without the stored zeros only when the pattern's own ordering
    # is not worth a band (linear_algebra): make this small chain's wide band not pay
    monkeypatch.setattr(band_module, "BAND_NARROW", 0)
    monkeypatch.setattr(band_module, "BAND_FILL_MAX", 2.0)
    assert not wide.worthwhile
    m = IterationMatrix(residual, n, sparsity=pattern)
    assert m.band.kl <= 2 and m.band.ku <= 2
    assert wide.kl + wide.ku > 2 * (m.band.kl + m.band.ku)
    assert m.band.outside is not None
    y, yp = np.ones(n), np.zeros(n)
    m.evaluate(0.0, y, yp, residual(0.0, y, yp), 10.0, 0.1, np.ones(n))
    rhs = np.arange(n, dtype=float)
    for poke in (False, True):
        if poke:
            # a non-zero where the band has no room: that matrix goes to SuperLU
            m.matrix.data[m.band.outside[0]] = 1e-3
        m.factorize()
        assert isinstance(m._lu, BandLU) is not poke
        ref = np.linalg.solve(m.matrix.toarray(), rhs)
        # diagonally dominant (cond < 10): both LUs agree with dense to a few eps
        assert np.max(np.abs(m.solve(rhs) - ref)) <= 100 * EPS * np.max(np.abs(ref))


def test_band_and_superlu_give_the_same_solution_of_a_dae():
    # the same DAE through the band LU and through SuperLU (band disabled): the two LUs
    # differ at round-off, so the step sequences may differ at round-off too; the
    # solutions agree to far below the tolerance (rtol 1e-8: 1e-9 of the values)
    n = 30
    pattern, pr, pc = shuffled_chain(n, seed=5)

    def residual(t, y, yp):
        x = np.empty(n)
        x[pc] = y
        xp = np.empty(n)
        xp[pc] = yp
        f = xp + x
        f[1:] -= x[:-1]
        return f[pr]

    y0 = np.zeros(n)
    y0[np.flatnonzero(pc == 0)] = 1.0
    runs = []
    for band in (True, False):
        saved = BandOrdering.worthwhile
        if not band:
            BandOrdering.worthwhile = property(lambda self: False)
        try:
            runs.append(
                solve_dae(residual, (0.0, 5.0), y0, rtol=1e-8, atol=1e-12, jac_sparsity=pattern)
            )
        finally:
            BandOrdering.worthwhile = saved
    a, b = runs
    assert abs(a.stats["steps"] - b.stats["steps"]) <= 0.01 * b.stats["steps"] + 1
    assert np.max(np.abs(a.y[:, -1] - b.y[:, -1])) <= 1e-9


def test_ida_band_solver_on_the_matched_ordering_agrees_with_dense():
    pytest.importorskip("sksundae")
    from dnasim.solver.ida import solve_ida

    n = 25
    pattern, pr, pc = shuffled_chain(n, seed=7)

    def residual(t, y, yp):
        x = np.empty(n)
        x[pc] = y
        xp = np.empty(n)
        xp[pc] = yp
        f = xp + 2.0 * x
        f[1:] -= 2.0 * x[:-1]
        return f[pr]

    y0 = np.zeros(n)
    y0[np.flatnonzero(pc == 0)] = 1.0
    g = np.empty(n)
    g[pr] = residual(0.0, y0, np.zeros(n))  # F in the original order at yp = 0
    yp0 = -g[pc]
    out = {}
    for lin in ("band", "dense"):
        out[lin] = solve_ida(
            residual,
            (0.0, 3.0),
            y0,
            yp0,
            algebraic=np.zeros(n, bool),
            reinitialise=lambda t, y, yp: (y, yp),
            jac_sparsity=pattern,
            rtol=1e-9,
            atol=1e-12,
            linsolver=lin,
        )
    assert out["band"].success and out["dense"].success
    # x_k(t) = (2t)^k e^{-2t} / k!: both IDA runs to their tolerance (rtol 1e-9, the
    # global error a few tens of it), so they agree to 1e-7 of the peak value
    exact = np.array([6.0**k * np.exp(-6.0) / math.factorial(k) for k in range(n)])
    for lin in ("band", "dense"):
        x = np.empty(n)
        x[pc] = out[lin].y[:, -1]
        assert np.max(np.abs(x - exact)) <= 1e-7


def test_restart_step_from_the_solution_saves_steps_after_a_tstop():
    # y' = -y + u(t), u stepping from 0 to 1 at t = 5 (a tstop): y = e^{-t} before,
    # y = 1 + (e^{-5} - 1) e^{-(t-5)} after. The restart from the solution must not take
    # more steps than IDA's rule and must keep the accuracy (rtol 1e-6: the global error
    # of this scalar problem stays below 1e-5 of the values)
    def residual(t, y, yp):
        return yp + y - (1.0 if t >= 5.0 else 0.0)

    def exact(t):
        return np.exp(-t) if t < 5 else 1.0 + (np.exp(-5.0) - 1.0) * np.exp(-(t - 5.0))

    steps = {}
    default = bdf.RESTART_FROM_SOLUTION
    for mode in (False, True):
        bdf.RESTART_FROM_SOLUTION = mode
        try:
            r = solve_dae(residual, (0.0, 10.0), [1.0], [-1.0], rtol=1e-6, atol=1e-9, tstops=[5.0])
        finally:
            bdf.RESTART_FROM_SOLUTION = default
        assert abs(r.y[0, -1] - exact(10.0)) <= 1e-5
        steps[mode] = int(np.sum(r.t > 5.0))
    assert steps[True] < steps[False]
