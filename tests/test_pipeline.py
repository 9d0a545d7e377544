"""The stages PlantSpec -> Plant -> compile() -> System -> simulate() -> Results."""

import gc
import io
import os
import pickle
import subprocess
import sys
import types
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

import dnasim
from dnasim.compilation.compiler import compile as compile_plant
from dnasim.compilation.system import System
from dnasim.core.errors import DAEError
from dnasim.core.timefunctions import Step
from dnasim.plant.examples import air_pipe_plant, attemperator_plant
from dnasim.plant.graph import PlantGraph
from dnasim.plant.plantfile import load
from dnasim.plant.spec import ComponentSpec, PlantSpec
from dnasim.run.results import Results
from dnasim.run.simulation import NordsieckBDF, simulate
from dnasim.start.initial import initial_values

ROOT = Path(__file__).resolve().parent.parent


def pickled_types(obj) -> set[type]:
    """The type of every object a pickle of ``obj`` writes (``persistent_id`` is
    called once per object the pickler meets)."""
    seen = set()

    class Scan(pickle.Pickler):
        def persistent_id(self, o):
            seen.add(type(o))

    Scan(io.BytesIO()).dump(obj)
    return seen


def reachable(obj):
    """Every object reachable from ``obj`` through references (a function's closure
    cells and a bound method's ``__self__``; not classes, modules or globals)."""
    seen, todo = set(), [obj]
    while todo:
        o = todo.pop()
        if id(o) in seen or isinstance(o, type | types.ModuleType):
            continue
        seen.add(id(o))
        yield o
        if isinstance(o, types.FunctionType):
            todo.extend(c.cell_contents for c in o.__closure__ or ())
        elif isinstance(o, types.MethodType):
            todo.append(o.__self__)
        else:
            todo.extend(gc.get_referents(o))


def holds(obj, *classes) -> bool:
    return any(isinstance(o, classes) for o in reachable(obj))


def stepped_air_pipe():
    plant = air_pipe_plant(2)
    plant.components["source"].params["T"] = Step(5.0, 600.0, 650.0)
    return plant


@pytest.fixture(scope="module")
def stepped():
    system = compile_plant(stepped_air_pipe())
    return system, simulate(system, t_end=10.0, start="given")


def test_results_is_a_mapping_with_strictly_increasing_time(stepped):
    _, res = stepped
    assert isinstance(res, Mapping)
    assert list(res) == res.names and len(res) == len(res.names)
    assert all(res[n].shape == res.t.shape for n in res)
    assert np.all(np.diff(res.t) > 0)
    # the step at t = 5 s restarts the solver: one row there, flagged
    k = int(np.flatnonzero(res.t == 5.0)[0])
    assert res.restart[k] and res.restart.sum() == 1


def test_units_survive_into_dataframe_and_xarray(stepped):
    _, res = stepped
    df = res.to_dataframe()
    assert df.index.is_unique and df.index.is_monotonic_increasing
    assert df.attrs["units"]["pipe1.T_out"] == "K" and df.attrs["units"]["time"] == "s"
    assert df.attrs["units"]["inlet.p"] == "Pa"
    ds = res.to_xarray()
    assert ds["pipe1.T_out"].attrs["units"] == "K" and ds["time"].attrs["units"] == "s"
    assert ds["pipe1.T_out"].dims == ("time",)  # as in results.nc and sweep.nc
    np.testing.assert_array_equal(ds["pipe1.T_out"].values, res["pipe1.T_out"])


def test_results_pickle_round_trip(stepped):
    _, res = stepped
    back = pickle.loads(pickle.dumps(res))
    assert back.names == res.names and back.units == res.units
    for n in ("pipe1.T_out", "inlet.T", "pipe1.M[0]"):
        np.testing.assert_array_equal(back[n], res[n])
    np.testing.assert_array_equal(back.restart, res.restart)
    assert back.events == res.events and back.success
    # no back-reference in the pickle: no System, no plant, no spec, no component
    written = pickled_types(res)
    assert not [t for t in written if issubclass(t, System | PlantGraph | PlantSpec)]
    assert not [t for t in written if t.__module__.startswith("dnasim.components")]
    # and, once its outputs are read, the live Results holds no System either (before,
    # the lazy output rows hold it: docs/architecture.md, Results)
    assert not holds(res, System, PlantGraph)


