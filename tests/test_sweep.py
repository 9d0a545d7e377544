"""Sweeps (dnasim.sweep, dnasim sweep): a Dask cluster gives the serial results,
failures are recorded, sweep.nc reopens with its units, restarts skip done cases,
--set is parsed with units and its errors are located.

The plant is tests/plants/lag_sensor.toml: a sensor of time constant tau on the
node of an air supply whose temperature steps from 100 degC to 150 degC at 10 s,
so the reading is T1 - (T1 - T0) exp(-(t - 10 s)/tau) after the step (the closed
form the sweep's values are checked against).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main
from dnasim.plant.cases import CaseError, apply_case, parse_set_option, product_cases, read_cases
from dnasim.plant.plantfile import LoadedPlant, load
from dnasim.plant.spec import build_plant
from dnasim.run.output import read_results_csv
from dnasim.run.runner import run_plant
from dnasim.tools import sweeps

PLANT = Path(__file__).parent / "plants" / "lag_sensor.toml"
T0, T1, T_STEP = 373.15, 423.15, 10.0  # supply temperature before/after [K], step time [s]


@pytest.fixture(scope="module")
def spec():
    s = load(PLANT).spec
    s.simulation.t_end = 30.0  # short runs: 20 s after the step
    return s


def _serial(spec, case, out):
    """results.csv of one case run in this process, without the sweep machinery."""
    s = apply_case(spec, case)
    run_plant(LoadedPlant(build_plant(s), s.simulation, s, s.path), out)
    return read_results_csv(Path(out) / "results.csv")


CASES = product_cases({"sensor.tau": ["4 s", "8 s"], "valve.C": [0.003, "0.004 kg/(s.Pa0.5)"]})


def test_dask_cluster_equals_serial_runs(spec, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        sw = sweeps.sweep(
            spec, CASES, client.get_executor(), out_dir=tmp_path / "sw", progress=False
        )
    assert list(sw.summary["status"]) == ["finished"] * 4
    assert sw.ran == 4 and sw.skipped == 0
    ds = sw.dataset
    for i, case in enumerate(CASES):
        names, _, ref = _serial(spec, case, tmp_path / f"serial{i}")
        _, _, got = read_results_csv(tmp_path / "sw" / f"case_{i:04d}" / "results.csv")
        assert got["time"].shape == ref["time"].shape
        for n in names:
            # the same code on the same numbers in another process: equal to round-off
            # (1e-12 relative leaves room for a different BLAS summation order only)
            np.testing.assert_allclose(got[n], ref[n], rtol=1e-12, atol=0, err_msg=n)
        # sweep.nc: the case's rows interpolated to the common grid
        keep = np.r_[ref["time"][1:] > ref["time"][:-1], True]
        expect = np.interp(ds["time"].values, ref["time"][keep], ref["sensor.T_s"][keep])
        np.testing.assert_allclose(ds["sensor.T_s"].values[i], expect, rtol=1e-12)
        # against the closed form of the first-order lag, at the case's rows after the
        # step: the solver's rtol 1e-6 on ~420 K allows 4e-4 K per step; over the ~40
        # steps the global error stays below a few times that (9e-4 K measured): 3e-3 K
        tau = float(ds["sensor.tau"].values[i])
        t = got["time"]
        after = t >= T_STEP + 1.0
        closed = T1 - (T1 - T0) * np.exp(-(t[after] - T_STEP) / tau)
        np.testing.assert_allclose(got["sensor.T_s"][after], closed, rtol=0, atol=3e-3)


def test_failing_case_is_recorded_and_the_others_run(spec, tmp_path):
    cases = [
        {"sensor.tau": "-1 s"},  # out of range: an input error of this case
        {"simulation.max_steps": 5},  # the solver stops after 5 steps
        {"sensor.tau": "8 s"},
    ]
    sw = sweeps.sweep(spec, cases, out_dir=tmp_path, progress=False)
    assert list(sw.summary["status"]) == ["input-error", "failed", "finished"]
    back = pd.read_csv(tmp_path / "summary.csv")
    assert list(back["status"]) == ["input-error", "failed", "finished"]
    assert "[components.sensor], key 'tau'" in back["message"][0]
    assert "5 steps" in back["message"][1] and "max_steps" in back["message"][1]
    assert str(tmp_path) not in back["message"][1]  # no worker's temporary path
    assert back["t_reached [s]"][2] == pytest.approx(30.0, abs=0.0)
    # the failed case's curves end where it stopped: NaN after t_reached
    ds = sw.dataset
    t_stop = float(ds["t_reached"][1])
    assert 0 < t_stop < 30.0
    after = ds["time"].values > t_stop
    assert np.isnan(ds["sensor.T_s"].values[1][after]).all()
    assert not np.isnan(ds["sensor.T_s"].values[1][~after]).any()
    assert np.isnan(ds["sensor.T_s"].values[0]).all()  # never ran


def test_netcdf_reopens_with_units(spec, tmp_path):
    xr = pytest.importorskip("xarray")
    cases = [{"sensor.tau": "4 s", "supply.p": "2.5 bar"}, {"sensor.tau": "8 s", "supply.p": 2e5}]
    sw = sweeps.sweep(spec, cases, out_dir=tmp_path, output_interval=0.5, progress=False)
    with xr.open_dataset(tmp_path / "sweep.nc", engine="h5netcdf") as ds:
        assert dict(ds.sizes) == {"case": 2, "time": 61}  # 0 .. 30 s every 0.5 s
        assert ds["time"].attrs["units"] == "s"
        assert ds["sensor.tau"].attrs["units"] == "s"
        assert ds["supply.p"].attrs["units"] == "Pa"
        np.testing.assert_array_equal(ds["supply.p"].values, [2.5e5, 2e5])  # SI
        np.testing.assert_array_equal(ds["sensor.tau"].values, [4.0, 8.0])
        assert ds["sensor.T_s"].attrs["units"] == "K"
        assert ds["supply.m"].attrs["units"] == "kg/s"
        assert ds["sensor.T_s"].dims == ("case", "time")
        np.testing.assert_array_equal(ds["sensor.T_s"].values, sw.dataset["sensor.T_s"].values)
        assert list(ds["status"].values) == ["finished", "finished"]
    head = (tmp_path / "summary.csv").read_text().splitlines()[0]
    assert "sensor.tau [s]" in head and "supply.p [Pa]" in head
    assert "sensor.T_s final [K]" in head and "sensor.T_s max [K]" in head


def test_restart_skips_done_cases(spec, tmp_path, monkeypatch):
    ran = []
    real = sweeps.run_case

    def counting(spec, case, index=0):
        ran.append(index)
        return real(spec, case, index)

    monkeypatch.setattr(sweeps, "run_case", counting)
    cases = [{"sensor.tau": "4 s"}, {"sensor.tau": "6 s"}, {"sensor.tau": "8 s"}]
    sweeps.sweep(spec, cases[:2], out_dir=tmp_path, progress=False)
    assert ran == [0, 1]
    # a crash before case 1 wrote its marker: its files without done.json
    (tmp_path / "case_0001" / "done.json").unlink()
    ran.clear()
    sw = sweeps.sweep(spec, cases, out_dir=tmp_path, progress=False)
    assert ran == [1, 2]  # case 0 was done
    assert (sw.ran, sw.skipped) == (2, 1)
    back = pd.read_csv(tmp_path / "summary.csv")
    assert list(back["sensor.tau [s]"]) == [4.0, 6.0, 8.0]  # rebuilt from all cases
    assert list(back["status"]) == ["finished"] * 3
    # a case at the same place with other values is not taken for done
    ran.clear()
    sweeps.sweep(spec, [{"sensor.tau": "5 s"}] + cases[1:], out_dir=tmp_path, progress=False)
    assert ran == [0]


# --------------------------------------------------------------------------- parsing


def test_parse_set_option_values_and_units():
    assert parse_set_option("valve.C=0.01,0.02") == ("valve.C", [0.01, 0.02])
    assert parse_set_option("steam.T=500 degC, 520 degC") == ("steam.T", ["500 degC", "520 degC"])
    assert parse_set_option("pipe.n_volumes=4,8") == ("pipe.n_volumes", [4, 8])
    key, vals = parse_set_option('steam.T={ type = "step", t0 = 1, before = 1, after = 2 },3')
    assert vals == [{"type": "step", "t0": 1, "before": 1, "after": 2}, 3]
    for bad in ("valve", "valve.C", "valve.C=", "valve.C=1,,2", "a.b.c=1"):
        with pytest.raises(CaseError):
            parse_set_option(bad)
    cases = product_cases({"a.x": [1, 2], "b.y": ["p", "q", "r"]})
    assert len(cases) == 6 and cases[1] == {"a.x": 1, "b.y": "q"}


def test_cases_files_csv_with_units_and_toml(tmp_path):
    p = tmp_path / "cases.csv"
    p.write_text("sensor.tau [s],valve.C\n4,0.003\n8,0.004 kg/(s.Pa0.5)\n")
    assert read_cases(p) == [
        {"sensor.tau": "4 s", "valve.C": 0.003},
        {"sensor.tau": "8 s", "valve.C": "0.004 kg/(s.Pa0.5)"},
    ]
    q = tmp_path / "cases.toml"
    q.write_text('[[case]]\nsensor.tau = "4 s"\n\n[[case]]\n"sensor.tau" = 8\nvalve.C = 0.004\n')
    assert tomllib.loads(q.read_text())  # valid TOML
    assert read_cases(q) == [{"sensor.tau": "4 s"}, {"sensor.tau": 8, "valve.C": 0.004}]


@pytest.mark.parametrize(
    "option, expect",
    [
        ("sensr.tau=4", "no component 'sensr'"),
        ("sensor.taux=4", "has no parameter 'taux'; did you mean 'tau'"),
        ("sensor.tau=4 s,3 bar", "'3 bar' has the dimension of pressure, but time is expected"),
        ("simulation.t_end=1 kg", "simulation.t_end = '1 kg'"),
        ("sensor.tau", "expected COMPONENT.PARAMETER=V1,V2"),
    ],
)
def test_cli_set_errors_exit_2_with_location(option, expect, tmp_path):
    r = CliRunner().invoke(main, ["sweep", str(PLANT), "-o", str(tmp_path), "--set", option])
    assert r.exit_code == 2, r.output
    assert "option --set" in r.output and expect in r.output
    assert "Traceback" not in r.output
    assert not list(tmp_path.glob("case_*"))  # nothing ran


def test_cli_sweep_cases_file_two_processes(tmp_path):
    cases = tmp_path / "cases.csv"
    cases.write_text("sensor.tau [s],simulation.t_end [s]\n4,20\n8,30\n")
    out = tmp_path / "out"
    r = CliRunner().invoke(
        main, ["sweep", str(PLANT), "-o", str(out), "--cases", str(cases), "-j", "2", "-q"]
    )
    assert r.exit_code == 0, r.output
    back = pd.read_csv(out / "summary.csv")
    assert list(back["t_reached [s]"]) == [20.0, 30.0]
    for i in range(2):
        d = out / f"case_{i:04d}"
        assert {"results.csv", "events.csv", "steps.csv", "done.json"} <= {
            f.name for f in d.iterdir()
        }
    # the final reading against the closed form (rtol 1e-6 of ~420 K: 1e-3 K is loose)
    for tau, t_end, final in zip([4, 8], [20, 30], back["sensor.T_s final [K]"], strict=True):
        assert final == pytest.approx(T1 - (T1 - T0) * math.exp(-(t_end - T_STEP) / tau), abs=1e-3)


def test_a_worker_that_dies_fails_its_case_only_and_runs_again(spec, tmp_path, monkeypatch):
    from concurrent.futures import ThreadPoolExecutor

    real = sweeps.run_case

    def dying(spec, case, index=0):
        if index == 1:
            raise MemoryError("worker killed")  # as a lost worker's future raises
        return real(spec, case, index)

    monkeypatch.setattr(sweeps, "run_case", dying)
    cases = [{"sensor.tau": "4 s"}, {"sensor.tau": "6 s"}]
    with ThreadPoolExecutor(2) as pool:
        sw = sweeps.sweep(spec, cases, pool, out_dir=tmp_path, progress=False)
    assert list(sw.summary["status"]) == ["finished", "error"]
    assert "MemoryError: worker killed" in sw.summary["message"][1]
    monkeypatch.setattr(sweeps, "run_case", real)
    sw = sweeps.sweep(spec, cases, out_dir=tmp_path, progress=False)
    assert (sw.ran, sw.skipped) == (1, 1)  # the case of the dead worker runs again
    assert list(sw.summary["status"]) == ["finished", "finished"]
