"""Consistent initial values for an assembled plant: a thin wrapper of the solver's routine.

Two starts:

* ``"steady"``: solve F(t0, y, 0) = 0 for y, starting from the components'
  initial guesses. Accumulators (running integrals such as the mass that has
  passed a boundary) keep their initial value and their derivative is solved for
  instead.
* ``"given"``: the differential variables keep the values of the initial
  guesses (the components' given initial states: a pipe's T0, a controller's
  integral0, ...); solve F(t0, y, y') = 0 for the algebraic variables and the
  derivatives of the differential ones.

Both are ``solve_mixed``: the unknown vector holds y_i where ``y_unknown[i]``
and y'_i elsewhere. The numerical work (globalised Newton, coloured
finite-difference Jacobian, weights from the current state, messages naming
variables and equations) is ``dnasim.solver.initial.solve_consistent``, the
same routine the integrator uses at its start, tstops and events.

Tolerances: the weights are 1 / (RTOL |y_i| + RTOL nominal_i) with RTOL = 1e-9,
so the iteration stops when the scaled Newton step is below 0.0033 of that:
a few 1e-12 of each variable's scale. Derivatives are measured over a time
scale of 1 s.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from dnasim.core.errors import DAEError, PlantError, ResidualDomainError
from dnasim.solver.initial import solve_consistent
from dnasim.solver.linear_algebra import IterationMatrix

RTOL = 1e-9
H_SCALE = 1.0  # [s]


def iteration_matrix(dae) -> IterationMatrix:
    """The finite-difference Jacobian of ``dae``'s residual on its sparsity (colouring
    and band ordering made here: for a 10000-volume pipe this costs more than the
    Newton iteration, so a caller with several solves makes it once), with ``dae``'s
    partial-residual channel ``residual_for_columns`` where it has one (a System)."""
    pattern = sp.csc_matrix(dae.pattern_y + dae.pattern_yp)
    # the quadratures (y' in one equation, y in none: the accumulators) may trail
    # (``IterationMatrix``): a fixed wall's heat summed over 10000 volumes took 10013
    # residual evaluations and 1.2 GB for the steady start, 45 with it
    in_y = np.diff(sp.csc_matrix(dae.pattern_y).indptr) > 0
    quadrature = (np.diff(sp.csc_matrix(dae.pattern_yp).indptr) == 1) & ~in_y
    return IterationMatrix(
        dae.residual,
        len(dae.names),
        sparsity=pattern,
        names=dae.names,
        equation_names=dae.eq_names,
        residual_for_columns=getattr(dae, "residual_for_columns", None),
        quadrature=quadrature,
    )


def solve_mixed(dae, t0, y, yp, y_unknown, *, max_iter=60, what="initial state", matrix=None):
    """Solve F(t0, y, y') = 0 for y[y_unknown] and y'[~y_unknown]. Returns (y, yp).

    ``dae`` needs ``residual``, ``nominal``, ``pattern_y``, ``pattern_yp``,
    ``names`` and ``eq_names``; ``matrix``: its ``iteration_matrix`` when the caller
    keeps one. Raises PlantError naming variables and equations.
    """
    y = np.array(y, dtype=float)
    yp = np.array(yp, dtype=float)
    y_unknown = np.asarray(y_unknown, dtype=bool)
    if matrix is None:
        matrix = iteration_matrix(dae)
    nominal = np.asarray(dae.nominal, dtype=float)
    try:
        return solve_consistent(
            dae.residual,
            t0,
            y,
            yp,
            y_unknown,
            rtol=RTOL,
            atol=RTOL * nominal,
            h_scale=H_SCALE,
            matrix=matrix,
            variable_names=dae.names,
            equation_names=dae.eq_names,
            max_iters=max_iter,
            what=what,
        )
    except ResidualDomainError as err:  # pragma: no cover - solve_consistent catches these
        raise PlantError(f"{what}: outside the model's domain: {err}") from None
    except DAEError as err:
        out = PlantError(str(err))
        out.state = getattr(err, "state", None)  # (y, yp) where Newton stopped
        raise out from None
