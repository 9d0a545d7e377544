"""Structural analysis of a plant and its compiled System, before any numerics.

``dnasim.compilation.compiler.check(plant)`` runs ``analyse_graph`` on the plant, builds the
System once and runs ``analyse_system`` on it.

Checks, in order (later ones need the earlier ones to pass):

1. names: duplicate component names, a node named like a component;
2. wiring: dangling fluid ports and signal inputs, nodes with one port only,
   groups of nodes (joined by valves and junctions, which pass enthalpy on)
   into which no port supplies an enthalpy of its own (no storage volume, no
   boundary with h or T);
3. counting: per component, equations = own variables (each node brings its p
   and h and its mass and mixing equations); for the plant, equations = unknowns;
4. structural regularity: a maximum matching between equations and variables
   (Hopcroft-Karp, ``scipy.sparse.csgraph.maximum_bipartite_matching``; a variable
   and its derivative count as one);
   unmatched equations and variables are named by component;
5. index 1: a maximum matching between the equations and {y'_i of the
   differential variables, y_j of the algebraic ones}. If it is not perfect the
   DAE has index > 1. The common cause, two storage volumes (or a storage volume
   and a fixed pressure) joined with no flow resistance between them, is named in
   plain words from the ports' pressure roles, with the parameter whose zero value
   removed the resistance (a Pipe's k = 0, a HeatExchanger side without friction),
   and from the components' own ``structure_problems()``;
6. connectivity: disconnected sub-networks are reported as a warning.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import maximum_bipartite_matching

from dnasim.core.errors import PlantError

__all__ = ["StructureReport", "analyse_graph", "analyse_system"]


@dataclass
class StructureReport:
    """What ``Plant.check()`` found. ``ok`` is True when there are no errors."""

    errors: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    n_equations: int = 0
    n_unknowns: int = 0
    n_differential: int = 0
    unmatched_equations: list = field(default_factory=list)
    unmatched_variables: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.errors

    def __str__(self):
        lines = [
            f"structure: {self.n_equations} equations, {self.n_unknowns} unknowns "
            f"({self.n_differential} differential)"
        ]
        lines += [f"error: {e}" for e in self.errors]
        lines += [f"warning: {w}" for w in self.warnings]
        if self.ok:
            lines.append("ok")
        return "\n".join(lines)

    def raise_if_errors(self):
        if self.errors:
            raise PlantError(
                "the plant is not well posed:\n" + "\n".join(f"  - {e}" for e in self.errors)
            )


def analyse_graph(plant, report) -> None:
    """Checks 1-2, on the ``Plant`` alone (no system is built)."""
    _check_names(plant, report)
    _check_wiring(plant, report)
    _check_node_guesses(plant, report)


def analyse_system(plant, system, report) -> None:
    """Checks 3-6, on the compiled ``System`` of ``plant`` (the plant's graph is
    used only to name nodes and ports in the messages)."""
    report.n_equations = system.n_equations
    report.n_unknowns = system.n
    report.n_differential = int(system.differential.sum())
    _check_counts(plant, system, report)
    _check_matching(plant, system, report)
    _check_connectivity(plant, report)


def _check_names(plant, report):
    for name in sorted(set(plant.duplicates)):
        report.errors.append(
            f"duplicate component name '{name}': each component needs its own name"
        )
    for node in plant.node_names():
        if node in plant.components:
            report.errors.append(
                f"node '{node}' has the same name as a component; rename one of them"
            )


def _check_node_guesses(plant, report):
    """A node guess (``PlantGraph.guess_node``) names a node of the plant."""
    guesses = getattr(plant, "node_guesses", {}) or {}
    nodes = plant.node_names()
    for node in guesses:
        if node not in nodes:
            close = [n for n in nodes if n.lower() == node.lower()]
            hint = f"; did you mean '{close[0]}'?" if close else ""
            report.errors.append(
                f"node guess for '{node}': the plant has no node of that name{hint} (its "
                f"nodes: {', '.join(nodes)})"
            )


def _check_wiring(plant, report):
    for name, comp in plant.components.items():
        for port in comp.fluid_ports():
            if (name, port.name) not in plant.connections:
                report.errors.append(
                    f"component '{name}' ({type(comp).__name__}): fluid port '{port.name}' is not "
                    "connected (dangling)"
                )
        for sig in comp.signal_inputs():
            if (name, sig.name) not in plant.links:
                report.errors.append(
                    f"component '{name}' ({type(comp).__name__}): signal input '{sig.name}' is "
                    "not linked (dangling)"
                )
    for node in plant.node_names():
        ports = plant.ports_at(node)
        labels = ", ".join(f"{c}.{p.name}" for c, p in ports)
        flowing = [(c, p) for c, p in ports if p.role != "probe"]
        if len(flowing) < 2:
            report.errors.append(
                f"node '{node}' connects only {labels}: a fluid port must meet at least one other "
                "port"
            )
    _check_enthalpy_sources(plant, report)


def _check_enthalpy_sources(plant, report):
    """Every group of nodes joined by pass-through components needs a port that
    supplies an enthalpy of its own (``FluidPort.h_source``)."""
    parent = {n: n for n in plant.node_names()}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for name, comp in plant.components.items():
        passing = [
            plant.connections[(name, p.name)]
            for p in comp.fluid_ports()
            if p.role != "probe" and not p.h_source and (name, p.name) in plant.connections
        ]
        for a, b in zip(passing, passing[1:], strict=False):
            parent[find(a)] = find(b)
    has_source = defaultdict(bool)
    members = defaultdict(list)
    for node in plant.node_names():
        members[find(node)].append(node)
    for (cname, pname), node in plant.connections.items():
        port = plant.components[cname].port(pname)
        if port.role != "probe" and port.h_source:
            has_source[find(node)] = True
    for root, nodes in members.items():
        if has_source[root]:
            continue
        labels = ", ".join(
            f"{c}.{p.name}" for n in nodes for c, p in plant.ports_at(n) if p.role != "probe"
        )
        which = " and ".join(f"node '{n}'" for n in nodes)
        report.errors.append(
            f"{which} ({labels}): no port supplies an "
            "enthalpy there (no storage volume, no boundary with h or T), so nothing sets the "
            "enthalpy; give a boundary h or T (a sink boundary may take only p or m)"
        )


def _check_counts(plant, dae, report):
    for b in dae.blocks:
        comp = b.comp
        n_eq = b.eq_slice.stop - b.eq_slice.start
        # unique: a component may read one of its own variables as a signal input
        n_own = len({g for g in b.gidx if g >= dae.n_node_vars and dae.var_owner[g] == comp.name})
        if n_eq != n_own:
            what = "too many" if n_eq > n_own else "too few"
            report.errors.append(
                f"component '{comp.name}' ({type(comp).__name__}) declares {n_eq} equations for "
                f"{n_own} own variables: {what} equations"
            )
    if dae.n_equations != dae.n:
        report.errors.append(
            f"degrees of freedom: the plant has {dae.n_equations} equations for {dae.n} unknowns"
        )


def _matching(n_eq, n_var, rows):
    """Maximum matching, then the Dulmage-Mendelsohn over- and under-determined
    parts: the equations (and their variables) reachable by alternating paths from
    the unmatched equations, and the variables (and their equations) reachable
    from the unmatched variables. Unlike the unmatched items of one particular
    matching these sets do not depend on which maximum matching was found."""
    cols_of = [list(c) for c in rows]
    rows_of = [[] for _ in range(n_var)]
    for i, cols in enumerate(rows):
        for j in cols:
            rows_of[j].append(i)
    # Hopcroft-Karp on the biadjacency matrix (scipy, iterative). networkx's
    # bipartite.hopcroft_karp_matching is recursive and exceeds Python's recursion
    # limit on a pipe of ~1000 volumes (a long alternating path).
    r = [i for i, cols in enumerate(rows) for _ in cols]
    c = [j for cols in rows for j in cols]
    bi = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(n_eq, n_var))
    match_of_eq = maximum_bipartite_matching(bi, perm_type="column")  # var index or -1
    m = {}
    for i, j in enumerate(match_of_eq):
        if j >= 0:
            m[("e", i)] = ("v", int(j))
            m[("v", int(j))] = ("e", i)
    un_eq = [i for i in range(n_eq) if ("e", i) not in m]
    un_var = [j for j in range(n_var) if ("v", j) not in m]
    over_eq, stack = set(un_eq), list(un_eq)
    while stack:
        i = stack.pop()
        for j in cols_of[i]:
            k = m.get(("v", j))
            if k is not None and k[1] not in over_eq:
                over_eq.add(k[1])
                stack.append(k[1])
    under_var, stack = set(un_var), list(un_var)
    while stack:
        j = stack.pop()
        for i in rows_of[j]:
            k = m.get(("e", i))
            if k is not None and k[1] not in under_var:
                under_var.add(k[1])
                stack.append(k[1])
    return sorted(over_eq), sorted(under_var)


def _check_matching(plant, dae, report):
    full_rows = [sorted(set(a) | set(b)) for a, b in zip(dae.rows_y, dae.rows_yp, strict=False)]
    over, under = _matching(dae.n_equations, dae.n, full_rows)
    if over or under:
        report.unmatched_equations = [dae.eq_names[i] for i in over]
        report.unmatched_variables = [dae.names[j] for j in under]
        parts = []
        if over:
            parts.append(
                "over-determined equations (more equations than unknowns among them): "
                + _by_owner(dae.eq_names, dae.eq_owner, over)
            )
        if under:
            parts.append(
                "under-determined variables (too few equations for them): "
                + _by_owner(dae.names, dae.var_owner, under)
            )
        report.errors.append("structurally singular: " + "; ".join(parts))
        return
    diff = dae.differential
    idx_rows = [
        sorted({j for j in yp if diff[j]} | {j for j in y if not diff[j]})
        for y, yp in zip(dae.rows_y, dae.rows_yp, strict=False)
    ]
    over, under = _matching(dae.n_equations, dae.n, idx_rows)
    plain = _pressure_conflicts(plant)
    for comp in plant.components.values():
        plain += comp.structure_problems()
    for text in plain:
        report.errors.append(text)
    if over or under:
        report.unmatched_equations = [dae.eq_names[i] for i in over]
        labels = [f"d({nm})/dt" if diff[j] else nm for j, nm in enumerate(dae.names)]
        report.unmatched_variables = [labels[j] for j in under]
        report.errors.append(
            "the DAE has index > 1: its equations cannot be solved for the algebraic variables "
            "and the "
            "derivatives of the differential ones. Over-determined equations: "
            + _by_owner(dae.eq_names, dae.eq_owner, over)
            + "; under-determined unknowns: "
            + _by_owner(labels, dae.var_owner, under)
        )


def _by_owner(names, owners, idx):
    groups = defaultdict(list)
    for i in idx:
        groups[owners[i]].append(names[i])
    if not groups:
        return "none"
    return "; ".join(
        f"in '{o}': {', '.join(v[:6])}{' ...' if len(v) > 6 else ''}" for o, v in groups.items()
    )


def _pressure_conflicts(plant):
    """Plain-words diagnosis: groups of nodes at one pressure (joined by junctions
    without resistance) whose pressure is set by more than one storage volume or
    fixed boundary."""
    parent = {n: n for n in plant.node_names()}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for name, comp in plant.components.items():
        equal = [
            plant.connections[(name, p.name)] for p in comp.fluid_ports() if p.pressure == "equal"
        ]
        for a, b in zip(equal, equal[1:], strict=False):
            parent[find(a)] = find(b)
    owners = defaultdict(list)
    for (cname, pname), node in plant.connections.items():
        port = plant.components[cname].port(pname)
        if port.pressure in ("storage", "fixed"):
            owners[find(node)].append((cname, pname, port.pressure, node, port.pressure_param))
    out = []
    for who in owners.values():
        if len(who) < 2:
            continue
        nodes = sorted({w[3] for w in who})
        parts = []
        for cname, pname, kind, _, param in who:
            what = "a storage volume" if kind == "storage" else "a fixed pressure"
            if kind == "storage" and param is not None:
                what += f": its friction parameter '{param}' is 0"
            parts.append(f"'{cname}' ({what}, port '{pname}')")
        out.append(
            f"node{'s' if len(nodes) > 1 else ''} {', '.join(repr(n) for n in nodes)}: "
            + " and ".join(parts)
            + " are joined with no flow resistance between them, so the pressure there is set "
            "twice "
            "and the DAE has index 2. Put a flow resistance between them (a Valve, or a Pipe, "
            "whose "
            "inlet has friction)."
        )
    return out


def _check_connectivity(plant, report):
    """Disconnected sub-networks of the graph of ``Plant.graph`` (components and
    nodes as vertices, fluid connections and signal links as edges), found with
    scipy's connected components (no networkx import on the run path)."""
    from scipy.sparse.csgraph import connected_components

    vertex = {("component", c): i for i, c in enumerate(plant.components)}
    for node in plant.node_names():
        vertex.setdefault(("node", node), len(vertex))
    edges = [(("component", c), ("node", n)) for (c, _), n in plant.connections.items()]
    edges += [(("component", s), ("component", d)) for (d, _), (s, _) in plant.links.items()]
    for a, b in edges:
        vertex.setdefault(a, len(vertex))
        vertex.setdefault(b, len(vertex))
    rows = [vertex[a] for a, _ in edges]
    cols = [vertex[b] for _, b in edges]
    nv = len(vertex)
    g = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(nv, nv))
    n_parts, labels = connected_components(g, directed=False)
    if n_parts > 1:
        desc = []
        for k in range(n_parts):  # part k holds the first vertex not in parts 0..k-1
            comps = sorted(
                n for (kind, n), i in vertex.items() if kind == "component" and labels[i] == k
            )
            desc.append("{" + ", ".join(comps) + "}")
        report.warnings.append(
            f"the plant has {n_parts} disconnected sub-networks: " + " ".join(desc)
        )
