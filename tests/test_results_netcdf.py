"""Results as data (issue 24 item 1, issue 23 item 9): results.nc written in blocks
while the run goes, read back by ``dnasim.read_results``; interpolation of Results."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import dnasim
from dnasim.cli.commands import main
from dnasim.run.output import read_results_csv
from dnasim.run.results import Results
from dnasim.run.sinks import NetCDFSink, netcdf_layout

h5py = pytest.importorskip("h5py")
xr = pytest.importorskip("xarray")

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "plants"


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


@pytest.fixture(scope="module")
def attemperator(tmp_path_factory):
    """simulate() of the attemperator over its set-point step at 120 s (a time event:
    a left limit and a restart row), streamed into a NetCDFSink and a CSVSink."""
    from dnasim.plant.plantfile import load
    from dnasim.run.simulation import CSVSink, simulate, simulation_keywords

    d = tmp_path_factory.mktemp("att")
    loaded = load(PLANTS / "attemperator.toml")
    _, kw = simulation_keywords(loaded.simulation)
    res = simulate(
        dnasim.compile(loaded.plant),
        t_end=150.0,
        sinks=[NetCDFSink(d / "r.nc", attrs={"title": "attemperator"}), CSVSink(d / "r.csv")],
        **kw,
    )
    assert res.success and res.restart.sum() >= 1
    return res, d


# --------------------------------------------------------------------------- layout


def test_layout_groups_vectors_into_dimensions():
    names = ["a.p", "pipe.m[0]", "pipe.M[1]", "pipe.M[0]", "pipe.m[1]", "pipe.m[2]", "x[1]"]
    layout = netcdf_layout(names)
    assert layout == [
        ("a.p", [0], None),
        ("pipe.m", [1, 4, 5], "pipe.face"),  # one more than the volumes: the faces
        ("pipe.M", [3, 2], "pipe.volume"),  # positions in index order
        ("x[1]", [6], None),  # no x[0]: not a vector, kept as a column
    ]


# --------------------------------------------------------------------------- round trip


def test_netcdf_round_trip_equals_the_streamed_rows_bit_for_bit(attemperator):
    res, d = attemperator
    nc, csv = dnasim.read_results(d / "r.nc"), dnasim.read_results(d / "r.csv")
    assert isinstance(nc, Results)
    assert nc.names == res.names == csv.names
    np.testing.assert_array_equal(nc.t, res.t)
    np.testing.assert_array_equal(nc.restart, res.restart)
    np.testing.assert_array_equal(csv.restart, res.restart)
    for n in res.names:
        # the two files hold the same rows (the sinks' rows), bit for bit: CSV writes
        # repr (the shortest text that reads back as the same float), netCDF the bits
        np.testing.assert_array_equal(nc[n], csv[n], err_msg=n)
    # against simulate()'s Results, which computes its outputs after the run from the
    # kept y: the unknowns (p, h, masses, energies, flows) are the same bits; derived
    # temperatures come from an iterative T(p, h) warm-started from the previous call,
    # so they may differ in the last bits (3e-14 measured): rtol 1e-12 says "same number"
    unknowns = set(dnasim.compile(_att()).names)
    for n in res.names:
        if n in unknowns:
            np.testing.assert_array_equal(nc[n], res[n], err_msg=n)
        else:
            np.testing.assert_allclose(nc[n], res[n], rtol=1e-12, atol=0, err_msg=n)


def _att():
    from dnasim.plant.plantfile import load

    return load(PLANTS / "attemperator.toml").plant


def test_netcdf_units_on_every_variable(attemperator):
    res, d = attemperator
    nc = dnasim.read_results(d / "r.nc")
    assert nc.units == res.units  # as System.output_units() gives them
    ds = xr.open_dataset(d / "r.nc", engine="h5netcdf")
    try:
        for name, var in ds.variables.items():
            assert var.attrs.get("units"), name
            assert var.attrs["units"] != "-", name  # dimensionless is "1" (UDUNITS)
        assert ds["time"].attrs["units"] == "s"
        assert ds["pipe.T"].attrs["units"] == "K"
        assert ds["pipe.T"].dims == ("time", "pipe.volume")
        assert list(ds["restart"].attrs["flag_values"]) == [0, 1]
        assert ds.attrs["title"] == "attemperator"
        # CSV headers carry the same units ("-" there for dimensionless)
        _, csv_units, _ = read_results_csv(d / "r.csv")
        for n, u in res.units.items():
            assert csv_units[n] == ("-" if u in ("", "1", "-") else u), n
    finally:
        ds.close()


def test_xarray_sel_at_an_event_time_and_the_left_limit(attemperator):
    res, d = attemperator
    t_event = float(res.t[res.restart][0])
    ds = xr.open_dataset(d / "r.nc", engine="h5netcdf")
    left = xr.open_dataset(d / "r.nc", engine="h5netcdf", group="left_limit")
    try:
        assert np.all(np.diff(ds["time"].values) > 0)  # strictly increasing
        after = ds.sel(time=t_event)  # works: no duplicate times
        assert int(after["restart"]) == 1
        nc = dnasim.read_results(d / "r.nc")
        assert float(after["pipe.T_out"]) == nc.at(t_event)["pipe.T_out"]
        before = left.sel(time=t_event)
        # the CSV's row before the restart row is the left limit the group holds
        names, _, data = read_results_csv(d / "r.csv")
        k = int(np.flatnonzero(data["restart"] == 1)[0])
        assert data["time"][k - 1] == t_event
        assert float(before["pi.z"]) == data["pi.z"][k - 1]
    finally:
        ds.close()
        left.close()


# --------------------------------------------------------------------------- dnasim run


def test_run_writes_both_formats_by_default_and_netcdf_alone(tmp_path):
    out = tmp_path / "both"
    r = invoke("run", PLANTS / "air_pipe.toml", "-o", out, "-q", "--t-end", "5 s")
    assert r.exit_code == 0, r.output
    assert (out / "results.csv").exists() and (out / "results.nc").exists()
    a, b = dnasim.read_results(out / "results.nc"), dnasim.read_results(out / "results.csv")
    for n in a.names:
        np.testing.assert_array_equal(a[n], b[n], err_msg=n)
    res = dnasim.read_results(out)  # the folder: results.nc, steps and events beside it
    assert res.success and res.steps.shape[1] == 3 and len(res.steps) > 0
    assert res.stats["steps"] == len(res.steps)  # from the file's stats_* attributes
    _, _, steps = read_results_csv(out / "steps.csv")
    np.testing.assert_array_equal(res.steps[:, 0], steps["time"])
    with h5py.File(out / "results.nc", "r") as f:
        assert f.attrs["status"] == "finished"
        assert f.attrs["simulation_rtol"] > 0 and "plant_file" in f.attrs
    only = tmp_path / "nc"
    r = invoke(
        "run", PLANTS / "air_pipe.toml", "-o", only, "-q", "--t-end", "5 s", "--format", "netcdf"
    )
    assert r.exit_code == 0, r.output
    assert not (only / "results.csv").exists() and (only / "results.nc").exists()
    r = invoke("run", PLANTS / "air_pipe.toml", "-o", only, "--format", "netcdf", "--plot")
    assert r.exit_code == 2 and "--format" in r.output  # plots read results.csv


def _start(out: Path, *extra):
    # tolerances 1e-10: ~1600 steps, a run that outlasts the signal (as in test_faults)
    return subprocess.Popen(
        [sys.executable, "-m", "dnasim", "run", str(PLANTS / "attemperator.toml")]
        + ["-o", str(out), "-q", "--rtol", "1e-10", "--atol-scaled", "1e-10", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
    )


def _wait_for_rows(proc, path: Path, rows: int = 20, timeout: float = 300):
    """Until ``path`` (a CSV written beside the netCDF file) holds ``rows`` lines."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        if path.exists() and path.read_text().count("\n") > rows:
            return
        time.sleep(0.05)
    pytest.fail("the run did not reach its first rows, or ended first")


