"""compile(plant) -> System: the one step between the plant graph and the solver.

    system = compile(plant)          # raises PlantError naming every problem
    report, system = check(plant)    # never raises for a bad plant; system is None then

Steps, each once:

1. graph checks on the ``Plant`` (names, wiring; ``structure.analyse_graph``);
2. signal sources (``signal_sources``): every ``inputs`` link resolved to a signal
   output, a component variable or a node quantity, with its unit and a dimension
   check against the input; a node temperature gets an ideal probe (``dnasim.plant.signals``);
   an unknown source is reported alone (nothing that follows from it);
3. media per port and per node (``resolve_media``): a port group's fluid is its
   component's parameter (``medium``, or e.g. a heat exchanger's ``hot_medium``),
   else it propagates through the nodes from the groups that name one, else the
   plant's default medium. A node joins ports of one fluid only;
4. the ``System`` is built (index maps, sparsity, switch functions);
5. structure checks on the System (counts, matching, index 1, connectivity;
   ``structure.analyse_system``), and algebraic loops through signals only
   (``signal_loops``).

One way: compile never writes into the Plant. Before anything is set, the
components are copied (``own_components``: a deep copy of each, made once per
compile, media shared as the one ``get_medium`` instance per fluid), and everything
compile decides is set on the copies, which the System keeps as its own: the media
(``component.port_media[port]``, and ``component.medium`` when all their ports carry
one fluid), the units of the linked signals (``component.input_units``), the
parameters converted in those units (``Component.resolve_signal_units``), and every
cache a component fills while it is evaluated. Two Systems of one Plant share no
component; a Plant changed and compiled again leaves every System compiled before as
it was. The System keeps no reference to the Plant; the resolved signal sources are
handed to it (``link_sources``), not resolved again.
"""

from __future__ import annotations

from copy import copy as shallow_copy
from copy import deepcopy
from dataclasses import replace

from dnasim.compilation.structure import StructureReport, analyse_graph, analyse_system
from dnasim.core.errors import PlantError

__all__ = ["compile", "check", "resolve_media", "signal_sources", "link_sources", "own_components"]


