"""System: a compiled plant, one DAE F(t, y, y') = 0 over plant-wide arrays.

Made by ``dnasim.compilation.compiler.compile(plant)``; holds the components, the index maps,
the node and port media, the sparsity, the switch functions and the discrete
modes, and no reference back to the ``Plant``. What a solver needs:
``residual(t, y, yp)``, ``jac_sparsity``, ``algebraic``, ``events``,
``tstops(t0, t_end)``; what output needs: ``output_names()``,
``output_units()``, ``output_row(t, y, yp)``.

Pickling: a System pickles. The media pickle as their registry names
(``Medium.__reduce__``); the switch functions (``events``, closures over the
components) are not pickled but rebuilt from the components on unpickling.

Global vector y:
  * for each node (in connection order): p [Pa], h [J/kg] (names "node.p", "node.h");
    h is the mixed specific enthalpy of the fluid flowing INTO the node;
  * for each component (in the order added): its variables ("comp.var",
    vector elements "comp.var[i]").
Signal inputs are not variables: they alias the linked output variable.

Global equations F:
  * each component's equations, in the order it declares them (rows "comp.eq");
  * per node, the mass balance (rows "node.mass")

        sum_k n_k = 0                                            [kg/s]

    and the mixing equation (rows "node.mixing")

        sum_k w_k(n_k) (h_out_k - h_node) = 0                    [W]

    where n_k is the flow from component k INTO the node through port k (the
    port's flow variable, signed by its role: +1 for an outlet, -1 for an inlet),
    h_out_k the enthalpy component k delivers when fluid leaves it through that
    port (``FluidPort.h_out``), and w_k(m) = (m + sqrt(m^2 + eps_k^2))/2 the smooth
    upwind weight with the port's flow scale eps_k = ``FluidPort.m_eps``
    (``physics.upwind_weight``: w(m) - w(-m) = m, w(0) = eps/2 > 0); a port may
    narrow the band of w to ``FluidPort.band`` (a number, or the name of one of the
    component's variables: a control valve's band follows its opening,
    ``physics.opening_band``), the tail keeping the scale eps_k. Probes carry
    no flow and take no part. So h_node is the flow-weighted mean of the
    enthalpies flowing in; at zero flow it is the eps-weighted mean, and the
    Jacobian stays regular.

Energy conservation across a node is exact. Every component computes the energy
flow into itself at port k with ``physics.energy_in``:

    E_k = w_k(m_k) h_node - w_k(-m_k) h_out_k,    m_k = -n_k (flow into component k).

Summing over the ports of a node and using the mixing equation
(sum_k w_k(-m_k) h_out_k = h_node sum_k w_k(-m_k)) and the mass balance
(sum_k m_k = 0):

    sum_k E_k = h_node sum_k (w_k(m_k) - w_k(-m_k)) = h_node sum_k m_k = 0,

so the energy leaving one component through a node equals the energy entering
the others, to round-off, in forward, reverse and zero flow. The design
direction of a port is only the sign convention of its flow variable.

Evaluation: ``residual`` runs over ``residual_units`` (``evaluation_units``): each
component alone (``Component.residual`` on its ``LocalVector``), or the components of
a class that offers batches (``batch_key()``, ``batch(blocks)``: the library's
``Pipe``) with one key together, as one vectorised block over the plant-wide vectors
(``dnasim.library.pipe.PipeBatch``), and the components with scalar rows
(``Component.row_reads``: boundaries, valves, sensors, controllers, attemperators,
junctions) in one ``dnasim.model.evaluation.ScalarRows``: their values gathered through
index arrays made once, no name look-up per value, and each component's
``row_values``, where its equations are written (once: its ``Component.residual`` is
derived from the same function). Each unit gives every row the same number as the
component's own ``residual``, to the bit. The finite-difference
Jacobian's partial evaluations (``residual_for_columns``) batch the components a
column group touches the same way (the units of each set of blocks made once).

Output rows (``output_row``): y, the node temperatures, and the components' derived
outputs, alike pipes together (``PipeBatch.output_values``).

Sparsity: from the components' ``Equation`` declarations (``y`` and ``yp``
lists) and the node equations; ``pattern_y`` (dF/dy), ``pattern_yp`` (dF/dy')
and their union ``jac_sparsity``. A variable is differential when some
equation declares its derivative; the others are algebraic.

Tolerances: ``atol_vector(atol, y0)`` gives atol_i = atol * scale_i with
scale_i = max(declared nominal_i, |y0_i|): a relative tolerance on each
variable's own magnitude (p ~ 1e5 Pa gets 1e5 times the absolute tolerance of a
valve opening ~ 1), whatever the length of the run.

Quadratures: ``quadrature`` marks the variables X that are pure integrals of the
others, found from the sparsity: X' appears in exactly one equation and X in
none (dX/dt = f(t, other y, y'), X read by no equation): the accumulators
M_passed [kg], H_passed [J], Q_passed [J], W [J]. As SUNDIALS IDA's quadratures
with errconQ = false, the solver leaves them out of its error test and its Newton
convergence norm, and integrates them with the same
BDF formula (they stay in the Newton system, so linear invariants such as a
mass balance over a boundary's M_passed hold to round-off). A declared
accumulator that some equation reads (a P-only controller's bias m_I, held by
a steady start) is not a quadrature.
"""

