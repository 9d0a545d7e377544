"""Clean output of the command line (issue 24, item 7): no binding-leak reports at exit,
``--vars`` patterns checked before the run, one rule for times written with and
without a space."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from dnasim.cli import main

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "plants"

#: a short refrigerant line: R134a vapour (CoolProp HEOS) through a pipe and a valve
R134A_PLANT = """
[plant]
name = "r134a_line"
medium = "R134a"

[simulation]
t_end = "2 s"
start = "given"

[components.inlet]
type = "PressureBoundary"
p = "5 bar"
T = "60 degC"
m_nominal = "0.5 kg/s"
ports = { port = "n_in" }

[components.pipe]
type = "Pipe"
V = "0.5 m3"
kA = "400 W/K"
k = 2e3
C_wall = "150 kJ/K"
n_volumes = 1
p0 = "4.9 bar"
T0 = "20 degC"
T_wall0 = "20 degC"
m_nominal = "0.5 kg/s"
ports = { inlet = "n_in", outlet = "n_out" }

[components.valve]
type = "Valve"
C = "0.002 kg/(s.Pa0.5)"
opening = 1
m_nominal = "0.5 kg/s"
ports = { inlet = "n_out", outlet = "n_sink" }

[components.outlet]
type = "PressureBoundary"
p = "4 bar"
ports = { port = "n_sink" }
"""


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


# ------------------------------------------------------------------ (a) nanobind


@pytest.mark.parametrize("command", ["run", "check"])
def test_coolprop_plant_leaves_stderr_empty_at_exit(tmp_path, command):
    """The ``dnasim`` program itself (a new interpreter, so that its shutdown is seen):
    CoolProp's AbstractState objects alive at exit made nanobind print ~30 lines of
    "nanobind: leaked ..." on stderr; now stderr is empty."""
    plant = tmp_path / "r134a.toml"
    plant.write_text(R134A_PLANT)
    args = [sys.executable, "-m", "dnasim", command, str(plant)]
    if command == "run":
        args += ["-o", str(tmp_path / "out"), "-q"]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "nanobind" not in proc.stderr
    assert proc.stderr == ""
    if command == "run":
        assert (tmp_path / "out" / "results.csv").is_file()


def test_a_released_medium_makes_a_new_abstract_state():
    """After the exit handler dropped the AbstractState, the medium still works (a use
    later in the interpreter's exit, or a test calling the handler)."""
    from dnasim.media import get_medium
    from dnasim.media.coolprop_medium import release_abstract_states

    m = get_medium("R134a", backend="HEOS")
    h = m.h_pT(5e5, 333.15)
    release_abstract_states()
    assert m._AS is None
    m._cache_hpT.clear()
    assert m.h_pT(5e5, 333.15) == h  # the same flash in a new AbstractState
