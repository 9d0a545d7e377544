"""MotorPump against its closed forms (tests/test_motor_pump.py): the run-down after a
trip against a pure resistance, omega_0/(1 + t/tau), by how far the speed has fallen;
the rotor's energy balance over a trip and restart; the run-down of the field plant
plants/feedpump_motor_trip.toml against a shut check valve; and the CPU time.

    python benchmarks/motor_pump_rundown.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from test_motor_pump import FIELD, MOTOR, RPM, resistance_plant  # noqa: E402

from dnasim.core.timefunctions import Step, Table  # noqa: E402
from dnasim.plant.plantfile import load, simulate_plant  # noqa: E402


def main():
    print("run-down after a trip against a pure resistance: |omega/omega_exact - 1|")
    t0 = time.process_time()
    res = resistance_plant(supply=Step(1.0, 1.0, 0.0)).simulate(
        40.0, start="steady", rtol=1e-8, atol_scaled=1e-8
    )
    cpu = time.process_time() - t0
    t, w = res.t, res["pump.omega"]
    w0, tau0 = w[0], res["pump.tau_h"][0]
    tau = MOTOR["J"] * w0 / tau0
    print(f"tau = J omega_0/tau_0 = {tau:.4f} s  (CPU {cpu:.2f} s, {res.stats['steps']} steps)")
    print(f"{'down to':>10} {'max dev':>10}")
    for f in (0.9, 0.7, 0.5, 0.3, 0.2, 0.125):
        a = (t > 1.0) & (w > f * w0)
        err = np.max(np.abs(w[a] / (w0 / (1 + (t[a] - 1.0) / tau)) - 1))
        print(f"{f:8.3f}w0 {err:10.2e}")
    plant = resistance_plant(P_friction=3e3, supply=Table([1.0, 1.01, 8.0, 8.01], [1, 0, 0, 1]))
    res = plant.simulate(20.0, start="steady", rtol=1e-7, atol_scaled=1e-7)
    w = res["pump.omega"]
    Wm, Wp, Wf = res["pump.W_motor"], res["pump.W"], res["pump.W_friction"]
    kin = 0.5 * MOTOR["J"] * (w**2 - w[0] ** 2)
    err = np.max(np.abs(Wm - (Wp - Wp[0]) - Wf - kin)) / np.max(np.abs(Wm))
    print()
    print(f"rotor energy balance, trip at 1 s, restart at 8 s (rtol 1e-7): {err:.2e}")
    loaded = load(FIELD)
    t0 = time.process_time()
    res = simulate_plant(loaded.plant, loaded.simulation)
    cpu = time.process_time() - t0
    t, w, m = res.t, res["pump.omega"], res["pump.m"]
    n0, J, P0, Pf = 2980 * RPM, 30.0, 120e3, 10e3
    k = np.flatnonzero((t > 10.0) & (m <= 0.0))[0]
    k1 = np.flatnonzero(t > t[k] + 1.0)[0]
    a, c = P0 / n0**3, Pf / n0**2
    sel = (t >= t[k1]) & (t < 40.0)
    ex = 1.0 / ((1.0 / w[k1] + a / c) * np.exp(c * (t[sel] - t[k1]) / J) - a / c)
    print()
    print("plants/feedpump_motor_trip.toml (80 s)")
    print(f"  check valve shuts at t = {t[k]:.4f} s, r = {w[k] / n0:.6f}")
    print(f"  run-down against the shut valve, max dev: {np.max(np.abs(w[sel] / ex - 1)):.2e}")
    print(f"  speed at 40 s: {w[sel][-1] / n0:.4f} n_0; after the restart: {w[-1] / w[0] - 1:.1e}")
    print(f"  CPU {cpu:.2f} s, {res.stats['steps']} steps, ratio to simulated {cpu / 80:.3f}")


if __name__ == "__main__":
    main()