def test_system_pickle_round_trip():
    system = compile_plant(attemperator_plant())
    y0, yp0 = initial_values(system, 0.0, "steady")
    back = pickle.loads(pickle.dumps(system))
    # the same residual, bit for bit, and the same switch functions
    np.testing.assert_array_equal(back.residual(1.0, y0, yp0), system.residual(1.0, y0, yp0))
    assert [e.name for e in back.events] == [e.name for e in system.events]
    g = [e(1.0, y0, yp0) for e in system.events]
    # (the plant's limits are a vector switch: compared element by element)
    for a, b in zip([e(1.0, y0, yp0) for e in back.events], g, strict=True):
        np.testing.assert_array_equal(a, b)
    # media unpickle as the shared registry instances
    assert back.node_media == system.node_media
    # the System pickles without the plant it was compiled from, or its spec
    assert not [t for t in pickled_types(system) if issubclass(t, PlantGraph | PlantSpec)]
    assert not [t for t in pickled_types(system) if issubclass(t, Results)]


def test_spec_pickle_round_trip():
    spec = load(ROOT / "plants" / "attemperator.toml").spec
    back = pickle.loads(pickle.dumps(spec))
    assert back.name == spec.name and back.simulation == spec.simulation
    assert [c.params for c in back.components] == [c.params for c in spec.components]
    # plain data: no plant, no System (a spec is the first stage)
    assert not [t for t in pickled_types(spec) if issubclass(t, PlantGraph | System | Results)]


def test_system_has_no_reference_to_the_plant():
    plant = air_pipe_plant(1)
    system = compile_plant(plant)
    assert all(v is not plant for v in vars(system).values())
    assert not holds(system, PlantGraph)


def test_plant_holds_no_spec_system_or_results():
    # the data flows one way: a simulated plant keeps nothing of the later stages, a
    # plant built from a spec nothing of the spec (it has its own [simulation] copy)
    loaded = load(ROOT / "plants" / "air_pipe.toml")
    plant = loaded.plant
    res = plant.simulate(t_end=1.0)
    assert res.success
    assert not holds(plant, System, Results, PlantSpec, ComponentSpec)
    assert plant.simulation == loaded.spec.simulation
    assert plant.simulation is not loaded.spec.simulation


def test_modes_live_in_the_system_not_the_component():
    # two Systems compiled from one plant keep their own controller modes
    plant = attemperator_plant()
    a, b = compile_plant(plant), compile_plant(plant)
    res = simulate(a, t_end=400.0)
    assert any(e["name"] == "pi.upper" for e in res.events)
    assert a.modes["pi"]["mode"] != "free"  # saturated at the end of the run
    assert b.modes["pi"] == {}
    assert "mode" not in vars(plant.components["pi"])


def test_failure_is_reported_or_raised():
    system = compile_plant(air_pipe_plant(1))
    res = simulate(system, t_end=10.0, start="given", solver=NordsieckBDF(max_steps=3))
    assert not res.success and res.message
    with pytest.raises(DAEError) as info:
        simulate(system, t_end=10.0, start="given", solver=NordsieckBDF(max_steps=3), throw=True)
    assert info.value.result.success is False


def test_load_plant_simulate_uses_the_files_settings():
    plant = dnasim.load_plant(ROOT / "plants" / "air_pipe.toml")
    settings = plant.simulation
    res = plant.simulate(t_end=60.0)  # only t_end overridden: start="given" from the file
    assert res.success
    assert res.t[-1] == 60.0
    assert settings.start == "given"
    # a given start keeps the cold pipe's initial outlet temperature (steady would not)
    T0 = plant.components["pipe"].params["T0"]
    assert res["pipe.T_out"][0] == pytest.approx(T0, rel=1e-9)


def test_top_level_names():
    from dnasim import Plant, PlantSpec, compile, load_plant, simulate  # noqa: F401

    assert compile is compile_plant


def _assert_coolprop_not_imported(code):
    """Run ``code`` (which ends by writing COOLPROP=<imported?> to stderr) in a fresh
    interpreter and check that it did not import CoolProp."""
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        timeout=120,
    )
    assert "COOLPROP=False" in out.stderr, out.stderr[-2000:]


@pytest.mark.parametrize(
    "args", [["components"], ["check", str(ROOT / "plants" / "air_pipe.toml")], ["--help"]]
)
def test_commands_on_air_do_not_import_coolprop(args):
    # CoolProp takes seconds to import: only a medium that needs it may import it
    code = (
        "import sys, runpy\n"
        f"sys.argv = ['dnasim'] + {args!r}\n"
        "try:\n"
        "    runpy.run_module('dnasim.cli.commands', run_name='__main__')\n"
        "except SystemExit as e:\n"
        "    assert not e.code, e.code\n"
        "sys.stderr.write('COOLPROP=%s' % ('CoolProp' in sys.modules))\n"
    )
    _assert_coolprop_not_imported(code)