def _agrees_with_csv(nc: Results, out: Path, closed: bool):
    """The netCDF rows are whole and are the CSV's rows, bit for bit. Closed files
    hold the same rows; after a kill each file holds the blocks it had flushed (each
    sink flushes on its own clock), so only the rows both hold are compared."""
    csv = dnasim.read_results(out / "results.csv")
    for name in nc.names:
        assert np.all(np.isfinite(nc[name])), name  # no unwritten (NaN) cells
    n = min(nc.t.size, csv.t.size)
    assert n > 0
    if closed:
        # the same rows; an interrupt between the two sinks' writes of one row leaves
        # that row in results.csv only (the CSV sink is handed each row first)
        assert nc.t.size in (csv.t.size, csv.t.size - 1)
    np.testing.assert_array_equal(nc.t[:n], csv.t[:n])
    np.testing.assert_array_equal(nc.restart[:n], csv.restart[:n])
    for name in nc.names:
        np.testing.assert_array_equal(nc[name][:n], csv[name][:n], err_msg=name)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_interrupted_run_keeps_whole_rows_in_a_closed_file(tmp_path, sig):
    # the attemperator run at 1e-10, interrupted after its first rows
    out = tmp_path / "out"
    proc = _start(out)
    _wait_for_rows(proc, out / "results.csv")
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 1 and "interrupted" in err, err
    with h5py.File(out / "results.nc", "r") as f:  # closed normally: no SWMR needed
        assert f.attrs["status"] == "interrupted"
    nc = dnasim.read_results(out / "results.nc")
    assert not nc.success
    _agrees_with_csv(nc, out, closed=True)


