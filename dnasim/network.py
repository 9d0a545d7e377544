"""The plant: components wired through named nodes (DNA's network view).

Nodes carry the pressure p [Pa] and the specific enthalpy h [J/kg] of the
fluid flowing into them (mixed); components carry the mass flows. A node has
no volume: its equations are the mass balance (sum of flows in = sum of flows
out) and the mixing equation, which makes h the flow-weighted mean of the
enthalpies the components deliver into the node (upwind by the actual flow, in
either direction; see ``dnasim.assembly``). Signal ports are linked output to
input. The plant is held as a networkx multigraph (``Plant.graph``) with one
vertex per component ("component", name) and per node ("node", name).

    plant = Plant("demo")
    plant.add(PressureBoundary("src", p=2e5, T=600.0, medium="Air"))
    plant.add(Pipe("pipe1", V=0.1, kA=50.0, k=1e3, C_wall=5e4))
    plant.connect("src.port", "a"); plant.connect("pipe1.inlet", "a")
    ...
    print(plant.check())
    res = plant.simulate(100.0)
    res["pipe1.T_out"]
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import networkx as nx
import numpy as np

from dnasim.components.base import Component
from dnasim.errors import DAEError, PlantError

__all__ = ["Plant", "StructureReport"]


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


class Plant:
    """A network of components. See the module docstring."""

    def __init__(self, name: str = "plant", medium: str | None = None):
        self.name = name
        self.default_medium = medium
        self.components: dict[str, Component] = {}
        self.connections: dict[tuple[str, str], str] = {}  # (component, port) -> node
        self.links: dict[tuple[str, str], tuple[str, str]] = {}  # (comp, input) -> (comp, output)
        self._duplicates: list[str] = []
        self._dae = None
        self._node_media: dict = {}

    # ------------------------------------------------------------ building
    def add(self, component: Component) -> Component:
        """Add a component; returns it. A duplicate name is reported by ``check()``."""
        if not isinstance(component, Component):
            raise PlantError(f"plant '{self.name}': add() takes a component, got {component!r}")
        if component.name in self.components:
            self._duplicates.append(component.name)
        else:
            self.components[component.name] = component
        self._dae = None
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
        self._dae = None

    def link(self, output_ref: str, input_ref: str) -> None:
        """Feed signal output "comp.output" into signal input "comp.input"."""
        src, out = self._split(output_ref, "output")
        dst, inp = self._split(input_ref, "input")
        outs = [s.name for s in src.signal_outputs()]
        if out not in outs:
            raise PlantError(
                f"component '{src.name}' ({type(src).__name__}) has no signal output '{out}'; "
                f"its signal outputs are: {', '.join(outs) or 'none'}"
            )
        ins = [s.name for s in dst.signal_inputs()]
        if inp not in ins:
            raise PlantError(
                f"component '{dst.name}' ({type(dst).__name__}) has no signal input '{inp}'; "
                f"its signal inputs are: {', '.join(ins) or 'none'}"
            )
        if (dst.name, inp) in self.links:
            raise PlantError(f"component '{dst.name}': signal input '{inp}' is already linked")
        self.links[(dst.name, inp)] = (src.name, out)
        self._dae = None

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
        g = nx.MultiGraph()
        for name, comp in self.components.items():
            g.add_node(("component", name), type=type(comp).__name__)
        for node in self.node_names():
            g.add_node(("node", node))
        for (cname, pname), node in self.connections.items():
            g.add_edge(("component", cname), ("node", node), key=pname, kind="fluid")
        for (dname, inp), (sname, out) in self.links.items():
            g.add_edge(
                ("component", sname), ("component", dname), key=f"{out}->{inp}", kind="signal"
            )
        return g

    def node_medium(self, node):
        return self._node_media.get(node)

    # ------------------------------------------------------------- media
    def _resolve_media(self, report: StructureReport | None = None):
        """Give every fluid component and node a medium object (``dnasim.media``).

        A component's ``medium`` parameter wins; otherwise it is taken from the
        nodes it is connected to (propagated through the network), else from the
        plant's default."""
        from dnasim.media import get_medium

        comp_med = {}
        for name, comp in self.components.items():
            if comp.params.get("medium"):
                comp_med[name] = comp.params["medium"]
        node_med = {}
        errors = []
        changed = True
        while changed:
            changed = False
            for (cname, _), node in self.connections.items():
                m = comp_med.get(cname)
                if m is None:
                    continue
                if node not in node_med:
                    node_med[node] = (m, cname)
                    changed = True
                elif node_med[node][0] != m and (node, cname) not in errors:
                    errors.append((node, cname))
            for (cname, _), node in self.connections.items():
                if cname not in comp_med and node in node_med:
                    comp_med[cname] = node_med[node][0]
                    changed = True
        msgs = []
        for node, cname in errors:
            msgs.append(
                f"node '{node}' joins different fluids: '{node_med[node][0]}' (from "
                f"'{node_med[node][1]}') "
                f"and '{comp_med[cname]}' (from '{cname}')"
            )
        for name, comp in self.components.items():
            if not comp.USES_MEDIUM:
                continue
            fluid = comp_med.get(name, self.default_medium)
            if fluid is None:
                msgs.append(
                    f"component '{name}': cannot tell which fluid it carries; give it medium=... "
                    f"or give the plant a default medium"
                )
                continue
            try:
                comp.medium = get_medium(fluid)
            except Exception as err:  # unknown fluid name
                msgs.append(f"component '{name}': medium '{fluid}': {err}")
                continue
            comp.medium_name = fluid
        self._node_media = {}
        for node in self.node_names():
            fluid = node_med.get(node, (self.default_medium, None))[0]
            if fluid is not None:
                try:
                    self._node_media[node] = get_medium(fluid)
                except Exception:
                    pass
        if report is not None:
            report.errors.extend(msgs)
        elif msgs:
            raise PlantError("\n".join(msgs))

    # ------------------------------------------------------------- checking
    def check(self) -> StructureReport:
        """Structural checks before any numerics. Never raises for a bad plant;
        the problems are listed in the report (``report.raise_if_errors()``)."""
        from dnasim.structure import analyse

        report = StructureReport()
        analyse(self, report)
        return report

    # ------------------------------------------------------------- assembly
    def assemble(self):
        """Check, resolve media and build the ``AssembledDAE`` (raises ``PlantError``)."""
        from dnasim.assembly import AssembledDAE

        if self._dae is None:
            report = self.check()
            report.raise_if_errors()
            self._resolve_media()
            self._dae = AssembledDAE(self)
        return self._dae

    def initial_values(self, t0: float = 0.0, start: str = "steady"):
        """Consistent (y0, yp0) at t0: start="steady" or "given" (see dnasim.initialization)."""
        from dnasim.initial_guess import initial_guess
        from dnasim.initialization import solve_mixed

        if start not in ("steady", "given"):
            raise PlantError(f"start must be 'steady' or 'given', got {start!r}")
        dae = self.assemble()
        for comp in self.components.values():
            comp.reset_discrete_state()
        y = initial_guess(self, dae, t0)
        yp = np.zeros(dae.n)
        if start == "steady":
            unknown = ~dae.accumulator
        else:
            unknown = dae.algebraic.copy()
        for _ in range(3):
            y, yp = solve_mixed(
                dae, t0, y, yp, unknown, what=f"{start} start of plant '{self.name}'"
            )
            changed = False
            for b in dae.blocks:
                changed |= bool(b.comp.init_discrete_state(t0, b.local(y), b.local(yp)))
            if not changed:
                break
        return y, yp

    # ------------------------------------------------------------- outputs
    def output_names(self) -> list[str]:
        """Names of the rows produced by ``output_row`` ("pipe1.T_out", "a.p", ...)."""
        return self.assemble().output_names()

    def output_units(self) -> dict:
        return self.assemble().output_units()

    def output_row(self, t, y, yp) -> np.ndarray:
        """The named outputs at one point (t, y, y') of a solution, for CSV streaming."""
        return self.assemble().output_row(t, y, yp)

    # ------------------------------------------------------------- simulate
    def simulate(
        self,
        t_end: float,
        *,
        t0: float = 0.0,
        rtol: float = 1e-6,
        atol: float = 1e-6,
        max_order: int = 4,
        start: str = "steady",
        t_eval=None,
        callback=None,
        max_step: float = np.inf,
        h0: float | None = None,
        solver: str = "dnasim",
        initial=None,
        exclude_algebraic_from_error: bool = False,
    ):
        """Simulate from t0 to t_end and return ``PlantResults``.

        atol is relative to each variable's scale: atol_i = atol * max(nominal_i,
        |y0_i|) (see ``AssembledDAE.atol_vector``). start: "steady" (F(t0, y, 0) = 0)
        or "given" (the components' given initial states). ``initial``: an
        already consistent (y0, yp0) pair, e.g. from ``initial_values``.
        exclude_algebraic_from_error: leave the algebraic variables (flows, node
        enthalpies, volume states) out of the dnasim solver's error test. Near zero
        flow a face or valve flow is fixed by a pressure difference far below the
        pressures' own tolerance, so its error estimate can stop a run that the
        differential states would allow (measured: a valve closing fully ahead of a
        5-volume steam line, see the report of issue 7).
        solver: "dnasim" (``dnasim.solve_dae``) or "ida" (SUNDIALS IDA through
        scikit-sundae, for cross-checks). ``callback(t, y, yp)`` is passed to the
        solver; turn its arguments into a named row with ``output_row``.
        """
        from dnasim.results import PlantResults

        dae = self.assemble()
        if not t_end > t0:
            raise PlantError(f"t_end ({t_end}) must be greater than t0 ({t0})")
        t_start = time.perf_counter()
        if initial is None:
            y0, yp0 = self.initial_values(t0, start)
        else:
            y0, yp0 = (np.array(v, dtype=float) for v in initial)
        t_init = time.perf_counter() - t_start
        atol_vec = dae.atol_vector(atol, y0, yp0, t_end - t0)
        tstops = dae.tstops(t0, t_end)
        kwargs = dict(
            rtol=rtol,
            atol=atol_vec,
            max_order=max_order,
            max_step=max_step,
            h0=h0,
            events=dae.events,
            tstops=tstops,
            t_eval=t_eval,
            callback=callback,
        )
        t_start = time.perf_counter()
        if solver == "dnasim":
            from dnasim.solver import solve_dae

            try:
                res = solve_dae(
                    dae.residual,
                    (t0, t_end),
                    y0,
                    yp0,
                    algebraic=dae.algebraic,
                    jac_sparsity=dae.jac_sparsity,
                    calc_initial=False,
                    variable_names=dae.names,
                    equation_names=dae.eq_names,
                    exclude_algebraic_from_error=exclude_algebraic_from_error,
                    **kwargs,
                )
            except DAEError as err:
                res = getattr(err, "result", None)
                if res is None:
                    raise
        elif solver == "ida":
            from dnasim.testing.ida_plant import solve_with_ida

            res = solve_with_ida(dae, (t0, t_end), y0, yp0, **kwargs)
        else:
            raise PlantError(f"solver must be 'dnasim' or 'ida', got {solver!r}")
        wall = time.perf_counter() - t_start
        return PlantResults.from_dae_result(self, dae, res, wall_time=wall, init_time=t_init)
