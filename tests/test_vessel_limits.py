"""Runs that reach an impossible state stop with a message and a non-zero exit code
(issue 20: "runs that end with exit 0 and impossible states").

Each case is a plant file in tests/plants/limits/ (its header says what it is and
what happened before), run through the command line as a user would. Every case
must: exit with 1 (the simulation failed; results up to that time on disk), print one
message naming the component (or node), the limit and the time, and leave a
results.csv in which no row holds NaN, a negative mass or liquid volume, or a level
outside its vessel. The stop is located: the last row is the state at the limit.
"""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from dnasim.cli.commands import main

ROOT = Path(__file__).resolve().parents[1]
LIMITS = ROOT / "tests" / "plants" / "limits"


def run_cli(plant: Path, out: Path):
    result = CliRunner().invoke(main, ["run", str(plant), "-o", str(out), "-q"])
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a traceback is a bug
    return result


def rows(out: Path) -> dict[str, np.ndarray]:
    path = out / "results.csv"
    if not path.exists():
        return {}
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader)
        data = np.array([[float(v) for v in r] for r in reader]).reshape(-1, len(header))
    return {h.split(" [")[0]: data[:, k] for k, h in enumerate(header)}


def assert_physical(r: dict[str, np.ndarray], vessels: dict[str, tuple[float, float]]):
    """No NaN; masses >= 0; each vessel's V_l in [0, V_t] and level in [0, V_t/A]
    (1e-9 of the vessel: round-off at the located limit, where the run stops)."""
    for name, v in r.items():
        assert np.all(np.isfinite(v)), f"{name} holds NaN or inf"
        if name.endswith(".M") or re.search(r"\.M\[\d+\]$", name):
            assert np.all(v >= 0.0), f"{name} min {v.min()}"
    for vessel, (V_t, height) in vessels.items():
        V_l = r[f"{vessel}.V_l"] if f"{vessel}.V_l" in r else None
        if V_l is not None:
            assert np.all((V_l >= -1e-9 * V_t) & (V_l <= V_t * (1 + 1e-9))), (V_l.min(), V_l.max())
        level = r[f"{vessel}.level"]
        assert np.all((level >= -1e-9 * height) & (level <= height * (1 + 1e-9))), (
            level.min(),
            level.max(),
        )


def stop_time(output: str) -> float:
    """The located time in the message ("... at t = 125.591 s ...")."""
    m = re.search(r"at t = ([0-9.e+-]+) s \(", output) or re.search(
        r"at t = ([0-9.e+-]+) s", output
    )
    assert m, output
    return float(m.group(1))


# (plant file, words the message must hold, vessels {name: (V_t, V_t/A)})
CASES = [
    (
        "drum_feed_stuck_open.toml",
        ["drum 'drum'", "is full", "the level reached the top of the vessel, 5 m"],
        {"drum": (100.0, 5.0)},
    ),
    (
        "drum_boils_dry.toml",
        ["drum 'drum'", "ran dry", "liquid volume reached 0"],
        {"drum": (20.0, 4.0)},
    ),
    (
        "deaerator_overfill.toml",
        ["tank 'deaerator' (FeedwaterTank) is full", "5 m"],
        {"deaerator": (60.0, 5.0)},
    ),
    (
        "drum_to_critical.toml",
        ["drum 'drum'", "the pressure reached 220.54 bar", "critical point", "220.64 bar"],
        {"drum": (100.0, 5.0)},
    ),
    (
        "condenser_hotwell_dry.toml",
        ["condenser 'condenser'", "the hotwell ran dry"],
        {"condenser": (50.0, 5.0)},
    ),
    (
        "condenser_fills.toml",
        ["condenser 'condenser'", "is full of water"],
        {"condenser": (50.0, 5.0)},
    ),
]