def test_killed_run_keeps_whole_rows_readable(tmp_path):
    # SIGKILL: no handler, no close; the file must still open and hold whole rows
    out = tmp_path / "out"
    # 120000 rows of 0.01 s: seconds of writing after the first rows, so that the run
    # outlasts the wait below also on an idle machine (at 1e-10 alone it finished first)
    proc = _start(out, "--output-interval", "0.01 s")
    _wait_for_rows(proc, out / "results.csv", rows=40)
    time.sleep(1.5)  # past results.nc's flush_seconds (1 s): it has flushed blocks too
    proc.kill()
    proc.communicate(timeout=60)
    nc = dnasim.read_results(out / "results.nc")
    assert not nc.success and "not closed" in nc.message
    _agrees_with_csv(nc, out, closed=False)


def test_file_size_limit_leaves_whole_rows_and_a_located_error(tmp_path):
    """RLIMIT_FSIZE (no root needed) at 450 kB: results.nc of the attemperator (about
    124 kB of definitions, 8 bytes a value) stops after a block; the error names the
    file and the time, and the file holds the rows before it, closed and readable."""
    import resource

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (450_000, 450_000))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "dnasim", "run", str(PLANTS / "attemperator.toml")]
        + ["-o", str(out), "-q", "--format", "netcdf"],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=limit,
        cwd=ROOT,
    )
    assert proc.returncode == 2, proc.stderr  # an environment error, not a crash
    assert "results.nc" in proc.stderr and "file size limit" in proc.stderr
    assert "whole rows, at simulated time t = " in proc.stderr
    assert "Traceback" not in proc.stderr
    res = dnasim.read_results(out / "results.nc")
    assert res.t.size > 1 and np.all(np.diff(res.t) > 0)
    for name in res.names:
        assert np.all(np.isfinite(res[name])), name


def test_dataframes_merge_and_the_xarray_restart_flag_has_attributes(attemperator):
    res, _ = attemperator
    a = res.to_dataframe()[["pipe.T_out"]]
    b = res.to_dataframe()[["pi.z"]]
    both = a.merge(b, left_index=True, right_index=True)  # attrs compare equal
    assert list(both.columns) == ["pipe.T_out", "pi.z"]
    assert sum(a.attrs["restart"]) == res.restart.sum()
    flag = res.to_xarray()["restart"]
    assert flag.attrs["units"] == "1" and flag.attrs["flag_meanings"].split()[1].startswith("state")


