"""``t_eval`` followed literally, in ``simulate`` and in plant files; ``progress=True``;
the IDA backend's output times (issues 21 and 24).

The closed form: tests/plants/lag_sensor.toml, an air supply whose temperature steps
from 100 to 150 degC at 10 s (a time event) and a sensor with a first-order lag of
8 s on its node: T_s(t) = 373.15 K before the step, 423.15 - 50 exp(-(t - 10)/8) K
after it. The node temperature n_in.T jumps at 10 s: its left limit is 373.15 K, its
right limit 423.15 K.
"""

from __future__ import annotations

import io
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import dnasim
from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.plant.plantfile import load, loads
from dnasim.run.output import read_results_csv
from dnasim.run.simulation import IDA, CSVSink, NordsieckBDF, simulate, simulation_keywords
from dnasim.run.sinks import AtTimes

HERE = Path(__file__).resolve().parent
LAG = HERE / "plants" / "lag_sensor.toml"
ATTEMPERATOR = HERE.parent / "plants" / "attemperator.toml"
T_EVAL = [0.0, 5.0, 10.0, 13.7, 17.5, 30.0, 60.0]


def _lag_text():
    return LAG.read_text().replace("tau =", "T_lag =")  # the key's current name


def _lag_system():
    return dnasim.compile(loads(_lag_text(), "lag_sensor.toml").plant)


def _exact(t):
    t = np.asarray(t, dtype=float)
    return np.where(t < 10.0, 373.15, 423.15 - 50.0 * np.exp(-(t - 10.0) / 8.0))


@pytest.mark.parametrize("backend", [NordsieckBDF, IDA])
def test_rows_are_exactly_the_t_eval_times_closed_form(backend, tmp_path):
    system = _lag_system()
    sink = CSVSink(tmp_path / "results.csv")
    res = simulate(
        system,
        t_end=60.0,
        t_eval=T_EVAL,
        solver=backend(rtol=1e-9, atol_scaled=1e-9),
        sinks=[sink],
    )
    assert res.success, res.message
    np.testing.assert_array_equal(res.t, T_EVAL)  # no row at the step's restart
    # at 10 s, where the supply steps: the right limit, flagged
    np.testing.assert_array_equal(res.restart, [t == 10.0 for t in T_EVAL])
    assert res["n_in.T"][2] == pytest.approx(423.15, abs=1e-9)  # left limit: 373.15
    assert res["n_in.T"][1] == pytest.approx(373.15, abs=1e-9)
    # the lag's closed form; measured 4e-6 K (NordsieckBDF) and 1.3e-5 K (IDA) at rtol
    # 1e-9, the global error over 50 s of a 50 K step; a row from the wrong side of the
    # step or at a wrong time is off by kelvins
    np.testing.assert_allclose(res["sensor.T_s"], _exact(T_EVAL), rtol=0, atol=1e-4)
    # the sink got the same rows, exactly these times, the restart column at 10 s
    _, _, d = read_results_csv(tmp_path / "results.csv")
    np.testing.assert_array_equal(d["time"], T_EVAL)
    np.testing.assert_array_equal(d["restart"], [float(t == 10.0) for t in T_EVAL])
    np.testing.assert_array_equal(d["sensor.T_s"], res["sensor.T_s"])


def test_attemperator_t_eval_has_no_rows_at_its_events():
    # the attemperator over 0:50:700 s: a set-point step at 120 s, a ramp ending at
    # 660 s and the controller's limit located at 638 s; none of them is a row
    loaded = load(ATTEMPERATOR)
    grid = np.arange(0.0, 701.0, 50.0)
    t_end, kw = simulation_keywords(loaded.simulation, 700.0, t_eval=grid)
    res = simulate(dnasim.compile(loaded.plant), t_end=t_end, **kw)
    assert res.success, res.message
    assert [e["name"] for e in res.events] == ["pi.upper"]
    assert 600 < res.events[0]["t"] < 700  # a located switch between two rows
    np.testing.assert_array_equal(res.t, grid)


def test_at_times_keeps_the_last_point_at_each_time():
    got = []
    keep = AtTimes([0.0, 2.0, 3.0], lambda t, restart, x: got.append((t, restart, x)))
    for t, x in ((0.0, "a"), (1.0, "b"), (1.0, "c"), (2.0, "d"), (2.0, "e"), (2.5, "f")):
        keep(t, x)
    assert got == [(0.0, False, "a"), (2.0, True, "e")]  # "e" after "d", at 2 s
    keep(3.0, "g")
    assert len(got) == 2  # (3.0, "g") waits: another point at 3 s may follow
    keep.flush()
    assert got == [(0.0, False, "a"), (2.0, True, "e"), (3.0, False, "g")]