from __future__ import annotations

import inspect

import numpy as np
import scipy.sparse as sp

from dnasim.compilation.limits import limit_event
from dnasim.core.errors import PlantError, ResidualDomainError
from dnasim.model.evaluation import ROWS_KEY, LocalVector, ScalarRows
from dnasim.model.physics import aside, upwind_weight

NODE_P_NOMINAL = 1e5  # Pa
NODE_H_NOMINAL = 1e5  # J/kg


class ComponentBlock:
    """A component's place in the global system."""

    def __init__(self, comp, gidx, index, eq_slice, local_names, modes):
        self.comp = comp
        self.modes = modes  # the System's dict of this component's discrete modes
        self.gidx = gidx  # local position -> global variable index
        self.index = index  # local name -> local position (int) or slice
        self.eq_slice = eq_slice
        self.local_names = local_names

    def local(self, v):
        return LocalVector(v[self.gidx], self.index, self.modes)


class PlantEvent:
    """A component switch function seen by the solver: g(t, y, yp) on global vectors.

    Attributes for the solver: ``name``, ``direction`` (scalar or array of
    ``size``), ``terminal``, ``restart`` (restart at order 1 without an action),
    ``size`` (1: g returns a float; n: an array of n values), ``names`` (one per
    entry, e.g. "evap.h_v[19] saturated liquid"), ``action``. ``variables``: the
    global indices of the variables the switch reads (its block's variables)."""

    def __init__(self, block: ComponentBlock, switch):
        self.block = block
        self.switch = switch
        self.component = block.comp.name
        self.name = f"{block.comp.name}.{switch.name}"
        self.direction = switch.direction
        self.terminal = bool(getattr(switch, "terminal", False))
        self.restart = bool(getattr(switch, "restart", False))
        self.kink = bool(getattr(switch, "kink", False))
        self.rearm = bool(getattr(switch, "rearm", False))
        self.size = int(getattr(switch, "size", 1) or 1)
        names = getattr(switch, "names", None)
        if self.size == 1:
            self.names = [self.name]
        else:
            names = names or [f"{switch.name}[{i}]" for i in range(self.size)]
            self.names = [f"{block.comp.name}.{nm}" for nm in names]
        self.variables = np.asarray(block.gidx, dtype=np.intp)
        # a vector switch's action(t, x, xp, which) is told the located entries; an
        # action(t, x, xp) acts on all of them itself
        action = getattr(switch, "action", None)
        self._action_takes_which = (
            self.size > 1 and action is not None and len(inspect.signature(action).parameters) >= 4
        )

    def __call__(self, t, y, yp):
        b = self.block
        v = self.switch.function(t, b.local(y), b.local(yp))
        if self.size == 1:
            return float(np.asarray(v, dtype=float).reshape(-1)[0])
        return np.asarray(v, dtype=float).reshape(self.size)

    def message(self, t):
        """The plain reason of a terminal switch (None when it has none)."""
        f = getattr(self.switch, "message", None)
        return f(t) if f is not None else None

    def action(self, t, y, yp, which=None):
        """Run the component's action; if it changed its variables (e.g. a
        controller resetting its integral), return the new (y, yp)."""
        if self.switch.action is None:
            return None
        b = self.block
        x, xp = b.local(y), b.local(yp)
        x0 = x.data.copy()
        if which is None or not self._action_takes_which:
            self.switch.action(t, x, xp)
        else:
            self.switch.action(t, x, xp, which)
        if np.array_equal(x.data, x0):
            return None
        y = np.array(y, dtype=float)
        y[b.gidx] = x.data
        return y, np.array(yp, dtype=float)


