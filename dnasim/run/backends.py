"""Solver backends: objects that integrate a ``Problem`` (F(t, y, y') = 0 and nothing
of the plant) and return a DAEResult-like record.

    NordsieckBDF(rtol=1e-6, atol_scaled=1e-6, max_order=4, ...)   # dnasim.solve_dae
    IDA(rtol=1e-6, atol_scaled=1e-6, ...)                          # SUNDIALS, scikit-sundae

Contract: ``backend.name`` (str), ``backend.rtol``, ``backend.atol_scaled`` and
``backend.solve(problem)`` returning an object with t, y, yp, success, status,
message, event_log, stats, step_history, sol. A failure is returned (success
False), not raised. ``dnasim.run.simulation.simulate`` turns it into ``Results``.

Tolerances (one meaning everywhere above ``solve_dae``): ``rtol`` relative,
``atol_scaled`` per unit of each variable's scale, atol_i = atol_scaled *
max(nominal_i, |y0_i|) (``System.atol_vector``); ``Problem.atol`` is that
vector. Defaults rtol = 1e-6, atol_scaled = 1e-6.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from dnasim.core.errors import DAEError

__all__ = ["ATOL_SCALED", "IDA", "NordsieckBDF", "Problem", "RTOL", "SOLVER_OPTIONS"]

RTOL = 1e-6  # default relative tolerance
ATOL_SCALED = 1e-6  # default absolute tolerance per unit of each variable's scale
#: the keywords of simulate() that configure the default backend
SOLVER_OPTIONS = ("rtol", "atol_scaled", "max_order", "max_step", "max_steps", "h0")


@dataclass
class Problem:
    """What a solver backend sees: F(t, y, y') = 0 and nothing of the plant."""

    residual: object
    t_span: tuple[float, float]
    y0: np.ndarray
    yp0: np.ndarray
    algebraic: np.ndarray
    jac_sparsity: object
    events: list
    tstops: list
    atol: np.ndarray  # absolute tolerance per variable
    variable_names: list
    equation_names: list = None
    t_eval: object = None
    #: output every output_interval [s] (generated as the solver goes), else t_eval
    output_interval: float | None = None
    callback: object = None
    #: reinitialise(t, y, yp) -> (y, yp): consistent values after a jump, the
    #: differential variables kept (for backends that restart by themselves, IDA)
    reinitialise: object = None
    #: mask of the quadratures (running integrals read by no equation,
    #: ``System.quadrature``): out of the error test and Newton's norm; None: none
    quadrature: np.ndarray | None = None
    #: the partial-residual channel, residual_for_columns(cols) -> F_cols(t, y, yp, f0)
    #: (``System.residual_for_columns``; ``solve_dae``'s keyword); None: none
    residual_for_columns: object = None
    #: (residual, residual_for_columns) for the re-solve of output points between
    #: steps, leaving the integration's path alone (``System.residual_aside``,
    #: ``solve_dae``'s ``output_residual``); None: the residual itself
    output_residual: object = None


@dataclass
class NordsieckBDF:
    """dnasim's own solver (``dnasim.solve_dae``): Nordsieck BDF orders 1..5 with
    Milne's error estimate, modified Newton, switch location and restarts.

    ``exclude_algebraic_from_error`` (default True for plants, as in ``dnasim run``):
    the algebraic variables (flows, pressures, node enthalpies) are left out of the
    error test, DASPK's advice for index-1 problems; their error follows from the
    differential states'. A liquid volume's pressure-flow mode has a time constant
    of about 1e-10 s, which no useful step could otherwise pass after a restart."""

    rtol: float = RTOL
    atol_scaled: float = ATOL_SCALED
    max_order: int = 4
    max_step: float = math.inf
    h0: float | None = None
    max_steps: int = 500_000
    exclude_algebraic_from_error: bool = True
    dense_output: bool = True
    #: solve the algebraic variables at output points between steps (``solve_dae``'s
    #: ``refine_output``), each value then kept solved or interpolated by their
    #: estimated errors (``driver.Driver._choose``: the re-solve alone amplified the
    #: interpolated states' error through the water's stiffness in a liquid line at
    #: rest, tests/plants/pump_shutoff.toml: -4.7e-3 kg/s through a shut pump whose flow
    #: is 1.4e-5 kg/s)
    refine_output: bool = True
    #: False: the rows go to the callback only (a solve_dae with ``keep_output``)
    keep_output: bool = True
    name: str = field(default="NordsieckBDF", init=False)

    def solve(self, pb: Problem):
        from dnasim.solver import solve_dae

        try:
            return solve_dae(
                pb.residual,
                pb.t_span,
                pb.y0,
                pb.yp0,
                algebraic=pb.algebraic,
                quadrature=pb.quadrature,
                jac_sparsity=pb.jac_sparsity,
                residual_for_columns=pb.residual_for_columns,
                output_residual=pb.output_residual,
                calc_initial=False,
                variable_names=pb.variable_names,
                equation_names=pb.equation_names,
                output_interval=pb.output_interval,
                rtol=self.rtol,
                atol=pb.atol,
                max_order=self.max_order,
                max_step=self.max_step,
                h0=self.h0,
                events=pb.events,
                tstops=pb.tstops,
                t_eval=pb.t_eval,
                callback=pb.callback,
                exclude_algebraic_from_error=self.exclude_algebraic_from_error,
                dense_output=self.dense_output,
                max_steps=self.max_steps,
                keep_output=self.keep_output,
                refine_output=self.refine_output,
                throw=True,
            )
        except DAEError as err:
            res = getattr(err, "result", None)
            if res is None:
                raise
            return res


@dataclass
class IDA:
    """SUNDIALS IDA through scikit-sundae (optional dependency), with the plant's
    semantics: it stops at every tstop and switch crossing, runs the switch's
    action and re-initialises by dnasim's damped Newton. It honours the problem's
    output times (``t_eval``, ``output_interval``: IDA's own interpolation between its
    steps, both sides of every restart) as ``NordsieckBDF`` does
    (``dnasim.solver.ida.solve_ida``)."""

    rtol: float = RTOL
    atol_scaled: float = ATOL_SCALED
    max_order: int = 4
    max_step: float = math.inf
    h0: float | None = None
    max_steps: int = 100_000
    name: str = field(default="IDA", init=False)

    def solve(self, pb: Problem):
        from dnasim.solver.ida import solve_ida

        return solve_ida(
            pb.residual,
            pb.t_span,
            pb.y0,
            pb.yp0,
            algebraic=pb.algebraic,
            reinitialise=pb.reinitialise,
            jac_sparsity=pb.jac_sparsity,
            rtol=self.rtol,
            atol=pb.atol,
            max_order=self.max_order,
            max_step=self.max_step,
            h0=self.h0,
            events=pb.events,
            tstops=pb.tstops,
            t_eval=pb.t_eval,
            output_interval=pb.output_interval,
            callback=pb.callback,
            max_num_steps=self.max_steps,
        )
