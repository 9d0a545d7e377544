"""Component plugins: components written outside the package.

Two ways in, both ending in ``REGISTRY`` (a ``Component`` subclass registers
itself under its class name when its module is imported):

* the entry-point group ``dnasim.components`` of installed distributions
  (``[project.entry-points."dnasim.components"] my_pipe = "my_pkg.my_pipe"``; a
  module or a class), loaded once, the first time the registry is asked for;
* modules a plant file names: ``[plant] import = ["my_components"]``, resolved
  next to the plant file first (``my_components.py`` or a package directory
  ``my_components/``), then on ``sys.path``. Importing runs the module's code, and
  a plant file is data: such a key is honoured only when the user allows it
  (``dnasim run --allow-import``, ``dnasim.plant.plantfile.load(path, allow_import=True)``);
  otherwise the plant file is refused with a message naming the modules
  (:func:`module_origin`, found without importing anything).

A second class with a name already in the registry is an error
(``dnasim.model.component.Component.__init_subclass__``), so a plugin cannot
silently replace a library component.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path

from dnasim.core.errors import PlantError

__all__ = [
    "ENTRY_POINT_GROUP",
    "load_entry_points",
    "import_component_modules",
    "module_origin",
    "registry",
]

ENTRY_POINT_GROUP = "dnasim.components"
_loaded = False


def load_entry_points() -> None:
    """Import every entry point of ``dnasim.components`` (once per process)."""
    global _loaded
    if _loaded:
        return
    _loaded = True
    from importlib.metadata import entry_points

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            ep.load()
        except PlantError:
            raise
        except Exception as exc:
            raise PlantError(
                f"component plugin '{ep.name}' ({ep.value}, entry point group "
                f"'{ENTRY_POINT_GROUP}') cannot be imported: {type(exc).__name__}: {exc}"
            ) from None


def registry() -> dict:
    """The component registry, with the library and the entry-point plugins loaded."""
    from dnasim.library import REGISTRY

    load_entry_points()
    return REGISTRY


def import_component_modules(names, base_dir=None) -> list[str]:
    """Import the modules ``names`` (a plant file's ``[plant] import``): from
    ``base_dir`` (the plant file's folder) when a file or package of that name
    is there, else from ``sys.path``. Returns the names; raises ``PlantError``."""
    out = []
    for name in names:
        if not isinstance(name, str) or not all(p.isidentifier() for p in name.split(".")):
            raise PlantError(f"import: {name!r} is not a module name such as 'my_components'")
        if name in sys.modules:
            out.append(name)
            continue
        local = _local_module(name, base_dir)
        try:
            if local is not None:
                spec = importlib.util.spec_from_file_location(name, local)
                module = importlib.util.module_from_spec(spec)
                sys.modules[name] = module
                try:
                    spec.loader.exec_module(module)
                except BaseException:
                    del sys.modules[name]
                    raise
            else:
                importlib.import_module(name)
        except PlantError:
            raise
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise PlantError(f"import: module '{name}' needs '{exc.name}': {exc}") from None
            where = f"next to the plant file ({base_dir}) nor " if base_dir else ""
            raise PlantError(
                f"import: no module '{name}' {where}on sys.path; put {name}.py next to the "
                "plant file"
            ) from None
        except Exception as exc:
            raise PlantError(
                f"import: module '{name}' failed to import: {type(exc).__name__}: {exc}"
            ) from None
        out.append(name)
    return out


def module_origin(name, base_dir=None) -> str:
    """Where ``[plant] import`` would take the module ``name`` from, in words, found
    without importing it (nor its parent packages): a file next to the plant file,
    a file on ``sys.path``, or nowhere."""
    import importlib.machinery

    if not isinstance(name, str) or not all(p.isidentifier() for p in name.split(".")):
        return "not a module name"
    local = _local_module(name, base_dir)
    if local is not None:
        return f"{local}, next to the plant file"
    if "." in name:
        return "a submodule of a package on sys.path"
    if name in sys.builtin_module_names:
        return "a module built into Python"
    try:
        found = importlib.machinery.PathFinder.find_spec(name)
    except (ImportError, ValueError):
        found = None
    if found is None:
        return "not found next to the plant file nor on sys.path"
    return f"{found.origin or name}, on sys.path"


def _local_module(name, base_dir):
    if base_dir is None or "." in name:
        return None
    base = Path(base_dir)
    if (base / f"{name}.py").is_file():
        return base / f"{name}.py"
    if (base / name / "__init__.py").is_file():
        return base / name / "__init__.py"
    return None
