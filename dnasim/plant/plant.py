"""Plant: the user's plant object, a ``PlantGraph`` with three shorthands.

``dnasim.plant.graph.PlantGraph`` is the graph of components, nodes and signal links;
it imports nothing of the later stages. ``Plant`` adds

    plant.check()      = dnasim.compilation.compiler.check(plant)[0]     -> StructureReport
    plant.compile()    = dnasim.compilation.compiler.compile(plant)      -> System
    plant.simulate(t)  = dnasim.run.simulation.simulate(plant.compile(), t_end=t, ...) -> Results

so that ``dnasim.load_plant(path).simulate()`` and ``Plant(...).simulate(100.0)``
work. This module is the one place where a plant object reaches the later
stages; it sits above the simulation in the import order (docs/architecture.md),
and every module that hands out a ``Plant`` (``dnasim.plant.spec``, ``dnasim.plant.plantfile``,
``dnasim.plant.examples``) sits above it. The shorthands keep no state: the plant
holds no System and no Results, and nothing below holds the plant.

    plant = Plant("demo")
    plant.add(PressureBoundary("src", p=2e5, T=600.0, medium="Air"))
    plant.add(Pipe("pipe1", V=0.1, kA=50.0, k=1e3, C_wall=5e4))
    plant.connect("src.port", "a"); plant.connect("pipe1.inlet", "a")
    ...
    print(plant.check())
    res = plant.simulate(100.0)
    res["pipe1.T_out"]
"""

from __future__ import annotations

from dnasim.compilation.compiler import check as check_plant
from dnasim.compilation.compiler import compile as compile_plant
from dnasim.core.errors import PlantError
from dnasim.plant.graph import PlantGraph
from dnasim.run.simulation import simulate, simulation_keywords

__all__ = ["Plant"]


class Plant(PlantGraph):
    """A network of components (``PlantGraph``) with the shorthands ``check``,
    ``compile`` and ``simulate``. A plant loaded from a file carries its
    ``[simulation]`` table as ``plant.simulation`` (a ``SimulationSettings``)."""

    def check(self):
        """Shorthand for ``dnasim.compilation.compiler.check(plant)[0]`` (a ``StructureReport``)."""
        return check_plant(self)[0]

    def compile(self):
        """Shorthand for ``dnasim.compile(plant)``: a new ``System`` (nothing is cached)."""
        return compile_plant(self)

    def simulate(self, t_end: float | None = None, **kwargs):
        """Shorthand for ``dnasim.simulate(dnasim.compile(plant), t_end=t_end, **kwargs)``.

        A plant loaded from a file carries its ``[simulation]`` table as
        ``plant.simulation`` (a ``SimulationSettings``); its values are the defaults
        here, and keywords override them. The plant keeps no reference to the System
        or the Results; see ``dnasim.run.simulation.simulate`` for the keywords.
        """
        settings = getattr(self, "simulation", None)
        if settings is not None:
            t_end, kwargs = simulation_keywords(settings, t_end, **kwargs)
        if t_end is None:
            raise PlantError(f"plant '{self.name}': simulate() needs t_end [s]")
        return simulate(self.compile(), t_end=t_end, **kwargs)
