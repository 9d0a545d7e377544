"""Consistent initial values for an assembled plant, by damped Newton.

Two starts:

* ``"steady"``: solve F(t0, y, 0) = 0 for y, starting from the components'
  initial guesses. Accumulators (running integrals such as the mass that has
  passed a boundary) keep their initial value and their derivative is solved for
  instead.
* ``"given"``: the differential variables keep the values of the initial
  guesses (the components' given initial states: a pipe's T0, a controller's
  integral0, ...); solve F(t0, y, y') = 0 for the algebraic variables and the
  derivatives of the differential ones.

Both are one routine, ``solve_mixed``: the unknown vector holds y_i where
``y_unknown[i]`` and y'_i elsewhere. The Jacobian is built by finite
differences grouped by a greedy column colouring of the declared sparsity and
factorised by sparse LU; the step is damped by backtracking on a row-scaled
residual norm (rows scaled by max_j |J_ij| scale_j, i.e. in units of the
variables they determine).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from dnasim.errors import PlantError, ResidualDomainError


def color_columns(pattern) -> np.ndarray:
    """Greedy colouring: columns of one colour share no row. Returns colour per column."""
    pat = sp.csc_matrix(pattern)
    patr = sp.csr_matrix(pattern)
    n = pat.shape[1]
    colors = -np.ones(n, dtype=int)
    for j in range(n):
        rows = pat.indices[pat.indptr[j] : pat.indptr[j + 1]]
        forbidden = set()
        for r in rows:
            cols = patr.indices[patr.indptr[r] : patr.indptr[r + 1]]
            forbidden.update(colors[cols][colors[cols] >= 0].tolist())
        c = 0
        while c in forbidden:
            c += 1
        colors[j] = c
    return colors


def fd_jacobian(fun, u, f0, pattern, colors, scale):
    """Sparse finite-difference Jacobian of fun at u with the given pattern and colouring."""
    pat = sp.csc_matrix(pattern)
    n = u.size
    rows_out, cols_out, vals_out = [], [], []
    for c in range(colors.max() + 1 if n else 0):
        cols = np.flatnonzero(colors == c)
        du = np.zeros(n)
        step = 1e-7 * np.maximum(np.abs(u[cols]), scale[cols])
        du[cols] = step
        f1 = fun(u + du)
        df = f1 - f0
        for j, hj in zip(cols, step, strict=False):
            rows = pat.indices[pat.indptr[j] : pat.indptr[j + 1]]
            rows_out.append(rows)
            cols_out.append(np.full(rows.size, j))
            vals_out.append(df[rows] / hj)
    if not rows_out:
        return sp.csc_matrix((f0.size, n))
    return sp.csc_matrix(
        (np.concatenate(vals_out), (np.concatenate(rows_out), np.concatenate(cols_out))),
        shape=(f0.size, n),
    )


def solve_mixed(dae, t0, y, yp, y_unknown, *, tol=1e-10, max_iter=60, what="initial state"):
    """Solve F(t0, y, y') = 0 for y[y_unknown] and y'[~y_unknown]. Returns (y, yp)."""
    y = np.array(y, dtype=float)
    yp = np.array(yp, dtype=float)
    scale = np.where(
        y_unknown, np.maximum(dae.nominal, np.abs(y)), np.maximum(dae.nominal, 1e-3 * np.abs(y))
    )
    ymask = y_unknown.astype(float)[None, :]
    pattern = sp.csc_matrix(dae.pattern_y.multiply(ymask) + dae.pattern_yp.multiply(1.0 - ymask))
    pattern.eliminate_zeros()
    pattern.data[:] = 1.0
    colors = color_columns(pattern)

    def unpack(u):
        yy = y.copy()
        yyp = yp.copy()
        yy[y_unknown] = u[y_unknown]
        yyp[~y_unknown] = u[~y_unknown]
        return yy, yyp

    def fun(u):
        yy, yyp = unpack(u)
        return dae.residual(t0, yy, yyp)

    u = np.where(y_unknown, y, yp)
    try:
        f = fun(u)
    except ResidualDomainError as err:
        raise PlantError(
            f"{what}: the initial guess is outside the model's domain: {err}"
        ) from None
    row_scale = None
    for _ in range(max_iter):
        J = fd_jacobian(fun, u, f, pattern, colors, scale)
        if row_scale is None:
            row_scale = np.asarray(abs(J).multiply(scale[None, :]).max(axis=1).todense()).ravel()
            row_scale[row_scale == 0] = 1.0
        try:
            lu = spla.splu(J.tocsc())
            du = lu.solve(-f)
        except RuntimeError:
            raise PlantError(
                f"{what}: the Jacobian is singular at t = {t0:g}; the plant has no unique "
                f"{'steady state' if np.all(y_unknown | dae.accumulator) else 'consistent state'} "
                "from this guess"
            ) from None
        if not np.all(np.isfinite(du)):
            raise PlantError(f"{what}: Newton step not finite (singular Jacobian)")
        norm0 = np.linalg.norm(f / row_scale)
        if np.max(np.abs(f / row_scale)) < 1e-13:
            # residual at round-off level (in units of the variables it determines)
            return unpack(u)
        lam = 1.0
        while True:
            u_new = u + lam * du
            try:
                f_new = fun(u_new)
                norm1 = np.linalg.norm(f_new / row_scale)
                if norm1 <= (1 - 1e-4 * lam) * norm0 or norm1 < 1e-12:
                    break
            except ResidualDomainError:
                pass
            lam *= 0.5
            if lam < 1e-6:
                raise PlantError(
                    f"{what}: damped Newton cannot reduce the residual (largest: "
                    f"{dae.eq_names[int(np.argmax(np.abs(f / row_scale)))]})"
                )
        u, f = u_new, f_new
        step = np.max(np.abs(lam * du) / scale) if u.size else 0.0
        if step < tol and np.max(np.abs(f / row_scale)) < 1e-8:
            return unpack(u)
    worst = int(np.argmax(np.abs(f / row_scale)))
    raise PlantError(
        f"{what}: Newton did not converge in {max_iter} iterations (largest residual: "
        f"{dae.eq_names[worst]})"
    )
