"""Bad input and failures give a DAEError that says what is wrong, never a numpy traceback."""

import numpy as np
import pytest

from dnasim import DAEError, ResidualDomainError, solve_dae


def decay(t, y, yp):
    return yp + y


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(y0=[[1.0, 2.0]]), "one-dimensional"),
        (dict(y0=[1.0], yp0=[0.0, 1.0]), "yp0 has 2 entries"),
        (dict(y0=[np.nan]), "NaN"),
        (dict(y0=[1.0], atol=[1e-8, 1e-8]), "atol"),
        (dict(y0=[1.0], rtol=-1), "rtol"),
        (dict(y0=[1.0], max_order=7), "max_order"),
        (dict(y0=[1.0], t_span=(1.0, 0.0)), "t_end > t0"),
        (dict(y0=[1.0], algebraic=[3]), "algebraic"),
        (dict(y0=[1.0], jac_sparsity=np.ones((2, 2))), "jac_sparsity"),
        (dict(y0=[1.0], t_eval=[5.0]), "t_eval"),
    ],
)
def test_bad_arguments(kwargs, words):
    args = dict(t_span=(0.0, 1.0))
    args.update(kwargs)
    with pytest.raises(DAEError, match=words):
        solve_dae(decay, args.pop("t_span"), args.pop("y0"), **args)


def test_residual_of_wrong_shape():
    with pytest.raises(DAEError, match=r"shape \(2,\)"):
        solve_dae(lambda t, y, yp: np.zeros(3), (0, 1), [1.0, 2.0])


def test_residual_returning_nan_fails_with_time_and_component():
    def residual(t, y, yp):
        f = yp + y
        if t > 0.5:
            f[1] = np.nan
        return f

    with pytest.raises(DAEError) as info:
        solve_dae(residual, (0, 1), [1.0, 1.0], rtol=1e-6, variable_names=["a", "b"], throw=True)
    message = str(info.value)
    assert "NaN" in message and "equation(s) 1" in message
    assert "t = 0.5" in message  # stopped at the last good time, just before 0.5+
    partial = info.value.result
    assert not partial.success and partial.t[-1] <= 0.5 and partial.t[-1] > 0.49


def test_nan_in_a_newton_iterate_names_the_equation():
    # NaN on every second call after t = 0.5: at predictors and at Newton iterates
    # (both occur in this run). At an iterate the corrector sees it through the
    # non-finite update that follows (bdf._newton); either way the message must name
    # the equation, not only say "not finite".
    calls = {"n": 0}

    def residual(t, y, yp):
        f = yp + y
        calls["n"] += 1
        if t > 0.5 and calls["n"] % 2 == 0:
            f[1] = np.nan
        return f

    with pytest.raises(DAEError) as info:
        solve_dae(residual, (0, 1), [1.0, 1.0], rtol=1e-6, throw=True)
    message = str(info.value)
    assert "returned NaN or inf" in message and "equation(s) 1" in message


def test_domain_error_is_recovered_by_a_smaller_step():
    """sqrt(y) with y -> 0: predictions below 0 raise, the solver cuts the step and goes on."""

    def residual(t, y, yp):
        if y[0] < 0:
            raise ResidualDomainError(f"negative y = {y[0]}")
        return yp + np.sqrt(y)

    # Closed form y = (1 - t/2)^2 until t = 2, then 0.
    res = solve_dae(residual, (0, 1.9), [1.0], rtol=1e-8, atol=1e-10)
    assert res.y[0, -1] == pytest.approx((1 - 1.9 / 2) ** 2, rel=1e-4)


def test_inconsistent_start_that_cannot_be_made_consistent():
    def residual(t, y, yp):
        return np.array([yp[0] + y[0], y[1] ** 2 + 1.0])  # 0 = y2^2 + 1 has no real root

    with pytest.raises(DAEError, match="inconsistent"):
        solve_dae(residual, (0, 1), [1.0, 0.5], algebraic=[1])


def test_singular_iteration_matrix_names_the_variable():
    def residual(t, y, yp):
        return np.array([yp[0] + y[0], y[0] - 1.0])  # y[1] appears nowhere

    with pytest.raises(DAEError) as info:
        solve_dae(
            residual,
            (0, 1),
            [1.0, 0.0],
            algebraic=[1],
            calc_initial=False,
            variable_names=["level", "flow"],
            throw=True,
        )
    message = str(info.value)
    assert "singular" in message and "flow" in message
