"""Declared sparsity must cover the numerically probed one, for every component.

Each plant below is brought to a consistent state, then y and y' are perturbed
randomly (so that no entry of the Jacobian vanishes by coincidence) and every
column of dF/dy and dF/dy' is probed by central differences. Any entry above
the noise level that the declarations do not contain fails the test, naming
the equation and the variable.
"""

import math

import numpy as np
import pytest

from dnasim.components import (
    REGISTRY,
    HeatExchanger,
    MassFlowBoundary,
    Mixer,
    Pipe,
    PressureBoundary,
    Splitter,
    TemperatureSensor,
    Valve,
)
from dnasim.examples import air_pipe_plant, attemperator_plant
from dnasim.plant import Plant
from dnasim.start import initial_values


def hx_plant():
    """Water heat exchanger fed by a split-and-remixed cold stream, with a sensor."""
    plant = Plant("hx", medium="Water")
    plant.add(PressureBoundary("hot_src", p=3e5, T=360.0, m_nominal=0.5))
    plant.add(
        HeatExchanger(
            "hx",
            hot_V=0.01,
            cold_V=0.01,
            hot_kA=2e3,
            cold_kA=2e3,
            hot_k=1e5,
            cold_k=1e5,
            C_wall=5e3,
            n_sections=3,
            m_nominal=0.5,
        )
    )
    plant.add(Valve("hot_valve", C=1e-3, opening=1.0, m_nominal=0.5))
    plant.add(PressureBoundary("hot_sink", p=1e5, m_nominal=0.5))
    plant.add(MassFlowBoundary("cold_src", m=0.5, T=290.0, m_nominal=0.5))
    plant.add(Splitter("split", m_nominal=0.5))
    plant.add(Valve("va", C=1e-3, opening=1.0, m_nominal=0.25))
    plant.add(Valve("vb", C=2e-3, opening=0.5, m_nominal=0.25))
    plant.add(Mixer("mix", m_nominal=0.5))
    plant.add(Pipe("cold_pipe", V=0.01, kA=50.0, k=1e5, T_wall=300.0, n_volumes=2, m_nominal=0.5))
    plant.add(Valve("cold_valve", C=1e-3, opening=1.0, m_nominal=0.5))
    plant.add(PressureBoundary("cold_sink", p=1e5, m_nominal=0.5))
    plant.add(TemperatureSensor("sensor", tau=2.0))
    wires = [
        ("hot_src.port", "h1"),
        ("hx.hot_in", "h1"),
        ("hx.hot_out", "h2"),
        ("hot_valve.inlet", "h2"),
        ("sensor.port", "h2"),
        ("hot_valve.outlet", "h3"),
        ("hot_sink.port", "h3"),
        ("cold_src.port", "c1"),
        ("split.inlet", "c1"),
        ("split.outlet1", "c2"),
        ("split.outlet2", "c3"),
        ("va.inlet", "c2"),
        ("vb.inlet", "c3"),
        ("va.outlet", "c4"),
        ("vb.outlet", "c5"),
        ("mix.inlet1", "c4"),
        ("mix.inlet2", "c5"),
        ("mix.outlet", "c6"),
        ("cold_pipe.inlet", "c6"),
        ("cold_pipe.outlet", "c7"),
        ("hx.cold_in", "c7"),
        ("hx.cold_out", "c8"),
        ("cold_valve.inlet", "c8"),
        ("cold_valve.outlet", "c9"),
        ("cold_sink.port", "c9"),
    ]
    for a, b in wires:
        plant.connect(a, b)
    return plant


def plant_file(name):
    """A plant of tests/plants (the fluid machines, valves and the condenser)."""
    from pathlib import Path

    from dnasim.plantfile import load

    return load(Path(__file__).parent / "plants" / name).plant


PLANTS = {
    "air_pipe": lambda: air_pipe_plant(3),
    "attemperator": attemperator_plant,
    "hx": hx_plant,
    "turbine_condenser": lambda: plant_file("turbine_condenser.toml"),
    "pump_check_valve": lambda: plant_file("pump_trip_check_valve.toml"),
}


def test_every_registered_component_is_probed():
    seen = set()
    for make in PLANTS.values():
        seen |= {type(c).__name__ for c in make().components.values()}
    assert set(REGISTRY) <= seen, f"add a plant using {set(REGISTRY) - seen} to this test"


@pytest.mark.parametrize("name", PLANTS)
def test_declared_pattern_covers_probed(name):
    plant = PLANTS[name]()
    dae = plant.compile()
    y0, yp0 = initial_values(dae, 0.0, "steady")
    rng = np.random.default_rng(1)
    scale = np.maximum(dae.nominal, np.abs(y0))
    # small random perturbations: generic point, still inside the property ranges
    y = y0 + 1e-4 * scale * rng.standard_normal(dae.n)
    yp = 1e-3 * scale * rng.standard_normal(dae.n)
    F0 = dae.residual(1.0, y, yp)
    row_scale = np.ones(dae.n_equations)
    declared = {"y": dae.pattern_y.toarray() != 0, "yp": dae.pattern_yp.toarray() != 0}
    missing = []
    for which, pattern in declared.items():
        for j in range(dae.n):
            d = 1e-6 * scale[j]
            args_p = [y.copy(), yp.copy()]
            args_m = [y.copy(), yp.copy()]
            k = 0 if which == "y" else 1
            args_p[k][j] += d
            args_m[k][j] -= d
            col = (dae.residual(1.0, *args_p) - dae.residual(1.0, *args_m)) / (2 * d) * scale[j]
            # noise of a central difference ~ eps |F| / d; entries above 1e-6 of
            # the row's magnitude are real dependencies
            noise = 1e-6 * (np.abs(F0) + row_scale * np.max(np.abs(col)) + 1.0)
            for i in np.flatnonzero((np.abs(col) > noise) & ~pattern[:, j]):
                missing.append(
                    f"{dae.eq_names[i]} depends on {which}[{dae.names[j]}] ({col[i]:.3g})"
                )
    assert not missing, "\n".join(missing[:20])


def test_hx_plant_runs_and_balances():
    plant = hx_plant()
    assert plant.check().ok
    res = plant.simulate(20.0, start="steady", rtol=1e-6)
    assert res.success
    # steady state stays steady; hot side gives what the cold side takes
    Q_hot = res["hx.hot_m[0]"][-1] * (res["h1.h"][-1] - res["h2.h"][-1])
    Q_cold = res["hx.cold_m[0]"][-1] * (res["c8.h"][-1] - res["c7.h"][-1])
    assert math.isclose(Q_hot, Q_cold, rel_tol=1e-6)
    assert res["h2.T"][-1] < 360.0 and res["c8.T"][-1] > 290.0
    assert abs(res["sensor.T_s"][-1] - res["h2.T"][-1]) < 1e-6
