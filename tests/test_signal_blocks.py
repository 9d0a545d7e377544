"""Signal blocks and sources against their closed forms, and sensors' lags against
1 - exp(-t/T_lag). Every run is at rtol 1e-9: the global error of these linear
and piecewise-linear signals is a few hundred times that at most, so 1e-6
absolute (on signals of order 1) is the tolerance unless a test says otherwise."""

import math

import numpy as np
import pytest

from dnasim.core.errors import PlantError
from dnasim.library.boundaries import PressureBoundary
from dnasim.library.sensor import (
    EnthalpySensor,
    LevelSensor,
    MassFlowSensor,
    PressureSensor,
    QualitySensor,
    TemperatureSensor,
)
from dnasim.library.signal_blocks import (
    DeadTime,
    FirstOrderLag,
    Gain,
    Limiter,
    Ramp,
    RateLimiter,
    Step,
    Sum,
    Table,
    TableSource,
)
from dnasim.library.valve import Valve
from dnasim.plant.plant import Plant

TOL = 1e-6


def run(plant, t_end, **kw):
    res = plant.simulate(t_end, start="given", rtol=1e-9, atol_scaled=1e-11, **kw)
    assert res.success, res.message
    return res


def chain(*comps, links=()):
    plant = Plant("blocks")
    for c in comps:
        plant.add(c)
    for src, dst in links:
        plant.link(src, dst)
    return plant


def test_sources_follow_their_time_functions():
    plant = chain(
        Step("s", t0=2.0, before=1.0, after=3.0),
        Ramp("r", t0=1.0, t1=3.0, start=-1.0, end=1.0),
        TableSource("tab", times=[0.0, 1.0, 4.0], values=[0.0, 2.0, -1.0]),
    )
    res = run(plant, 5.0, t_eval=np.linspace(0.0, 5.0, 51))
    t = res.t
    # sources are algebraic y = f(t): exact to round-off
    assert np.allclose(res["s.y"], np.where(t < 2.0, 1.0, 3.0), atol=1e-12)
    assert np.allclose(res["r.y"], np.clip(-1.0 + (t - 1.0), -1.0, 1.0), atol=1e-12)
    assert np.allclose(res["tab.y"], np.interp(t, [0.0, 1.0, 4.0], [0.0, 2.0, -1.0]), atol=1e-12)


def test_gain_and_weighted_sum():
    plant = chain(
        Ramp("a", t0=0.0, t1=10.0, start=0.0, end=10.0),
        Step("b", t0=5.0, before=2.0, after=-1.0),
        Gain("g", k=-2.5, unit="Pa"),
        Sum("s", n_inputs=2, w1=0.5, w2=3.0, bias=1.0),
        links=[("a.y", "g.u"), ("a.y", "s.u1"), ("b.y", "s.u2")],
    )
    res = run(plant, 10.0, t_eval=np.linspace(0.0, 10.0, 41))
    t = res.t
    assert np.allclose(res["g.y"], -2.5 * t, atol=1e-12)
    assert np.allclose(res["s.y"], 1.0 + 0.5 * t + 3.0 * np.where(t < 5.0, 2.0, -1.0), atol=1e-12)
    assert plant.compile().units["g.y"] == "Pa"


def test_first_order_lag_step():
    plant = chain(
        Step("u", t0=1.0, before=0.0, after=2.0),
        FirstOrderLag("f", T=3.0, k=1.5),
        links=[("u.y", "f.u")],
    )
    res = run(plant, 20.0)
    t = res.t
    exact = np.where(t >= 1.0, 3.0 * (1.0 - np.exp(-np.clip(t - 1.0, 0, None) / 3.0)), 0.0)
    assert np.max(np.abs(res["f.y"] - exact)) < TOL


def test_limiter_switches_at_the_limits():
    # u = 2 sin-free ramp from -2 to 2 over [0, 4] s and back down: y = clip(u, -1, 0.5)
    plant = chain(
        TableSource("u", times=[0.0, 4.0, 8.0], values=[-2.0, 2.0, -2.0]),
        Limiter("lim", y_min=-1.0, y_max=0.5),
        links=[("u.y", "lim.u")],
    )
    res = run(plant, 8.0, t_eval=np.linspace(0.0, 8.0, 81))
    u = np.interp(res.t, [0.0, 4.0, 8.0], [-2.0, 2.0, -2.0])
    assert np.max(np.abs(res["lim.y"] - np.clip(u, -1.0, 0.5))) < TOL
    # the crossings are located where u = limit: t = 1, 2.5, 5.5, 7 s
    times = sorted(e["t"] for e in res.events)
    assert np.allclose(times, [1.0, 2.5, 5.5, 7.0], atol=1e-8)


