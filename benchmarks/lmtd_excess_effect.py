"""What the bound on the LMTD's excess heat flow (``physics.lmtd_excess``) changes.

    python benchmarks/lmtd_excess_effect.py [T_END] FILE.toml [FILE.toml ...]

runs each plant file (its own settings; to T_END [s] if given as the first argument)
twice in this process: with the channels' heat flow the plain LMTD ("plain": the bound
replaced by the identity, as before it) and as the code stands ("bounded"). Prints per
run the time reached, steps, rejected steps, residual evaluations, Jacobians, CPU [s]
(time.process_time), how many channel evaluations had at least one volume beyond the
exact range (|dQ/L| > LMTD_EXCESS_EXACT) and, for runs that both finished, the largest
difference of the two runs over the plain run's output times (the bounded one
interpolated linearly onto them), per output, relative to the larger of that output's
range and 1e-6 (the solvers' rtol) of its size: max |x_bounded - x_plain| /
max(ptp(x_plain), 1e-6 max |x_plain|) over every output, with where it is and the two
values, then the same for the end values alone; below 1 means within the solver's
tolerance.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from dnasim.compilation.compiler import compile as compile_plant
from dnasim.library.submodels import channel
from dnasim.model import physics
from dnasim.plant.plantfile import load
from dnasim.run.simulation import simulate, simulation_keywords

BOUNDED = channel.lmtd_excess


def run(path, t_end, bounded):
    active = [0]

    def counted(dQ, H_x, Q_floor):
        out = BOUNDED(dQ, H_x, Q_floor)
        L = np.sqrt(H_x * H_x + Q_floor * Q_floor) + 1e-300
        if np.any(np.abs(dQ / L) > physics.LMTD_EXCESS_EXACT):
            active[0] += 1
        return out

    channel.lmtd_excess = counted if bounded else (lambda dQ, H_x, Q_floor: dQ)
    try:
        loaded = load(path)
        system = compile_plant(loaded.plant)
        t1, kw = simulation_keywords(loaded.simulation, t_end=t_end)
        c0 = time.process_time()
        res = simulate(system, t_end=t1, **kw)
        cpu = time.process_time() - c0
    finally:
        channel.lmtd_excess = BOUNDED
    return res, cpu, active[0]


def main(argv) -> int:
    t_end = None
    if argv and not argv[0].endswith(".toml"):
        t_end = float(argv[0])
        argv = argv[1:]
    print(
        f"{'plant':42s} {'variant':8s} {'t [s]':>9s} {'steps':>6s} {'rej':>5s} "
        f"{'evals':>7s} {'jacs':>6s} {'cpu [s]':>8s} {'bounded':>8s} "
        "max rel diff (output at time: plain -> bounded)"
    )
    for path in argv:
        out = {}
        for bounded in (False, True):
            res, cpu, active = run(path, t_end, bounded)
            out[bounded] = res
            st = res.stats
            diff = ""
            if bounded and out[False].success and res.success:
                worst, which = 0.0, ""
                for name in res.names:
                    a, b = np.asarray(out[False][name]), np.asarray(res[name])
                    b = np.interp(out[False].t, res.t, b)
                    scale = max(np.ptp(a), 1e-6 * np.max(np.abs(a)), 1e-300)
                    k = int(np.argmax(np.abs(b - a)))
                    if abs(b[k] - a[k]) / scale > worst:
                        worst = abs(b[k] - a[k]) / scale
                        which = f"{name} at {out[False].t[k]:.6g} s: {a[k]:.9g} -> {b[k]:.9g}"
                end, end_which = 0.0, ""
                for name in res.names:
                    a, b = np.asarray(out[False][name]), np.asarray(res[name])
                    scale = max(np.ptp(a), 1e-6 * np.max(np.abs(a)), 1e-300)
                    if abs(b[-1] - a[-1]) / scale > end:
                        end = abs(b[-1] - a[-1]) / scale
                        end_which = f"{name}: {a[-1]:.9g} -> {b[-1]:.9g}"
                diff = f"{worst:.2e}  {which}; at the end {end:.2e}  {end_which}"
            print(
                f"{path.split('/')[-1]:42s} {'bounded' if bounded else 'plain':8s} "
                f"{res.t[-1]:9.6g} {st.get('steps', 0):6d} {st.get('rejected', 0):5d} "
                f"{st.get('residual_evals', 0):7d} {st.get('jac_evals', 0):6d} {cpu:8.2f} "
                f"{active if bounded else '':>8} {diff}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
