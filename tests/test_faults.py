"""Faults and bad input (issue 12): nothing stale, nothing torn, nothing unbounded,
every failure located. One test (or a small group) per item of the issue."""

from __future__ import annotations

import errno
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.core.errors import OutputError
from dnasim.run.output import RESULT_FILES, StreamingCSV, read_results_csv

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "plants"
AIR = (PLANTS / "air_pipe.toml").read_text()
ATT = (PLANTS / "attemperator.toml").read_text()
DNASIM = [sys.executable, "-m", "dnasim"]


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


def plant(tmp_path, text, name="p.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def assert_located(result, *words):
    """Exit 2, one message naming the place, no internal error."""
    assert result.exit_code == 2, result.output
    assert "internal error" not in result.output
    assert "Traceback" not in result.output
    for w in words:
        assert w in result.output, (w, result.output)


# --------------------------------------------------------------------------- 1. output files


def test_previous_results_are_removed_before_a_run_that_fails(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    for name in RESULT_FILES:
        (out / name).write_text("stale\n")
    bad = plant(tmp_path, AIR.replace('V = "0.5 m3"', 'V = "0.5 furlong"'))
    res = invoke("run", bad, "-o", out, "-q")
    assert_located(res, "furlong")
    assert sorted(os.listdir(out)) == []


def test_previous_results_are_removed_when_the_run_fails_before_its_first_row(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.csv").write_text("time [s]\n1.0\n")
    (out / "steps.csv").write_text("time,step_size,order\n1.0,1.0,1\n")
    # a valid file whose start cannot be computed: the run fails while starting
    text = AIR.replace('p = "1.5 bar"', "p = 1e30")
    res = invoke("run", plant(tmp_path, text), "-o", out, "-q", "--t-end", "1 s")
    assert res.exit_code in (1, 2) and "internal error" not in res.output
    assert not (out / "results.csv").exists()
    steps = (out / "steps.csv").read_text() if (out / "steps.csv").exists() else ""
    assert "1.0,1.0,1" not in steps


def test_symlinks_planted_in_the_output_directory_are_not_followed(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    outside = tmp_path / "precious.txt"
    outside.write_text("keep me\n")
    for name in ("results.csv", "events.csv", "steps.csv", "variables.png"):
        (out / name).symlink_to(outside)
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", out, "-q", "--t-end", "10 s", "--plot")
    assert res.exit_code == 0, res.output
    assert outside.read_text() == "keep me\n"
    for name in ("results.csv", "events.csv", "steps.csv", "variables.png"):
        assert not (out / name).is_symlink() and (out / name).is_file()


def test_streaming_csv_never_opens_an_existing_file_or_link(tmp_path):
    target = tmp_path / "elsewhere.csv"
    target.write_text("keep\n")
    link = tmp_path / "results.csv"
    link.symlink_to(target)
    with pytest.raises(OutputError, match="results.csv"):
        StreamingCSV(link, ["time [s]"])
    assert target.read_text() == "keep\n"


def test_results_csv_being_a_directory_is_a_located_error(tmp_path):
    out = tmp_path / "out"
    (out / "results.csv").mkdir(parents=True)
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", out, "-q", "--t-end", "1 s")
    assert_located(res, "results.csv", "is a directory")


def test_disk_full_truncates_to_the_last_whole_row(tmp_path, monkeypatch):
    """ENOSPC injected into the writer: half a block reaches the disk, then the error."""
    import dnasim.run.output as output

    path = tmp_path / "r.csv"
    w = StreamingCSV(path, ["time [s]", "x [K]"], flush_rows=4, flush_seconds=1e9)
    for i in range(4):
        w.write_row([float(i), 300.0 + i])  # 4 rows flushed
    real_write = os.write

    def full(fd, data):
        real_write(fd, bytes(data[: len(data) // 2]))  # a torn block, then the disk is full
        monkeypatch.setattr(output.os, "write", failing)
        return len(data) // 2

    def failing(fd, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output.os, "write", full)
    with pytest.raises(OutputError) as info:
        for i in range(4, 8):
            w.write_row([float(i), 300.0 + i])
    monkeypatch.setattr(output.os, "write", real_write)
    err = info.value
    assert "r.csv" in str(err) and "disk is full" in str(err) and "t = 3 s" in str(err)
    assert err.t_reached == 3.0 and err.rows == 4
    text = path.read_text()
    assert text.endswith("\n") and len(text.splitlines()) == 1 + 4
    w.close()  # closing after the failure is harmless


def _limit_file_size(nbytes):
    def preexec():
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    return preexec


def test_file_size_limit_in_a_real_process_is_an_environment_error(tmp_path):
    """RLIMIT_FSIZE (no root needed): results.csv (676 kB for the whole run) hits the
    300 kB limit; steps.csv (about 20 kB) and events.csv still fit."""
    out = tmp_path / "out"
    proc = subprocess.run(
        # results.csv alone: results.nc has its own test (tests/test_results_netcdf.py)
        [*DNASIM, "run", str(PLANTS / "attemperator.toml"), "-o", str(out), "-q"]
        + ["--format", "csv"],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_limit_file_size(300_000),
        cwd=ROOT,
    )
    assert proc.returncode == 2, proc.stderr
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
    assert "results.csv" in proc.stderr and "file size limit" in proc.stderr
    assert "t = " in proc.stderr
    text = (out / "results.csv").read_text()
    assert text.endswith("\n")
    names, _, data = read_results_csv(out / "results.csv")
    assert len(data["time"]) > 1
    assert (out / "events.csv").exists() and (out / "steps.csv").exists()


# --------------------------------------------------------------------------- 2. units


@pytest.mark.parametrize(
    "value, words",
    [
        ('"0.02 degC"', ["absolute temperature", "1/temperature", "'0.02 1/K'"]),
        ('"0.02 K"', ["temperature", "1/temperature"]),
        ('"0.02 degF"', ["absolute temperature"]),
    ],
)
def test_controller_gain_accepts_only_inverse_temperature(tmp_path, value, words):
    res = invoke("check", plant(tmp_path, ATT.replace('Kp = "0.02 1/K"', f"Kp = {value}")))
    assert_located(res, "[components.pi]", "key 'Kp'", *words)


def test_controller_gain_in_inverse_temperature_is_read_per_kelvin():
    from dnasim.plant.plantfile import loads

    for text, kp in (('"0.02 1/K"', 0.02), ('"0.02 1/degC"', 0.02), ('"0.01 1/degF"', 0.018)):
        spec = loads(ATT.replace('Kp = "0.02 1/K"', f"Kp = {text}")).spec
        pi = next(c for c in spec.components if c.name == "pi")
        # 1e-15: one rounding of the degF scale 5/9
        assert pi.params["Kp"] == pytest.approx(kp, rel=1e-15)


def test_temperature_difference_refuses_degC(tmp_path):
    text = AIR.replace("n_volumes = 1", 'n_volumes = 1\ndT_reg = "2 degC"')
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, "key 'dT_reg'", "temperature difference", "'2 K'", "delta_degC")
    from dnasim.plant.plantfile import loads

    for ok in ('"2 K"', '"2 delta_degC"', "2"):
        spec = loads(AIR.replace("n_volumes = 1", f"n_volumes = 1\ndT_reg = {ok}")).spec
        pipe = next(c for c in spec.components if c.name == "pipe")
        assert pipe.params["dT_reg"] == 2.0  # exact: scale 1, no offset


# --------------------------------------------------------------------------- 3. limits


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("n_volumes = 1", "n_volumes = 1000000000", ["n_volumes = 1e+09", "limit of 5000"]),
        ("n_volumes = 1", "n_volumes = 1e5", ["n_volumes = 100000", "limit of 5000"]),
    ],
)
def test_counts_have_an_upper_limit(tmp_path, old, new, words):
    res = invoke("check", plant(tmp_path, AIR.replace(old, new)))
    assert_located(res, "[components.pipe]", *words)


def test_splitter_outlets_have_an_upper_limit(tmp_path):
    text = (
        (PLANTS / "superheater_line.toml").read_text().replace("n_outlets = 2", "n_outlets = 5000")
    )
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, "key 'n_outlets'", "n_outlets = 5000", "limit of 64")


def test_output_points_are_capped_before_the_grid_exists(tmp_path):
    import tracemalloc

    from dnasim.core.errors import PlantError
    from dnasim.plant.plantfile import loads

    text = AIR.replace('t_end = "30 min"', 't_end = 1e9\noutput_interval = "1 s"')
    tracemalloc.start()
    with pytest.raises(PlantError, match=r"output_interval.*1e\+09 output points.*1e\+07"):
        loads(text)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 50e6  # the grid would be 8 GB; the whole check needs a few MB
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, "[simulation]", "key 'output_interval'")


def test_max_steps_from_the_file_and_from_the_command_line(tmp_path):
    text = AIR.replace('t_end = "30 min"', 't_end = "30 min"\nmax_steps = 5')
    res = invoke("run", plant(tmp_path, text), "-o", tmp_path / "a", "-q")
    assert res.exit_code == 1 and "5" in res.output and "steps" in res.output
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", tmp_path / "b", "-q", "--max-steps", "7")
    assert res.exit_code == 1 and "7" in res.output
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", tmp_path / "c", "--max-steps", "0")
    assert_located(res, "--max-steps")


def test_streaming_run_keeps_no_rows_in_memory(tmp_path):
    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant

    outcome = run_plant(load(PLANTS / "air_pipe.toml"), tmp_path / "o", flush_rows=10)
    assert outcome.success and outcome.rows > 10
    assert outcome.result.y is None and outcome.result.sol is None
    kept = run_plant(load(PLANTS / "air_pipe.toml"), tmp_path / "k", keep_rows=True)
    assert kept.result.y.shape[1] == kept.rows


# --------------------------------------------------------------------------- 4. located messages


@pytest.mark.parametrize(
    "text, words",
    [
        ("x = " + "[" * 1000 + "]" * 1000 + "\n" + AIR, ["nested too deeply", "p.toml"]),
        (AIR.replace('V = "0.5 m3"', 'V = "0.5 m^(1/0)"'), ["key 'V'", "divides by zero"]),
        (AIR.replace('V = "0.5 m3"', 'V = "0.5 m^999"'), ["key 'V'", "out of range"]),
        (
            AIR.replace('V = "0.5 m3"', 'V = "0.5 ' + "(" * 500 + "m3" + ")" * 500 + '"'),
            ["key 'V'"],
        ),
        (
            AIR.replace('t_end = "30 min"', 't_end = "30 min"\noutput_interval = "1e-300 s"'),
            ["key 'output_interval'", "limit"],
        ),
        (
            ATT.replace('measured = "sensor.T"', 'measured = "sensr.T"'),
            ["no component named 'sensr'", "did you mean 'sensor'"],
        ),
        (
            ATT.replace('inputs = { z = "pi.z" }', 'opening = 0.5\ninputs = { z = "pi.z" }'),
            ["both the parameter 'opening' and the signal input 'z'"],
        ),
        (
            ATT.replace('inputs = { z = "pi.z" }', 'inputs = { z = "sensor.T" }'),
            ["dimension mismatch", "'sensor.T' is a temperature signal", "dimensionless"],
        ),
    ],
    ids=[
        "toml-1000-deep",
        "exp-1-0",
        "exp-999",
        "parens",
        "interval",
        "dangling",
        "both",
        "T-to-z",
    ],
)
def test_bad_input_is_located(tmp_path, text, words):
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, *words)


def test_a_dangling_signal_is_the_only_error_reported(tmp_path):
    text = ATT.replace('measured = "sensor.T"', 'measured = "sensr.T"')
    res = invoke("check", plant(tmp_path, text))
    assert res.output.count(".toml,") == 1, res.output  # one paragraph, no unit follow-ons


def test_boundary_far_outside_the_medium_range_is_located(tmp_path):
    text = ATT.replace('T = "200 degC"', 'T = "5000 degC"')
    res = invoke("run", plant(tmp_path, text), "-o", tmp_path / "o", "-q", "--t-end", "1 s")
    assert_located(res, "5000 degC")


@pytest.mark.parametrize("value", ["inf", "nan", "-1", "0"])
def test_atol_must_be_finite_and_positive(tmp_path, value):
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", tmp_path, "--atol-scaled", value)
    assert_located(res, "--atol-scaled")


def test_sigterm_while_starting_exits_with_a_message(tmp_path):
    # tight tolerances: the whole default run now takes under 1 s of CPU, so it could end
    # before the signal; at 1e-10 it lasts many seconds
    cmd = [*DNASIM, "run", str(PLANTS / "attemperator.toml"), "-o", str(tmp_path), "-q"]
    proc = subprocess.Popen(
        [*cmd, "--rtol", "1e-10", "--atol-scaled", "1e-10"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        preexec_fn=lambda: signal.signal(signal.SIGTERM, signal.SIG_DFL),
    )
    # after Python itself has started (about 0.2 s, the one window where SIGTERM still
    # kills silently), while numpy, CoolProp and the plant load or the run starts
    time.sleep(1.0)
    assert proc.poll() is None, "the run ended before the signal; the test did not test"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 1, (proc.returncode, err)
    assert "interrupted" in err and "SIGTERM" in err and "Traceback" not in err


# --------------------------------------------------------------------------- 5. CoolProp tables


def test_tabular_medium_is_announced_before_its_tables_are_built(tmp_path, monkeypatch):
    import CoolProp.CoolProp as CP

    import dnasim.media as media

    order = []
    real = media.get_medium

    def fake_get_medium(name, *a, **k):
        order.append(("build", name))
        if "BICUBIC" in name.upper():
            return real("Water")  # the same fluid, without 15 s of table building
        return real(name, *a, **k)

    import dnasim.cli.run_command as cli  # `run` and its helpers

    real_notice = cli._tabular_notice

    def notice(name):
        order.append(("notice", name))
        real_notice(name)

    monkeypatch.setattr(media, "get_medium", fake_get_medium)
    monkeypatch.setattr(cli, "_tabular_notice", notice)
    old = CP.get_config_string(CP.ALTERNATIVE_TABLES_DIRECTORY)
    try:
        text = ATT.replace('medium = "Water"', 'medium = "BICUBIC&HEOS::Water"')
        res = invoke("check", plant(tmp_path, text), "--coolprop-cache", tmp_path / "cp")
        assert "BICUBIC&HEOS::Water" in res.output and "tables" in res.output
        assert str((tmp_path / "cp").resolve()) in res.output
        assert CP.get_config_string(CP.ALTERNATIVE_TABLES_DIRECTORY) == os.path.join(
            (tmp_path / "cp").resolve(), ""
        )
        kinds = [k for k, name in order if "BICUBIC" in name.upper()]
        assert kinds[:2] == ["notice", "build"]
    finally:
        CP.set_config_string(CP.ALTERNATIVE_TABLES_DIRECTORY, old)


def test_an_unknown_component_type_hides_its_follow_on_errors(tmp_path):
    """Without the attemperator its nodes have one port each: that follows from the
    misspelt type and is not reported again."""
    res = invoke("check", plant(tmp_path, ATT.replace('"Attemperator"', '"Attemperatr"')))
    assert_located(res, "unknown component type 'Attemperatr'", "did you mean 'Attemperator'")
    assert res.output.count(".toml,") == 1, res.output


def test_small_tables_on_a_full_disk_leave_no_partial_file(tmp_path, monkeypatch):
    """events.csv/steps.csv go through a temporary file: ENOSPC while writing it leaves
    neither a torn table nor the temporary file, and names the table."""
    import dnasim.run.output as output
    from dnasim.run.output import write_steps_csv

    class Full:
        def __init__(self, f):
            self.f = f

        def write(self, data):
            raise OSError(errno.ENOSPC, "No space left on device")

        def __getattr__(self, name):
            return getattr(self.f, name)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

    real_fdopen = os.fdopen
    monkeypatch.setattr(output.os, "fdopen", lambda fd, mode: Full(real_fdopen(fd, mode)))
    with pytest.raises(OutputError, match=r"steps\.csv: the disk is full"):
        write_steps_csv(tmp_path / "steps.csv", [(1.0, 0.1, 2)])
    assert os.listdir(tmp_path) == []


def test_plot_into_a_missing_directory_is_bad_input(tmp_path):
    res = invoke("run", PLANTS / "air_pipe.toml", "-o", tmp_path / "o", "-q", "--t-end", "5 s")
    assert res.exit_code == 0
    res = invoke("plot", tmp_path / "o" / "results.csv", "-o", tmp_path / "nowhere" / "x.png")
    assert_located(res, "x.png")


@pytest.mark.skipif(
    not os.environ.get("DNASIM_TABULAR_TESTS"),
    reason="building CoolProp tables takes 15-30 s; set DNASIM_TABULAR_TESTS=1",
)
def test_coolprop_tables_go_to_the_cache_directory(tmp_path):
    text = ATT.replace('medium = "Water"', 'medium = "BICUBIC&HEOS::Water"')
    cache = tmp_path / "cp"
    proc = subprocess.run(
        [*DNASIM, "check", str(plant(tmp_path, text)), "--coolprop-cache", str(cache)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr
    assert "note:" in proc.stderr and str(cache.resolve()) in proc.stderr
    assert any(p.name.endswith(".bin.z") for p in cache.rglob("*"))


# --------------------------------------------------------------------------- 7. states


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('p = "120 bar"', "p = 1e30", ["boundary 'steam'", "above the IF97 limit"]),
        ('"500 degC"', '"1000000 degC"', ["boundary 'steam'", "IF97"]),
    ],
)
def test_check_evaluates_the_prescribed_states(tmp_path, old, new, words):
    """`dnasim check` evaluates every boundary's supply state at t0 and at the
    breakpoints of its time functions: out-of-range states are input errors naming
    the boundary, before any numerics (they used to pass check and fail the run)."""
    text = (PLANTS / "attemperator.toml").read_text()
    assert old in text
    path = tmp_path / "p.toml"
    path.write_text(text.replace(old, new, 1))
    result = invoke("check", path)
    assert result.exit_code == 2, result.output
    assert "internal error" not in result.output and "Traceback" not in result.output
    for w in words:
        assert w in result.output, (w, result.output)


# --------------------------------------------------------------------------- 8. back-pressure


def test_back_pressure_below_the_fluid_range_is_located(tmp_path):
    # 0.001 bar = 100 Pa is below IF97's lowest pressure, p_sat(273.15 K) = 611.2 Pa:
    # no state of the steam leaving through the sink exists, whatever its enthalpy
    text = ATT.replace('p = "100 bar"', 'p = "0.001 bar"')
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, "boundary 'turbine'", "0.001 bar", "outside the range of Water (IF97)")


def _attemperator_pi_file(tmp_dir) -> Path:
    """plants/attemperator.toml with the seed's PIController (eqs. 10.13) in place of
    its PIDController: the same gains, KI = Kp/T_i."""
    text = (PLANTS / "attemperator.toml").read_text()
    for old, new in (
        ('type = "PIDController"', 'type = "PIController"'),
        ('T_i = "33.3 s"', 'KI = "6e-4 1/(K.s)"'),
    ):
        assert old in text, old
        text = text.replace(old, new)
    path = Path(tmp_dir) / "attemperator_pi.toml"
    path.write_text(text)
    return path


def test_steady_start_beyond_a_limit_saturates_and_says_so(tmp_path):
    # 0.01 bar is inside IF97's range, but the turbine valve (m = C z sqrt(dp), no
    # choking) then passes 2.6 times its nominal flow, and the spray controller would
    # need an opening above 1 to hold its set point. Before issue 20 the steady start
    # stopped there ("no steady state found"); a PI controller whose output at rest lies
    # beyond its limit engages the limit (z = 1), and there the error keeps its sign
    # (the steam stays too hot, the controller asks for more): a state at rest with the
    # controller saturated, its held integral free. The start says both: the
    # controller that holds its limit and the valve whose law ignores choking.
    import dnasim
    from dnasim.start.steady_state import find_steady_state

    spec = dnasim.load_plant(_attemperator_pi_file(tmp_path))
    spec.components["turbine"].params["p"] = 1000.0  # [Pa] = 0.01 bar
    system = dnasim.compile(spec)
    rest = find_steady_state(system, 0.0)
    at = system.index
    assert rest.saturated == [("pi", "high")]
    assert rest.y[at["pi.z"]] == 1.0  # the output equation in mode "high": z = z_max exactly
    assert rest.y[at["pi.e"]] > 0.0  # measured above the set point: it would open further
    notes = " ".join(rest.notes)
    for words in ("controller 'pi' holds its output at z_max = 1", "'turbine_valve'", "choked"):
        assert words in notes, (words, notes)
    # at rest: y' = 0 except the accumulators' (the boundaries' running integrals)
    moving = [
        n
        for n, v, acc in zip(system.names, rest.yp, system.accumulator, strict=True)
        if v and not acc
    ]
    assert not moving, moving
    assert rest.yp[at["pi.m_I"]] == 0.0  # held (anti_windup): the integral does not wind


# --------------------------------------------------------------------------- 10. early signals


def _catches_sigterm(pid: int) -> bool:
    """The process has a handler for SIGTERM (bit 15 of SigCgt in /proc/PID/status)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    line = next((s for s in status.splitlines() if s.startswith("SigCgt:")), "SigCgt: 0")
    return bool(int(line.split()[1], 16) & (1 << (signal.SIGTERM - 1)))


def _start_run(out: Path, block: bool):
    """`python -m dnasim run` on the attemperator into ``out``, which holds a previous
    run's results. block: SIGTERM and SIGINT blocked across exec, so a signal sent
    at once stays pending through the interpreter's own start-up (before any line
    of dnasim runs, where no Python program can catch it) until dnasim's handlers
    are installed and unblock it."""
    out.mkdir()
    for name in RESULT_FILES:
        (out / name).write_text("stale\n")

    def child():
        for s in (signal.SIGTERM, signal.SIGINT):
            signal.signal(s, signal.SIG_DFL)
        if block:
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM, signal.SIGINT})

    return subprocess.Popen(
        [sys.executable, "-m", "dnasim", "run", str(PLANTS / "attemperator.toml")]
        # tolerances 1e-10: ~1600 steps instead of ~320, so that the run outlasts the
        # latest signal of these tests (1 s after the handler exists) on a fast, idle
        # machine too (at the file's tolerances it once finished first: exit 0)
        + ["-o", str(out), "-q", "--rtol", "1e-10", "--atol-scaled", "1e-10"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        preexec_fn=child,
    )


def _assert_interrupted_cleanly(proc, out: Path, what: str):
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1, (proc.returncode, err)
    assert len(err.strip().splitlines()) == 1, err  # one line, no traceback
    assert "interrupted" in err and what in err, err
    for f in out.iterdir():  # nothing of the previous run; whole rows only
        if f.name == "results.nc":  # binary: a netCDF file, closed, of whole rows
            import dnasim

            assert not dnasim.read_results(f).success, f
            continue
        text = f.read_text()
        assert "stale" not in text, f
        assert text == "" or text.endswith("\n"), f


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_a_signal_at_the_very_start_is_held_until_the_handlers_exist(tmp_path, sig):
    proc = _start_run(tmp_path / "out", block=True)
    proc.send_signal(sig)
    _assert_interrupted_cleanly(
        proc, tmp_path / "out", "SIGTERM" if sig == signal.SIGTERM else "Ctrl-C"
    )


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc/PID/status")
@pytest.mark.parametrize("delay", [0.0, 0.02, 0.1, 0.3, 1.0])
def test_sigterm_at_any_early_time_gives_one_line_and_no_stale_files(tmp_path, delay):
    # from the moment the handler exists (polled in /proc, so a loaded machine's slow
    # interpreter start does not matter) through imports, option parsing, clearing
    # the output directory, loading the plant and the steady start
    proc = _start_run(tmp_path / "out", block=False)
    deadline = time.monotonic() + 60
    while not _catches_sigterm(proc.pid) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.001)
    time.sleep(delay)
    assert proc.poll() is None, "the run ended before the signal could be sent: lengthen it"
    proc.send_signal(signal.SIGTERM)
    _assert_interrupted_cleanly(proc, tmp_path / "out", "SIGTERM")


# --------------------------------------------------------------------------- 3. gains from Python


def _attemperator_with_pi(tmp_dir, **params):
    """The attemperator plant built from Python, its controller a PIController given
    ``params``; and the reference read from the plant file with a PIController."""
    import dnasim
    from dnasim.library.controller import PIController
    from dnasim.plant.plant import Plant

    ref = dnasim.load_plant(_attemperator_pi_file(tmp_dir))
    plant = Plant("att", medium="Water")
    for c in ref.components.values():
        plant.add(PIController("pi", **params) if c.name == "pi" else c)
    for (c, port), node in ref.connections.items():
        plant.connect(f"{c}.{port}", node)
    for (c, inp), (s, out) in ref.links.items():
        plant.link(f"{s}.{out}", f"{c}.{inp}")
    return ref, plant


def test_controller_units_from_python_are_read_as_from_a_plant_file(tmp_path):
    import dnasim

    ref, plant = _attemperator_with_pi(
        tmp_path, Kp="0.02 1/K", KI="6e-4 1/(K.s)", setpoint="450 degC", measured_nominal="700 K"
    )
    pi = dnasim.compile(plant).components["pi"]
    for k in ("Kp", "KI", "measured_nominal"):  # the file gives the same in these units
        assert pi.params[k] == ref.components["pi"].params[k], k
    assert pi.param_at("setpoint", 0.0) == 723.15  # 450 degC


@pytest.mark.parametrize(
    "value, words",
    [
        ("0.02 degC", "absolute temperature"),
        ("0.02 K", "dimension of temperature"),
        ("2 %/bar", "1/temperature is expected"),
    ],
)
def test_controller_gain_from_python_refuses_what_a_plant_file_refuses(value, words, tmp_path):
    import dnasim

    _, plant = _attemperator_with_pi(tmp_path, Kp=value, setpoint=723.15)
    with pytest.raises(dnasim.PlantError, match="component 'pi'") as info:
        dnasim.compile(plant)
    assert "'Kp'" in str(info.value) and words in str(info.value)


def test_controller_gain_per_bar_from_python_for_a_pressure_signal():
    import dnasim
    from dnasim.library.controller import PIController
    from dnasim.model.component import Component, Equation, SignalPort, Variable
    from dnasim.plant.plant import Plant

    class PressureSignal(Component):
        """A constant pressure signal p = 1e5 Pa (test only)."""

        REGISTER = False
        USES_MEDIUM = False
        SIGNAL_OUTPUTS = (SignalPort("p", "Pa", "pressure", variable="p"),)

        def variables(self):
            return [Variable("p", "Pa", 1e5)]

        def equations(self):
            return [Equation("p", y=("p",), residual=lambda t, x, xp: x["p"] - 1e5)]

    plant = Plant("signals")
    plant.add(PressureSignal("src"))
    plant.add(PIController("pi", Kp="2 %/bar", setpoint="1 bar", measured_nominal="1 bar"))
    plant.link("src.p", "pi.measured")
    pi = dnasim.compile(plant).components["pi"]
    # 2 % per bar = 0.02 / 1e5 Pa (relative 1e-12: the unit conversion's rounding)
    assert pi.params["Kp"] == pytest.approx(2e-7, rel=1e-12)
    assert pi.param_at("setpoint", 0.0) == pytest.approx(1e5, rel=1e-12)


def test_cli_results_are_the_csv_sink_of_simulate(tmp_path):
    # one writer (issue 8): `dnasim run` streams through CSVSink and the same rows as
    # simulate(sinks=[CSVSink]); over the set-point step at 2 min (a time event: a left
    # limit and a restart row) the two files are identical, byte for byte
    import dnasim
    from dnasim.plant.plantfile import load
    from dnasim.run.simulation import CSVSink, simulate, simulation_keywords

    loaded = load(PLANTS / "attemperator.toml")
    loaded.simulation.t_end = 150.0
    api = tmp_path / "api.csv"
    t_end, kw = simulation_keywords(loaded.simulation)
    simulate(dnasim.compile(loaded.plant), t_end=t_end, sinks=[CSVSink(api)], **kw)
    res = invoke(
        "run", PLANTS / "attemperator.toml", "-o", tmp_path / "cli", "-q", "--t-end", "150 s"
    )
    assert res.exit_code == 0, res.output
    cli = (tmp_path / "cli" / "results.csv").read_text()
    assert cli == api.read_text()
    restart = read_results_csv(tmp_path / "cli" / "results.csv")[2]["restart"]
    assert restart.sum() >= 1  # the step at 120 s
