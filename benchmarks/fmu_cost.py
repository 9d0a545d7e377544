"""FMU export: build time, and the cost of stepping the plant through doStep.

    python benchmarks/fmu_cost.py [--repeat 3] [--plant plants/attemperator.toml]

The scenario is the attemperator's (plants/attemperator.toml, 20 min): the set
point steps from 450 to 440 degC at 2 min. `plain` is one `simulate()` of the file
(its set point a step function) on the output grid of the communication step h;
`CoSimulation` steps the same plant from Python (no FMI) with the set point as an
input changed at t = 120 s; `FMPy` simulates the FMU (FMI 2.0 CS, pythonfmu), in
a fresh process per row (pythonfmu instantiates an FMU once per process). CPU time
is time.process_time (all threads of the process). The FMPy rows include the FMU's
instantiation (loading and compiling the plant) and its steady start; the
`plain+load` row is the plain run with the same loading and compiling, for them;
`FMPy trivial` is a do-nothing pythonfmu slave, the cost of FMPy and pythonfmu alone
(dnasim's modules are imported in the FMPy process before its clock starts).
Best of --repeat.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
T_STEP, BEFORE, AFTER = 120.0, 723.15, 713.15

_FMPY = """
import json, sys, time
import numpy as np
import fmpy
# the modules the FMU's slave imports, imported before the clock starts (as the
# plain rows run in a process that has them): the FMPy rows then count the FMU's
# extraction, instantiation (loading and compiling the plant), start and steps
import dnasim.tools.fmu, dnasim.plant.plantfile, dnasim.run.simulation, dnasim.start.initial  # noqa
import dnasim.start.steady_state, dnasim.start.consistent, dnasim.solver  # noqa
fmu, h, t_step, before, after, t_end = sys.argv[1], *map(float, sys.argv[2:7])
sig = np.array([(0.0, before), (t_step, before), (t_step, after), (t_end, after)],
               dtype=[("time", float), ("pi.setpoint", float)])
t0 = time.process_time()
res = fmpy.simulate_fmu(fmu, stop_time=t_end, output_interval=h, input=sig)
print(json.dumps({"cpu": time.process_time() - t0, "rows": len(res)}), flush=True)
import os
os._exit(0)  # the trivial slave has no balancing reference to its module dict (docs/fmu.md)
"""

_TRIVIAL = """
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class trivial(Fmi2Slave):
    def __init__(self, **kw):
        super().__init__(**kw)
        self.y = 0.0
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, t, h):
        self.y = t + h
        return True
