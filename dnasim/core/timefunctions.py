"""Time functions for boundary values and set points.

Each function is a callable ``f(t) -> float`` with an attribute ``breakpoints``:
the times at which the function or its slope jumps. The plant hands those times
to the integrator as ``tstops`` so that it stops exactly there and restarts
(a step is a time event; the integrator does not have to find it).

    Constant(value)                  f(t) = value
    Step(t0, before, after)          f(t) = before for t < t0, after for t >= t0
    Ramp(t0, t1, start, end)         start before t0, end after t1, linear between
    Table(times, values)             piecewise linear through the points, held flat
                                     outside the table
    Sine(mean, amplitude, period, phase=0)
                                     f(t) = mean + amplitude sin(2 pi t / period + phase)

``as_time_function(x)`` turns a number into ``Constant(x)`` and passes a time
function (or any callable with a ``breakpoints`` attribute) through.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "TimeFunction",
    "Constant",
    "Step",
    "Ramp",
    "Table",
    "Sine",
    "as_time_function",
]


class TimeFunction:
    """Base class: a scalar function of time with known breakpoints."""

    breakpoints: tuple[float, ...] = ()

    def __call__(self, t: float) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def __eq__(self, other):
        """Equal when of one type with equal attributes (plain data, e.g. for specs)."""
        if type(other) is not type(self):
            return NotImplemented
        a, b = vars(self), vars(other)
        return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)

    __hash__ = None

    def scaled(self, factor: float, offset: float = 0.0) -> TimeFunction:
        """Return ``factor * f(t) + offset`` as a time function (same breakpoints)."""
        return _Affine(self, factor, offset)


class _Affine(TimeFunction):
    def __init__(self, f: TimeFunction, factor: float, offset: float):
        self.f, self.factor, self.offset = f, float(factor), float(offset)
        self.breakpoints = tuple(f.breakpoints)

    def __call__(self, t):
        return self.factor * self.f(t) + self.offset

    def __repr__(self):
        return f"{self.factor!r}*{self.f!r}+{self.offset!r}"


class Constant(TimeFunction):
    """f(t) = value."""

    def __init__(self, value: float):
        self.value = float(value)
        self.breakpoints = ()

    def __call__(self, t):
        return self.value

    def __repr__(self):
        return f"Constant({self.value!r})"


class Step(TimeFunction):
    """f(t) = before for t < t0, after for t >= t0. Breakpoint: t0."""

    def __init__(self, t0: float, before: float, after: float):
        self.t0, self.before, self.after = float(t0), float(before), float(after)
        self.breakpoints = (self.t0,)

    def __call__(self, t):
        return self.after if t >= self.t0 else self.before

    def __repr__(self):
        return f"Step(t0={self.t0!r}, before={self.before!r}, after={self.after!r})"


class Ramp(TimeFunction):
    """start for t <= t0, end for t >= t1, linear in between. Breakpoints: t0, t1."""

    def __init__(self, t0: float, t1: float, start: float, end: float):
        if not t1 > t0:
            raise ValueError(f"Ramp needs t1 > t0, got t0={t0}, t1={t1}")
        self.t0, self.t1 = float(t0), float(t1)
        self.start, self.end = float(start), float(end)
        self.breakpoints = (self.t0, self.t1)

    def __call__(self, t):
        if t <= self.t0:
            return self.start
        if t >= self.t1:
            return self.end
        return self.start + (self.end - self.start) * (t - self.t0) / (self.t1 - self.t0)

    def __repr__(self):
        return f"Ramp({self.t0!r}, {self.t1!r}, {self.start!r}, {self.end!r})"


class Table(TimeFunction):
    """Piecewise-linear interpolation in (times, values); flat outside.

    Breakpoints: every table time (the slope jumps there).
    """

    def __init__(self, times, values):
        times = np.asarray(times, dtype=float)
        values = np.asarray(values, dtype=float)
        if times.ndim != 1 or times.shape != values.shape or times.size < 1:
            raise ValueError("Table needs two 1-D sequences of equal, non-zero length")
        if np.any(np.diff(times) <= 0):
            raise ValueError("Table times must be strictly increasing")
        self.times, self.values = times, values
        self.breakpoints = tuple(float(x) for x in times)

    def __call__(self, t):
        return float(np.interp(t, self.times, self.values))

    def __repr__(self):
        return f"Table({self.times.tolist()!r}, {self.values.tolist()!r})"


class Sine(TimeFunction):
    """f(t) = mean + amplitude sin(2 pi t / period + phase). No breakpoints."""

    def __init__(self, mean: float, amplitude: float, period: float, phase: float = 0.0):
        if not period > 0:
            raise ValueError(f"Sine needs period > 0, got {period}")
        self.mean, self.amplitude = float(mean), float(amplitude)
        self.period, self.phase = float(period), float(phase)
        self.breakpoints = ()

    def __call__(self, t):
        return self.mean + self.amplitude * math.sin(2.0 * math.pi * t / self.period + self.phase)

    def __repr__(self):
        return f"Sine({self.mean!r}, {self.amplitude!r}, {self.period!r}, {self.phase!r})"


def as_time_function(x) -> TimeFunction:
    """Turn a number into ``Constant``; pass time functions through unchanged."""
    if isinstance(x, TimeFunction):
        return x
    if callable(x) and hasattr(x, "breakpoints"):
        return x
    if isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool):
        return Constant(float(x))
    raise TypeError(f"expected a number or a time function, got {x!r}")