class System:
    """The plant as a DAE: residual, sparsity, masks, events, tstops, names.

    ``plant``: read while building, not kept (the compiler's copy: its components,
    ``dnasim.compilation.compiler.own_components``, become the System's own);
    ``node_media``: node name -> medium object (or None); ``port_media``: (component,
    port) -> medium object; ``sources``: (component, input) ->
    ``dnasim.plant.signals.Source`` of every link, resolved by the compiler
    (``link_sources``), with final units. Built once by
    ``dnasim.compilation.compiler.compile``.
    """

    def __init__(self, plant, node_media=None, port_media=None, sources=None):
        self.name = plant.name
        self.components = dict(plant.components)
        self.node_names = list(plant.node_names())
        self.connections = dict(plant.connections)  # (component, port) -> node
        self.links = dict(plant.links)  # (component, input) -> (component, output)
        self.node_media = dict(node_media or {})
        #: the plant's guesses of node states for the start (``PlantGraph.guess_node``)
        self.node_guesses = {
            n: dict(g)
            for n, g in getattr(plant, "node_guesses", {}).items()
            if n in self.node_names
        }
        self.port_media = dict(port_media or {})
        #: discrete modes, component name -> {key: value}; the components read and
        #: write them through ``LocalVector.modes`` (e.g. a controller's saturation)
        self.modes = {name: {} for name in self.components}
        if sources is None and plant.links:
            raise PlantError(
                f"plant '{plant.name}': a System is built by dnasim.compile(plant), which "
                "resolves the signal links (System(plant, ..., sources) needs them)"
            )
        self._build(plant, dict(sources or {}))

    # ------------------------------------------------------------------ build
    def _build(self, plant, sources):
        # each component learns the units of the signals linked to its inputs, so that
        # quantities in the unit of a measured signal (a controller's set point and
        # error) carry it into the results; the components are the System's own (the
        # compiler's copies), so this is written into no Plant
        for comp in plant.components.values():
            comp.input_units = {}
        for (dname, inp), src in sources.items():
            plant.components[dname].input_units[inp] = src.unit
        for comp in plant.components.values():  # "0.5 1/K" from Python, now that 1/K is known
            comp.resolve_signal_units(comp.input_units.values())
        names, units, nominal, owner, accumulator = [], [], [], [], []
        lower, upper = {}, {}  # global index -> declared min / max (Variable.min, .max)
        self.node_index = {}
        for node in plant.node_names():
            self.node_index[node] = len(names)
            names += [f"{node}.p", f"{node}.h"]
            units += ["Pa", "J/kg"]
            nominal += [NODE_P_NOMINAL, NODE_H_NOMINAL]
            owner += [node, node]
            accumulator += [False, False]
        self.n_node_vars = len(names)

        # own variables of each component
        own = {}
        for comp in plant.components.values():
            table = {}
            for var in comp.variables():
                for k in range(len(names), len(names) + (var.size or 1)):
                    if var.min is not None:
                        lower[k] = float(var.min)
                    if var.max is not None:
                        upper[k] = float(var.max)
                if var.size is None:
                    table[var.name] = len(names)
                    names.append(f"{comp.name}.{var.name}")
                    units.append(var.unit)
                    nominal.append(var.nominal)
                    owner.append(comp.name)
                    accumulator.append(var.accumulator)
                else:
                    start = len(names)
                    for i in range(var.size):
                        table[f"{var.name}[{i}]"] = len(names)
                        names.append(f"{comp.name}.{var.name}[{i}]")
                        units.append(var.unit)
                        nominal.append(var.nominal)
                        owner.append(comp.name)
                        accumulator.append(var.accumulator)
                    table[var.name] = slice(start, start + var.size)
            own[comp.name] = table

        # local layouts
        self.blocks = []
        eq_names, eq_owner, rows_y, rows_yp = [], [], [], []
        for comp in plant.components.values():
            gidx, index, local_names = [], {}, []

            def add_local(name, g, index=index, gidx=gidx, local_names=local_names):
                index[name] = len(gidx)
                gidx.append(g)
                local_names.append(name)

            for port in comp.fluid_ports():
                node = plant.connections[(comp.name, port.name)]
                k = self.node_index[node]
                add_local(f"{port.name}.p", k)
                add_local(f"{port.name}.h", k + 1)
            table = own[comp.name]
            for vname, g in table.items():
                if isinstance(g, slice):
                    continue
                add_local(vname, g)
            for vname, g in table.items():
                if isinstance(g, slice):
                    first = index[f"{vname}[0]"]
                    index[vname] = slice(first, first + (g.stop - g.start))
            for sig in comp.signal_inputs():
                src = sources[(comp.name, sig.name)]  # dnasim.plant.signals.Source
                if src.kind == "node":
                    add_local(sig.name, self.node_index[src.owner] + (src.ref == "h"))
                else:
                    add_local(sig.name, own[src.owner][src.variable])
            eqs = comp.equations()
            start = len(eq_names)
            for eq in eqs:
                for row, ys, yps in eq.rows():  # a vector equation: one row per element
                    eq_names.append(f"{comp.name}.{row}")
                    eq_owner.append(comp.name)
                    rows_y.append([gidx[_local(index, r, comp, row)] for r in ys])
                    rows_yp.append([gidx[_local(index, r, comp, row)] for r in yps])
            self.blocks.append(
                ComponentBlock(
                    comp,
                    np.array(gidx, dtype=np.intp),
                    index,
                    slice(start, len(eq_names)),
                    local_names,
                    self.modes[comp.name],
                )
            )

        # node mass balances and mixing equations
        self.node_eq_start = len(eq_names)
        node_names = plant.node_names()
        n_nodes = len(node_names)
        entries = []  # (node number, flow index, sign, h_out index, eps, band)
        eps_vars = []  # (entry number, index of the variable that holds the band)
        for j, node in enumerate(node_names):
            eq_names.append(f"{node}.mass")
            eq_owner.append(node)
            cols = []
            for comp_name, port in plant.ports_at(node):
                if port.role == "probe":
                    continue
                b = self.block(comp_name)
                g = b.gidx[b.index[port.flow]]
                try:
                    gh = b.gidx[b.index[port.h_out]]
                except KeyError:
                    raise PlantError(
                        f"component '{comp_name}' ({type(b.comp).__name__}): port '{port.name}' "
                        f"delivers h_out = {port.h_out!r}, which is not one of its variables or "
                        "port values"
                    ) from None
                sign = 1.0 if port.role == "outlet" else -1.0
                band = port.band
                if isinstance(band, str):  # a variable of the component (a valve's band)
                    eps_vars.append((len(entries), b.gidx[b.index[band]]))
                    band = np.nan
                elif band is None:
                    band = port.m_eps
                entries.append((j, g, sign, gh, float(port.m_eps), float(band)))
                cols.append(g)
            rows_y.append(cols)
            rows_yp.append([])
        for j, node in enumerate(node_names):
            eq_names.append(f"{node}.mixing")
            eq_owner.append(node)
            k = self.node_index[node]
            cols = [k + 1]
            for jj, g, _, gh, _, _ in entries:
                if jj == j:
                    cols += [g, gh]
            cols += [ge for e, ge in eps_vars if entries[e][0] == j]
            rows_y.append(cols)
            rows_yp.append([])
        n = len(names)
        e = np.array(entries, dtype=float).reshape(-1, 6)
        self._mix_node = e[:, 0].astype(np.intp)
        self._mix_flow = e[:, 1].astype(np.intp)
        self._mix_sign = e[:, 2]
        self._mix_hout = e[:, 3].astype(np.intp)
        self._mix_eps = e[:, 4]
        ev = np.array(eps_vars, dtype=np.intp).reshape(-1, 2)
        self._mix_eps_at, self._mix_eps_var = ev[:, 0], ev[:, 1]
        #: the ports' bands (``FluidPort.band``; nan where a variable holds it), or
        #: None when every band is its port's m_eps
        narrower = ~np.isnan(e[:, 5]) & (e[:, 5] != e[:, 4])
        self._mix_band = e[:, 5] if (narrower.any() or len(eps_vars)) else None
        self._node_h = np.array([self.node_index[nd] + 1 for nd in node_names], dtype=np.intp)
        self._mix_hnode = self._node_h[self._mix_node]
        self.n_nodes = n_nodes
        self.node_matrix = sp.csr_matrix(
            (self._mix_sign, (self._mix_node, self._mix_flow)), shape=(n_nodes, n)
        )

        self.n = n
        self.n_equations = len(eq_names)
        self.names = names
        self.index = {nm: i for i, nm in enumerate(names)}
        self.units = dict(zip(names, units, strict=False))
        self.nominal = np.array(nominal, dtype=float)
        self.var_owner = owner
        self.accumulator = np.array(accumulator, dtype=bool)
        #: declared ranges per variable (-inf, inf where none): ``dnasim.compilation.limits``
        self.lower = np.full(n, -np.inf)
        self.upper = np.full(n, np.inf)
        self.lower[list(lower)] = list(lower.values())
        self.upper[list(upper)] = list(upper.values())
        self.eq_names = eq_names
        self.eq_owner = eq_owner
        self.rows_y = rows_y
        self.rows_yp = rows_yp
        self.pattern_y = _pattern(rows_y, self.n_equations, n)
        self.pattern_yp = _pattern(rows_yp, self.n_equations, n)
        self.differential = np.asarray(self.pattern_yp.sum(axis=0)).ravel() > 0
        self.algebraic = ~self.differential
        self.quadrature = quadratures(self.pattern_y, self.pattern_yp)
        self._checked_lengths = False
        #: what ``residual`` evaluates: the blocks, with alike components in batches
        self.residual_units = evaluation_units(self.blocks)

        self.events = self._make_events()

    def _make_events(self):
        """The components' switches, and the plant's general limits (declared ranges,
        node states within their media's ranges: ``dnasim.compilation.limits``) as the last one."""
        events = [PlantEvent(b, sw) for b in self.blocks for sw in b.comp.switches()]
        limits = limit_event(self, self._node_groups())
        return events + ([limits] if limits is not None else [])

    def __getstate__(self):
        state = dict(self.__dict__)
        state.pop("events", None)  # closures over the components: rebuilt on unpickling
        state.pop("_units_cache", None)  # made again on use
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self.events = self._make_events()

    def reset_modes(self) -> None:
        """Every component's discrete modes back to their start (``Component.reset_modes``)."""
        for b in self.blocks:
            self.modes[b.comp.name].clear()
            b.comp.reset_discrete_state(self.modes[b.comp.name])

    def warnings(self) -> list[str]:
        """The components' warnings of the last start and run, in plain words: the
        texts they put in their modes under "warnings" (a pump with cavitation =
        "warn" when NPSH_a falls below NPSH_r, ``dnasim.library.pump``)."""
        return [w for b in self.blocks for w in self.modes[b.comp.name].get("warnings", ())]

    def block(self, comp_name) -> ComponentBlock:
        for b in self.blocks:
            if b.comp.name == comp_name:
                return b
        raise KeyError(comp_name)

    # --------------------------------------------------------------- numerics
    @property
    def jac_sparsity(self):
        """Union of the dF/dy and dF/dy' patterns (scipy.sparse CSR, 0/1)."""
        if self.n != self.n_equations:
            raise PlantError(f"{self.n_equations} equations for {self.n} unknowns")
        pat = (self.pattern_y + self.pattern_yp).tocsr()
        pat.data[:] = 1.0
        return pat

    def residual(self, t, y, yp):
        """F(t, y, y') for the whole plant (length n)."""
        F = np.empty(self.n_equations)
        self._component_rows(t, y, yp, F, self.residual_units)
        self._node_rows(y, F)
        self._checked_lengths = True
        self._check_finite(t, F)
        return F

    def residual_aside(self, t, y, yp):
        """``residual`` leaving no trace in the property memos (``physics.aside``): for
        evaluations outside the integration's own path, the re-solve of an output point
        between steps (``solve_dae``'s ``output_residual``), so that the output asked
        for does not change the steps taken."""
        with aside():
            return self.residual(t, y, yp)

    def residual_for_columns_aside(self, cols):
        """``residual_for_columns(cols)`` leaving no trace in the property memos (see
        ``residual_aside``)."""
        F_cols = self.residual_for_columns(cols)

        def F_cols_aside(t, y, yp, f0):
            with aside():
                return F_cols(t, y, yp, f0)

        return F_cols_aside

    def residual_for_columns(self, cols):
        """F_cols(t, y, y', f0) -> F(t, y, y') at a point that differs only in y[cols] and
        y'[cols] from the point where F is f0: the rows that read none of ``cols`` are
        taken from f0, the others are evaluated again (the components with one of
        ``cols`` among their variables, port values or signal inputs, and the node
        equations when a flow, a delivered enthalpy or a node enthalpy is among them).

        Used by the finite-difference Jacobian (``dnasim.solver.linear_algebra``): a
        column group perturbs a few columns, and the rows the Jacobian keeps from
        F(y + d) - f0 are exactly the rows of the sparsity pattern in those columns,
        which are all evaluated again, with the same inputs as in a whole-plant
        evaluation, so the matrix is the same to the bit. Each component is evaluated
        as a whole (its ``prepare`` included), never in part."""
        touched = np.zeros(self.n, dtype=bool)
        touched[np.asarray(cols, dtype=np.intp)] = True
        which = tuple(k for k, b in enumerate(self.blocks) if touched[b.gidx].any())
        # the units of a set of blocks, made once: a Jacobian's column groups touch the
        # same few sets (each pipe is in most groups), and every start, tstop and event
        # builds its iteration matrix anew (superheater_line.toml: 3 x 12 groups, 10 ms
        # of batches each set)
        cache = self.__dict__.setdefault("_units_cache", {})
        blocks = cache.get(which)
        if blocks is None:
            blocks = cache[which] = evaluation_units([self.blocks[k] for k in which])
        node_cols = np.concatenate(
            (self._mix_flow, self._mix_hout, self._node_h, self._mix_eps_var)
        )
        nodes = bool(touched[node_cols].any())

        def F_cols(t, y, yp, f0):
            F = np.array(f0, dtype=float)
            self._component_rows(t, y, yp, F, blocks)
            if nodes:
                self._node_rows(y, F)
            self._check_finite(t, F)
            return F

        return F_cols

    def _component_rows(self, t, y, yp, F, units) -> None:
        """F[rows of each unit] = its residual: a block's component alone
        (``Component.residual``), a batch of alike components as one
        (``batch.residual_into``, see ``evaluation_units``)."""
        for b in units:
            try:
                if type(b) is not ComponentBlock:
                    b.residual_into(t, y, yp, F)
                    continue
                r = b.comp.residual(
                    t,
                    LocalVector(y[b.gidx], b.index, b.modes),
                    LocalVector(yp[b.gidx], b.index, b.modes),
                )
            except ResidualDomainError as exc:
                _name_the_component(exc, b, t)
                raise
            if not self._checked_lengths:
                nr = np.size(r)
                ne = b.eq_slice.stop - b.eq_slice.start
                if nr != ne:
                    raise PlantError(
                        f"component '{b.comp.name}' ({type(b.comp).__name__}) returned {nr} "
                        "residuals "
                        f"but declares {ne} equations"
                    )
            F[b.eq_slice] = r

    def _node_rows(self, y, F) -> None:
        """F[node rows]: the mass balances sum_k n_k (the rows of ``node_matrix``,
        without the sparse-product call overhead) and the mixing equations."""
        inflow = self._mix_sign * y[self._mix_flow]
        start = self.node_eq_start
        F[start : start + self.n_nodes] = np.bincount(
            self._mix_node, weights=inflow, minlength=self.n_nodes
        )
        F[start + self.n_nodes :] = self.node_mixing(y, inflow)

    def _check_finite(self, t, F) -> None:
        # a sum is finite only when every term is (nan and inf propagate); a finite F
        # whose sum overflows is looked at element by element
        if not np.isfinite(F.sum()) and not np.isfinite(F).all():
            bad = np.flatnonzero(~np.isfinite(F))[:3]
            raise ResidualDomainError(
                "residual not finite in "
                + ", ".join(self.eq_names[i] for i in bad)
                + f" at t = {t:g}"
            )

    def node_mixing(self, y, inflow=None) -> np.ndarray:
        """Residuals of the nodes' mixing equations [W] (see the module docstring);
        ``inflow``: the port flows into the nodes, sign * y[flow], when known."""
        if inflow is None:
            inflow = self._mix_sign * y[self._mix_flow]
        if self._mix_band is None:
            w = upwind_weight(inflow, self._mix_eps)
        else:  # narrower bands (valves: by their opening), some held by variables
            band = self._mix_band
            if self._mix_eps_var.size:
                band = band.copy()
                band[self._mix_eps_at] = y[self._mix_eps_var]
            w = upwind_weight(inflow, self._mix_eps, band)
        terms = w * (y[self._mix_hout] - y[self._mix_hnode])
        return np.bincount(self._mix_node, weights=terms, minlength=self.n_nodes)

    def atol_vector(self, atol: float, y0) -> np.ndarray:
        """atol_i = atol * max(nominal_i, |y0_i|), the same for a run of any length.

        An accumulator (a running integral such as M_passed [kg], H_passed [J],
        Q_passed [J], which starts at 0) gets atol times its declared nominal value
        like any variable; what keeps it from setting the step size is that it is a
        quadrature (``quadrature``: out of the error test and Newton's norm). Before,
        its atol was atol |y0'| t_span (what it holds at the end of the run), so a
        short run tested it far tighter than a long one: rankine.toml with t_end =
        0.5 s took 2196 steps against 141 to 0.5 s of its 4000 s run."""
        y0 = np.abs(np.asarray(y0, dtype=float))
        return atol * np.maximum(self.nominal, y0)

    def tstops(self, t0: float, t_end: float) -> list[float]:
        """Breakpoints of all time-function parameters inside (t0, t_end)."""
        out = set()
        for comp in self.components.values():
            for b in comp.breakpoints():
                if t0 < b < t_end:
                    out.add(float(b))
        return sorted(out)

    # ---------------------------------------------------------------- outputs
    def output_names(self) -> list[str]:
        """Names of one output row: every variable, node temperatures, derived outputs."""
        if not hasattr(self, "_output_names"):
            names = list(self.names)
            units = dict(self.units)
            for node in self.node_names:
                names.append(f"{node}.T")
                units[f"{node}.T"] = "K"
            for b in self.blocks:
                for o in b.comp.outputs():
                    nm = f"{b.comp.name}.{o.name}"
                    names.append(nm)
                    units[nm] = o.unit
            self._output_names, self._output_units = names, units
        return list(self._output_names)

    def output_units(self) -> dict:
        self.output_names()
        return dict(self._output_units)

    def _node_groups(self):
        groups = self.__dict__.get("_node_groups_cache")
        if groups is None:
            groups = _group_nodes(self.node_names, self.node_index, self.node_media)
            self._node_groups_cache = groups
        return groups

    def output_row(self, t, y, yp) -> np.ndarray:
        """One output row (order of ``output_names()``) from (t, y, y'). Its property
        calls leave the residual's memos as they were (``physics.aside``): the rows
        asked for do not move the integration."""
        with aside():
            return self._output_row(t, y, yp)

    def _output_row(self, t, y, yp) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        node_T = np.full(len(self.node_names), np.nan)
        for medium, pos, kp in self._node_groups():
            # one property call per medium for all its nodes; nan where out of range
            r = medium.states(y[kp], y[kp + 1], check=False)
            node_T[pos] = np.where(r.ok, r.T, np.nan)
        plan = self.__dict__.get("_output_plan")
        if plan is None:
            plan = self._output_plan = self._make_output_plan()
        units, size = plan
        out = np.empty(size)
        out[: self.n] = y
        out[self.n : self.n + node_T.size] = node_T
        for unit, where in units:
            if type(unit) is ComponentBlock:
                out[where] = unit.comp.output_values(t, unit.local(y), unit.local(yp))
            else:
                out[where] = unit.output_values(t, y, yp)
        return out

    def _make_output_plan(self):
        """([(unit, positions in the row)], row length): the blocks with derived
        outputs, with alike pipes in one batch (``evaluation_units``) when the batch
        offers ``output_values`` (its components' values, one after the other), and
        where each unit's values go (a slice for a block, an index array for a batch)."""
        start = self.n + len(self.node_names)
        where, out_blocks = {}, []
        for b in self.blocks:
            k = len(b.comp.outputs())
            if k:
                out_blocks.append(b)
                where[b.comp.name] = slice(start, start + k)
                start += k
        units = []
        for u in evaluation_units(out_blocks):
            if type(u) is ComponentBlock:
                units.append((u, where[u.comp.name]))
            elif not hasattr(u, "output_values"):
                units += [(b, where[b.comp.name]) for b in u.blocks]
            else:
                pos = [
                    np.arange(where[b.comp.name].start, where[b.comp.name].stop) for b in u.blocks
                ]
                units.append((u, np.concatenate(pos)))
        return units, start


