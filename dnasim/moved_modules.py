"""Module paths of earlier versions, and where each module lives now.

dnasim's modules were moved into one package per stage (docs/architecture.md): for
example ``dnasim.compiler`` is now ``dnasim.compilation.compiler`` and
``dnasim.components.pipe`` is ``dnasim.library.pipe``. Code written against the old paths
keeps working: importing an old path gives the module at its new path (the same module
object, so attributes set through either name are seen through both) and a
``DeprecationWarning`` naming the new path. The old paths will be removed in a later
version; ``MOVED`` is the one table of them.

Three old modules became packages of the same name (``dnasim.plant``, ``dnasim.start``,
``dnasim.cli``); their packages hand out the old module's names
(:func:`package_getattr`).
"""

from __future__ import annotations

import importlib
import importlib.machinery
import sys

__all__ = ["MOVED", "install", "package_getattr"]

MOVED: dict[str, str] = {
    "dnasim.backends": "dnasim.run.backends",
    "dnasim.blas_threads": "dnasim.core.blas_threads",
    "dnasim.cases": "dnasim.plant.cases",
    "dnasim.compiler": "dnasim.compilation.compiler",
    "dnasim.components": "dnasim.library",
    "dnasim.components.attemperator": "dnasim.library.attemperator",
    "dnasim.components.base": "dnasim.model.component",
    "dnasim.components.boundaries": "dnasim.library.boundaries",
    "dnasim.components.channel": "dnasim.library.submodels.channel",
    "dnasim.components.condenser": "dnasim.library.condenser",
    "dnasim.components.control_valve": "dnasim.library.control_valve",
    "dnasim.components.controller": "dnasim.library.controller",
    "dnasim.components.drain_valve": "dnasim.library.drain_valve",
    "dnasim.components.drum": "dnasim.library.drum",
    "dnasim.components.heat_exchanger": "dnasim.library.heat_exchanger",
    "dnasim.components.junctions": "dnasim.library.junctions",
    "dnasim.components.lmtd_numba": "dnasim.model.lmtd_numba",
    "dnasim.components.physics": "dnasim.model.physics",
    "dnasim.components.pid": "dnasim.library.pid",
    "dnasim.components.pipe": "dnasim.library.pipe",
    "dnasim.components.pump": "dnasim.library.pump",
    "dnasim.components.safety_valve": "dnasim.library.safety_valve",
    "dnasim.components.sensor": "dnasim.library.sensor",
    "dnasim.components.signal_blocks": "dnasim.library.signal_blocks",
    "dnasim.components.tube_geometry": "dnasim.library.submodels.tube_geometry",
    "dnasim.components.tube_laws": "dnasim.library.submodels.tube_laws",
    "dnasim.components.turbine": "dnasim.library.turbine",
    "dnasim.components.valve": "dnasim.library.valve",
    "dnasim.components.valve_laws": "dnasim.library.submodels.valve_laws",
    "dnasim.components.walls": "dnasim.library.submodels.walls",
    "dnasim.design_point": "dnasim.tools.design_point",
    "dnasim.entry": "dnasim.cli.entry",
    "dnasim.errors": "dnasim.core.errors",
    "dnasim.examples": "dnasim.plant.examples",
    "dnasim.graph": "dnasim.plant.graph",
    "dnasim.initial_guess": "dnasim.start.guess",
    "dnasim.initialization": "dnasim.start.consistent",
    "dnasim.interrupts": "dnasim.core.interrupts",
    "dnasim.limits": "dnasim.compilation.limits",
    "dnasim.linearize": "dnasim.tools.linearize",
    "dnasim.output": "dnasim.run.output",
    "dnasim.plantfile": "dnasim.plant.plantfile",
    "dnasim.plantinfo": "dnasim.plant.plantinfo",
    "dnasim.plots": "dnasim.tools.plots",
    "dnasim.plugins": "dnasim.plant.plugins",
    "dnasim.reference": "dnasim.tools.reference",
    "dnasim.report": "dnasim.tools.report",
    "dnasim.results": "dnasim.run.results",
    "dnasim.runner": "dnasim.run.runner",
    "dnasim.schematic": "dnasim.tools.schematic",
    "dnasim.signals": "dnasim.plant.signals",
    "dnasim.simulation": "dnasim.run.simulation",
    "dnasim.sinks": "dnasim.run.sinks",
    "dnasim.spec": "dnasim.plant.spec",
    "dnasim.steady_state": "dnasim.start.steady_state",
    "dnasim.structure": "dnasim.compilation.structure",
    "dnasim.sweeps": "dnasim.tools.sweeps",
    "dnasim.system": "dnasim.compilation.system",
    "dnasim.timefunctions": "dnasim.core.timefunctions",
    "dnasim.units": "dnasim.core.units",
    "dnasim.values": "dnasim.core.values",
}


class _MovedLoader:  # an importlib Loader (importlib.abc costs 50 ms to import)
    def __init__(self, new: str):
        self.new = new

    def create_module(self, spec):
        return None  # a placeholder; exec_module puts the real module in its place

    def exec_module(self, module):
        import warnings

        old = module.__name__
        warnings.warn(
            f"the module {old} has moved to {self.new}; import it from there "
            "(the old path will be removed in a later version)",
            DeprecationWarning,
            stacklevel=2,
        )
        sys.modules[old] = importlib.import_module(self.new)


class _MovedFinder:  # an importlib MetaPathFinder
    """Finds the old paths of ``MOVED`` (and modules below an old package path, such as
    a plugin's ``dnasim.components.my_valve`` written into the old folder: none)."""

    def find_spec(self, fullname, path=None, target=None):
        new = MOVED.get(fullname)
        if new is None:
            return None
        is_package = new in ("dnasim.library",)
        return importlib.machinery.ModuleSpec(fullname, _MovedLoader(new), is_package=is_package)


def install() -> None:
    """Put the finder on ``sys.meta_path`` once (``import dnasim`` does this)."""
    if not any(isinstance(f, _MovedFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, _MovedFinder())


def package_getattr(package: str, old_module: str):
    """``__getattr__`` for a package that replaced a module of the same name: a
    submodule of the package by its name, else the name from ``old_module``."""

    def __getattr__(name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        import importlib.util

        try:
            spec = importlib.util.find_spec(f"{package}.{name}")
        except (ImportError, ValueError):
            spec = None
        if spec is not None:
            return importlib.import_module(f"{package}.{name}")
        module = importlib.import_module(old_module)
        try:
            return getattr(module, name)
        except AttributeError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None

    return __getattr__
