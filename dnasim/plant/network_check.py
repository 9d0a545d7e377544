"""The network of a plant file, checked before anything is built: every port on a
node, every signal input linked to an output that exists, with the dimension the
input expects (one located message per problem)."""

from __future__ import annotations

from dnasim.core.errors import Problems
from dnasim.core.values import (
    suggest,
)
from dnasim.plant.component_info import input_unit
from dnasim.plant.spec import ComponentSpec


def _network(specs: list[ComponentSpec], errors: Problems, broken: dict | None = None) -> None:
    """Nodes with one port, signals from unknown components or outputs, signal
    dimensions. ``broken``: raw tables of components already reported as invalid;
    what follows only from their absence (their nodes, their outputs) is not
    reported again."""
    broken = broken or {}
    broken_nodes = set()
    for table in broken.values():
        ports = table.get("ports") if isinstance(table, dict) else None
        if isinstance(ports, dict):
            broken_nodes.update(n for n in ports.values() if isinstance(n, str))
    by_name = {c.name: c for c in specs}
    node_members: dict[str, list[tuple[str, str]]] = {}
    for c in specs:
        for port, node in c.ports.items():
            node_members.setdefault(node, []).append((c.name, port))
    for node, members in node_members.items():
        if node in by_name:
            c, port = members[0]
            errors.add(
                ("components", c, "ports"),
                port,
                f"name used twice: '{node}' is both a component and a node; "
                "give the node another name",
            )
        if len(members) == 1 and node not in broken_nodes:
            c, port = members[0]
            errors.add(
                ("components", c, "ports"),
                port,
                f"unconnected port: node '{node}' has only {c}.{port}; every node joins at least "
                "two ports (end a line with a boundary component)",
            )
    for c in specs:
        for inp, src in c.inputs.items():
            sub = ("components", c.name, "inputs")
            comp, out = src.split(".")
            other = by_name.get(comp)
            if other is None and comp in node_members:
                found = _signal_source(comp, out, None, True)
                if isinstance(found, str):
                    errors.add(sub, inp, found)
                    continue
                msg = _link_dimension_problem(c, inp, comp, out, found.unit)
                if msg:
                    errors.add(sub, inp, msg)
                continue
            if other is None:
                if comp not in broken and comp not in broken_nodes:
                    errors.add(
                        sub,
                        inp,
                        f"no component named '{comp}' (and no node) for the signal source "
                        f"'{src}', which must be a component's output or variable, or a "
                        "node's p, h or T"
                        f"{suggest(comp, list(by_name) + list(node_members))}",
                    )
                continue
            outs = other.signal_outputs
            if out in outs:
                msg = _link_dimension_problem(c, inp, other, out)
                if msg:
                    errors.add(sub, inp, msg)
                continue
            if other.instance is not None:
                found = _signal_source(comp, out, other.instance, False)
                if not isinstance(found, str):
                    msg = _link_dimension_problem(c, inp, comp, out, found.unit)
                    if msg:
                        errors.add(sub, inp, msg)
                    continue
                if out in other.fluid_ports:
                    found = (
                        f"'{src}' is a fluid port of {other.type}: a signal is a signal output, "
                        f"a variable, or a node's p, h or T (write the node's name, e.g. "
                        f"'<node>.p'); {found}"
                    )
                errors.add(sub, inp, found)
                continue
            if out in other.fluid_ports:
                errors.add(
                    sub,
                    inp,
                    f"'{src}' is a fluid port of {other.type}: a signal input must be linked "
                    f"to a signal output, a variable or a node's p, h or T (outputs of {comp}: "
                    f"{', '.join(outs) or 'none'})",
                )
            # otherwise: the source component's own parameters are in error (reported
            # with it); whether it has this variable cannot be told without it


def _signal_source(owner, ref, instance, is_node):
    from dnasim.plant.signals import resolve

    return resolve(owner, ref, instance, is_node)


def _port(ports, name):
    return next((q for q in ports or () if getattr(q, "name", None) == name), None)


def _link_dimension_problem(dest: ComponentSpec, inp: str, src, out: str, have: str | None = None):
    """Why the signal ``src.out`` cannot drive ``dest.inp`` (units of another dimension),
    or None. ``src`` is a ComponentSpec, or a node name with ``have`` its unit.
    Inputs with unit "*" take any signal."""
    from dnasim.plant.signals import dimension_problem

    q_in = _instance_port(dest, "signal_inputs", "SIGNAL_INPUTS", inp)
    if q_in is None:
        return None
    src_name = src if isinstance(src, str) else src.name
    if have is None:
        q_out = _instance_port(src, "signal_outputs", "SIGNAL_OUTPUTS", out)
        if q_out is None:
            return None
        have = str(getattr(q_out, "unit", "1") or "1")
        if src.instance is None and getattr(src.cls, "OUTPUT_UNIT_PARAM", None):
            # not built (its own parameters are in error): the output's unit is the
            # unit parameter's, not the class's placeholder
            from dnasim.core.values import output_unit_of

            have = output_unit_of(src.cls, src.params) or "*"
    return dimension_problem(
        f"{src_name}.{out}",
        have,
        inp,
        f"{dest.type} '{dest.name}'",
        input_unit(dest.cls, q_in),
        getattr(q_in, "doc", "") or "",
    )


def _instance_port(spec: ComponentSpec, method: str, attr: str, name: str):
    """The port ``name``: from the built instance when there is one (ports and their
    units may depend on parameters), else from the class."""
    inst = spec.instance
    if inst is not None and hasattr(inst, method):
        try:
            return _port(getattr(inst, method)(), name)
        except Exception:  # a plugin's port method failing: fall back to the class
            pass
    return _port(getattr(spec.cls, attr, ()), name)
