"""dnasim.plant.plantfile: TOML -> validated description -> Plant. Validation before numerics."""

import os
import textwrap

import pytest

from dnasim.core.errors import PlantError
from dnasim.core.timefunctions import Ramp, Sine, Step, Table
from dnasim.plant.plantfile import _decode, load, parse_plant

BASE = textwrap.dedent(
    """\
    [plant]
    name = "spray"

    [simulation]
    t_end = "20 min"
    output_interval = "2 s"
    rtol = 1e-6
    atol_scaled = 1e-8
    max_order = 4
    start = "steady"

    [components.steam]
    type = "PressureBoundary"
    medium = "Water"
    p = "120 bar"
    T = "540 degC"
    ports = { port = "n_steam" }

    [components.water]
    type = "PressureBoundary"
    p = "140 bar"
    T = "200 degC"
    ports = { port = "n_water" }

    [components.spray_valve]
    type = "Valve"
    C = "5e-5 kg/(s.Pa0.5)"
    ports = { inlet = "n_water", outlet = "n_spray" }
    inputs = { z = "pi.z" }

    [components.att]
    type = "Attemperator"
    V = "0.3 m3"
    k = 2e3
    ports = { steam_in = "n_steam", water_in = "n_spray", outlet = "n_mix" }

    [components.sensor]
    type = "TemperatureSensor"
    T_lag = "5 s"
    ports = { port = "n_mix" }

    [components.pi]
    type = "PIController"
    Kp = "0.02 1/K"
    KI = "4e-4 1/(K.s)"
    setpoint = "500 degC"
    inputs = { measured = "sensor.T" }

    [components.outlet_valve]
    type = "Valve"
    C = "1e-3 kg/(s.Pa0.5)"
    opening = 1
    ports = { inlet = "n_mix", outlet = "n_turbine" }

    [components.turbine]
    type = "PressureBoundary"
    p = "100 bar"
    ports = { port = "n_turbine" }
    """
)


def spec_of(text, path="plant.toml"):
    return parse_plant(_decode(text, path), path, text)


def errors_of(text, path="plant.toml") -> str:
    with pytest.raises(PlantError) as info:
        spec_of(text, path)
    return str(info.value)


def comp(spec, name):
    return next(c for c in spec.components if c.name == name)


# ------------------------------------------------------------------ the valid file


def test_base_file_is_valid_and_in_si():
    spec = spec_of(BASE)
    assert spec.name == "spray"
    s = spec.simulation
    assert (s.t_end, s.output_interval, s.rtol, s.atol_scaled, s.max_order, s.start) == (
        1200.0,
        2.0,
        1e-6,
        1e-8,
        4,
        "steady",
    )
    assert comp(spec, "steam").params["p"] == 1.2e7
    assert comp(spec, "steam").params["T"] == pytest.approx(813.15)
    assert comp(spec, "spray_valve").params["C"] == 5e-5
    pi = comp(spec, "pi")
    assert pi.params["setpoint"] == pytest.approx(773.15)  # the unit of the measured signal
    assert pi.params["Kp"] == pytest.approx(0.02)
    assert pi.params["KI"] == pytest.approx(4e-4)
    assert pi.inputs == {"measured": "sensor.T"}
    assert comp(spec, "att").ports == {
        "steam_in": "n_steam",
        "water_in": "n_spray",
        "outlet": "n_mix",
    }


def test_t_eval_covers_the_interval():
    s = spec_of(BASE).simulation
    t = s.output_times()
    assert t[0] == 0.0 and t[-1] == 1200.0 and len(t) == 601


def test_defaults_without_optional_simulation_keys():
    text = BASE.replace('output_interval = "2 s"\n', "").replace("max_order = 4\n", "")
    s = spec_of(text).simulation
    assert s.output_interval is None and s.output_times() is None and s.max_order == 4


