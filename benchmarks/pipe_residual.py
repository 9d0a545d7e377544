"""The N-volume steam pipe's residual and its IF97 kernel, CPU time (issue 10, big10).

    .venv/bin/python benchmarks/pipe_residual.py                 # N = 1000
    .venv/bin/python benchmarks/pipe_residual.py --n 300 --base 122d9b6

Part 1, the residual of ``plant_scaling.steam_pipe(N)`` at its steady start: every
unknown moved by a relative 1e-7 per call (a Newton iteration) and unchanged; the
difference is the IF97 kernel (with the memo, unchanged states are copied), the
unchanged call the rest of the residual. Part 2, the kernel alone on the pipe's states
(50 bar, 500 degC steam, branch VAPOUR as the pipe's phase modes evaluate them, and
AUTO): CPU us per state without memo (cold), with a memo and every state moved by
1e-7 (Newton) or 1e-4 (a predictor), and unchanged. ``--base REV`` also times
``dnasim/media/if97_numba.py`` of git revision REV, loaded under another name into the
same process (its numba cache goes to a temporary directory). Best of 7 (residual) or
10 (kernel) blocks of ``time.process_time``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def best(f, reps, blocks):
    """Min over blocks of the CPU seconds per call of f(k), k = 0..reps-1."""
    f(0)
    out = []
    for _ in range(blocks):
        t = time.process_time()
        for k in range(reps):
            f(k)
        out.append((time.process_time() - t) / reps)
    return min(out)


def residual_times(n):
    from plant_scaling import steam_pipe

    from dnasim.start.initial import initial_values

    dae = steam_pipe(n).compile()
    y0, yp0 = initial_values(dae, 0.0, "steady")
    reps = max(20, 100000 // n)
    ys = [y0 * (1 + 1e-7 * ((k % 7) - 3)) for k in range(reps)]
    moved = best(lambda k: dae.residual(0.0, ys[k], yp0), reps, 7)
    same = best(lambda k: dae.residual(0.0, y0, yp0), reps, 7)
    return moved, same


def load_base_kernel(rev):
    """if97_numba.py of git revision rev as a module (None if git fails)."""
    from revision import module_at

    return module_at(rev, "dnasim/media/if97_numba.py", f"if97_numba_{rev}")


def kernel_times(n, base):
    from dnasim.media import if97_numba as NB

    p = np.linspace(50e5, 49.5e5, n)
    h = np.linspace(3.433e6, 3.40e6, n)
    br = np.full(n, 3, dtype=np.int64)
    cases = []
    if base is not None:
        cases += [("base AUTO, no memo", base, None, None, 1e-7)]
        cases += [("base VAPOUR, no memo", base, br, None, 1e-7)]
    cases += [
        ("AUTO, no memo", NB, None, None, 1e-7),
        ("VAPOUR, no memo", NB, br, None, 1e-7),
        ("VAPOUR, memo, moved 1e-7", NB, br, NB.PhMemo(), 1e-7),
        ("VAPOUR, memo, moved 1e-4", NB, br, NB.PhMemo(), 1e-4),
        ("VAPOUR, memo, unchanged", NB, br, NB.PhMemo(), 0.0),
    ]
    reps = max(20, 200000 // n)
    rows = []
    for name, mod, b, memo, rel in cases:
        kw = {} if memo is None else {"memo": memo}
        moved = [(p * (1 + rel * (k % 7 + 1)), h * (1 + rel * (k % 7 + 1))) for k in range(7)]

        def call(k, mod=mod, b=b, kw=kw, moved=moved):
            mod.ph_arrays(*moved[k % 7], b, **kw)

        rows.append((name, best(call, reps, 10) / n * 1e6))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000, help="volumes")
    ap.add_argument("--base", help="git revision whose IF97 kernel to time alongside")
    args = ap.parse_args(argv)
    np.seterr(all="ignore")
    moved, same = residual_times(args.n)
    print(f"pipe of N = {args.n} volumes, CPU ms per residual evaluation")
    print(f"  all states moved 1e-7: {moved * 1e3:.3f}   unchanged: {same * 1e3:.3f}")
    print(f"  kernel (difference): {(moved - same) * 1e3:.3f}   rest: {same * 1e3:.3f}")
    base = load_base_kernel(args.base) if args.base else None
    print(f"IF97 kernel, CPU us per state, {args.n} states per call")
    for name, us in kernel_times(args.n, base):
        print(f"  {name:28s} {us:7.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
