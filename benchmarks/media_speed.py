"""Microseconds per water/steam state: the IF97 kernel (numpy, numba) vs the old path.

Run:  .venv/bin/python benchmarks/media_speed.py [--quick]

Table 1, per batch size n = 1, 100, 1000, 10000 and per state mix, the CPU time per
state of

- ``numpy``: :func:`dnasim.media.if97_kernel.ph` on arrays of n states (one call);
- ``numba``: :func:`dnasim.media.if97_numba.ph_arrays` (one call, compiled loop);
- ``memo``: the same with a :class:`~dnasim.media.if97_numba.PhMemo` (what a pipe's
  property call uses), every state moved by a relative 1e-7 in p and h from the
  previous call (a Newton iteration): warm-started from the remembered state;
- ``numba 1x1``: n calls of the scalar ``IF97Water.state(p, h)`` (cache missed: each
  h is new), the path the components use today;
- ``old``: n calls of ``state(p, h)`` of the IF97 medium of commit ea86a1d (CoolProp's
  IF97 flash plus a Newton refinement, one state at a time), loaded from git history;
  skipped if git or that commit is not available.

State mixes (each batch cycles through its states with h varied by 1 mJ/kg steps so
no cache can hit): "liquid" 1 MPa / 400 kJ/kg, "two-phase" 1 MPa / 1500 kJ/kg,
"vapour" 1 MPa / 3000 kJ/kg, "supercrit." 25 MPa / 2000 kJ/kg (region 3), and
"plant mix": 1000 states spread over a boiling pipe at 10, 60 and 190 bar (liquid,
two-phase, vapour in equal parts). Best of 3 repetitions (the machine may be shared),
``time.process_time`` (CPU time). Table 2: one-off costs (import, first compiled call).
Table 3: the flue gas, :class:`dnasim.media.GasMixture` (``get_medium("FlueGas")``, NASA
polynomials, numpy): ``states`` on n states from 300 K to 2000 K at 1 bar (one call),
and n calls of the scalar ``state(p, h)`` (cache missed), CPU us per state.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time

import numpy as np

STATES = {
    "liquid": (1e6, 4.0e5),
    "two-phase": (1e6, 1.5e6),
    "vapour": (1e6, 3.0e6),
    "supercrit.": (25e6, 2.0e6),
}


def plant_mix(n):
    """n (p, h) of a boiling pipe at 10, 60, 190 bar: subcooled to superheated."""
    p = np.repeat([10e5, 60e5, 190e5], -(-n // 3))[:n]
    h = np.tile(np.linspace(5e5, 3.0e6, -(-n // 3)), 3)[:n]
    return p, h


def batch(name, n):
    if name == "plant mix":
        return plant_mix(n)
    p0, h0 = STATES[name]
    return np.full(n, p0), h0 + 1e-3 * np.arange(n)


def best(fn, repeats=3):
    t = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        t = min(t, time.process_time() - t0)
    return t


def load_old_medium():
    """The IF97 medium of commit ea86a1d (CoolProp IF97 + Newton), or None."""
    from revision import module_at

    mod = module_at("ea86a1d", "dnasim/media/if97.py", "old_if97")
    return None if mod is None else mod.IF97Water()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="n up to 1000 only")
    args = ap.parse_args()
    sizes = [1, 100, 1000] if args.quick else [1, 100, 1000, 10000]

    t0 = time.process_time()
    from dnasim.media import if97_kernel as K
    from dnasim.media import if97_numba as NB
    from dnasim.media.if97 import IF97Water

    t_import = time.process_time() - t0
    t0 = time.process_time()
    NB.ph_scalar(1e6, 4e5)
    NB.ph_arrays(np.array([1e6]), np.array([4e5]))
    t_first = time.process_time() - t0
    t0 = time.process_time()
    old = load_old_medium()
    t_old_load = time.process_time() - t0
    water = IF97Water(kernel="numba")

    rows = []
    for name in [*STATES, "plant mix"]:
        for n in sizes:
            p, h = batch(name, n)
            pl, hl = p.tolist(), h.tolist()
            reps = max(1, 2000 // n)

            def run_numpy():
                for _ in range(reps):
                    K.ph(p, h)

            def run_numba():
                for _ in range(reps):
                    NB.ph_arrays(p, h)

            memo = NB.PhMemo()
            moved = [(p * (1.0 + s), h * (1.0 + s)) for s in (1e-7, -1e-7)]
            NB.ph_arrays(p, h, memo=memo)

            def run_memo():
                for k in range(reps):
                    NB.ph_arrays(*moved[k % 2], memo=memo)

            def run_scalar(medium):
                def f():
                    for _ in range(reps):
                        medium.cache_clear()
                        for pi, hi in zip(pl, hl, strict=True):
                            medium.state(pi, hi)

                return f

            per = 1e6 / (reps * n)
            numpy_us = best(run_numpy) * per if n <= 1000 or name == "plant mix" else np.nan
            numba_us = best(run_numba) * per
            memo_us = best(run_memo) * per
            scal_us = best(run_scalar(water)) * per
            old_us = np.nan
            if old is not None and n <= 1000:
                try:
                    old_us = best(run_scalar(old), repeats=2) * per
                except Exception:  # noqa: BLE001 - the old flash fails in region 3 above p_c
                    old_us = np.nan
            rows.append((name, n, numpy_us, numba_us, memo_us, scal_us, old_us))

    print(f"dnasim.media IF97 speed; Python {platform.python_version()}, {platform.machine()}")
    print("CPU us per state (best of 3); old = ea86a1d's CoolProp IF97 + Newton, one state")
    print("per call; nan: not run (numpy above 1000 single-state batches: slow; old above")
    print("1000: slow) or failing (the old CoolProp flash fails in region 3 above p_c)")
    head = (
        f"{'states':12s}{'n':>7s}{'numpy':>10s}{'numba':>10s}{'memo':>10s}{'numba 1x1':>11s}"
        f"{'old':>10s}"
    )
    print(head)
    print("-" * len(head))
    for name, n, a, b, m, c, d in rows:
        print(f"{name:12s}{n:7d}{a:10.2f}{b:10.2f}{m:10.2f}{c:11.2f}{d:10.2f}")
    print()
    print(f"one-off CPU s: import kernels {t_import:.2f}, first compiled call {t_first:.2f}")
    print("(numba's cache in __pycache__; without it the first call compiles), old medium load")
    print(f"incl. CoolProp import {t_old_load:.2f}")
    print()
    flue_gas_table(sizes)
    sys.stdout.flush()


def flue_gas_table(sizes) -> None:
    """Table 3: CPU us per state of the flue gas (GasMixture), arrays and scalar calls."""
    from dnasim.media import get_medium

    gas = get_medium("FlueGas")
    print("flue gas (GasMixture, NASA7, numpy): CPU us per state, 300..2000 K at 1 bar")
    head = f"{'n':>7s}{'states':>10s}{'state 1x1':>11s}"
    print(head)
    print("-" * len(head))
    for n in sizes:
        p = np.full(n, 1e5)
        h = gas.h_T(np.linspace(300.0, 2000.0, n)) + 1e-3 * np.arange(n)
        pl, hl = p.tolist(), h.tolist()
        reps = max(1, 2000 // n)

        def run_states():
            for _ in range(reps):
                gas.states(p, h)

        def run_scalar():
            for _ in range(reps):
                gas.cache_clear()
                for pi, hi in zip(pl, hl, strict=True):
                    gas.state(pi, hi)

        per = 1e6 / (reps * n)
        print(f"{n:7d}{best(run_states) * per:10.2f}{best(run_scalar) * per:11.2f}")


if __name__ == "__main__":
    main()
