"""Consistent initialisation: one routine for the start, tstops, events and plant starts."""

from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

from dnasim import DAEError, solve_dae
from dnasim.core.errors import PlantError
from dnasim.solver.initial import solve_consistent
from dnasim.solver.linear_algebra import IterationMatrix
from dnasim.start.consistent import solve_mixed

EPS = np.finfo(float).eps
A, B, C = 1.1, 3.3, 0.7


def _noisy_accumulator(t, y, yp):
    """m c = a b with round-off-level noise that no m can remove; E' = m H, H = 2.7e9.

    The noise (eps times the size of the terms, a deterministic function of m) mimics
    a residual whose floating-point value cannot reach zero.
    """
    m, _ = y
    noise = 4.0 * EPS * A * B * np.sin(1e12 * m)
    return np.array([m * C - A * B + noise, yp[1] - 2.7e9 * m])


def test_roundoff_residual_is_accepted_with_weights_of_the_current_state():
    """E = 1e10 now (it was 0 at t0): the test must be scaled by the current E."""
    n = 2
    y = np.array([A * B / C * (1 + 1e-3), 1e10])
    yp = np.array([0.0, 0.0])
    matrix = IterationMatrix(_noisy_accumulator, n)
    y1, yp1 = solve_consistent(
        _noisy_accumulator,
        5.0,
        y,
        yp,
        np.array([True, False]),
        rtol=1e-6,
        atol=np.full(n, 1e-8),
        h_scale=1e-3,
        matrix=matrix,
    )
    # m to round-off (the noise moves the root by ~4 eps); E kept; E' = m H to round-off.
    assert y1[0] == pytest.approx(A * B / C, rel=1e-14)
    assert y1[1] == 1e10
    assert yp1[1] == pytest.approx(2.7e9 * A * B / C, rel=1e-14)


def test_restarts_after_a_large_flow_step_with_an_accumulator_that_was_zero():
    """The accumulator starts at 0 (weight 1/atol = 1e8) and grows to ~1e10."""

    def residual(t, y, yp):
        h = 1.0 if t < 0.5 else 2.7e9
        f = _noisy_accumulator(t, y, yp)
        f[1] = yp[1] - h * y[0]
        return f

    tstops = [0.5, *np.linspace(0.6, 1.9, 14)]
    res = solve_dae(
        residual, (0, 2), [A * B / C, 0.0], algebraic=[0], rtol=1e-6, atol=1e-8, tstops=tstops
    )
    m = A * B / C
    # Closed form E(2) = m (0.5 + 2.7e9 * 1.5); rtol 1e-6 on a linear function: 1e-6.
    assert res.y[1, -1] == pytest.approx(m * (0.5 + 2.7e9 * 1.5), rel=1e-6)


def test_line_search_converges_where_plain_newton_diverges():
    """arctan(x - 2) = 0 from x = 7: the full Newton step overshoots ever farther."""

    def residual(t, y, yp):
        return np.array([yp[0] + y[0], np.arctan(y[1] - 2.0)])

    res = solve_dae(residual, (0, 1), [1.0, 7.0], algebraic=[1], rtol=1e-8, atol=1e-10)
    # The algebraic variable is exact up to the initialisation tolerance (0.0033 atol).
    assert res.y[1, 0] == pytest.approx(2.0, abs=1e-11)
    assert res.yp[0, 0] == pytest.approx(-1.0, abs=1e-12)


def test_failure_names_equations_and_variables():
    def residual(t, y, yp):
        return np.array([yp[0] + y[0], y[1] ** 2 + 1.0])  # 0 = y2^2 + 1 has no real root

    with pytest.raises(DAEError) as info:
        solve_dae(
            residual,
            (0, 1),
            [1.0, 0.5],
            algebraic=[1],
            variable_names=["tank.level", "tank.flow"],
            equation_names=["tank.mass", "tank.momentum"],
        )
    message = str(info.value)
    assert "inconsistent" in message
    assert "tank.momentum" in message and "tank.flow" in message
    # The largest residual is named first.
    assert message.index("tank.momentum") < message.find("tank.mass") or "tank.mass" not in (
        message
    )


def test_singular_initial_jacobian_names_the_equation():
    def residual(t, y, yp):
        return np.array([yp[0] + y[0], y[0] - 1.0])  # y[1] appears nowhere

    with pytest.raises(DAEError) as info:
        solve_dae(
            residual,
            (0, 1),
            [1.0, 0.0],
            algebraic=[1],
            variable_names=["level", "flow"],
            equation_names=["tank.mass", "valve.law"],
        )
    message = str(info.value)
    assert "singular" in message and "flow" in message and "equation" in message


def _plant_like(residual, names, eq_names, pattern):
    pat = sp.csc_matrix(pattern, dtype=float)
    return SimpleNamespace(
        residual=residual,
        nominal=np.ones(len(names)),
        pattern_y=pat,
        pattern_yp=sp.csc_matrix(pat.shape),
        names=names,
        eq_names=eq_names,
        accumulator=np.zeros(len(names), dtype=bool),
    )


def test_plant_wrapper_solves_a_steady_state_and_raises_plant_error():
    # Steady state of a 2x2 nonlinear system: x^2 + y^2 = 5, x y = 2 -> (2, 1) from (3, 0.5).
    def residual(t, y, yp):
        return np.array([y[0] ** 2 + y[1] ** 2 - 5.0, y[0] * y[1] - 2.0])

    dae = _plant_like(residual, ["a.x", "a.y"], ["a.circle", "a.product"], np.ones((2, 2)))
    y, yp = solve_mixed(dae, 0.0, [3.0, 0.5], [0.0, 0.0], np.array([True, True]))
    # Converged to the plant tolerance (1e-9 relative, 0.0033 of it).
    np.testing.assert_allclose(y, [2.0, 1.0], rtol=1e-11)

    def impossible(t, y, yp):
        return np.array([y[0] ** 2 + 1.0, y[1] - 1.0])

    dae = _plant_like(impossible, ["a.x", "a.y"], ["a.circle", "a.product"], np.eye(2))
    with pytest.raises(PlantError, match="a.circle"):
        solve_mixed(dae, 0.0, [3.0, 0.5], [0.0, 0.0], np.array([True, True]), what="steady start")
