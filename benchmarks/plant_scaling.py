"""Scaling of the plant model: a steam pipe split into N volumes, inlet temperature step.

    .venv/bin/python benchmarks/plant_scaling.py                 # N = 10 30 100 300 1000 3000
    .venv/bin/python benchmarks/plant_scaling.py --sizes 10 30   # quick run
    .venv/bin/python benchmarks/plant_scaling.py --no-ida
    .venv/bin/python benchmarks/plant_scaling.py --geometry      # the pipe from geometry
    .venv/bin/python benchmarks/plant_scaling.py --sizes 1000 10000 --wall sine --no-ida
    .venv/bin/python benchmarks/plant_scaling.py --sizes 1000 --wall sine --no-ida --split
    .venv/bin/python benchmarks/plant_scaling.py --sizes 1000 --medium "IF97-TABLES::Water"

Plant: steam reservoir (50 bar, 500 C, stepping to 520 C at t = 1 s) -> Pipe
(20 m, D = 0.1 m, kA = 6283 W/K, C_wall = 1.3e5 J/K, N volumes) -> valve ->
45 bar. About 2 kg/s; steady start; simulated to t_end = 60 s (two wall time
constants). For each N the same assembled residual is integrated by dnasim's
solve_dae and by SUNDIALS IDA (scikit-sundae's band solver, with the equations
matched to the unknowns and both in reverse Cuthill-McKee order, the ordering
dnasim's band LU uses: ``dnasim.solver.band``), both at rtol = 1e-6 and the same
atol vector; dnasim leaves the algebraic variables out of its error test, as
`dnasim run` does (IDA through scikit-sundae cannot: it has no IDASetSuppressAlg).
Printed per N: unknowns, CPU time (``time.process_time``: the machine
is shared, so wall time is noise) per simulated second, steps, residual
evaluations, property calls (calls of ``medium.state``, ``medium.states`` and
``medium.T_rho_u``, the pipes' lean call, cache hits included) and the states the
backend computed ("prop pts", ``medium.n_evaluations``), the share of the run's wall
time spent inside property calls,
T_out at t_end, and the ratio of the CPU times IDA/dnasim (> 1: dnasim faster).
``--json FILE`` also writes the rows (T_out to full precision) for comparing two
versions.

``--wall sine``: the wall temperature prescribed, T_wall(t) = 500 C + 20 K sin(2 pi t /
20 s) (no wall storage), on top of the inlet step. ``--medium "IF97-TABLES::Water"``:
the same plant on the bicubic IF97 tables (dnasim.media.if97_tables). N = 10000 is
two 5000-volume pipes in series (``--sizes 10000``; a Pipe has at most 5000 volumes;
not in the default list: minutes of CPU).

``--split``: a second table, dnasim's residual evaluations by purpose (the Newton
iterations, the finite-difference Jacobians' column groups, the settling of the
quadratures whose rows the Jacobian leaves out: ``IterationMatrix``'s ``quadrature``),
Jacobians, evaluations per Jacobian, Newton iterations per step, rejected steps, and
the steady start's evaluations, CPU and peak-memory growth, with the CPU per simulated
second of start and run together (the first table's CPU is the run's alone).

``--geometry``: the same pipe described by its geometry instead (issue 22): D = 0.1 m,
length 20 m, a 5 mm carbon-steel wall (its mass and c(T), lambda(T)), Darcy-Weisbach
with Colebrook and Gnielinski's (VDI G1) heat transfer from the steam's IAPWS transport
properties, evaluated each residual. The lumped pipe's kA is 1000 W/(m2 K) on the same
surface, its C_wall the same wall at 500 J/(kg K); the correlations give about 1.6 times
that kA, so T_out differs. The column "us/vol-step" is the CPU time per volume and step
(CPU s / (N steps)).
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from dnasim.core.timefunctions import Sine, Step
from dnasim.library import Pipe, PressureBoundary, Valve
from dnasim.media import get_medium
from dnasim.plant.plant import Plant

T_END = 60.0


#: --medium: the water medium of the plant (e.g. "IF97-TABLES::Water", the tables)
MEDIUM = {"name": "Water"}


#: most volumes of one Pipe (its n_volumes limit): longer pipes are pipes in series
MAX_VOLUMES_PER_PIPE = 5000


def steam_pipe(n, geometry=False, wall="storage"):
    """The plant of the module doc; N > 5000 volumes as ceil(N / 5000) equal pipes in
    series (20 m in all, volume, kA, friction and wall shared out by length)."""
    plant = Plant(f"steam_pipe_{n}", medium=MEDIUM["name"])
    L_all, D, s = 20.0, 0.1, 0.005
    parts = -(-n // MAX_VOLUMES_PER_PIPE)
    if n % parts:
        raise SystemExit(f"N = {n}: more than {MAX_VOLUMES_PER_PIPE} volumes must split evenly")
    L = L_all / parts
    plant.add(PressureBoundary("steam", p=50e5, T=Step(1.0, 773.15, 793.15), m_nominal=2.0))
    nodes = ["in"] + [f"mid{k}" for k in range(1, parts)] + ["out"]
    for k in range(parts):
        name = "pipe" if parts == 1 else f"pipe{k + 1}"
        if geometry:
            pipe = Pipe(
                name,
                D=D,
                length=L,
                wall_thickness=s,
                wall_material="carbon steel",
                n_volumes=n // parts,
                m_nominal=2.0,
            )
        elif wall == "sine":  # a prescribed wall temperature 500 +- 20 C, period 20 s
            pipe = Pipe(
                name,
                V=math.pi / 4 * D**2 * L,
                kA=1000.0 * math.pi * D * L,
                k=2e5 / parts,
                T_wall=Sine(773.15, 20.0, 20.0),
                n_volumes=n // parts,
                m_nominal=2.0,
            )
        else:
            pipe = Pipe(
                name,
                V=math.pi / 4 * D**2 * L,
                kA=1000.0 * math.pi * D * L,
                k=2e5 / parts,
                C_wall=7850.0 * math.pi * (D + s) * s * L * 500.0,
                n_volumes=n // parts,
                m_nominal=2.0,
            )
        plant.add(pipe)
        plant.connect(f"{name}.inlet", nodes[k])
        plant.connect(f"{name}.outlet", nodes[k + 1])
    plant.add(Valve("valve", C=0.003, opening=1.0, m_nominal=2.0))
    plant.add(PressureBoundary("sink", p=45e5, m_nominal=2.0))
    for a, b in [
        ("steam.port", "in"),
        ("valve.inlet", "out"),
        ("valve.outlet", "exit"),
        ("sink.port", "exit"),
    ]:
        plant.connect(a, b)
    return plant


class PropertyTimer:
    """Wraps medium.state, medium.states and medium.T_rho_u on the shared Water instance
    (each when the medium has it); accumulates
    their wall time (perf_counter: a CPU clock costs a system call per read, which
    would inflate the 1e5 scalar calls of a run) and number of calls."""

    def __init__(self, medium):
        self.medium = medium
        self.seconds = 0.0
        self.calls = 0

    def _wrap(self, name):
        inner = getattr(type(self.medium), name).__get__(self.medium)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                self.seconds += time.perf_counter() - t0
                self.calls += 1

        setattr(self.medium, name, timed)

    def __enter__(self):
        self.evaluations = self.medium.n_evaluations
        self.wrapped = [n for n in ("state", "states", "T_rho_u") if hasattr(self.medium, n)]
        for name in self.wrapped:
            self._wrap(name)
        return self

    def __exit__(self, *exc):
        for name in self.wrapped:
            delattr(self.medium, name)
        self.evaluations = self.medium.n_evaluations - self.evaluations


class EvaluationSplit:
    """Where dnasim's residual evaluations go (``--split``): the finite-difference
    Jacobians' column groups (``IterationMatrix.finite_difference``), the settling of
    the quadratures whose rows the matrix leaves out (``trailing_residual``, one a
    converged corrector), and the rest, the Newton iterations (their first residual
    at the predictor included). Counted by wrapping the two methods."""

    def __enter__(self):
        from dnasim.solver import linear_algebra as la

        self.la, self.fd, self.settle = la, 0, 0
        self.saved = la.IterationMatrix.finite_difference, la.IterationMatrix.trailing_residual
        split = self

        def fd(matrix, *args, **kwargs):
            stats = getattr(matrix.residual, "stats", None)  # IDA's restarts: none
            if stats is None:
                return split.saved[0](matrix, *args, **kwargs)
            before = stats.residual_evals
            try:
                return split.saved[0](matrix, *args, **kwargs)
            finally:
                split.fd += stats.residual_evals - before

        def settle(matrix, *args, **kwargs):
            split.settle += 1
            return split.saved[1](matrix, *args, **kwargs)

        la.IterationMatrix.finite_difference = fd
        la.IterationMatrix.trailing_residual = settle
        return self

    def __exit__(self, *exc):
        self.la.IterationMatrix.finite_difference = self.saved[0]
        self.la.IterationMatrix.trailing_residual = self.saved[1]


def steady_start(dae):
    """The steady start (``find_steady_state``): (y0, yp0) and its CPU [s], residual
    evaluations and the growth of the peak resident memory [MB] (ru_maxrss)."""
    import resource

    from dnasim.start.steady_state import find_steady_state

    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    rest = find_steady_state(dae, 0.0)
    grew = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss) / 1024.0
    return rest.y, rest.yp, {"cpu": rest.stats.cpu, "fevals": rest.stats.residual_evals, "MB": grew}


def run(n, solver, rtol=1e-6, linsolver=None, geometry=False, wall="storage"):
    plant = steam_pipe(n, geometry, wall)
    dae = plant.compile()
    y0, yp0, start = steady_start(dae)
    water = get_medium(MEDIUM["name"])
    split = EvaluationSplit()
    with PropertyTimer(water) as timer, split:
        t0 = time.process_time()
        w0 = time.perf_counter()
        if solver == "dnasim":
            from dnasim.solver import solve_dae

            res = solve_dae(
                dae.residual,
                (0.0, T_END),
                y0,
                yp0,
                algebraic=dae.algebraic,
                quadrature=dae.quadrature,
                rtol=rtol,
                atol=dae.atol_vector(1e-6, y0),
                jac_sparsity=dae.jac_sparsity,
                residual_for_columns=dae.residual_for_columns,
                tstops=dae.tstops(0.0, T_END),
                calc_initial=False,
                # as `dnasim run` (backends.NordsieckBDF): algebraic variables out of the
                # error test (scikit-sundae exposes no IDASetSuppressAlg: IDA keeps them)
                exclude_algebraic_from_error=True,
                dense_output=False,
                throw=True,
            )
        else:
            from dnasim.solver.ida import solve_ida
            from dnasim.start.initial import reinitialise

            res = solve_ida(
                dae.residual,
                (0.0, T_END),
                y0,
                yp0,
                algebraic=dae.algebraic,
                reinitialise=lambda t, y, yp: reinitialise(dae, t, y, yp),
                jac_sparsity=dae.jac_sparsity,
                rtol=rtol,
                atol=dae.atol_vector(1e-6, y0),
                tstops=dae.tstops(0.0, T_END),
                linsolver=linsolver,
            )
        wall = time.process_time() - t0
        w = time.perf_counter() - w0
    T_out = water.state(res.y[dae.index["out.p"], -1], res.y[dae.index["out.h"], -1]).T
    return {
        "n": dae.n,
        "wall": wall,
        "steps": res.stats["steps"],
        "fevals": res.stats["residual_evals"],
        "prop_share": timer.seconds / w,
        "prop_calls": timer.calls,
        "prop_points": timer.evaluations,
        "T_out": T_out,
        "ok": bool(res.success),
        "start": start,
        "jacobians": res.stats.get("jac_evals", 0),  # (dnasim's counters; IDA's differ)
        "newton_iters": res.stats.get("newton_iters", 0),
        "rejected": res.stats.get("rejected_error", 0) + res.stats.get("rejected_newton", 0),
        "fd_evals": split.fd,
        "settle_evals": split.settle,
    }


def main(argv=None):
    global T_END
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 30, 100, 300, 1000, 3000])
    ap.add_argument("--no-ida", action="store_true", help="skip the IDA comparison")
    ap.add_argument("--json", help="also write the rows to this JSON file")
    ap.add_argument("--geometry", action="store_true", help="the pipe from geometry (issue 22)")
    ap.add_argument(
        "--wall",
        choices=["storage", "sine"],
        default="storage",
        help="storage: the lumped wall (C_wall); sine: T_wall = 500 +- 20 C, period 20 s",
    )
    ap.add_argument("--medium", default="Water", help='the water medium, e.g. "IF97-TABLES::Water"')
    ap.add_argument("--t-end", type=float, default=T_END, help="simulated time [s] (60)")
    ap.add_argument(
        "--split",
        action="store_true",
        help="also print dnasim's residual evaluations by purpose and the steady start",
    )
    args = ap.parse_args(argv)
    ap_t = args.t_end
    MEDIUM["name"] = args.medium
    T_END = ap_t
    print(f"# medium {args.medium}, wall {args.wall}, geometry {args.geometry}, t_end {T_END:g} s")
    header = (
        f"{'N':>5} {'unknowns':>8} {'CPU s/sim-s':>11} {'us/vol-step':>11} {'steps':>6} "
        f"{'F evals':>8} "
        f"{'prop calls':>10} {'prop pts':>9} {'prop %':>7} {'T_out K':>11} | "
        f"{'IDA CPU s/sim-s':>15} {'IDA steps':>9} {'IDA F':>7} {'IDA prop %':>10} "
        f"{'IDA/dnasim':>10}"
    )
    print(header)
    print("-" * len(header))
    rows = []
    for n in args.sizes:
        ours = run(n, "dnasim", geometry=args.geometry, wall=args.wall)
        row = {"N": n, "dnasim": ours}
        rows.append(row)
        per = 1e6 * ours["wall"] / (n * max(ours["steps"], 1))
        line = (
            f"{n:>5} {ours['n']:>8} {ours['wall'] / T_END:>11.4f} {per:>11.2f} {ours['steps']:>6} "
            f"{ours['fevals']:>8} {ours['prop_calls']:>10} {ours['prop_points']:>9} "
            f"{100 * ours['prop_share']:>6.1f}% {ours['T_out']:>11.5f}"
        )
        if not ours["ok"]:
            line += " (dnasim FAILED)"
        if not args.no_ida:
            ida = run(n, "ida", linsolver="band", geometry=args.geometry, wall=args.wall)
            row["ida"] = ida
            line += (
                f" | {ida['wall'] / T_END:>15.4f} {ida['steps']:>9} {ida['fevals']:>7} "
                f"{100 * ida['prop_share']:>9.1f}% {ida['wall'] / ours['wall']:>10.2f}"
            )
            if not ida["ok"]:
                line += " (IDA FAILED)"
            if abs(ida["T_out"] - ours["T_out"]) > 1e-2:
                line += f" (T_out differs: IDA {ida['T_out']:.3f})"
        print(line, flush=True)
        if args.json:
            with open(args.json, "w") as f:
                json.dump(rows, f, indent=1)
    if args.split:
        print_split(rows)
    return 0


def print_split(rows):
    """dnasim's residual evaluations by purpose (``EvaluationSplit``) and the steady
    start's work, per N; the CPU of the run with the start's (the start is outside the
    table above's CPU) per simulated second."""
    print()
    head = (
        f"{'N':>5} {'F evals':>8} {'Newton':>7} {'FD Jac':>7} {'settle':>7} {'Jacs':>5} "
        f"{'F/Jac':>6} {'iters/step':>10} {'rejected':>8} | {'start F':>7} {'start CPU s':>11} "
        f"{'start MB':>8} {'CPU s/sim-s with start':>22}"
    )
    print(head)
    print("-" * len(head))
    for row in rows:
        r = row["dnasim"]
        newton = r["fevals"] - r["fd_evals"] - r["settle_evals"]
        per_jac = r["fd_evals"] / max(r["jacobians"], 1)
        st = r["start"]
        print(
            f"{row['N']:>5} {r['fevals']:>8} {newton:>7} {r['fd_evals']:>7} "
            f"{r['settle_evals']:>7} {r['jacobians']:>5} {per_jac:>6.1f} "
            f"{r['newton_iters'] / max(r['steps'], 1):>10.2f} {r['rejected']:>8} | "
            f"{st['fevals']:>7} {st['cpu']:>11.3f} {st['MB']:>8.0f} "
            f"{(r['wall'] + st['cpu']) / T_END:>22.4f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    raise SystemExit(main())
