"""Plant files that keep working (issue 24 item 5): ``[plant] format``, the table of
migrations (dnasim.plant.migrations) and ``dnasim upgrade``.

The files under tests/plants/old/ are written for dnasim as it was on 2026-11-21:
attemperator and air_pipe are the repository's own plants/ files of commit
a0163cd, unchanged (``atol``, the sensor's ``tau``, a PI controller whose default
had no anti-windup); extraction_sink is a sink with that version's sign (m > 0
out of the plant)."""

from __future__ import annotations

import re
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.plant import migrations as pm
from dnasim.plant.plantfile import load, loads

HERE = Path(__file__).parent
OLD = HERE / "plants" / "old"
ATT = OLD / "attemperator_2026-11-21.toml"
AIR = OLD / "air_pipe_2026-11-21.toml"
SINK = OLD / "extraction_sink_2026-11-21.toml"


@pytest.fixture(autouse=True)
def _notices_as_warnings(monkeypatch):
    """Each test starts with notices going to ``warnings`` and none seen yet (a
    command run in this process routes them to its output and remembers them)."""
    monkeypatch.setattr(pm, "NOTICE", None)
    monkeypatch.setattr(pm, "_SEEN", set())


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return result


def notices_of(path) -> tuple[object, list[str]]:
    pm.NOTICE = None  # as warnings, also after a command of this test (fixture restores)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        loaded = load(path)
    return loaded, [str(w.message) for w in caught if w.category is pm.PlantFileNotice]


def upgraded(path: Path, tmp_path: Path) -> Path:
    out = tmp_path / ("new_" + path.name)
    res = invoke("upgrade", path, "-o", out)
    assert res.exit_code == 0, res.output
    return out


# ------------------------------------------------------------------ notices


def test_old_keys_give_one_notice_line_each_naming_file_table_key_and_new_key():
    _loaded, notes = notices_of(ATT)
    atol = [n for n in notes if "key 'atol'" in n]
    tau = [n for n in notes if "key 'tau'" in n]
    assert len(atol) == 1 and len(tau) == 1
    for n, table, new in (
        (atol[0], "[simulation]", "atol_scaled"),
        (tau[0], "[components.sensor]", "T_lag"),
    ):
        assert "\n" not in n
        assert n.startswith(f"{ATT}, {table}, key ")
        assert re.search(r"line \d+", n) and f"'{new}'" in n and "dnasim upgrade" in n
    # the line is where the key is
    line = int(re.search(r"line (\d+)", atol[0]).group(1))
    assert ATT.read_text().splitlines()[line - 1].startswith("atol =")


def test_old_keys_keep_their_meaning():
    loaded, _notes = notices_of(ATT)
    assert loaded.simulation.atol_scaled == 1e-6  # atol = 1e-6 in the file
    spec = {c.name: c for c in loaded.spec.components}
    assert spec["sensor"].params["tau"] == 5.0  # read by the sensor as its T_lag
    # written before anti_windup's default became true: read with the old default
    assert spec["pi"].params["anti_windup"] is False


def test_notice_on_the_command_line(tmp_path):
    res = invoke("check", AIR)
    assert res.exit_code == 0
    lines = [x for x in res.output.splitlines() if x.startswith("dnasim: notice:")]
    assert any("[simulation], key 'atol'" in x and "'atol_scaled'" in x for x in lines)


def test_current_files_get_no_notice():
    for f in ("attemperator.toml", "air_pipe.toml", "superheater_line.toml"):
        _loaded, notes = notices_of(HERE.parent / "plants" / f)
        assert notes == [], f


# ------------------------------------------------------------------ format 2 refuses


def test_format_2_refuses_an_old_key_naming_the_new_one():
    text = ATT.read_text().replace('name = "attemperator"', 'name = "attemperator"\nformat = 2')
    with pytest.raises(PlantError) as exc:
        loads(text, "att.toml")
    msg = str(exc.value)
    assert "att.toml, [simulation], key 'atol', line 26" in msg
    assert "renamed 'atol_scaled'" in msg and "write atol_scaled = 1e-06" in msg
    assert "[components.sensor], key 'tau'" in msg and "'T_lag'" in msg