"""

_BUILD = """
import json, sys, time
from dnasim.tools.fmu import build_fmu
from dnasim.plant.plantfile import load
t0 = time.process_time(); w0 = time.perf_counter()
build_fmu(sys.argv[1], sys.argv[2], inputs=["pi.setpoint"])
print(json.dumps({"cpu": time.process_time() - t0, "wall": time.perf_counter() - w0}))
"""


def _best(f, repeat):
    out = None
    for _ in range(repeat):
        r = f()
        if out is None or r["cpu"] < out["cpu"]:
            out = r
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--plant", default=str(ROOT / "plants" / "attemperator.toml"))
    args = ap.parse_args()
    from dnasim.plant.plantfile import load
    from dnasim.tools.fmu import CoSimulation, build_fmu

    plant = args.plant
    tmp = Path(tempfile.mkdtemp(prefix="dnasim_fmu_bench_"))
    fmu = tmp / "plant.fmu"

    def build_cold():
        w0 = time.perf_counter()
        out = subprocess.run(
            [sys.executable, "-c", _BUILD, plant, str(fmu)], capture_output=True, text=True
        )
        r = json.loads(out.stdout.strip().splitlines()[-1])
        r["process"] = time.perf_counter() - w0
        return r

    b = _best(build_cold, args.repeat)
    build_fmu(plant, fmu, inputs=["pi.setpoint"])  # warm the imports of this process
    t_end = load(plant).simulation.t_end
    print(f"FMU build ({Path(plant).name}, best of {args.repeat}):")
    print(
        f"  build_fmu: {b['cpu']:.3f} s CPU, {b['wall']:.3f} s wall (imports done); "
        f"the whole process with its imports: {b['process']:.3f} s wall"
    )
    w0 = time.perf_counter()
    c0 = time.process_time()
    for _ in range(args.repeat):
        build_fmu(plant, fmu, inputs=["pi.setpoint"])
    print(
        f"  build_fmu in a warm process: {(time.process_time() - c0) / args.repeat:.3f} s CPU, "
        f"{(time.perf_counter() - w0) / args.repeat:.3f} s wall"
    )
    print()

    def plain(h, with_load=False):
        c0 = time.process_time()
        loaded = load(plant)
        if not with_load:
            c0 = time.process_time()
        res = loaded.simulate(t_eval=np.arange(0.0, t_end + h / 2, h))
        return {"cpu": time.process_time() - c0, **res.stats, "n": int(round(t_end / h))}

    def cosim(h):
        cs = CoSimulation(load(plant), ["pi.setpoint"], ["sensor.T_s", "pi.z"], stop_time=t_end)
        c0 = time.process_time()
        cs.start()
        n = int(round(t_end / h))
        for k in range(n):
            t = k * h
            if abs(t - T_STEP) < 1e-9 * h:
                cs.set_input("pi.setpoint", AFTER)
            assert cs.step(t, h), cs.message
            cs.value("sensor.T_s")
            cs.value("pi.z")
        cs.close()
        return {"cpu": time.process_time() - c0, **cs.stats, "n": n, "restarts": cs.restarts}

    from pythonfmu import FmuBuilder

    (tmp / "trivial.py").write_text(_TRIVIAL)
    trivial = FmuBuilder.build_FMU(tmp / "trivial.py", dest=tmp)

    def via_fmpy(h, path=fmu):
        out = subprocess.run(
            [sys.executable, "-c", _FMPY, str(path), str(h), str(T_STEP)]
            + [str(BEFORE), str(AFTER), str(t_end)],
            capture_output=True,
            text=True,
        )
        return json.loads(out.stdout.strip().splitlines()[-1])

    head = (
        f"{'h [s]':>6} {'how':<14} {'doSteps':>8} {'CPU [s]':>8} {'/plain':>7} "
        f"{'us/doStep':>10} {'steps':>6} {'F evals':>8} {'LUs':>5} {'restarts':>8}"
    )
    print(f"doStep cost over {t_end:g} s simulated (best of {args.repeat}):")
    print(head)
    by_h = {}
    for h in (10.0, 1.0, 0.1):
        p = _best(lambda h=h: plain(h), args.repeat)
        pl = _best(lambda h=h: plain(h, True), args.repeat)
        c = _best(lambda h=h: cosim(h), args.repeat)
        f = _best(lambda h=h: via_fmpy(h), args.repeat)
        tr = _best(lambda h=h: via_fmpy(h, trivial), args.repeat)
        n = p["n"]
        by_h[h] = {"n": n, "plain": p, "CoSimulation": c, "FMPy (FMI)": f, "FMPy trivial": tr}
        for name, r in (
            ("plain", p),
            ("plain+load", pl),
            ("CoSimulation", c),
            ("FMPy (FMI)", f),
            ("FMPy trivial", tr),
        ):
            ratio = r["cpu"] / (pl["cpu"] if name.startswith("FMPy") else p["cpu"])
            if name.startswith("plain"):
                per = ""
            elif name == "FMPy trivial":
                per = f"{1e6 * r['cpu'] / n:10.1f}"
            else:
                per = f"{1e6 * (r['cpu'] - p['cpu']) / n:10.1f}"
            steps = r.get("steps", "")
            fe = r.get("residual_evals", "")
            lus = r.get("lu_decomps", "")
            rs = r.get("restarts", "")
            print(
                f"{h:6g} {name:<14} {n if not name.startswith('plain') else '':>8} "
                f"{r['cpu']:8.3f} {ratio:7.2f} {per:>10} {steps!s:>6} {fe!s:>8} {lus!s:>5} "
                f"{rs!s:>8}"
            )
    print()
    a, b = by_h[1.0], by_h[0.1]
    dn = b["n"] - a["n"]
    print("marginal CPU per doStep, from h = 1 s to h = 0.1 s (the same integration):")
    for name in ("plain", "CoSimulation", "FMPy (FMI)", "FMPy trivial"):
        d = b[name]["cpu"] - a[name]["cpu"]
        print(f"  {name:<14} {1e6 * d / dn:8.1f} us per communication point")
    print()
    print(
        "us/doStep: (CPU - plain CPU)/doSteps, the cost a communication point adds "
        "(FMPy trivial: its CPU/doSteps, FMPy and pythonfmu alone, a do-nothing slave); "
        "/plain: against plain (FMPy: against plain+load). steps, F evals, LUs: the "
        "solver's, summed over the integrations (CoSimulation: abandoned ones included)."
    )


if __name__ == "__main__":
    main()
