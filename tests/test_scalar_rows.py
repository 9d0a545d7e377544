"""Components evaluated together in ``ScalarRows`` (their ``row_values`` over
plant-wide index arrays) give the rows of their own ``residual`` (the same
``row_values``, its values looked up by name in the component's ``LocalVector``), to
the bit, so the finite-difference Jacobian of partial evaluations stays the whole
plant's. What these tests check is the gathering (index arrays, rows, modes); the
physics of each ``row_values`` is tested against closed forms and references in the
components' own tests. Each equation is written once (``rows_checked``)."""

from pathlib import Path

import numpy as np
import pytest

from dnasim.model.component import ScalarRows
from dnasim.plant.plantfile import load
from dnasim.start.guess import initial_guess
from dnasim.start.initial import initial_values

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


def assert_batched_equals_by_component(system, y0, yp0):
    """The whole-plant residual (ScalarRows units) equals the per-component residuals
    to the bit at the steady state and the moved points of ``points`` (a moved point
    outside a medium's range is skipped); at least two points compared."""
    compared = 0
    for y, yp in points(system, y0, yp0):
        try:
            expected = by_component(system, 1.0, y, yp)
        except Exception:  # a moved point outside a medium's range: not compared
            continue
        np.testing.assert_array_equal(system.residual(1.0, y, yp), expected)
        compared += 1
    assert compared >= 2  # the steady state and a point moved by 1e-6


@pytest.mark.parametrize("name", ALL)
def test_scalar_rows_equal_the_components_residuals_to_the_bit(name):
    # fails when the unit gathers a value from another place of y or y' than the
    # component's name holds, writes rows into another block's, or passes another
    # mode dict; at the steady state, points moved like Newton iterates, flows reversed
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
    assert_batched_equals_by_component(system, y0, yp0)


def pid_loop(pid):
    """tests/test_pid.py's loop (a first-order lag G under a PIDController), with the
    track input (``tracking``) and the set point signal (``setpoint=None``) linked to
    G's output when asked."""
    from test_pid import loop

    from dnasim.core.timefunctions import Step

    if pid.get("active") == "manual_then_auto":
        pid = dict(pid, active=Step(100.0, 0.0, 1.0))
    setpoint = pid.pop("setpoint", 1.0)
    plant = loop(setpoint, **pid)
    if pid.get("tracking"):
        plant.link("G.y", "pid.track")
    if setpoint is None:
        plant.link("G.y", "pid.set_point")
    return plant


@pytest.mark.parametrize(
    "pid",
    [
        dict(Kp=0.8, T_i=5.0, z_min=0.0, z_max=1.0),  # PI with back-calculation
        dict(Kp=0.8, T_i=5.0, anti_windup=False),  # plain PI
        dict(Kp=0.8),  # P only: m_I a bias
        dict(Kp=0.8, T_i=5.0, active="manual_then_auto", z_manual=0.3),  # bumpless transfer
        dict(Kp=0.8, T_i=5.0, T_d=2.0, N=8.0),  # PID, D on the measurement
        dict(Kp=0.8, T_i=5.0, T_d=2.0, c_d=0.5, setpoint=None),  # weighted D, set point signal
        dict(Kp=0.8, T_i=5.0, tracking=True),  # anti-windup on the actuator position
        dict(Kp=0.8, T_i=5.0, T_d=1.0, tracking=True, active="manual_then_auto"),  # tracks
    ],
)
def test_pid_rows_in_every_configuration_and_mode(pid):
    # every configuration of the PIDController (D part, set point weight, set point
    # signal, tracking, manual/automatic) and every mode (free, high, low) is in the
    # ScalarRows unit; its rows must equal those of the controller's residual (the
    # same row_values, its values looked up by name in the LocalVector, the System's
    # mode dict): fails when the unit gathers a value from another place than the
    # name holds (y' for y, another block's index), writes the rows elsewhere, or
    # reads another mode dict than the one the switch actions change. The physics of
    # row_values itself is tested against closed forms in tests/test_pid.py.
    system = pid_loop(dict(pid)).compile()
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


def sensor_plant():
    """Water through two valves; at the middle node b a flow from a MassFlowBoundary,
    and every node sensor (lagged and not); a mass-flow sensor on v1.m; a
    MassFlowBoundary at c whose flow is the signal of the quality sensor (m_scale
    0.1: the subcooled water's quality is negative, so the tap, a sink only, takes
    water out; with -0.1 it fed the plant, which no state at rest may do)."""
    from dnasim.library import MassFlowBoundary, PressureBoundary, Valve
    from dnasim.library.sensor import (
        EnthalpySensor,
        MassFlowSensor,
        PressureSensor,
        QualitySensor,
        TemperatureSensor,
    )
    from dnasim.plant.plant import Plant

    plant = Plant("sensors", medium="Water")
    plant.add(PressureBoundary("src", p=10e5, T=440.0))
    plant.add(Valve("v1", C=1e-3, opening=0.8))
    plant.add(Valve("v2", C=1e-3, opening=1.0))
    plant.add(PressureBoundary("sink", p=5e5))
    plant.add(MassFlowBoundary("inj", m=0.05, T=350.0))
    plant.add(MassFlowBoundary("tap", m_scale=0.1))
    plant.add(PressureSensor("ps", T_lag=2.0))
    plant.add(EnthalpySensor("hs"))
    plant.add(QualitySensor("qs", T_lag=1.0))
    plant.add(TemperatureSensor("ts", T_lag=0.0))
    plant.add(MassFlowSensor("fs", T_lag=3.0))
    for a, n in [
        ("src.port", "a"),
        ("v1.inlet", "a"),
        ("v1.outlet", "b"),
        ("v2.inlet", "b"),
        ("v2.outlet", "c"),
        ("sink.port", "c"),
        ("inj.port", "b"),
        ("tap.port", "c"),
        ("ps.port", "b"),
        ("hs.port", "b"),
        ("qs.port", "b"),
        ("ts.port", "b"),
    ]:
        plant.connect(a, n)
    plant.link("v1.m", "fs.u")
    plant.link("qs.x", "tap.m_in")
    return plant


