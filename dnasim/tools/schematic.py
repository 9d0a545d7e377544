"""The plant schematic of ``report.html``: an SVG drawn from the plant's graph.

Input: the description of ``plant.json`` (:mod:`dnasim.plant.plantinfo`). Output: one
``<svg>`` element, inline in the page, with

- every component as a symbol by its type (boundary arrow, pipe, valve bow-tie
  with an actuator when a signal drives it, pump, turbine, drum, heat
  exchanger, condenser, attemperator, junction; instruments and controllers as
  ISA bubbles "TT", "LC", ...; signal blocks as boxes), named below;
- every node as a dot, named above;
- fluid connections as lines coloured by the node's medium (water and steam,
  gases, other fluids), with an arrow into each component's inlet;
- signal links as dashed lines from the source to the input they drive,
  instrument taps as thin lines from a sensor to its node.

Layout (:func:`layout`), left to right along the flow as far as the graph
allows (a layered drawing, Sugiyama's method):

1. a directed graph (networkx) of components and nodes: component -> node at an
   outlet port, node -> component at an inlet port; a boundary is a source when
   its flow over the run is into the plant (else, when it gives a supply state);
2. cycles (a closed water-steam loop) are broken by a depth-first search from
   the pumps, then the sources: each edge back to a vertex on the search's path
   is reversed for the layout only (its arrow still shows the flow);
3. layers by the longest path, each vertex then moved right up to its nearest
   successor (a flue-gas source sits next to the exchanger it feeds);
4. edges longer than one layer get dummy points; each layer is ordered by the
   barycentre of its neighbours (down and up sweeps, the order with the fewest
   crossings kept), vertical positions move toward their neighbours' and are
   then spread to keep the symbols apart;
5. separate pieces of the plant are stacked; instruments go below the node
   they measure, controllers and signal blocks in a band below the plant, at
   the mean position of what they read and drive.

Every name in the SVG is escaped (``html.escape``): a plant's strings never
become markup. The elements carry ``data-comp``/``data-node`` and
``data-cols`` (the results columns of the value shown under a symbol), which
the report's script uses for hover cards, values and clicks.
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass, field

__all__ = ["symbol_kind", "layout", "schematic_svg", "Layout"]

#: horizontal distance between layers [px]; vertical gap between symbols [px]
DX = 78.0
GAP = 34.0

#: kind -> (width, height) of the symbol [px]
SIZES = {
    "boundary": (40, 24),
    "pipe": (62, 16),
    "valve": (30, 34),  # the body is 30 x 20; the actuator stands above it
    "pump": (34, 34),
    "turbine": (40, 42),
    "drum": (66, 32),
    "hx": (56, 40),
    "condenser": (54, 46),
    "attemperator": (46, 24),
    "junction": (18, 18),
    "sensor": (30, 30),
    "controller": (36, 36),
    "block": (44, 28),
    "generic": (48, 30),
}

_KINDS = {
    "PressureBoundary": "boundary",
    "MassFlowBoundary": "boundary",
    "Pipe": "pipe",
    "Valve": "valve",
    "ControlValve": "valve",
    "CheckValve": "valve",
    "DrainValve": "valve",
    "SafetyValve": "valve",
    "Pump": "pump",
    "SteamTurbine": "turbine",
    "Drum": "drum",
    "FeedwaterTank": "drum",
    "HeatExchanger": "hx",
    "Condenser": "condenser",
    "Attemperator": "attemperator",
    "Mixer": "junction",
    "Splitter": "junction",
    "TemperatureSensor": "sensor",
    "PressureSensor": "sensor",
    "EnthalpySensor": "sensor",
    "QualitySensor": "sensor",
    "MassFlowSensor": "sensor",
    "LevelSensor": "sensor",
    "PIController": "controller",
    "PIDController": "controller",
}

#: ISA letters of an instrument by its type
_SENSOR_TAGS = {
    "TemperatureSensor": "TT",
    "PressureSensor": "PT",
    "EnthalpySensor": "HT",
    "QualitySensor": "QT",
    "MassFlowSensor": "FT",
    "LevelSensor": "LT",
}
#: a controller's first letter by the SI unit of what it measures
_MEASURED_LETTER = {"K": "T", "Pa": "P", "m": "L", "m3": "L", "kg/s": "F", "J/kg": "H", "-": "Q"}
_BLOCK_TAGS = {
    "Gain": "K",
    "Sum": "Σ",
    "Product": "×",
    "Division": "÷",
    "FirstOrderLag": "1/(1+Ts)",
    "Limiter": "lim",
    "RateLimiter": "rate",
    "Table": "f(u)",
    "DeadTime": "e⁻ˢᵀ",
    "Step": "step",
    "Ramp": "ramp",
    "TableSource": "f(t)",
    "Sine": "sin",
}

#: component leaves shown under a symbol, first ones found (the report's script
#: fills in their final values)
_VALUE_LEAVES = {
    "drum": ("p", "level"),
    "condenser": ("p_v", "level"),
    "turbine": ("P",),
    "pump": ("P",),
    "hx": ("Q_total",),
    "pipe": ("T_out",),
    "valve": ("m",),
    "boundary": ("m",),
    "attemperator": ("T",),
    "junction": ("m_out", "m_in"),
    "sensor": ("T_s", "p_s", "h_s", "x_s", "m_s", "l_s"),
    "controller": ("z",),
    "block": ("y",),
}


def symbol_kind(type_name: str) -> str:
    """The symbol of a component type ("valve", "pump", ...; "generic" if unknown)."""
    if type_name in _KINDS:
        return _KINDS[type_name]
    if type_name in _BLOCK_TAGS:
        return "block"
    if type_name.endswith("Boundary"):
        return "boundary"
    if type_name.endswith("Valve"):
        return "valve"
    if type_name.endswith("Sensor"):
        return "sensor"
    if type_name.endswith("Controller"):
        return "controller"
    return "generic"


def medium_class(name: str | None) -> str:
    """ "water" (water and steam), "gas" (air, flue gas, ideal gases) or "other"."""
    if not name:
        return "other"
    n = str(name).split("::")[-1].split("[")[0].lower()
    if n in ("water", "steam", "if97", "h2o") or n.startswith("water"):
        return "water"
    gases = ("air", "fluegas", "n2", "o2", "co2", "nitrogen", "oxygen", "argon", "ar", "gas")
    if n in gases or "gas" in n or n.startswith("air"):
        return "gas"
    return "other"


@dataclass
class Vertex:
    """A symbol or a node dot (``kind`` "node") at (x, y), its centre [px]."""

    key: tuple  # ("c", name) | ("n", name) | ("d", i)
    kind: str
    x: float = 0.0
    y: float = 0.0
    w: float = 0.0
    h: float = 0.0
    type: str = ""


@dataclass
class Layout:
    vertices: dict = field(default_factory=dict)  # key -> Vertex
    fluid: list = field(default_factory=list)  # (comp, port, node, role, points, into comp)
    taps: list = field(default_factory=list)  # (sensor, node)
    signals: list = field(default_factory=list)  # (source key, target comp, input)
    width: float = 0.0
    height: float = 0.0


def _flow_into(comp: dict, flows: dict) -> bool:
    """Whether a boundary lets fluid into the plant (its port is a source)."""
    f = flows.get(comp["name"])
    if f is not None and math.isfinite(f) and f != 0:
        return f > 0
    return bool(comp.get("supply"))


def _fluid_graph(desc: dict, flows: dict):
    import networkx as nx

    g = nx.DiGraph()
    ports = []  # (comp, port, node, role, edge)
    for c in desc.get("components", ()):
        fluid = [p for p in c.get("ports", ()) if p.get("role") in ("inlet", "outlet")]
        if not fluid:
            continue
        cv = ("c", c["name"])
        g.add_node(cv)
        for p in fluid:
            nv = ("n", p["node"])
            g.add_node(nv)
            if c.get("supply") is not None:
                out = _flow_into(c, flows)
                role = "outlet" if out else "inlet"
            else:
                out = p["role"] == "outlet"
                role = p["role"]
            edge = (cv, nv) if out else (nv, cv)
            g.add_edge(*edge)
            ports.append((c["name"], p["port"], p["node"], role, edge))
    return g, ports


def _back_edges(g, roots) -> tuple[list, list]:
    """Edges that close a cycle (to a vertex on the depth-first path) and the
    order the vertices were found in."""
    seen, on_path, back, found = set(), set(), [], []
    for r in [*roots, *g.nodes]:
        if r in seen:
            continue
        seen.add(r)
        on_path.add(r)
        found.append(r)
        stack = [(r, iter(list(g.successors(r))))]
        while stack:
            v, it = stack[-1]
            w = next(it, None)
            if w is None:
                stack.pop()
                on_path.discard(v)
            elif w in on_path:
                back.append((v, w))
            elif w not in seen:
                seen.add(w)
                on_path.add(w)
                found.append(w)
                stack.append((w, iter(list(g.successors(w)))))
    return back, found


def _crossings(layers, edges_between) -> int:
    n = 0
    for i in range(len(layers) - 1):
        pos_a = {v: k for k, v in enumerate(layers[i])}
        pos_b = {v: k for k, v in enumerate(layers[i + 1])}
        es = [(pos_a[u], pos_b[v]) for u, v in edges_between[i]]
        for a in range(len(es)):
            for b in range(a + 1, len(es)):
                if (es[a][0] - es[b][0]) * (es[a][1] - es[b][1]) < 0:
                    n += 1
    return n


def _layer_piece(dag, found_order):
    """Layers, orders and y positions of one weakly connected piece of the DAG;
    returns (layer of vertex, layers [[vertex]], chains {edge: [dummy, ...]})."""
    import networkx as nx

    layer = {}
    for v in nx.topological_sort(dag):
        layer[v] = max((layer[u] + 1 for u in dag.predecessors(v)), default=0)
    for v in reversed(list(nx.topological_sort(dag))):
        succ = [layer[w] for w in dag.successors(v)]
        if succ and min(succ) - 1 > layer[v]:
            layer[v] = min(succ) - 1
    low = min(layer.values(), default=0)
    layer = {v: k - low for v, k in layer.items()}
    n_layers = max(layer.values(), default=0) + 1
    chains = {}
    dummy = 0
    adj = []  # edges between consecutive layers, (upper vertex, lower vertex)
    for u, v in dag.edges:
        pts = [u]
        for k in range(layer[u] + 1, layer[v]):
            d = ("d", id(dag), dummy)
            dummy += 1
            layer[d] = k
            pts.append(d)
        pts.append(v)
        chains[(u, v)] = pts[1:-1]
        adj += list(zip(pts[:-1], pts[1:], strict=True))
    rank = {v: i for i, v in enumerate(found_order)}
    layers = [[] for _ in range(n_layers)]
    for v in sorted(layer, key=lambda v: (rank.get(v, len(rank)), str(v))):
        layers[layer[v]].append(v)
    # dummies follow the vertex they come from
    for k in range(1, n_layers):
        prev = {v: i for i, v in enumerate(layers[k - 1])}
        up = {}
        for a, b in adj:
            if layer[b] == k and a in prev:
                up.setdefault(b, []).append(prev[a])
        layers[k].sort(key=lambda v: sum(up.get(v, [0])) / max(len(up.get(v, [0])), 1))
    between = [[(a, b) for a, b in adj if layer[a] == k] for k in range(n_layers - 1)]
    preds, succs = {}, {}
    for a, b in adj:
        succs.setdefault(a, []).append(b)
        preds.setdefault(b, []).append(a)
    best, best_n = [list(x) for x in layers], _crossings(layers, between)
    for sweep in range(12):
        down = sweep % 2 == 0
        rng = range(1, n_layers) if down else range(n_layers - 2, -1, -1)
        for k in rng:
            ref = layers[k - 1] if down else layers[k + 1]
            pos = {v: i for i, v in enumerate(ref)}
            nbr = preds if down else succs
            cur = {v: i for i, v in enumerate(layers[k])}

            def key(v, pos=pos, nbr=nbr, cur=cur):
                ps = [pos[w] for w in nbr.get(v, ()) if w in pos]
                return (sum(ps) / len(ps)) if ps else cur[v]

            layers[k].sort(key=key)
        n = _crossings(layers, between)
        if n < best_n:
            best, best_n = [list(x) for x in layers], n
    return layer, best, chains, adj


def _place_y(layers, adj, height_of, iterations: int = 24) -> dict:
    """Vertical positions: each vertex toward the mean of its neighbours, the
    layer's order kept and symbols ``GAP`` apart."""
    nbrs: dict = {}
    for a, b in adj:
        nbrs.setdefault(a, []).append(b)
        nbrs.setdefault(b, []).append(a)
    y = {}
    for lay in layers:
        acc = 0.0
        for v in lay:
            y[v] = acc + height_of(v) / 2
            acc += height_of(v) + GAP
    for _ in range(iterations):
        for lay in layers:
            want = [
                (sum(y[w] for w in nbrs[v]) / len(nbrs[v])) if nbrs.get(v) else y[v] for v in lay
            ]
            pos = []
            for i, v in enumerate(lay):
                p = want[i]
                if i:
                    u = lay[i - 1]
                    p = max(p, pos[-1] + (height_of(u) + height_of(v)) / 2 + GAP)
                pos.append(p)
            shift = sum(w - p for w, p in zip(want, pos, strict=True)) / max(len(lay), 1)
            for i, v in enumerate(lay):
                y[v] = pos[i] + shift
    return y


