"""Component library. Every subclass of ``Component`` registers itself in ``REGISTRY``.

See ``dnasim.model.component`` for the contract a component fulfils.
"""

from dnasim.library.attemperator import Attemperator
from dnasim.library.boundaries import MassFlowBoundary, PressureBoundary
from dnasim.library.condenser import Condenser
from dnasim.library.control_valve import CheckValve, ControlValve
from dnasim.library.controller import PIController
from dnasim.library.heat_exchanger import HeatExchanger
from dnasim.library.junctions import Mixer, Splitter
from dnasim.library.pipe import Pipe
from dnasim.library.pump import Pump
from dnasim.library.sensor import TemperatureSensor
from dnasim.library.turbine import SteamTurbine
from dnasim.library.valve import Valve
from dnasim.model.component import (
    REGISTRY,
    REQUIRED,
    Component,
    Equation,
    FluidPort,
    LocalVector,
    Output,
    Param,
    SignalPort,
    Switch,
    Variable,
)

__all__ = [
    "REGISTRY",
    "REQUIRED",
    "Component",
    "Equation",
    "FluidPort",
    "LocalVector",
    "Output",
    "Param",
    "SignalPort",
    "Switch",
    "Variable",
    "Attemperator",
    "CheckValve",
    "Condenser",
    "ControlValve",
    "HeatExchanger",
    "MassFlowBoundary",
    "Mixer",
    "PIController",
    "Pipe",
    "PressureBoundary",
    "Pump",
    "Splitter",
    "SteamTurbine",
    "TemperatureSensor",
    "Valve",
]


def _import_all_component_modules():
    """Import every module of this package, so that a new component file registers
    itself in REGISTRY without an edit here. Compiled kernels (``*_numba``) are not
    components and are imported on first use: importing numba costs 0.3 to 0.4 s of
    CPU, which a plant without them (air, gases) must not pay."""
    import importlib
    import pkgutil

    for info in pkgutil.iter_modules(__path__):
        if not info.name.endswith("_numba"):
            importlib.import_module(f"{__name__}.{info.name}")


_import_all_component_modules()
