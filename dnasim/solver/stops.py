"""Known time discontinuities (tstops): the steps land on them exactly."""

from __future__ import annotations


class Stops:
    """The tstops strictly inside (t0, t_end), in order, consumed as they are reached.

    ``next(t)`` is where the step from t must end at the latest: the first stop after
    t, else t_end. A step that lands on a stop sees the residual at its left limit
    (``NordsieckBDF.step(left_limit=True)``); ``reached(t)`` then removes it and the
    driver restarts from values made consistent at the right limit.
    """

    def __init__(self, tstops, t0: float, t_end: float):
        self.t_end = t_end
        self.times = sorted({float(s) for s in tstops if t0 < s < t_end})  # each once

    def next(self, t: float) -> float:
        """The first stop after t, or t_end."""
        times = self.times
        return times[0] if times and times[0] > t else self.t_end

    def reached(self, t: float) -> bool:
        """Whether t is the next stop; if so it is consumed."""
        if self.times and t == self.times[0]:
            self.times.pop(0)
            return True
        return False