@pytest.mark.parametrize(
    "value, cls, probe",
    [
        ('{ type = "step", t0 = "5 min", before = "540 degC", after = "560 degC" }', Step, 813.15),
        (
            '{ type = "ramp", t0 = 60, t1 = "2 min", start = "540 degC", end = "600 degC" }',
            Ramp,
            813.15,
        ),
        (
            '{ type = "table", times = [0, "1 min", "2 min"], values = [800, "550 degC", 830] }',
            Table,
            800.0,
        ),
        (
            '{ type = "sine", mean = "540 degC", amplitude = "10 degC", period = "1 min" }',
            Sine,
            813.15,
        ),
        ('{ type = "constant", value = "540 degC" }', None, 813.15),
    ],
)
def test_time_functions(value, cls, probe):
    text = BASE.replace('T = "540 degC"', f"T = {value}")
    f = comp(spec_of(text), "steam").params["T"]
    if cls is not None:
        assert isinstance(f, cls)
    assert f(0.0) == pytest.approx(probe)


def test_sine_amplitude_is_a_difference():
    text = BASE.replace(
        'T = "540 degC"',
        'T = { type = "sine", mean = "540 degC", amplitude = "10 degC", period = "1 min" }',
    )
    f = comp(spec_of(text), "steam").params["T"]
    assert f.amplitude == pytest.approx(10.0)


def test_time_function_as_sub_table():
    text = BASE.replace('T = "540 degC"\n', "", 1) + textwrap.dedent(
        """
        [components.steam.T]
        type = "table"
        times = ["0 min", "10 min", "12 min"]
        values = ["540 degC", "540 degC", "580 degC"]
        """
    )
    f = comp(spec_of(text), "steam").params["T"]
    assert isinstance(f, Table) and f(720.0) == pytest.approx(853.15)


def test_setpoint_time_function_in_measured_unit():
    text = BASE.replace(
        'setpoint = "500 degC"',
        'setpoint = { type = "step", t0 = "1 min", before = "500 degC", after = "490 degC" }',
    )
    f = comp(spec_of(text), "pi").params["setpoint"]
    assert f(0) == pytest.approx(773.15) and f(61) == pytest.approx(763.15)


# ------------------------------------------------------------------ errors


def test_malformed_toml_names_file_and_line():
    text = BASE.replace('T_lag = "5 s"', 'T_lag = "5 s')
    with pytest.raises(PlantError) as info:
        _decode(text, "bad.toml")
    msg = str(info.value)
    assert msg.startswith("bad.toml, line ")
    line = int(msg.split("line ")[1].split(",")[0])
    assert "T_lag" in text.splitlines()[line - 1]
    assert "malformed TOML" in msg


def test_duplicate_component_is_a_name_used_twice():
    text = BASE + '\n[components.sensor]\ntype = "TemperatureSensor"\n'
    with pytest.raises(PlantError, match="name is used twice"):
        _decode(text, "bad.toml")


def test_unknown_type_suggests_closest():
    msg = errors_of(BASE.replace('type = "Attemperator"', 'type = "Atemperator"'))
    assert "[components.att], key 'type', line 32" in msg
    assert "did you mean 'Attemperator'?" in msg


def test_unknown_parameter_suggests_closest():
    msg = errors_of(BASE.replace('T_lag = "5 s"', 'T_lag = "5 s"\ntua = 3'))
    assert "[components.sensor], key 'tua'" in msg and "did you mean 'tau'?" in msg


def test_missing_parameter():
    msg = errors_of(BASE.replace('V = "0.3 m3"\n', ""))
    assert "[components.att], key 'V'" in msg and "missing required parameter" in msg


def test_wrong_dimension():
    msg = errors_of(BASE.replace('V = "0.3 m3"', 'V = "0.3 bar"'))
    assert "key 'V', line 33" in msg
    assert "pressure" in msg and "volume" in msg


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('p = "100 bar"', 'p = "-1 bar"', ["key 'p'", "out of", "pressure"]),
        ('p = "100 bar"', "p = 0", ["key 'p'", "out of the physical range"]),
        ('V = "0.3 m3"', 'V = "0 m3"', ["key 'V'", "out of the physical range", "volume"]),
        ('T = "200 degC"', 'T = "-300 degC"', ["key 'T'", "out of the physical range"]),
        ('T_lag = "5 s"', 'T_lag = "-5 s"', ["key 'T_lag'", "out of range", "at least 0 s"]),
    ],
)
def test_out_of_range(old, new, words):
    msg = errors_of(BASE.replace(old, new))
    for w in words:
        assert w in msg


