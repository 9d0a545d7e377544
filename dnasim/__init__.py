"""dnasim: dynamic simulation of energy systems as index-1 DAEs (in the tradition of DTU's DNA)."""

from dnasim.errors import DAEError, DnasimError, PlantError, ResidualDomainError

__version__ = "0.1.0"

__all__ = [
    "solve_dae",
    "DAEResult",
    "DAEError",
    "DnasimError",
    "PlantError",
    "ResidualDomainError",
    "load_plant",
]


def __getattr__(name):
    # Imported lazily, so `dnasim --help` starts fast: the solver pulls in scipy, the
    # plant-file layer the component library and CoolProp.
    if name in ("solve_dae", "DAEResult"):
        import dnasim.solver

        return getattr(dnasim.solver, name)
    if name == "load_plant":
        from dnasim.plantfile import load_plant

        return load_plant
    raise AttributeError(f"module 'dnasim' has no attribute {name!r}")