def test_limiter_enters_at_a_jump_of_its_input():
    # a step from 0 to 2 at t = 1 s jumps past y_max = 0.5: the switch fires at the
    # time event itself
    plant = chain(
        Step("u", t0=1.0, before=0.0, after=2.0),
        Limiter("lim", y_min=-1.0, y_max=0.5),
        links=[("u.y", "lim.u")],
    )
    res = run(plant, 3.0)
    assert [e["t"] for e in res.events] == [1.0]
    assert np.all(res["lim.y"][res.t >= 1.0] == 0.5)


def test_rate_limiter_ramp_then_lag():
    R, T = 0.5, 0.1
    plant = chain(
        Step("u", t0=1.0, before=0.0, after=1.0),
        RateLimiter("rl", R_up=R, T=T),
        links=[("u.y", "rl.u")],
    )
    res = run(plant, 5.0)
    t = res.t
    # ramp at R until u - y = R T (t1 = 1 + (1 - R T)/R = 2.9 s), then the lag
    t1 = 1.0 + (1.0 - R * T) / R
    exact = np.where(
        t < 1.0,
        0.0,
        np.where(t < t1, R * (t - 1.0), 1.0 - R * T * np.exp(-np.clip(t - t1, 0, None) / T)),
    )
    assert np.max(np.abs(res["rl.y"] - exact)) < TOL
    ev = [e["t"] for e in res.events]
    assert ev[0] == 1.0 and ev[1] == pytest.approx(t1, abs=1e-8)


def test_table_is_piecewise_linear_and_flat_outside():
    xs, ys = [2.0, 5.0, 8.0], [0.0, 3.0, -3.0]
    plant = chain(
        Ramp("u", t0=0.0, t1=10.0, start=0.0, end=10.0),
        Table("tab", x=xs, y=ys),
        links=[("u.y", "tab.u")],
    )
    res = run(plant, 10.0, t_eval=np.linspace(0.0, 10.0, 101))
    assert np.max(np.abs(res["tab.y"] - np.interp(res.t, xs, ys))) < TOL
    # one segment change at each table point, located where u = x_i
    assert np.allclose(sorted(e["t"] for e in res.events), xs, atol=1e-8)


def test_dead_time_is_an_erlang_step_response():
    n, Td = 6, 4.0
    plant = chain(
        Step("u", t0=0.5, before=0.0, after=1.0),
        DeadTime("d", T_dead=Td, n_stages=n),
        links=[("u.y", "d.u")],
    )
    res = run(plant, 15.0)
    s = np.clip(res.t - 0.5, 0.0, None) / (Td / n)
    # n lags of Td/n: y = 1 - sum_{k<n} e^-s s^k / k!  (Erlang CDF, mean delay Td)
    exact = 1.0 - sum(np.exp(-s) * s**k / math.factorial(k) for k in range(n))
    assert np.max(np.abs(res["d.y"] - exact)) < TOL


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: Limiter("x", y_min=1.0, y_max=0.0), "y_max must be greater"),
        (lambda: Table("x", x=[1.0, 1.0], y=[0.0, 1.0]), "strictly increasing"),
        (lambda: Table("x", x=[1.0, 2.0], y=[0.0]), "same number of points"),
        (lambda: Table("x", x="1, 2", y=[0.0, 1.0]), "list of numbers"),
        (lambda: FirstOrderLag("x", T=0.0), "T must be > 0"),
        (lambda: Gain("x", unit="furlong/fortnight"), "unit"),
    ],
)
def test_bad_block_parameters(make, words):
    with pytest.raises(PlantError, match=words):
        make()


# ----------------------------------------------------------------------------- sensors


