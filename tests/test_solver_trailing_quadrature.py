"""A quadrature whose equation reads many columns does not cost a Jacobian column each.

A quadrature Q' = g(y) with g summing over many unknowns (a fixed wall's heat
dQ_passed/dt = sum_i Q_i over a pipe's volumes) is a dense row: no two of its columns
may share a finite-difference group, so a 1000-volume pipe needed 1002 groups
(residual evaluations) per Jacobian against 13 without the row, and the dense row
broke the band LU. Column Q is read by that row alone, so the matrix is block
triangular: ``IterationMatrix(quadrature=...)`` keeps only the row's entry in column
Q (``linear_algebra.trailing_rows``). The other unknowns' Newton updates do not
depend on the row at all; only Q's update trails by one iteration, and Q is out of
every norm, so the integrator's decisions are the same.

The problem: n relaxations towards an input u(t) that steps smoothly at t = 1 s,
coupled by diffusion with closed ends, y_i' = k (u - y_i) + D (y_{i-1} - 2 y_i + y_{i+1}),
and the quadrature of their relaxation terms, Q' = sum_i k (u - y_i). The diffusion
sums to zero, so Q - sum_i y_i is a linear invariant (closed form).
"""

import numpy as np
import scipy.sparse as sp

from dnasim import solve_dae
from dnasim.solver.linear_algebra import IterationMatrix

N = 60
K = 2.0  # 1/s
D = 3.0  # 1/s
W = 0.05  # s, width of the input's step


def u(t):
    return 1.0 + 0.5 * np.tanh((t - 1.0) / W)


def residual(t, y, yp):
    x = y[:N]
    ext = np.concatenate(([x[0]], x, [x[-1]]))  # closed ends: no flux
    diffusion = D * (ext[:-2] - 2.0 * x + ext[2:])
    f = np.empty(N + 1)
    f[:N] = yp[:N] - K * (u(t) - x) - diffusion
    f[N] = yp[N] - np.sum(K * (u(t) - x))
    return f


def sparsity():
    rows, cols = [], []
    for i in range(N):
        for j in (i - 1, i, i + 1):
            if 0 <= j < N:
                rows.append(i)
                cols.append(j)
    rows += [N] * (N + 1)
    cols += list(range(N + 1))
    return sp.csc_matrix((np.ones(len(rows)), (rows, cols)), shape=(N + 1, N + 1))


def solve(trailing):
    """The problem with Q a quadrature; ``trailing``: its row reduced (the default) or
    the whole matrix (``IterationMatrix`` without the quadrature mask)."""
    y0 = np.concatenate((np.full(N, u(0.0)), [0.0]))
    import dnasim.solver.api as api

    original = api.IterationMatrix
    if not trailing:

        def whole(*args, **kwargs):
            kwargs["quadrature"] = None
            return original(*args, **kwargs)

        api.IterationMatrix = whole
    try:
        return solve_dae(
            residual,
            (0.0, 5.0),
            y0,
            np.zeros(N + 1),
            rtol=1e-6,
            atol=1e-8,
            jac_sparsity=sparsity(),
            quadrature=[N],
        )
    finally:
        api.IterationMatrix = original


def test_the_dense_quadrature_row_is_reduced_to_its_own_entry():
    pattern = sparsity()
    whole = IterationMatrix(residual, N + 1, sparsity=pattern)
    reduced = IterationMatrix(residual, N + 1, sparsity=pattern, quadrature=[N])
    # the whole pattern: the row of Q reads all N + 1 columns, one group each
    assert len(whole.groups) == N + 1
    assert reduced.trailing == {N: N}
    # tridiagonal rest: 3 groups, Q's column in one of them (it shares no row with them)
    assert len(reduced.groups) <= 4
    # the matrix: the same entries but row N's off-diagonal ones, which are left out
    rng = np.random.default_rng(3)
    y = 1.0 + 0.1 * rng.standard_normal(N + 1)
    yp = 0.1 * rng.standard_normal(N + 1)
    f0 = residual(0.5, y, yp)
    inc = np.full(N + 1, 1e-6)
    a = whole.finite_difference(0.5, y, yp, f0, inc, 1.0, 10.0).toarray()
    b = reduced.finite_difference(0.5, y, yp, f0, inc, 1.0, 10.0).toarray()
    # each entry is its own row's difference from one column: the same to the bit
    assert np.array_equal(a[:N], b[:N])
    assert b[N, N] == a[N, N] and not np.any(b[N, :N])
    assert np.any(a[N, :N])  # (the row does read them)


def test_reduced_row_takes_the_same_steps_and_keeps_the_invariant():
    whole, reduced = solve(False), solve(True)
    assert whole.success and reduced.success
    s_w, s_r = whole.stats, reduced.stats
    # the integrator's decisions: the other unknowns' updates do not depend on the row,
    # Q is out of every norm, so the same steps, iterations and Jacobians
    for key in ("steps", "rejected_error", "rejected_newton", "newton_iters", "jac_evals"):
        assert s_w[key] == s_r[key], (key, s_w, s_r)
    # ... for fewer evaluations: a Jacobian costs <= 4 instead of N + 1, and each
    # accepted or error-rejected step one more (the rows at the solution: 166 here)
    assert s_r["residual_evals"] < 0.6 * s_w["residual_evals"], (s_w, s_r)
    # the states: the same updates from the same entries (measured equal to the bit;
    # 1e-12 of y ~ 1.5 allows for another LU's round-off)
    assert np.max(np.abs(whole.y[:N] - reduced.y[:N])) < 1e-12
    # the quadrature where the whole matrix puts it (the settled gap), and the
    # invariant Q - sum y = -sum y(0) to round-off in both (N y ~ 90: 1e-11, measured
    # 1.4e-13 and 3.3e-13; the quadrature's last update alone left 2e-5)
    assert np.max(np.abs(whole.y[N] - reduced.y[N])) < 1e-11 * N
    for res in (whole, reduced):
        inv = res.y[N] - res.y[:N].sum(axis=0) + res.y[:N, 0].sum()
        assert np.max(np.abs(inv)) < 1e-11 * N


