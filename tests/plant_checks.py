"""Helpers for the plant field tests: running plant files, closing balances."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from dnasim.library import HeatExchanger, MassFlowBoundary, Pipe, PressureBoundary
from dnasim.plant.plantfile import load, loads, simulate_plant

PLANTS = Path(__file__).resolve().parent / "plants"


def run_file(name: str, replace: dict | None = None, **overrides):
    """Load tests/plants/<name> (optionally with text replacements), simulate it with
    its own [simulation] settings; returns (plant, results)."""
    path = PLANTS / name
    text = path.read_text()
    for old, new in (replace or {}).items():
        assert old in text, f"{old!r} not in {name}"
        text = text.replace(old, new)
    loaded = loads(text, str(path)) if replace else load(path)
    return loaded.plant, simulate_plant(loaded.plant, loaded.simulation, **overrides)


def stored(plant, res):
    """Mass [kg] and energy [J] stored in the plant over t: every component's fluid
    masses M and internal energies U (Pipe, HeatExchanger sides, Attemperator) and
    wall energies C T_w (Pipe E_wall, HeatExchanger C_wall/n sum T_w)."""
    pat_M = re.compile(r"^(hot_|cold_)?M(\[\d+\])?$")
    pat_U = re.compile(r"^(hot_|cold_)?U(\[\d+\])?$")
    M = np.zeros_like(res.t)
    E = np.zeros_like(res.t)
    for name in res.variable_names:
        comp, _, local = name.partition(".")
        if pat_M.match(local):
            M = M + res[name]
        elif pat_U.match(local):
            E = E + res[name]
    for c in plant.components.values():
        if isinstance(c, Pipe):
            E = E + res[f"{c.name}.E_wall"]
        elif isinstance(c, HeatExchanger) and c.wall_parts:  # from geometry: m e(T_w)
            E = E + res[f"{c.name}.E_wall"]
        elif isinstance(c, HeatExchanger):
            C_i = c.params["C_wall"] / c.n
            E = E + C_i * sum(res[f"{c.name}.T_w[{i}]"] for i in range(c.n))
    return M, E


def balances(plant, res):
    """Mass and energy balance errors over the run and the throughputs.

    Stored: ``stored()``. Passed (positive into the plant): the boundaries'
    M_passed and H_passed, minus the heat to fixed walls and condensers (Q_passed),
    plus the shaft work of pumps, minus that of turbines (W). Throughput:
    the total variation of the boundaries' running integrals (mass [kg], energy
    [J]) plus that of the heat to fixed walls."""
    bounds = [
        c.name
        for c in plant.components.values()
        if isinstance(c, (PressureBoundary, MassFlowBoundary))
    ]
    M, E = stored(plant, res)
    M_in = sum(res[f"{b}.M_passed"] for b in bounds)
    H_in = sum(res[f"{b}.H_passed"] for b in bounds)
    # heat leaving the fluid [J]: fixed walls, walls with an outer boundary, a
    # condenser's cooling, heated vessels (Drum, FeedwaterTank: -integral of the heat)
    fixed = [c for c in plant.components if f"{c}.Q_passed" in res]
    Q_out = sum((res[f"{p}.Q_passed"] for p in fixed), np.zeros_like(res.t))
    # shaft work of fluid machines [J]: into the fluid (Pump), out of it (SteamTurbine)
    sign = {"Pump": 1.0, "SteamTurbine": -1.0}
    machines = [c for c in plant.components.values() if type(c).__name__ in sign]
    W_in = sum(
        (sign[type(c).__name__] * res[f"{c.name}.W"] for c in machines), np.zeros_like(res.t)
    )
    err_M = np.max(np.abs((M - M[0]) - (M_in - M_in[0])))
    err_E = np.max(np.abs((E - E[0]) - (H_in - H_in[0]) + (Q_out - Q_out[0]) - (W_in - W_in[0])))
    thr_M = sum(np.sum(np.abs(np.diff(res[f"{b}.M_passed"]))) for b in bounds)
    thr_E = sum(np.sum(np.abs(np.diff(res[f"{b}.H_passed"]))) for b in bounds)
    thr_E += sum(np.sum(np.abs(np.diff(res[f"{p}.Q_passed"]))) for p in fixed)
    thr_E += sum(np.sum(np.abs(np.diff(res[f"{c.name}.W"]))) for c in machines)
    return err_M, thr_M, err_E, thr_E


def node_temperatures(plant, res):
    """All fluid temperatures [K]: every node and every pipe volume, over t."""
    out = [res[f"{n}.T"] for n in plant.node_names()]
    for c in plant.components.values():
        if isinstance(c, Pipe):
            out += [res[f"{c.name}.T[{i}]"] for i in range(c.n)]
    return np.array(out)
