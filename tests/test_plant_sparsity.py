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

from dnasim.library import (
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
from dnasim.plant.examples import air_pipe_plant, attemperator_plant
from dnasim.plant.plant import Plant
from dnasim.start.initial import initial_values


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


def signals_plant():
    """A water line with every sensor on it, a PID (manual until 0.5 s, so the
    probe at t = 1 s sees it automatic) and every signal block in a chain."""
    from dnasim.core.timefunctions import Step
    from dnasim.library import sensor as S
    from dnasim.library import signal_blocks as B
    from dnasim.library.pid import PIDController

    plant = Plant("signals", medium="Water")
    plant.add(PressureBoundary("src", p=10e5, T=350.0, m_nominal=1.0))
    plant.add(Valve("v", C=1e-3, opening=0.5, m_nominal=1.0))
    plant.add(PressureBoundary("sink", p=1e5, m_nominal=1.0))
    for a, b in [("src.port", "a"), ("v.inlet", "a"), ("v.outlet", "b"), ("sink.port", "b")]:
        plant.connect(a, b)
    for cls in (S.PressureSensor, S.EnthalpySensor, S.QualitySensor):
        plant.add(cls(cls.__name__.lower(), T_lag=1.0))
        plant.connect(f"{cls.__name__.lower()}.port", "a")
    plant.add(S.MassFlowSensor("flow", T_lag=1.0))
    plant.link("v.m", "flow.u")
    plant.add(B.Ramp("lvl", t0=0.0, t1=10.0, start=0.5, end=1.0, unit="m"))
    plant.add(S.LevelSensor("level", T_lag=1.0))
    plant.link("lvl.y", "level.u")
    plant.add(B.Step("track", t0=5.0, before=0.3, after=0.4))
    plant.add(
        PIDController(
            "pid",
            Kp=1e-6,
            T_i=5.0,
            T_d=1.0,
            c_d=0.5,
            setpoint=9e5,
            tracking=True,
            active=Step(0.5, 0.0, 1.0),
        )
    )
    plant.link("pressuresensor.p", "pid.measured")
    plant.link("track.y", "pid.track")
    plant.add(B.Gain("gain", k=2.0))
    plant.add(B.TableSource("ts", times=[0.0, 10.0], values=[0.1, 0.2]))
    plant.add(B.Sum("sum", n_inputs=3, w1=0.5, w2=0.5, w3=1.0))
    plant.link("pid.z", "gain.u")
    plant.link("gain.y", "sum.u1")
    plant.link("flow.m", "sum.u2")
    plant.link("ts.y", "sum.u3")
    chain = [
        B.FirstOrderLag("lag", T=2.0),
        B.Limiter("lim", y_min=-10.0, y_max=10.0),
        B.RateLimiter("rate", R_up=100.0),
        B.Table("tab", x=[-10.0, 0.0, 10.0], y=[0.0, 1.0, 3.0]),
        B.DeadTime("dead", T_dead=2.0, n_stages=3),
    ]
    prev = "sum.y"
    for block in chain:
        plant.add(block)
        plant.link(prev, f"{block.name}.u")
        prev = f"{block.name}.y"
    return plant


def plant_file(name):
    """A plant of tests/plants (the fluid machines, valves and the condenser)."""
    from pathlib import Path

    from dnasim.plant.plantfile import load

    return load(Path(__file__).parent / "plants" / name).plant


def relief_plant():
    """A popped safety valve part-way up its lift curve (the lift depends on the inlet
    pressure there), steam from a 102 bar header to the atmosphere."""
    from dnasim.library.safety_valve import SafetyValve

    plant = Plant("relief", medium="Water")
    plant.add(PressureBoundary("header", p=102e5, T=650.0, m_nominal=5.0))
    plant.add(
        SafetyValve(
            "sv", p_set=100e5, A=1e-3, K_d=0.9, pop_lift=0.5, overpressure=0.05, m_nominal=5.0
        )
    )
    plant.add(PressureBoundary("vent", p=1e5, m_nominal=5.0))
    for a, b in [
        ("header.port", "n1"),
        ("sv.inlet", "n1"),
        ("sv.outlet", "n2"),
        ("vent.port", "n2"),
    ]:
        plant.connect(a, b)
    return plant


PLANTS = {
    "air_pipe": lambda: air_pipe_plant(3),
    "relief": relief_plant,
    "signal_blocks_sine": lambda: plant_file("signal_blocks_sine.toml"),
    "drain_steam_blowthrough": lambda: plant_file("drain_steam_blowthrough.toml"),
    "attemperator": attemperator_plant,
    "hx": hx_plant,
    "signals": signals_plant,
    "turbine_condenser": lambda: plant_file("turbine_condenser.toml"),
    "pump_check_valve": lambda: plant_file("pump_trip_check_valve.toml"),
    "motor_pump": lambda: plant_file("../../plants/feedpump_motor_trip.toml"),
    "drum_boiler": lambda: plant_file("../../plants/drum_boiler.toml"),
    "feedwater_heater": lambda: plant_file("../../plants/feedwater_heater.toml"),
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


@pytest.mark.parametrize(
    "cls, params",
    [
        (Mixer, dict(n_inlets=3)),
        (Splitter, dict(n_outlets=2)),
        (PressureBoundary, dict(p=1e5, T=300.0)),
        (PressureBoundary, dict(p=1e5)),
        (MassFlowBoundary, dict(m=1.0, h=1e5)),
        (MassFlowBoundary, dict(m=-1.0)),
    ]
    + [(REGISTRY["Attemperator"], dict(V=0.3, k=4000.0))],
    ids=["Mixer", "Splitter", "PB-T", "PB-sink", "MFB-h", "MFB-sink"] + ["Attemperator"],
)
def test_equations_are_declared_once(cls, params):
    # issue 8: name, dependencies, doc and unit sit together in one Equation; the
    # residual is the base class's, derived from one definition (it cannot drift from
    # the docs or the sparsity, which test_declared_pattern_covers_probed checks):
    # every Equation's own function, or (a class with row_reads, issue 10) the
    # class's row_values and no Equation function
    from dnasim.model.component import Component

    comp = cls("c", **params)
    eqs = comp.equations()
    assert eqs and all(e.doc and e.unit for e in eqs)
    if comp.row_reads() is None:
        assert all(e.residual is not None for e in eqs)
    else:
        assert all(e.residual is None for e in eqs)
        assert "row_values" in {
            k for c in type(comp).__mro__ for k in c.__dict__ if c is not Component
        }
    assert type(comp).residual is Component.residual
