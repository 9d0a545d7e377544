"""Output times with both backends: rows, steps, residual evaluations, CPU time and,
for the lag sensor, the error against its closed form.

    python benchmarks/output_times.py

Plants: tests/plants/lag_sensor.toml (a 50 K supply step at 10 s through a sensor lag
of 8 s: T_s = 423.15 - 50 exp(-(t - 10)/8) K after it) and plants/attemperator.toml
(time events at 120, 600, 660 s, a controller limit located near 638 s), each to its
t_end (60 s, 700 s). Modes: every accepted step, output_interval = 10 s, t_eval = a
grid of 50 s (lag: 5 s) with a time at each step time. A fresh System per run (an
IDA run on a System that ran before takes other steps). CPU time: time.process_time,
best of 3.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import dnasim
from dnasim.plant.plantfile import loads
from dnasim.run.simulation import IDA, NordsieckBDF, simulate

ROOT = Path(__file__).resolve().parents[1]
PLANTS = {
    "lag_sensor": (ROOT / "tests/plants/lag_sensor.toml", 60.0, np.arange(0.0, 61.0, 5.0)),
    "attemperator": (ROOT / "plants/attemperator.toml", 700.0, np.arange(0.0, 701.0, 50.0)),
}


def system(path):
    text = path.read_text().replace("tau =", "T_lag =")  # the lag's current key name
    return dnasim.compile(loads(text, path.name).plant)


def lag_error(res):
    t = res.t
    exact = np.where(t < 10.0, 373.15, 423.15 - 50.0 * np.exp(-(t - 10.0) / 8.0))
    return float(np.max(np.abs(res["sensor.T_s"] - exact)))


def main():
    print(
        f"{'plant':13s} {'solver':12s} {'output':16s} {'rows':>5s} {'extra':>5s} "
        f"{'steps':>6s} {'F evals':>8s} {'CPU [s]':>8s} {'err [K]':>9s}"
    )
    for name, (path, t_end, grid) in PLANTS.items():
        for make in (
            lambda: NordsieckBDF(rtol=1e-7, atol_scaled=1e-8),
            lambda: IDA(rtol=1e-7, atol_scaled=1e-8),
        ):
            for label, kw in (
                ("every step", {}),
                ("interval 10 s", {"output_interval": 10.0}),
                (f"t_eval ({len(grid)})", {"t_eval": grid}),
            ):
                cpu = []
                for _ in range(3):
                    s = system(path)
                    c = time.process_time()
                    res = simulate(s, t_end=t_end, solver=make(), **kw)
                    cpu.append(time.process_time() - c)
                assert res.success, res.message
                extra = len(res.t) - len(grid) if "t_eval" in kw else 0
                err = f"{lag_error(res):9.2e}" if name == "lag_sensor" else f"{'':9s}"
                print(
                    f"{name:13s} {res.solver:12s} {label:16s} {len(res.t):5d} {extra:5d} "
                    f"{res.stats['steps']:6d} {res.stats['residual_evals']:8d} "
                    f"{min(cpu):8.3f} {err}"
                )


if __name__ == "__main__":
    main()