def _name_the_component(exc: ResidualDomainError, unit, t) -> None:
    """Prefix the message of a state outside a model's domain (a ``PropertyError``
    naming the fluid, p, h and the limit) with the component(s) whose residual met it
    and the time, once; the exception keeps its type and attributes."""
    if getattr(exc, "component", None) is not None:
        return
    if type(unit) is ComponentBlock or len(unit.blocks) == 1:
        comp = unit.comp if type(unit) is ComponentBlock else unit.blocks[0].comp
        where = f"component '{comp.name}' ({type(comp).__name__})"
        exc.component = comp.name
    else:
        names = [b.comp.name for b in unit.blocks]
        shown = ", ".join(f"'{n}'" for n in names[:6]) + (", ..." if len(names) > 6 else "")
        where = f"one of the components {shown} ({type(unit.blocks[0].comp).__name__})"
        exc.component = names
    exc.args = (f"{where} at t = {t:.10g} s: {exc}",) + tuple(exc.args[1:])


def evaluation_units(blocks) -> list:
    """``blocks`` with alike components joined into batches: the blocks of components of
    one class whose ``batch_key()`` is equal and not None become one unit,
    ``type(component).batch(blocks)`` (e.g. ``dnasim.library.pipe.PipeBatch``), with
    ``residual_into(t, y, yp, F)`` writing all their rows at once; the others stay
    ``ComponentBlock``s, evaluated alone. A batch gives each row the value its
    component's own ``residual`` gives, so which components are batched together (all
    pipes of a plant, or the few of a Jacobian column group) changes no number."""
    groups: dict = {}
    order: list = []
    for b in blocks:
        key_of = getattr(b.comp, "batch_key", None)
        key = key_of() if key_of is not None else None
        if key is None:
            order.append(b)
            continue
        # the components with scalar rows (``ScalarRows``) in one unit, whatever their class
        group_key = key if key == ROWS_KEY else (type(b.comp), key)
        group = groups.get(group_key)
        if group is None:
            group = groups[group_key] = []
            order.append(group)
        group.append(b)
    units = []
    for u in order:
        if type(u) is not list:
            units.append(u)
        elif u[0].comp.batch_key() == ROWS_KEY:
            units.append(ScalarRows(u))
        else:
            units.append(type(u[0].comp).batch(u))
    return units