@pytest.mark.parametrize("name, words, vessels", CASES, ids=[c[0] for c in CASES])
def test_vessel_limit_stops_the_run_with_its_message(tmp_path, name, words, vessels):
    res = run_cli(LIMITS / name, tmp_path)
    assert res.exit_code == 1, res.output
    for w in words:
        assert w in res.output, (w, res.output)
    assert "Newton" not in res.output  # the physical reason, not the solver's
    r = rows(tmp_path)
    assert r["time"].size > 2
    assert_physical(r, vessels)
    # the last row is the state at the limit, at the located time (6 digits printed)
    assert r["time"][-1] == pytest.approx(stop_time(res.output), rel=1e-5)


def test_rankine_with_the_pump_at_17_percent_stops_when_the_drum_runs_dry(tmp_path):
    # plants/rankine.toml with one change, the feed pump at 17 % speed: the drum's
    # level controller opens the feed valve fully, the pump cannot deliver, the drum
    # boils dry. Before: drum.M = -13.8 t in results.csv and exit 0.
    text = (ROOT / "plants" / "rankine.toml").read_text()
    assert "speed = 1.0\n" in text
    plant = tmp_path / "rankine_pump_17pct.toml"
    plant.write_text(text.replace("speed = 1.0\n", "speed = 0.17\n"))
    out = tmp_path / "out"
    res = run_cli(plant, out)
    assert res.exit_code == 1, res.output
    assert "drum 'drum' (Drum) ran dry" in res.output, res.output
    r = rows(out)
    assert_physical(r, {"drum": (20.0, 4.0), "condenser": (30.0, 6.0)})
    assert r["time"][-1] == pytest.approx(stop_time(res.output), rel=1e-5)


def test_feed_below_if97_stops_before_the_first_row(tmp_path):
    res = run_cli(LIMITS / "feed_below_if97.toml", tmp_path)
    assert res.exit_code == 1, res.output
    for w in ["node 'n_feed'", "h = -20 kJ/kg", "below 273.15 K", "pump.port"]:
        assert w in res.output, (w, res.output)
    assert rows(tmp_path) == {}  # no row with a NaN temperature was written


def test_state_beyond_if97_in_a_residual_names_the_component(tmp_path):
    # the tube's steam passes 1073.15 K at 600 bar: the pipe's property call fails,
    # the step cannot be taken; the message names the tube, its state, the IF97 limit
    # and the time (before: "the plant cannot be simulated", exit 2, no component)
    res = run_cli(LIMITS / "tube_beyond_if97.toml", tmp_path)
    assert res.exit_code == 1, res.output
    for w in ["component 'tube' (Pipe)", "1073.15 K", "601.05", "at t = 81.9"]:
        assert w in res.output, (w, res.output)
    r = rows(tmp_path)
    assert r["time"][-1] > 80.0
    assert all(np.all(np.isfinite(v)) for v in r.values())


def test_a_declared_range_stops_the_run_with_its_message():
    # the general guard: a variable declared with a range (Variable(min=...)), here a
    # state of a small test component driven below its minimum; the run stops at the
    # located crossing with a message naming component, variable, limit and time
    from dnasim.model.component import Component, Equation, Variable
    from dnasim.plant.plant import Plant

    class Tank(Component):
        """dM/dt = -2 kg/s from M(0) = 10 kg, M >= 0 (reaches 0 at t = 5 s)."""

        REGISTER = False
        PARAMS = ()
        USES_MEDIUM = False

        def variables(self):
            return [Variable("M", "kg", 10.0, doc="mass", min=0.0)]

        def equations(self):
            return [
                Equation("drain", yp=("M",), residual=lambda t, x, xp: xp["M"] + 2.0, unit="kg/s")
            ]

        def initial_guess(self, t0, x):
            x["M"] = 10.0

    plant = Plant("tank")
    plant.add(Tank("tank"))
    res = plant.simulate(20.0, start="given")
    assert not res.success
    assert "component 'tank': M reached its minimum 0 kg at t = 5 s" in res.message, res.message
    assert res.t[-1] == pytest.approx(5.0, rel=1e-9)  # located: M(t) = 10 - 2 t
    assert np.all(res["tank.M"] >= 0.0)
    assert math.isclose(res["tank.M"][-1], 0.0, abs_tol=1e-9)