def test_python_api_on_air_does_not_import_coolprop():
    # the same through the Python API: load, check, compile and simulate an air plant
    code = (
        "import sys, dnasim\n"
        "plant = dnasim.load_plant('plants/air_pipe.toml')\n"
        "assert plant.check().ok\n"
        "assert plant.simulate(t_end=5.0).success\n"
        "sys.stderr.write('COOLPROP=%s' % ('CoolProp' in sys.modules))\n"
    )
    _assert_coolprop_not_imported(code)


def test_python_api_takes_unit_strings_and_the_same_checks_as_files():
    from dnasim.core.errors import PlantError
    from dnasim.library import PressureBoundary
    from dnasim.plant.plantfile import loads

    b = PressureBoundary("src", p="120 bar", T="200 degC")
    assert b.param_at("p", 0.0) == 120e5 and b.param_at("T", 0.0) == pytest.approx(473.15)
    # 0 Pa is refused by the one Param check, from Python and from TOML
    with pytest.raises(PlantError, match="pressure and must be greater than 0"):
        PressureBoundary("src", p="0 bar", T=300.0)
    text = (ROOT / "plants" / "air_pipe.toml").read_text().replace('p = "1.5 bar"', "p = 0", 1)
    with pytest.raises(PlantError, match="pressure and must be greater than 0"):
        loads(text)


def test_plant_spec_from_python_builds_and_simulates():
    from dnasim import ComponentSpec, PlantSpec

    m = {"m_nominal": "0.1 kg/s"}
    spec = PlantSpec(
        "demo",
        medium="Air",
        components=[
            ComponentSpec(
                "src", "PressureBoundary", {"p": "2 bar", "T": "600 K", **m}, ports={"port": "a"}
            ),
            ComponentSpec(
                "pipe",
                "Pipe",
                {"V": "0.1 m3", "kA": "50 W/K", "k": 1.2e5, "C_wall": "5e4 J/K", **m},
                ports={"inlet": "a", "outlet": "b"},
            ),
            ComponentSpec(
                "valve",
                "Valve",
                {"C": 3.2e-4, "opening": 1.0, **m},
                ports={"inlet": "b", "outlet": "c"},
            ),
            ComponentSpec("sink", "PressureBoundary", {"p": "1 bar", **m}, ports={"port": "c"}),
        ],
    )
    back = pickle.loads(pickle.dumps(spec))
    assert back == spec
    res = back.build().simulate(10.0)
    assert res.success and res["pipe.m[1]"][-1] > 0


def test_a_shorter_run_of_a_file_with_an_output_grid_ends_on_its_own_t_end():
    # plants/evaporator.toml has output_interval = 5 s up to 1200 s; simulate(t_end=12)
    # must cut that grid at 12 s (it used to refuse: "t_eval must lie within t_span")
    from dnasim import load_plant

    res = load_plant(ROOT / "plants" / "evaporator.toml").simulate(t_end=12.0)
    assert res.success, res.message
    assert list(res.t) == [0.0, 5.0, 10.0, 12.0]


# ------------------------------------------------------------------ compile is one-way
# (issue 21: compile() wrote the media, input units and converted parameters into the
# Plant's own components, so a second compile changed every System compiled before)


def _plant_component_ids(plant) -> set[int]:
    return {id(c) for c in plant.components.values()}


def test_a_second_compile_with_another_medium_leaves_the_first_system_as_it_was():
    from dnasim.media import get_medium

    plant = air_pipe_plant(2)
    first = compile_plant(plant)
    y0, yp0 = initial_values(first, 0.0, "given")
    F0 = first.residual(1.0, y0, yp0)
    plant.default_medium = "FlueGas"  # an ideal-gas mixture: another h(T), another T(h)
    second = compile_plant(plant)
    # the first System keeps its own components and media: the same residual to the bit
    # (the issue measured it moving by 1.1e4 when the pipe took the second medium)
    np.testing.assert_array_equal(first.residual(1.0, y0, yp0), F0)
    air, flue = get_medium("Air"), get_medium("FlueGas")
    for name in ("source", "pipe1", "valve", "exhaust"):
        assert first.components[name].medium is air, name
        assert set(first.components[name].port_media.values()) == {air}, name
        assert second.components[name].medium is flue, name
    assert set(first.node_media.values()) == {air}
    # the second System is another DAE at the same point (it is not the first's)
    assert not np.array_equal(second.residual(1.0, y0, yp0), F0)
    # the Plant was not written by either compile: no media on its components
    for comp in plant.components.values():
        assert comp.medium is None and comp.port_media == {}
    # each System holds its own component objects, none of the Plant's
    ids = _plant_component_ids(plant)
    assert not ids & {id(c) for c in first.components.values()}
    assert not {id(c) for c in first.components.values()} & {
        id(c) for c in second.components.values()
    }


