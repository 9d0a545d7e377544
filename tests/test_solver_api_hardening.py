"""Solver API hardening: user-callback exceptions, wrong returns, bad input, extreme scales."""

import numpy as np
import pytest

from dnasim import DAEError, solve_dae


def decay(t, y, yp):
    return yp + y


class Boom(RuntimeError):
    pass


def _raises_after(t_fail, value=None):
    def fn(t, *args):
        if t > t_fail:
            raise Boom("user code failed")
        return value(t, *args) if value is not None else None

    return fn


@pytest.mark.parametrize("where", ["residual", "event", "action", "jac", "callback"])
def test_exception_in_a_user_callback_is_wrapped_with_the_partial_result(where):
    kwargs = {}
    residual = decay
    if where == "residual":
        residual = _raises_after(0.5, decay)
    elif where == "event":
        g = _raises_after(0.5, lambda t, y, yp: y[0] - 0.1)
        g.name = "level"
        kwargs["events"] = [g]
    elif where == "action":

        def g(t, y, yp):
            return y[0] - 0.5

        def action(t, y, yp):
            raise Boom("user code failed")

        g.action = action
        kwargs["events"] = [g]
    elif where == "jac":
        # A linear problem needs one Jacobian only: make that one fail.
        kwargs["jac"] = _raises_after(-1.0, lambda t, y, yp, cj: np.array([[1.0 + cj]]))
    else:
        kwargs["callback"] = _raises_after(0.5)
    with pytest.raises(DAEError) as info:
        solve_dae(residual, (0, 3), [1.0], rtol=1e-6, throw=True, **kwargs)
    err = info.value
    assert isinstance(err.__cause__, Boom)  # the original, chained
    assert "Boom" in str(err) and "user code failed" in str(err)
    partial = err.result
    assert not partial.success and partial.t.size >= 1 and partial.t[-1] <= 3.0
    # throw=False (the default, as simulate's): the same failure, returned
    res = solve_dae(residual, (0, 3), [1.0], rtol=1e-6, **kwargs)
    assert not res.success and res.status == -1 and res.message == str(err)
    np.testing.assert_array_equal(res.t, partial.t)


def test_residual_returning_strings_is_named():
    with pytest.raises(DAEError, match="strings"):
        solve_dae(lambda t, y, yp: np.array(["a"]), (0, 1), [1.0], calc_initial=False)


def test_action_returning_the_wrong_shape_is_named():
    def g(t, y, yp):
        return y[0] - 0.5

    g.name = "half"
    g.action = lambda t, y, yp: (np.zeros(3), np.zeros(3))
    with pytest.raises(DAEError, match=r"action of switch 'half'.*shape \(1,\)"):
        solve_dae(decay, (0, 1), [1.0], events=[g], throw=True)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(t_eval=[0.0, np.nan, 1.0]), "t_eval holds NaN"),
        (dict(t_eval=[0.0, np.inf]), "t_eval holds NaN or inf"),
        (dict(t_eval=["0", "1"]), "t_eval must hold real numbers; it holds strings"),
        (dict(y0=[1.0 + 2.0j]), "y0 must hold real numbers; it holds complex"),
        (dict(y0=["1.0"]), "y0 must hold real numbers; it holds strings"),
        (dict(yp0=[1j]), "yp0 must hold real numbers; it holds complex"),
        (dict(atol="1e-8"), "atol must hold real numbers"),
        (dict(rtol="1e-6"), "rtol must be one number"),
        (dict(t_span=("0", "1")), "t_span must hold real numbers"),
    ],
)
def test_bad_values_are_refused_with_a_plain_message(kwargs, words):
    args = dict(t_span=(0.0, 1.0), y0=[1.0])
    args.update(kwargs)
    with pytest.raises(DAEError, match=words):
        solve_dae(decay, args.pop("t_span"), args.pop("y0"), **args)


def test_extreme_time_scales_are_not_reported_singular():
    # y' = -y / T over [0, T], T = 1e300: y(T) = exp(-1); with an algebraic y2 = 2 y1.
    def scaled(t, y, yp):
        return np.array([yp[0] + y[0] / 1e300, y[1] - 2.0 * y[0]])

    res = solve_dae(scaled, (0, 1e300), [1.0, 2.0], rtol=1e-6)
    # Global error of a BDF run at rtol 1e-6: 1e-4 leaves a factor 100.
    assert res.y[0, -1] == pytest.approx(np.exp(-1.0), rel=1e-4)
    # A first step of 1e10 s on a time constant of 1e12 s, run to 1e13 s: exp(-10).
    res = solve_dae(lambda t, y, yp: yp + y / 1e12, (0, 1e13), [1.0], h0=1e10, rtol=1e-6)
    assert res.y[0, -1] == pytest.approx(np.exp(-10.0), rel=1e-3)  # 10 time constants
    # y' + 1e12 y = 0 over 1e-11 s: the y' term is 1e-12 of the others; it must still
    # be seen as a derivative (not taken for an algebraic variable).
    res = solve_dae(lambda t, y, yp: yp + 1e12 * y, (0, 1e-11), [1.0], rtol=1e-6)
    assert res.y[0, 0] == 1.0
    assert res.y[0, -1] == pytest.approx(np.exp(-10.0), rel=1e-3)


def test_stiff_damped_oscillator_over_100_seconds():
    """x'' + 10 x' + 1e4 x = 0, x(0) = 1: decays as exp(-5 t); at t = 100 it is ~0."""

    def osc(t, y, yp):
        return np.array([yp[0] - y[1], yp[1] + 1e4 * y[0] + 10.0 * y[1]])

    res = solve_dae(osc, (0, 100), [1.0, 0.0], rtol=1e-3, atol=1e-6)
    assert res.success and res.t[-1] == 100.0
    # |x(100)| = exp(-500) ~ 0: what is left is the solver's noise, a few atol at most.
    assert abs(res.y[0, -1]) < 1e-5


def test_failures_are_reported_alike_by_solve_dae_and_simulate():
    # one contract (issue 8): success False by default, DAEError with .result on
    # throw=True; the default is the same in both
    import inspect

    from dnasim.run.simulation import simulate

    for f in (solve_dae, simulate):
        assert inspect.signature(f).parameters["throw"].default is False
    res = solve_dae(decay, (0, 1e6), [1.0], max_steps=5)
    assert not res.success and res.status == -1 and "5 steps" in res.message
    assert res.t.size >= 1  # the solution up to the last accepted step
    with pytest.raises(DAEError, match="5 steps") as info:
        solve_dae(decay, (0, 1e6), [1.0], max_steps=5, throw=True)
    assert not info.value.result.success


def test_inconsistent_initial_values_raise_whatever_throw_says():
    # no solution to return (simulate raises for a plant that cannot start, too)
    def residual(t, y, yp):
        return np.array([yp[0] + y[0], y[1] ** 2 + 1.0])  # y1^2 = -1 has no solution

    with pytest.raises(DAEError, match="initial values"):
        solve_dae(residual, (0, 1), [1.0, 0.0], algebraic=[1], throw=False)
