"""compile(plant) -> System: the one step between the plant graph and the solver.

    system = compile(plant)          # raises PlantError naming every problem
    report, system = check(plant)    # never raises for a bad plant; system is None then

Steps, each once:

1. graph checks on the ``Plant`` (names, wiring; ``structure.analyse_graph``);
2. media per port and per node (``resolve_media``): a port group's fluid is its
   component's parameter (``medium``, or e.g. a heat exchanger's ``hot_medium``),
   else it propagates through the nodes from the groups that name one, else the
   plant's default medium. A node joins ports of one fluid only;
3. the ``System`` is built (index maps, sparsity, switch functions);
4. structure checks on the System (counts, matching, index 1, connectivity;
   ``structure.analyse_system``).

The System keeps no reference to the Plant; the components it holds get their
media (``component.port_media[port]``, and ``component.medium`` when all their
ports carry one fluid).
"""

from __future__ import annotations

from dnasim.errors import PlantError
from dnasim.structure import StructureReport, analyse_graph, analyse_system

__all__ = ["compile", "check", "resolve_media"]


def resolve_media(plant) -> tuple[dict, dict, list[str]]:
    """Fluid names per port and per node: ``(port_fluids, node_fluids, errors)``.

    ``port_fluids``: (component, port) -> fluid name; ``node_fluids``: node ->
    fluid name (nodes with no known fluid are left out); ``errors``: one message
    per problem (a node joining two fluids, a port group with no fluid)."""
    connections = plant.connections
    groups = plant.medium_units()  # [(component, group, fluid or None, ports)]
    unit_fluid = {}  # (component, group) -> (fluid, where it came from)
    for cname, group, fluid, _ in groups:
        if fluid:
            unit_fluid[(cname, group)] = fluid
    node_fluid: dict[str, tuple[str, str]] = {}
    clashes = []
    changed = True
    while changed:
        changed = False
        for cname, group, _, ports in groups:
            fluid = unit_fluid.get((cname, group))
            nodes = [connections[(cname, p)] for p in ports if (cname, p) in connections]
            if fluid is None:
                known = [node_fluid[n][0] for n in nodes if n in node_fluid]
                if known:
                    unit_fluid[(cname, group)] = known[0]
                    changed = True
                continue
            for node in nodes:
                if node not in node_fluid:
                    node_fluid[node] = (fluid, cname)
                    changed = True
                elif node_fluid[node][0] != fluid and (node, cname, fluid) not in clashes:
                    clashes.append((node, cname, fluid))
    errors = [
        f"node '{node}' joins different fluids: '{node_fluid[node][0]}' (from "
        f"'{node_fluid[node][1]}') and '{fluid}' (from '{cname}')"
        for node, cname, fluid in clashes
    ]
    port_fluids = {}
    for cname, group, _, ports in groups:
        fluid = unit_fluid.get((cname, group), plant.default_medium)
        if fluid is None:
            what = "" if group == "fluid" else f" on its {group} side"
            errors.append(
                f"component '{cname}': cannot tell which fluid it carries{what}; give it "
                "medium=... or give the plant a default medium"
            )
            continue
        for p in ports:
            port_fluids[(cname, p)] = fluid
    nodes = {n: f for n, (f, _) in node_fluid.items()}
    if plant.default_medium is not None:
        for n in plant.node_names():
            nodes.setdefault(n, plant.default_medium)
    return port_fluids, nodes, errors


def _media_objects(plant, port_fluids, node_fluids, errors):
    """get_medium for every fluid name; sets the components' media. Returns
    (node_media, port_media) as name -> medium object."""
    from dnasim.media import get_medium

    cache, bad = {}, set()

    def medium(fluid, who):
        if fluid not in cache and fluid not in bad:
            try:
                cache[fluid] = get_medium(fluid)
            except Exception as err:  # an unknown fluid name: reported, not raised
                bad.add(fluid)
                errors.append(f"{who}: medium '{fluid}': {err}")
        return cache.get(fluid)

    port_media = {}
    for (cname, port), fluid in port_fluids.items():
        port_media[(cname, port)] = medium(fluid, f"component '{cname}'")
    for name, comp in plant.components.items():
        own = {p: m for (c, p), m in port_media.items() if c == name}
        comp.port_media = own
        fluids = {port_fluids[(name, p)] for p in own}
        if len(fluids) == 1 and all(m is not None for m in own.values()):
            comp.medium = next(iter(own.values()))
            comp.medium_name = fluids.pop()
        else:
            comp.medium = None
    node_media = {}
    for node, fluid in node_fluids.items():
        if fluid in cache or fluid not in bad:
            m = cache.get(fluid)
            if m is None:
                try:
                    m = cache[fluid] = get_medium(fluid)
                except Exception:  # reported with the components that carry it
                    m = None
            node_media[node] = m
    return node_media, port_media


def check(plant):
    """Structural analysis: ``(StructureReport, System or None)``; never raises for a
    bad plant (the problems are in ``report.errors``). The DAE is built once."""
    from dnasim.system import System

    report = StructureReport()
    analyse_graph(plant, report)
    if report.errors:
        return report, None
    port_fluids, node_fluids, errors = resolve_media(plant)
    node_media, port_media = _media_objects(plant, port_fluids, node_fluids, errors)
    try:
        system = System(plant, node_media, port_media)
    except PlantError as err:
        report.errors.extend(errors)
        report.errors.append(str(err))
        return report, None
    analyse_system(plant, system, report)
    report.errors.extend(errors)
    if not report.errors:
        report.errors.extend(_state_problems(plant))
    return report, system


def _state_problems(plant, t0: float = 0.0) -> list[str]:
    """States the components prescribe (a boundary's supply at (p, T)), evaluated at
    t0 and at every breakpoint of their time functions: a pressure above the fluid's
    range, 5000 degC, a (p, T) supply at its saturation temperature. The messages
    name the component and the state (``BoundaryStateError``); found here, ``dnasim
    check`` reports them before any numerics."""
    from dnasim.errors import ResidualDomainError

    problems = []
    for comp in plant.components.values():
        for t in sorted({t0, *comp.breakpoints()}):
            try:
                comp.guess_nodes(t)
            except (ResidualDomainError, PlantError, ValueError) as err:
                problems.append(str(err))
                break
    return problems


def compile(plant):  # noqa: A001 - the name of the stage
    """The plant as a ``System`` (raises ``PlantError`` listing every problem)."""
    report, system = check(plant)
    report.raise_if_errors()
    return system