@pytest.mark.parametrize(
    ("value", "words"),
    [("3", ["format 3 is newer", "upgrade dnasim"]), ('"2"', ["integer"]), ("0", ["integer"])],
)
def test_bad_format_is_a_located_error(value, words):
    text = AIR.read_text().replace('medium = "Air"', f'medium = "Air"\nformat = {value}')
    with pytest.raises(PlantError) as exc:
        loads(text, "air.toml")
    msg = str(exc.value)
    assert msg.startswith("air.toml, [plant], key 'format', line 12: ")
    assert all(w in msg for w in words), msg


def test_atol_and_atol_scaled_together_are_refused():
    text = AIR.read_text().replace("atol = 1e-6", "atol = 1e-6\natol_scaled = 1e-7")
    with pytest.raises(PlantError, match="former name of 'atol_scaled': give one"):
        loads(text, "air.toml")


# ------------------------------------------------------------------ the old sink


def test_old_sink_sign_stops_naming_the_convention():
    with pytest.raises(PlantError) as exc:
        load(SINK)
    msg = str(exc.value)
    assert f"{SINK}, [components.extraction], key 'm', line 36:" in msg
    assert "ambiguous" in msg and "INTO the plant" in msg and "OUT of the plant" in msg
    assert "dnasim upgrade" in msg and "h, T or x" in msg


def test_old_sink_in_format_2_is_refused_with_the_sign_named():
    text = (
        SINK.read_text()
        .replace('name = "extraction_sink"', 'name = "extraction_sink"\nformat = 2')
        .replace("atol = 1e-6", "atol_scaled = 1e-6")
    )
    with pytest.raises(PlantError) as exc:
        loads(text, "sink.toml")
    msg = str(exc.value)
    assert "[components.extraction], key 'm'" in msg and "m > 0 is the flow INTO" in msg
    assert "ambiguous" not in msg


def test_source_and_new_sink_are_not_taken_for_old_sinks():
    text = SINK.read_text().replace(
        'before = "2 kg/s", after = "2.5 kg/s"', 'before = "-2 kg/s", after = "-2.5 kg/s"'
    )
    with pytest.warns(pm.PlantFileNotice, match="'atol' read as"):  # its only notice
        loads(text, "sink.toml")  # a sink written the current way: m < 0
    text = SINK.read_text().replace(
        'm_nominal = "2 kg/s"\nports = { port = "n_out" }',
        'm_nominal = "2 kg/s"\nT = "300 degC"\nports = { port = "n_out" }',
    )
    assert 'T = "300 degC"' in text
    with pytest.warns(pm.PlantFileNotice, match="'atol' read as"):
        loads(text, "source.toml")  # h or T given: a source, m > 0 into the plant always


# ------------------------------------------------------------------ dnasim upgrade


def test_upgrade_keeps_comments_and_layout_and_prints_each_change(tmp_path):
    out = tmp_path / "new.toml"
    res = invoke("upgrade", ATT, "-o", out)
    assert res.exit_code == 0, res.output
    old, new = ATT.read_text(), out.read_text()
    for line in old.splitlines():  # every comment and every untouched line is kept
        if not re.match(r"^(atol|tau) =", line):
            assert line in new.splitlines(), line
    assert "atol_scaled = 1e-6" in new and 'T_lag = "5 s"' in new and "atol =" not in new
    data = tomllib.loads(new)
    assert data["plant"]["format"] == pm.CURRENT_FORMAT
    assert data["components"]["pi"]["anti_windup"] is False
    printed = [x for x in res.output.splitlines() if x.startswith("dnasim: upgrade:")]
    assert any("[simulation], key 'atol', line 25: 'atol' -> 'atol_scaled'" in x for x in printed)
    assert any("[components.sensor], key 'tau', line 59: 'tau' -> 'T_lag'" in x for x in printed)
    assert any("[components.pi]" in x and "anti_windup = false added" in x for x in printed)
    # the pipe relies on a default that changed at a time the file cannot be placed against
    assert any("review: internal_energy not given" in x for x in res.output.splitlines())
    # the new file loads without a notice, and upgrading it again changes nothing
    _loaded, notes = notices_of(out)
    assert notes == []
    again = invoke("upgrade", out)
    assert again.exit_code == 0 and "already in the current format" in again.output


