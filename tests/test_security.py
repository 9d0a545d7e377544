"""Security and faults (issue 25): plant files run no code, sweeps never present stale
results or leave workers behind, output that does not fit is one paragraph, every
option's input is checked, CSV cells are safe for spreadsheets, every message is
located, vessels and media are validated, and the docs state the trust model.
One test (or a small group) per item of the issue.

The sweeps run tests/plants/lag_sensor.toml (an air supply, a valve, a sink and a
temperature sensor) for 20 s: about 0.3 s of CPU per case.
"""

from __future__ import annotations

import os
import re
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.run.output import read_results_csv, write_events_csv

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "plants"
LAG = (
    (ROOT / "tests" / "plants" / "lag_sensor.toml")
    .read_text()
    .replace('t_end = "60 s"', 't_end = "20 s"')
)
DNASIM = [sys.executable, "-m", "dnasim"]


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


def plant(tmp_path, text, name="p.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def assert_located(result, *words):
    """Exit 2, one message naming the place, no internal error, no traceback."""
    out = result.output if hasattr(result, "output") else result.stderr
    code = result.exit_code if hasattr(result, "exit_code") else result.returncode
    assert code == 2, out
    assert "internal error" not in out and "Traceback" not in out, out
    for w in words:
        assert w in out, (w, out)


def _no_temporary_files(directory: Path) -> list[Path]:
    return [p for p in directory.rglob("*") if p.name.endswith(".tmp")]


# --------------------------------------------------------------------------- 1. no code


EVIL = """
from pathlib import Path
Path(__file__).with_name("RAN").write_text("the module ran")
"""


def test_a_plant_file_runs_no_code_without_the_opt_in(tmp_path):
    (tmp_path / "evil.py").write_text(EVIL)
    text = LAG.replace('medium = "Air"', 'medium = "Air"\nimport = ["evil"]', 1)
    path = plant(tmp_path, text)
    for args in (
        ["check", path],
        ["run", path, "-o", tmp_path / "out", "-q"],
        ["sweep", path, "-o", tmp_path / "sw", "--set", "sensor.tau=4,5", "-j", "1", "-q"],
    ):
        res = invoke(*args)
        assert_located(res, "p.toml", "[plant]", "key 'import'", "line ", "'evil'", "evil.py")
        assert "--allow-import" in res.output and "runs its code" in res.output
        assert res.output.count("dnasim: error") == 1  # one paragraph
        assert not (tmp_path / "RAN").exists(), args
    with pytest.raises(PlantError, match="not imported"):
        from dnasim.plant.plantfile import load

        load(path)
    assert not (tmp_path / "RAN").exists()
    # the user's opt-in: the module is imported (and its code runs)
    res = invoke("check", "--allow-import", path)
    assert res.exit_code == 0, res.output
    assert (tmp_path / "RAN").exists()


# --------------------------------------------------------------------------- 2. stale sweeps


def _final(sw_dir: Path, name: str) -> list[float]:
    summary = pd.read_csv(sw_dir / "summary.csv")
    return list(summary[[c for c in summary.columns if c.startswith(f"{name} final")][0]])


def test_a_sweep_runs_again_after_the_plant_or_a_setting_changed(tmp_path):
    path = plant(tmp_path, LAG)
    sw = tmp_path / "sw"
    args = ["sweep", path, "-o", sw, "--set", "sensor.tau=4,6", "-j", "1"]
    res = invoke(*args)
    assert res.exit_code == 0, res.output
    assert "ran 2, skipped 0" in res.output
    m_before = _final(sw, "valve.m")
    assert "ran 0, skipped 2" in invoke(*args).output  # unchanged: nothing runs
    # the sink's back pressure 1 -> 0.6 bar: every case runs again, with the new plant
    path.write_text(LAG.replace('p = "1 bar"', 'p = "0.6 bar"'))
    res = invoke(*args)
    assert res.exit_code == 0, res.output
    assert "ran 2, skipped 0" in res.output
    assert "run with another plant or other settings" in res.output
    m_after = _final(sw, "valve.m")
    # a larger pressure drop over the valve: more flow (sqrt law), far beyond round-off
    assert all(a > 1.05 * b for a, b in zip(m_after, m_before, strict=True))
    # another --output-interval: the rows of every case change, so they run again
    res = invoke(*args, "--output-interval", "1 s")
    assert "ran 2, skipped 0" in res.output, res.output
    _, _, data = read_results_csv(sw / "case_0000" / "results.csv")
    t = data["time"]
    assert np.all(np.isin(np.arange(0.0, 21.0), t))  # the 1 s grid (restart rows besides)
    assert "ran 0, skipped 2" in invoke(*args, "--output-interval", "1 s").output


def test_collect_reads_only_folders_of_this_plant(tmp_path):
    from dnasim.plant.plantfile import loads
    from dnasim.tools import sweeps

    spec = loads(LAG, "lag.toml").spec
    cases = [{"sensor.tau": "4 s"}]
    sweeps.sweep(spec, cases, out_dir=tmp_path, progress=False)
    other = loads(LAG.replace('p = "1 bar"', 'p = "0.6 bar"'), "lag.toml").spec
    assert sweeps.plant_fingerprint(other) != sweeps.plant_fingerprint(spec)
    summary, ds = sweeps.collect(other, cases, tmp_path)
    assert list(summary["status"]) == ["not run"]
    assert np.all(np.isnan(ds["valve.m"].values)) if "valve.m" in ds else True


# --------------------------------------------------------------------------- 3. no orphans


def _group(pgid: int) -> list[tuple[int, str]]:
    """Live processes of the process group ``pgid`` (from /proc)."""
    out = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            stat = Path(f"/proc/{d}/stat").read_text()
            cmd = Path(f"/proc/{d}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if int(fields[2]) == pgid and fields[0] != "Z":
            out.append((int(d), cmd[:120]))
    return out


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc (Linux)")
def test_sigkill_of_a_sweep_leaves_no_process_of_its_group(tmp_path):
    # long cases (max_step 1 ms over 1000 s): both workers are busy when the sweep dies
    text = LAG.replace('t_end = "20 s"', 't_end = "1000 s"\nmax_step = "0.001 s"')
    path = plant(tmp_path, text)
    temp = tmp_path / "temp"  # the workers' temporary case directories
    temp.mkdir()
    proc = subprocess.Popen(
        [*DNASIM, "sweep", path, "-o", tmp_path / "sw", "--set", "sensor.tau=4,5,6", "-j", "2"],
        start_new_session=True,  # its own process group, as a shell job or a CI step
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=tmp_path,
        env={**os.environ, "TMPDIR": str(temp)},
    )
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            workers = [c for _, c in _group(proc.pid) if "spawn_main" in c]
            if len(workers) >= 2:
                break
            time.sleep(0.2)
        assert len(workers) >= 2, _group(proc.pid)
        time.sleep(4.0)  # the workers import dnasim and start their cases
        os.kill(proc.pid, signal.SIGKILL)  # an out-of-memory kill: no handler runs
        proc.wait(timeout=10)
        deadline = time.monotonic() + 10  # the workers poll their parent every 0.5 s
        while _group(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert _group(proc.pid) == []
        # nobody holds the sweep's stdout open: reading it ends
        assert proc.stdout.read() == b""
        # the workers removed their cases' temporary directories on the way out
        assert list(temp.glob("dnasim-case-*")) == []
    finally:
        for pid, _ in _group(proc.pid):
            os.kill(pid, signal.SIGKILL)
        proc.stdout.close()
        proc.stderr.close()


# --------------------------------------------------------------------------- 4. full disk


def _limit_file_size(nbytes):
    def preexec():
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes fail with EFBIG

    return preexec


def _can_limit_file_size() -> bool:
    try:
        soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    except (ValueError, OSError):
        return False
    return hard == resource.RLIM_INFINITY or hard >= 200_000


@pytest.mark.skipif(not _can_limit_file_size(), reason="no RLIMIT_FSIZE")
def test_a_sweep_whose_sweep_nc_does_not_fit_is_one_paragraph_and_resumes(tmp_path):
    """RLIMIT_FSIZE 60 kB: each case's files (about 10 kB) fit, sweep.nc (6 cases times
    501 points times 20 outputs) does not."""
    path = plant(tmp_path, LAG)
    sw = tmp_path / "sw"
    cmd = [*DNASIM, "sweep", path, "-o", sw, "--set", "sensor.tau=4,5,6,7,8,9", "-j", "2"]
    proc = subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=_limit_file_size(60_000),
        cwd=tmp_path,
    )
    assert_located(proc, "sweep.nc", "file size limit", "6 of the 6 cases", "same command again")
    assert proc.stderr.count("dnasim: error") == 1 and "HDF5" not in proc.stderr
    assert not (sw / "sweep.nc").exists() and not (sw / "summary.csv").exists()
    assert _no_temporary_files(sw) == []
    for i in range(6):
        assert (sw / f"case_{i:04d}" / "done.json").exists()
    # resumed without the limit: nothing runs again, both files are written
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "ran 0, skipped 6" in proc.stdout
    assert (sw / "sweep.nc").exists() and (sw / "summary.csv").exists()


@pytest.mark.skipif(not _can_limit_file_size(), reason="no RLIMIT_FSIZE")
def test_a_run_whose_report_does_not_fit_exits_2_and_keeps_its_results(tmp_path):
    """RLIMIT_FSIZE 1 MB: air_pipe's results.csv (130 kB), plots and report.html (100 kB)
    fit, the report's plotly.min.js beside it (4.8 MB) does not: the report is not
    written (a page without its script would be torn)."""
    out = tmp_path / "out"
    proc = subprocess.run(
        [*DNASIM, "run", PLANTS / "air_pipe.toml", "-o", out, "-q", "--report"],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=_limit_file_size(1_000_000),
        cwd=tmp_path,
    )
    assert_located(proc, "plotly.min.js", "file size limit", "results.csv", "complete")
    assert not (out / "report.html").exists()
    assert _no_temporary_files(out) == []
    names, _, data = read_results_csv(out / "results.csv")
    assert data["time"][-1] == 1800.0  # the whole run is on disk


# --------------------------------------------------------------------------- 5. option input


def test_cases_files_are_checked_before_anything_runs(tmp_path):
    path = plant(tmp_path, LAG)
    sw = tmp_path / "sw"

    def sweep_cases(name, data: bytes, *words):
        f = tmp_path / name
        f.write_bytes(data)
        res = invoke("sweep", path, "-o", sw, "--cases", f, "-j", "1")
        assert_located(res, "option --cases", name, *words)
        assert not list(sw.glob("case_*"))

    sweep_cases("latin1.csv", b"sensor.tau,valve.C\n4,0.003\n5 \xb5s,0.003\n", "line 3, column 3")
    sweep_cases("dup.csv", b"sensor.tau,valve.C,sensor.tau\n4,0.003,5\n", "given twice")
    sweep_cases("big.csv", b'sensor.tau\n"' + b"4" * 200_000 + b'"\n', "line 2", "limit")
    sweep_cases("nul.csv", b"sensor.tau\n4\x00\n", "line 2", "NUL")
    sweep_cases("dup.toml", b'[[case]]\n"sensor.tau" = 4\nsensor = { tau = 5 }\n', "twice")
    if Path("/dev/zero").exists():  # endless: refused after the size limit, not read whole
        res = invoke("sweep", path, "-o", sw, "--cases", "/dev/zero", "-j", "1")
        assert_located(res, "/dev/zero", "larger than")


def test_sweep_output_size_is_refused_up_front_as_in_run(tmp_path):
    path = plant(tmp_path, LAG)
    res = invoke("run", path, "-o", tmp_path / "out", "--output-interval", "1e-9")
    assert_located(res, "output points")
    sw = tmp_path / "sw"
    res = invoke("sweep", path, "-o", sw, "--set", "sensor.tau=4,5", "--output-interval", "1e-9")
    assert_located(res, "option --output-interval", "output points", "limit")
    assert not list(sw.glob("case_*"))  # nothing ran
    res = invoke("sweep", path, "-o", sw, "--set", "simulation.output_interval=1,1e-9", "-j", "1")
    assert_located(res, "case 1", "output points")
    assert not list(sw.glob("case_*"))


@pytest.mark.parametrize(
    "address, words",
    [
        ("file:///etc/passwd", "scheme 'file://'"),
        ("http://127.0.0.1:8786", "scheme 'http://'"),
        ("inproc://x", "scheme 'inproc://'"),
        ("ucx://127.0.0.1:8786", "scheme 'ucx://'"),
        ("tcp://[::1", "closing ']'"),
        ("tcp://" + "h" * 300 + ":8786", "253"),
        ("tcp://127.0.0.1", "no port"),
        ("tcp://127.0.0.1:0", "port '0'"),
        ("tcp://bad_host!:8786", "not a host name"),
    ],
)
def test_scheduler_addresses_are_checked(tmp_path, address, words):
    path = plant(tmp_path, LAG)
    res = invoke(
        "sweep", path, "-o", tmp_path / "sw", "--set", "sensor.tau=4", "--scheduler", address
    )
    assert_located(res, "option --scheduler", words)
    assert res.output.count("dnasim: error") == 1


# --------------------------------------------------------------------------- 6. CSV cells


def test_every_csv_cell_is_safe_for_spreadsheets(tmp_path):
    from dnasim.run.output import spreadsheet_safe

    assert spreadsheet_safe('=HYPERLINK("http://x")') == '\'=HYPERLINK("http://x")'
    for text in ("@SUM(A1)", "+cmd", "-cmd", "\tx", "\rx"):
        assert spreadsheet_safe(text) == "'" + text
    for number in ("-1.5", "+2e5", "-inf", "nan", "0.25", "-1e-300"):
        assert spreadsheet_safe(number) == number  # numbers stay numbers
    # summary.csv: string values of a cases file (a medium name) are prefixed
    path = plant(tmp_path, LAG)
    cases = tmp_path / "cases.csv"
    cases.write_text('supply.medium,sensor.tau\n"=HYPERLINK(""http://x"")",4\n@SUM(A1),-1.5\n')
    res = invoke("sweep", path, "-o", tmp_path / "sw", "--cases", cases, "-j", "1")
    assert res.exit_code == 1, res.output  # both cases refuse their medium (or tau)
    text = (tmp_path / "sw" / "summary.csv").read_text()
    cells = [
        c
        for line in text.splitlines()
        for c in re.split(r",(?=(?:[^\"]*\"[^\"]*\")*[^\"]*$)", line)
    ]
    assert not any(c.lstrip('"').startswith(("=", "@")) for c in cells), text
    assert "'@SUM(A1)" in text and "'=HYPERLINK" in text
    assert ",-1.5," in text  # the number is a number
    # events.csv: a component name of the Python API, times below zero stay numbers
    write_events_csv(
        tmp_path / "events.csv",
        [{"component": "=cmd", "switch": "@x", "iterates": [(-1.5, -2.0)]}],
    )
    lines = (tmp_path / "events.csv").read_text().splitlines()
    assert lines[1] == "1,1,-1.5,-2.0,'=cmd,'@x"


# --------------------------------------------------------------------------- 7. messages


def test_malformed_files_are_located_by_line(tmp_path):
    text = (PLANTS / "attemperator.toml").read_text()
    lines = text.splitlines()
    lines.insert(20, "deep = " + "[" * 1000 + "]" * 1000)
    res = invoke("check", plant(tmp_path, "\n".join(lines) + "\n", "deep.toml"))
    assert_located(res, "deep.toml, line 21", "nested too deeply")
    raw = text.encode()
    i = raw.index(b"[components.steam]")
    bad = raw[:i] + b"# caf\xe9\n" + raw[i:]
    (tmp_path / "latin1.toml").write_bytes(bad)
    line = raw[:i].count(b"\n") + 1
    res = invoke("check", tmp_path / "latin1.toml")
    assert_located(res, f"latin1.toml, line {line}, column 6", "UTF-8")
    assert "byte 0xe9" in res.output


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('Kp = "0.02 1/K"', 'Kp = "0.02 degC"', ["key 'Kp'", "absolute temperature"]),
        ('T_i = "33.3 s" ', 'T_i = "33.3 s"\nz_min = 0.5\nz_max = 0.5\n', ["key 'z_max'"]),
    ],
)
def test_no_follow_on_errors_after_the_first_cause(tmp_path, old, new, words):
    text = (PLANTS / "attemperator.toml").read_text()
    assert old in text
    res = invoke("check", plant(tmp_path, text.replace(old, new)))
    assert_located(res, "p.toml", "[components.pi]", "line ", *words)
    assert res.output.count("p.toml,") == 1, res.output  # one problem, nothing that follows
    assert "not linked" not in res.output


