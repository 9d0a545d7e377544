"""The progress line of a run on stderr: one line redrawn in place (click's progress
bar), percentage of the end time reached, the simulated time, an estimate of the time
left; for ``dnasim run --progress`` and ``simulate(progress=True)``."""

from __future__ import annotations

__all__ = ["Progress"]


class Progress:
    """Progress from t0 to t1 [s]; ``update(t)`` as the run goes, ``close()`` at its end."""

    def __init__(self, t0: float, t1: float, enabled: bool):
        self.enabled = enabled
        self.t0, self.t1 = t0, t1
        self.bar = None
        self.done = 0
        if enabled:
            import sys

            import click

            self.bar = click.progressbar(
                file=sys.stderr,  # one line, redrawn; stdout keeps the summary
                length=1000,
                label="simulating",
                show_eta=True,
                show_percent=True,
                width=30,
                item_show_func=lambda t: None if t is None else f"t = {t:.6g} s",
            )
            self.bar.__enter__()

    def update(self, t: float) -> None:
        if self.bar is None:
            return
        frac = (t - self.t0) / (self.t1 - self.t0) if self.t1 > self.t0 else 1.0
        n = int(max(0.0, min(1.0, frac)) * 1000)
        if n > self.done:
            self.bar.update(n - self.done, current_item=t)
            self.done = n

    def close(self) -> None:
        if self.bar is not None:
            self.bar.__exit__(None, None, None)
            self.bar = None