def test_a_quadrature_row_no_longer_than_the_others_stays_whole():
    # Q' = y_0: one entry, no group saved; the pattern is left as it is (bit-identical
    # runs of the plants whose accumulators read one flow each)
    pattern = sp.csc_matrix(np.array([[1.0, 0.0], [1.0, 1.0]]))
    m = IterationMatrix(lambda t, y, yp: y, 2, sparsity=pattern, quadrature=[1])
    assert m.trailing is None


def _fixed_wall_pipe(n):
    """The steam pipe of benchmarks/plant_scaling.py --wall sine: 50 bar, 500 C steam
    (520 C from t = 1 s) through n volumes whose wall is held at 500 +- 20 C (period 20
    s), a valve to 45 bar; its heat to the wall, Q_passed, sums n heat flows."""
    import math

    from dnasim.core.timefunctions import Sine, Step
    from dnasim.library import Pipe, PressureBoundary, Valve
    from dnasim.plant.plant import Plant

    plant = Plant("fixed_wall", medium="Water")
    D, L = 0.1, 20.0
    plant.add(PressureBoundary("steam", p=50e5, T=Step(1.0, 773.15, 793.15), m_nominal=2.0))
    plant.add(
        Pipe(
            "pipe",
            V=math.pi / 4 * D**2 * L,
            kA=1000.0 * math.pi * D * L,
            k=2e5,
            T_wall=Sine(773.15, 20.0, 20.0),
            n_volumes=n,
            m_nominal=2.0,
        )
    )
    plant.add(Valve("valve", C=0.003, opening=1.0, m_nominal=2.0))
    plant.add(PressureBoundary("sink", p=45e5, m_nominal=2.0))
    for a, b in [
        ("steam.port", "in"),
        ("pipe.inlet", "in"),
        ("pipe.outlet", "out"),
        ("valve.inlet", "out"),
        ("valve.outlet", "exit"),
        ("sink.port", "exit"),
    ]:
        plant.connect(a, b)
    return plant


def test_fixed_wall_pipe_start_and_run_as_with_the_whole_matrix(monkeypatch):
    import dnasim.solver.api as api
    import dnasim.start.consistent as consistent
    from dnasim.start.steady_state import find_steady_state

    n = 100
    dae = _fixed_wall_pipe(n).compile()
    q = dae.index["pipe.Q_passed"]
    assert dae.quadrature[q]
    # the steady start: the row of Q_passed' (n + 1 entries) left out of the groups
    rest = find_steady_state(dae, 0.0)
    matrix = consistent.iteration_matrix(dae)
    assert list(matrix.trailing.values()) == [q]
    whole_groups = len(IterationMatrix(None, dae.n, sparsity=dae.jac_sparsity).groups)
    assert whole_groups > n and len(matrix.groups) < 20  # 13 measured at n = 1000
    # a few Jacobians of < 20 groups and the Newton iterations: measured 33 at n = 1000
    # and 51 at n = 10000 (before: 2013 and 10013)
    assert rest.stats.residual_evals < 80, rest.stats

    def run():
        return solve_dae(
            dae.residual,
            (0.0, 10.0),
            rest.y,
            rest.yp,
            algebraic=dae.algebraic,
            quadrature=dae.quadrature,
            rtol=1e-6,
            atol=dae.atol_vector(1e-6, rest.y),
            jac_sparsity=dae.jac_sparsity,
            residual_for_columns=dae.residual_for_columns,
            tstops=dae.tstops(0.0, 10.0),
            calc_initial=False,
            exclude_algebraic_from_error=True,
        )

    reduced = run()
    original = api.IterationMatrix
    monkeypatch.setattr(
        api, "IterationMatrix", lambda *a, **k: original(*a, **{**k, "quadrature": None})
    )
    whole = run()
    assert reduced.success and whole.success
    for key in ("steps", "rejected_error", "rejected_newton", "newton_iters", "jac_evals"):
        assert reduced.stats[key] == whole.stats[key], (key, reduced.stats, whole.stats)
    # fewer evaluations: a Jacobian of 13 groups instead of 102, one more evaluation a
    # step (the settled row); measured 918 against 2180 over these 10 s
    assert reduced.stats["residual_evals"] < 0.6 * whole.stats["residual_evals"]
    # the states: the same updates; band LU (reduced) against SuperLU (the whole
    # pattern's dense row leaves no band): round-off apart, 1e-9 of each scale (the
    # accumulators' their largest value)
    others = np.ones(dae.n, dtype=bool)
    others[q] = False
    scale = np.maximum(dae.nominal, np.max(np.abs(whole.y), axis=1))[:, None]
    assert np.max(np.abs(reduced.y[others] - whole.y[others]) / scale[others]) < 1e-9
    # the heat to the wall where the whole matrix puts it (its last update settled):
    # 1e-9 of the heat passed (~1e6 J over the run)
    Q_r, Q_w = reduced.y[q], whole.y[q]
    assert np.max(np.abs(Q_r - Q_w)) < 1e-9 * np.max(np.abs(Q_w))
