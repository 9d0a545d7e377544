"""Plant.check(): wiring, counting, structural singularity, index 2, bad input."""

import numpy as np
import pytest

from dnasim.core.errors import PlantError
from dnasim.library import (
    Component,
    Equation,
    FluidPort,
    Param,
    Pipe,
    PressureBoundary,
    Valve,
    Variable,
)
from dnasim.plant.examples import air_pipe_plant, attemperator_plant
from dnasim.plant.plant import Plant


class _Resistor(Component):
    """Test component: a linear resistance m = G (p_in - p_out), isenthalpic both
    ways (h_out of each port is the other port's node h), optionally with one
    equation too many or too few."""

    REGISTER = False
    PARAMS = (Param("G", "kg/(s.Pa)", 1e-5), Param("variant", "1", "ok", kind="string"))
    FLUID_PORTS = (
        FluidPort("inlet", "inlet", "m", h_out="outlet.h", h_source=False),
        FluidPort("outlet", "outlet", "m", h_out="inlet.h", h_source=False),
    )

    def variables(self):
        return [Variable("m", "kg/s", 1.0)]

    def equations(self):
        eqs = [Equation("flow", y=("m", "inlet.p", "outlet.p"))]
        if self.params["variant"] == "extra":
            eqs.append(Equation("extra", y=("m",)))
        if self.params["variant"] == "missing":
            eqs = eqs[1:]
        return eqs

    def residual(self, t, x, xp):
        r = [x["m"] - self.params["G"] * (x["inlet.p"] - x["outlet.p"])]
        if self.params["variant"] == "extra":
            r.append(x["m"] - 1.0)
        if self.params["variant"] == "missing":
            r = r[1:]
        return np.array(r)


def chain(middle):
    plant = Plant("chain", medium="Air")
    plant.add(PressureBoundary("src", p=2e5, T=300.0))
    plant.add(middle)
    plant.add(PressureBoundary("sink", p=1e5))
    for a, b in [
        ("src.port", "a"),
        (f"{middle.name}.inlet", "a"),
        (f"{middle.name}.outlet", "b"),
        ("sink.port", "b"),
    ]:
        plant.connect(a, b)
    return plant


def test_good_plants_pass():
    for plant in (
        air_pipe_plant(1),
        air_pipe_plant(5),
        attemperator_plant(),
        chain(_Resistor("r")),
    ):
        report = plant.check()
        assert report.ok, str(report)
        assert report.n_equations == report.n_unknowns


def test_dangling_port_names_component_and_port():
    plant = air_pipe_plant(1)
    plant.add(Valve("spare", C=1e-3, opening=1.0))
    plant.connect("spare.inlet", "outlet")
    report = plant.check()
    assert not report.ok
    assert any("'spare'" in e and "'outlet'" in e and "dangling" in e for e in report.errors), (
        report.errors
    )
    with pytest.raises(PlantError, match="spare"):
        plant.simulate(1.0)


def test_dangling_signal_input():
    plant = attemperator_plant()
    del plant.links[("spray_valve", "z")]
    report = plant.check()
    assert any("'spray_valve'" in e and "'z'" in e for e in report.errors), report.errors


def test_extra_equation_names_component():
    report = chain(_Resistor("res1", variant="extra")).check()
    assert not report.ok
    assert any("'res1'" in e and "too many" in e for e in report.errors), report.errors
    assert any(
        "res1.extra" in e or "res1" in e for e in report.errors if "structurally singular" in e
    )


def test_missing_equation_names_component():
    report = chain(_Resistor("res2", variant="missing")).check()
    assert not report.ok
    assert any("'res2'" in e and "too few" in e for e in report.errors), report.errors
    assert any("res2.m" in e for e in report.errors if "structurally singular" in e), report.errors


def test_two_volumes_without_resistance_is_explained():
    # pipe1's outlet volume feeds a sink boundary directly: storage volume and a
    # fixed pressure on one node, index 2.
    plant = Plant("bad", medium="Air")
    plant.add(PressureBoundary("src", p=2e5, T=300.0))
    plant.add(Pipe("pipe1", V=0.1, k=1e5))
    plant.add(PressureBoundary("sink", p=1e5))
    for a, b in [
        ("src.port", "a"),
        ("pipe1.inlet", "a"),
        ("pipe1.outlet", "b"),
        ("sink.port", "b"),
    ]:
        plant.connect(a, b)
    report = plant.check()
    assert not report.ok
    text = "\n".join(report.errors)
    assert (
        "'pipe1'" in text
        and "'sink'" in text
        and "no flow resistance" in text
        and "index 2" in text
    )
    assert "index > 1" in text  # confirmed by the matching, with names
    assert "pipe1.density" in text or "pipe1.internal_energy" in text


