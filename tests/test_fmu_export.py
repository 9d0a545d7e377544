"""FMU export (dnasim fmu): the FMU simulated by FMPy against `dnasim run`.

The plant is plants/attemperator.toml (the seed's Example 2): its set point steps
from 450 to 440 degC at 2 min in the file; the FMU gets the set point as an input
and the master makes the same step at t = 120 s. The steam ramp at 10 min stays in
the plant (not an input) and drives the controller into saturation (a located
switch inside the FMU's integration).

pythonfmu 0.7's native wrapper frees the slave module's __dict__ at instantiation
(a Py_DECREF of a borrowed reference) while the module still uses it: FMPy's process
crashed at exit and a second instantiation failed (NTNU-IHB/PythonFMU#228). The
generated slave balances it; test_two_instances_in_one_process checks it. Each
simulation still runs in its own process (the FMU says canBeInstantiatedOnlyOncePerProcess).
"""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("pythonfmu")
fmpy = pytest.importorskip("fmpy")

from dnasim.cli.commands import main  # noqa: E402
from dnasim.plant.plantfile import load  # noqa: E402
from dnasim.tools.fmu import CoSimulation, FmuError, build_fmu, fmi_name  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PLANT = ROOT / "plants" / "attemperator.toml"
T_BEFORE, T_AFTER = 723.15, 713.15  # the file's set point, 450 and 440 degC [K]
T_STEP = 120.0  # [s]
H = 1.0  # communication step = dnasim run's output interval [s]
OUTPUTS = ["att.T", "sensor.T_s", "pi.z", "pi.m_I"]

_FMPY_SCRIPT = """
import json, sys
import numpy as np
import fmpy
fmu, h, t_step, before, after, t_end = sys.argv[1], *map(float, sys.argv[2:7])
sig = np.array([(0.0, before), (t_step, before), (t_step, after), (t_end, after)],
               dtype=[("time", float), ("pi.setpoint", float)])
res = fmpy.simulate_fmu(fmu, stop_time=t_end, output_interval=h, input=sig, validate=True)
print(json.dumps({n: res[n].tolist() for n in res.dtype.names}), flush=True)
import os
os._exit(0)
"""
# the process ends with os._exit(0) once the results are out: FMPy's process can still
# crash in the interpreter's finalisation after an FMU run (heap corruption; one cause,
# pythonfmu's wrapper freeing the slave module's __dict__, is balanced by the generated
# slave, another is not found: docs/fmu.md). The crash is not ours to hide in a user's
# host, and is stated there; here it would only make the test fail at random.


def _fmpy_run(fmu: Path, t_end: float) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", _FMPY_SCRIPT, str(fmu), str(H), str(T_STEP)]
        + [str(T_BEFORE), str(T_AFTER), str(t_end)],
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _dnasim_run(tmp_path: Path) -> dict:
    """`dnasim run` on the output grid of the communication step; at a time with two
    rows (an event: the left and right limits) the left limit, which is what a
    master reads after the doStep that ends there."""
    import pandas as pd

    res = CliRunner().invoke(
        main, ["run", str(PLANT), "-o", str(tmp_path / "run"), "--output-interval", "1 s", "-q"]
    )
    assert res.exit_code == 0, res.output
    df = pd.read_csv(tmp_path / "run" / "results.csv")
    df = df.groupby("time [s]", sort=True).first()
    cols = {c.split(" [")[0]: c for c in df.columns}
    return {"time": df.index.to_numpy(), **{n: df[cols[n]].to_numpy() for n in OUTPUTS}}


