"""Run a dnasim residual F(t, y, y') through SUNDIALS IDA (scikit-sundae), for cross-checks.

scikit-sundae is a development dependency: it is imported when ``solve_with_ida``
is called, not when dnasim is. The residual is the very same Python function
dnasim integrates, so the comparison measures the integrators alone.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np


@dataclass
class IDARun:
    t: np.ndarray
    y: np.ndarray  # shape (n, m)
    success: bool
    message: str
    stats: dict  # steps, residual_evals, jac_evals, lu_decomps, rejected_error, rejected_newton
    wall_time: float


def solve_with_ida(
    residual,
    t_span,
    y0,
    yp0,
    *,
    algebraic=None,
    rtol=1e-6,
    atol=1e-8,
    t_eval=None,
    sparsity=None,
    max_order=5,
    calc_initial=False,
    max_num_steps=1_000_000,
    first_step=0.0,
) -> IDARun:
    """Integrate F(t, y, yp) = 0 with IDA; return the solution at t_eval (or at t_span[1]).

    With ``sparsity`` the sparse direct solver (SuperLU_MT) is used with
    scikit-sundae's grouped finite-difference Jacobian; otherwise IDA's dense
    difference-quotient Jacobian.
    """
    from sksundae.ida import IDA

    calls = [0]

    def resfn(t, y, yp, res):
        calls[0] += 1
        res[:] = residual(t, y, yp)

    alg_idx = None
    if algebraic is not None:
        a = np.asarray(algebraic)
        alg_idx = list(np.flatnonzero(a)) if a.dtype == bool else [int(i) for i in a]
        if not alg_idx:
            alg_idx = None
    options = dict(
        rtol=rtol,
        atol=atol,
        algebraic_idx=alg_idx,
        max_order=max_order,
        max_num_steps=max_num_steps,
        first_step=first_step,
    )
    if calc_initial:
        options.update(calc_initcond="yp0", calc_init_dt=1e-3 * (t_span[1] - t_span[0]))
    if sparsity is not None:
        options.update(linsolver="sparse", sparsity=sparsity)
    solver = IDA(resfn, **options)
    # With just (t0, t_end) scikit-sundae returns every internal step: the step count.
    times = np.asarray(t_eval if t_eval is not None else [t_span[0], t_span[1]], dtype=float)
    if times[0] != t_span[0]:
        times = np.concatenate([[t_span[0]], times])
    start = time.perf_counter()
    sol = solver.solve(times, np.asarray(y0, float), np.asarray(yp0, float))
    wall = time.perf_counter() - start
    stats = {
        # Every call of the Python residual, the difference-quotient Jacobian's included
        # (IDAGetNumResEvals alone leaves those out), counted the same way as dnasim's.
        "residual_evals": calls[0],
        # Each linear-solver setup evaluates the Jacobian and factorises it once.
        "jac_evals": int(sol.njev),
        "lu_decomps": int(sol.njev),
        "steps": len(sol.t) - 1 if t_eval is None else None,
    }
    return IDARun(
        np.asarray(sol.t), np.asarray(sol.y).T, bool(sol.success), str(sol.message), stats, wall
    )
