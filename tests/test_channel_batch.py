"""Pipes evaluated together (``PipeBatch``, ``dnasim.compilation.system.evaluation_units``) against
each pipe's own residual (``Pipe.residual``), to the bit.

A batch evaluates the channel equations of several pipes as one set of arrays, with
index arrays instead of slices and the per-pipe constants as arrays; each element goes
through the same floating-point operations as in its own pipe's evaluation, so the two
must agree exactly, not to a tolerance. The plant mixes what a batch must keep apart
per pipe: different numbers of volumes, volumes, friction and heat-transfer
coefficients, fixed and stored walls, and IF97 phase modes (a forced branch per
volume).
"""

import numpy as np

from dnasim.compilation.compiler import compile as compile_plant
from dnasim.compilation.system import evaluation_units
from dnasim.plant.plantfile import loads
from dnasim.solver.linear_algebra import SQRT_EPS, IterationMatrix
from dnasim.start.initial import initial_values

PLANT = """
[plant]
name = "three_tubes"
medium = "Water"

[simulation]
t_end = "10 s"

[components.feed]
type = "MassFlowBoundary"
m = "1 kg/s"
T = "250 degC"
m_nominal = "1 kg/s"
ports = { port = "n_in" }

[components.tube1]
type = "Pipe"
V = "20 L"
kA = "20 kW/K"
k = 1e6
T_wall = "300 degC"
n_volumes = 3
m_nominal = "1 kg/s"
ports = { inlet = "n_in", outlet = "n_1" }

[components.tube2]
type = "Pipe"
V = "30 L"
kA = "15 kW/K"
C_wall = "50 kJ/K"
k = 2e6
n_volumes = 2
m_nominal = "1 kg/s"
ports = { inlet = "n_1", outlet = "n_2" }

[components.tube3]
type = "Pipe"
V = "10 L"
kA = "30 kW/K"
k = 5e5
T_wall = "320 degC"
n_volumes = 4
m_nominal = "1 kg/s"
ports = { inlet = "n_2", outlet = "n_3" }

[components.valve]
type = "Valve"
C = "0.0032 kg/(s.Pa0.5)"
opening = 1
m_nominal = "1 kg/s"
ports = { inlet = "n_3", outlet = "n_exit" }

[components.header]
type = "PressureBoundary"
p = "58 bar"
m_nominal = "1 kg/s"
ports = { port = "n_exit" }
"""


def _systems():
    """(batched, one pipe at a time): two compilations of two loads of the plant, so
    that no property memo is shared, both started steady."""
    batched = compile_plant(loads(PLANT).plant)
    alone = compile_plant(loads(PLANT).plant)
    alone.residual_units = list(alone.blocks)
    starts = [initial_values(s, 0.0, "steady") for s in (batched, alone)]
    return batched, alone, starts


def test_batched_pipes_give_their_own_residuals_to_the_bit():
    batched, alone, ((y0, yp0), (y0b, yp0b)) = _systems()
    assert [type(u).__name__ for u in batched.residual_units].count("PipeBatch") == 1
    assert any(u.comp.channel.phase_modes for u in batched.blocks if hasattr(u.comp, "channel"))
    # the same start: every residual of the steady solve was the same
    assert np.array_equal(y0, y0b) and np.array_equal(yp0, yp0b)
    rng = np.random.default_rng(11)
    scale = np.maximum(batched.nominal, np.abs(y0))
    for rel in (1e-9, 1e-6, 1e-4, 1e-6, 0.0):  # Newton-like and predictor-like moves
        y = y0 + rel * scale * rng.standard_normal(y0.size)
        yp = yp0 + rel * scale * rng.standard_normal(y0.size)
        np.testing.assert_array_equal(batched.residual(1.0, y, yp), alone.residual(1.0, y, yp))


def test_batched_partial_jacobian_equals_whole_evaluations_of_each_pipe():
    """The FD Jacobian with column groups evaluated in part (sub-batches of the pipes a
    group touches) equals the one from whole evaluations one pipe at a time."""
    batched, alone, ((y0, yp0), _) = _systems()
    rng = np.random.default_rng(3)
    scale = np.maximum(batched.nominal, np.abs(y0))
    y = y0 + 1e-6 * scale * rng.standard_normal(y0.size)
    yp = yp0 + 1e-3 * scale * rng.standard_normal(y0.size)
    inc = (y + np.maximum(SQRT_EPS * np.abs(y), 1e-3)) - y
    matrices = []
    for system, partial in ((batched, True), (alone, False)):
        m = IterationMatrix(
            system.residual,
            system.n,
            sparsity=system.jac_sparsity,
            residual_for_columns=system.residual_for_columns,
        )
        if not partial:
            m._group_residuals = [None] * len(m.groups)
        f0 = system.residual(0.0, y, yp)
        matrices.append(m.finite_difference(0.0, y, yp, f0, inc, 1.0, 37.0))
    partial, whole = matrices
    # some column groups touch only some of the pipes: sub-batches were evaluated
    sub = [
        len(u.names)
        for cols in IterationMatrix(
            batched.residual,
            batched.n,
            sparsity=batched.jac_sparsity,
            residual_for_columns=batched.residual_for_columns,
        ).groups
        for u in evaluation_units([b for b in batched.blocks if np.isin(b.gidx, cols).any()])
        if hasattr(u, "names")
    ]
    assert min(sub) < 3 == max(sub)
    assert np.array_equal(partial.indices, whole.indices)
    assert np.array_equal(partial.data, whole.data)
    assert np.count_nonzero(whole.data) > whole.nnz // 2  # a matrix, not zeros