def layout(desc: dict, flows: dict | None = None) -> Layout:
    """Positions of the symbols, nodes and lines (see the module docstring).

    ``flows``: component name -> mean flow [kg/s] over the run, for the direction
    of boundaries (positive: into the plant)."""
    import networkx as nx

    flows = flows or {}
    comps = {c["name"]: c for c in desc.get("components", ())}
    g, ports = _fluid_graph(desc, flows)
    pumps = [
        ("c", n) for n, c in comps.items() if symbol_kind(c["type"]) == "pump" and ("c", n) in g
    ]
    sources = [v for v in g if v[0] == "c" and g.in_degree(v) == 0 and g.out_degree(v) > 0]
    roots = pumps + sources + [v for v in g if g.in_degree(v) == 0]
    back, found = _back_edges(g, roots)
    dag = g.copy()
    reversed_edges = set()
    for u, v in back:
        dag.remove_edge(u, v)
        if not dag.has_edge(v, u):
            dag.add_edge(v, u)
        reversed_edges.add((u, v))

    def size(v):
        if v[0] == "c":
            return SIZES[symbol_kind(comps[v[1]]["type"])]
        if v[0] == "n":
            return (10, 10)
        return (2, 2)

    lay = Layout()
    top = 40.0
    pieces = sorted(nx.weakly_connected_components(dag), key=len, reverse=True)
    positions = {}
    for piece in pieces:
        sub = dag.subgraph(piece).copy()
        layer, layers, chains, adj = _layer_piece(sub, found)
        ys = _place_y(layers, adj, lambda v: size(v)[1])
        lo = min(ys[v] - size(v)[1] / 2 for v in ys)
        hi = max(ys[v] + size(v)[1] / 2 for v in ys)
        for v, k in layer.items():
            positions[v] = (60.0 + k * DX, top + 22 + ys[v] - lo)
        for (u, v), ds in chains.items():
            positions[(u, v)] = ds
        top += hi - lo + 70.0
    for v in g.nodes:
        x, y = positions[v]
        w, h = size(v)
        kind = "node" if v[0] == "n" else symbol_kind(comps[v[1]]["type"])
        typ = comps[v[1]]["type"] if v[0] == "c" else ""
        lay.vertices[v] = Vertex(v, kind, x, y, w, h, typ)

    # fluid lines: port -> node (or back) through the dummies of the layout edge; a
    # port sits on the side of its symbol that faces where its line goes, ports on
    # one side in the order of their lines' ends (no crossing at the symbol)
    lines = []
    for cname, port, node, role, edge in ports:
        u, v = edge
        key = (u, v) if (u, v) not in reversed_edges else (v, u)
        ds = [positions[d] for d in positions.get(key, [])]
        if (u, v) in reversed_edges:
            ds = ds[::-1]
        if u[0] == "n":
            ds = ds[::-1]  # from the component's side
        cv = lay.vertices[("c", cname)]
        nv = lay.vertices[("n", node)]
        far = ds[0] if ds else (nv.x, nv.y)
        if abs(far[0] - cv.x) > 1:
            right_side = far[0] > cv.x
        else:
            right_side = role == "outlet"
        lines.append([cname, port, node, role, u, ds, right_side, far])
    sides: dict = {}
    for ln in lines:
        sides.setdefault((ln[0], ln[6]), []).append(ln)
    for group in sides.values():
        group.sort(key=lambda ln: ln[7][1])
    for ln in lines:
        cname, port, node, role, u, ds, right_side, _far = ln
        cv = lay.vertices[("c", cname)]
        nv = lay.vertices[("n", node)]
        same = sides[(cname, right_side)]
        i = same.index(ln)
        off = (i - (len(same) - 1) / 2) * min(cv.h / max(len(same), 1), 14.0)
        inset = 2 if cv.kind in ("junction", "pump", "sensor", "controller") else 0
        px = cv.x + (cv.w / 2 - inset if right_side else -cv.w / 2 + inset)
        port_pt = (px, cv.y + off)
        pts = [port_pt, *ds, (nv.x, nv.y)]
        into = u[0] == "n"
        lay.fluid.append((cname, port, node, role, pts[::-1] if into else pts, into))

    # instruments and signal components
    if lay.vertices:
        bottom = max(v.y + v.h / 2 for v in lay.vertices.values())
        right = max(v.x + v.w / 2 for v in lay.vertices.values())
    else:
        bottom, right = 20.0, 60.0
    taken = [(v.x, v.y, v.w, v.h) for v in lay.vertices.values()]

    def free(x, y, w, h):
        return all(
            abs(x - a) > (w + c) / 2 + 8 or abs(y - b) > (h + d) / 2 + 8 for a, b, c, d in taken
        )

    band = []
    for name, c in comps.items():
        if ("c", name) in lay.vertices:
            continue
        kind = symbol_kind(c["type"])
        w, h = SIZES[kind]
        probes = [p["node"] for p in c.get("ports", ()) if p.get("role") == "probe"]
        for node in probes:
            lay.taps.append((name, node))
        placed = False
        if probes and ("n", probes[0]) in lay.vertices:
            nv = lay.vertices[("n", probes[0])]
            for dy in (48, -48, 84, -84):
                if free(nv.x, nv.y + dy, w, h):
                    lay.vertices[("c", name)] = Vertex(
                        ("c", name), kind, nv.x, nv.y + dy, w, h, c["type"]
                    )
                    taken.append((nv.x, nv.y + dy, w, h))
                    placed = True
                    break
        if not placed:
            band.append(name)

    # signal links: source component or node -> target component
    for link in desc.get("links", ()):
        src = str(link.get("source", "")).split(".", 1)[0]
        dst, _, inp = str(link.get("target", "")).partition(".")
        skey = ("c", src) if src in comps else ("n", src)
        lay.signals.append((skey, ("c", dst), inp))
    # the band: x at the mean of the partners, a few passes for chains of blocks
    xs = {n: right / 2 for n in band}
    for _ in range(4):
        for n in band:
            partners = [s for s, d, _ in lay.signals if d == ("c", n)]
            partners += [d for s, d, _ in lay.signals if s == ("c", n)]
            pts = []
            for p in partners:
                if p in lay.vertices:
                    pts.append(lay.vertices[p].x)
                elif p[0] == "c" and p[1] in xs:
                    pts.append(xs[p[1]])
            if pts:
                xs[n] = sum(pts) / len(pts)
    rows: list[list[float]] = []
    for n in sorted(band, key=lambda n: xs[n]):
        kind = symbol_kind(comps[n]["type"])
        w, h = SIZES[kind]
        x = xs[n]
        r = next((i for i, row in enumerate(rows) if x >= row[-1] + 80), None)
        if r is None and len(rows) < 3:
            rows.append([])
            r = len(rows) - 1
        elif r is None:  # three rows full here: the end of the emptiest one
            r = min(range(len(rows)), key=lambda i: rows[i][-1])
            x = rows[r][-1] + 80
        rows[r].append(x)
        y = bottom + 64 + r * 62
        lay.vertices[("c", n)] = Vertex(("c", n), kind, x, y, w, h, comps[n]["type"])
    xs_all = [v.x - v.w / 2 for v in lay.vertices.values()] or [0.0]
    shift = 40.0 - min(xs_all)
    for v in lay.vertices.values():
        v.x += shift
    lay.fluid = [
        (c, p, n, r, [(x + shift, y) for x, y in pts], into) for c, p, n, r, pts, into in lay.fluid
    ]
    lay.width = max([v.x + v.w / 2 for v in lay.vertices.values()] or [100.0]) + 60.0
    lay.height = max([v.y + v.h / 2 for v in lay.vertices.values()] or [60.0]) + 40.0
    return lay


