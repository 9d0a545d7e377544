"""The ``dnasim`` command end to end: run every plant in plants/, check the physics,
the bad-input messages and exit codes, interrupted and failed runs."""

from __future__ import annotations

import csv
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.run.output import read_results_csv

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "plants"
ALL_PLANTS = sorted(PLANTS.glob("*.toml"))


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


def output_of(result) -> str:
    return result.output


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Run each plant once (in-process) and keep the output directories."""
    cache = {}

    def get(name):
        if name not in cache:
            out = tmp_path_factory.mktemp(name)
            res = invoke("run", PLANTS / f"{name}.toml", "-o", out, "--plot")
            cache[name] = (res, out)
        return cache[name]

    return get


def test_plants_directory_has_the_examples():
    names = {p.stem for p in ALL_PLANTS}
    assert {"air_pipe", "attemperator", "superheater_line"} <= names


# ------------------------------------------------------------------ every plant


@pytest.mark.parametrize("plant", ALL_PLANTS, ids=lambda p: p.stem)
def test_check_every_plant(plant):
    res = invoke("check", plant)
    assert res.exit_code == 0, output_of(res)
    out = res.output
    for word in ("equations:", "unknowns:", "differential states", "matching:   complete"):
        assert word in out
    assert out.strip().endswith("ok")


@pytest.mark.parametrize("plant", ALL_PLANTS, ids=lambda p: p.stem)
def test_run_every_plant_writes_valid_files(plant, runs):
    res, out = runs(plant.stem)
    assert res.exit_code == 0, output_of(res)
    names, units, data = read_results_csv(out / "results.csv")
    assert names[0] == "time" and units["time"] == "s"
    header = (out / "results.csv").read_text().splitlines()[0].split(",")
    assert all(re.fullmatch(r".+ \[.+\]", h) for h in header)
    t = data["time"]
    assert t[0] == 0.0 and np.all(np.diff(t) >= 0)  # a restart may repeat a time
    assert all(np.all(np.isfinite(v)) for k, v in data.items() if not k.endswith(".T"))
    steps = read_rows(out / "steps.csv")
    assert list(steps[0]) == ["time", "step_size", "order"]
    assert all(1 <= int(r["order"]) <= 5 for r in steps)
    events = (out / "events.csv").read_text().splitlines()[0]
    assert events == "event,iteration,time,switch_value,component,switch"
    for png in ("variables.png", "steps.png"):
        assert (out / png).read_bytes()[:4] == b"\x89PNG"
    assert "steps" in res.output and "events" in res.output and "wall time" in res.output


# ------------------------------------------------------------------ physics


def test_air_pipe_outlet_rises_monotonically_to_the_inlet_temperature(runs):
    res, out = runs("air_pipe")
    assert res.exit_code == 0, output_of(res)
    _, units, d = read_results_csv(out / "results.csv")
    assert units["pipe.T_out"] == "K"
    T_out = d["pipe.T_out"]
    T_in = d["pipe.T_in"]
    assert np.allclose(T_in, 473.15, atol=1e-6)  # 200 degC
    assert T_out[0] == pytest.approx(293.15, abs=0.01)  # the pipe starts cold
    assert np.all(np.diff(T_out) >= -1e-9)  # monotone
    assert np.all(T_out <= T_in + 1e-9)  # never overshoots
    assert T_in[-1] - T_out[-1] < 0.1 * (T_in[0] - T_out[0])  # most of the way there
    # the wall heats up too, and stays between the air and its initial temperature
    T_w = d["pipe.T_w[0]"]
    assert np.all(np.diff(T_w) >= -1e-9) and T_w[-1] < T_out[-1]


def test_attemperator_control_and_saturation(runs):
    res, out = runs("attemperator")
    assert res.exit_code == 0, output_of(res)
    _, _, d = read_results_csv(out / "results.csv")
    t, T, z = d["time"], d["n_mix.T"], d["pi.z"]
    # not saturated: the outlet settles at the set point, 450 degC then 440 degC
    before = (t > 60) & (t < 120)
    assert np.all(np.abs(T[before] - 723.15) < 0.01)
    settled = (t > 480) & (t < 600)
    assert np.all(np.abs(T[settled] - 713.15) < 0.05)
    assert np.all((z[t < 600] > 0.05) & (z[t < 600] < 0.95))
    # the hotter steam drives the controller into saturation exactly once
    events = read_rows(out / "events.csv")
    assert {r["event"] for r in events} == {"1"}
    assert {(r["component"], r["switch"]) for r in events} == {("pi", "upper")}
    assert [int(r["iteration"]) for r in events] == list(range(1, len(events) + 1))
    assert len(events) >= 3  # before, detection, refinements (Table 10.1)
    assert float(events[0]["switch_value"]) > 0 > float(events[1]["switch_value"])
    assert abs(float(events[-1]["switch_value"])) <= 1e-10
    t_sw = float(events[-1]["time"])
    assert 600 < t_sw < 720
    # z stays at its limit from the switch on, and the outlet stays above the set point
    after = t > t_sw + 1e-9
    assert np.allclose(z[after], 1.0, atol=1e-12) and np.all(z <= 1.0 + 1e-12)
    assert np.all(T[t > t_sw + 60] > 713.15 + 10)
    # the integration restarts at order 1 right after the switching point (Fig. 10.7)
    steps = read_rows(out / "steps.csv")
    # (the step that lands on the switching point ends there; the next one restarts)
    first_after = next(r for r in steps if float(r["time"]) > t_sw + 1e-9 * t_sw)
    assert int(first_after["order"]) == 1


def test_superheater_line_holds_both_temperatures_through_the_load_change(runs):
    res, out = runs("superheater_line")
    assert res.exit_code == 0, output_of(res)
    _, _, d = read_results_csv(out / "results.csv")
    t = d["time"]
    # a load change happened: the steam flow to the turbine drops by about 30 %
    m = d["turbine_valve.m"]
    assert m[-1] < 0.8 * m[0]
    for sensor, setpoint in (("sensor1.T_s", 713.15), ("sensor2.T_s", 813.15)):
        T = d[sensor]
        assert abs(T[0] - setpoint) < 0.01
        assert abs(T[-1] - setpoint) < 0.5  # back at the set point after the disturbance
        assert np.max(np.abs(T[t > 300] - setpoint)) > 0.5  # ... which did disturb it
    for z in ("pi1.z", "pi2.z"):
        assert np.all((d[z] > 0) & (d[z] < 1))  # both controllers in their range
    assert (out / "events.csv").read_text().count("\n") == 1  # no saturation


def test_superheater_line_has_at_least_100_states():
    res = invoke("check", PLANTS / "superheater_line.toml")
    m = re.search(r"\((\d+) differential states", res.output)
    assert m and int(m.group(1)) >= 100


# ------------------------------------------------------------------ options, plot, components


def test_run_options_override_the_file(tmp_path):
    res = invoke(
        "run",
        PLANTS / "air_pipe.toml",
        "-o",
        tmp_path,
        "--t-end",
        "2 min",
        "--rtol",
        "1e-5",
        "--output-interval",
        "10 s",
        "-q",
    )
    assert res.exit_code == 0, output_of(res)
    _, _, d = read_results_csv(tmp_path / "results.csv")
    assert d["time"].tolist() == [10.0 * k for k in range(13)]


def test_plot_command_replots_saved_results(runs, tmp_path):
    _, out = runs("attemperator")
    target = tmp_path / "p.png"
    res = invoke("plot", out / "results.csv", "--vars", "pi.z,sensor.*", "-o", target)
    assert res.exit_code == 0, output_of(res)
    assert target.read_bytes()[:4] == b"\x89PNG"
    res = invoke("plot", out / "results.csv", "n_mix.T")  # patterns as arguments
    assert res.exit_code == 0 and (out / "variables.png").exists()
    assert (out / "steps.png").exists()


def test_plot_with_unknown_variable_is_bad_input(runs):
    _, out = runs("attemperator")
    res = invoke("plot", out / "results.csv", "--vars", "nothing.here")
    assert res.exit_code == 2 and "no variable matches" in res.output


def test_plot_of_a_missing_file_is_bad_input(tmp_path):
    res = invoke("plot", tmp_path / "results.csv")
    assert res.exit_code == 2 and "no such file" in res.output


def test_components_lists_the_library():
    from dnasim.library import REGISTRY

    res = invoke("components")
    assert res.exit_code == 0
    for name in REGISTRY:
        assert name in res.output
    assert '{ type = "ramp", t0 = T, t1 = T, start = V, end = V }' in res.output


def test_components_shows_ports_parameters_units_defaults_equations():
    res = invoke("components", "Pipe")
    assert res.exit_code == 0
    out = res.output
    assert re.search(r"fluid ports.*:\n\s+inlet\s+inlet.*\n\s+outlet\s+outlet", out)
    # V is required unless the pipe is given by geometry (D): optional, saying so
    assert re.search(r"V\s+\[m3\]\s+optional.*\n.*required, unless D is given", out)
    assert re.search(r"n_volumes\s+\[1\]\s+default 1", out)
    assert "momentum" in out and "dM[i]/dt" in out  # equations (from the docstring)
    res = invoke("components", "PIController")
    assert re.search(r"signal inputs.*:\n\s+measured", res.output)
    assert "may be a time function" in res.output
    # the skeleton lists every input; set_point replaces the parameter setpoint
    assert (
        'inputs = { measured = "<component>.<output>", set_point = "<component>.<output>" }'
        in res.output
    )
    assert "when the parameter 'setpoint' is not given" in res.output
    res = invoke("components", "Mixer")
    assert 'ports = { inlet1 = "<node>", inlet2 = "<node>", outlet = "<node>" }' in res.output


def test_components_unknown_name():
    res = invoke("components", "Pipee")
    assert res.exit_code == 2 and "did you mean 'Pipe'?" in res.output


def test_help_is_fast_to_import():
    """`dnasim --help` must not import matplotlib or CoolProp."""
    code = (
        "import sys; from dnasim.cli.commands import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "print([m for m in ('matplotlib', 'CoolProp', 'pandas') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"


# ------------------------------------------------------------------ bad input: exit 2


def base_text():
    return (PLANTS / "attemperator.toml").read_text()


BAD_CASES = {
    "malformed_toml": (
        lambda s: s.replace('T_lag = "5 s"', 'T_lag = "5 s'),
        ["malformed TOML", "line "],
    ),
    "unknown_type": (
        lambda s: s.replace('type = "TemperatureSensor"', 'type = "TemperatureSenser"'),
        ["[components.sensor], key 'type'", "did you mean 'TemperatureSensor'?"],
    ),
    "unknown_parameter": (
        lambda s: s.replace('T_lag = "5 s"', 'T_lag = "5 s"\ntaux = 1'),
        ["[components.sensor], key 'taux'", "unknown parameter", "did you mean 'tau'?"],
    ),
    "missing_parameter": (
        lambda s: s.replace('V = "0.3 m3"\n', ""),
        ["[components.att], key 'V'", "missing required parameter"],
    ),
    "wrong_dimension": (
        lambda s: s.replace('V = "0.3 m3"', 'V = "0.3 kg"'),
        ["[components.att], key 'V'", "mass", "volume"],
    ),
    "negative_pressure": (
        lambda s: s.replace('p = "100 bar"', 'p = "-100 bar"'),
        ["[components.turbine], key 'p'", "out of the physical range", "pressure"],
    ),
    "zero_volume": (
        lambda s: s.replace('V = "0.3 m3"', "V = 0"),
        ["[components.att], key 'V'", "out of the physical range", "volume"],
    ),
    "unconnected_port": (
        lambda s: s.replace(
            'ports = { steam_in = "n_steam", water_in = "n_spray", outlet = "n_mix" }',
            'ports = { steam_in = "n_steam", outlet = "n_mix" }',
        ),
        ["[components.att]", "unconnected port", "'water_in'"],
    ),
    "name_used_twice": (
        lambda s: s + '\n[components.sensor]\ntype = "TemperatureSensor"\n',
        ["malformed TOML", "name is used twice", "line "],
    ),
    "node_and_component_same_name": (
        lambda s: s.replace('"n_line"', '"pipe"'),
        ["name used twice", "'pipe'"],
    ),
    "signal_wired_to_fluid_port": (
        lambda s: s.replace(
            'inputs = { measured = "sensor.T" }', 'inputs = { measured = "att.outlet" }'
        ),
        ["[components.pi.inputs], key 'measured'", "'att.outlet' is a fluid port"],
    ),
    "signal_port_connected_to_a_node": (
        lambda s: s.replace(
            'ports = { inlet = "n_water", outlet = "n_spray" }\ninputs = { z = "pi.z" }',
            'ports = { inlet = "n_water", outlet = "n_spray", z = "n_spray" }',
        ),
        ["[components.spray_valve.ports], key 'z'", "a signal cannot be wired to a node"],
    ),
    "bad_time_function": (
        lambda s: s.replace('type = "step", t0 = "2 min"', 'type = "stepp", t0 = "2 min"'),
        ["[components.pi.setpoint], key 'type'", "did you mean 'step'?"],
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
@pytest.mark.parametrize("command", ["check", "run"])
def test_bad_input_exit_2(case, command, tmp_path):
    mutate, words = BAD_CASES[case]
    text = mutate(base_text())
    assert text != base_text()
    path = tmp_path / "bad.toml"
    path.write_text(text)
    args = [command, path] + (["-o", tmp_path / "out"] if command == "run" else [])
    res = invoke(*args)
    assert res.exit_code == 2, res.output
    assert "Traceback" not in res.output
    assert str(path) in res.output
    for w in words:
        assert w in res.output
    assert not (tmp_path / "out" / "results.csv").exists()  # nothing ran


def test_missing_plant_file_is_bad_input(tmp_path):
    res = invoke("check", tmp_path / "none.toml")
    assert res.exit_code == 2 and "no such plant file" in res.output


@pytest.mark.parametrize(
    "option, value",
    [("--t-end", "5 bar"), ("--t-end", "-1"), ("--rtol", "2"), ("--max-order", "9")],
)
def test_bad_options_are_bad_input(option, value, tmp_path):
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", tmp_path, option, value)
    assert res.exit_code == 2, res.output


# ------------------------------------------------------------------ failures: exit 1, nothing lost


def _sine_steam(text, mean, amplitude, period, phase):
    return re.sub(
        r'T = \{ type = "ramp", t0 = "10 min".*\}',
        f'T = {{ type = "sine", mean = "{mean}", amplitude = "{amplitude}", '
        f'period = "{period}", phase = {phase} }}',
        text,
    )


def test_solver_failure_leaves_results_up_to_that_time(tmp_path):
    # the steam boundary is cooled into the two-phase dome, where T does not fix h
    text = _sine_steam(base_text(), "400 K", "390 K", "200 s", 1.5707963)
    plant = tmp_path / "fail.toml"
    plant.write_text(text)
    out = tmp_path / "out"
    res = invoke("run", plant, "-o", out, "-q")
    assert res.exit_code == 1, res.output
    m = re.search(r"failed at t = ([0-9.e+-]+) s", res.output)
    assert m, res.output
    t_fail = float(m.group(1))
    assert 0 < t_fail < 1200
    _, _, d = read_results_csv(out / "results.csv")
    assert len(d["time"]) > 10
    assert d["time"][-1] == pytest.approx(t_fail, rel=1e-5)
    assert "results.csv holds" in res.output
    assert (out / "steps.csv").exists() and (out / "events.csv").exists()


def _long_plant(tmp_path):
    """A run that takes minutes: the steam temperature oscillates for ever."""
    text = _sine_steam(base_text(), "540 degC", "20 K", "20 s", 0)
    text = text.replace('t_end = "20 min"', 't_end = "100 h"')
    plant = tmp_path / "long.toml"
    plant.write_text(text)
    return plant


def _default_signals():
    """In the child: SIGINT handled as usual, nothing blocked.

    A shell starts `command &` with SIGINT ignored, and an ignored signal stays
    ignored across exec; Python then installs no KeyboardInterrupt handler. The
    test must not depend on how the test run itself was started.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_SETMASK, [])


