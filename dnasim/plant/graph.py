"""PlantGraph: components wired through named nodes (DNA's network view).

Nodes carry the pressure p [Pa] and the specific enthalpy h [J/kg] of the
fluid flowing into them (mixed); components carry the mass flows. A node has
no volume: its equations are the mass balance (sum of flows in = sum of flows
out) and the mixing equation, which makes h the flow-weighted mean of the
enthalpies the components deliver into the node (upwind by the actual flow, in
either direction; see ``dnasim.compilation.system``). Signal ports are linked output to
input. The graph is also given as a networkx multigraph (``PlantGraph.graph``)
with one vertex per component ("component", name) and per node ("node", name).

``PlantGraph`` is the graph only: it builds and answers queries, and imports
nothing but the components, the signal references and the errors.
``dnasim.compilation.compiler`` turns it into a ``System`` (media, index maps, residual,
sparsity, switches); ``dnasim.run.simulation`` integrates a System. The user's
``dnasim.Plant`` (``dnasim.plant.plant``) is this graph with the shorthands
``check()``, ``compile()`` and ``simulate()``.

    plant = Plant("demo")
    plant.add(PressureBoundary("src", p=2e5, T=600.0, medium="Air"))
    plant.add(Pipe("pipe1", V=0.1, kA=50.0, k=1e3, C_wall=5e4))
    plant.connect("src.port", "a"); plant.connect("pipe1.inlet", "a")
    ...
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dnasim.core.errors import PlantError
from dnasim.model.component import Component
from dnasim.plant.signals import resolve, split_ref

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["PlantGraph"]


class PlantGraph:
    """A network of components, nodes and signal links. See the module docstring."""

    def __init__(self, name: str = "plant", medium: str | None = None):
        self.name = name
        self.default_medium = medium
        self.components: dict[str, Component] = {}
        self.connections: dict[tuple[str, str], str] = {}  # (component, port) -> node
        self.links: dict[tuple[str, str], tuple[str, str]] = {}  # (comp, input) -> (comp, output)
        #: guesses of node states for the start, node -> {"p": Pa, "h": J/kg or "T": K}
        self.node_guesses: dict[str, dict[str, float]] = {}
        self._duplicates: list[str] = []

    # ------------------------------------------------------------ building
    def add(self, component: Component) -> Component:
        """Add a component; returns it. A duplicate name is reported by ``check()``."""
        if not isinstance(component, Component):
            raise PlantError(f"plant '{self.name}': add() takes a component, got {component!r}")
        if component.name in self.components:
            self._duplicates.append(component.name)
        else:
            self.components[component.name] = component
        return component

    def _split(self, ref: str, what: str):
        if not isinstance(ref, str) or ref.count(".") != 1:
            raise PlantError(f"plant '{self.name}': expected 'component.{what}', got {ref!r}")
        comp, port = ref.split(".")
        if comp not in self.components:
            raise PlantError(f"plant '{self.name}': no component named '{comp}' (in {ref!r})")
        return self.components[comp], port

    def connect(self, port_ref: str, node: str) -> None:
        """Bind fluid port "comp.port" to the node named ``node`` (created on first use)."""
        comp, port = self._split(port_ref, "port")
        names = [p.name for p in comp.fluid_ports()]
        if port not in names:
            raise PlantError(
                f"component '{comp.name}' ({type(comp).__name__}) has no fluid port '{port}'; "
                f"its fluid ports are: {', '.join(names) or 'none'}"
            )
        if not isinstance(node, str) or not node or "." in node:
            raise PlantError(
                f"plant '{self.name}': node name must be a non-empty string without '.', got "
                f"{node!r}"
            )
        key = (comp.name, port)
        if key in self.connections:
            raise PlantError(
                f"component '{comp.name}': port '{port}' is already connected to node "
                f"'{self.connections[key]}'"
            )
        self.connections[key] = node

    def link(self, output_ref: str, input_ref: str) -> None:
        """Feed a signal source into signal input "comp.input".

        The source is a signal output ("pi.z"), any component variable ("valve.m",
        "pipe.m[3]", "drum.level") or a node quantity ("n_hdr.p", "n_hdr.h",
        "n_hdr.T"); see ``dnasim.plant.signals``. Component sources are checked here;
        node sources when the plant is compiled (the node may be connected later)."""
        parts = split_ref(output_ref)
        if parts is None:
            raise PlantError(
                f"plant '{self.name}': expected a signal source 'component.output', "
                f"'component.variable' or 'node.p', got {output_ref!r}"
            )
        sname, out = parts
        dst, inp = self._split(input_ref, "input")
        src = self.components.get(sname)
        if src is not None:
            found = resolve(sname, out, src)
            if isinstance(found, str):
                raise PlantError(found)
        ins = [s.name for s in dst.signal_inputs()]
        declared = {s.name: s for s in type(dst).SIGNAL_INPUTS}
        if inp not in ins and inp in declared:  # a parameter replaces the input
            doc = declared[inp].doc
            raise PlantError(
                f"component '{dst.name}' ({type(dst).__name__}) has no signal input "
                f"'{inp}' with these parameters: {inp} is the {doc}; give the parameter or "
                "link the input, not both"
            )
        if inp not in ins:
            raise PlantError(
                f"component '{dst.name}' ({type(dst).__name__}) has no signal input '{inp}'; "
                f"its signal inputs are: {', '.join(ins) or 'none'}"
            )
        if (dst.name, inp) in self.links:
            raise PlantError(f"component '{dst.name}': signal input '{inp}' is already linked")
        self.links[(dst.name, inp)] = (sname, out)

    def guess_node(self, node: str, p=None, T=None, h=None) -> None:
        """Guesses of the state of ``node`` for the start: pressure ``p`` [Pa] and
        temperature ``T`` [K] or specific enthalpy ``h`` [J/kg], numbers in SI or unit
        strings ("100 bar", "500 degC", "3200 kJ/kg"). Only starting points of the
        start's Newton iteration and the steady start's search, they win over every
        guess the components make (``dnasim.start.guess``); the state found is the
        plant's. (A given start's component without initial values of its own takes its
        initial state from its nodes, so there a node guess is also that state.) The
        node must exist when the plant is compiled."""
        from dnasim.core.units import UnitError, to_si

        if not isinstance(node, str) or not node or "." in node:
            raise PlantError(
                f"plant '{self.name}': guess_node: node name must be a non-empty string "
                f"without '.', got {node!r}"
            )
        if T is not None and h is not None:
            raise PlantError(
                f"plant '{self.name}': node '{node}': give T or h as the guess, not both"
            )
        out = {}
        for key, value, unit in (("p", p, "Pa"), ("T", T, "K"), ("h", h, "J/kg")):
            if value is None:
                continue
            try:
                x = to_si(value, unit)
            except (UnitError, TypeError, ValueError) as exc:
                raise PlantError(
                    f"plant '{self.name}': node '{node}': guess {key} = {value!r}: {exc}"
                ) from None
            if not (isinstance(x, float | int) and abs(x) < float("inf")) or (
                key != "h" and not x > 0
            ):
                what = "finite" if key == "h" else "finite and > 0"
                raise PlantError(
                    f"plant '{self.name}': node '{node}': guess {key} = {value!r} must be {what}"
                )
            out[key] = float(x)
        if not out:
            raise PlantError(f"plant '{self.name}': node '{node}': a guess needs p, T or h")
        self.node_guesses[node] = out

    # ------------------------------------------------------------- queries
    def node_names(self) -> list[str]:
        seen = {}
        for node in self.connections.values():
            seen.setdefault(node, None)
        return list(seen)

    def ports_at(self, node: str):
        """[(component name, FluidPort)] attached to ``node``."""
        out = []
        for (cname, pname), n in self.connections.items():
            if n == node:
                out.append((cname, self.components[cname].port(pname)))
        return out

    @property
    def graph(self) -> nx.MultiGraph:
        """Components and nodes as vertices; fluid connections and signal links as edges."""
        import networkx as nx  # 0.15 s to import: only when a graph is asked for

        g = nx.MultiGraph()
        for name, comp in self.components.items():
            g.add_node(("component", name), type=type(comp).__name__)
        for node in self.node_names():
            g.add_node(("node", node))
        for (cname, pname), node in self.connections.items():
            g.add_edge(("component", cname), ("node", node), key=pname, kind="fluid")
        for (dname, inp), (sname, out) in self.links.items():
            kind = "component" if sname in self.components else "node"
            g.add_edge((kind, sname), ("component", dname), key=f"{out}->{inp}", kind="signal")
        return g

    @property
    def duplicates(self) -> list[str]:
        """Names given to more than one ``add()`` (the later ones were not added)."""
        return list(self._duplicates)

    def medium_units(self):
        """The groups of ports that carry one fluid, per component.

        ``[(component name, group, medium parameter value or None, [port names])]``
        (see ``Component.medium_groups``)."""
        out = []
        for name, comp in self.components.items():
            for group, param, ports in comp.medium_groups():
                out.append((name, group, comp.params.get(param), list(ports)))
        return out
