"""The compiled loops of the BDF step (dnasim/solver/kernels.py) against the numpy code
they replace: the same numbers to the bit, so no decision of the solver changes.

References: numpy's element-wise operations (one IEEE rounding each), numpy's and
LAPACK's own results for the dot product, the Pascal product and the LU solve; and
whole solves of published problems with and without the loops (identical step
histories, counters and end points). Every comparison is exact (``array_equal``,
``==``): bit-identity is the property claimed, a tolerance would hide a change.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
from problems import (
    HIRES_T_END,
    HIRES_Y0,
    ROBERTSON_Y0,
    ROBERTSON_YP0,
    as_residual,
    hires_rhs,
    robertson,
)

from dnasim import solve_dae
from dnasim.solver import bdf, kernels
from dnasim.solver import nordsieck as nd
from dnasim.solver.linear_algebra import colour_columns

RNG = np.random.default_rng(2026)


def _vec(n):
    """Random values over 16 decades with random signs (exercise every rounding)."""
    return RNG.standard_normal(n) * 10.0 ** RNG.uniform(-8, 8, n)


@pytest.mark.parametrize("n", [1, 3, 8, 15, 16, 100, 7015])
def test_newton_update_is_the_numpy_update(n):
    x, y, yp, w = _vec(n), _vec(n), _vec(n), 10.0 ** RNG.uniform(-6, 6, n)
    for scale in (1.0, 2.0 / (1.0 + 1.37)):
        cj = 3.7e4
        d = -x  # numpy: d = solve(-f) = -solve(f)
        if scale != 1.0:
            d = d * scale
        y_new, yp_new, dw = np.empty(n), np.empty(n), np.empty(n)
        ss = kernels.newton_update(x, scale, y, yp, cj, w, y_new, yp_new, dw)
        assert np.array_equal(y_new, y + d)
        assert np.array_equal(yp_new, yp + cj * d)
        assert np.array_equal(dw, d * w)
        if kernels.dot_matches_numpy():
            assert ss == (d * w).dot(d * w)


@pytest.mark.parametrize("n", [2, 8, 7015])
def test_weights_correct_rescale_wrms_are_the_numpy_ones(n):
    y, atol = _vec(n), 10.0 ** RNG.uniform(-10, 0, n)
    w = np.empty(n)
    kernels.weights(y, 1e-6, atol, w)
    assert np.array_equal(w, 1.0 / (1e-6 * np.abs(y) + atol))
    for q in range(1, nd.MAX_ORDER + 1):
        z_pred, delta = RNG.standard_normal((7, n)), _vec(n)
        z = np.zeros((7, n))
        kernels.correct(z_pred, nd.l_vector(q), delta, q, z)
        assert np.array_equal(z[: q + 1], z_pred[: q + 1] + nd.l_vector(q)[:, None] * delta)
        z1 = RNG.standard_normal((7, n))
        z2 = z1.copy()
        kernels.rescale(z1, q, 0.731)
        factor = 1.0  # nordsieck.rescale's factors, row by row
        for j in range(1, q + 1):
            factor *= 0.731
            z2[j] *= factor
        assert np.array_equal(z1, z2)
    if kernels.dot_matches_numpy():
        v, w = _vec(n), 10.0 ** RNG.uniform(-6, 6, n)
        vw = v * w
        assert kernels.wrms(v, w) == math.sqrt(vw.dot(vw) / vw.size)


@pytest.mark.parametrize("n", [1, 3, 8, 16, 7015])
def test_error_norms_are_the_numpy_ones(n):
    # bdf._choose_next's two norms in one call: numpy rounds delta - delta_prev, then
    # the product with w, then sums by BLAS's ddot; the loop must do the same.
    if not kernels.dot_matches_numpy():
        pytest.skip("this BLAS's ddot is not numba's: the step keeps numpy's norms")
    zq, delta, delta_prev = _vec(n), _vec(n), _vec(n)
    w = 10.0 ** RNG.uniform(-6, 6, n)
    e_down, e_up = kernels.wrms_order_errors(zq, delta, delta_prev, w)
    a, b = zq * w, (delta - delta_prev) * w
    assert e_down == math.sqrt(a.dot(a) / n)
    assert e_up == math.sqrt(b.dot(b) / n)
    # bdf.step's Delta = y - y_pred and its error norm in one call
    y, y_pred, delta = _vec(n), _vec(n), np.empty(n)
    enorm = kernels.delta_wrms(y, y_pred, w, delta)
    assert np.array_equal(delta, y - y_pred)
    c = (y - y_pred) * w
    assert enorm == math.sqrt(c.dot(c) / n)


@pytest.mark.parametrize("n", [3, 8, 7015])
def test_predict_is_the_pascal_product(n):
    z = RNG.standard_normal((7, n)) * 10.0 ** RNG.uniform(-8, 8, (7, 1))
    for q in range(1, nd.MAX_ORDER + 1):
        out, yp = np.empty_like(z), np.empty(n)
        kernels.predict(nd.pascal_matrix(q), z, q, 0.01, out, yp)
        ref = nd.pascal_matrix(q) @ z[: q + 1]
        if kernels.predict_matches_numpy():  # the BLAS kernel sums as the loop does
            assert np.array_equal(out[: q + 1], ref)
            assert np.array_equal(yp, ref[1] / 0.01)
        else:  # another BLAS: equal to round-off (a few ulp of the largest term)
            scale = nd.pascal_matrix(q) @ np.abs(z[: q + 1])
            assert np.all(np.abs(out[: q + 1] - ref) <= 8 * np.finfo(float).eps * scale)


@pytest.mark.parametrize("n", [1, 2, 5, 8, 15])
def test_small_dense_solve_is_lapacks(n):
    (getrs,) = scipy.linalg.get_lapack_funcs(("getrs",), (np.zeros(1),))
    for _ in range(20):
        a = RNG.standard_normal((n, n)) * 10.0 ** RNG.uniform(-3, 3, (n, n)) + np.eye(n)
        lu, piv = scipy.linalg.lu_factor(a)
        b = _vec(n)
        x = b.copy()
        kernels.lu_solve_small(lu, piv, x)
        ref = getrs(lu, piv, b)[0]
        if kernels.dense_solve_matches_lapack():
            assert np.array_equal(x, ref)
        else:  # another BLAS: the residual of the solve at round-off level
            assert np.linalg.norm(a @ x - b) <= 1e-10 * np.linalg.norm(np.abs(a) @ np.abs(x))


def _first_fit_reference(pattern):
    """The greedy colouring as first written (a boolean row mask per group)."""
    indptr, indices = pattern.indptr, pattern.indices
    structure = scipy.sparse.csc_matrix((np.ones(indices.size), indices, indptr), pattern.shape)
    order = np.argsort(-np.diff((structure.T @ structure).tocsr().indptr), kind="stable")
    used_by, group_of = [], np.empty(pattern.shape[1], dtype=np.intp)
    for j in order:
        rows = indices[indptr[j] : indptr[j + 1]]
        for g, used in enumerate(used_by):
            if not used[rows].any():
                used[rows] = True
                group_of[j] = g
                break
        else:
            used_by.append(np.zeros(pattern.shape[0], dtype=bool))
            used_by[-1][rows] = True
            group_of[j] = len(used_by) - 1
    return [np.flatnonzero(group_of == g) for g in range(len(used_by))]


def test_colouring_is_the_first_fit_of_the_mask_version():
    for k in range(25):
        m = int(RNG.integers(2, 80))
        p = scipy.sparse.random(m, m, density=RNG.uniform(0.02, 0.4), random_state=k)
        p = scipy.sparse.csc_matrix(p + scipy.sparse.eye(m))
        p.data[:] = 1.0
        p.sort_indices()
        got, ref = colour_columns(p), _first_fit_reference(p)
        assert len(got) == len(ref)
        assert all(np.array_equal(a, b) for a, b in zip(got, ref, strict=True))


def _solve(monkeypatch, compiled, name):
    """A whole solve with (True) or without (False) the compiled loops."""
    monkeypatch.setattr(bdf, "KERNELS", compiled)
    monkeypatch.setattr(bdf, "KERNELS_AFTER_STEPS", 0 if compiled else 10**12)
    monkeypatch.setattr(bdf, "KERNELS_AFTER_STEPS_LOADED", 0 if compiled else 10**12)
    if not compiled:  # the process-wide hooks back to numpy for this run
        monkeypatch.setattr(bdf, "_compiled_wrms", [None])
        monkeypatch.setattr(nd, "compiled_rescale", None)
    if name == "robertson":
        r = solve_dae(
            robertson,
            (0, 4e5),
            ROBERTSON_Y0,
            ROBERTSON_YP0,
            algebraic=[2],
            rtol=1e-6,
            atol=np.array([1e-12, 1e-16, 1e-12]),
            calc_initial=False,
        )
    else:
        r = solve_dae(
            as_residual(hires_rhs),
            (0, HIRES_T_END),
            HIRES_Y0,
            None,
            rtol=1e-6,
            atol=1e-10,
            calc_initial=True,
        )
    monkeypatch.undo()
    return r


@pytest.mark.parametrize("name", ["robertson", "hires"])
def test_whole_solve_identical_with_and_without_compiled_loops(monkeypatch, name):
    numpy_run = _solve(monkeypatch, False, name)
    compiled_run = _solve(monkeypatch, True, name)
    assert compiled_run.stats == numpy_run.stats
    assert np.array_equal(compiled_run.step_history, numpy_run.step_history)
    assert np.array_equal(compiled_run.y, numpy_run.y)
    assert np.array_equal(compiled_run.yp, numpy_run.yp)
