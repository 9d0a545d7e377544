"""The progress bar (issue 24): tqdm (``tqdm.auto``) for ``simulate(progress=True)``,
``dnasim run --progress`` and sweeps; in a terminal the text line, in Jupyter the
notebook's widget (with ipywidgets) or the text line in the cell's stderr (without).

The bar is checked on its tqdm object (a recording subclass of the real tqdm put in
place of ``tqdm.auto.tqdm``): it reaches exactly t_end - t0 [s] and is closed, also
when the run stops early. The notebook cases run a real IPython kernel through
nbclient (skipped when nbclient/ipykernel are not installed).
"""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

import dnasim
from dnasim.cli.commands import main
from dnasim.plant.plantfile import load
from dnasim.run import progress as progress_module
from dnasim.run.simulation import simulate

ROOT = Path(__file__).resolve().parents[1]
AIR_PIPE = ROOT / "plants" / "air_pipe.toml"


def _system():
    return dnasim.compile(load(AIR_PIPE).plant)


@pytest.fixture
def bars(monkeypatch):
    """The tqdm bars made while the test runs (real tqdm objects, on a StringIO)."""
    from tqdm.std import tqdm

    made = []

    class Recording(tqdm):
        def __init__(self, *args, **kwargs):
            kwargs["file"] = io.StringIO()
            super().__init__(*args, **kwargs)
            self.closed_ = False
            made.append(self)

        def close(self):
            super().close()
            self.closed_ = True

        def update(self, n=1):
            self.updates = getattr(self, "updates", 0) + 1
            return super().update(n)

    monkeypatch.setattr(progress_module, "_tqdm_class", lambda: Recording)
    return made


def test_simulate_progress_bar_reaches_t_end_and_is_closed(bars):
    res = simulate(_system(), t0=2.0, t_end=12.0, output_interval=1.0, progress=True)
    assert res.success, res.message
    (bar,) = bars
    assert bar.total == 10.0  # simulated seconds from t0 to t_end
    assert bar.n == 10.0  # exactly: the last point is t_end
    assert bar.closed_
    text = bar.fp.getvalue()
    assert "simulating" in text and "100%" in text and "t = 12 s of 12 s" in text


def test_many_output_points_update_the_bar_at_most_1000_times(bars):
    res = simulate(_system(), t_end=10.0, output_interval=0.002, progress=True)
    assert len(res.t) == 5001
    (bar,) = bars
    assert bar.n == 10.0 and bar.closed_
    # one update each 1/1000 of the run (the points at 0.002 s are 1/5000 apart)
    assert 900 <= bar.updates <= 1001


def test_no_bar_without_progress(bars):
    assert simulate(_system(), t_end=2.0).success
    assert bars == []


def test_the_bar_is_closed_when_the_run_stops_early(bars):
    def stop(t, y, yp):
        if t > 3.0:
            raise RuntimeError("stop here")

    res = simulate(_system(), t_end=10.0, output_interval=1.0, callback=stop, progress=True)
    assert not res.success and "stop here" in res.message
    (bar,) = bars
    assert bar.closed_
    assert bar.n == 3.0  # the last point delivered (the callback refused the one at 4 s)


def test_dnasim_run_progress_bar(bars, tmp_path):
    out = CliRunner().invoke(
        main, ["run", str(AIR_PIPE), "-o", str(tmp_path), "--t-end", "4 s", "--progress"]
    )
    assert out.exit_code == 0, out.output
    (bar,) = bars
    assert bar.n == bar.total == 4.0 and bar.closed_
    # not a terminal and not asked: no bar
    out = CliRunner().invoke(main, ["run", str(AIR_PIPE), "-o", str(tmp_path), "--t-end", "4 s"])
    assert out.exit_code == 0, out.output
    assert len(bars) == 1


def test_the_text_bar_on_a_terminal_is_one_line(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    term = Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    assert simulate(_system(), t_end=5.0, progress=True).success
    text = term.getvalue()
    assert "\r" in text and text.count("\n") <= 1  # redrawn in place
    last = text.rstrip("\n").split("\r")[-1]
    assert last.startswith("simulating: 100%|") and "| t = 5 s of 5 s [" in last


# --------------------------------------------------------------------------- Jupyter


CELL = f"""
import dnasim
from dnasim.plant.plantfile import load
system = dnasim.compile(load({str(AIR_PIPE)!r}).plant)
res = dnasim.simulate(system, t_end=3.0, progress=True)
print("success", res.success)
"""


def _run_notebook(tmp_path, monkeypatch, cells):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    # a kernel spec for this interpreter, found first (JUPYTER_PATH): the kernel runs
    # the dnasim under test, not whatever "python3" kernel the machine has
    spec = tmp_path / "jupyter" / "kernels" / "dnasim-test"
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(
        json.dumps({"argv": argv, "display_name": "dnasim test", "language": "python"})
    )
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(c) for c in cells]
    client = nbclient.NotebookClient(
        nb,
        kernel_name="dnasim-test",
        timeout=600,
        resources={"metadata": {"path": str(tmp_path)}},
        store_widget_state=True,
    )
    client.execute()
    return nb


def _outputs(nb):
    return [o for cell in nb.cells for o in cell.outputs]


def test_jupyter_shows_the_progress_widget(tmp_path, monkeypatch):
    pytest.importorskip("ipywidgets")
    nb = _run_notebook(tmp_path, monkeypatch, [CELL])
    outputs = _outputs(nb)
    text = "".join(o.get("text", "") for o in outputs)
    assert "success True" in text
    views = [o for o in outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})]
    assert len(views) == 1  # one widget: the bar
    # the widgets' final state, as the kernel left it: the bar full and green
    state = nb.metadata["widgets"]["application/vnd.jupyter.widget-state+json"]["state"]
    progress = [w["state"] for w in state.values() if w["model_name"] == "FloatProgressModel"]
    assert len(progress) == 1
    assert progress[0]["value"] == progress[0]["max"] == 3.0
    assert progress[0]["bar_style"] == "success"  # tqdm's colour of a bar closed at 100 %
    labels = [w["state"].get("value", "") for w in state.values() if w["model_name"] == "HTMLModel"]
    assert any("t\u2007=\u20073\u2007s\u2007of\u20073\u2007s" in v for v in labels)  # tqdm's spaces


def test_jupyter_without_ipywidgets_shows_the_text_bar(tmp_path, monkeypatch):
    block = "import sys\nsys.modules['ipywidgets'] = None  # as if not installed\n"
    nb = _run_notebook(tmp_path, monkeypatch, [block + CELL])
    outputs = _outputs(nb)
    err = "".join(o.get("text", "") for o in outputs if o.get("name") == "stderr")
    out = "".join(o.get("text", "") for o in outputs if o.get("name") == "stdout")
    assert "success True" in out
    assert "simulating: 100%" in err and "t = 3 s of 3 s" in err
    assert not [o for o in outputs if "data" in o]  # no widget