# --------------------------------------------------------------------------- SVG


def _e(s) -> str:
    return html.escape(str(s), quote=True)


def _path(pts) -> str:
    """A smooth path through ``pts``: horizontal tangents at every point."""
    (x0, y0), rest = pts[0], pts[1:]
    d = [f"M{x0:.1f},{y0:.1f}"]
    for x1, y1 in rest:
        if abs(y1 - y0) < 0.5:
            d.append(f"L{x1:.1f},{y1:.1f}")
        else:
            dx = (x1 - x0) / 2 if abs(x1 - x0) > 1 else 30.0
            d.append(f"C{x0 + dx:.1f},{y0:.1f} {x1 - dx:.1f},{y1:.1f} {x1:.1f},{y1:.1f}")
        x0, y0 = x1, y1
    return " ".join(d)


def _shape(v: Vertex, comp: dict, desc: dict, units: dict) -> str:
    """The symbol of component ``comp`` at the origin (the group is translated)."""
    w, h = v.w, v.h
    k = v.kind
    t = comp["type"]
    if k == "boundary":
        tip = 9
        pts = (
            f"{-w / 2},{-h / 2} {w / 2 - tip},{-h / 2} {w / 2},0 {w / 2 - tip},{h / 2} "
            f"{-w / 2},{h / 2}"
        )
        letter = "ṁ" if t == "MassFlowBoundary" else "p"
        return (
            f'<polygon class="body" points="{pts}"/><text class="tag" x="-3" y="4">{letter}</text>'
        )

    if k == "pipe":
        return f'<rect class="body" x="{-w / 2}" y="{-h / 2}" width="{w}" height="{h}" rx="3"/>'
    if k == "valve":
        a, b = w / 2, 10
        out = f'<path class="body" d="M{-a},{-b} L{a},{b} L{a},{-b} L{-a},{b} Z"/>'
        if any(i["input"] in ("z", "opening") for i in comp.get("inputs", ())):
            out += (
                f'<line class="stem" x1="0" y1="0" x2="0" y2="{-b - 8}"/>'
                f'<path class="body" d="M-9,{-b - 8} A9,9 0 0 1 9,{-b - 8} Z"/>'
            )
        if t == "SafetyValve":
            out += f'<path class="stem" d="M0,0 L0,{-b - 2} l-5,-3 l10,-4 l-10,-4 l10,-4 l-5,-3"/>'
        if t == "CheckValve":
            out += f'<path class="fillmark" d="M{-a},{-b} L0,0 L{-a},{b} Z"/>'
        return out
    if k == "pump":
        r = w / 2
        return (
            f'<circle class="body" r="{r}"/>'
            f'<path class="mark" d="M{-r * 0.45},{-r * 0.6} L{r * 0.7},0 '
            f'L{-r * 0.45},{r * 0.6} Z"/>'
        )
    if k == "turbine":
        return (
            f'<polygon class="body" points="{-w / 2},{-h / 4} {w / 2},{-h / 2} '
            f'{w / 2},{h / 2} {-w / 2},{h / 4}"/>'
        )
    if k == "drum":
        return (
            f'<rect class="body" x="{-w / 2}" y="{-h / 2}" width="{w}" height="{h}" rx="{h / 2}"/>'
            f'<path class="liquid" d="M{-w / 2 + 3},2 L{w / 2 - 3},2 '
            f"A{h / 2 - 2},{h / 2 - 2} 0 0 1 {w / 2 - h / 2},{h / 2 - 2} "
            f'L{-w / 2 + h / 2},{h / 2 - 2} A{h / 2 - 2},{h / 2 - 2} 0 0 1 {-w / 2 + 3},2 Z"/>'
        )
    if k == "hx":
        zig = " ".join(
            f"L{-w / 2 + 6 + i * (w - 12) / 6:.1f},{(-1) ** i * h / 4:.1f}" for i in range(7)
        )
        return (
            f'<rect class="body" x="{-w / 2}" y="{-h / 2}" width="{w}" height="{h}" rx="3"/>'
            f'<path class="mark-line" d="M{-w / 2},0 {zig} L{w / 2},0"/>'
        )
    if k == "condenser":
        lines = "".join(
            f'<line class="mark-line" x1="{-w / 2 + 6}" y1="{y}" x2="{w / 2 - 6}" y2="{y}"/>'
            for y in (-h / 4, -h / 4 + 7)
        )
        return (
            f'<path class="body" d="M{-w / 2},{-h / 2} L{w / 2},{-h / 2} L{w / 2},{h / 4} '
            f"Q{w / 2},{h / 2} {w / 4},{h / 2} L{-w / 4},{h / 2} "
            f'Q{-w / 2},{h / 2} {-w / 2},{h / 4} Z"/>'
            + lines
            + f'<path class="liquid" d="M{-w / 2 + 2},{h / 4 - 2} L{w / 2 - 2},{h / 4 - 2} '
            f"Q{w / 2 - 2},{h / 2 - 2} {w / 4},{h / 2 - 2} L{-w / 4},{h / 2 - 2} "
            f'Q{-w / 2 + 2},{h / 2 - 2} {-w / 2 + 2},{h / 4 - 2} Z"/>'
        )
    if k == "attemperator":
        return (
            f'<rect class="body" x="{-w / 2}" y="{-h / 2}" width="{w}" height="{h}" rx="4"/>'
            f'<path class="mark" d="M-4,{-h / 2} L4,{-h / 2} L0,{-h / 2 + 8} Z"/>'
            f'<path class="mark-line" d="M0,{-h / 2 + 8} l-6,8 M0,{-h / 2 + 8} l0,9 '
            f'M0,{-h / 2 + 8} l6,8"/>'
        )
    if k == "junction":
        return f'<circle class="body" r="{w / 2}"/>'
    if k == "sensor":
        tag = _SENSOR_TAGS.get(t, "XT")
        return f'<circle class="bubble" r="{w / 2}"/><text class="tag" y="4">{_e(tag)}</text>'
    if k == "controller":
        letter = "X"
        for ctrl in desc.get("controllers", ()):
            if ctrl.get("name") == comp["name"] and ctrl.get("measured"):
                letter = _MEASURED_LETTER.get(str(units.get(ctrl["measured"], "")), "X")
        r = w / 2
        sub = "PID" if t == "PIDController" else "PI"
        return (
            f'<circle class="bubble" r="{r}"/>'
            f'<line class="mark-line" x1="{-r}" y1="0" x2="{r}" y2="0"/>'
            f'<text class="tag" y="-4">{_e(letter)}C</text>'
            f'<text class="tag small" y="11">{sub}</text>'
        )
    if k == "block":
        tag = _BLOCK_TAGS.get(t, t[:4])
        return (
            f'<rect class="block" x="{-w / 2}" y="{-h / 2}" width="{w}" height="{h}" rx="2"/>'
            f'<text class="tag" y="4">{_e(tag)}</text>'
        )
    initials = "".join(ch for ch in t if ch.isupper())[:3] or t[:3]
    return (
        f'<rect class="body" x="{-w / 2}" y="{-h / 2}" width="{w}" height="{h}" rx="4"/>'
        f'<text class="tag" y="4">{_e(initials)}</text>'
    )


