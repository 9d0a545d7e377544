"""Components evaluated together in ``ScalarRows`` (their ``row_values`` over
plant-wide index arrays) give the rows of their own ``residual``, to the bit, so the
finite-difference Jacobian of partial evaluations stays the whole plant's."""

from pathlib import Path

import numpy as np
import pytest

from dnasim.components.base import ScalarRows
from dnasim.initial_guess import initial_guess
from dnasim.plantfile import load
from dnasim.start import initial_values

PLANTS = Path(__file__).resolve().parent.parent / "plants"
ALL = sorted(p.stem for p in PLANTS.glob("*.toml"))


def by_component(system, t, y, yp):
    """F with every component alone (``Component.residual`` on its ``LocalVector``)."""
    F = np.empty(system.n_equations)
    system._component_rows(t, y, yp, F, system.blocks)
    system._node_rows(y, F)
    return F


def points(system, y0, yp0):
    """The steady state, then points moved as Newton iterates move them, with flows in
    the upwind band (|m| < m_eps) and reversed."""
    rng = np.random.default_rng(11)
    yield y0, yp0
    for scale in (1e-6, 1e-3):
        yield (
            y0 * (1.0 + scale * rng.standard_normal(y0.size)),
            yp0 + scale * rng.standard_normal(y0.size),
        )
    flows = [i for i, nm in enumerate(system.names) if nm.split(".")[-1].startswith("m")]
    y = y0.copy()
    y[flows] = rng.uniform(-1e-4, 1e-4, len(flows)) * np.where(rng.random(len(flows)) < 0.5, 1, -1)
    yield y, yp0


@pytest.mark.parametrize("name", ALL)
def test_scalar_rows_equal_the_components_residuals_to_the_bit(name):
    system = load(PLANTS / f"{name}.toml").plant.compile()
    batched = [u for u in system.residual_units if isinstance(u, ScalarRows)]
    if name in ("superheater_line", "attemperator"):
        # boundaries, valves, sensors, controllers and attemperators take part
        kinds = {type(b.comp).__name__ for u in batched for b in u.blocks}
        assert {"PressureBoundary", "Valve", "TemperatureSensor"} <= kinds
        assert "Attemperator" in kinds
        assert ("PIDController" if name == "attemperator" else "PIController") in kinds
    try:
        y0, yp0 = initial_values(system, 0.0, "steady")
    except Exception:  # a plant without a steady state: its guess
        y0, yp0 = initial_guess(system, 0.0), np.zeros(system.n)
    compared = 0
    for y, yp in points(system, y0, yp0):
        for t in (0.0, 400.0):
            try:
                expected = by_component(system, t, y, yp)
            except Exception:  # a moved point outside a medium's range: not compared
                continue
            np.testing.assert_array_equal(system.residual(t, y, yp), expected)
            compared += 1
    assert compared >= 4  # the steady state and a point moved by 1e-6, at both times


def test_partial_evaluations_of_scalar_rows_equal_the_whole_plant():
    # the Jacobian's column groups evaluate the components they touch as a subset
    # (``residual_for_columns``): a ScalarRows of that subset must give the rows the
    # whole plant's gives (rows reading none of the columns come from f0)
    system = load(PLANTS / "superheater_line.toml").plant.compile()
    y, yp = initial_values(system, 0.0, "steady")
    f0 = system.residual(0.0, y, yp)
    rng = np.random.default_rng(5)
    for _ in range(10):
        cols = rng.choice(system.n, size=4, replace=False)
        y1, yp1 = y.copy(), yp.copy()
        y1[cols] *= 1.0 + 1e-7
        yp1[cols] += 1e-7
        whole = system.residual(0.0, y1, yp1)
        partial = system.residual_for_columns(cols)(0.0, y1, yp1, f0)
        rows = np.flatnonzero(np.asarray(system.jac_sparsity[:, cols].sum(axis=1)).ravel())
        np.testing.assert_array_equal(partial[rows], whole[rows])


