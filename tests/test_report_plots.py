"""report.html and the engineers' plots, from real runs of plants/ (issue 24 items 2, 3).

The report: its data block holds every results column with its unit, its schematic
every component, node and link, the event table collapses under a summary line,
plotly is one file per folder (not embedded), every plant string is escaped.
The plots: the default selection by quantity on real plants (pressures, levels,
powers, duties, controller measured value against set point, outputs), one unit
per axis, no constants drawn, the plant's name as title. The browser checks are in
tests/test_report_browser.py (headless Chromium, where present).
"""

from __future__ import annotations

import base64
import dataclasses
import json
import re
import shutil
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.run.output import read_results_csv
from dnasim.tools.plots import default_selection, display, merge_identical, quantity_of

PLANTS = Path(__file__).parents[1] / "plants"


def run(out: Path, plant: str, *extra: str) -> Path:
    res = CliRunner().invoke(
        main,
        ["run", str(PLANTS / f"{plant}.toml"), "-o", str(out), "-q", *extra],
        catch_exceptions=False,
    )
    assert res.exit_code == 0, res.output
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Each plant run once, with --plot and --report in engineering units."""
    cache: dict[str, Path] = {}

    def get(name: str, *extra: str) -> Path:
        if name not in cache:
            out = tmp_path_factory.mktemp(name)
            cache[name] = run(out, name, "--plot", "--report", "--units", "engineering", *extra)
        return cache[name]

    return get


@pytest.fixture(scope="module")
def run_dir(runs):
    return runs("attemperator", "--output-interval", "2 s")


def page_data(text: str) -> dict:
    m = re.search(r"<script type='application/json' id='dnasim-data'>(.*?)</script>", text, re.S)
    assert m, "the report has no data block"
    return json.loads(m.group(1))


def decode(var: dict, n: int) -> np.ndarray:
    d = var["data"]
    if "c" in d:
        return np.full(n, np.nan if d["c"] is None else d["c"])
    return d["b"] + np.frombuffer(base64.b64decode(d["d"]), dtype="<f4").astype(float)


def svg_of(text: str) -> ET.Element:
    m = re.search(r"<svg class=\"schematic\".*?</svg>", text, re.S)
    assert m, "the report has no schematic"
    return ET.fromstring(m.group(0))


# --------------------------------------------------------------------------- the report


def test_report_is_small_and_loads_plotly_from_its_folder(run_dir):
    """plotly is plotly.min.js beside the page, not embedded: the page of this plant
    was 5.0 MB with plotly inside (main at 83b0bb2), it is now about 0.2 MB."""
    text = (run_dir / "report.html").read_text()
    size = (run_dir / "report.html").stat().st_size
    assert size < 600_000, size  # 219 kB measured; plotly alone is 4.8 MB
    # the only external script is the relative plotly file; nothing from the network
    assert re.findall(r"<script[^>]+src=['\"]([^'\"]+)", text) == ["plotly.min.js"]
    assert not re.search(r"(src|href)=['\"]?(https?:)?//", text)
    assert not re.search(r"<link[^>]+href=", text) and "@import" not in text
    js = run_dir / "plotly.min.js"
    from dnasim.tools.report import _plotly_source

    assert js.read_bytes() == _plotly_source()
    # the run and the report's sections
    assert "Attemperator" in text and "PIDController" in text
    assert "Table 10.1" in text and "Fig. 10.7" in text and "equations" in text


def test_plotly_is_written_once_per_folder(run_dir, tmp_path):
    from dnasim.tools.report import write_plotly_js

    js = run_dir / "plotly.min.js"
    stat = js.stat()
    path, written = write_plotly_js(run_dir)
    assert (path, written) == (js, False)  # there and identical: left alone
    assert js.stat().st_ino == stat.st_ino and js.stat().st_mtime_ns == stat.st_mtime_ns
    # another version (or a torn copy) is replaced
    other = tmp_path / "plotly.min.js"
    other.write_text("/* plotly 1.0 */")
    assert write_plotly_js(tmp_path) == (other, True)
    assert other.stat().st_size > 1_000_000


def test_browser_data_holds_every_variable_with_its_unit(run_dir):
    names, units, data = read_results_csv(run_dir / "results.csv")
    page = page_data((run_dir / "report.html").read_text())
    variables = {v["name"]: v for v in page["vars"]}
    assert list(variables) == [n for n in names if n not in ("time", "restart")]
    n = page["rows"]["shown"]
    assert page["rows"] == {"shown": len(data["time"]), "of": len(data["time"])}
    t = np.frombuffer(base64.b64decode(page["time"]), dtype="<f8")
    assert np.array_equal(t, data["time"])  # float64: event times to the bit
    for name, v in variables.items():
        assert v["unit"] == ("-" if units[name] in ("1", "-") else units[name]), name
        assert v["quantity"] == quantity_of(name, units[name])
        x = data[name]
        # statistics from the full float64 data
        assert v["final"] == pytest.approx(x[-1], rel=1e-15, abs=1e-300)
        assert v["min"] == x.min() and v["max"] == x.max()
        # values: float32 differences from the first value: 2^-23 of the largest
        # difference (the variation, not the magnitude, keeps its seven digits)
        span = np.abs(x - x[0]).max()
        np.testing.assert_allclose(decode(v, n), x, rtol=0, atol=span * 2.0**-23 + 1e-300)


def test_browser_groups_by_component_and_quantity(run_dir):
    page = page_data((run_dir / "report.html").read_text())
    v = {x["name"]: x for x in page["vars"]}
    assert v["att.T"]["owner"] == "att" and v["att.T"]["kind"] == "component"
    assert v["n_mix.p"]["owner"] == "n_mix" and v["n_mix.p"]["kind"] == "node"
    assert v["pipe.T[2]"]["quantity"] == "temperature" and v["pi.e"]["unit"] == "delta_K"
    assert page["components"]["pi"] == {"type": "PIDController", "kind": "controller"}
    assert page["units"] == "engineering" and page["engineering"]["Pa"] == ["bar", 1e-5, 0.0]


def test_schematic_holds_every_component_node_and_link(run_dir):
    import dnasim.plant.plantfile as pf

    plant = pf.load(PLANTS / "attemperator.toml").plant
    svg = svg_of((run_dir / "report.html").read_text())
    ns = {"s": "http://www.w3.org/2000/svg"}
    comps = {
        g.get("data-comp")
        for g in svg.iterfind(".//s:g[@class]", ns)
        if "comp" in g.get("class").split()
    }
    nodes = {
        g.get("data-node")
        for g in svg.iterfind(".//s:g[@class]", ns)
        if "node" in g.get("class").split()
    }
    assert comps == set(plant.components) and nodes == set(plant.node_names())
    kinds = {
        g.get("data-comp"): g.get("class").split()[1]
        for g in svg.iterfind(".//s:g[@class]", ns)
        if "comp" in g.get("class").split()
    }
    assert kinds == {
        "steam": "kind-boundary",
        "water": "kind-boundary",
        "spray_valve": "kind-valve",
        "att": "kind-attemperator",
        "sensor": "kind-sensor",
        "pi": "kind-controller",
        "pipe": "kind-pipe",
        "turbine_valve": "kind-valve",
        "turbine": "kind-boundary",
    }
    flows = [p for p in svg.iterfind(".//s:path", ns) if "flow" in p.get("class", "").split()]
    signals = [p for p in svg.iterfind(".//s:path", ns) if p.get("class") == "signal"]
    taps = list(svg.iterfind(".//s:line[@class='tap']", ns))
    fluid = {(c, n) for (c, p), n in plant.connections.items() if c != "sensor"}
    assert {(p.get("data-comp"), p.get("data-node")) for p in flows} == fluid
    assert len(flows) == len(fluid)
    assert {(p.get("data-source"), p.get("data-target")) for p in signals} == {
        ("pi", "spray_valve.z"),
        ("sensor", "pi.measured"),
    }
    assert [(t.get("data-comp"), t.get("data-node")) for t in taps] == [("sensor", "n_mix")]
    # water and steam lines are drawn as water, every inlet gets an arrow
    assert all("water" in p.get("class") for p in flows)
    # left to right along the flow: the steam source, the attemperator, the pipe, the
    # turbine valve and the turbine's boundary follow each other
    x = {
        g.get("data-comp"): float(re.match(r"translate\(([-\d.]+)", g.get("transform")).group(1))
        for g in svg.iterfind(".//s:g[@data-comp]", ns)
    }
    assert x["steam"] < x["att"] < x["pipe"] < x["turbine_valve"] < x["turbine"]
    assert x["water"] < x["spray_valve"] < x["att"]


def test_schematic_of_a_closed_loop_and_two_fluids(tmp_path):
    """The Rankine cycle's loop is broken at the pump: pump, economiser, drum,
    superheater, turbine and condenser from left to right; flue gas lines are gas."""
    from dnasim.plant.plantfile import load
    from dnasim.plant.plantinfo import describe_loaded
    from dnasim.tools.schematic import layout, schematic_svg

    loaded = load(PLANTS / "rankine.toml")
    desc = describe_loaded(loaded, loaded.plant.compile())
    lay = layout(desc, {"cw_supply": 800.0, "flue_gas": 60.0, "stack": -60.0, "cw_return": -800.0})
    x = {k[1]: v.x for k, v in lay.vertices.items() if k[0] == "c"}
    assert x["pump"] < x["economiser"] < x["drum"] < x["superheater"] < x["turbine"]
    assert x["turbine"] < x["condenser"]
    svg = ET.fromstring(schematic_svg(desc))
    ns = {"s": "http://www.w3.org/2000/svg"}
    flows = [p for p in svg.iterfind(".//s:path", ns) if "flow" in p.get("class", "").split()]
    gas = {p.get("data-node") for p in flows if "gas" in p.get("class").split()}
    assert gas == {"g_in", "g_sh", "g_eco", "g_stack"}
    # symbols do not overlap
    boxes = [(v.x, v.y, v.w, v.h) for k, v in lay.vertices.items() if k[0] == "c"]
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert abs(a[0] - b[0]) >= (a[2] + b[2]) / 2 or abs(a[1] - b[1]) >= (a[3] + b[3]) / 2


def test_event_table_collapses_under_a_summary(runs):
    """The evaporator's 136 rows of iterates are collapsed under one line that says
    how many switches were located and which fired how often."""
    out = runs("evaporator", "--t-end", "7 min")
    text = (out / "report.html").read_text()
    m = re.search(r"<details class='events'( open)?><summary>(.*?)</summary>", text)
    assert m and m.group(1) is None  # collapsed
    rows = len((out / "events.csv").read_text().splitlines()) - 1
    assert rows > 20
    assert m.group(2) == (
        f"9 located switches: evaporator: cold_h_v[i] saturated liquid × 9 ({rows} rows of "
        "iterates)"
    )
    # a short table stays open (the attemperator: one switch)
    att = (runs("attemperator", "--output-interval", "2 s") / "report.html").read_text()
    m = re.search(r"<details class='events'( open)?><summary>(.*?)</summary>", att)
    assert m and m.group(1) == " open" and m.group(2).startswith("1 located switch: pi: upper")


def test_event_summary_counts_locations_not_iterates():
    from dnasim.tools.report import event_summary

    header = ["event", "iteration", "time", "switch_value", "component", "switch"]
    rows = [
        ["1", "1", "1.0", "2", "pi", "upper"],
        ["1", "2", "1.1", "-1", "pi", "upper"],
        ["2", "1", "5.0", "1", "pi", "upper"],
        ["3", "1", "7.0", "1", "pipe", "h_v[3] saturated liquid"],
        ["4", "1", "8.0", "1", "pipe", "h_v[4] saturated liquid"],
    ]
    assert event_summary(header, rows) == (
        4,
        [("pi: upper", 2), ("pipe: h_v[i] saturated liquid", 2)],
    )


class _Elements(HTMLParser):
    def __init__(self):
        super().__init__()
        self.elements = []

    def handle_starttag(self, tag, attrs):
        self.elements.append((tag, dict(attrs)))


EVIL = '<img src=x onerror="alert(1)">'


def test_no_markup_from_plant_strings(tmp_path):
    """Names, description and node names full of markup stay text: no element, no
    event handler, no script comes from them (the page, the SVG and the JSON)."""
    from dnasim.library import Pipe, PressureBoundary, Valve
    from dnasim.plant.plant import Plant
    from dnasim.plant.plantfile import load
    from dnasim.run.runner import run_plant
    from dnasim.tools.report import write_report

    base = load(PLANTS / "air_pipe.toml")
    p = Plant('<script>alert("plant")</script>', medium="Air")
    src, pipe, valve = EVIL, "pipe</script><script>alert(2)</script>", "v'\"&<>"
    p.add(PressureBoundary(src, p=2.0e5, T=600.0))
    p.add(Pipe(pipe, V=0.08, kA=157.0, k=1.2e5, C_wall=6.2e4, m_nominal=0.1, p0=1.99e5, T0=300.0))
    p.add(Valve(valve, C=3.2e-4, opening=1.0, m_nominal=0.1))
    p.add(PressureBoundary("sink", p=1.0e5, m_nominal=0.1))
    for port, node in (
        (f"{src}.port", "n<b>in"),
        (f"{pipe}.inlet", "n<b>in"),
        (f"{pipe}.outlet", "n'out\""),
        (f"{valve}.inlet", "n'out\""),
        (f"{valve}.outlet", "n_sink"),
        ("sink.port", "n_sink"),
    ):
        p.connect(port, node)
    spec = dataclasses.replace(base.spec, description="<iframe src=javascript:alert(3)>")
    sim = dataclasses.replace(base.simulation, t_end=5.0)
    loaded = type(base)(p, sim, spec, "<svg onload=alert(4)>.toml")
    outcome = run_plant(loaded, tmp_path)
    assert outcome.success, outcome.message
    text = write_report(outcome, loaded, tmp_path).read_text()
    for raw in ("<script>alert", "<img", "<iframe", "<svg onload", "n<b>in", "</script><script>"):
        assert raw not in text
    parser = _Elements()
    parser.feed(text)
    tags = [t for t, _ in parser.elements]
    assert tags.count("script") == 3  # the data block, plotly.min.js, the page's script
    assert not [t for t in tags if t in ("img", "iframe")]
    assert tags.count("b") == 7  # the page's own: the facts under the title
    assert not [(t, a) for t, a in parser.elements for k in a if k.lower().startswith("on")]
    # the names are there, as text
    page = page_data(text)
    assert page["plant"]["name"] == '<script>alert("plant")</script>'
    assert {v["owner"] for v in page["vars"]} >= {src, pipe, valve, "n<b>in", "n'out\""}
    svg = svg_of(text)
    assert {g.get("data-comp") for g in svg.iter() if g.get("data-comp")} >= {src, pipe, valve}
    assert "&lt;script&gt;alert(&quot;plant&quot;)&lt;/script&gt;" in text


# --------------------------------------------------------------------------- the plots


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


def panels_of(out: Path):
    from dnasim.plant.plantinfo import read_plant_json
    from dnasim.tools.plots import select_panels

    names, units, data = read_results_csv(out / "results.csv")
    plant = read_plant_json(out)
    assert plant is not None
    panels, constants = select_panels(names[1:], units, data, plant)
    return panels, constants, units, data


def assert_one_unit_per_axis(panels, units, data):
    from dnasim.tools.plots import is_constant

    for p in panels:
        assert {units[n] for n in p.names} == {p.unit}, (p.quantity, p.names)
        for c in p.curves:
            # nothing drawn is a constant: the first name's curve changes over the run
            # (a controller's set point is drawn against its measured value even when
            # it is constant: it is the reference)
            if not (p.title and c.dashed):
                assert not is_constant(c.sign * data[c.names[0]], 0.0, p.unit), c.names


def find(panels, name):
    return [p for p in panels if name in p.names]


def test_drum_boiler_selection(runs):
    """Pressure, level, heat input, flows, the level controller's measured liquid
    volume against its set point (both m3), its output; the sink's 0.5 bar is a
    constant, listed, not drawn."""
    panels, constants, units, data = panels_of(runs("drum_boiler"))
    assert_one_unit_per_axis(panels, units, data)
    q = [(p.quantity, p.unit, p.title) for p in panels]
    assert q[:2] == [("pressure", "Pa", ""), ("level", "m", "")]
    assert find(panels, "drum.p")[0].quantity == "pressure"
    assert find(panels, "drum.level")[0].quantity == "level"
    assert find(panels, "drum.Q_in")[0].quantity == "heat flow"
    ctrl = [p for p in panels if p.title == "level_pi"]
    assert len(ctrl) == 1 and ctrl[0].unit == "m3"
    assert [(c.names, c.dashed) for c in ctrl[0].curves] == [
        (["drum.V_l"], False),
        (["level_pi.setpoint"], True),
    ]
    out = [p for p in panels if p.quantity == "controller output"]
    assert len(out) == 1 and out[0].names == ["level_pi.z"] and out[0].limits == (0.0, 1.0)
    # the sink lets steam out: drawn as -m, out of the plant, merged with the valve
    flows = find(panels, "sink.m")[0]
    curve = next(c for c in flows.curves if "sink.m" in c.names)
    assert curve.label == "steam_valve.m = -sink.m (out of the plant)"
    assert (curve.sign * data[curve.names[0]]).mean() > 0 and data["sink.m"].mean() < 0
    assert ("n_sink.p", 0.5e5, "Pa") in [(n, pytest.approx(v), u) for n, v, u in constants]
    drawn = {n for p in panels for n in p.names}
    assert not drawn & {n for n, _, _ in constants}
    assert not [n for n in drawn if n.endswith(("z_min", "z_max", "m_I", "restart"))]


def test_feedwater_heater_selection(runs):
    """Powers of both turbines on one axis, the deaerator level against its set
    point (and only there), pressures in bands that do not squeeze each other."""
    panels, constants, units, data = panels_of(runs("feedwater_heater"))
    assert_one_unit_per_axis(panels, units, data)
    power = find(panels, "hp.P")
    assert len(power) == 1 and set(power[0].names) == {"hp.P", "lp.P"}
    assert power[0].quantity == "power"
    level = find(panels, "deaerator.level")
    assert len(level) == 1 and level[0].title == "level_pi"
    assert level[0].names == ["deaerator.level", "level_pi.setpoint"]
    assert find(panels, "deaerator.p")[0].quantity == "pressure"
    assert "n_live.p" in {n for n, _, _ in constants}  # a fixed boundary pressure


def test_attemperator_selection_keeps_temperatures_and_differences_apart(run_dir):
    panels, constants, units, data = panels_of(run_dir)
    assert_one_unit_per_axis(panels, units, data)
    ctrl = [p for p in panels if p.title == "pi"][0]
    assert ctrl.unit == "K" and ctrl.names == ["sensor.T_s", "pi.setpoint"]
    assert ctrl.quantity == "temperature"
    temps = [p for p in panels if p.quantity == "temperature" and not p.title]
    assert "att.T" in {n for p in temps for n in p.names}
    assert "sensor.T_s" not in {n for p in temps for n in p.names}  # it has its own panel
    assert not [p for p in panels if p.unit == "delta_K"]  # the error is not a default
    assert "pipe.Q_total" in {n for n, _, _ in constants}  # an adiabatic pipe: 0 W


def test_evaporator_selection(runs):
    panels, constants, units, data = panels_of(runs("evaporator", "--t-end", "7 min"))
    assert_one_unit_per_axis(panels, units, data)
    assert find(panels, "evaporator.Q_total")[0].quantity == "heat flow"
    assert find(panels, "w_in.p")[0].quantity == "pressure"
    assert {"feedwater.m", "flue_gas.m"} <= {n for n, _, _ in constants}


def test_no_two_units_share_an_axis():
    """Set points and errors of controllers that measure different quantities
    (main put 'set point [m]' over a bar and a metre set point)."""
    from dnasim.tools.plots import select_panels

    names = [
        "lc.e", "lc.z", "lc.m_I", "lc.setpoint", "pc.e", "pc.z", "pc.m_I", "pc.setpoint",
        "drum.level", "drum.p",
    ]  # fmt: skip
    units = {
        "lc.e": "m", "lc.setpoint": "m", "pc.e": "Pa", "pc.setpoint": "Pa",
        "drum.level": "m", "drum.p": "Pa",
    }  # fmt: skip
    t = np.linspace(0.0, 10.0, 11)
    data = {n: np.sin(t + i) + 2.0 for i, n in enumerate(names)}
    ctrls = [
        {
            "name": c,
            "measured": m,
            "setpoint": f"{c}.setpoint",
            "output": f"{c}.z",
            "error": f"{c}.e",
        }
        for c, m in (("lc", "drum.level"), ("pc", "drum.p"))
    ]
    plant = {"nodes": [], "components": [], "controllers": ctrls}
    panels, _ = select_panels(names, units, data, plant)
    for p in panels:
        assert len({units.get(n, "-") for n in p.names}) == 1
    assert [(p.title, p.unit, p.names) for p in panels if p.title] == [
        ("lc", "m", ["drum.level", "lc.setpoint"]),
        ("pc", "Pa", ["drum.p", "pc.setpoint"]),
    ]
    # without plant.json the measured value is unknown: the set point and the error
    panels, _ = select_panels(names, units, data, None)
    assert [(p.title, p.quantity, p.unit) for p in panels if p.title] == [
        ("lc", "length", "m"),
        ("lc", "control error", "m"),
        ("pc", "pressure", "Pa"),
        ("pc", "control error", "Pa"),
    ]
    for p in panels:
        assert len({units.get(n, "-") for n in p.names}) == 1


def test_vars_still_choose_and_engineering_units_still_convert(runs, tmp_path):
    from dnasim.tools.plots import panels_for

    out = runs("drum_boiler")
    names, units, data = read_results_csv(out / "results.csv")
    panels = panels_for(["drum.p", "drum.level", "n_sink.p"], units, data)
    # asked for: drawn, constants too, one unit per panel
    assert [(p.quantity, p.unit, p.names) for p in panels] == [
        ("pressure", "Pa", ["drum.p", "n_sink.p"]),
        ("level", "m", ["drum.level"]),
    ]
    target = tmp_path / "v.png"
    res = CliRunner().invoke(
        main,
        ["plot", str(out / "results.csv"), "--vars", "drum.*", "-o", str(target)],
    )
    assert res.exit_code == 0, res.output
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    v, u = display(np.array([1e5, 2e5]), "Pa", "engineering")
    assert u == "bar" and v.tolist() == [1.0, 2.0]
    # kW below 1 MW on an axis of small powers
    assert display(np.array([4e4]), "W", "engineering", 4e4)[1] == "kW"


def test_plot_title_is_the_plant_name(runs, tmp_path, monkeypatch):
    """The title is the plant's name and description (plant.json), also for
    `dnasim plot` on a copied folder; not the CSV's path."""
    import dnasim.tools.plots as plots

    out = runs("drum_boiler")
    copy = tmp_path / "copied"
    copy.mkdir()
    for f in ("results.csv", "plant.json", "events.csv", "steps.csv"):
        shutil.copy(out / f, copy / f)
    seen = {}
    real = plots.plot_panels

    def spy(*args, **kwargs):
        seen.update(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(plots, "plot_panels", spy)
    res = CliRunner().invoke(main, ["plot", str(copy / "results.csv"), "--units", "engineering"])
    assert res.exit_code == 0, res.output
    assert seen["title"] == "drum_boiler"
    assert seen["subtitle"].startswith("Drum boiler start-up with level control")
    assert "results.csv" not in seen["title"] + seen["subtitle"]
    assert seen["note"].startswith("constant over the run (not drawn): n_sink.p = 0.5 bar")
    # without plant.json: the run's folder
    (copy / "plant.json").unlink()
    res = CliRunner().invoke(main, ["plot", str(copy / "results.csv")])
    assert res.exit_code == 0 and seen["title"] == "copied"


def test_quantities_are_separate_and_named():
    assert quantity_of("att.T", "K") == "temperature"
    assert quantity_of("pi.z", "-") == "controller output"
    assert quantity_of("pi.e", "-") == "control error"
    assert quantity_of("steam.m", "kg/s") == "mass flow"
    assert quantity_of("pipe.Q_total", "W") == "heat flow"
    assert quantity_of("turbine.P", "W") == "power"
    assert quantity_of("drum.level", "m") == "level"
    assert quantity_of("pump.H", "m") == "head"
    assert quantity_of("condenser.x", "-") == "quality"
    assert quantity_of("pi.setpoint", "K") == "temperature"


def test_engineering_units():
    v, u = display(np.array([273.15, 373.15]), "K", "engineering")
    assert u == "°C" and v == pytest.approx([0.0, 100.0])
    assert display(np.array([1e5]), "Pa", "engineering")[0] == pytest.approx([1.0])
    assert display(np.array([1.0]), "kg/s", "engineering")[0] == pytest.approx([3.6])
    assert display(np.array([2e6]), "W", "engineering") == (pytest.approx([2.0]), "MW")
    assert display(np.array([5.0]), "K", "si") == (pytest.approx([5.0]), "K")


def test_default_selection_and_merging(run_dir):
    names, units, data = read_results_csv(run_dir / "results.csv")
    chosen = default_selection(names[1:], units)
    assert {"att.T", "pipe.T_out", "sensor.T_s", "pi.z", "steam.m", "att.p_v"} <= set(chosen)
    # no volume temperatures, no internal controller parts, no flag column
    assert not [n for n in chosen if "[" in n or n.endswith(("m_I", "m_p", "restart"))]
    temps = {n: data[n] for n in chosen if units[n] == "K"}
    groups = merge_identical(data["time"], temps)
    merged = [g for g in groups if len(g) > 1]
    # the attemperator's outlet is its node's temperature, the pipe's outlet its node's
    assert ["att.T", "n_mix.T"] in merged and ["pipe.T_out", "n_line.T"] in merged
    assert len(groups) < len(temps)


def test_bands_that_do_not_overlap_get_their_own_panel():
    from dnasim.tools.plots import split_bands

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
    # far apart by ratio: a condenser at 0.08 bar beside a duct at 1 bar
    p = {
        "cond": np.array([8e3, 9e3]),
        "duct": np.array([1.0e5, 1.02e5]),
        "drum": np.array([9e6, 1e7]),
    }
    assert split_bands([["cond"], ["duct"], ["drum"]], p, gap=np.inf) == [
        [["drum"]],
        [["duct"]],
        [["cond"]],
    ]


def test_flat_curves_do_not_magnify_round_off():
    from dnasim.tools.plots import y_limits

    flat = 633.15 + 1e-10 * np.sin(np.arange(50))
    lo, hi = y_limits([flat])
    # at least 1e-3 of the magnitude: 0.63 K around 633 K
    assert hi - lo == pytest.approx(0.63315) and lo < 633.15 < hi
    assert y_limits([np.linspace(400.0, 500.0, 5)]) is None


def test_constants():
    from dnasim.tools.plots import is_constant

    # 1e-5 of the magnitude: 1 mbar of 100 bar is constant, 10 mbar is not
    assert is_constant(1e7 + np.array([0.0, 90.0]), 0.0, "Pa")
    assert not is_constant(1e7 + np.array([0.0, 1000.0]), 0.0, "Pa")
    # round-off around zero (an adiabatic pipe's duty) against the unit's floor
    assert is_constant(np.array([1e-13, -2e-13]), 0.0, "W")
    assert not is_constant(np.array([0.0, 1.0]), 0.0, "W")
