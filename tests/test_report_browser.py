"""report.html in headless Chromium, offline (issue 24 item 2).

Skipped where Debian's chromium is absent (CI does not install it; on a developer's
machine: ``apt-get install -y chromium chromium-driver``). Two ways in:

- ``chromium --headless --dump-dom`` under ``unshare -n`` (no network at all, where
  the machine allows it): the DOM after the page's scripts ran, every main panel
  and the schematic drawn;
- selenium with ``chromedriver`` (the ``dev`` extra): a user types in the search
  box, presses Enter, clicks a component of the schematic, and the page answers;
  every request to the network goes to a proxy that does not exist.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main

PLANTS = Path(__file__).parents[1] / "plants"
CHROMIUM = next(
    (p for p in ("/usr/bin/chromium", "/usr/bin/chromium-browser") if Path(p).exists()), None
)
CHROMEDRIVER = shutil.which("chromedriver")

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (headless)")


@pytest.fixture(scope="module")
def drum_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("drum_boiler")
    res = CliRunner().invoke(
        main,
        ["run", str(PLANTS / "drum_boiler.toml"), "-o", str(out), "-q", "--report", "--units",
         "engineering"],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    return out


def page_data(out: Path) -> dict:
    text = (out / "report.html").read_text()
    m = re.search(r"<script type='application/json' id='dnasim-data'>(.*?)</script>", text, re.S)
    return json.loads(m.group(1))


def test_the_page_draws_offline(drum_dir):
    """No network at all (unshare -n where allowed): plotly from the folder draws a
    line for every curve of every main panel, and the schematic holds every
    component with its final values filled in by the page's script."""
    data = page_data(drum_dir)
    n_panels = len(data["panels"])
    n_curves = sum(len(p["curves"]) for p in data["panels"])
    assert n_panels >= 5
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=5000"]
    if shutil.which("unshare") and subprocess.run(["unshare", "-n", "true"]).returncode == 0:
        cmd = ["unshare", "-n", *cmd]  # no network at all: the page must not need it
    dom = subprocess.run(
        [*cmd, "--dump-dom", (drum_dir / "report.html").as_uri()],
        capture_output=True,
        text=True,
        timeout=120,
    ).stdout
    end = r'(?=<div class="panel|</div></div><p id="constants")'
    panels = re.findall(r'<div class="panel[^"]*" id="panel-\d+".*?' + end, dom, re.S)
    assert len(panels) == n_panels
    assert all('class="main-svg"' in p for p in panels)  # every panel drawn by plotly
    # one drawn line per curve (plotly's trace groups, each with a path)
    traces = re.findall(
        r'<g class="trace scatter.*?class="js-line"[^>]*\sd="M-?[0-9.]+,', dom, re.S
    )
    assert len(traces) >= n_curves
    # the schematic's values: written by the script from the data
    for comp in ("pump", "drum", "steam_valve", "sink", "level_pi"):
        assert f'data-comp="{comp}"' in dom
    assert re.search(r'data-col="drum.p">[0-9.]+ bar<', dom)
    assert re.search(r'data-col="drum.level">[0-9.]+ m<', dom)
    assert 'id="noplotly" class="warn" hidden' in dom  # plotly was found


@pytest.fixture(scope="module")
def browser():
    webdriver = pytest.importorskip("selenium.webdriver")
    if CHROMEDRIVER is None:
        pytest.skip("needs chromedriver (Debian's chromium-driver)")
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for a in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--window-size=1600,1200",
        # every request to the network goes to a proxy that is not there
        "--proxy-server=http://127.0.0.1:9",
        "--proxy-bypass-list=<-loopback>",
    ):
        opts.add_argument(a)
    drv = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    yield drv
    drv.quit()


def plotted(drv) -> list[list[str]]:
    """The names of the curves of each plot of the variable browser, as plotly holds them."""
    return drv.execute_script(
        "return Array.from(document.querySelectorAll('#plotstack .pdiv'))"
        ".map(d => (d.data || []).map(t => t.name))"
    )


