"""The stages import one way (issue 8, docs/architecture.md).

Every module of the package is parsed with ``ast`` (nothing is imported), and every
``import`` statement in it is read, also those inside functions (the lazy imports
that keep ``dnasim --help`` fast). The stages below are in import order: a module
may import modules of its own stage and of earlier stages only, never a later one.
A stage is a list of modules; a package named there holds all its submodules.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import networkx as nx
import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "dnasim"

#: the stages, earliest first (docs/architecture.md has one line per stage)
STAGES: list[tuple[str, list[str]]] = [
    (
        "foundation",
        [
            "dnasim.core",
            "dnasim.moved_modules",
            "dnasim.core.errors",
            "dnasim.core.interrupts",
            "dnasim.core.timefunctions",
            "dnasim.core.blas_threads",
        ],
    ),
    ("units", ["dnasim.core.units"]),
    ("values", ["dnasim.core.values"]),
    ("media", ["dnasim.media", "dnasim.correlations"]),
    ("components", ["dnasim.model", "dnasim.library"]),
    ("plugins", ["dnasim.plant.plugins"]),
    ("signals", ["dnasim.plant.signals"]),
    ("graph", ["dnasim.plant", "dnasim.plant.graph"]),
    (
        "system",
        [
            "dnasim.compilation",
            "dnasim.compilation.system",
            "dnasim.compilation.structure",
            "dnasim.compilation.limits",
        ],
    ),
    ("compiler", ["dnasim.compilation.compiler"]),
    ("solver", ["dnasim.solver", "dnasim.start.consistent", "dnasim.start.guess"]),
    ("start", ["dnasim.start", "dnasim.start.initial", "dnasim.start.steady_state"]),
    ("results", ["dnasim.run", "dnasim.run.results", "dnasim.run.output", "dnasim.run.sinks"]),
    ("backends", ["dnasim.run.backends"]),
    ("simulation", ["dnasim.run.simulation"]),
    ("plant", ["dnasim.plant.plant"]),
    ("spec", ["dnasim.plant.spec"]),
    (
        "plant files",
        [
            "dnasim.plant.plantfile",
            "dnasim.plant.toml_reading",
            "dnasim.plant.component_info",
            "dnasim.plant.network_check",
            "dnasim.plant.migrations",
            "dnasim.plant.examples",
        ],
    ),
    ("cases", ["dnasim.plant.cases"]),
    (
        "runner",
        [
            "dnasim.run.runner",
            "dnasim.plant.plantinfo",
            "dnasim.tools.plots",
            "dnasim.tools.linearize",
            "dnasim.testing",
            "dnasim.tools.design_point",
        ],
    ),
    (
        "tools",
        [
            "dnasim.tools",
            "dnasim.tools.sweeps",
            "dnasim.tools.schematic",
            "dnasim.tools.report",
            "dnasim.tools.reference",
        ],
    ),
    (
        "command line",
        ["dnasim.cli", "dnasim.cli.commands", "dnasim.cli.entry", "dnasim.__main__", "dnasim"],
    ),
]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def all_modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def imports_of(name: str, path: Path, modules) -> list[tuple[str, int]]:
    """(imported dnasim module, line) for every import statement in the file,
    at any depth. ``from dnasim.x import y`` imports ``dnasim.x.y`` when that is a
    module, else ``dnasim.x``; relative imports are resolved against the package."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in _walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for a in node.names:
                sub = f"{mod}.{a.name}"
                out.append((sub if sub in modules else mod, node.lineno))
    return [(m, line) for m, line in out if m == "dnasim" or m.startswith("dnasim.")]


def _is_main_block(node) -> bool:
    """``if __name__ == "__main__":``: what runs when the file is run as a program
    (``python -m dnasim.cli.commands``), not a dependency of the module."""
    t = node.test if isinstance(node, ast.If) else None
    return (
        isinstance(t, ast.Compare)
        and isinstance(t.left, ast.Name)
        and t.left.id == "__name__"
        and any(isinstance(c, ast.Constant) and c.value == "__main__" for c in t.comparators)
    )


