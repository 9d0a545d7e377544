"""report.html and the engineers' plots, from a real run of the seed's Example 2."""

import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from dnasim.cli import main
from dnasim.plots import default_selection, display, merge_identical, quantity_of

PLANT = Path(__file__).parents[1] / "plants" / "attemperator.toml"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("att")
    res = CliRunner().invoke(
        main,
        [
            "run",
            str(PLANT),
            "-o",
            str(out),
            "-q",
            "--plot",
            "--report",
            "--units",
            "engineering",
            "--output-interval",
            "2 s",
        ],
    )
    assert res.exit_code == 0, res.output
    return out


def test_report_is_self_contained(run_dir):
    text = (run_dir / "report.html").read_text()
    # nothing fetched: no external script, stylesheet, import or font
    assert not re.search(r"<script[^>]+src=", text)
    assert not re.search(r"<link[^>]+href=", text)
    assert "@import" not in text
    assert "Plotly.newPlot" in text  # the interactive plots, with plotly embedded
    # the event table with its iterates (Table 10.1) and the plant structure
    assert "Table 10.1" in text and "upper" in text
    assert "Attemperator" in text and "PIDController" in text
    assert "equations" in text and "Fig. 10.7" in text
    # axis titles with quantity and engineering unit (plotly's JSON escapes the degree sign)
    assert re.search(r"temperature \[(°|\\u00b0)C\]", text) and re.search(
        r"mass flow \[t(/|\\u002f)h\]", text
    )


def test_run_plot_and_plot_command_write_the_same_files(run_dir):
    before = {p: (run_dir / p).stat().st_size for p in ("variables.png", "steps.png")}
    for p in before:
        (run_dir / p).unlink()
    res = CliRunner().invoke(main, ["plot", str(run_dir / "results.csv"), "--units", "engineering"])
    assert res.exit_code == 0, res.output
    for p, size in before.items():
        # the same picture: matplotlib's PNG of the same figure, byte sizes within 1 %
        # (the title and the data are the same; only metadata could differ)
        assert (run_dir / p).stat().st_size == pytest.approx(size, rel=0.01)


def test_quantities_are_separate_and_named():
    assert quantity_of("att.T", "K") == "temperature"
    assert quantity_of("pi.z", "-") == "controller output"
    assert quantity_of("pi.e", "-") == "control error"
    assert quantity_of("steam.m", "kg/s") == "mass flow"
    assert quantity_of("pipe.Q_total", "W") == "power"


def test_engineering_units():
    v, u = display(np.array([273.15, 373.15]), "K", "engineering")
    assert u == "°C" and v == pytest.approx([0.0, 100.0])
    assert display(np.array([1e5]), "Pa", "engineering")[0] == pytest.approx([1.0])
    assert display(np.array([1.0]), "kg/s", "engineering")[0] == pytest.approx([3.6])
    assert display(np.array([2e6]), "W", "engineering") == (pytest.approx([2.0]), "MW")
    assert display(np.array([5.0]), "K", "si") == (pytest.approx([5.0]), "K")


def test_default_selection_and_merging(run_dir):
    from dnasim.output import read_results_csv

    names, units, data = read_results_csv(run_dir / "results.csv")
    chosen = default_selection(names[1:], units)
    assert {"att.T", "pipe.T_out", "sensor.T_s", "pi.z", "pi.e", "steam.m"} <= set(chosen)
    # no volume temperatures, no internal controller parts, no flag column
    assert not [n for n in chosen if "[" in n or n.endswith(("m_I", "m_p", "restart"))]
    temps = {n: data[n] for n in chosen if units[n] == "K"}
    groups = merge_identical(data["time"], temps)
    merged = [g for g in groups if len(g) > 1]
    # the attemperator's outlet is its node's temperature, the pipe's outlet its node's
    assert ["att.T", "n_mix.T"] in merged and ["pipe.T_out", "n_line.T"] in merged
    assert len(groups) < len(temps)


