"""The progress bar of a run, for ``dnasim run --progress`` and ``simulate(progress=True)``:
the fraction of the end time reached, the simulated time [s], the wall time spent and an
estimate of the time left.

Drawn by tqdm (``tqdm.auto``): in a terminal one line on stderr, redrawn in place; in
Jupyter (IPython kernel with ipywidgets, the ``notebook`` extra) the notebook's progress
widget; in Jupyter without ipywidgets the text line in the cell's stderr. tqdm is
imported only when a bar is asked for, so ``import dnasim`` and ``dnasim --help`` stay
light (tests/test_startup_imports.py).
"""

from __future__ import annotations

__all__ = ["Progress"]

# the text line: "simulating:  42%|#####     | t = 25.2 s of 60 s [00:01<00:01]"; tqdm's
# fields in double braces, the simulated time filled in at each update (``_format``)
_FORMAT = "{{desc}}: {{percentage:3.0f}}%|{{bar}}| t = {t:.6g} s of {t1:.6g} s [{{elapsed}}<{eta}]"


def _format(t: float, t1: float, fraction: float = 0.0) -> str:
    # no estimate of the time left before 1 % of the run: the first steps are tiny
    # (a start at rest), tqdm's rate from them would promise days
    return _FORMAT.format(t=t, t1=t1, eta="{remaining}" if fraction >= 0.01 else "?")


def _tqdm_class():
    """``tqdm.auto.tqdm``: the notebook widget under an IPython kernel that has
    ipywidgets, the text bar everywhere else (its own choice, made at import)."""
    from tqdm.auto import tqdm

    return tqdm


class Progress:
    """Progress from t0 to t1 [s]; ``update(t)`` as the run goes, ``close()`` at its end.

    The bar counts simulated seconds from t0 (its total is t1 - t0 [s]); the text beside
    it is the simulated time t [s]. ``enabled=False``: nothing is imported or drawn.
    """

    def __init__(self, t0: float, t1: float, enabled: bool):
        self.enabled = enabled
        self.t0, self.t1 = float(t0), float(t1)
        self.bar = None
        self.done = 0.0  # the simulated time reached, from t0 [s]
        if enabled:
            import sys

            span = self.t1 - self.t0
            self.bar = _tqdm_class()(
                total=span if span > 0 else 1.0,
                desc="simulating",
                file=sys.stderr,  # stdout keeps the summary
                bar_format=_format(self.t0, self.t1),
                mininterval=0.1,  # at most ten redraws a second: a run has many steps
                leave=True,
            )

    def update(self, t: float) -> None:
        if self.bar is None:
            return
        span = self.t1 - self.t0
        x = min(max(t - self.t0, 0.0), span) if span > 0 else 1.0
        # at most 1000 updates a run (each 1/1000 of it) and the end: a run may hand
        # over many more output points than a bar can show
        if x >= self.done + 1e-3 * span or (x == span and x > self.done):
            # the text first (no redraw of its own), then the count: tqdm redraws at
            # most every mininterval; at t1 the count is exactly the total
            self.bar.bar_format = _format(t, self.t1, x / span if span > 0 else 1.0)
            self.bar.update(x - self.bar.n)
            self.bar.n = x  # no rounding left by the subtraction above
            self.done = x

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
