"""The starting point for initialisation, from the components' own guesses.

1. Node guesses: each component may guess (p, h) at its ports
   (``Component.guess_nodes``). A fixed-pressure port wins for p, a port that
   supplies its own enthalpy (``FluidPort.h_source``) wins for h.
2. Missing node guesses are propagated along components (within each stream of
   a two-stream component, ``medium_groups``), inlet to outlet and
   back (enthalpy along the design direction), then default to p = 1e5 Pa and
   h = h(1e5 Pa, 293.15 K) of the node's fluid.
3. Components fill their own variables (``Component.initial_guess``) in flow
   order (sources first), so a component sees its upstream neighbours' guesses.
"""

from __future__ import annotations

from collections import deque

import numpy as np

P_DEFAULT = 1e5  # Pa
T_DEFAULT = 293.15  # K


def flow_order(plant) -> list[str]:
    """``plant``: anything with ``components`` and ``connections`` (a Plant or a
    System). Component names in breadth-first order from the sources along the design flow."""
    downstream = {}  # node -> components with an inlet/probe there
    for (cname, pname), node in plant.connections.items():
        port = plant.components[cname].port(pname)
        if port.role != "outlet":
            downstream.setdefault(node, []).append(cname)
    sources = [
        name
        for name, comp in plant.components.items()
        if not any(p.role == "inlet" for p in comp.fluid_ports())
    ]
    order, seen = [], set()
    queue = deque(sources)
    while queue:
        c = queue.popleft()
        if c in seen:
            continue
        seen.add(c)
        order.append(c)
        comp = plant.components[c]
        for p in comp.fluid_ports():
            if p.role == "outlet":
                queue.extend(downstream.get(plant.connections[(c, p.name)], []))
    order += [c for c in plant.components if c not in seen]
    # signal-only components (controllers) after the components they read
    fluid = [c for c in order if plant.components[c].fluid_ports()]
    signal = [c for c in order if not plant.components[c].fluid_ports()]
    return fluid + signal


def _streams(comp) -> list[list]:
    """The component's fluid ports grouped by stream (``Component.medium_groups``;
    ports in no group, e.g. probes, form one more group)."""
    ports = {p.name: p for p in comp.fluid_ports()}
    groups = [[ports[n] for n in g[2] if n in ports] for g in comp.medium_groups()]
    rest = [p for n, p in ports.items() if not any(n in g[2] for g in comp.medium_groups())]
    return [g for g in groups + [rest] if g]


def initial_guess(system, t0: float) -> np.ndarray:
    y = np.zeros(system.n)
    p_guess, h_guess = {}, {}
    p_rank, h_rank = {}, {}
    for name, comp in system.components.items():
        guesses = comp.guess_nodes(t0) if comp.fluid_ports() else {}
        for pname, (p, h) in guesses.items():
            node = system.connections[(name, pname)]
            port = comp.port(pname)
            rp = 2 if port.pressure == "fixed" else 1
            rh = 2 if port.h_source and port.role != "probe" else 1
            if p is not None and rp > p_rank.get(node, 0):
                p_guess[node], p_rank[node] = p, rp
            if h is not None and rh > h_rank.get(node, 0):
                h_guess[node], h_rank[node] = h, rh
    # propagate along components, within each stream (``medium_groups``): a heat
    # exchanger's gas side must not take the water side's pressure
    for _ in range(len(system.components) + 1):
        changed = False
        for name, comp in system.components.items():
            for ports in _streams(comp):
                nodes = [system.connections[(name, p.name)] for p in ports]
                inlets = [system.connections[(name, p.name)] for p in ports if p.role == "inlet"]
                outlets = [system.connections[(name, p.name)] for p in ports if p.role == "outlet"]
                known_p = [p_guess[n] for n in nodes if n in p_guess]
                for n in nodes:
                    if n not in p_guess and known_p:
                        p_guess[n] = known_p[0]
                        changed = True
                known_h = [h_guess[n] for n in inlets if n in h_guess]
                for n in outlets:
                    if n not in h_guess and known_h:
                        h_guess[n] = known_h[0]
                        changed = True
        if not changed:
            break
    for node in system.node_names:
        k = system.node_index[node]
        p = p_guess.get(node, P_DEFAULT)
        h = h_guess.get(node)
        if h is None:
            medium = system.node_media.get(node)
            h = medium.h_pT(p, T_DEFAULT) if medium is not None else 1e5
        y[k], y[k + 1] = p, h
    by_name = {b.comp.name: b for b in system.blocks}
    for name in flow_order(system):
        b = by_name[name]
        x = b.local(y)
        b.comp.initial_guess(t0, x)
        y[b.gidx] = x.data
    return y
