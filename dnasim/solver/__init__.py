"""The numerical core: a Nordsieck BDF integrator for index-1 DAEs F(t, y, y') = 0.

It sees a residual, a sparsity pattern, switch functions and, where the caller
gives it, a partial-residual channel (``residual_for_columns``), and nothing else:
it imports nothing from the components, media or networks.

The modules, in the order a step meets them:

- ``api``: ``solve_dae``, the entry point; ``problem``: its input validated;
- ``driver``: steps from t0 to t_end; ``stops`` (tstops), ``crossings`` (switch
  crossings located, logged, acted on), ``output`` (output points, dense output);
- ``bdf``: the Nordsieck BDF stepper, one step at a time; ``controller``: its step
  size and order; ``newton``: its corrector; ``nordsieck``: the array's algebra;
  ``residual``: the counted residual and the counters; ``kernels``: compiled loops;
- ``linear_algebra`` and ``band``: the iteration matrix, its colouring and LU;
- ``initial``: consistent initial values; ``events``: switch functions and root
  location; ``result``: what ``solve_dae`` returns; ``ida``: the SUNDIALS backend.
"""

from dnasim.solver.api import solve_dae
from dnasim.solver.bdf import NordsieckBDF, SolverStats
from dnasim.solver.result import DAEResult

__all__ = ["solve_dae", "DAEResult", "NordsieckBDF", "SolverStats"]