def test_upgrade_in_place_and_to_stdout(tmp_path):
    f = tmp_path / "air.toml"
    f.write_text(AIR.read_text())
    res = invoke("upgrade", f)
    assert res.exit_code == 0
    assert "format = 2" in res.stdout and f.read_text() == AIR.read_text()  # stdout only
    res = invoke("upgrade", f, "--in-place")
    assert res.exit_code == 0 and "format = 2" in f.read_text()
    assert invoke("upgrade", f, "--in-place", "-o", tmp_path / "x.toml").exit_code == 2
    assert invoke("upgrade", tmp_path / "missing.toml").exit_code == 2


def test_upgrade_negates_the_old_sink(tmp_path):
    out = upgraded(SINK, tmp_path)
    m = tomllib.loads(out.read_text())["components"]["extraction"]["m"]
    assert (m["before"], m["after"]) == ("-2 kg/s", "-2.5 kg/s")
    assert "# a sink: 2 kg/s leave the plant" in out.read_text()


def test_upgraded_sink_takes_the_old_flow_out_of_the_plant(tmp_path):
    """The meaning the old file was written with: 2 kg/s, then 2.5 kg/s, leave the
    plant at the extraction. Conservation: at steady state the header supplies what
    the extraction takes (the pipe's storage changes only after the step)."""
    res = load(upgraded(SINK, tmp_path)).simulate()
    t = np.asarray(res.t)
    m_ext, m_hdr = np.asarray(res["extraction.m"]), np.asarray(res["header.m"])
    before, end = t < 5.0, t > 19.0
    # the flows are prescribed (exact) or balance the prescribed one within the
    # solver's tolerance (rtol 1e-6 of 2 kg/s, a margin of 100)
    np.testing.assert_allclose(m_ext[before], -2.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m_ext[end], -2.5, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m_hdr[before], 2.0, rtol=0, atol=2e-4)
    np.testing.assert_allclose(m_hdr[end], 2.5, rtol=0, atol=2e-3)


@pytest.mark.parametrize(("path", "t_end"), [(ATT, 150.0), (AIR, 120.0)])
def test_old_file_and_its_upgraded_copy_give_identical_results(path, t_end, tmp_path):
    old, _notes = notices_of(path)
    new = load(upgraded(path, tmp_path))
    a, b = old.simulate(t_end=t_end), new.simulate(t_end=t_end)
    assert list(a.keys()) == list(b.keys())
    np.testing.assert_array_equal(a.t, b.t)  # bit for bit: the same plant
    for k in a.keys():
        np.testing.assert_array_equal(np.asarray(a[k]), np.asarray(b[k]), err_msg=k)


def test_table_entries_are_real_keys_of_today():
    """Each migration's new key exists today (a rename to a key that does not exist
    would turn a notice into an error)."""
    from dnasim.plant.plantfile import SIMULATION_KEYS, _registry, params_of

    reg = _registry()
    for m in pm.MIGRATIONS:
        if m.table == "simulation":
            assert m.new in SIMULATION_KEYS
        else:
            cls = reg[m.table.split(".", 1)[1]]
            assert m.new in [p.name for p in params_of(cls)], m
        assert re.fullmatch(r"[0-9a-f]{7}", m.commit) and m.since == pm.CURRENT_FORMAT


def test_upgrade_refuses_old_and_new_key_together(tmp_path):
    f = tmp_path / "both.toml"
    f.write_text(AIR.read_text().replace("atol = 1e-6", "atol = 1e-6\natol_scaled = 1e-7"))
    res = invoke("upgrade", f, "--in-place")
    assert res.exit_code == 2
    assert f"{f}, [simulation], key 'atol', line 16: " in res.output and "give one" in res.output
    assert "format" not in f.read_text()  # left as it was


def test_parse_plant_of_decoded_data_accepts_and_checks_format():
    """Data decoded by the caller (not through the plant-file reader) may carry
    ``format`` too: the version is checked, the rest read as usual."""
    from dnasim.plant.plantfile import parse_plant

    data = tomllib.loads((HERE.parent / "plants" / "air_pipe.toml").read_text())
    data["plant"]["format"] = 2
    assert parse_plant(data, "air.toml").name == "air_pipe"
    data["plant"]["format"] = 7
    with pytest.raises(PlantError, match=r"air.toml, \[plant\], key 'format': format 7 is newer"):
        parse_plant(data, "air.toml")