def _start(plant, out):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-c", "from dnasim.cli.commands import main; main()", "run", str(plant)]
    return subprocess.Popen(
        cmd + ["-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
        preexec_fn=_default_signals,
    )


def _wait_for_rows(proc, path, rows=3, timeout=120):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if path.exists() and path.read_text().count("\n") > rows:
            return
        if proc.poll() is not None:
            raise AssertionError(f"the run ended early: {proc.stdout.read()}")
        time.sleep(0.2)
    proc.kill()
    raise AssertionError("no rows were flushed")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_interrupted_run_leaves_a_valid_csv(sig, tmp_path):
    out = tmp_path / "out"
    proc = _start(_long_plant(tmp_path), out)
    _wait_for_rows(proc, out / "results.csv")
    time.sleep(1.5)
    proc.send_signal(sig)
    text, _ = proc.communicate(timeout=60)
    assert proc.returncode == 1, text
    assert "Traceback" not in text
    m = re.search(r"was interrupted at t = ([0-9.e+-]+) s", text)
    assert m, text
    _, _, d = read_results_csv(out / "results.csv")
    assert d["time"][-1] == pytest.approx(float(m.group(1)), rel=1e-5)
    assert 0 < d["time"][-1] < 100 * 3600
    assert np.all(np.diff(d["time"]) >= 0)
    steps = read_rows(out / "steps.csv")
    assert steps and float(steps[-1]["time"]) <= d["time"][-1] + 1e-9


def test_killed_run_leaves_a_parsable_csv(tmp_path):
    """SIGKILL: no clean-up at all; what was flushed is whole rows."""
    out = tmp_path / "out"
    proc = _start(_long_plant(tmp_path), out)
    _wait_for_rows(proc, out / "results.csv")
    time.sleep(1.5)
    proc.kill()
    proc.communicate(timeout=60)
    names, _, d = read_results_csv(out / "results.csv")
    text = (out / "results.csv").read_text()
    assert text.endswith("\n")  # no torn line
    assert len(d["time"]) > 3 and np.all(np.diff(d["time"]) >= 0)
    assert all(len(d[n]) == len(d["time"]) for n in names)
