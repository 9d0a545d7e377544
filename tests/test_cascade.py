"""Set point as a signal input (cascade control): tests/plants/cascade_level.toml
through the CLI (drum level master -> feedwater flow slave), and the set point
from a signal source against the same set point as a time function, for the
PIDController and the PIController.

The drum's steady state by hand (IF97 via CoolProp): at rest the feed flow equals
the steam flow and the heat Q raises the feed water to saturated steam,

    m = Q / (h''(p) - h_feed),   h_feed = h(160 bar, 200 degC)            [kg/s]
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from CoolProp.CoolProp import PropsSI

from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.plant.plantfile import loads, simulate_plant
from dnasim.run.output import read_results_csv

PLANT = Path(__file__).parent / "plants" / "cascade_level.toml"
WATER = "IF97::Water"
T_STEP = 60.0  # s, the load step in the plant file
H_FEED = PropsSI("H", "P", 160e5, "T", 473.15, WATER)  # J/kg


@pytest.fixture(scope="module")
def cascade(tmp_path_factory):
    out = tmp_path_factory.mktemp("cascade") / "out"
    res = CliRunner().invoke(main, ["run", str(PLANT), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(out / "results.csv")
    return d


def _steady_flow(Q, p):
    return Q / (PropsSI("H", "P", p, "Q", 1, WATER) - H_FEED)


def test_cascade_starts_steady_with_the_feed_balancing_the_steam(cascade):
    d = cascade
    # the level at its set point, the slave's set point = the master's output = the
    # feed flow = the steam flow = Q / (h'' - h_feed). Tolerances: 1e-6 relative is the
    # steady Newton (1e-8 of the nominal flow 20 kg/s) with margin; 1e-4 on the flow
    # from the hand calculation covers CoolProp's IF97 against dnasim's (both IF97,
    # measured 4e-15)
    assert d["drum.level"][0] == pytest.approx(2.0, abs=1e-6)
    m = d["feed_valve.m"][0]
    assert d["steam_valve.m"][0] == pytest.approx(m, rel=1e-6)
    assert d["level_pi.z"][0] == pytest.approx(m, rel=1e-6)
    assert d["flow_pi.setpoint"][0] == pytest.approx(m, rel=1e-6)
    assert d["flow.m_s"][0] == pytest.approx(m, rel=1e-6)
    assert m == pytest.approx(_steady_flow(40e6, d["drum.p"][0]), rel=1e-4)


def test_slave_tracks_the_master_and_the_level_returns(cascade):
    d = cascade
    t = d["time"]
    after = t >= T_STEP
    # the slave's set point is the master's output at every output row (a link, so
    # equal to round-off)
    assert np.array_equal(d["flow_pi.setpoint"], d["level_pi.z"])
    # the slave (time constants ~2 s) follows the master (minutes): its tracking
    # error stays below 3 % of the flow through the transient (measured 0.5 %) and
    # vanishes at the end (integral action; measured 1.2e-5 kg/s at 1200 s)
    err = d["level_pi.z"] - d["feed_valve.m"]
    assert np.max(np.abs(err[after])) < 0.03 * 21.4
    assert abs(err[-1]) < 1e-4
    # swell: the level first rises on the load step (Astrom-Bell bubbles), then falls
    # as the steam flow exceeds the feed, and returns to its set point 2 m; 1e-4 m
    # is above the last transient's tail (measured 5e-5 m at 1200 s)
    early = after & (t <= T_STEP + 20.0)
    assert np.max(d["drum.level"][early]) > 2.005
    assert np.min(d["drum.level"][after]) < 1.99
    assert d["drum.level"][-1] == pytest.approx(2.0, abs=1e-4)
    # the new steady state: the steam flow rose by ~10 % and the feed balances it at
    # Q/(h'' - h_feed) with Q = 44 MW (1e-4 as above, plus the tail of the transient)
    m_end = d["feed_valve.m"][-1]
    assert d["steam_valve.m"][-1] == pytest.approx(m_end, rel=1e-4)
    assert m_end == pytest.approx(_steady_flow(44e6, d["drum.p"][-1]), rel=2e-4)
    assert m_end / d["feed_valve.m"][0] == pytest.approx(1.1, abs=0.01)


def test_cascade_mass_balance_closes(cascade):
    d = cascade
    t = d["time"]
    # drum mass: M(t_end) - M(0) = int (m_feed - m_steam) dt; the trapezoid rule on
    # the 2 s output grid integrates the smooth flows to ~1e-4 of the throughput
    # (~28 t): the tolerance is 1e-4 of it
    dM = d["drum.M"][-1] - d["drum.M"][0]
    flow = np.trapezoid(d["drum.m_feed"] - d["drum.m_steam"], t)
    throughput = np.trapezoid(d["drum.m_steam"], t)
    assert abs(dM - flow) < 1e-4 * throughput
    # the feed valve's flow is the drum's feed (one node between them)
    assert np.max(np.abs(d["drum.m_feed"] - d["feed_valve.m"])) < 1e-9 * throughput


# ---------------------------------------------- set point from a signal source

LOOP = """
[plant]
name = "flow_step"
medium = "Water"
[simulation]
t_end = "60 s"
output_interval = "0.5 s"
start = "steady"
[components.src]
type = "PressureBoundary"
p = "20 bar"
T = "150 degC"
ports = {{ port = "n_src" }}
[components.v]
type = "Valve"
C = "0.002 kg/(s.Pa0.5)"
ports = {{ inlet = "n_src", outlet = "n_mid" }}
inputs = {{ z = "pi.z" }}
[components.v_fix]
type = "Valve"
C = "0.004 kg/(s.Pa0.5)"
opening = 1
ports = {{ inlet = "n_mid", outlet = "n_sink" }}
[components.sink]
type = "PressureBoundary"
p = "5 bar"
ports = {{ port = "n_sink" }}
[components.flow]
type = "MassFlowSensor"
T_lag = "1 s"
inputs = {{ u = "v.m" }}
[components.w]
type = "Step"
t0 = 5.0
before = 1.0
after = 1.3
unit = "kg/s"
[components.pi]
type = "{kind}"
{gains}
error_sign = "setpoint-measured"
measured_nominal = "1 kg/s"
{setpoint}
"""
GAINS = {"PIDController": 'Kp = "0.2 s/kg"\nT_i = "2 s"', "PIController": "Kp = 0.2\nKI = 0.1"}
AS_TIME_FUNCTION = (
    'setpoint = { type = "step", t0 = "5 s", before = "1 kg/s", after = "1.3 kg/s" }\n'
    'inputs = { measured = "flow.m" }'
)
AS_SIGNAL = 'inputs = { measured = "flow.m", set_point = "w.y" }'


def _run(kind, setpoint):
    loaded = loads(LOOP.format(kind=kind, gains=GAINS[kind], setpoint=setpoint), "loop.toml")
    res = simulate_plant(loaded.plant, loaded.simulation)
    assert res.success, res.message
    return res


@pytest.mark.parametrize("kind", ["PIDController", "PIController"])
def test_set_point_signal_equals_the_time_function(kind):
    a = _run(kind, AS_TIME_FUNCTION)
    b = _run(kind, AS_SIGNAL)
    # the same equations, the set point read from a variable y = w(t) instead of
    # w(t): the runs agree to the integrators' tolerance (rtol 1e-6; 1e-5 of the
    # flow with margin; measured: bit-identical)
    for name in ("v.m", "pi.z", "pi.e", "pi.setpoint"):
        assert np.allclose(np.interp(a.t, b.t, b[name]), a[name], rtol=1e-5, atol=1e-7), name
    # the step arrived: the flow approaches the new set point 1.3 kg/s (integral
    # action; 55 s after the step the transient is below 1e-4, measured 1e-5)
    assert b["v.m"][-1] == pytest.approx(1.3, rel=1e-4)
    assert b["v.m"][0] == pytest.approx(1.0, rel=1e-6)


def test_set_point_given_twice_or_never_is_an_input_error():
    both = LOOP.format(
        kind="PIDController",
        gains=GAINS["PIDController"],
        setpoint='setpoint = "1 kg/s"\n' + AS_SIGNAL,
    )
    with pytest.raises(PlantError, match="both the parameter 'setpoint' and the signal input"):
        loads(both, "both.toml")
    never = LOOP.format(
        kind="PIController",
        gains=GAINS["PIController"],
        setpoint='inputs = { measured = "flow.m" }',
    )
    with pytest.raises(PlantError, match="signal input 'set_point' of PIController is not linked"):
        loads(never, "never.toml")


def test_set_point_of_another_dimension_is_refused():
    text = PLANT.read_text().replace('unit = "kg/s"\n', 'unit = "Pa"\n', 1)
    with pytest.raises(PlantError, match="set point signal \\[Pa\\] and the measured signal"):
        load_text(text)


def load_text(text):
    loaded = loads(text, "cascade.toml")
    return loaded.plant.compile()