def _group_nodes(node_names, node_index, node_media):
    """[(medium, positions in node_names, indices of the nodes' p in y)] per medium."""
    groups = {}
    for j, node in enumerate(node_names):
        medium = node_media.get(node)
        if medium is not None:
            groups.setdefault(id(medium), (medium, [], []))
            groups[id(medium)][1].append(j)
            groups[id(medium)][2].append(node_index[node])
    return [
        (m, np.array(pos, dtype=np.intp), np.array(kp, dtype=np.intp))
        for m, pos, kp in groups.values()
    ]


def _local(index, ref, comp, row):
    """Local position of ``ref`` in equation row ``row`` (its name) of ``comp``."""
    try:
        k = index[ref]
    except KeyError:
        raise PlantError(
            f"component '{comp.name}' ({type(comp).__name__}): equation '{row}' refers to "
            f"'{ref}', which is not one of its variables or port values"
        ) from None
    if isinstance(k, slice):
        raise PlantError(
            f"component '{comp.name}': equation '{row}' refers to the whole vector '{ref}'; "
            "name elements"
        )
    return k


def quadratures(pattern_y, pattern_yp) -> np.ndarray:
    """Mask of the quadrature variables: column j of dF/dy' has one entry and column j
    of dF/dy none, so y_j' = f(t, other y, y') is set by one equation and y_j is read by
    none (it feeds nothing back)."""
    in_y = np.diff(sp.csc_matrix(pattern_y).indptr) > 0
    n_yp = np.diff(sp.csc_matrix(pattern_yp).indptr)
    return (n_yp == 1) & ~in_y


def _pattern(rows, n_rows, n_cols):
    r, c = [], []
    for i, cols in enumerate(rows):
        r.extend([i] * len(cols))
        c.extend(cols)
    m = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(n_rows, n_cols))
    m.sum_duplicates()
    m.data[:] = 1.0
    return m
