"""Output rows with the pipes batched (``PipeBatch.output_values``) are the rows of the
components' own ``output_values``, to the bit."""

from pathlib import Path

import numpy as np
import pytest

from dnasim.compilation.system import ComponentBlock
from dnasim.library import MassFlowBoundary, Pipe, PressureBoundary, Valve
from dnasim.model.physics import aside
from dnasim.plant.plant import Plant
from dnasim.plant.plantfile import load
from dnasim.start.initial import initial_values

PLANTS = Path(__file__).resolve().parent.parent / "plants"


def row_by_component(system, t, y, yp):
    """The row as the System made it before the batches: y, the node temperatures,
    then each block's own ``output_values``, in block order; their property calls
    aside from the memos, as ``System.output_row`` makes them (``physics.aside``)."""
    with aside():
        return _row_by_component(system, t, y, yp)


def _row_by_component(system, t, y, yp):
    y = np.asarray(y, dtype=float)
    node_T = np.full(len(system.node_names), np.nan)
    for medium, pos, kp in system._node_groups():
        r = medium.states(y[kp], y[kp + 1], check=False)
        node_T[pos] = np.where(r.ok, r.T, np.nan)
    parts = [y, node_T]
    for b in system.blocks:
        if b.comp.outputs():
            parts.append(np.asarray(b.comp.output_values(t, b.local(y), b.local(yp)), float))
    return np.concatenate(parts)


def mixed_pipes():
    """Air through pipes of 1, 3 and 3 volumes (a fixed wall, a storage wall, none)
    and a valve: two volume counts and three wall kinds in one batch."""
    plant = Plant("pipes", medium="Air")
    plant.add(MassFlowBoundary("src", m=0.1, T=600.0, m_nominal=0.1))
    plant.add(Pipe("a", V=0.02, kA=50.0, k=1e5, T_wall=300.0, n_volumes=1, m_nominal=0.1))
    plant.add(Pipe("b", V=0.03, kA=80.0, k=1e5, C_wall=5e3, n_volumes=3, m_nominal=0.1))
    plant.add(Pipe("c", V=0.03, k=1e5, n_volumes=3, m_nominal=0.1))
    plant.add(Valve("valve", C=3.2e-4, opening=1.0, m_nominal=0.1))
    plant.add(PressureBoundary("sink", p=1e5, m_nominal=0.1))
    for a, n in [
        ("src.port", "n0"),
        ("a.inlet", "n0"),
        ("a.outlet", "n1"),
        ("b.inlet", "n1"),
        ("b.outlet", "n2"),
        ("c.inlet", "n2"),
        ("c.outlet", "n3"),
        ("valve.inlet", "n3"),
        ("valve.outlet", "n4"),
        ("sink.port", "n4"),
    ]:
        plant.connect(a, n)
    return plant.compile()


@pytest.mark.parametrize("which", ["superheater_line", "attemperator", "mixed_pipes"])
def test_batched_output_rows_equal_the_components_rows_to_the_bit(which):
    if which == "mixed_pipes":
        system = mixed_pipes()
    else:
        system = load(PLANTS / f"{which}.toml").plant.compile()
    assert any(type(u) is not ComponentBlock for u, _ in system._make_output_plan()[0])
    y0, yp0 = initial_values(system, 0.0, "steady")
    rng = np.random.default_rng(7)
    for k in range(4):
        # steady, then states moved as an output point between steps moves them, with
        # flows in the upwind band too (|m| < m_eps: the tail and the polynomial)
        y = y0 * (1.0 + (1e-4 * k) * rng.standard_normal(y0.size))
        if k == 3:
            y[[i for i, nm in enumerate(system.names) if ".m[" in nm]] = 1e-7
        yp = yp0 + 1e-3 * rng.standard_normal(y0.size)
        expected = row_by_component(system, 10.0, y, yp)
        row = system.output_row(10.0, y, yp)
        assert len(row) == len(system.output_names())
        np.testing.assert_array_equal(row, expected)
