"""Consistent initial values (y0, y'0) of a compiled ``System``.

    y0, yp0 = initial_values(system, t0=0.0, start="steady")

start="steady": the plant at rest, F(t0, y, 0) = 0 (the accumulators' derivatives
solved), found by ``dnasim.start.steady_state.find_steady_state`` (Newton from the guess,
pseudo-transient continuation, the controllers' limits chosen at rest, the
components' ranges checked); start="given": the components' given initial states
(differential variables fixed), the algebraic variables and y' solved from
``initial_guess`` (its march of the enthalpies along the flow first, then the node
pressures copied or interpolated: they differ only where a node has no storage
next to it) by ``dnasim.start.consistent.solve_mixed``, the discrete modes
(``System.modes``) reset first and chosen to fit the initial values (at most 3
passes).
"""

from __future__ import annotations

import numpy as np

from dnasim.core.errors import PlantError

__all__ = ["initial_values", "reinitialise"]


def initial_values(system, t0: float = 0.0, start: str = "steady"):
    """(y0, yp0) consistent at t0; raises ``PlantError`` (a ``SteadyStateError`` for the
    steady start) when none is found."""
    if start not in ("steady", "given"):
        raise PlantError(f"start must be 'steady' or 'given', got {start!r}")
    if start == "steady":
        from dnasim.start.steady_state import find_steady_state

        rest = find_steady_state(system, t0)
        return rest.y, rest.yp
    from dnasim.start.consistent import solve_mixed
    from dnasim.start.guess import initial_guess

    what = f"given start of plant '{system.name}'"
    first = None
    # the march first (node enthalpies along the flow: a feed line downstream of its
    # pump starts with the pump's water, not with the drum's, from which its Newton
    # found a steam-bound state with no feed flow); then the guesses of the steady
    # start's first stage, which differ in the node pressures only (a chain of valves
    # with no volume between them, tests/plants/valve_chain_check.toml)
    for kw in ({"march": True}, {}, {"interpolate": True}):
        system.reset_modes()
        y = initial_guess(system, t0, **kw)
        yp = np.zeros(system.n)
        try:
            for _ in range(3):
                y, yp = solve_mixed(system, t0, y, yp, system.algebraic.copy(), what=what)
                changed = False
                for b in system.blocks:
                    if b.comp.init_discrete_state(t0, b.local(y), b.local(yp)):
                        changed = True
                if not changed:
                    break
            return y, yp
        except PlantError as err:
            first = first or err
    raise first


def reinitialise(system, t: float, y, yp):
    """Consistent (y, yp) after a jump at t, the differential variables kept (the
    algebraic ones and y' solved): the restart of a backend without its own."""
    from dnasim.start.consistent import solve_mixed

    return solve_mixed(system, t, y, yp, system.algebraic.copy(), what="restart")