def _walk(tree):
    """Every node of ``tree`` (functions and classes included), except the insides
    of ``if __name__ == "__main__":`` blocks."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        if not _is_main_block(node):
            todo.extend(ast.iter_child_nodes(node))


def stage_of(module: str) -> int:
    """Index of the stage holding ``module`` (the longest listed prefix)."""
    best, index = "", None
    for i, (_, names) in enumerate(STAGES):
        for n in names:
            if (module == n or module.startswith(n + ".")) and len(n) > len(best):
                best, index = n, i
    if index is None:
        raise AssertionError(f"module {module} is in no stage: add it to STAGES")
    return index


@functools.cache
def import_graph() -> nx.DiGraph:
    modules = all_modules()
    g = nx.DiGraph()
    for name, path in modules.items():
        g.add_node(name)
        for target, line in imports_of(name, path, modules):
            if target != name:
                g.add_edge(name, target, line=line, path=path)
    return g


def test_every_module_is_in_a_stage():
    for name in all_modules():
        stage_of(name)  # raises naming the module


def test_no_module_imports_a_later_stage():
    g = import_graph()
    bad = []
    for src, dst, data in g.edges(data=True):
        a, b = stage_of(src), stage_of(dst)
        if b > a:
            where = f"{data['path'].relative_to(PACKAGE.parent)}:{data['line']}"
            bad.append(
                f"{where}: {src} (stage '{STAGES[a][0]}') imports {dst} (later stage "
                f"'{STAGES[b][0]}')"
            )
    assert not bad, "imports against the stage order:\n" + "\n".join(sorted(bad))


def test_no_import_cycle():
    # within a stage imports may go either way; still no module imports itself round a
    # cycle, lazy imports and packages' __init__ included (at 6533d66 one cycle ran
    # through 34 modules: components, media, compiler, system, plant, spec, plantfile,
    # plugins, runner, sweeps, cases, cli and entry)
    cycles = [sorted(c) for c in nx.strongly_connected_components(import_graph()) if len(c) > 1]
    assert not cycles, f"import cycles: {cycles}"


def test_the_check_finds_a_back_import(tmp_path):
    # the check can fail: a lazy import of the simulation inside a function of a
    # component module is found, at its line, and it is against the stage order
    source = (PACKAGE / "library" / "valve.py").read_text()
    fake = tmp_path / "valve.py"
    fake.write_text(source + "\n\ndef f():\n    from dnasim.run.simulation import simulate\n")
    found = imports_of("dnasim.library.valve", fake, all_modules())
    assert ("dnasim.run.simulation", source.count("\n") + 4) in found
    assert stage_of("dnasim.run.simulation") > stage_of("dnasim.library.valve")
    # and one under `if __name__ == "__main__":` is not a dependency of the module
    fake.write_text(source + '\nif __name__ == "__main__":\n    import dnasim.cli.commands\n')
    assert "dnasim.cli.commands" not in [m for m, _ in imports_of("x", fake, all_modules())]


@pytest.mark.parametrize(
    ("module", "forbidden"),
    [
        ("dnasim.model.component", "dnasim.plant.plantfile"),
        ("dnasim.model.component", "dnasim.plant.spec"),
        ("dnasim.plant.graph", "dnasim.compilation.compiler"),
        ("dnasim.plant.graph", "dnasim.run.simulation"),
        ("dnasim.compilation.system", "dnasim.plant.graph"),
        ("dnasim.compilation.system", "dnasim.plant.plant"),
        ("dnasim.run.results", "dnasim.compilation.system"),
        ("dnasim.media.if97", "dnasim.cli.entry"),
    ],
)
def test_known_back_references_are_gone(module, forbidden):
    g = import_graph()
    assert not g.has_edge(module, forbidden)


def test_the_model_names_keep_their_import_path():
    # issue 21: dnasim.model.component was split into declarations (Param, ports,
    # Variable, Equation, Switch, Output), evaluation (LocalVector, ScalarRows) and the
    # Component base; every moved name still imports from dnasim.model.component, as
    # the same object
    from dnasim.model import component, declarations, evaluation

    for mod in (declarations, evaluation):
        for name in mod.__all__:
            assert getattr(component, name) is getattr(mod, name), (mod.__name__, name)
            assert name in component.__all__, name
    # each of the three has one job: the declarations and the evaluation views import
    # no Component, the evaluation no declaration
    mods = all_modules()
    for name in ("dnasim.model.declarations", "dnasim.model.evaluation"):
        assert "dnasim.model.component" not in {m for m, _ in imports_of(name, mods[name], mods)}
    ev = "dnasim.model.evaluation"
    assert "dnasim.model.declarations" not in {m for m, _ in imports_of(ev, mods[ev], mods)}
