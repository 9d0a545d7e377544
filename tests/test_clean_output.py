"""Clean output of the command line (issue 24, item 7): no binding-leak reports at exit,
``--vars`` patterns checked before the run, one rule for times written with and
without a space."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "plants"

#: a short refrigerant line: R134a vapour (CoolProp HEOS) through a pipe and a valve
R134A_PLANT = """
[plant]
name = "r134a_line"
medium = "R134a"

[simulation]
t_end = "2 s"
start = "given"

[components.inlet]
type = "PressureBoundary"
p = "5 bar"
T = "60 degC"
m_nominal = "0.5 kg/s"
ports = { port = "n_in" }

[components.pipe]
type = "Pipe"
V = "0.5 m3"
kA = "400 W/K"
k = 2e3
C_wall = "150 kJ/K"
n_volumes = 1
p0 = "4.9 bar"
T0 = "20 degC"
T_wall0 = "20 degC"
m_nominal = "0.5 kg/s"
ports = { inlet = "n_in", outlet = "n_out" }

[components.valve]
type = "Valve"
C = "0.002 kg/(s.Pa0.5)"
opening = 1
m_nominal = "0.5 kg/s"
ports = { inlet = "n_out", outlet = "n_sink" }

[components.outlet]
type = "PressureBoundary"
p = "4 bar"
ports = { port = "n_sink" }
"""


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


# ------------------------------------------------------------------ (a) nanobind


@pytest.mark.parametrize("command", ["run", "check"])
def test_coolprop_plant_leaves_stderr_empty_at_exit(tmp_path, command):
    """The ``dnasim`` program itself (a new interpreter, so that its shutdown is seen):
    CoolProp's AbstractState objects alive at exit made nanobind print ~30 lines of
    "nanobind: leaked ..." on stderr; now stderr is empty."""
    plant = tmp_path / "r134a.toml"
    plant.write_text(R134A_PLANT)
    args = [sys.executable, "-m", "dnasim", command, str(plant)]
    if command == "run":
        args += ["-o", str(tmp_path / "out"), "-q"]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "nanobind" not in proc.stderr
    assert proc.stderr == ""
    if command == "run":
        assert (tmp_path / "out" / "results.csv").is_file()


def test_a_released_medium_makes_a_new_abstract_state():
    """After the exit handler dropped the AbstractState, the medium still works (a use
    later in the interpreter's exit, or a test calling the handler)."""
    from dnasim.media import get_medium
    from dnasim.media.coolprop_medium import release_abstract_states

    m = get_medium("R134a", backend="HEOS")
    h = m.h_pT(5e5, 333.15)
    release_abstract_states()
    assert m._AS is None
    m._cache_hpT.clear()
    assert m.h_pT(5e5, 333.15) == h  # the same flash in a new AbstractState


# ------------------------------------------------------------------ (b) --vars


@pytest.mark.parametrize(
    "patterns, named, suggested",
    [
        (["att.TT"], ["'att.TT'"], ["'att.T'"]),
        (["pipe.T_out,att.TT"], ["'att.TT'"], ["'att.T'"]),  # one bad pattern is enough
        (["pipe.T_out", "nosuch.*"], ["'nosuch.*'"], []),
        (["pipe.Tout"], ["'pipe.Tout'"], ["'pipe.T_out'"]),
    ],
)
def test_unmatched_vars_pattern_is_an_input_error_before_the_run(
    tmp_path, patterns, named, suggested
):
    out = tmp_path / "out"
    args = ["run", PLANTS / "attemperator.toml", "-o", out]
    for p in patterns:
        args += ["--vars", p]
    res = invoke(*args)
    assert res.exit_code == 2, res.output
    msg = res.output
    assert msg.count("dnasim: error:") == 1 and "Traceback" not in msg
    assert "attemperator.toml" in msg and "--vars" in msg
    for w in named + suggested:
        assert w in msg
    assert "pipe.T_out' matches" not in msg  # the good pattern is not reported
    # nothing was simulated: no results, events or steps
    assert not (out / "results.csv").exists()
    assert not (out / "events.csv").exists() and not (out / "steps.csv").exists()


def test_matching_vars_patterns_still_plot(tmp_path):
    out = tmp_path / "out"
    res = invoke(
        "run", PLANTS / "air_pipe.toml", "-o", out, "--t-end", "2 min", "--vars", "pipe.T_out,n_*.p"
    )
    assert res.exit_code == 0, res.output
    assert (out / "results.csv").is_file() and (out / "variables.png").is_file()


# ------------------------------------------------------------------ (c) times


def _last_time(out: Path) -> float:
    last = (out / "results.csv").read_text().strip().splitlines()[-1]
    return float(last.split(",")[0])


@pytest.mark.parametrize(
    "t_end", ["2min", "2 min", "2 mins", "2 minutes", "120", "120s", "0.0333333333333333333h"]
)
def test_time_options_with_and_without_a_space(tmp_path, t_end):
    out = tmp_path / "out"
    res = invoke(
        "run", PLANTS / "air_pipe.toml", "-o", out, "--t-end", t_end, "--output-interval", "30s"
    )
    assert res.exit_code == 0, res.output
    assert _last_time(out) == pytest.approx(120.0, rel=1e-12)  # the end time is hit exactly
    rows = (out / "results.csv").read_text().strip().splitlines()[1:]
    times = [float(r.split(",")[0]) for r in rows]
    assert times == pytest.approx([0.0, 30.0, 60.0, 90.0, 120.0], rel=1e-12)


@pytest.mark.parametrize(
    "option, value, words",
    [
        ("--t-end", "1h30min", ["sum of 2 quantities", "'90 min'"]),
        ("--t-end", "1 min 30 s", ["'90 s'"]),
        ("--t-end", "1:30", ["clock time"]),
        ("--t-end", "20 m", ["minutes are 'min'"]),
        ("--output-interval", "1h5min", ["'65 min'"]),
    ],
)
def test_ambiguous_time_options_are_refused_before_the_run(tmp_path, option, value, words):
    out = tmp_path / "out"
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", out, option, value, "-q")
    assert res.exit_code == 2, res.output
    assert f"option {option}" in res.output
    for w in words:
        assert w in res.output
    assert not (out / "results.csv").exists()