def test_set_point_and_limits_are_plotted_when_recorded(tmp_path):
    """With the PIController outputs the lead adds (setpoint in the measured unit,
    z_min, z_max), they are chosen and drawn with their quantities."""
    from dnasim.plots import write_run_plots

    names = ["pi.e", "pi.z", "pi.m_I", "pi.setpoint", "pi.z_min", "pi.z_max", "sensor.T_s"]
    units = {"pi.setpoint": "K", "sensor.T_s": "K"}
    assert default_selection(names, units) == [
        "pi.e",
        "pi.z",
        "pi.setpoint",
        "pi.z_min",
        "pi.z_max",
        "sensor.T_s",
    ]
    assert quantity_of("pi.setpoint", "K") == "temperature"
    assert quantity_of("pi.z_max", "-") == "controller output"
    t = np.linspace(0, 10, 11)
    header = ["time [s]"] + [f"{n} [{units.get(n, '-')}]" for n in names] + ["restart [-]"]
    rows = [[ti, 0.0, 0.5, 0.5, 700.0, 0.0, 1.0, 700.0, 0.0] for ti in t]
    (tmp_path / "results.csv").write_text(
        ",".join(header) + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n"
    )
    files = write_run_plots(tmp_path / "results.csv", units="engineering")
    assert files == [tmp_path / "variables.png"]


def test_bands_that_do_not_overlap_get_their_own_panel():
    from dnasim.plots import split_bands

    data = {
        "water": np.full(5, 473.0),
        "att": np.array([713.0, 713.0, 723.0, 740.0, 755.0]),
        "steam": np.array([773.0, 773.0, 800.0, 873.0, 873.0]),
    }
    # water is 240 K below the rest, 60 % of the 400 K span: its own band
    curves = [["att"], ["water"], ["steam"]]
    assert split_bands(curves, data) == [[["att"], ["steam"]], [["water"]]]
    # curves that overlap stay together
    data["water"] = np.linspace(700.0, 760.0, 5)
    assert split_bands(curves, data) == [curves]


def test_flat_curves_do_not_magnify_round_off():
    from dnasim.plots import y_limits

    flat = 633.15 + 1e-10 * np.sin(np.arange(50))
    lo, hi = y_limits([flat])
    # at least 1e-3 of the magnitude: 0.63 K around 633 K
    assert hi - lo == pytest.approx(0.63315) and lo < 633.15 < hi
    assert y_limits([np.linspace(400.0, 500.0, 5)]) is None


CHROMIUM = next(
    (p for p in ("/usr/bin/chromium", "/usr/bin/chromium-browser") if Path(p).exists()), None
)


@pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (headless)")
def test_report_draws_its_curves_in_headless_chromium(run_dir):
    """The page as a browser shows it: plotly, embedded, draws a line for every curve
    of every figure (the DOM after the scripts ran), with no network access needed."""
    import json
    import shutil
    import subprocess

    text = (run_dir / "report.html").read_text()
    # the figures' own trace lists: the number of curves plotly has to draw
    decoder = json.JSONDecoder()
    n_curves = 0
    for m in re.finditer(r'Plotly\.newPlot\(\s*"[^"]+",\s*', text):
        traces, _ = decoder.raw_decode(text, m.end())
        n_curves += len(traces)
    n_figures = text.count('class="plotly-graph-div"')
    assert n_figures >= 4 and n_curves >= n_figures
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom"]
    if shutil.which("unshare") and subprocess.run(["unshare", "-n", "true"]).returncode == 0:
        cmd = ["unshare", "-n", *cmd]  # no network at all: the page must not need it
    dom = subprocess.run(
        [*cmd, (run_dir / "report.html").as_uri()],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    assert dom.count('class="main-svg"') >= n_figures  # every figure drawn
    # one group per curve, each with a drawn line (the legend's samples are js-lines too)
    traces = dom.split('<g class="trace scatter')[1:]  # each up to the next curve
    assert len(traces) == n_curves
    assert all(re.search(r'class="js-line"[^>]*\sd="M-?[0-9.]+,-?[0-9.]+[LHV]', g) for g in traces)