def test_a_parameter_or_connection_changed_after_compile_leaves_the_system_as_it_was():
    plant = air_pipe_plant(2)
    system = compile_plant(plant)
    y0, yp0 = initial_values(system, 0.0, "given")
    F0 = system.residual(1.0, y0, yp0)
    plant.components["pipe1"].params["kA"] *= 2.0  # [W/K]
    plant.components["source"].params["T"] = Step(0.0, 600.0, 700.0)  # [K]
    plant.connections[("valve", "outlet")] = "elsewhere"
    np.testing.assert_array_equal(system.residual(1.0, y0, yp0), F0)
    assert system.connections[("valve", "outlet")] != "elsewhere"


def test_signal_units_are_resolved_on_the_systems_components_not_the_plants():
    # a controller gain in the unit of its linked signal ("0.02 1/K") is converted per
    # System; the Plant's controller keeps the text it was given, so a second compile
    # (after a change of the link) converts it again
    from dnasim.library import PIController

    plant = attemperator_plant()
    old = plant.components["pi"]
    params = {**old.params}
    for k in ("Kp", "KI"):
        params.pop(k)
    plant.components["pi"] = PIController(
        "pi",
        Kp="0.02 1/K",
        KI="6e-4 1/(K.s)",
        **{k: v for k, v in params.items() if v is not None and k not in ("Kp", "KI")},
    )
    system = compile_plant(plant)
    assert system.components["pi"].params["Kp"] == pytest.approx(0.02, rel=1e-12)
    assert plant.components["pi"].params["Kp"] is None
    assert plant.components["pi"].signal_unit_values["Kp"] == "0.02 1/K"
    assert getattr(plant.components["pi"], "input_units", {}) == {}
    again = compile_plant(plant)
    assert again.components["pi"].params["Kp"] == system.components["pi"].params["Kp"]


def test_compile_simulate_compile_again_gives_identical_results():
    plant = attemperator_plant()
    a = simulate(compile_plant(plant), t_end=300.0)
    b = simulate(compile_plant(plant), t_end=300.0)
    first, second = compile_plant(plant), compile_plant(plant)
    c, d = simulate(first, t_end=300.0), simulate(second, t_end=300.0)

    def counts(res):  # the solver's counters (its timings differ from run to run)
        return {k: v for k, v in res.stats.items() if not k.endswith("time")}

    assert a.success and counts(a) == counts(b) == counts(c) == counts(d)
    for res in (b, c, d):
        np.testing.assert_array_equal(res.t, a.t)
        for name in a:
            np.testing.assert_array_equal(res[name], a[name], err_msg=name)


def test_a_system_pickle_and_the_system_hold_none_of_the_plants_objects():
    from dnasim.media.base import Medium

    plant = attemperator_plant()
    system = compile_plant(plant)
    ids = _plant_component_ids(plant)
    assert not [o for o in reachable(system) if id(o) in ids]
    back = pickle.loads(pickle.dumps(system))
    assert not [t for t in pickled_types(system) if issubclass(t, PlantGraph | PlantSpec)]
    assert not [o for o in reachable(back) if id(o) in ids]
    # and the plant holds no medium object: compile gave the media to the System only
    assert not holds(plant, Medium, System)


@pytest.mark.parametrize(
    "name", ["attemperator", "superheater_line", "turbine_trip_safety_valve", "rankine"]
)
def test_compile_and_simulate_write_nothing_into_the_plant(name):
    # the whole plant, pickled, is the same byte for byte after a compile and a run
    # (before issue 21 the components came back with media, input units and caches)
    plant = load(ROOT / "plants" / f"{name}.toml").plant
    before = pickle.dumps(plant)
    plant.compile()
    assert plant.simulate(5.0).success
    assert pickle.dumps(plant) == before
