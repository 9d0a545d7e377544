"""Packaging (issue 24 item 8): the optional extras (ida, dask, report, notebook) are not
imported by ``import dnasim``, and a feature whose extra is missing says which
extra to install (exit 2 on the command line), while the core still runs.

"Missing" is simulated in a fresh interpreter by a meta-path finder that refuses
the extras' modules, as an install without them would."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXTRAS = {
    "ida": "sksundae",
    "dask": "distributed",
    "report": "plotly",
    "notebook": "ipywidgets",
}

BLOCK = """
import sys
class _Missing:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {blocked!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}}")
        return None
sys.meta_path.insert(0, _Missing())
"""


def python(code: str, blocked=(), timeout=600):
    src = (BLOCK.format(blocked=set(blocked)) if blocked else "") + code
    return subprocess.run(
        [sys.executable, "-c", src], capture_output=True, text=True, timeout=timeout, cwd=ROOT
    )


def test_extras_declared_and_not_in_the_core():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = project["optional-dependencies"]
    core = " ".join(project["dependencies"])
    for extra in ("ida", "dask", "report", "notebook"):
        assert extra in extras
        for req in extras[extra]:
            assert req.split(">=")[0].split("[")[0] not in core
    names = [r.split(">=")[0].split("[")[0].lower() for r in project["dependencies"]]
    assert len(names) == len(set(names))  # each dependency once
    assert any(r.startswith("dnasim[") for r in extras["dev"])  # the tests get the extras


def test_import_dnasim_imports_no_optional_or_heavy_module():
    heavy = ("plotly", "dask", "distributed", "sksundae", "tomlkit", "matplotlib", "pandas")
    heavy += ("tqdm", "ipywidgets")  # the progress bar's, imported when a bar is asked for
    out = python(
        f"import sys, dnasim\nprint(sorted(m for m in sys.modules if m.split('.')[0] in {heavy!r}))"
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_core_runs_without_the_extras(tmp_path):
    code = (
        "from dnasim.plant.plantfile import load\n"
        "res = load('plants/air_pipe.toml').simulate(t_end=10.0)\n"
        "print(len(res.t) > 1)\n"
    )
    out = python(code, blocked=EXTRAS.values())
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().endswith("True")


def test_report_without_plotly_is_refused_before_the_run(tmp_path):
    code = (
        "import sys\nfrom dnasim.cli.entry import main\n"
        f"sys.exit(main(['run', 'plants/air_pipe.toml', '-o', {str(tmp_path / 'o')!r}, "
        "'--report', '-q']))\n"
    )
    out = python(code, blocked=["plotly"])
    assert out.returncode == 2, out.stderr
    assert "option --report needs plotly" in out.stderr and "dnasim[report]" in out.stderr
    assert "Traceback" not in out.stderr
    assert not (tmp_path / "o" / "results.csv").exists()  # refused before any work


def test_ida_without_scikit_sundae_names_the_extra():
    code = (
        "from dnasim.solver.ida import solve_ida\n"
        "try:\n"
        "    solve_ida(lambda t, y, yp: yp, (0.0, 1.0), [1.0], [0.0], algebraic=[False],\n"
        "              reinitialise=lambda t, y, yp: (y, yp))\n"
        "except ImportError as exc:\n"
        "    print(exc)\n"
    )
    out = python(code, blocked=["sksundae"])
    assert out.returncode == 0, out.stderr
    assert "scikit-sundae" in out.stdout and "dnasim[ida]" in out.stdout


def test_scheduler_without_dask_names_the_extra(tmp_path):
    cases = tmp_path / "cases.csv"
    cases.write_text("sensor.tau\n4 s\n")
    code = (
        "import sys\nfrom dnasim.cli.entry import main\n"
        "sys.exit(main(['sweep', 'tests/plants/lag_sensor.toml', '--cases', "
        f"{str(cases)!r}, '-o', {str(tmp_path / 'o')!r}, '--scheduler', "
        "'tcp://127.0.0.1:1']))\n"
    )
    out = python(code, blocked=["dask", "distributed"])
    assert out.returncode == 2, out.stderr
    assert "dnasim[dask]" in out.stderr and "Traceback" not in out.stderr
