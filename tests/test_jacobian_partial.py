"""The finite-difference Jacobian of a plant: column colouring and partial evaluation.

Two ways of computing the same matrix cheaper, each checked against the plain
way on the example plants: the coloured Jacobian (largest-first colouring) against
one residual evaluation per column, and the partial evaluation of a column group
(``System.residual_for_columns``: only the components that read the group's
columns) against whole-plant evaluations. Both must give the same matrix to the
bit: every entry comes from a row that reads only its own column of the group,
evaluated from the same inputs by the same code.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from dnasim.compilation.compiler import compile as compile_plant
from dnasim.plant.plantfile import load
from dnasim.solver.linear_algebra import SQRT_EPS, IterationMatrix, colour_columns
from dnasim.start.initial import initial_values

PLANTS = Path(__file__).resolve().parent.parent / "plants"


def _plant(name):
    loaded = load(PLANTS / f"{name}.toml")
    system = compile_plant(loaded.plant)
    sim = loaded.simulation
    y0, yp0 = initial_values(system, sim.t_start, sim.start)
    return system, y0, yp0


def _off_steady(system, y0, yp0):
    """A point near the start that is not a steady state (every column matters)."""
    rng = np.random.default_rng(7)
    scale = np.maximum(system.nominal, np.abs(y0))
    y = y0 + 1e-6 * scale * rng.standard_normal(y0.size)
    yp = yp0 + 1e-3 * scale * rng.standard_normal(y0.size)
    return y, yp


def _increments(y):
    inc = np.maximum(SQRT_EPS * np.abs(y), 1e-3)
    return (y + inc) - y


@pytest.mark.parametrize("name", ["attemperator", "air_pipe", "feedwater_heater", "drum_boiler"])
def test_partial_group_evaluation_gives_the_same_jacobian(name):
    system, y0, yp0 = _plant(name)
    y, yp = _off_steady(system, y0, yp0)
    matrix = IterationMatrix(
        system.residual,
        system.n,
        sparsity=system.jac_sparsity,
        residual_for_columns=system.residual_for_columns,
    )
    assert all(g is not None for g in matrix._group_residuals)
    f0 = system.residual(0.0, y, yp)
    inc = _increments(y)
    cj = 37.0
    partial = matrix.finite_difference(0.0, y, yp, f0, inc, 1.0, cj)
    matrix._group_residuals = [None] * len(matrix.groups)  # whole evaluations
    whole = matrix.finite_difference(0.0, y, yp, f0, inc, 1.0, cj)
    assert np.array_equal(partial.indptr, whole.indptr)
    assert np.array_equal(partial.indices, whole.indices)
    # to the bit: the same rows evaluated from the same inputs (module doc)
    assert np.array_equal(partial.data, whole.data)
    assert np.count_nonzero(whole.data) > whole.nnz // 2  # a matrix, not zeros


def test_the_partial_channel_is_only_what_the_caller_gives():
    """The solver sees a residual, a pattern and switches, and the partial-residual
    channel only when the caller passes it (issue 21): a System's bound residual alone
    gives whole evaluations, however the residual is wrapped."""
    system, y0, yp0 = _plant("attemperator")
    matrix = IterationMatrix(system.residual, system.n, sparsity=system.jac_sparsity)
    assert all(g is None for g in matrix._group_residuals)
    from dnasim.run.simulation import problem_for

    pb = problem_for(system, 0.0, 1.0, y0, yp0, 1e-6)
    assert pb.residual_for_columns == system.residual_for_columns


def test_partial_evaluation_skips_untouched_components():
    """A group that perturbs one valve's flow re-evaluates that valve and the node
    equations only; the other rows are f0's, whatever f0 holds there."""
    system, y0, yp0 = _plant("attemperator")
    j = system.index["turbine_valve.m"]
    F_cols = system.residual_for_columns([j])
    f0 = system.residual(0.0, y0, yp0)
    marker = f0.copy()
    valve = system.block("turbine_valve").eq_slice
    others = np.ones(f0.size, dtype=bool)
    others[valve] = False
    others[system.node_eq_start :] = False
    marker[others] = 12345.0
    y = y0.copy()
    y[j] += 1e-3
    F = F_cols(0.0, y, yp0, marker)
    assert np.all(F[others] == 12345.0)
    whole = system.residual(0.0, y, yp0)
    assert np.array_equal(F[~others], whole[~others])


def test_coloured_jacobian_equals_column_by_column():
    system, y0, yp0 = _plant("attemperator")
    y, yp = _off_steady(system, y0, yp0)
    matrix = IterationMatrix(
        system.residual,
        system.n,
        sparsity=system.jac_sparsity,
        residual_for_columns=system.residual_for_columns,
    )
    f0 = system.residual(0.0, y, yp)
    inc = _increments(y)
    cj = 37.0
    coloured = matrix.finite_difference(0.0, y, yp, f0, inc, 1.0, cj).toarray()
    pattern = matrix.pattern.toarray() != 0
    for j in range(system.n):
        yj, ypj = y.copy(), yp.copy()
        yj[j] += inc[j]
        ypj[j] += cj * inc[j]
        column = (system.residual(0.0, yj, ypj) - f0) / inc[j]
        # off the pattern the column is zero: the declared dependencies are complete
        assert np.all(column[~pattern[:, j]] == 0.0), system.names[j]
        assert np.array_equal(coloured[pattern[:, j], j], column[pattern[:, j]]), system.names[j]


def test_colouring_is_valid_and_reaches_the_row_bound():
    """No two columns of a group share a row; on attemperator.toml largest first needs
    as many groups as the fullest row has entries (the lower bound), 11."""
    system, _, _ = _plant("attemperator")
    pattern = sp.csc_matrix(system.jac_sparsity + sp.eye(system.n))
    pattern.data[:] = 1.0
    groups = colour_columns(pattern)
    csr = pattern.tocsr()
    for cols in groups:
        per_row = np.asarray(csr[:, cols].sum(axis=1)).ravel()
        assert per_row.max() <= 1
    assert sorted(np.concatenate(groups).tolist()) == list(range(system.n))
    assert len(groups) == int(np.diff(csr.indptr).max())


def test_colouring_of_random_patterns_is_valid():
    rng = np.random.default_rng(3)
    for n in (1, 5, 40, 200):
        m = sp.random(n, n, density=min(1.0, 4.0 / n), random_state=rng, format="csc")
        m = (m + sp.eye(n)).tocsc()
        m.data[:] = 1.0
        groups = colour_columns(m)
        csr = m.tocsr()
        for cols in groups:
            assert np.asarray(csr[:, cols].sum(axis=1)).max() <= 1
        assert sorted(np.concatenate(groups).tolist()) == list(range(n))
