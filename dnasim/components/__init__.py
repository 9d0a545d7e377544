"""Component library. Every subclass of ``Component`` registers itself in ``REGISTRY``.

See ``dnasim.components.base`` for the contract a component fulfils.
"""

from dnasim.components.attemperator import Attemperator
from dnasim.components.base import (
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
from dnasim.components.boundaries import MassFlowBoundary, PressureBoundary
from dnasim.components.condenser import Condenser
from dnasim.components.control_valve import CheckValve, ControlValve
from dnasim.components.controller import PIController
from dnasim.components.heat_exchanger import HeatExchanger
from dnasim.components.junctions import Mixer, Splitter
from dnasim.components.pipe import Pipe
from dnasim.components.pump import Pump
from dnasim.components.sensor import TemperatureSensor
from dnasim.components.turbine import SteamTurbine
from dnasim.components.valve import Valve

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
