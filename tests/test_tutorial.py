"""docs/tutorial.md: every command of the page runs, and the numbers it quotes hold.

The tutorial is what a new user reads first; if a key is renamed or a default changes
meaning, this test fails before the page misleads anyone. The plant files are
docs/tutorial/*.toml; the page's TOML blocks must be (parts of) those files.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import CoolProp.CoolProp as CP
import numpy as np
import pytest
from click.testing import CliRunner
from scipy.optimize import brentq

from dnasim.cli.commands import main

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "tutorial.md"
LINE = ROOT / "docs" / "tutorial" / "steam_line.toml"
PRV = ROOT / "docs" / "tutorial" / "prv_station.toml"
DRUM_FIRST = ROOT / "docs" / "tutorial" / "drum_boiler_first.toml"
DRUM = ROOT / "docs" / "tutorial" / "drum_boiler.toml"


def _blocks(lang):
    return re.findall(rf"```{lang}\n(.*?)```", PAGE.read_text(), flags=re.S)


def _run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    return result.output


def test_the_pages_plant_files_are_the_shipped_files():
    toml = _blocks("toml")
    assert toml[0] == LINE.read_text()
    files = [f.read_text() for f in sorted((ROOT / "docs" / "tutorial").glob("*.toml"))]
    for block in toml[1:]:
        for table in block.strip().split("\n\n"):  # each table as in one of the files
            assert any(table + "\n" in f for f in files), table[:80]


def test_check_counts_as_quoted():
    out = _run("check", LINE)
    assert re.search(r"equations:\s+86", out) and re.search(r"unknowns:\s+86 \(34 diff", out)


def test_design_point_and_the_hand_calculation(tmp_path):
    _run("steady", LINE, "-o", tmp_path)
    nodes = {
        row.split(",")[0]: row.split(",")
        for row in (tmp_path / "nodes.csv").read_text().splitlines()
    }
    header = [h.split(" [")[0] for h in next(iter(nodes.values()))]
    col = {name: i for i, name in enumerate(header)}
    p_in = float(nodes["n_valve_in"][col["p"]])
    m = float(nodes["n_header"][col["m"]])
    dp = 40e5 - p_in
    assert round(m, 2) == 8.02  # "8.02 kg/s" on the page
    assert round(dp / 1e5, 2) == 1.56  # "1.56 bar"
    # Darcy-Weisbach + Colebrook at the mean pressure, IAPWS properties via CoolProp
    p, T, D, L, eps = 40e5 - dp / 2, 673.15, 0.15, 200.0, 4.5e-5
    rho = CP.PropsSI("D", "P", p, "T", T, "Water")
    mu = CP.PropsSI("V", "P", p, "T", T, "Water")
    v = m / (rho * math.pi * D**2 / 4)
    re_ = rho * v * D / mu
    f = brentq(
        lambda f: 1 / math.sqrt(f) + 2 * math.log10(eps / D / 3.7 + 2.51 / (re_ * math.sqrt(f))),
        1e-4,
        0.1,
    )
    dp_hand = f * L / D * rho * v**2 / 2
    # 1 %: the hand value takes the mean density; along the line rho falls by 4 %, and
    # the mean-value error is of the order of (dp/p)^2, a few tenths of a per cent
    assert dp == pytest.approx(dp_hand, rel=0.01)
    assert round(dp_hand / 1e5, 2) == 1.57


def test_transient_of_the_line(tmp_path):
    out = _run("run", LINE, "-o", tmp_path / "r", "--plot", "--report")
    assert "t = 600 s of 600 s" in out
    for f in ("results.csv", "events.csv", "steps.csv", "variables.png", "report.html"):
        assert (tmp_path / "r" / f).exists(), f


def _column(path, name):
    lines = path.read_text().splitlines()
    header = [h.split(" [")[0] for h in lines[0].split(",")]
    i = header.index(name)
    return np.array([float(r.split(",")[i]) for r in lines[1:]])


def test_prv_station_behaves_as_the_page_says(tmp_path):
    _run("run", PRV, "-o", tmp_path / "prv", "--plot")
    res = tmp_path / "prv" / "results.csv"
    t, p, z = _column(res, "time"), _column(res, "ps.p_s"), _column(res, "pc.z")
    q = _column(res, "line.Q_total")
    assert round((p.max() - 12e5) / 1e5, 1) == 0.4  # "+0.4 bar"
    assert round((12e5 - p.min()) / 1e5, 1) == 0.5  # "-0.5 bar"
    back = (t > 3.5 * 60 + 120) & (t < 9 * 60) | (t > 9.5 * 60 + 120)
    assert np.abs(p[back] - 12e5).max() < 0.01e5  # "within 0.01 bar after two minutes"
    assert [round(z[t <= 170][-1], 2), round(z[t <= 530][-1], 2), round(z[-1], 2)] == [
        0.81,
        0.66,
        0.87,
    ]
    assert round(q[0] / 1e3) == 75  # "75 kW at rest"


def test_sweep_and_linearisation_as_quoted(tmp_path):
    _run(
        "sweep", PRV, "-o", tmp_path / "sw", "--set", "pc.Kp=0.1 1/bar,0.2 1/bar,0.4 1/bar",
        "--set", "simulation.t_end=6 min", "-q",
    )  # fmt: skip
    assert (tmp_path / "sw" / "sweep.nc").exists()
    assert len((tmp_path / "sw" / "summary.csv").read_text().splitlines()) == 4
    out = _run("linearize", PRV, "--inputs", "users.opening", "--outputs", "ps.p_s,prv.m")
    assert re.search(r"-0\.778\d* [+-]2\.12\d*j\s+1\.28\d*\s+0\.344", out), out


def test_the_python_snippet(monkeypatch):
    (snippet,) = _blocks("python")
    monkeypatch.chdir(ROOT)
    exec(compile(snippet.replace("print(", "_ = ("), "tutorial", "exec"), {})


def _design_point(plant, out):
    _run("steady", plant, "-o", out)
    rows = (out / "nodes.csv").read_text().splitlines()
    header = [h.split(" [")[0] for h in rows[0].split(",")]
    return {r.split(",")[0]: dict(zip(header, r.split(","), strict=True)) for r in rows[1:]}


def test_the_drum_boilers_first_try_runs_dry_as_the_page_says(tmp_path):
    nodes = _design_point(DRUM_FIRST, tmp_path / "s")
    assert round(float(nodes["n_steam"]["p"]) / 1e5, 1) == 88.5  # "88.5 bar"
    assert round(float(nodes["n_feed"]["m"]), 2) == 52.95  # "52.95 kg/s"
    result = CliRunner().invoke(main, ["run", str(DRUM_FIRST), "-o", str(tmp_path / "r")])
    assert result.exit_code == 1, result.output
    out = result.output
    assert "drum 'drum' (Drum) ran dry" in out and "t = 703.3" in out and "111.786 bar" in out


def test_the_drum_boiler_with_pressure_control(tmp_path):
    nodes = _design_point(DRUM, tmp_path / "s")
    p = float(nodes["n_steam"]["p"])
    m = float(nodes["n_feed"]["m"])
    assert p == pytest.approx(90e5, rel=1e-9)  # the pressure controller's set point, at rest
    assert round(m, 2) == 42.35
    q = float(
        next(
            r.split(",")[3]
            for r in (tmp_path / "s" / "components.csv").read_text().splitlines()
            if r.startswith("drum,")
        )
    )
    assert round(q / 1e6, 2) == 79.83  # "79.83 MW"
    # the hand balance with IAPWS-95 (CoolProp): Q = m (h''(90 bar) - h(140 bar, 200 degC));
    # 1e-4: IF97 (inside dnasim) and IAPWS-95 differ by that much in h
    h_feed = CP.PropsSI("H", "P", 140e5, "T", 473.15, "Water")
    h_steam = CP.PropsSI("H", "P", 90e5, "Q", 1, "Water")
    assert m == pytest.approx(q / (h_steam - h_feed), rel=1e-4)
    _run("run", DRUM, "-o", tmp_path / "r")
    res = tmp_path / "r" / "results.csv"
    t, level = _column(res, "time"), _column(res, "drum.level")
    feed, steam = _column(res, "feed.m"), -_column(res, "turbine.m")
    swell = (t > 300) & (t < 330)  # the valve opens: more leaves than enters, yet the level rises
    assert level[swell].max() > 2.01 and np.all(steam[swell] > feed[swell])
    shrink = (t >= 18 * 60) & (t <= 18.5 * 60)  # it closes: the level dips first
    assert level[shrink].min() < level[t == 18 * 60][0] - 0.01