def own_components(plant):
    """A copy of ``plant`` for one compile: the same class and attributes, its own
    ``components`` (a deep copy of each component, in one pass so that objects the
    components share stay shared; a medium copies as itself, ``Medium.__deepcopy__``),
    ``connections`` and ``links``. What compile sets on a component (media, input
    units, converted parameters) and what a component caches while it is evaluated
    then belong to the System it makes, never to the caller's plant."""
    memo: dict = {}
    copy = shallow_copy(plant)
    copy.components = {name: deepcopy(comp, memo) for name, comp in plant.components.items()}
    copy.connections = dict(plant.connections)
    copy.links = dict(plant.links)
    return copy


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
    """get_medium for every fluid name; sets the media of ``plant``'s components (the
    copies of ``own_components``, never the caller's). Returns
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
    from dnasim.compilation.system import System

    report = StructureReport()
    analyse_graph(plant, report)
    if report.errors:
        return report, None
    plant = own_components(plant)  # from here on: the System's components, not the caller's
    plant, problems, sources = link_sources(plant)
    if problems:
        report.errors.extend(problems)
        return report, None
    port_fluids, node_fluids, errors = resolve_media(plant)
    node_media, port_media = _media_objects(plant, port_fluids, node_fluids, errors)
    try:
        system = System(plant, node_media, port_media, sources)
    except PlantError as err:
        report.errors.extend(errors)
        report.errors.append(str(err))
        return report, None
    analyse_system(plant, system, report)
    if not report.errors:
        report.errors.extend(signal_loops(system))
    report.errors.extend(errors)
    if not report.errors:
        report.errors.extend(_medium_problems(plant))
    if not report.errors:
        report.errors.extend(_state_problems(plant))
    if not report.errors:
        report.errors.extend(_vessel_problems(plant))
    return report, system


def signal_sources(plant):
    """Resolve every signal link (``dnasim.plant.signals``): ``(plant, problems)``,
    the first two of ``link_sources``."""
    plant, problems, _ = link_sources(plant)
    return plant, problems


def link_sources(plant):
    """Resolve every signal link (``dnasim.plant.signals``), once per compile:
    ``(plant, problems, sources)``.

    Returns the plant to compile: the given one, or, when a link reads a node
    temperature ("n_hdr.T"), a copy with one ideal ``TemperatureSensor`` (tau = 0)
    probing that node, named "n_hdr~T", and the link reading its output. The
    caller's plant is not changed. ``problems``: plain-words messages naming both
    ends of each bad link (unknown source, a vector without an index, a
    dimension that does not fit the input). ``sources``: (component, input) ->
    ``dnasim.plant.signals.Source`` of the plant returned (a node temperature: the
    probe's output), each with its final unit (a signal output of unit "*" takes
    the unit its block derives from its own linked inputs, ``signal_output_unit``);
    empty when there are problems. The System takes them as they are."""
    from dnasim.plant.signals import NODE_QUANTITIES, dimension_problem, node_sensor_name, resolve

    nodes = set(plant.node_names())
    problems, sources = [], {}
    for (dname, inp), (sname, ref) in plant.links.items():
        comp = plant.components.get(sname)
        found = resolve(sname, ref, comp, sname in nodes)
        if found is None:
            found = (
                f"no component named '{sname}' (and no node) for the signal source "
                f"'{sname}.{ref}', which must be a component's output or variable, or a "
                "node's " + ", ".join(NODE_QUANTITIES)
            )
        if isinstance(found, str):
            problems.append(f"component '{dname}': signal input '{inp}': {found}")
        else:
            sources[(dname, inp)] = found
    if problems:
        return plant, problems, {}

    def unit_of(key, seen=()):
        src = sources[key]
        if src.unit != "*" or key in seen:
            return src.unit
        ins = [k for k in sources if k[0] == src.owner]  # the block's own inputs
        if not ins:
            return "*"
        units = {k[1]: unit_of(k, (*seen, key)) for k in ins}
        return plant.components[src.owner].signal_output_unit(src.variable, units)

    for (dname, inp), src in sources.items():
        dst = plant.components[dname]
        port = next(q for q in dst.signal_inputs() if q.name == inp)
        msg = dimension_problem(
            f"{src.owner}.{src.ref}",
            unit_of((dname, inp)),
            inp,
            f"{type(dst).__name__} '{dname}'",
            str(port.unit or "1"),
            port.doc,
        )
        if msg:
            problems.append(msg)
    if problems:
        return plant, problems, {}
    resolved = {}
    for key, src in sources.items():
        unit = unit_of(key)
        resolved[key] = src if unit == src.unit else replace(src, unit=unit)
    temps = sorted({s.owner for s in sources.values() if s.kind == "node" and s.ref == "T"})
    if not temps:
        return plant, [], resolved
    from dnasim.library.sensor import TemperatureSensor

    copy = shallow_copy(plant)  # the same class and attributes; new dicts below
    copy.components = dict(plant.components)
    copy.connections = dict(plant.connections)
    copy.links = dict(plant.links)
    for node in temps:
        name = node_sensor_name(node)
        copy.components[name] = TemperatureSensor(name, T_lag=0.0)
        copy.connections[(name, "port")] = node
    for key, src in sources.items():
        if src.kind == "node" and src.ref == "T":
            probe = node_sensor_name(src.owner)
            copy.links[key] = (probe, "T")
            resolved[key] = resolve(probe, "T", copy.components[probe])
    return copy, [], resolved


def signal_loops(system) -> list[str]:
    """Algebraic loops through signals only, in plain words (empty when none).

    The equations and algebraic variables of the components without fluid ports
    (controllers, blocks, sensors on signals) are matched, and the strongly
    connected components of the resulting dependency graph are the blocks that
    must be solved simultaneously. A block that reads a signal input (a link) is a
    loop closed through signals with no lag in it, e.g. a controller measuring its
    own output: reported with the links it runs through."""
    import numpy as np
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components, maximum_bipartite_matching

    blocks = [b for b in system.blocks if not b.comp.fluid_ports()]
    rows = [i for b in blocks for i in range(b.eq_slice.start, b.eq_slice.stop)]
    if not rows:
        return []
    alg = system.algebraic
    owned = sorted({g for b in blocks for g in b.gidx if system.var_owner[g] == b.comp.name})
    # unknowns of the index-1 system: the algebraic variables and the derivatives
    # of the differential ones (a state itself is known at each instant)
    col_pos = {g: k for k, g in enumerate(owned)}
    cols = owned
    r, c = [], []
    for k, i in enumerate(rows):
        for g in system.rows_y[i]:
            if g in col_pos and alg[g]:
                r.append(k)
                c.append(col_pos[g])
        for g in system.rows_yp[i]:
            if g in col_pos and not alg[g]:
                r.append(k)
                c.append(col_pos[g])
    if not cols:
        return []
    bi = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(len(rows), len(cols)))
    match = maximum_bipartite_matching(bi.tocsc(), perm_type="row")  # col -> row or -1
    eq_of_col = {k: int(e) for k, e in enumerate(match) if e >= 0}
    # equation a depends on equation b when a reads the variable b is solved for
    dr, dc = [], []
    for a, b in zip(r, c, strict=True):
        e = eq_of_col.get(b)
        if e is not None and e != a:
            dr.append(a)
            dc.append(e)
    n = len(rows)
    dep = sp.csr_matrix((np.ones(len(dr)), (dr, dc)), shape=(n, n))
    ncomp, label = connected_components(dep, directed=True, connection="strong")
    out = []
    local_rows = {}
    for b in blocks:
        for i in range(b.eq_slice.start, b.eq_slice.stop):
            local_rows[i] = b
    for lab in range(ncomp):
        members = [rows[k] for k in range(n) if label[k] == lab]
        solved = {cols[k] for k, e in eq_of_col.items() if label[e] == lab}
        links = []  # (source, destination) of the links the loop runs through
        for (dname, inp), (sname, ref) in system.links.items():
            b = next((x for x in blocks if x.comp.name == dname), None)
            if b is None or inp not in b.index:
                continue
            g = b.gidx[b.index[inp]]
            reads = any(local_rows[i] is b and g in system.rows_y[i] for i in members)
            if reads and g in solved:
                links.append((f"{sname}.{ref}", f"{dname}.{inp}", sname == dname))
        if not links:
            continue
        comps = sorted({system.eq_owner[i] for i in members})
        if len(comps) == 1 and all(own for _, _, own in links):
            verb = "measures" if any(b.endswith(".measured") for _, b, _ in links) else "reads"
            what = f"component '{comps[0]}' {verb} its own output"
        else:
            what = "the signals of " + ", ".join(f"'{c}'" for c in comps) + " form a closed loop"
        out.append(
            f"algebraic loop through signals only: {what} ("
            + ", ".join(f"'{a}' -> '{b}'" for a, b, _ in links)
            + "), with no lag and no plant in the loop: the equations "
            + ", ".join(system.eq_names[i] for i in members)
            + " must hold at once, and the loop alone defines the value. Link the input to a "
            "measurement of the plant (a sensor, a node's p, or a variable of a fluid "
            "component), or put a FirstOrderLag in the loop"
        )
    return out


def _medium_problems(plant) -> list[str]:
    """Components that hold a liquid and its vapour (``Component.TWO_PHASE_GROUPS``:
    a drum, a feedwater tank, a condenser's shell) given a medium without a
    two-phase region (a gas): one message each, naming the component and the key
    of the medium, instead of the property failure that would follow."""
    from dnasim.model.physics import is_condensable

    out = []
    for name, comp in plant.components.items():
        need = getattr(comp, "TWO_PHASE_GROUPS", ())
        if not need:
            continue
        for group, param, ports in comp.medium_groups():
            medium = next((comp.port_media.get(p) for p in ports if comp.port_media.get(p)), None)
            if group not in need or medium is None or is_condensable(medium):
                continue
            kind = type(comp).__name__
            side = "" if group == "fluid" else f" on its {group} side"
            out.append(
                f"component '{name}' ({kind}), key '{param}': the medium "
                f"{getattr(medium, 'label', medium)} has no two-phase region, but a {kind} "
                f"holds saturated liquid and vapour{side} and needs a two-phase (condensable) "
                f'medium such as "Water"; give the component {param} = "Water" or change '
                "the plant's medium"
            )
    return out


def _component_message(comp, err: Exception, t: float) -> str:
    """``err`` raised by component ``comp`` as a message naming it and, for a state
    a parameter gives (a temperature or pressure out of a fluid's range), the key:
    ``component 'pipe' (Pipe), key 'T0': FlueGas (NASA7): cannot evaluate h_pT ...``."""
    msg = str(err)
    if msg.startswith(f"component '{comp.name}'"):
        return msg
    key = None
    for value in (getattr(err, "T", None), getattr(err, "p", None)):
        if key is None and isinstance(value, float):
            key = _param_with_value(comp, value, t)
    where = f"component '{comp.name}' ({type(comp).__name__})"
    return f"{where}{f', key {key!r}' if key else ''}: {msg}"


def _param_with_value(comp, value: float, t: float) -> str | None:
    """The first parameter of ``comp`` whose value (SI, at time t) is ``value``."""
    for pname, v in getattr(comp, "params", {}).items():
        if v is None or isinstance(v, bool | str):
            continue
        try:
            x = float(comp.param_at(pname, t)) if callable(v) else float(v)
        except (TypeError, ValueError, KeyError, AttributeError):
            continue
        if x == value or abs(x - value) <= 1e-9 * max(1.0, abs(value)):
            return pname
    return None


def _state_problems(plant, t0: float = 0.0) -> list[str]:
    """States the components prescribe (a boundary's supply at (p, T), a pipe's T0, a
    turbine's nominal inlet state), evaluated at t0 and at every breakpoint of their
    time functions: a pressure above the fluid's range, 5000 degC, a (p, T) supply at
    its saturation temperature. The messages name the component and, where a
    parameter gives the state, the key (``_component_message``); found here,
    ``dnasim check`` reports them before any numerics."""
    from dnasim.core.errors import ResidualDomainError

    problems = []
    t0 = getattr(getattr(plant, "simulation", None), "t_start", t0)
    for comp in plant.components.values():
        for t in sorted({t0, *comp.breakpoints()}):
            try:
                comp.guess_nodes(t)
            except (ResidualDomainError, PlantError, ValueError) as err:
                problems.append(_component_message(comp, err, t))
                break
    return problems


def _vessel_problems(plant) -> list[str]:
    """Set points that ask a vessel for more than it holds: a controller's
    ``setpoint`` (at its start and every breakpoint) for a signal that the vessel
    bounds (``Component.signal_range``: a drum's level below V_t/A, its V_l below
    V_t). At a steady start the controller's integral puts exactly that much water
    in the vessel; found here, ``dnasim check`` reports it."""
    problems = []
    t0 = getattr(getattr(plant, "simulation", None), "t_start", 0.0)
    for (dname, inp), (sname, ref) in plant.links.items():
        dest, src = plant.components.get(dname), plant.components.get(sname)
        if inp != "measured" or dest is None or src is None:
            continue
        if dest.params.get("setpoint") is None or not hasattr(src, "signal_range"):
            continue
        bounds = src.signal_range(ref)
        if bounds is None:
            continue
        lo, hi, unit, what = bounds
        for t in sorted({t0, *dest.breakpoints()}):
            try:
                w = float(dest.param_at("setpoint", t))
            except (TypeError, ValueError, KeyError):
                break
            if lo < w < hi:
                continue
            side = f"above {what}" if w >= hi else f"at or below {lo:g} {unit}, an empty vessel"
            problems.append(
                f"component '{dname}' ({type(dest).__name__}), key 'setpoint': the set point "
                f"{w:.6g} {unit} of '{sname}.{ref}' (at t = {t:g} s) is {side}: the "
                f"controller would drive '{sname}' ({type(src).__name__}) outside its volume "
                "(at a steady start it puts exactly this much liquid in it); give a set "
                f"point between {lo:g} and {hi:.6g} {unit}, or a larger vessel"
            )
            break
    return problems


def compile(plant):  # noqa: A001 - the name of the stage
    """The plant as a ``System`` (raises ``PlantError`` listing every problem)."""
    report, system = check(plant)
    report.raise_if_errors()
    return system