def test_time_function_values_are_range_checked():
    text = BASE.replace(
        'p = "100 bar"', 'p = { type = "ramp", t0 = 0, t1 = 10, start = "100 bar", end = "-1 bar" }'
    )
    assert "out of the physical range" in errors_of(text)


def test_unconnected_fluid_port():
    msg = errors_of(
        BASE.replace(
            'ports = { steam_in = "n_steam", water_in = "n_spray", outlet = "n_mix" }',
            'ports = { steam_in = "n_steam", outlet = "n_mix" }',
        )
    )
    assert "unconnected port" in msg and "'water_in'" in msg and "[components.att]" in msg


def test_dangling_node():
    msg = errors_of(BASE.replace('ports = { port = "n_turbine" }', 'ports = { port = "n_turb" }'))
    assert "unconnected port" in msg and "'n_turbine'" in msg and "'n_turb'" in msg


def test_unlinked_signal_input():
    msg = errors_of(BASE.replace('inputs = { measured = "sensor.T" }', ""))
    assert "unconnected port" in msg and "'measured'" in msg


def test_node_named_like_a_component():
    msg = errors_of(BASE.replace('"n_mix"', '"sensor"'))
    assert "name used twice" in msg and "'sensor'" in msg


def test_signal_input_wired_to_a_node():
    msg = errors_of(
        BASE.replace(
            'ports = { inlet = "n_water", outlet = "n_spray" }\ninputs = { z = "pi.z" }',
            'ports = { inlet = "n_water", outlet = "n_spray", z = "n_spray" }',
        )
    )
    assert "[components.spray_valve.ports], key 'z'" in msg
    assert "a signal cannot be wired to a node" in msg


def test_signal_linked_from_a_fluid_port():
    msg = errors_of(BASE.replace('measured = "sensor.T"', 'measured = "att.outlet"'))
    assert "'att.outlet' is a fluid port" in msg and "[components.pi.inputs], key 'measured'" in msg


def test_fluid_port_in_inputs():
    msg = errors_of(
        BASE.replace('inputs = { z = "pi.z" }', 'inputs = { z = "pi.z", inlet = "pi.z" }')
    )
    assert "'inlet' is a fluid port of Valve: a signal cannot be wired to a fluid port" in msg


def test_unknown_signal_source():
    msg = errors_of(BASE.replace('z = "pi.z"', 'z = "pid.z"'))
    assert "no component named 'pid'" in msg and "did you mean 'pi'?" in msg


def test_all_problems_reported_together():
    text = BASE.replace('V = "0.3 m3"', 'V = "0.3 bar"').replace('T_lag = "5 s"', "tua = 3")
    with pytest.raises(PlantError) as info:
        spec_of(text)
    assert len(info.value.errors) >= 2


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('t_end = "20 min"', 't_end = "20 bar"', ["[simulation], key 't_end'", "time"]),
        ('t_end = "20 min"\n', "", ["key 't_end'", "missing"]),
        ("rtol = 1e-6", "rtol = 2", ["key 'rtol'"]),
        ("max_order = 4", "max_order = 9", ["key 'max_order'", "1 to 5"]),
        ("max_order = 4", "max_order = true", ["key 'max_order'"]),
        ('start = "steady"', 'start = "warm"', ["key 'start'", "steady"]),
        ("rtol = 1e-6", "rtl = 1e-6", ["key 'rtl'", "did you mean 'rtol'"]),
    ],
)
def test_simulation_table_errors(old, new, words):
    msg = errors_of(BASE.replace(old, new, 1))
    for w in words:
        assert w in msg


@pytest.mark.parametrize(
    "value, words",
    [
        ('{ type = "stp", t0 = 1, before = 1, after = 2 }', ["did you mean 'step'"]),
        ('{ type = "step", t0 = 1, before = "540 degC" }', ["key 'after'", "missing"]),
        ('{ type = "ramp", t0 = 10, t1 = 5, start = 800, end = 810 }', ["t1 > t0"]),
        ('{ type = "table", times = [0, 1], values = [800] }', ["'times' has 2"]),
        ('{ type = "table", times = [1, 0], values = [800, 810] }', ["increase"]),
        ("{ t0 = 1, before = 1, after = 2 }", ["needs 'type'"]),
        ('{ type = "step", t0 = "1 bar", before = 800, after = 810 }', ["key 't0'", "time"]),
    ],
)
def test_time_function_errors(value, words):
    msg = errors_of(BASE.replace('T = "540 degC"', f"T = {value}"))
    assert "[components.steam.T]" in msg or "[components.steam]" in msg
    for w in words:
        assert w in msg