@pytest.mark.parametrize(
    "source, old, new, words",
    [
        (  # a drum given a gas
            "drum_boiler.toml",
            'medium = "Water"',
            'medium = "FlueGas"',
            ["[components.drum]", "Drum", "two-phase (condensable) medium", "key 'medium'"],
        ),
        (  # a pipe's initial temperature below the NASA polynomials' range
            "air_pipe.toml",
            'T0 = "20 degC"',
            'T0 = "100 K"',
            ["[components.pipe]", "key 'T0'", "NASA"],
        ),
        (  # a turbine's nominal inlet state below IF97's range
            "feedwater_heater.toml",
            'T_in_nominal = "500 degC"',
            'T_in_nominal = "-100 degC"',
            ["[components.hp]", "key 'T_in_nominal'", "IF97"],
        ),
    ],
)
def test_property_range_errors_name_the_component_and_key(tmp_path, source, old, new, words):
    text = (PLANTS / source).read_text()
    assert old in text
    text = text.replace(old, new)
    if source == "air_pipe.toml":
        text = text.replace('medium = "Air"', 'medium = "FlueGas"')
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, "p.toml", "line ", *words)
    assert "cannot evaluate saturation_enthalpies" not in res.output


# --------------------------------------------------------------------------- 8. validation


def test_a_vessel_smaller_than_the_water_its_start_puts_in_it_is_refused(tmp_path):
    """feedwater_heater: the level PI holds 2.5 m over A = 12 m2 at the steady start,
    30 m3 of water; in a 20 m3 tank that is above its top (1.67 m)."""
    text = (PLANTS / "feedwater_heater.toml").read_text()
    small = text.replace('V_t = "60 m3"', 'V_t = "20 m3"').replace(
        'V_l0 = "30 m3"', 'V_l0 = "10 m3"'
    )
    assert small != text
    res = invoke("check", plant(tmp_path, small))
    assert_located(res, "[components.level_pi]", "key 'setpoint'", "deaerator", "1.66667 m")
    # the original tank (60 m3, top at 5 m) holds it
    assert invoke("check", plant(tmp_path, text, "ok.toml")).exit_code == 0