@pytest.fixture(scope="module")
def fmu(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("fmu") / "attemperator.fmu"
    build_fmu(PLANT, path, inputs=["pi.setpoint"], outputs=OUTPUTS)
    return path


def test_fmu_outputs_equal_dnasim_run_for_a_set_point_step(fmu, tmp_path):
    got = _fmpy_run(fmu, 1200.0)
    ref = _dnasim_run(tmp_path)
    t = np.asarray(got["time"])
    assert np.allclose(t, np.arange(0.0, 1200.0 + H / 2, H))
    idx = np.searchsorted(ref["time"], t)
    assert np.allclose(ref["time"][idx], t, rtol=0, atol=1e-9)
    # Tolerance: both integrations keep each step's error at rtol = 1e-6 of the
    # state (atol_scaled = 1e-6 of its scale); they take different steps (the FMU
    # steps past t = 120 s and restarts from the interpolated state there, the run
    # stops on the tstop), so they differ by about their global errors: 1e-5 of a
    # temperature (10 rtol, 7.5 mK at 750 K), and for the controller's output and
    # integral part Kp = 0.02 1/K times that temperature tolerance (1.5e-4).
    tol = {"att.T": 1e-5 * 750.0, "sensor.T_s": 1e-5 * 750.0, "pi.z": 1.5e-4, "pi.m_I": 1.5e-4}
    for name in OUTPUTS:
        a, b = np.asarray(got[name]), ref[name][idx]
        err = np.max(np.abs(a - b))
        assert err <= tol[name], (name, err, t[np.argmax(np.abs(a - b))])
    # the step is in both: the sensor leaves the old set point, and the controller
    # saturates at z = 1 (the steam ramp at 10 min) in the FMU too
    T_s = np.asarray(got["sensor.T_s"])
    assert abs(T_s[int(T_STEP / H)] - T_BEFORE) < 1e-3
    assert T_s[int(300 / H)] < T_BEFORE - 9.0
    assert np.max(got["pi.z"]) == pytest.approx(1.0, abs=1e-9)


_TWICE_SCRIPT = """
import gc, sys
import numpy as np
import fmpy
sig = np.array([(0.0, 723.15), (10.0, 713.15)], dtype=[("time", float), ("pi.setpoint", float)])
for k in range(3):
    res = fmpy.simulate_fmu(sys.argv[1], stop_time=10.0, output_interval=1.0, input=sig)
    d = sys.modules[sys.argv[2]].__dict__
    gc.collect()
    others = [r for r in gc.get_referrers(d) if r is not globals()]
    # references to the slave module's dict: refcount less this name and the argument
    print(len(res), res["sensor.T_s"][-1], sys.getrefcount(d) - 2, len(others), flush=True)
    del d, others
import os
os._exit(0)  # the crash at exit has a second cause, not found (docs/fmu.md)
"""


def test_two_instances_in_one_process(fmu):
    # pythonfmu 0.7's findClass drops a reference to the slave module's __dict__ that
    # it never took: without the slave's balancing reference the dict's count is 0 while
    # the module holds it (freed, its memory reused: the crash at exit) and the second
    # instantiation fails ("Failed to instantiate model", NTNU-IHB/PythonFMU#228)
    with zipfile.ZipFile(fmu) as z:  # the slave's module, as the wrapper imports it
        module = z.read("resources/slavemodule.txt").decode().strip()
    out = subprocess.run(
        [sys.executable, "-c", _TWICE_SCRIPT, str(fmu), module],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    rows = [line.split() for line in out.stdout.strip().splitlines()]
    assert len(rows) == 3
    for n, T_s, refcount, referrers in rows:
        assert int(n) == 11
        assert float(T_s) == float(rows[0][1])  # the same run each time
        assert int(refcount) == int(referrers) == 1  # the module's own reference


def test_fmpy_validates_the_model_description(fmu):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu), validate=True)
    v = {x.name: x for x in md.modelVariables}
    assert v["pi.setpoint"].causality == "input"
    assert float(v["pi.setpoint"].start) == pytest.approx(T_BEFORE)  # the file's value at t0
    # units are in the descriptions (FMI UnitDefinitions crashed FMPy at exit)
    assert v["pi.setpoint"].description == "pi.setpoint [K]"
    assert v["pi.z"].description == "pi.z [1]"
    assert [x.causality for x in md.modelVariables].count("output") == len(OUTPUTS)
    assert md.coSimulation.canBeInstantiatedOnlyOncePerProcess
    assert md.defaultExperiment.stopTime == "1200.0"
    assert float(md.defaultExperiment.tolerance) == 1e-6
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
    assert "resources/plant.toml" in names and "binaries/linux64/attemperator.so" in names


