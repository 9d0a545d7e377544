"""The numerical core: a Nordsieck BDF integrator for index-1 DAEs F(t, y, y') = 0.

It sees a residual, a sparsity pattern and switch functions, and nothing else:
it imports nothing from the components, media or networks.
"""

from dnasim.solver.api import solve_dae
from dnasim.solver.bdf import NordsieckBDF, SolverStats
from dnasim.solver.result import DAEResult

__all__ = ["solve_dae", "DAEResult", "NordsieckBDF", "SolverStats"]