def test_search_finds_a_variable_and_plots_it(browser, drum_dir):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    drv = browser
    drv.get((drum_dir / "report.html").as_uri())
    n_vars = len(page_data(drum_dir)["vars"])
    search = drv.find_element(By.ID, "search")
    assert drv.find_element(By.ID, "count").text == f"{n_vars} variables"
    search.send_keys("drum level")
    # one match: drum.level; every other row is hidden
    assert drv.find_element(By.ID, "count").text == f"1 of {n_vars} variables"
    shown = [
        r.get_attribute("data-name")
        for r in drv.find_elements(By.CSS_SELECTOR, ".var")
        if r.is_displayed()
    ]
    assert shown == ["drum.level"]
    search.send_keys(Keys.ENTER)
    assert plotted(drv) == [["drum.level"]]
    # the curve is drawn: a path with points, the axis says level [m]
    svg = drv.find_element(By.CSS_SELECTOR, "#plotstack .pdiv .main-svg")
    assert re.search(
        r'class="js-line"[^>]*\sd="M-?[0-9.]+,-?[0-9.]+L', svg.get_attribute("outerHTML")
    )
    assert "level [m]" in drv.find_element(By.CSS_SELECTOR, "#plotstack .pdiv").text
    # a pattern, then a click on a row: pressure in bar goes on the right axis
    search.clear()
    search.send_keys("drum.p")
    row = next(r for r in drv.find_elements(By.CSS_SELECTOR, ".var") if r.is_displayed())
    assert row.get_attribute("data-name") == "drum.p"
    row.click()
    assert plotted(drv) == [["drum.level", "drum.p (right)"]]
    # a third unit (°C) opens a second plot
    search.clear()
    search.send_keys("*.T bar", Keys.ESCAPE)  # Escape clears the search
    assert search.get_attribute("value") == ""
    search.send_keys("drum.T", Keys.ENTER)
    assert plotted(drv) == [["drum.level", "drum.p (right)"], ["drum.T"]]


def test_clicking_a_component_selects_its_variables(browser, drum_dir):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    drv = browser
    drv.get((drum_dir / "report.html").as_uri())
    data = page_data(drum_dir)
    comps = drv.find_elements(By.CSS_SELECTOR, "svg.schematic g.comp")
    assert {c.get_attribute("data-comp") for c in comps} == set(data["components"])
    drum = drv.find_element(By.CSS_SELECTOR, 'svg.schematic g.comp[data-comp="drum"]')
    ActionChains(drv).move_to_element(drum).perform()
    tip = drv.find_element(By.ID, "tip")
    assert tip.is_displayed() and tip.text.startswith("drum (Drum)")
    assert re.search(r"\bp [0-9.]+ bar [0-9.]+ [0-9.]+", tip.text)  # final, min, max
    drum.click()
    card = drv.find_element(By.ID, "card")
    own = [v["name"] for v in data["vars"] if v["owner"] == "drum"]
    rows = card.find_elements(By.CSS_SELECTOR, "tr.cvar")
    assert [r.get_attribute("data-name") for r in rows] == own
    # the browser shows the drum's variables, and only those
    assert drv.find_element(By.ID, "search").get_attribute("value") == "drum.*"
    shown = [
        r.get_attribute("data-name")
        for r in drv.find_elements(By.CSS_SELECTOR, ".var")
        if r.is_displayed()
    ]
    assert shown == own
    # its main variables plotted from the card: pressure, level and the measured volume
    card.find_element(By.XPATH, ".//button[text()='plot main variables']").click()
    time.sleep(0.2)
    names = [n.replace(" (right)", "") for p in plotted(drv) for n in p]
    assert {"drum.p", "drum.level", "drum.V_l", "drum.Q_in"} <= set(names)
    for p in drv.execute_script("return window.dnasimReport.plots().map(p => p.vars.map(n => n))"):
        units = {next(v["unit"] for v in data["vars"] if v["name"] == n) for n in p}
        assert len(units) <= 2  # two units at most on one plot
    # the units switch: SI shows Pa
    drv.find_element(By.CSS_SELECTOR, ".unitswitch button[data-units='si']").click()
    value = drv.find_element(By.CSS_SELECTOR, 'svg.schematic text[data-col="drum.p"]').text
    assert value.endswith(" Pa")
