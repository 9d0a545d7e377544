"""The bound on the node enthalpy the components read (issue 20 item 9,
``System._bounded_node_h``): a node's mixed enthalpy solves a weighted mean of the
enthalpies its ports deliver, so the components are given it within their range
(widened by HULL_MARGIN_REL); a Newton iterate or a prediction outside it (13.9 MJ/kg
at the outlet of tests/field/closed_feed_line_boiling.toml, beyond IF97) no longer makes
the residual fail, and a state inside the range is evaluated unchanged.
"""

from __future__ import annotations

import numpy as np
import pytest

from dnasim.compilation.system import HULL_MARGIN_REL
from dnasim.core.errors import ResidualDomainError
from dnasim.library import Pipe, PressureBoundary, Valve
from dnasim.plant.plant import Plant
from dnasim.start.initial import initial_values


def water_line():
    """supply 60 bar --> pipe a --> node j --> pipe b --> valve --> sink 50 bar."""
    plant = Plant("line", medium="Water")
    plant.add(PressureBoundary("src", p=60e5, T=473.15))
    plant.add(Pipe("a", V=0.05, k=1e7, n_volumes=2, m_nominal=2.0))
    plant.add(Pipe("b", V=0.05, k=1e7, n_volumes=2, m_nominal=2.0))
    plant.add(Valve("v", C=0.01, opening=1.0, m_nominal=2.0))
    plant.add(PressureBoundary("snk", p=50e5, T=533.15))
    wires = [
        ("src.port", "in"),
        ("a.inlet", "in"),
        ("a.outlet", "j"),
        ("b.inlet", "j"),
        ("b.outlet", "o"),
        ("v.inlet", "o"),
        ("v.outlet", "e"),
        ("snk.port", "e"),
    ]
    for port, node in wires:
        plant.connect(port, node)
    return plant


@pytest.fixture(scope="module")
def line():
    dae = water_line().compile()
    y, _ = initial_values(dae, 0.0, "steady")
    ix = dae.index
    # steam in a's last volume, water in b's first: the range at j is [h_b, h_a]
    y[ix["a.h_v[1]"]] = 2.9e6
    y[ix["b.h_v[0]"]] = 1.1e6
    return dae, y


def _rows(dae, F):
    """The component rows (everything but the node equations)."""
    return F[: dae.node_eq_start]


def test_inside_the_range_the_components_read_the_node_enthalpy_itself(line):
    dae, y0 = line
    yp = np.zeros_like(y0)
    k = dae.index["j.h"]
    y = y0.copy()
    F = {}
    for h in (1.5e6, 2.5e6):
        y[k] = h
        F[h] = dae.residual(0.0, y, yp)
    # a node enthalpy inside the range is what pipe b's inflow reads: its rows move
    assert not np.array_equal(_rows(dae, F[1.5e6]), _rows(dae, F[2.5e6]))
    # and the bound returns y itself, unchanged (no copy, no change of any bit)
    assert dae._bounded_node_h(y) is y


def test_an_iterate_beyond_the_medium_is_evaluated_at_the_bound(line):
    dae, y0 = line
    yp = np.zeros_like(y0)
    k = dae.index["j.h"]
    hi = 2.9e6 + HULL_MARGIN_REL * ((2.9e6 - 1.1e6) + 2.9e6)
    y = y0.copy()
    y[k] = 1.39e7  # beyond IF97 (T > 2273 K at 60 bar): no component could evaluate it
    F_far = dae.residual(0.0, y, yp)  # must not raise
    assert np.isfinite(F_far).all()
    y_hi = y0.copy()
    y_hi[k] = hi
    F_hi = dae.residual(0.0, y_hi, yp)
    # the components see the bound: their rows are those at h = hi, to the bit
    assert np.array_equal(_rows(dae, F_far), _rows(dae, F_hi))
    # the node's own mixing equation reads the iterate itself: sum_k w_k (h_k - h) is
    # linear in h with slope -sum_k w_k < 0, so it still drives Newton back
    row = dae.eq_names.index("j.mixing")
    assert F_far[row] < F_hi[row]
    # below the range likewise (a negative enthalpy is outside IF97 too)
    y[k] = -5e6
    assert np.isfinite(dae.residual(0.0, y, yp)).all()


def test_without_the_bound_such_an_iterate_fails(line, monkeypatch):
    # the check above can fail: with the bound switched off the same iterate is outside
    # the medium's range and the residual raises
    dae, y0 = line
    monkeypatch.setattr(type(dae), "_bounded_node_h", lambda self, y: y)
    y = y0.copy()
    y[dae.index["j.h"]] = 1.39e7
    with pytest.raises(ResidualDomainError):
        dae.residual(0.0, y, np.zeros_like(y))