# --------------------------------------------------------------------------- interpolation


def test_at_is_linear_between_output_points_and_exact_at_them():
    t = np.array([0.0, 1.0, 3.0])
    res = Results(t, ["x", "y"], {"x": "K", "y": "Pa"}, np.array([[0.0, 2.0, 6.0], [5, 5, 5]]))
    assert res.at(1.0) == {"x": 2.0, "y": 5.0}
    assert res.at(2.0)["x"] == 4.0  # halfway between 2 and 6
    np.testing.assert_array_equal(res.at([0.5, 3.0], "x")["x"], [1.0, 6.0])
    sub = res.interp([0.5, 2.5])
    np.testing.assert_array_equal(sub["x"], [1.0, 5.0])
    assert sub.units == res.units
    with pytest.raises(ValueError, match="outside"):
        res.at(3.5)


def test_at_on_a_run_matches_an_output_interval_run(attemperator):
    # the attemperator over its first 100 s, every accepted step; interpolated at the
    # points of a second run whose t_eval asks for them: the difference is the linear
    # interpolation's error between steps, well below the outlet's 100 K range (0.5 K)
    res, _ = attemperator
    grid = np.linspace(1.0, 100.0, 12)
    from dnasim.plant.plantfile import load
    from dnasim.run.simulation import simulate, simulation_keywords

    loaded = load(PLANTS / "attemperator.toml")
    t_end, kw = simulation_keywords(loaded.simulation, 100.0, t_eval=grid)
    ref = simulate(dnasim.compile(loaded.plant), t_end=t_end, **kw)
    got = res.at(ref.t)["pipe.T_out"]
    np.testing.assert_allclose(got, ref["pipe.T_out"], atol=0.5)


def test_read_results_of_a_folder_reads_its_events(tmp_path):
    from dnasim.run.output import write_events_csv
    from dnasim.run.sinks import CSVSink

    sink = CSVSink(tmp_path / "results.csv")
    sink.open(["a.x", "restart"], {"a.x": "K"})
    for t, x, r in ((0.0, 1.0, 0.0), (2.0, 3.0, 0.0), (2.0, 4.0, 1.0), (3.0, 5.0, 0.0)):
        sink.write(t, [x, r])
    sink.close()
    log = [{"component": "pi", "switch": "upper", "iterates": [(1.5, 0.2), (2.0, -1e-12)]}]
    write_events_csv(tmp_path / "events.csv", log)
    res = dnasim.read_results(tmp_path)
    np.testing.assert_array_equal(res.t, [0.0, 2.0, 3.0])  # the state after the jump
    np.testing.assert_array_equal(res["a.x"], [1.0, 4.0, 5.0])
    np.testing.assert_array_equal(res.restart, [False, True, False])
    assert res.units == {"a.x": "K"}
    assert res.events == [
        {
            "event": 1,
            "name": "pi.upper",
            "component": "pi",
            "switch": "upper",
            "iterates": [(1.5, 0.2), (2.0, -1e-12)],
            "t": 2.0,
        }
    ]
    assert res.at(2.5)["a.x"] == 4.5


def test_progress_goes_to_stderr_only_when_asked_or_on_a_terminal(tmp_path):
    # CliRunner's streams are not terminals: no progress line by default
    quiet = CliRunner().invoke(
        main, ["run", str(PLANTS / "air_pipe.toml"), "-o", str(tmp_path / "a"), "--t-end", "2 s"]
    )
    assert quiet.exit_code == 0, quiet.output
    assert "simulating" not in quiet.stderr and "simulating" not in quiet.stdout
    shown = CliRunner().invoke(
        main,
        ["run", str(PLANTS / "air_pipe.toml"), "-o", str(tmp_path / "b"), "--t-end", "2 s"]
        + ["--progress"],
    )
    assert shown.exit_code == 0, shown.output
    assert "simulating" in shown.stderr and "simulating" not in shown.stdout
    assert "finished" in shown.stdout  # the summary stays on stdout