def _line(sensors, links=()):
    """10 bar -> valve -> 1 bar water; the supply pressure steps to 12 bar at t = 1 s."""
    from dnasim.core.timefunctions import Step as StepF

    plant = Plant("line", medium="Water")
    plant.add(PressureBoundary("src", p=StepF(1.0, 10e5, 12e5), T=350.0, m_nominal=1.0))
    plant.add(Valve("v", C=1e-3, opening=0.5, m_nominal=1.0))
    plant.add(PressureBoundary("sink", p=1e5, m_nominal=1.0))
    plant.connect("src.port", "a")
    plant.connect("v.inlet", "a")
    plant.connect("v.outlet", "b")
    plant.connect("sink.port", "b")
    for s, node in sensors:
        plant.add(s)
        if node is not None:
            plant.connect(f"{s.name}.port", node)
    for src, dst in links:
        plant.link(src, dst)
    return plant


def test_sensor_lags_are_one_minus_exp():
    T_lag = 2.0
    plant = _line(
        [(PressureSensor("ps", T_lag=T_lag), "a"), (MassFlowSensor("fs", T_lag=T_lag), None)],
        links=[("v.m", "fs.u")],
    )
    res = plant.simulate(15.0, start="steady", rtol=1e-9, atol_scaled=1e-11)
    assert res.success
    t, after = res.t, res.t >= 1.0
    lag = 1.0 - np.exp(-(t[after] - 1.0) / T_lag)
    p_exact = 10e5 + 2e5 * lag
    # 1e-6 relative: the solver's global error on a first-order lag at rtol 1e-9
    assert np.max(np.abs(res["ps.p_s"][after] - p_exact)) < 1e-6 * 12e5
    m0, m1 = res["v.m"][0], res["v.m"][-1]  # the valve flow before and after (algebraic)
    assert np.max(np.abs(res["fs.m_s"][after] - (m0 + (m1 - m0) * lag))) < 1e-6 * m1
    assert np.all(res["ps.p_s"][~after] == pytest.approx(10e5, rel=1e-12))


def test_ideal_node_sensors_read_the_medium():
    from dnasim.media import get_medium

    plant = _line(
        [
            (TemperatureSensor("ts", T_lag=0.0), "a"),
            (EnthalpySensor("hs"), "a"),
            (QualitySensor("xs"), "a"),
        ]
    )
    res = plant.simulate(2.0, start="steady", rtol=1e-9)
    water = get_medium("Water")
    p, h = res["a.p"][-1], res["a.h"][-1]
    st = water.state(p, h)
    assert res["ts.T_s"][-1] == pytest.approx(st.T, rel=1e-12)
    assert res["hs.h_s"][-1] == pytest.approx(h, rel=1e-12)
    hl, hv = water.saturation_enthalpies(np.array([p]))
    # subcooled water at 350 K: the thermodynamic quality is negative, not clipped
    x = (h - hl[0]) / (hv[0] - hl[0])
    assert x < 0 and res["xs.x_s"][-1] == pytest.approx(x, rel=1e-12)


def test_quality_sensor_in_two_phase_matches_if97_quality():
    from dnasim.media import get_medium

    water = get_medium("Water")
    p = 10e5
    h = water.h_pQ(p, 0.3)
    plant = Plant("wet", medium="Water")
    plant.add(PressureBoundary("src", p=p, h=h, m_nominal=1.0))
    plant.add(Valve("v", C=1e-4, opening=0.5, m_nominal=0.1))
    plant.add(PressureBoundary("sink", p=9e5, m_nominal=0.1))
    plant.add(QualitySensor("xs"))
    plant.connect("src.port", "a")
    plant.connect("v.inlet", "a")
    plant.connect("xs.port", "a")
    plant.connect("v.outlet", "b")
    plant.connect("sink.port", "b")
    res = plant.simulate(1.0, start="steady", rtol=1e-9)
    # h_pQ and saturation_enthalpies are one IF97 saturation line: 1e-9 is round-off
    assert res["xs.x_s"][-1] == pytest.approx(0.3, abs=1e-9)
    assert water.state(p, h).quality == pytest.approx(res["xs.x_s"][-1], abs=1e-9)


def test_level_sensor_lag_on_a_ramp():
    # a ramp r t through a lag T: y = r (t - T (1 - exp(-t/T)))
    r, T_lag = 0.2, 3.0
    plant = chain(
        Ramp("lvl", t0=0.0, t1=100.0, start=0.0, end=100.0 * r, unit="m"),
        LevelSensor("ls", T_lag=T_lag, y0=0.0),
        links=[("lvl.y", "ls.u")],
    )
    res = run(plant, 20.0)
    t = res.t
    assert np.max(np.abs(res["ls.l_s"] - r * (t - T_lag * (1.0 - np.exp(-t / T_lag))))) < TOL
