"""plants/drum_unit.toml: its full-load steady state against the hand heat balance of
tests/test_drum_unit.py (CoolProp's IF97), and the CPU time of the whole 100 -> 50 ->
100 % scenario against the simulated time.

    python benchmarks/drum_unit.py [--repeat N]

CPU seconds are time.process_time() of ``simulate_plant`` alone (the steady start
and the run; imports and the plant file's loading are not counted)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from test_drum_unit import (  # noqa: E402
    PLANT,
    design_balance,
    hand_balance,
    operating_points,
    simulated,
)

from dnasim.plant.plantfile import load, simulate_plant  # noqa: E402

#: (label, result, factor, unit, set point): the controlled quantities
CONTROLLED = [
    ("drum pressure", "drum.p", 1e-5, "bar", 140.0),
    ("drum level", "drum.level", 1.0, "m", 2.5),
    ("live steam T (n_ms)", "n_ms.T", 1.0, "K", 813.15),
    ("hot reheat T (n_hrh)", "n_hrh.T", 1.0, "K", 795.15),
    ("  reheater outlet (n_rho, free)", "n_rho.T", 1.0, "K", float("nan")),
    ("  reheat spray flow", "rh_spray_valve.m", 1.0, "kg/s", float("nan")),
    ("deaerator pressure (5.5 / 5.3)", "deaerator.p", 1e-5, "bar", 5.5),
    ("deaerator level", "deaerator.level", 1.0, "m", 2.5),
    ("hotwell level", "condenser.level", 1.0, "m", 1.0),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    runs = []
    for _ in range(args.repeat):
        loaded = load(PLANT)
        t0 = time.process_time()
        res = simulate_plant(loaded.plant, loaded.simulation)
        runs.append((time.process_time() - t0, res))
    cpu = [c for c, _ in runs]
    res = runs[-1][1]
    hand = hand_balance(operating_points(res))
    sim = simulated(res)
    design = design_balance()
    units = {"m": ("kg/s", 1.0), "P": ("MW", 1e-6), "n": ("MW", 1e-6), "Q": ("MW", 1e-6),
             "e": ("-", 1.0), "T": ("K", 1.0)}  # fmt: skip
    print("full load, steady start: simulation against the hand heat balance (IF97)")
    print(f"{'quantity':<10} {'unit':>5} {'simulated':>12} {'hand':>12} {'rel. diff':>10} "
          f"{'design':>10}")  # fmt: skip
    for key in ("m_steam", "m_feed", "m_spray", "m_rh_spray", "m_hph", "m_hph2", "m_da", "m_cond",
                "m_lph", "m_lph2", "P_hp", "P_ip", "P_lp", "P_pumps", "net", "eta",
                "T_rho"):  # fmt: skip
        unit, f = units[key[0]]
        s, h = sim[key], hand[key]
        d = design.get(key)
        dtxt = f"{d * f:10.4f}" if d is not None else f"{'':>10}"
        print(f"{key:<10} {unit:>5} {s * f:12.5f} {h * f:12.5f} {s / h - 1:10.2e} {dtxt}")
    print(f"{'Q_in':<10} {'MW':>5} {hand['Q_in'] * 1e-6:12.5f} {'(given)':>12} {'':>10} "
          f"{design['Q_in'] * 1e-6:10.4f}")  # fmt: skip
    print()
    print("controls through the load change (min and max over the whole 3300 s)")
    print(f"{'quantity':<34} {'unit':>5} {'set point':>10} {'min':>10} {'max':>10}")
    t = res.t
    half = (t > 1400) & (t < 1800)
    for label, x, f, unit, w in CONTROLLED:
        y = res[x] * f
        print(f"{label:<34} {unit:>5} {w:10.3f} {y.min():10.3f} {y.max():10.3f}")
        if x == "deaerator.p":
            print(f"{'  at 50 %, 1400-1800 s':<34} {unit:>5} {5.3:10.3f} {y[half].min():10.3f} "
                  f"{y[half].max():10.3f}")  # fmt: skip
    st = res.stats
    t_end = float(res.t[-1])
    print()
    print("whole scenario (simulate_plant: steady start and run)")
    print(f"{'t_end [s]':>10} {'CPU [s]':>9} {'CPU/real':>9} {'steps':>6} {'res. evals':>10} "
          f"{'Jacobians':>9} {'LUs':>5}")  # fmt: skip
    for c in cpu:
        print(f"{t_end:10.0f} {c:9.2f} {c / t_end:9.2e} {st.get('steps', 0):6d} "
              f"{st.get('residual_evals', 0):10d} {st.get('jac_evals', 0):9d} "
              f"{st.get('lu_decomps', 0):5d}")  # fmt: skip


if __name__ == "__main__":
    main()