def test_scalar_rows_of_a_split_and_remixed_stream():
    # Splitter and Mixer (signed flows into the junction, numpy mixing) and valves of
    # fixed opening, in tests/test_plant_sparsity.py's heat exchanger plant
    from test_plant_sparsity import hx_plant

    system = hx_plant().compile()
    kinds = {type(b.comp).__name__ for u in system.residual_units if isinstance(u, ScalarRows)
             for b in u.blocks}  # fmt: skip
    assert {"Splitter", "Mixer", "Valve", "TemperatureSensor"} <= kinds
    y0, yp0 = initial_values(system, 0.0, "steady")
    compared = 0
    for y, yp in points(system, y0, yp0):
        try:
            expected = by_component(system, 1.0, y, yp)
        except Exception:  # a moved point outside a medium's range: not compared
            continue
        np.testing.assert_array_equal(system.residual(1.0, y, yp), expected)
        compared += 1
    assert compared >= 2  # the steady state and a point moved by 1e-6


@pytest.mark.parametrize(
    "pid",
    [
        dict(Kp=0.8, T_i=5.0, z_min=0.0, z_max=1.0),  # PI with back-calculation
        dict(Kp=0.8, T_i=5.0, anti_windup=False),  # plain PI
        dict(Kp=0.8),  # P only: m_I a bias
        dict(Kp=0.8, T_i=5.0, active="manual_then_auto", z_manual=0.3),  # bumpless transfer
    ],
)
def test_pid_rows_in_every_mode(pid):
    # the PIDController's rows without a D part, in automatic and manual, free and
    # saturated high and low: the rows of its own residual, to the bit
    from test_pid import loop

    from dnasim.timefunctions import Step

    if pid.get("active") == "manual_then_auto":
        pid = dict(pid, active=Step(100.0, 0.0, 1.0))
    system = loop(1.0, **pid).compile()
    assert any(
        isinstance(u, ScalarRows) and any(b.comp.name == "pid" for b in u.blocks)
        for u in system.residual_units
    )
    y0, yp0 = initial_values(system, 0.0, "steady")
    modes = system.modes["pid"]
    for mode in ("free", "high", "low"):
        modes["mode"] = mode
        for y, yp in points(system, y0, yp0):
            for t in (0.0, 150.0):  # manual before 100 s with active given
                expected = by_component(system, t, y, yp)
                np.testing.assert_array_equal(system.residual(t, y, yp), expected)


def test_a_subclass_elsewhere_is_evaluated_by_its_own_residual():
    # a plugin's subclass of Valve that changes the flow law must not be evaluated by
    # Valve.row_values (which restates Valve's law): it stays a ComponentBlock
    from dnasim.components import PressureBoundary, Valve
    from dnasim.plant import Plant
    from dnasim.system import ComponentBlock

    class LinearValve(Valve):
        REGISTER = False

        def _flow(self, t, x, xp):
            return x["m"] - self.params["C"] * (x["inlet.p"] - x["outlet.p"])

    plant = Plant("linear", medium="Air")
    plant.add(PressureBoundary("src", p=2e5, T=300.0))
    plant.add(LinearValve("valve", C=1e-5, opening=1.0))
    plant.add(PressureBoundary("sink", p=1e5))
    for a, n in [
        ("src.port", "a"),
        ("valve.inlet", "a"),
        ("valve.outlet", "b"),
        ("sink.port", "b"),
    ]:
        plant.connect(a, n)
    system = plant.compile()
    units = {
        b.comp.name: type(u)
        for u in system.residual_units
        for b in (u.blocks if isinstance(u, ScalarRows) else [u])
    }
    assert units == {"src": ScalarRows, "valve": ComponentBlock, "sink": ScalarRows}
    y, yp = initial_values(system, 0.0, "steady")
    # its own law holds at the steady state: m = C dp = 1e-5 * 1e5 = 1 kg/s (to the
    # start's Newton tolerance, 1e-9 relative)
    assert abs(y[system.index["valve.m"]] - 1.0) < 1e-9
