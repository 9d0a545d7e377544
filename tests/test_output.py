"""dnasim.run.output: streaming CSV, events/steps CSV, plots."""

import csv
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from dnasim.run.output import (
    StreamingCSV,
    column_header,
    event_rows,
    parse_column_header,
    plot_steps,
    read_results_csv,
    select_variables,
    write_events_csv,
    write_steps_csv,
)


def test_header_units():
    assert column_header("time", "s") == "time [s]"
    assert column_header("pipe1.T_out", "K") == "pipe1.T_out [K]"
    assert column_header("pi.output", "1") == "pi.output [-]"
    assert column_header("x", None) == "x [-]"
    assert parse_column_header("pipe1.T_out [K]") == ("pipe1.T_out", "K")
    assert parse_column_header("htc [W/(m2.K)]") == ("htc", "W/(m2.K)")
    assert parse_column_header("plain") == ("plain", "")


def test_streaming_roundtrip_is_exact(tmp_path):
    path = tmp_path / "r.csv"
    values = [0.1, 1 / 3, 1e-300, -2.5e17, 813.15]
    with StreamingCSV(path, ["time [s]", "a.x [K]"], flush_rows=2) as w:
        for i, v in enumerate(values):
            w.write_row([float(i), v])
    names, units, data = read_results_csv(path)
    assert names == ["time", "a.x"] and units == {"time": "s", "a.x": "K"}
    assert data["a.x"].tolist() == values  # repr round-trips floats exactly


def test_flush_every_n_rows_leaves_whole_lines_on_disk(tmp_path):
    path = tmp_path / "r.csv"
    w = StreamingCSV(path, ["time [s]", "v [-]"], flush_rows=3, flush_seconds=1e9)
    for i in range(7):
        w.write_row([i, 2 * i])
    # 6 rows flushed, the 7th still buffered; the file ends with a newline
    text = path.read_text()
    assert text.endswith("\n")
    assert len(text.splitlines()) == 1 + 6
    w.close()
    assert len(path.read_text().splitlines()) == 1 + 7
    w.close()  # twice is fine


def test_flush_after_seconds(tmp_path):
    path = tmp_path / "r.csv"
    w = StreamingCSV(path, ["time [s]"], flush_rows=10**6, flush_seconds=0.0)
    w.write_row([1.0])
    assert len(path.read_text().splitlines()) == 2
    w.close()


def test_writer_refuses_wrong_width_and_writes_after_close(tmp_path):
    w = StreamingCSV(tmp_path / "r.csv", ["time [s]", "a [-]"])
    with pytest.raises(ValueError):
        w.write_row([1.0])
    w.close()
    with pytest.raises(ValueError):
        w.write_row([1.0, 2.0])


def test_killed_writer_leaves_parsable_csv(tmp_path):
    """SIGKILL (no clean-up at all) after some flushes: the file still parses."""
    path = tmp_path / "r.csv"
    code = textwrap.dedent(
        f"""
        import os, signal
        from dnasim.run.output import StreamingCSV
        w = StreamingCSV({str(path)!r}, ["time [s]", "a [-]", "b [-]"], flush_rows=7)
        for i in range(1000):
            w.write_row([i * 0.5, i, -i])
        os.kill(os.getpid(), signal.SIGKILL)
        """
    )
    proc = subprocess.run([sys.executable, "-c", code])
    assert proc.returncode != 0
    names, units, data = read_results_csv(path)
    n = len(data["time"])
    assert n == 994  # 142 flushes of 7 rows
    assert data["time"][-1] == (n - 1) * 0.5


def test_read_results_ignores_a_torn_last_line(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time [s],a [K]\n0,1\n1,2\n2,")
    _, _, data = read_results_csv(path)
    assert data["time"].tolist() == [0.0, 1.0]


def test_events_csv_table_10_1(tmp_path):
    log = [
        {
            "event": 0,
            "name": "pi.saturation",
            "t": 216.8363,
            "iterates": [
                (211.55, 0.19e-2),
                (264.50, -0.0176),
                (216.9019, -2.0e-5),
                (216.8363, 5e-10),
            ],
        }
    ]
    n = write_events_csv(tmp_path / "events.csv", log)
    assert n == 4
    with open(tmp_path / "events.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["event", "iteration", "time", "switch_value", "component", "switch"]
    assert [int(r["iteration"]) for r in rows] == [1, 2, 3, 4]
    assert {r["component"] for r in rows} == {"pi"} and {r["switch"] for r in rows} == {
        "saturation"
    }
    assert float(rows[-1]["switch_value"]) == 5e-10
    assert float(rows[-1]["time"]) == 216.8363


def test_event_rows_prefer_explicit_component_and_switch():
    rows = event_rows(
        [{"name": "x", "component": "a.b", "switch": "sat", "iterates": [(1.0, 0.0)]}]
    )
    assert rows == [(1, 1, 1.0, 0.0, "a.b", "sat")]


def test_empty_events_csv_has_header(tmp_path):
    write_events_csv(tmp_path / "e.csv", [])
    assert (tmp_path / "e.csv").read_text().strip() == (
        "event,iteration,time,switch_value,component,switch"
    )


def test_steps_csv(tmp_path):
    hist = np.array([[0.1, 0.1, 1], [0.3, 0.2, 2], [0.7, 0.4, 3]])
    assert write_steps_csv(tmp_path / "s.csv", hist) == 3
    with open(tmp_path / "s.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["time", "step_size", "order"]
    assert [int(r["order"]) for r in rows] == [1, 2, 3]
    assert float(rows[1]["step_size"]) == 0.2


def test_steps_csv_unknown_order_is_empty(tmp_path):
    write_steps_csv(tmp_path / "s.csv", [(1.0, 1.0, math.nan)])
    lines = (tmp_path / "s.csv").read_text().splitlines()
    assert lines[1] == "1.0,1.0,"


def test_select_variables():
    names = ["pipe1.T_out", "pipe1.p_out", "pipe2.T_out", "pi.output"]
    assert select_variables(names, ["*.T_out"]) == ["pipe1.T_out", "pipe2.T_out"]
    assert select_variables(names, ["pipe1"]) == ["pipe1.T_out", "pipe1.p_out"]
    assert select_variables(names, ["pi.output", "pipe2.*"]) == ["pipe2.T_out", "pi.output"]
    assert select_variables(names, None) == names
    assert select_variables(names, ["nothing"]) == []


def test_plots_are_pngs(tmp_path):
    t = np.linspace(0, 600, 50)
    from dnasim.tools.plots import plot_quantities

    data = {"a.T": 300 + t / 10, "b.m": np.sin(t)}
    p1 = plot_quantities(t, data, ["a.T", "b.m"], {"a.T": "K", "b.m": "kg/s"}, tmp_path / "v.png")
    p2 = plot_steps(
        np.array([[1, 1, 1], [3, 2, 2], [7, 4, 3]]), tmp_path / "s.png", event_times=[2]
    )
    for p in (p1, p2):
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert os.path.getsize(p) > 1000
