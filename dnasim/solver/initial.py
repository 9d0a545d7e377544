"""Consistent initial values for an index-1 DAE (as SUNDIALS IDACalcIC, YA_YDP_INIT).

Given the differential components of y, find the algebraic components of y and
the derivatives y' of the differential components such that F(t0, y, y') = 0.
The unknowns are u = (y_a, y'_d); the Jacobian dF/du takes the columns of
dF/dy for the algebraic and of dF/dy' for the differential components. For an
index-1 DAE it is nonsingular. The derivatives of the algebraic components are
not determined by F; they are set to zero.

Newton's method with a backtracking line search on ||F||_2; convergence when
the weighted RMS norm of the update is below 0.01 * 0.33 (IDA's epicfac * epcon),
with y' updates weighted by a time scale h so they count as changes of y.
"""

from __future__ import annotations

import numpy as np

from dnasim.errors import DAEError, ResidualDomainError
from dnasim.solver.linear_algebra import SQRT_EPS, IterationMatrix, SingularMatrixError

MAX_ITERS = 30
TOLERANCE = 0.01 * 0.33


def _evaluate(residual, t, y, yp):
    try:
        f = residual(t, y, yp)
    except ResidualDomainError:
        return None
    return f if np.all(np.isfinite(f)) else None


def make_consistent(
    residual,
    t: float,
    y: np.ndarray,
    yp: np.ndarray,
    algebraic: np.ndarray,
    weights: np.ndarray,
    h_scale: float,
    matrix: IterationMatrix,
    names=None,
) -> tuple[np.ndarray, np.ndarray]:
    """Return (y, yp) with the differential y kept and F(t, y, yp) = 0 solved for the rest."""
    y = np.array(y, dtype=float)
    yp = np.array(yp, dtype=float)
    yp[algebraic] = 0.0
    alg = algebraic.astype(float)
    diff = 1.0 - alg
    # Scale of each unknown: y weights for y_a, h * y weights for y'_d.
    unknown_weights = weights * (alg + h_scale * diff)
    f = _evaluate(residual, t, y, yp)
    if f is None:
        raise DAEError(_message(t, "the residual cannot be evaluated at the initial values", names))
    last_problem = ""
    for _ in range(MAX_ITERS):
        u = np.where(algebraic, y, yp)
        inc = np.maximum(SQRT_EPS * np.abs(u), 1.0 / unknown_weights)  # as IDA's DQ increments
        inc = (u + inc) - u
        jac = matrix.finite_difference(t, y, yp, f, inc, alg, diff)
        matrix.matrix = jac
        matrix.cj = None
        try:
            matrix.factorize()
        except SingularMatrixError as exc:
            raise DAEError(
                _message(
                    t,
                    "the Jacobian of F with respect to the algebraic variables and the "
                    f"derivatives of the differential ones is singular. {exc} If some variables "
                    "are algebraic (their derivatives appear nowhere), pass them as `algebraic`.",
                    names,
                )
            ) from None
        du = matrix.solve(-f)
        full_update = np.sqrt(np.mean((du * unknown_weights) ** 2))
        if full_update <= TOLERANCE:
            # Converged: the residual is at round-off level and the last correction tiny.
            # (A line search is no use there: ||F|| is round-off noise.)
            y = y + du * alg
            yp = yp + du * diff
            matrix.matrix = None
            return y, yp
        f_norm = np.linalg.norm(f)
        step = 1.0
        for _ in range(12):
            y_new = y + step * du * alg
            yp_new = yp + step * du * diff
            f_new = _evaluate(residual, t, y_new, yp_new)
            if f_new is not None and np.linalg.norm(f_new) <= (1.0 - 1e-4 * step) * f_norm + 1e-300:
                break
            if f_new is not None and step < 1.0 / 64 and np.linalg.norm(f_new) <= f_norm:
                break
            step *= 0.5
        else:
            last_problem = "the line search could not reduce the residual"
            break
        y, yp, f = y_new, yp_new, f_new
        update = np.sqrt(np.mean((step * du * unknown_weights) ** 2))
        if update <= TOLERANCE or np.linalg.norm(f) == 0.0:
            matrix.matrix = None  # the solver must build its own iteration matrix
            return y, yp
    matrix.matrix = None
    worst = np.argsort(-np.abs(f))[:4]
    eqs = ", ".join(f"equation {i} (residual {f[i]:.3g})" for i in worst)
    raise DAEError(
        _message(
            t,
            "the initial values are inconsistent and could not be made consistent"
            + (f" ({last_problem})" if last_problem else "")
            + f"; the largest remaining residuals: {eqs}",
            names,
        )
    )


def _message(t, what, names) -> str:
    return f"At t = {t:.10g}: {what}."


def detect_algebraic(residual, t, y, yp, matrix: IterationMatrix) -> np.ndarray:
    """Components whose derivative does not appear in F, found by probing dF/dy'.

    A column of dF/dy' that is zero at the initial point and at a perturbed point
    marks an algebraic component.
    """
    n = y.size
    mask = np.ones(n, dtype=bool)
    for scale in (1.0, 1.37):
        yp_probe = yp * scale + 1e-3 * (np.arange(n) % 7 + 1)
        f0 = residual(t, y, yp_probe)
        inc = 1e-6 * np.maximum(1.0, np.abs(yp_probe))
        inc = (yp_probe + inc) - yp_probe
        jac = matrix.finite_difference(t, y, yp_probe, f0, inc, 0.0, 1.0)
        dense = jac.toarray() if hasattr(jac, "toarray") else jac
        mask &= ~np.any(dense != 0.0, axis=0)
    matrix.matrix = None
    return mask
