"""Start-up: which heavy modules each small command imports (issue 23 item 8).

Not timing tests: each runs the command in a fresh interpreter and asserts on
``sys.modules`` at its exit, so an eager top-level import of numba, scipy, h5py,
CoolProp, matplotlib, ... on a path that does not use them fails here whatever the
machine's speed. The CPU times are measured by benchmarks/startup.py.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PLANTS = ROOT / "plants"

# What a command may not import unless it needs it: the numerics (numpy, numba, scipy),
# the result files (h5py), the optional media and plots and data frames.
HEAVY = (
    "numpy",
    "numba",
    "llvmlite",
    "scipy",
    "h5py",
    "CoolProp",
    "matplotlib",
    "pandas",
    "xarray",
    "networkx",
    "tqdm",  # the progress bar's: only when a bar is drawn (dnasim.run.progress)
)

# Runs argv through the console script's entry point; prints the heavy modules loaded.
DRIVER = """
import atexit, json, sys
HEAVY = {heavy!r}
atexit.register(lambda: print("LOADED " + json.dumps(
    sorted({{m for m in sys.modules for h in HEAVY if m == h or m.startswith(h + ".")}}))))
{body}
"""


def _loaded(body: str, cwd: Path = ROOT) -> list[str]:
    code = DRIVER.format(heavy=HEAVY, body=body)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=str(cwd), timeout=300
    )
    assert out.returncode == 0, out.stdout + out.stderr
    line = [x for x in out.stdout.splitlines() if x.startswith("LOADED ")]
    assert line, out.stdout
    return json.loads(line[-1][len("LOADED ") :])


def _cli(*argv: str) -> str:
    return f"from dnasim.cli.entry import main\nsys.exit(main({list(argv)!r}))"


def _top(modules: list[str]) -> set[str]:
    return {m.split(".")[0] for m in modules}


def test_import_of_the_command_line_imports_nothing_heavy():
    assert _loaded("import dnasim.cli.commands") == []


@pytest.mark.parametrize(
    "argv",
    [["--help"], ["--version"], ["run", "--help"], ["check", "--help"]],
    ids=lambda a: " ".join(a),
)
def test_help_imports_nothing_heavy(argv):
    assert _loaded(_cli(*argv)) == []


def test_check_of_a_gas_plant_loads_no_kernels_or_result_files():
    # air_pipe is air (the ideal-gas mixture): no IF97 kernels (numba), no results.nc
    # (h5py); the structure analysis uses numpy and scipy.sparse.csgraph
    top = _top(_loaded(_cli("check", str(PLANTS / "air_pipe.toml"))))
    assert top.isdisjoint({"numba", "llvmlite", "h5py", "CoolProp", "matplotlib", "pandas"})
    assert top.isdisjoint({"xarray", "networkx"})
    assert {"numpy", "scipy"} <= top  # what it does use (the test sees the real command)


def test_run_of_a_gas_plant_imports_no_kernels_plots_or_frames(tmp_path):
    # results.csv and results.nc (h5py) are written by default; --plot is not
    top = _top(_loaded(_cli("run", str(PLANTS / "air_pipe.toml"), "-o", str(tmp_path), "-q")))
    assert (tmp_path / "results.nc").is_file()
    assert "h5py" in top
    assert top.isdisjoint({"numba", "llvmlite", "CoolProp", "matplotlib", "pandas"})
    assert top.isdisjoint({"xarray", "networkx", "tqdm"})  # -q: no progress bar