def test_time_function_on_a_constant_parameter():
    msg = errors_of(BASE.replace('V = "0.3 m3"', 'V = { type = "constant", value = 1 }'))
    assert "constant parameter" in msg


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('type = "Valve"', "type = 3", ["key 'type'", "expected the name"]),
        ('medium = "Water"', "medium = 3", ["key 'medium'", "expected a string"]),
        ('T_lag = "5 s"', "T_lag = true", ["key 'T_lag'", "boolean"]),
        ('T_lag = "5 s"', "T_lag = [5]", ["key 'T_lag'", "array"]),
        ('ports = { port = "n_turbine" }', 'ports = "n_turbine"', ["key 'ports'"]),
        ('inputs = { z = "pi.z" }', "inputs = 3", ["key 'inputs'"]),
        ('z = "pi.z"', "z = 3", ["component.output"]),
        ('medium = "Water"', 'medium = "Water"\ndescription = 4', ["key 'description'"]),
    ],
)
def test_type_swaps(old, new, words):
    msg = errors_of(BASE.replace(old, new, 1))
    for w in words:
        assert w in msg


def test_bad_component_name():
    msg = errors_of(BASE.replace("[components.turbine]", '[components."tur.bine"]'))
    assert "invalid component name" in msg


def test_unknown_top_level_table():
    msg = errors_of(BASE + "\n[simulaton]\nx = 1\n")
    assert "did you mean 'simulation'" in msg


def test_no_components():
    msg = errors_of(BASE.split("[components.steam]")[0])
    assert "no components" in msg


def test_missing_file(tmp_path):
    with pytest.raises(PlantError, match="no such plant file"):
        load(tmp_path / "nope.toml")


def test_not_utf8(tmp_path):
    p = tmp_path / "x.toml"
    p.write_bytes(b"\xff\xfe[simulation]")
    with pytest.raises(PlantError, match="UTF-8"):
        load(p)


# ------------------------------------------------------------------ random mutations


def _toml_key(k: str) -> str:
    import json
    import re

    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def _toml_value(v) -> str:
    import json
    import math

    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(v)


def to_toml(data: dict) -> str:
    """A small TOML writer for plant-file shaped data (tables of tables of values)."""
    lines = []
    for k, v in data.items():
        if not isinstance(v, dict):
            lines.append(f"{_toml_key(k)} = {_toml_value(v)}")
    for k, v in data.items():
        if isinstance(v, dict):
            if k == "components" and all(isinstance(c, dict) for c in v.values()):
                for name, comp in v.items():
                    lines.append(f"\n[components.{_toml_key(name)}]")
                    lines += [f"{_toml_key(a)} = {_toml_value(b)}" for a, b in comp.items()]
            else:
                lines.append(f"\n[{_toml_key(k)}]")
                lines += [f"{_toml_key(a)} = {_toml_value(b)}" for a, b in v.items()]
    return "\n".join(lines) + "\n"


def test_toml_writer_round_trips_the_base_file():
    import tomllib

    data = tomllib.loads(BASE)
    assert tomllib.loads(to_toml(data)) == data


def _paths(d, prefix=()):
    out = []
    for k, v in d.items():
        out.append(prefix + (k,))
        if isinstance(v, dict):
            out += _paths(v, prefix + (k,))
    return out


def _random_values():
    from hypothesis import strategies as st

    units = ["bar", "degC", "K", "kg/s", "t/h", "min", "m3", "W/(m2.K)", "%", "furlong", ""]
    scalars = st.one_of(
        st.integers(-(10**6), 10**6),
        st.floats(allow_nan=True, allow_infinity=True),
        st.booleans(),
        st.text(max_size=12),
        st.builds(lambda x, u: f"{x} {u}", st.floats(-1e6, 1e6), st.sampled_from(units)),
        st.sampled_from(["steady", "given", "Water", "Air", "pi.z", "sensor.T", "n_mix", "x.y.z"]),
    )
    return st.one_of(
        scalars,
        st.lists(scalars, max_size=3),
        st.dictionaries(
            st.sampled_from(["type", "t0", "t1", "before", "after", "times", "values", "x"]),
            st.one_of(scalars, st.lists(scalars, max_size=3)),
            max_size=4,
        ),
    )


