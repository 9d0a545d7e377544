"""The starting point for initialisation, from the components' own guesses.

1. Node guesses: each component may guess (p, h) at its ports
   (``Component.guess_nodes``). A fixed-pressure port wins for p, a port that
   supplies its own enthalpy (``FluidPort.h_source``) wins for h.
2. Missing node guesses are propagated along components (within each stream of
   a two-stream component, ``medium_groups``): p copied from a neighbour, h inlet
   to outlet (the design direction); with ``interpolate`` (the steady start's
   second try) the missing pressures are first interpolated between the guessed
   ones (a harmonic mean over the node graph, ``_interpolated_pressures``). What is still missing
   defaults to p = 1e5 Pa and h = h(1e5 Pa, 293.15 K) of the node's fluid.
3. Components fill their own variables (``Component.initial_guess``) in flow
   order (sources first), so a component sees its upstream neighbours' guesses;
   for the steady start each then moves them towards its steady state
   (``Component.steady_guess``: a heated pipe marches its heat balance from the
   inlet, a mixing volume mixes its inflows), so the Newton iteration starts nearer.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from dnasim.core.errors import ResidualDomainError

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


def _interpolated_pressures(system, p_known: dict) -> dict:
    """Pressure guesses [Pa] of the nodes nobody guessed: harmonic interpolation
    between the guessed ones along the components' streams (``medium_groups``).

    Every component stream couples its nodes (a graph edge, weight 1, between each
    pair); an unguessed node's pressure is the mean of its neighbours', i.e. the
    graph Laplacian system L_uu p_u = -L_uk p_k with the guessed nodes k fixed. A
    node between a 20 bar source and a 1 bar sink through two valves thus starts at
    10.5 bar, not at either boundary's pressure: copying the upstream pressure
    would give the first valve dp = 0, where a valve's flow does not depend on its
    opening (dm/dz = C sqrt(dp) = 0), and a controller driving that valve would be
    a singular column of the steady-start Jacobian. Nodes connected to no guessed
    node are left out (they get P_DEFAULT)."""
    nodes = list(system.node_names)
    pos = {n: i for i, n in enumerate(nodes)}
    adj = np.zeros((len(nodes), len(nodes)))
    for name, comp in system.components.items():
        for ports in _streams(comp):
            idx = sorted({pos[system.connections[(name, p.name)]] for p in ports})
            for a in idx:
                for b in idx:
                    if a != b:
                        adj[a, b] = 1.0
    known = np.array([n in p_known for n in nodes], dtype=bool)
    # the unguessed nodes that reach a guessed one (the others keep P_DEFAULT)
    reach = known.copy()
    for _ in range(len(nodes)):
        grown = reach | (adj[:, reach].sum(axis=1) > 0)
        if np.array_equal(grown, reach):
            break
        reach = grown
    free = reach & ~known
    if not free.any():
        return {}
    lap = np.diag(adj.sum(axis=1)) - adj
    p_k = np.array([p_known.get(n, 0.0) for n in nodes])[known]
    p_u = np.linalg.solve(lap[np.ix_(free, free)], -lap[np.ix_(free, known)] @ p_k)
    return {n: float(p) for n, p in zip(np.array(nodes)[free], p_u, strict=True)}


def _restriction(ports) -> bool:
    """A stream whose ports are all flow resistances (a valve, a pump, a turbine)."""
    return all(p.pressure == "resistance" for p in ports if p.role != "probe")


def _spread_pressures(system, p_guess, low_friction) -> None:
    """Copy guessed pressures to the unguessed nodes of each stream, until nothing
    changes; ``low_friction`` True: through the streams that are not restrictions only,
    False: through the restrictions only, None: through all."""
    for _ in range(len(system.components) + 1):
        changed = False
        for name, comp in system.components.items():
            for ports in _streams(comp):
                if low_friction is not None and _restriction(ports) == low_friction:
                    continue
                nodes = [system.connections[(name, p.name)] for p in ports]
                known_p = [p_guess[n] for n in nodes if n in p_guess]
                for n in nodes:
                    if n not in p_guess and known_p:
                        p_guess[n] = known_p[0]
                        changed = True
        if not changed:
            break


def initial_guess(
    system, t0: float, interpolate: bool = False, steady: bool = False, march: bool = False
) -> np.ndarray:
    """The starting point y [SI] at t0. ``interpolate``: unguessed node pressures
    between the guessed ones (``_interpolated_pressures``), otherwise copied from a
    neighbour along the streams. ``steady``: for the steady start, each component's
    ``steady_guess`` follows its ``initial_guess`` (a heated pipe's marched
    enthalpies). ``march``: the node enthalpies follow the flow (``_march``), and for
    the steady start the controllers' set points guess what they measure
    (``set_point_guesses``). The plant file's node guesses (``System.node_guesses``)
    win over everything else."""
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
            if march and port.role == "inlet":
                # an inlet's own enthalpy is what leaves it in reverse flow; in the
                # design direction the node holds what its outlet port delivers
                rh = 0.5
            if p is not None and rp > p_rank.get(node, 0):
                p_guess[node], p_rank[node] = p, rp
            if h is not None and rh > h_rank.get(node, 0):
                h_guess[node], h_rank[node] = h, rh
    T_guess = {}
    if march and steady:
        for node, (q, value) in set_point_guesses(system, t0).items():
            if q == "p" and p_rank.get(node, 0) < SET_POINT_RANK:
                p_guess[node], p_rank[node] = value, SET_POINT_RANK
            elif q == "h" and h_rank.get(node, 0) < SET_POINT_RANK:
                h_guess[node], h_rank[node] = value, SET_POINT_RANK
            elif q == "T" and h_rank.get(node, 0) < SET_POINT_RANK:
                T_guess[node], h_rank[node] = value, SET_POINT_RANK
    for node, g in getattr(system, "node_guesses", {}).items():
        if g.get("p") is not None:
            p_guess[node], p_rank[node] = g["p"], NODE_GUESS_RANK
        if g.get("h") is not None:
            h_guess[node], h_rank[node] = g["h"], NODE_GUESS_RANK
            T_guess.pop(node, None)
        elif g.get("T") is not None:
            T_guess[node], h_rank[node] = g["T"], NODE_GUESS_RANK
            h_guess.pop(node, None)
    if interpolate:
        p_guess.update(_interpolated_pressures(system, p_guess))
    # propagate along components, within each stream (``medium_groups``): a heat
    # exchanger's gas side must not take the water side's pressure or enthalpy.
    # With ``march`` the pressures spread first through the streams that hold a volume
    # or a junction (pipes, exchangers, vessels: small friction), and only then across
    # the restrictions (valves, pumps, turbines: every port a resistance), so that a
    # pressure drop is guessed across a valve rather than along a pipe
    passes = (True, False) if march else (None,)
    for low_friction in passes:
        _spread_pressures(system, p_guess, low_friction)
    for _ in range(len(system.components) + 1):
        changed = False
        for name, comp in system.components.items():
            for ports in _streams(comp):
                inlets = [system.connections[(name, p.name)] for p in ports if p.role == "inlet"]
                outlets = [system.connections[(name, p.name)] for p in ports if p.role == "outlet"]
                known_h = [h_guess[n] for n in inlets if n in h_guess]
                for n in outlets:
                    if n not in h_guess and n not in T_guess and known_h:
                        h_guess[n] = known_h[0]
                        changed = True
        if not changed:
            break
    for node in system.node_names:
        k = system.node_index[node]
        p = p_guess.get(node, P_DEFAULT)
        h = h_guess.get(node)
        medium = system.node_media.get(node)
        if h is None and node in T_guess and medium is not None:
            try:
                h = medium.h_pT(p, T_guess[node])
            except ResidualDomainError:
                h = None
        if h is None:
            h = medium.h_pT(p, T_DEFAULT) if medium is not None else 1e5
        y[k], y[k + 1] = p, h
    pinned = {n for n, r in h_rank.items() if r >= SET_POINT_RANK}
    by_name = {b.comp.name: b for b in system.blocks}
    order = flow_order(system)
    for name in order:
        b = by_name[name]
        x = b.local(y)
        b.comp.initial_guess(t0, x)
        if steady:
            b.comp.steady_guess(t0, x)
        y[b.gidx] = x.data
        if march:
            _march(system, b, y, pinned)
    return y


#: ranks of the guesses of a node's p and h: the plant file's node guesses win over
#: everything; a controller's set point over the components' own guesses (a drum's
#: p0) but not over a boundary's pressure (rank 2) when both name a node
NODE_GUESS_RANK = 10
SET_POINT_RANK = 1.5


def _march(system, block, y, pinned) -> None:
    """The march of the enthalpies through the network: after a component's guess, each
    node at one of its outlet ports takes the enthalpy it delivers there in the design
    direction (``FluidPort.h_out``: a valve's inlet enthalpy, a pump's h_2, a pipe's last
    volume, a drum's saturated steam), so the components downstream (later in
    ``flow_order``) see the fluid that reaches them. A node guessed by the plant file or
    by a controller's set point (``pinned``) keeps its guess."""
    comp = block.comp
    for port in comp.fluid_ports():
        if port.role != "outlet" or port.h_out is None:
            continue
        node = system.connections[(comp.name, port.name)]
        if node in pinned:
            continue
        try:
            h = float(y[block.gidx[block.index[port.h_out]]])
        except (KeyError, IndexError):
            continue
        medium = system.node_media.get(node)
        k = system.node_index[node]
        if not np.isfinite(h):
            continue
        if medium is not None:
            try:
                medium.state(float(y[k]), h)
            except ResidualDomainError:
                continue
        y[k + 1] = h


