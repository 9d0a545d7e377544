"""``plant.json``: the plant's graph beside its results, for plots and reports.

A run writes it next to ``results.csv`` (:func:`write_plant_json`), so that
``dnasim plot DIR/results.csv`` knows, without the plant file, what the run's
report knows: the plant's name and description (the plots' title), its
components with their types and fluid ports, its nodes, its signal links with
the results column that holds each signal (a controller's measured value:
``"drum.level"``, ``"sensor.T_s"``, ``"n_hdr.p"``), and its controllers.

The description is plain JSON data (:func:`describe_plant`)::

    {"format": "dnasim plant.json 1", "name": "rankine", "description": "...",
     "file": "plants/rankine.toml",
     "components": [{"name": "pump", "type": "Pump",
                     "ports": [{"port": "inlet", "node": "n_hotwell", "role": "inlet"}, ...],
                     "inputs": [{"input": "z", "source": "level_pi.z", "column": "level_pi.z"}],
                     "supply": null}, ...],
     "nodes": ["n_hotwell", ...], "media": {"n_hotwell": "Water", "g_in": "FlueGas", ...},
     "links": [{"source": "level_pi.z", "target": "feed_valve.z", "column": "level_pi.z"}],
     "controllers": [{"name": "level_pi", "measured": "drum.level",
                      "setpoint": "level_pi.setpoint", "output": "level_pi.z",
                      "error": "level_pi.e"}]}

``role`` is the port's role ("inlet", "outlet", "probe"); a boundary's one port
is its "outlet" (its flow ``m`` is positive into the plant) and ``supply`` says
whether it gives the state of the fluid it lets in (a source) or not (a sink);
other components have ``supply`` null. ``column`` is null when no results column
holds the signal (a signal output without a variable).

Reading is forgiving (:func:`read_plant_json`): a missing or unreadable file gives
None, and the plots fall back to what the CSV alone tells.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = [
    "FORMAT",
    "PLANT_JSON",
    "describe_plant",
    "describe_loaded",
    "write_plant_json",
    "read_plant_json",
]

FORMAT = "dnasim plant.json 1"
PLANT_JSON = "plant.json"


def _column(plant, owner: str, ref: str, names) -> str | None:
    """The results column holding the signal ``owner.ref`` (None when none does)."""
    from dnasim.plant.signals import resolve

    comp = plant.components.get(owner)
    nodes = set(plant.node_names())
    found = resolve(owner, ref, comp, owner in nodes)
    if found is None or isinstance(found, str):
        return None
    col = f"{owner}.{found.ref if found.kind == 'node' else found.variable}"
    if found.kind != "node" and not found.variable:
        return None
    if names is not None and col not in names:
        return None
    return col


def describe_plant(
    plant, names=None, *, description: str = "", file=None, media: dict | None = None
) -> dict:
    """The JSON description of ``plant`` (a ``PlantGraph``; see the module docstring).

    ``names``: the results columns (``System.output_names()``); a signal whose
    column is not among them gets ``column`` null. ``description`` and ``file``:
    the plant file's ``[plant] description`` and path. ``media``: node -> medium
    (a name or an object with ``name``; ``System.node_media``), written as
    ``"media": {node: name}``."""
    names = None if names is None else set(names)
    comps = []
    for name, comp in plant.components.items():
        roles = {p.name: p.role for p in comp.fluid_ports()}
        ports = [
            {"port": p, "node": node, "role": roles.get(p, "inlet")}
            for (c, p), node in plant.connections.items()
            if c == name
        ]
        inputs = []
        for (c, inp), (s, o) in plant.links.items():
            if c == name:
                inputs.append(
                    {"input": inp, "source": f"{s}.{o}", "column": _column(plant, s, o, names)}
                )
        supply = getattr(comp, "has_supply", None)
        comps.append(
            {
                "name": name,
                "type": type(comp).__name__,
                "ports": ports,
                "inputs": inputs,
                "supply": None if supply is None else bool(supply),
            }
        )
    links = [
        {"source": f"{s}.{o}", "target": f"{c}.{i}", "column": _column(plant, s, o, names)}
        for (c, i), (s, o) in plant.links.items()
    ]
    controllers = []
    for c in comps:
        measured = next((i for i in c["inputs"] if i["input"] == "measured"), None)
        if measured is None:
            continue

        def col(leaf, cname=c["name"]):
            n = f"{cname}.{leaf}"
            return n if names is None or n in names else None

        controllers.append(
            {
                "name": c["name"],
                "measured": measured["column"],
                "measured_source": measured["source"],
                "setpoint": col("setpoint"),
                "output": col("z"),
                "error": col("e"),
            }
        )
    return {
        "format": FORMAT,
        "name": str(plant.name),
        "description": str(description or ""),
        "file": None if file is None else str(file),
        "components": comps,
        "nodes": list(plant.node_names()),
        "media": {
            str(n): str(getattr(m, "name", m)) for n, m in (media or {}).items() if m is not None
        },
        "links": links,
        "controllers": controllers,
    }


def describe_loaded(loaded, system=None) -> dict:
    """:func:`describe_plant` of a ``LoadedPlant`` (or a plant), with the plant
    file's description and path; ``system``: the compiled plant (its output names
    and node media), or None."""
    plant = getattr(loaded, "plant", loaded)
    names = None if system is None else system.output_names()
    media = None if system is None else getattr(system, "node_media", None)
    spec = getattr(loaded, "spec", None)
    description = getattr(spec, "description", "") or ""
    return describe_plant(
        plant,
        names,
        description=description if isinstance(description, str) else "",
        file=getattr(loaded, "path", None),
        media=media,
    )


def write_plant_json(out_dir, desc: dict) -> Path:
    """Write ``desc`` to ``out_dir/plant.json`` (atomically); returns the path."""
    from dnasim.run.output import _atomic_write

    text = (json.dumps(desc, indent=1, ensure_ascii=False) + "\n").encode("utf-8")
    return _atomic_write(Path(out_dir) / PLANT_JSON, lambda f: f.write(text))


def read_plant_json(out_dir) -> dict | None:
    """The description in ``out_dir/plant.json``, or None (missing, unreadable, or
    not a dnasim plant.json)."""
    try:
        desc = json.loads((Path(out_dir) / PLANT_JSON).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(desc, dict) or desc.get("format") != FORMAT:
        return None
    return desc
