"""results.csv with output_interval: both sides of every discontinuity are rows."""

from pathlib import Path

import numpy as np
import pytest

from dnasim.plant.plantfile import loads
from dnasim.run.output import read_results_csv
from dnasim.run.runner import run_plant

PLANTS = Path(__file__).parent / "plants"


def _lag_plant(output_interval="1 s"):
    text = (PLANTS / "lag_sensor.toml").read_text()
    text = text.replace('t0 = "10 s"', 't0 = "10.3 s"')  # off the output grid
    text = text.replace(
        'start = "steady"', f'start = "steady"\nrtol = 1e-9\noutput_interval = "{output_interval}"'
    )
    return text


def _trapezoid(t, f):
    return float(np.sum(np.diff(t) * (f[1:] + f[:-1]) / 2))


def test_integral_over_csv_is_exact_across_a_time_event(tmp_path):
    """The supply temperature steps 100 -> 150 degC at 10.3 s, so the enthalpy flow
    E = m h_supply out of the supply jumps (the valve flow C z sqrt(dp) does not) and
    is constant on both sides: the trapezoidal integral of E over the rows equals the
    integrated counter H_passed (dH/dt = E, exactly m h_supply for outflow,
    ``physics.energy_in``)."""
    outcome = run_plant(loads(_lag_plant(), "lag.toml"), tmp_path)
    assert outcome.success, outcome.message
    _, _, d = read_results_csv(tmp_path / "results.csv")
    t, flag = d["time"], d["restart"]
    E, H = d["supply.m"] * d["supply.h_supply"], d["supply.H_passed"]
    at = np.flatnonzero(t == 10.3)
    assert len(at) == 2 and list(flag[at]) == [0.0, 1.0]
    jump = E[at[1]] - E[at[0]]
    assert jump > 0.1 * abs(E[0])  # a real jump (about 50 kW on 380 kW)
    exact = H[-1] - H[0]
    # 1e-9: the BDF integrates a constant exactly; what is left is the solver's
    # tolerance (rtol 1e-9) on H_passed and round-off
    assert _trapezoid(t, E) == pytest.approx(exact, rel=1e-9)
    # the old CSV (grid rows only) averages the rows at 10 and 11 s over that second
    # where the exact mean is 0.3 E(10) + 0.7 E(11): off by 0.2 s * jump, ~1e-4 of
    # the total, far outside that tolerance
    old = flag == 0
    old[at[0]] = False  # the left limit was not a row either (off the grid)
    err_old = _trapezoid(t[old], E[old]) - exact
    assert abs(err_old) > 1e3 * 1e-9 * abs(exact)
    # the grid rows are all there, each once, and the time never goes back
    grid = t[flag == 0]
    assert set(np.arange(0.0, 61.0)) <= set(grid.tolist())
    assert np.all(np.diff(t) >= 0)


def test_located_event_has_both_sides(tmp_path):
    text = (Path(__file__).parents[1] / "plants" / "attemperator.toml").read_text()
    text = text.replace('start = "steady"', 'start = "steady"\noutput_interval = "10 s"')
    outcome = run_plant(loads(text, "att.toml"), tmp_path)
    assert outcome.success, outcome.message
    _, _, d = read_results_csv(tmp_path / "results.csv")
    t_sw = outcome.event_log[0]["t"]
    at = np.flatnonzero(d["time"] == t_sw)
    assert len(at) == 2 and list(d["restart"][at]) == [0.0, 1.0]
    # the controller output reaches its limit there: continuous, 1 on both sides
    # (1e-8: the switch is located to |g| < 1e-9 and the output is z_max after it)
    assert d["pi.z"][at] == pytest.approx([1.0, 1.0], abs=1e-8)
    # and the set-point step at 2 min (on the grid) has its two rows as well
    at = np.flatnonzero(d["time"] == 120.0)
    assert len(at) == 2
    # the error jumps by the set-point step, 10 K (sensor reading continuous)
    assert d["pi.e"][at[1]] - d["pi.e"][at[0]] == pytest.approx(10.0, rel=1e-9)


def test_rows_per_step_flag_restarts(tmp_path):
    text = _lag_plant().replace('output_interval = "1 s"', "")
    outcome = run_plant(loads(text, "lag.toml"), tmp_path)
    _, _, d = read_results_csv(tmp_path / "results.csv")
    rep = np.flatnonzero(np.diff(d["time"]) == 0) + 1
    assert outcome.success and len(rep) >= 1
    assert np.array_equal(np.flatnonzero(d["restart"] == 1), rep)


def test_left_limit_row_evaluates_time_functions_before_the_event(tmp_path, monkeypatch):
    """At the set-point step (2 min) the row before holds the old set point in every
    column, the row after the new one. No component outputs a time function yet, so
    the PIController gets the set-point output proposed to the lead."""
    from dnasim.library.controller import PIController
    from dnasim.model.component import Output

    monkeypatch.setattr(PIController, "outputs", lambda self: [Output("setpoint", "K")])
    monkeypatch.setattr(
        PIController, "output_values", lambda self, t, x, xp: [self.param_at("setpoint", t)]
    )
    text = (Path(__file__).parents[1] / "plants" / "attemperator.toml").read_text()
    text = text.replace('t_end = "20 min"', 't_end = "3 min"')
    for extra in ("", 'output_interval = "10 s"\n'):
        outcome = run_plant(loads(text.replace("rtol", extra + "rtol", 1), "att.toml"), tmp_path)
        assert outcome.success
        _, _, d = read_results_csv(tmp_path / "results.csv")
        at = np.flatnonzero(d["time"] == 120.0)
        assert list(d["pi.setpoint"][at]) == [723.15, 713.15]  # 450 and 440 degC exactly
        assert list(d["restart"][at]) == [0.0, 1.0]