def test_cosimulation_restarts_only_where_an_input_changes():
    """In process, without FMI: one integration while the input stays; a set-point
    change restarts it, and the outputs show the new input at once (direct
    feedthrough of the P part: z jumps by Kp times the set-point step)."""
    cs = CoSimulation(load(PLANT), ["pi.setpoint"], ["pi.z", "sensor.T_s"], stop_time=200.0)
    cs.start()
    t = 0.0
    while t < T_STEP - 1e-9:
        assert cs.step(t, 10.0)
        t += 10.0
    assert cs.restarts == 1
    z_left = cs.value("pi.z")
    cs.set_input("pi.setpoint", T_AFTER)
    z_right = cs.value("pi.z")
    # Kp = 0.02 1/K, set point 10 K lower, error_sign measured - setpoint (the spray
    # opens when the steam is too hot); the sensor and the integral are continuous
    assert z_right - z_left == pytest.approx(0.02 * 10.0, rel=1e-6)
    assert cs.step(t, 10.0) and cs.restarts == 2
    assert cs.step(t + 10.0, 10.0) and cs.restarts == 2
    assert cs.step(t + 20.0, 5.0) and cs.restarts == 3  # a new communication step size
    assert not cs.step(0.0, 5.0) and "the master must step on" in cs.message
    cs.close()


def test_bad_interfaces_are_named():
    loaded = load(PLANT)
    with pytest.raises(FmuError, match="linked to 'pi.z'"):
        build_fmu(PLANT, "/nonexistent/x.fmu", inputs=["spray_valve.z"], loaded=loaded)
    with pytest.raises(FmuError, match="did you mean 'att.T'"):
        build_fmu(PLANT, "/nonexistent/x.fmu", outputs=["att.TT"], loaded=loaded)
    assert fmi_name("n_hdr~T.T_s") == "'n_hdr~T'.T_s" and fmi_name("pipe.T[3]") == "pipe.T[3]"


@pytest.mark.parametrize(
    "args, words",
    [
        (["missing.toml"], ["missing.toml", "no such plant file"]),
        ([str(PLANT), "--vars", "att.TT"], ["'att.TT' matches no output", "did you mean 'att.T'"]),
        ([str(PLANT), "--inputs", "pii.setpoint"], ["no component named 'pii'", "'pi'"]),
        ([str(PLANT), "--inputs", "spray_valve.z"], ["signal input", "'opening'"]),
    ],
)
def test_cli_input_errors_exit_2(args, words, tmp_path):
    res = CliRunner().invoke(main, ["fmu", *args, "-o", str(tmp_path / "x.fmu")])
    assert res.exit_code == 2, res.output
    assert "Traceback" not in res.output and res.output.count("\n") == 1  # one paragraph
    for w in words:
        assert w in res.output
    assert not (tmp_path / "x.fmu").exists()


def test_cli_writes_the_fmu_with_the_default_interface(tmp_path):
    res = CliRunner().invoke(main, ["fmu", str(PLANT), "-o", str(tmp_path / "a.fmu")])
    assert res.exit_code == 0, res.output
    with zipfile.ZipFile(tmp_path / "a.fmu") as z:
        iface = json.loads(z.read("resources/dnasim_fmu.json"))["interface"]
    # boundaries' values, the set point and the turbine valve's opening; the signal outputs
    assert iface["inputs"] == [
        "steam.p",
        "steam.T",
        "water.p",
        "water.T",
        "pi.setpoint",
        "turbine_valve.opening",
        "turbine.p",
    ]
    assert iface["outputs"] == ["att.T", "sensor.T_s", "pi.z"]


def test_a_run_that_stops_fails_the_step_with_the_components_message():
    """tests/plants/limits/drum_boils_dry.toml: the drum runs dry at t = 125.591 s
    (the time `dnasim run` reports, docs/plant_files.md); the doStep over it fails."""
    plant = ROOT / "tests" / "plants" / "limits" / "drum_boils_dry.toml"
    cs = CoSimulation(load(plant), outputs=["drum.V_l"], stop_time=2000.0)
    cs.start()
    t = 0.0
    while cs.step(t, 10.0):
        t += 10.0
    assert t == 120.0
    assert "drum 'drum' (Drum) ran dry" in cs.message and "t = 125.591 s" in cs.message
    cs.close()