def test_sensors_and_flow_boundaries_rows():
    # every sensor class and both boundary classes (supply state given or not, flow
    # from a parameter or from a signal) in one ScalarRows unit: its rows must equal
    # the components' residuals (fails when the unit gathers a value from another
    # place than the LocalVector's name, e.g. a signal input linked to another
    # component's variable, or writes rows elsewhere); then the steady state against
    # the medium's functions, which fails when a row_reads order and its row_values
    # unpacking disagree (e.g. p and h swapped in a node sensor)
    system = sensor_plant().compile()
    kinds = {type(b.comp).__name__ for u in system.residual_units if isinstance(u, ScalarRows)
             for b in u.blocks}  # fmt: skip
    assert {
        "PressureSensor",
        "EnthalpySensor",
        "QualitySensor",
        "TemperatureSensor",
        "MassFlowSensor",
        "MassFlowBoundary",
    } <= kinds
    y0, yp0 = initial_values(system, 0.0, "steady")
    assert_batched_equals_by_component(system, y0, yp0)
    # the steady state the rows give, against the medium's own functions (nobody's
    # equations here): the readings are the node's p, h, T(p, h) and quality, the flow
    # sensor v1's flow, and the tap takes m_scale times the quality (signs: into the
    # plant); to the start's Newton tolerance, 1e-9 relative
    at = system.index
    water = next(b.comp.medium for b in system.blocks if b.comp.name == "ts")
    p, h = y0[at["ps.p_s"]], y0[at["hs.h_s"]]
    hl, hv = (float(a[0]) for a in water.saturation_enthalpies([p]))
    np.testing.assert_allclose(y0[at["ts.T_s"]], water.state(p, h).T, rtol=1e-9)
    np.testing.assert_allclose(y0[at["qs.x_s"]], (h - hl) / (hv - hl), rtol=1e-9)
    np.testing.assert_allclose(y0[at["fs.m_s"]], y0[at["v1.m"]], rtol=1e-9)
    np.testing.assert_allclose(y0[at["tap.m"]], 0.1 * y0[at["qs.x_s"]], rtol=1e-9)
    assert y0[at["tap.m"]] < 0.0  # out of the plant


def linear_valve_plant(cls):
    from dnasim.library import PressureBoundary
    from dnasim.plant.plant import Plant

    plant = Plant("linear", medium="Air")
    plant.add(PressureBoundary("src", p=2e5, T=300.0))
    plant.add(cls("valve", C=1e-5, opening=1.0))
    plant.add(PressureBoundary("sink", p=1e5))
    for a, n in [
        ("src.port", "a"),
        ("valve.inlet", "a"),
        ("valve.outlet", "b"),
        ("sink.port", "b"),
    ]:
        plant.connect(a, n)
    return plant


def test_a_subclass_that_overrides_row_values_has_its_law_on_both_paths():
    # a plugin's subclass of Valve with another flow law, written (once) in its own
    # row_values: the System evaluates it in the ScalarRows unit, Component.residual
    # derives from the same function, so both give its law (fails if either path
    # still used Valve's law)
    from dnasim.library import Valve

    class LinearValve(Valve):
        REGISTER = False

        def row_values(self, t, v, vp, modes):
            m, p_in, p_out = v
            return [m - self.params["C"] * (p_in - p_out)]

    system = linear_valve_plant(LinearValve).compile()
    assert all(isinstance(u, ScalarRows) for u in system.residual_units)
    y, yp = initial_values(system, 0.0, "steady")
    # its own law holds at the steady state: m = C dp = 1e-5 * 1e5 = 1 kg/s (to the
    # start's Newton tolerance, 1e-9 relative)
    assert abs(y[system.index["valve.m"]] - 1.0) < 1e-9
    y1 = y * (1.0 + 1e-3 * np.random.default_rng(3).standard_normal(y.size))
    np.testing.assert_array_equal(system.residual(0.0, y1, yp), by_component(system, 0.0, y1, yp))


def test_an_equation_written_twice_is_refused():
    # a subclass that gives its equations residual functions but inherits row_reads
    # would have two definitions (its functions would be silently ignored): PlantError
    from dnasim.core.errors import PlantError
    from dnasim.library import Valve
    from dnasim.model.component import Equation

    class TwiceValve(Valve):
        REGISTER = False

        def equations(self):
            return [Equation("flow", y=("m", "inlet.p", "outlet.p"), residual=lambda t, x, xp: 0.0)]

    with pytest.raises(PlantError, match="carry residual functions"):
        linear_valve_plant(TwiceValve).compile()

    class OwnValve(TwiceValve):
        # the same equations, without the row path: evaluated alone, by its functions
        REGISTER = False

        def row_reads(self):
            return None

        def equations(self):
            law = lambda t, x, xp: x["m"] - self.params["C"] * (x["inlet.p"] - x["outlet.p"])  # noqa: E731
            return [Equation("flow", y=("m", "inlet.p", "outlet.p"), residual=law)]

    system = linear_valve_plant(OwnValve).compile()
    assert not any(isinstance(u, ScalarRows) and any(b.comp.name == "valve" for b in u.blocks)
                   for u in system.residual_units)  # fmt: skip
    y, yp = initial_values(system, 0.0, "steady")
    assert abs(y[system.index["valve.m"]] - 1.0) < 1e-9  # m = C dp, as above