@pytest.mark.parametrize(
    "t_eval, message",
    [
        ([0.0, 20.0, 10.0], "strictly increasing: t_eval\\[2\\] = 10 s follows"),
        ([0.0, 10.0, 10.0], "strictly increasing"),
        ([0.0, 70.0], "t_eval\\[1\\] = 70 s is after t_end = 60 s"),
        ([-1.0, 10.0], "before t_start = 0 s"),
        ([0.0, math.nan], "not a finite time"),
        ([], "at least one time"),
        (["10 s"], "numbers"),
    ],
)
def test_simulate_refuses_bad_t_eval(t_eval, message):
    system = _lag_system()
    with pytest.raises(PlantError, match="t_eval") as err:
        simulate(system, t_end=60.0, t_eval=t_eval)
    assert err.match(message)


# --------------------------------------------------------------------------- plant files


def _with_sim(lines: str) -> str:
    return _lag_text().replace('start = "steady"', 'start = "steady"\n' + lines)


def test_plant_file_t_eval_is_read_in_si():
    sim = loads(_with_sim('t_eval = ["0 s", 5, "10 s", "0.5 min", 60]'), "lag.toml").simulation
    assert sim.t_eval == (0.0, 5.0, 10.0, 30.0, 60.0)
    assert sim.output_interval is None
    t_end, kw = simulation_keywords(sim)
    assert kw["t_eval"] == [0.0, 5.0, 10.0, 30.0, 60.0] and "output_interval" not in kw
    # a caller's output_interval replaces the file's t_eval, and a t_eval the file's
    _, kw = simulation_keywords(sim, output_interval=2.0)
    assert "t_eval" not in kw and kw["output_interval"] == 2.0
    _, kw = simulation_keywords(sim, t_eval=[0.0, 60.0])
    assert kw["t_eval"] == [0.0, 60.0]


@pytest.mark.parametrize(
    "lines, message",
    [
        ('t_eval = "10 s"', "expected a list of times"),
        ('t_eval = ["0 s", "10 kg"]', "t_eval\\[1\\] = '10 kg'"),
        ("t_eval = [0, true]", "t_eval\\[1\\]: expected a number"),
        ('t_eval = ["0 s", "20 s", "10 s"]', "strictly increasing: t_eval\\[2\\] = 10 s"),
        ('t_eval = ["0 s", "2 min"]', "t_eval\\[1\\] = 120 s is after t_end = 60 s"),
        ('t_eval = [0, 10]\noutput_interval = "1 s"', "t_eval and output_interval"),
    ],
)
def test_plant_file_t_eval_errors_are_located(lines, message):
    text = _with_sim(lines)
    with pytest.raises(PlantError) as err:
        loads(text, "lag.toml")
    text_lines = text.splitlines()
    line = next(i for i, s in enumerate(text_lines, 1) if s.startswith("t_eval"))
    assert err.match(f"lag.toml, \\[simulation\\], key 't_eval', line {line}: ")
    assert err.match(message)


def _cli(tmp_path, text, *extra):
    path = tmp_path / "lag.toml"
    path.write_text(text)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(out), "-q", *extra])
    return res, out


def test_dnasim_run_writes_exactly_the_t_eval_rows(tmp_path):
    times = [0.0, 5.0, 10.0, 13.7, 30.0, 60.0]
    text = _with_sim(
        "rtol = 1e-9\natol_scaled = 1e-9\nt_eval = [" + ", ".join(map(repr, times)) + "]"
    )
    res, out = _cli(tmp_path, text, "--format", "both")
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(out / "results.csv")
    np.testing.assert_array_equal(d["time"], times)
    np.testing.assert_array_equal(d["restart"], [float(t == 10.0) for t in times])
    ran = dnasim.read_results(out)  # results.nc
    np.testing.assert_array_equal(ran.t, times)
    np.testing.assert_array_equal(ran.restart, [t == 10.0 for t in times])
    # the file's settings through the Python API: the same rows (the same solver, the
    # same steps, the same output points), to round-off (1e-12 relative, four orders of
    # magnitude below rtol: another road, another grid or start shows up at 1e-9 and up)
    loaded = loads(text, "lag.toml")
    t_end, kw = simulation_keywords(loaded.simulation)
    py = simulate(dnasim.compile(loaded.plant), t_end=t_end, **kw)
    np.testing.assert_array_equal(py.t, times)
    for name in ("sensor.T_s", "n_in.T", "supply.H_passed"):
        np.testing.assert_allclose(d[name], py[name], rtol=1e-12, atol=0, err_msg=name)
        np.testing.assert_allclose(ran[name], py[name], rtol=1e-12, atol=0, err_msg=name)
    # the closed form (tolerance as in the simulate() test above)
    np.testing.assert_allclose(d["sensor.T_s"], _exact(times), rtol=0, atol=1e-4)


def test_dnasim_run_t_eval_against_a_shorter_t_end_is_refused(tmp_path):
    res, _ = _cli(tmp_path, _with_sim('t_eval = [0, "1 min"]'), "--t-end", "30 s")
    assert res.exit_code == 2
    assert "--t-end" in res.output and "t_eval[1] = 60 s is after t_end = 30 s" in res.output
    # --output-interval replaces the file's t_eval
    res, out = _cli(tmp_path, _with_sim('t_eval = [0, "1 min"]'), "--output-interval", "20 s")
    assert res.exit_code == 0, res.output
    _, _, d = read_results_csv(out / "results.csv")
    assert list(d["time"]) == [0.0, 10.0, 10.0, 20.0, 40.0, 60.0]  # both sides of 10 s


