"""The residual as the solver calls it (``CountedResidual``: counted, its shape and
type checked), the work counters (``SolverStats``) and why a step failed
(``StepFailure``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from dnasim.core.errors import DAEError, ResidualDomainError
from dnasim.solver.callbacks import user_error


@dataclass
class SolverStats:
    """Work counters, named as in the IDA/DASSL literature."""

    steps: int = 0
    rejected_error: int = 0
    rejected_newton: int = 0
    residual_evals: int = 0
    jac_evals: int = 0
    lu_decomps: int = 0
    newton_iters: int = 0
    full_newton_iters: int = 0
    reinitializations: int = 0
    #: output points between steps whose algebraic variables were solved for
    #: (``driver.Driver.refine``), and those where that failed (kept interpolated)
    output_solves: int = 0
    output_solve_failures: int = 0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class StepFailure:
    """Why the last attempt failed (used in the final error message)."""

    reason: str = ""
    bad_components: list = field(default_factory=list)


class CountedResidual:
    """Wraps the user's residual: counts calls, checks the returned shape."""

    def __init__(self, residual, n, stats: SolverStats):
        self.residual = residual
        self.n = n
        self.shape = (n,)
        self.stats = stats

    def __call__(self, t, y, yp):
        self.stats.residual_evals += 1
        try:  # call_user inlined: this is the hot path of small problems
            f = self.residual(t, y, yp)
        except (ResidualDomainError, DAEError):
            raise
        except Exception as exc:
            raise user_error("the residual", t, exc) from exc
        if not (type(f) is np.ndarray and f.dtype.kind == "f"):
            f = _as_float_array(f, t)
        if f.shape != self.shape:
            raise DAEError(
                f"residual(t, y, yp) returned an array of shape {f.shape}; it must return "
                f"shape ({self.n},), one equation per unknown."
            )
        return f


def _as_float_array(f, t) -> np.ndarray:
    """The residual's value as floats; strings, None or complex numbers are an error."""
    arr = np.asarray(f)
    if arr.dtype.kind not in "biuf":
        raise DAEError(
            f"residual(t, y, yp) returned {_describe(f)} at t = {float(t):.10g}; it must "
            "return an array of real numbers."
        )
    return arr.astype(float)


def _describe(f) -> str:
    arr = np.asarray(f)
    kinds = {"U": "strings", "S": "bytes", "O": "objects", "c": "complex numbers"}
    what = kinds.get(arr.dtype.kind, f"values of type {arr.dtype}")
    return f"{what} ({str(f)[:60]!r})"


def _largest(scaled: np.ndarray, k: int = 5) -> list:
    """Indices of the k largest |entries| (the unknowns whose last Newton update was
    largest against their tolerance: named in the failure message)."""
    k = min(k, scaled.size)
    idx = np.argpartition(-np.abs(scaled), k - 1)[:k]
    return idx[np.argsort(-np.abs(scaled[idx]))].tolist()


def all_finite(f: np.ndarray) -> bool:
    """No NaN or inf in f; the same answer as np.all(np.isfinite(f)), in 1 us instead of 4.

    f.f is not finite whenever an entry is NaN or inf (inf * inf = inf, NaN spreads),
    so a finite dot product proves every entry finite; only a non-finite one (an
    entry NaN or inf, or finite entries whose squares overflow) needs the full test.
    """
    s = f.dot(f)
    return math.isfinite(s) or bool(np.isfinite(f).all())