def test_two_storage_volumes_joined():
    # a pipe's outlet volume joined to an attemperator's spray inlet (p_water = p)
    from dnasim.library import Attemperator

    plant = Plant("bad2", medium="Water")
    plant.add(PressureBoundary("w", p=60e5, T=400.0))
    plant.add(Pipe("feed", V=0.01, k=1e5))
    plant.add(PressureBoundary("s", p=40e5, T=773.0))
    plant.add(Attemperator("att", V=0.5, k=6500.0))
    plant.add(Valve("v", C=0.01, opening=1.0))
    plant.add(PressureBoundary("out", p=35e5))
    for a, b in [
        ("w.port", "n1"),
        ("feed.inlet", "n1"),
        ("feed.outlet", "n2"),
        ("att.water_in", "n2"),
        ("s.port", "n3"),
        ("att.steam_in", "n3"),
        ("att.outlet", "n4"),
        ("v.inlet", "n4"),
        ("v.outlet", "n5"),
        ("out.port", "n5"),
    ]:
        plant.connect(a, b)
    report = plant.check()
    text = "\n".join(report.errors)
    assert "'feed'" in text and "'att'" in text and "storage volume" in text and "index 2" in text


def test_node_without_enthalpy_and_duplicate_names():
    plant = Plant("p", medium="Air")
    plant.add(PressureBoundary("a", p=2e5))
    plant.add(PressureBoundary("a", p=1e5))
    plant.add(PressureBoundary("b", p=1e5))
    plant.add(Valve("v", C=1e-3, opening=1.0))
    plant.connect("a.port", "n1")
    plant.connect("v.inlet", "n1")
    plant.connect("v.outlet", "n2")
    plant.connect("b.port", "n2")
    text = "\n".join(plant.check().errors)
    assert "duplicate component name 'a'" in text
    assert "node 'n1'" in text and "enthalpy" in text


def test_disconnected_subnetworks_warn():
    plant = air_pipe_plant(1)
    other = chain(_Resistor("r"))
    for c in other.components.values():
        c2 = type(c)(c.name + "_2", **{k: v for k, v in c.params.items() if v is not None})
        plant.add(c2)
    for (c, p), n in other.connections.items():
        plant.connect(f"{c}_2.{p}", n + "_2")
    report = plant.check()
    assert report.ok, report.errors
    assert any("2 disconnected sub-networks" in w for w in report.warnings)


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda: Pipe("p1"), ["'p1'", "'V'", "required"]),
        (lambda: Pipe("p1", V=-1.0), ["'p1'", "'V'", "below its minimum"]),
        (lambda: Pipe("p1", V=1.0, colour=3), ["'p1'", "unknown parameter", "colour"]),
        (lambda: Pipe("p1", V=1.0, n_volumes=2.5), ["'p1'", "'n_volumes'", "integer"]),
        (lambda: Pipe("p1", V="big"), ["'p1'", "'V'", "number"]),
        (lambda: Valve("v", C=1.0, opening="half"), ["'v'", "'opening'"]),
        (lambda: PressureBoundary("b", p=1e5, h=1e5, T=300.0), ["'b'", "one of 'h', 'T' or 'x'"]),
    ],
)
def test_bad_parameters_give_plant_errors(make, words):
    with pytest.raises(PlantError) as info:
        make()
    for w in words:
        assert w in str(info.value)


def test_bad_connections_give_plant_errors():
    plant = air_pipe_plant(1)
    with pytest.raises(PlantError, match="no fluid port 'outlett'"):
        plant.connect("pipe1.outlett", "x")
    with pytest.raises(PlantError, match="no component named 'pipe9'"):
        plant.connect("pipe9.inlet", "x")
    with pytest.raises(PlantError, match="already connected"):
        plant.connect("pipe1.inlet", "x")
    with pytest.raises(PlantError, match="no signal output"):
        plant.link("pipe1.T", "valve.z")
