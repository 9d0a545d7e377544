"""The output asked for does not change the integration (the property memos).

IF97 water's property memo starts each moved point from the state it remembers, so a
property call's result depends, to round-off, on the calls before it. The output rows
(derived values) and the re-solve of output points between steps used to evaluate
through the same memos as the integration's residual: plants/drum_unit.toml took
different steps with output every 10 s and every 7 s (302.6139 and 302.6105 s for the
first step after the start's rest; 78 and 65 Jacobians over 600 s). Now they evaluate
aside (``physics.aside``: cold, the memos untouched) and every simulation starts with
fresh memos (``physics.forget_memos``).

The check is exact: the same steps, so the same polynomials, so the differential
values at the times both grids share are the same floats (no tolerance: any difference
is a different path). The algebraic values there may be re-solved
(``refine_output``), from a warm start that depends on the other points solved in the
same step, so they agree to the re-solve's convergence, not to the bit; they are not
compared here (tests/test_output_between_steps.py checks their accuracy).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dnasim.compilation.compiler import compile as compile_plant
from dnasim.plant.plantfile import load
from dnasim.run.simulation import simulate, simulation_keywords

ROOT = Path(__file__).resolve().parent.parent


def _run(system, settings, t_end, dt):
    t_end, kw = simulation_keywords(settings, t_end=t_end)
    kw["output_interval"] = dt
    res = simulate(system, t_end=t_end, **kw)
    assert res.success, res.message
    return res


@pytest.mark.parametrize(
    "plant, t_end",
    [("plants/drum_boiler.toml", 400.0), ("plants/rankine.toml", 200.0)],
)
def test_output_interval_does_not_change_the_steps(plant, t_end):
    loaded = load(ROOT / plant)
    system = compile_plant(loaded.plant)
    a = _run(system, loaded.simulation, t_end, 10.0)
    b = _run(system, loaded.simulation, t_end, 7.0)
    for key in ("steps", "rejected_error", "rejected_newton", "jac_evals"):
        assert a.stats[key] == b.stats[key], key
    # differential values at the shared times 0, 70, 140, ... s: the same floats
    diff = ~np.asarray(system.algebraic, dtype=bool)
    ta, tb = np.asarray(a.t), np.asarray(b.t)
    shared = np.intersect1d(ta, tb)
    assert shared.size >= 3
    for t in shared:
        ia, ib = np.flatnonzero(ta == t)[-1], np.flatnonzero(tb == t)[-1]
        assert np.array_equal(a.y[diff, ia], b.y[diff, ib]), t


def test_a_system_simulated_twice_takes_the_same_steps():
    # rankine: the plant whose steps the memos moved (drum_boiler's they did not)
    loaded = load(ROOT / "plants/rankine.toml")
    system = compile_plant(loaded.plant)
    a = _run(system, loaded.simulation, 200.0, 10.0)
    b = _run(system, loaded.simulation, 200.0, 10.0)
    assert a.stats["residual_evals"] == b.stats["residual_evals"]
    assert np.array_equal(a.y, b.y, equal_nan=True)