# --------------------------------------------------------------------------- progress


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_is_one_line_redrawn_on_stderr(monkeypatch, capsys):
    system = _lag_system()
    simulate(system, t_end=60.0)
    assert capsys.readouterr().err == ""  # off by default
    term = _Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    res = simulate(system, t_end=60.0, t_eval=T_EVAL, progress=True)
    assert res.success
    text = term.getvalue()
    assert "simulating" in text and "100%" in text and "t = 60 s" in text
    assert "\r" in text and text.count("\n") <= 1  # redrawn in place: one line


# --------------------------------------------------------------------------- IDA


def test_ida_honours_output_interval_and_keeps_its_steps():
    text = _lag_text().replace('t0 = "10 s"', 't0 = "10.3 s"')  # the step off the grid
    system = dnasim.compile(loads(text, "lag.toml").plant)
    solver = IDA(rtol=1e-9, atol_scaled=1e-9)
    res = simulate(system, t_end=60.0, solver=solver, output_interval=10.0)
    assert res.success, res.message
    # the grid, and the time event at 10.3 s (both sides handed over; the Results keep
    # the state after the step, as NordsieckBDF's)
    np.testing.assert_array_equal(res.t, [0.0, 10.0, 10.3, 20.0, 30.0, 40.0, 50.0, 60.0])
    np.testing.assert_array_equal(res.restart, res.t == 10.3)
    bdf = simulate(system, t_end=60.0, output_interval=10.0, rtol=1e-9, atol_scaled=1e-9)
    np.testing.assert_array_equal(bdf.t, res.t)
    exact = np.where(res.t < 10.3, 373.15, 423.15 - 50.0 * np.exp(-(res.t - 10.3) / 8.0))
    # IDA's own interpolation between its steps; tolerance as in the t_eval test
    np.testing.assert_allclose(res["sensor.T_s"], exact, rtol=0, atol=1e-4)
    # the output times do not change IDA's steps (it interpolates, it does not stop)
    steps = simulate(system, t_end=60.0, solver=solver)
    np.testing.assert_array_equal(res.steps, steps.steps)
    assert res.stats["steps"] == steps.stats["steps"]


def test_ida_output_grid_across_a_located_switch():
    # the attemperator to 700 s: time events at 120, 600 and 660 s and the controller's
    # limit located at 638 s, where IDA hands over its root before the output times
    # inside that step can be interpolated
    def system():  # a fresh System for each run: a System run twice with IDA takes
        return dnasim.compile(load(ATTEMPERATOR).plant)  # other steps the second time

    solver = IDA(rtol=1e-7, atol_scaled=1e-8)
    res = simulate(system(), t_end=700.0, solver=solver, output_interval=10.0)
    assert res.success, res.message
    t_switch = res.events[0]["t"]
    assert 630 < t_switch < 640
    np.testing.assert_array_equal(res.t, np.union1d(np.arange(0.0, 701.0, 10.0), [t_switch]))
    np.testing.assert_array_equal(res.t[res.restart], [120.0, 600.0, t_switch, 660.0])
    steps = simulate(system(), t_end=700.0, solver=solver)
    np.testing.assert_array_equal(res.steps, steps.steps)  # interpolated, not stopped at
    # and the rows are those of the run without output times where the two coincide:
    # at its steps (the step-end states are the same numbers)
    common = np.intersect1d(res.t, steps.t)
    assert len(common) >= 5  # t0, the time events, the switch, t_end
    np.testing.assert_array_equal(res.at(common)["att.T"], steps.at(common)["att.T"])


def test_sweep_rows_are_the_t_eval_times(tmp_path):
    from dnasim.tools.sweeps import sweep

    loaded = loads(_with_sim("t_eval = [0, 5, 10, 13.7, 60]"), "lag.toml")
    res = sweep(loaded, {"sensor.T_lag": ["4 s", "8 s"]}, out_dir=tmp_path / "a")
    np.testing.assert_array_equal(res.dataset["time"].values, [0.0, 5.0, 10.0, 13.7, 60.0])
    lag8 = res.dataset["sensor.T_s"].values[1]
    # tolerance: the file's rtol 1e-6 over 50 s of a 50 K step (measured 2e-4 K)
    np.testing.assert_allclose(lag8, _exact([0.0, 5.0, 10.0, 13.7, 60.0]), rtol=0, atol=1e-3)
    # a case's output_interval replaces the file's times; a case's t_end before the
    # last of them is that case's input error, named
    cases = [{"simulation.output_interval": "20 s"}, {"simulation.t_end": "30 s"}]
    res = sweep(loaded, cases, out_dir=tmp_path / "b")
    status = list(res.summary["status"])
    assert status == ["finished", "input-error"], list(res.summary["message"])
    assert "t_eval[4] = 60 s is after t_end = 30 s" in res.summary["message"][1]
