"""Which unknowns make the corrector fail in a stalling plant (issue 20 item 9).

    python benchmarks/stagnant_newton_failures.py tests/field/closed_feed_line_boiling.toml 340 352

runs the plant file (its own settings) from its start to T1 [s] and prints, for each
failed corrector attempt after T0 [s] (at most 60), the time, the step size, the reason
and the five unknowns with the largest last Newton update against their tolerance
(``StepFailure.bad_components``), then the solver's counters and the CPU time
[s]. The headers of tests/field/closed_feed_line_boiling.toml,
superheater_turbine_closed.toml and superheater_line_trip.toml quote its output.
"""

from __future__ import annotations

import sys
import time

from dnasim.compilation.compiler import compile as compile_plant
from dnasim.plant.plantfile import load
from dnasim.run.simulation import simulate, simulation_keywords
from dnasim.solver import newton

MAX_LINES = 60


def main(argv) -> int:
    path, t_from, t_to = argv[0], float(argv[1]), float(argv[2])
    loaded = load(path)
    system = compile_plant(loaded.plant)
    correct = newton.NewtonCorrector._correct
    shown = [0]

    def logged(self, t, z_pred, cj, h, *args, **kwargs):
        result = correct(self, t, z_pred, cj, h, *args, **kwargs)
        if t > t_from and not result[0] and shown[0] < MAX_LINES:
            shown[0] += 1
            f = self.failure
            names = [system.names[i] for i in (f.bad_components or [])[:5] if i < system.n]
            print(f"t = {t:.9g} s  h = {h:.3g} s  {f.reason}  {names}", flush=True)
        return result

    newton.NewtonCorrector._correct = logged
    t_end, kw = simulation_keywords(loaded.simulation, t_end=t_to)
    c0 = time.process_time()
    res = simulate(system, t_end=t_end, **kw)
    print(f"cpu {time.process_time() - c0:.1f} s")
    print(getattr(res, "message", ""), getattr(res, "stats", ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
