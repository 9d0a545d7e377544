"""Calling the user's functions: their exceptions become a DAEError naming the callback.

Every function the user hands to ``solve_dae`` (residual, jac, switch functions,
actions, the output callback) is called through ``call_user``. An exception it
raises is re-raised as ``UserCallbackError`` (a ``DAEError``) naming the
callback and the time, with the original chained as ``__cause__``; the driver
then attaches the partial result. ``ResidualDomainError`` (a state outside the
model's domain: the solver cuts the step), ``DAEError`` and
``KeyboardInterrupt`` pass through unchanged.
"""

from __future__ import annotations

from dnasim.core.errors import DAEError, ResidualDomainError


class UserCallbackError(DAEError):
    """A function given to ``solve_dae`` raised an exception (chained as __cause__)."""


def call_user(fn, what: str, t: float, *args):
    """fn(*args); a foreign exception becomes UserCallbackError naming ``what`` and t."""
    try:
        return fn(*args)
    except (ResidualDomainError, DAEError):
        raise
    except Exception as exc:
        raise user_error(what, t, exc) from exc


def user_error(what: str, t: float, exc: Exception) -> UserCallbackError:
    """The UserCallbackError for ``exc`` raised by the callback ``what`` at time t."""
    return UserCallbackError(
        f"{what[0].upper()}{what[1:]} raised {type(exc).__name__} at t = {float(t):.10g}: {exc}"
    )