def _mutations():
    from hypothesis import strategies as st

    op = st.sampled_from(["drop", "replace", "rename", "to_string", "to_list", "to_table"])
    return st.lists(st.tuples(op, st.integers(0, 10**6), _random_values()), min_size=1, max_size=4)


def _apply(data, mutations):
    import copy

    data = copy.deepcopy(data)
    for op, pick, value in mutations:
        paths = _paths(data)
        if not paths:
            break
        path = paths[pick % len(paths)]
        parent = data
        for k in path[:-1]:
            parent = parent[k]
        key = path[-1]
        old = parent[key]
        if op == "drop":
            del parent[key]
        elif op == "replace":
            parent[key] = value
        elif op == "rename":
            parent[key[:-1] + "x" if len(key) > 1 else key + "_"] = parent.pop(key)
        elif op == "to_string":
            parent[key] = str(old)
        elif op == "to_list":
            parent[key] = [old] if not isinstance(old, dict) else list(old)
        else:
            parent[key] = {"value": old} if not isinstance(old, dict) else "table"
    return data


def test_random_mutations_never_give_a_traceback():
    """Mutated plant files (keys dropped, values changed, types swapped, lines cut):
    `dnasim check` answers with exit 0 or a message and exit 2, never a traceback."""
    import tempfile
    import tomllib
    from pathlib import Path

    from click.testing import CliRunner
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from dnasim.cli.commands import main

    plant_file = Path(__file__).resolve().parents[1] / "plants" / "attemperator.toml"
    base = tomllib.loads(plant_file.read_text())
    assert tomllib.loads(to_toml(base)) == base
    runner = CliRunner()
    tmp = Path(tempfile.mkdtemp())

    @settings(
        max_examples=int(os.environ.get("DNASIM_FUZZ_EXAMPLES", "40")),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(_mutations(), st.integers(0, 10**6), st.booleans())
    def check(mutations, cut, cut_line):
        text = to_toml(_apply(base, mutations))
        if cut_line:  # also damage the text itself now and then
            lines = text.splitlines()
            del lines[cut % len(lines)]
            text = "\n".join(lines)
        path = tmp / "mutant.toml"
        path.write_text(text)
        result = runner.invoke(main, ["check", str(path)])
        if result.exception is not None and not isinstance(result.exception, SystemExit):
            raise result.exception
        assert result.exit_code in (0, 2), result.output
        assert "Traceback" not in result.output
        if result.exit_code == 2:
            assert "dnasim: error: " in result.output, result.output
            assert str(path) in result.output

    check()


# ------------------------------------------------------------------ Python API


def test_load_plant_gives_the_python_api_plant():
    from pathlib import Path

    import dnasim
    from dnasim.plant.plant import Plant

    plant = dnasim.load_plant(Path(__file__).resolve().parents[1] / "plants" / "air_pipe.toml")
    assert isinstance(plant, Plant)
    assert set(plant.components) == {"inlet", "pipe", "valve", "outlet"}
    s = plant.simulation
    assert s.start == "given" and s.t_end == 1800.0
    res = plant.simulate(
        60.0, rtol=s.rtol, atol_scaled=s.atol_scaled, max_order=s.max_order, start=s.start
    )
    assert res.success
    df = res.to_dataframe()
    assert "pipe.T_out" in df.columns and len(df) == len(res.t)


def test_docs_example_is_a_valid_plant():
    import re
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "plant_files.md").read_text()
    example = re.search(r"```toml\n(.*?)```", doc, re.S).group(1)
    spec = spec_of(example, "docs/plant_files.md")
    assert {c.name for c in spec.components} >= {"steam", "att", "pi", "turbine"}
    from dnasim.plant.plantfile import build_plant

    report = build_plant(spec).check()
    assert report.ok, str(report)
