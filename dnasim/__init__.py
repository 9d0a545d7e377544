"""dnasim: dynamic simulation of energy systems as index-1 DAEs (in the tradition of DTU's DNA).

The stages, each one object with one job (docs/architecture.md)::

    spec = PlantSpec(...)  or  load_plant("plant.toml")   # data / the Plant graph
    system = compile(plant)                                # the DAE over plant-wide arrays
    res = simulate(system, t_end=100.0, solver=NordsieckBDF(), sinks=[CSVSink("r.csv")])
    res["pipe.T_out"], res.to_dataframe(), res.to_xarray(), res.at(42.0)
    res = read_results("results/plant")                    # a run's results.nc or .csv
    sw = sweep(spec, {"valve.C": [0.01, 0.02]}, executor=pool)   # many runs
"""

from dnasim import moved_modules as _moved_modules
from dnasim.core.errors import DAEError, DnasimError, PlantError, ResidualDomainError

_moved_modules.install()  # old module paths (dnasim.compiler, ...) keep working

__version__ = "0.1.0"

__all__ = [
    "CSVSink",
    "ComponentSpec",
    "DAEError",
    "DAEResult",
    "DnasimError",
    "IDA",
    "NordsieckBDF",
    "Plant",
    "PlantError",
    "PlantSpec",
    "ResidualDomainError",
    "Results",
    "SimulationSettings",
    "System",
    "compile",
    "load_plant",
    "read_results",
    "simulate",
    "solve_dae",
    "sweep",
]

# Imported lazily, so `dnasim --help` starts fast: the solver pulls in scipy, the
# plant layer the component library, and nothing imports CoolProp before a medium
# needs it.
_LAZY = {
    "solve_dae": "dnasim.solver",
    "DAEResult": "dnasim.solver",
    "load_plant": "dnasim.plant.plantfile",
    "Plant": "dnasim.plant.plant",
    "PlantSpec": "dnasim.plant.spec",
    "ComponentSpec": "dnasim.plant.spec",
    "SimulationSettings": "dnasim.plant.spec",
    "compile": "dnasim.compilation.compiler",
    "System": "dnasim.compilation.system",
    "simulate": "dnasim.run.simulation",
    "NordsieckBDF": "dnasim.run.simulation",
    "IDA": "dnasim.run.simulation",
    "CSVSink": "dnasim.run.simulation",
    "Results": "dnasim.run.results",
    "read_results": "dnasim.run.results",
    "sweep": "dnasim.tools.sweeps",
}


def __getattr__(name):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'dnasim' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(module), name)