def _value_columns(comp: dict, kind: str, columns) -> list[str]:
    leaves = _VALUE_LEAVES.get(kind, ())
    out = []
    for leaf in leaves:
        col = f"{comp['name']}.{leaf}"
        if col in columns:
            out.append(col)
            if kind not in ("drum", "condenser"):
                break
    return out[:2]


def schematic_svg(desc: dict, flows: dict | None = None, units: dict | None = None) -> str:
    """The plant's schematic as one ``<svg>`` element (see the module docstring).

    ``flows``: component -> mean flow over the run [kg/s] (boundaries' direction);
    ``units``: results column -> SI unit (the values shown under the symbols, the
    letter of a controller's bubble)."""
    units = dict(units or {})
    columns = set(units)
    lay = layout(desc, flows)
    comps = {c["name"]: c for c in desc.get("components", ())}
    media = desc.get("media") or {}
    out = [
        f'<svg class="schematic" xmlns="http://www.w3.org/2000/svg" '
        f'viewBox="0 0 {lay.width:.0f} {lay.height:.0f}" width="{lay.width:.0f}" '
        f'height="{lay.height:.0f}" role="img" aria-label="plant schematic">',
        "<defs>"
        '<marker id="arrow-water" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,1 L10,5 L0,9 Z" class="arrow water"/></marker>'
        '<marker id="arrow-gas" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,1 L10,5 L0,9 Z" class="arrow gas"/></marker>'
        '<marker id="arrow-other" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
        'markerHeight="7" orient="auto"><path d="M0,1 L10,5 L0,9 Z" class="arrow other"/></marker>'
        '<marker id="arrow-signal" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="6" '
        'markerHeight="6" orient="auto"><path d="M0,1 L10,5 L0,9 Z" class="arrow signal"/></marker>'
        "</defs>",
        '<g class="fluid-links">',
    ]
    for cname, port, node, _role, pts, into in lay.fluid:
        m = medium_class(media.get(node))
        marker = f' marker-end="url(#arrow-{m})"' if into else ""
        out.append(
            f'<path class="flow {m}" d="{_path(pts)}"{marker} data-comp="{_e(cname)}" '
            f'data-port="{_e(port)}" data-node="{_e(node)}"/>'
        )
    out.append('</g><g class="taps">')
    for sensor, node in lay.taps:
        a, b = lay.vertices.get(("c", sensor)), lay.vertices.get(("n", node))
        if a is None or b is None:
            continue
        out.append(
            f'<line class="tap" x1="{a.x:.1f}" y1="{a.y:.1f}" x2="{b.x:.1f}" y2="{b.y:.1f}" '
            f'data-comp="{_e(sensor)}" data-node="{_e(node)}"/>'
        )
    out.append('</g><g class="signal-links">')
    for skey, dkey, inp in lay.signals:
        a, b = lay.vertices.get(skey), lay.vertices.get(dkey)
        if a is None or b is None:
            continue
        x0, y0 = a.x, a.y + (a.h / 2 if b.y > a.y + 4 else (-a.h / 2 if b.y < a.y - 4 else 0))
        x1, y1 = (
            b.x,
            b.y + (-b.h / 2 - (10 if b.kind == "valve" else 0) if b.y > a.y + 4 else b.h / 2),
        )
        if abs(b.y - a.y) <= 4:
            x0, y0 = a.x + (a.w / 2 if b.x > a.x else -a.w / 2), a.y
            x1, y1 = b.x - (b.w / 2 if b.x > a.x else -b.w / 2), b.y
            d = f"M{x0:.1f},{y0:.1f} L{x1:.1f},{y1:.1f}"
        else:
            my = (y0 + y1) / 2
            d = f"M{x0:.1f},{y0:.1f} C{x0:.1f},{my:.1f} {x1:.1f},{my:.1f} {x1:.1f},{y1:.1f}"
        out.append(
            f'<path class="signal" d="{d}" marker-end="url(#arrow-signal)" '
            f'data-source="{_e(skey[1])}" data-target="{_e(dkey[1])}.{_e(inp)}"/>'
        )
    out.append('</g><g class="nodes">')
    for v in lay.vertices.values():
        if v.kind != "node":
            continue
        name = v.key[1]
        m = medium_class(media.get(name))
        cols = " ".join(c for c in (f"{name}.p", f"{name}.T") if c in columns)
        out.append(
            f'<g class="node {m}" data-node="{_e(name)}" data-cols="{_e(cols)}" '
            f'transform="translate({v.x:.1f},{v.y:.1f})" tabindex="0">'
            f'<circle r="4.5"/><text class="node-name" y="-8">{_e(name)}</text>'
            f"<title>node {_e(name)}</title></g>"
        )
    out.append('</g><g class="components">')
    for v in lay.vertices.values():
        if v.kind == "node":
            continue
        name = v.key[1]
        comp = comps[name]
        cols = _value_columns(comp, v.kind, columns)
        values = "".join(
            f'<text class="value" y="{v.h / 2 + 25 + 11 * i:.1f}" data-col="{_e(c)}"></text>'
            for i, c in enumerate(cols)
        )
        out.append(
            f'<g class="comp kind-{v.kind}" data-comp="{_e(name)}" data-type="{_e(comp["type"])}" '
            f'transform="translate({v.x:.1f},{v.y:.1f})" tabindex="0">'
            f"{_shape(v, comp, desc, units)}"
            f'<text class="name" y="{v.h / 2 + 13:.1f}">{_e(name)}</text>{values}'
            f"<title>{_e(name)} ({_e(comp['type'])})</title></g>"
        )
    out.append("</g></svg>")
    return "".join(out)