def set_point_guesses(system, t0) -> dict:
    """{node: (quantity, value)}: what each controller with a set point measures at a
    node, read as a guess of that node's state at rest: a pressure controller's set
    point [Pa] (``"n_hdr.p"`` or a ``PressureSensor`` at the node), a temperature
    controller's [K], an enthalpy controller's [J/kg]. A controller at rest holds its
    set point unless it is saturated, so this is where the node's state goes."""
    out = {}
    units = {"Pa": "p", "K": "T", "J/kg": "h"}
    for (cname, inp), (src, ref) in system.links.items():
        if inp != "measured":
            continue
        comp = system.components[cname]
        if getattr(comp, "setpoint_from_signal", True) or "setpoint" not in comp.params:
            continue
        try:
            w = float(comp.param_at("setpoint", t0))
        except (TypeError, ValueError):
            continue
        if src in system.node_index:
            if ref in ("p", "h", "T"):
                out[src] = (ref, w)
            continue
        sensor = system.components.get(src)
        if sensor is None:
            continue
        probes = [p for p in sensor.fluid_ports() if p.role == "probe"]
        outputs = {s.name: s.unit for s in sensor.signal_outputs()}
        if len(probes) != 1 or ref not in outputs or outputs[ref] not in units:
            continue
        node = system.connections[(src, probes[0].name)]
        out[node] = (units[outputs[ref]], w)
    return out
