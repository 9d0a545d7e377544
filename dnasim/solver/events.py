"""Switch functions: detecting their sign changes and locating them.

A switch function g(t, y, y') (seed sec. 10.2.1) is defined to change sign at a
discontinuity. After every accepted step the driver compares the signs of g at
the two ends of the step. On a change, the zero is located on the step's
Nordsieck interpolant by iterating on the inverse function t = g^{-1}(0):
inverse quadratic interpolation through the last three iterates (secant when
only two are distinct), safeguarded by bisection so it can never stall
(Brent's zeroin). It stops when the bracket is a few ulp of t wide or g is
exactly zero, and returns the bracket end on the *new* side of the switch, so
that integration restarts where the switch has already changed sign (seed:
"it is important that the method is restarted at a time instance where the
switch has changed its sign"). Every iterate (t, g) is recorded.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from dnasim.errors import DAEError

EPS = float(np.finfo(float).eps)
MAX_ITERATIONS = 100


@dataclass
class SwitchFunction:
    """A user's switch function with its attributes made explicit."""

    g: Callable
    index: int
    name: str
    direction: int  # +1: only rising (- to +), -1: only falling, 0: both
    terminal: bool
    action: Callable | None

    @classmethod
    def wrap(cls, g, index) -> SwitchFunction:
        if not callable(g):
            raise DAEError(f"events[{index}] is not callable; a switch function is g(t, y, yp).")
        direction = int(np.sign(getattr(g, "direction", 0) or 0))
        name = getattr(g, "name", None) or getattr(g, "__name__", None) or f"event{index}"
        action = getattr(g, "action", None)
        if action is not None and not callable(action):
            raise DAEError(f"events[{index}].action is not callable.")
        return cls(g, index, str(name), direction, bool(getattr(g, "terminal", False)), action)

    def value(self, t, y, yp) -> float:
        v = self.g(t, y, yp)
        try:
            v = float(v)
        except (TypeError, ValueError):
            raise DAEError(
                f"Switch function {self.name!r} returned {v!r}; it must return one number."
            ) from None
        if not np.isfinite(v):
            raise DAEError(f"Switch function {self.name!r} returned {v} at t = {t:.10g}.")
        return v

    def crossed(self, g_old: float, g_new: float) -> bool:
        """A sign change from g_old to g_new that this function's direction reports."""
        if g_old == 0.0 or np.sign(g_old) == np.sign(g_new):
            return False
        if g_new == 0.0:
            return False  # not across yet; seen on the next step
        rising = g_new > 0.0
        return self.direction == 0 or (self.direction > 0) == rising


def locate_zero(
    g: Callable[[float], float], t_a: float, g_a: float, t_b: float, g_b: float
) -> tuple[float, float, list[tuple[float, float]]]:
    """Zero of g between t_a (old sign) and t_b (new sign), by Brent's zeroin.

    Returns (t_star, g(t_star), iterates) with t_star on the new side of the
    switch (sign of g_b, or g = 0), within a few ulp of the true crossing.
    """
    iterates = [(t_a, g_a), (t_b, g_b)]
    new_sign = np.sign(g_b)
    a, fa, b, fb = t_a, g_a, t_b, g_b
    c, fc = a, fa
    d = e = b - a
    for _ in range(MAX_ITERATIONS):
        if np.sign(fb) == np.sign(fc):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, fa = b, fb
            b, fb = c, fc
            c, fc = a, fa
        tol = 2.0 * EPS * abs(b)
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            break
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:  # secant
                p = 2.0 * m * s
                qq = 1.0 - s
            else:  # inverse quadratic interpolation
                qq = fa / fc
                r = fb / fc
                p = s * (2.0 * m * qq * (qq - r) - (b - a) * (r - 1.0))
                qq = (qq - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                qq = -qq
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * qq - abs(tol * qq), abs(e * qq)):
                e, d = d, p / qq
            else:
                d = e = m
        else:
            d = e = m
        a, fa = b, fb
        b = b + d if abs(d) > tol else b + np.copysign(tol, m)
        fb = g(b)
        iterates.append((b, fb))
    # The bracket is [b, c] (or b is an exact zero). Return its end on the new side.
    if fb == 0.0 or np.sign(fb) == new_sign:
        return b, fb, iterates
    if fc == 0.0 or np.sign(fc) == new_sign:
        if (c, fc) != iterates[-1]:
            iterates.append((c, fc))
        return c, fc, iterates
    raise DAEError("internal error: the switch-function bracket was lost")  # pragma: no cover
