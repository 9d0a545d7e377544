"""The seed's air pipe example (10.2.2) and the plant's Python API."""

import numpy as np
import pytest

from dnasim.core.timefunctions import Constant, Ramp, Sine, Step, Table, as_time_function
from dnasim.library import REGISTRY, Pipe
from dnasim.plant.examples import air_pipe_plant
from dnasim.run.simulation import simulate


@pytest.fixture(scope="module")
def air():
    return air_pipe_plant(1).simulate(4000.0, start="given", rtol=1e-6)


def test_air_pipe_heats_and_approaches_inlet(air):
    assert air.success
    T_out, T_w = air["pipe1.T_out"], air["pipe1.T_w[0]"]
    assert T_out[0] == pytest.approx(300.0, abs=1e-6)
    assert np.all(np.diff(T_w) > -1e-9)  # the wall only heats
    # after ~5 wall time constants the outlet is within 2 K of the 600 K inlet
    assert 598.0 < T_out[-1] < 600.0
    assert T_w[-1] > 595.0
    # the air in the pipe gets lighter as it heats (Fig. 10.2)
    assert air["pipe1.M_total"][-1] < 0.55 * air["pipe1.M_total"][0]
    # mass and energy balance (running integrals at the boundaries, see
    # test_plant_conservation for the reasoning): rtol of the throughput
    dM = air["pipe1.M_total"] - air["pipe1.M_total"][0]
    assert (
        np.max(np.abs(dM - (air["source.M_passed"] + air["exhaust.M_passed"])))
        < 1e-6 * air["source.M_passed"][-1]
    )


def test_air_pipe_step_size_grows_towards_steady_state(air):
    h = air.steps[:, 1]
    n = h.size
    # Fig. 10.3: the step size grows as the solution settles
    assert np.median(h[-n // 5 :]) > 100 * np.median(h[: n // 5])
    assert h[-2] > 10.0


def test_results_are_named_with_units(air):
    assert air.units["pipe1.T_out"] == "K"
    assert air.units["inlet.p"] == "Pa"
    assert air.units["pipe1.M[0]"] == "kg"
    assert air.units["source.m"] == "kg/s"
    assert len(air.names) == len(set(air.names))
    for key in ("steps", "residual_evals", "wall_time"):
        assert key in air.stats
    df = air.to_dataframe()
    assert list(df.columns) == air.names and len(df) == air.t.size


def test_output_row_and_callback_stream():
    system = air_pipe_plant(1).compile()
    rows = []
    res = simulate(
        system,
        t_end=10.0,
        start="given",
        callback=lambda t, y, yp: rows.append(system.output_row(t, y, yp)),
    )
    names = system.output_names()
    assert len(rows) == res.t.size
    last = dict(zip(names, rows[-1], strict=False))
    assert last["pipe1.T_out"] == pytest.approx(res["pipe1.T_out"][-1], rel=1e-12)


def test_registry_and_describe():
    for name in [
        "PressureBoundary",
        "MassFlowBoundary",
        "Pipe",
        "Valve",
        "Attemperator",
        "PIController",
        "Mixer",
        "Splitter",
        "HeatExchanger",
        "TemperatureSensor",
    ]:
        cls = REGISTRY[name]
        text = cls.describe()
        assert name in text and "parameters" in text
    assert "kA" in Pipe.describe() and "[W/K]" in Pipe.describe()


def test_time_functions():
    assert Constant(3.0)(10.0) == 3.0 and Constant(3.0).breakpoints == ()
    s = Step(2.0, 1.0, 5.0)
    assert s(1.999) == 1.0 and s(2.0) == 5.0 and s.breakpoints == (2.0,)
    r = Ramp(1.0, 3.0, 0.0, 10.0)
    assert r(0.0) == 0.0 and r(2.0) == 5.0 and r(4.0) == 10.0 and r.breakpoints == (1.0, 3.0)
    tb = Table([0.0, 1.0, 3.0], [0.0, 2.0, 0.0])
    assert (
        tb(0.5) == 1.0 and tb(2.0) == 1.0 and tb(5.0) == 0.0 and tb.breakpoints == (0.0, 1.0, 3.0)
    )
    sn = Sine(1.0, 2.0, 4.0)
    assert sn(1.0) == pytest.approx(3.0) and sn.breakpoints == ()
    assert isinstance(as_time_function(2), Constant)
    with pytest.raises(ValueError):
        Table([0.0, 0.0], [1.0, 2.0])
    with pytest.raises(TypeError):
        as_time_function("x")


def test_step_is_a_tstop():
    plant = air_pipe_plant(1)
    plant.components["source"].params["T"] = Step(5.0, 600.0, 650.0)
    res = plant.simulate(10.0, start="given")
    assert 5.0 in res.t
    assert plant.compile().tstops(0.0, 10.0) == [5.0]