@pytest.mark.parametrize(
    "source, component",
    [
        ("feedwater_heater.toml", "deaerator"),
        ("../tests/plants/condenser_level_control.toml", "condenser"),
    ],
)
def test_two_phase_vessels_refuse_a_gas(tmp_path, source, component):
    text = (PLANTS / source).read_text().replace('medium = "Water"', 'medium = "Air"', 1)
    res = invoke("check", plant(tmp_path, text))
    assert_located(res, f"[components.{component}]", "two-phase (condensable) medium")


# --------------------------------------------------------------------------- 9. docs, notes


def test_docs_state_the_dask_trust_model():
    text = (ROOT / "docs" / "sweeps.md").read_text()
    assert "connect only to a scheduler you control" in text.lower()
    assert "pickles" in text and "run code" in text
    assert "--allow-import" in (ROOT / "docs" / "plant_files.md").read_text()


def test_check_notes_the_seeds_mean_internal_energy(tmp_path):
    text = (PLANTS / "attemperator.toml").read_text()
    text = text.replace("n_volumes = 4\n", 'n_volumes = 4\ninternal_energy = "mean"\n', 1)
    res = invoke("check", plant(tmp_path, text))
    assert res.exit_code == 0, res.output
    assert "note: " in res.output and "key 'internal_energy'" in res.output
    assert "colder than anything in the plant" in res.output
    assert "note" not in invoke("check", PLANTS / "attemperator.toml").output
