"""Consistent initial values (y0, y'0) of a compiled ``System``.

    y0, yp0 = initial_values(system, t0=0.0, start="steady")

start="steady": F(t0, y, 0) = 0 for the accumulators' derivatives too (every
storage at rest); start="given": the components' given initial states
(differential variables fixed), the algebraic variables and y' solved. The
starting point is ``initial_guess``; the Newton iteration is
``dnasim.initialization.solve_mixed``. The discrete modes (``System.modes``) are
reset first and chosen to fit the initial values (at most 3 passes).
"""

from __future__ import annotations

import numpy as np

from dnasim.errors import PlantError

__all__ = ["initial_values", "reinitialise"]


def initial_values(system, t0: float = 0.0, start: str = "steady"):
    """(y0, yp0) consistent at t0; raises ``DAEError`` when Newton fails."""
    from dnasim.initial_guess import initial_guess
    from dnasim.initialization import solve_mixed

    if start not in ("steady", "given"):
        raise PlantError(f"start must be 'steady' or 'given', got {start!r}")
    system.reset_modes()
    y = initial_guess(system, t0)
    yp = np.zeros(system.n)
    unknown = ~system.accumulator if start == "steady" else system.algebraic.copy()
    for _ in range(3):
        y, yp = solve_mixed(
            system, t0, y, yp, unknown, what=f"{start} start of plant '{system.name}'"
        )
        changed = False
        for b in system.blocks:
            changed |= bool(b.comp.init_discrete_state(t0, b.local(y), b.local(yp)))
        if not changed:
            break
    return y, yp


def reinitialise(system, t: float, y, yp):
    """Consistent (y, yp) after a jump at t, the differential variables kept (the
    algebraic ones and y' solved): the restart of a backend without its own."""
    from dnasim.initialization import solve_mixed

    return solve_mixed(system, t, y, yp, system.algebraic.copy(), what="restart")
