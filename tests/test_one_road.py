"""One road from a plant file's settings to the solver (issue 21).

``dnasim run``, ``Plant.simulate`` (the shorthand), ``LoadedPlant.simulate`` and
``simulate_plant`` merge the file's ``[simulation]`` table with the caller's keywords in
one place (``simulation_keywords``), and the file's ``output_interval`` reaches the
solver the same way from all of them: the solver generates the grid as it goes, both
sides of every discontinuity included. So the rows agree to round-off.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import dnasim
from dnasim.cli.commands import main
from dnasim.core.errors import PlantError
from dnasim.plant.plantfile import load, simulate_plant
from dnasim.run.simulation import simulate, simulation_keywords

PLANT = Path(__file__).resolve().parent.parent / "plants" / "attemperator.toml"


def _cli_rows(tmp_path, *extra):
    res = CliRunner().invoke(
        main, ["run", str(PLANT), "-o", str(tmp_path / "cli"), "-q", "--t-end", "150 s", *extra]
    )
    assert res.exit_code == 0, res.output
    lines = (tmp_path / "cli" / "results.csv").read_text().splitlines()
    header = [h.split(" [")[0] for h in lines[0].split(",")]
    data = np.array([[float(v) for v in r.split(",")] for r in lines[1:]])
    return header, data


def test_every_python_road_gives_the_rows_of_dnasim_run(tmp_path):
    header, cli = _cli_rows(tmp_path, "--output-interval", "10 s")

    plant_file = tmp_path / "attemperator.toml"  # the file with an output interval
    plant_file.write_text(
        PLANT.read_text().replace('t_end = "20 min"', 't_end = "20 min"\noutput_interval = "10 s"')
    )

    def fresh():  # each road its own Plant (one compile each, as in its own process)
        return load(plant_file)

    roads = {"Plant.simulate": fresh().plant.simulate(150.0)}
    roads["LoadedPlant.simulate"] = fresh().simulate(t_end=150.0)
    loaded = fresh()
    roads["simulate_plant"] = simulate_plant(loaded.plant, loaded.simulation, t_end=150.0)
    loaded = fresh()
    t_end, kw = simulation_keywords(loaded.simulation, 150.0)
    roads["simulate"] = simulate(dnasim.compile(loaded.plant), t_end=t_end, **kw)
    t = cli[:, header.index("time")]
    assert t[-1] == 150.0 and np.any(np.diff(t) == 0)  # both sides of the 120 s step
    for road, res in roads.items():
        for name in ("sensor.T_s", "pi.z", "spray_valve.m"):
            got = np.interp(t, res.t, res[name])  # res.t is strictly increasing
            keep = np.r_[np.diff(t) > 0, True]  # the right side of each discontinuity
            # the same steps and the same grid; the values agree to round-off (seen: 7e-15
            # relative in pi.z after the set-point step; the roads differ in what they
            # keep, dense output or not, not in the method), so 1e-12, six orders of
            # magnitude below rtol: a different road (another grid, other tolerances, a
            # different start) shows up as 1e-7 or more
            np.testing.assert_allclose(
                got[keep], cli[keep, header.index(name)], rtol=1e-12,
                atol=0, err_msg=f"{road}: {name}",
            )  # fmt: skip


def test_keywords_override_the_file_and_t_eval_replaces_the_interval():
    loaded = load(PLANT)
    loaded.simulation.output_interval = 10.0
    t_end, kw = simulation_keywords(loaded.simulation, None, rtol=1e-4)
    assert t_end == loaded.simulation.t_end and kw["rtol"] == 1e-4
    assert kw["output_interval"] == 10.0
    _, kw = simulation_keywords(loaded.simulation, 100.0, t_eval=[0.0, 50.0, 100.0])
    assert "output_interval" not in kw
    _, kw = simulation_keywords(loaded.simulation, solver=dnasim.NordsieckBDF(rtol=1e-3))
    assert "rtol" not in kw and "atol_scaled" not in kw  # the solver brings its own
    res = loaded.plant.simulate(100.0, t_eval=[0.0, 50.0, 100.0])
    assert list(res.t) == [0.0, 50.0, 100.0]


def test_conflicting_output_settings_are_refused():
    system = dnasim.compile(load(PLANT).plant)
    with pytest.raises(PlantError, match="t_eval or output_interval"):
        simulate(system, t_end=10.0, t_eval=[0.0, 10.0], output_interval=1.0)
    with pytest.raises(PlantError, match="positive time"):
        simulate(system, t_end=10.0, output_interval=-1.0)
    loaded = load(PLANT)
    loaded.simulation.output_interval = 1e-6
    with pytest.raises(PlantError, match="output points"):  # the row limit, before numerics
        simulation_keywords(loaded.simulation, 1e6)
