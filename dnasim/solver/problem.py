"""The solver's input, validated: ``Problem.validate`` checks what ``solve_dae`` is
given and raises ``DAEError`` with one plain sentence for anything it cannot use."""

from __future__ import annotations

import numpy as np

from dnasim.core.errors import DAEError
from dnasim.solver.events import SwitchFunction


class Problem:
    """The DAE as the solver sees it, validated: the residual, t_span, (y0, yp0), the
    algebraic and quadrature masks, tolerances, step limits, the sparsity pattern
    and the partial-residual channel, switch functions, tstops and output times.
    Every check raises DAEError with a plain message (``validate``)."""

    @classmethod
    def validate(
        cls,
        residual,
        t_span,
        y0,
        yp0,
        algebraic,
        quadrature,
        rtol,
        atol,
        max_order,
        h0,
        max_step,
        sparsity,
        events,
        tstops,
        t_eval,
        names,
        equation_names=None,
        residual_for_columns=None,
        output_interval=None,
    ):
        p = cls()
        if not callable(residual):
            raise DAEError("residual must be a function F(t, y, yp) -> array.")
        span = _real_array(t_span, "t_span").ravel()
        if span.size != 2:
            raise DAEError(f"t_span must be two numbers (t0, t_end); got {t_span!r}.")
        t0, t_end = float(span[0]), float(span[1])
        if not (np.isfinite(t0) and np.isfinite(t_end)) or t_end <= t0:
            raise DAEError(f"t_span must be finite with t_end > t0; got ({t0}, {t_end}).")
        p.t0, p.t_end = t0, t_end
        p.y0 = _vector(y0, "y0")
        p.n = n = p.y0.size
        p.yp0 = np.zeros(n) if yp0 is None else _vector(yp0, "yp0", n)
        if not (_is_real(rtol) and np.isfinite(rtol) and 0.0 < rtol < 1.0):
            raise DAEError(f"rtol must be one number between 0 and 1; got {rtol!r}.")
        a = _real_array(atol, "atol")
        if a.ndim == 0:
            a = np.full(n, float(a))
        if a.shape != (n,) or not np.all(np.isfinite(a)) or np.any(a <= 0.0):
            raise DAEError(
                f"atol must be a positive number or {n} positive numbers; got shape {a.shape} "
                f"with minimum {np.min(a) if a.size else 'n/a'}."
            )
        p.atol = a
        if max_order not in (1, 2, 3, 4, 5):
            raise DAEError(f"max_order must be 1, 2, 3, 4 or 5; got {max_order!r}.")
        if h0 is not None and not (_is_real(h0) and np.isfinite(h0) and h0 > 0):
            raise DAEError(f"h0 must be a positive number; got {h0!r}.")
        if not (_is_real(max_step) and max_step > 0):
            raise DAEError(f"max_step must be positive; got {max_step!r}.")
        p.algebraic = _mask(algebraic, n, "algebraic")
        p.quadrature = _mask(quadrature, n, "quadrature")
        p.sparsity = sparsity
        if sparsity is not None and getattr(sparsity, "shape", None) != (n, n):
            raise DAEError(
                f"jac_sparsity must have shape ({n}, {n}); got {getattr(sparsity, 'shape', None)}."
            )
        p.tstops = sorted(float(s) for s in np.atleast_1d(_real_array(tstops, "tstops")))
        if any(not np.isfinite(s) for s in p.tstops):
            raise DAEError("tstops must be finite times.")
        p.t_eval = None
        if t_eval is not None:
            te = _real_array(t_eval, "t_eval").ravel()
            if not np.all(np.isfinite(te)):
                bad = np.flatnonzero(~np.isfinite(te))[:5].tolist()
                raise DAEError(f"t_eval holds NaN or inf at index(es) {bad}.")
            if np.any(np.diff(te) < 0) or te.size == 0:
                raise DAEError("t_eval must be a non-empty, increasing sequence of times.")
            if te[0] < t0 or te[-1] > t_end:
                raise DAEError(f"t_eval must lie within t_span [{t0}, {t_end}].")
            p.t_eval = te
        p.names, p.equation_names = names, equation_names
        if names is not None and len(names) != n:
            raise DAEError(f"variable_names has {len(names)} names for {n} unknowns.")
        if equation_names is not None and len(equation_names) != n:
            raise DAEError(f"equation_names has {len(equation_names)} names for {n} equations.")
        for i, g in enumerate(events):
            SwitchFunction.wrap(g, i)
        if residual_for_columns is not None and not callable(residual_for_columns):
            raise DAEError(
                "residual_for_columns must be a function cols -> F_cols(t, y, yp, f0) or None."
            )
        if residual_for_columns is not None and sparsity is None:
            raise DAEError("residual_for_columns needs jac_sparsity (its column groups).")
        p.residual_for_columns = residual_for_columns
        if p.t_eval is not None and output_interval is not None:
            raise DAEError("give t_eval or output_interval, not both.")
        if output_interval is not None:
            dt = output_interval
            if isinstance(dt, bool) or not (
                isinstance(dt, (int, float, np.integer, np.floating)) and np.isfinite(dt) and dt > 0
            ):
                raise DAEError(f"output_interval must be a positive number; got {dt!r}.")
            output_interval = float(dt)
        p.output_interval = output_interval
        return p


def _mask(v, n, what) -> np.ndarray | None:
    """A boolean mask of n entries from indices or a mask (None stays None)."""
    if v is None:
        return None
    arr = np.asarray(v)
    mask = np.zeros(n, dtype=bool)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise DAEError(f"{what} as a mask must have {n} entries; got {arr.shape}.")
        return arr.copy()
    if arr.size:
        if not np.issubdtype(arr.dtype, np.integer) or arr.min() < -n or arr.max() >= n:
            raise DAEError(
                f"{what} must hold indices in 0..{n - 1} or a boolean mask; got {arr!r}."
            )
        mask[arr] = True
    return mask


def _is_real(v) -> bool:
    """A real number (bool excluded), as Python or numpy scalar."""
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _real_array(v, what) -> np.ndarray:
    """v as a float array; strings, complex numbers, None or objects are refused."""
    try:
        raw = np.asarray(v)
    except (TypeError, ValueError):
        raise DAEError(f"{what} must be an array of real numbers.") from None
    if raw.dtype.kind not in "biuf":
        kinds = {"U": "strings", "S": "bytes", "c": "complex numbers", "O": "non-numbers"}
        got = kinds.get(raw.dtype.kind, f"values of type {raw.dtype}")
        raise DAEError(f"{what} must hold real numbers; it holds {got}.")
    return raw.astype(float)


def _vector(v, what, n=None) -> np.ndarray:
    arr = np.array(_real_array(v, what), dtype=float)
    if arr.ndim != 1 or arr.size == 0:
        raise DAEError(f"{what} must be a one-dimensional array; got shape {arr.shape}.")
    if n is not None and arr.size != n:
        raise DAEError(f"{what} has {arr.size} entries but y0 has {n}.")
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.isfinite(arr))[:5].tolist()
        raise DAEError(f"{what} holds NaN or inf at index(es) {bad}.")
    return arr
