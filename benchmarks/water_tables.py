"""Bicubic IF97 tables (``IF97-TABLES::Water``) against the IF97 kernel: cost and error.

    .venv/bin/python benchmarks/water_tables.py [--n 200000]

Cost: CPU us per state (``time.process_time``, best of 5) of ``states`` on 1000 random
(p, h) points, of the residual's lean call ``T_rho_u`` on the same points (IF97 with a
fresh memo each call: every point computed, as in a Newton iteration), and of a single
``state`` call (a new (p, h) each call: no cache hit). Error: max |rho/rho_IF97 - 1|,
max |T - T_IF97| and max |cp/cp_IF97 - 1| over ``--n`` random states by IF97 region
(points in the near-critical band, where IF97 answers, left out), and the table build
time and size.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dnasim.media import get_medium
from dnasim.media import if97_numba as NB
from dnasim.media import if97_tables as TW


def random_states(n, seed=1):
    rng = np.random.default_rng(seed)
    p = np.exp(rng.uniform(np.log(700.0), np.log(100e6), n))
    ha = np.array([NB.h_pT_scalar(x, 273.2)[0] for x in p])
    hb = np.array([NB.h_pT_scalar(x, 1073.0)[0] for x in p])
    return p, ha + rng.uniform(0.0, 1.0, n) * (hb - ha)


def best(fn, repeat=5):
    fn()
    t = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        t = min(t, time.process_time() - t0)
    return t


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200000)
    args = ap.parse_args(argv)
    if97 = get_medium("Water")
    tab = get_medium("Water", backend="IF97-TABLES")
    t0 = time.process_time()
    tables = TW.build_tables()
    build = time.process_time() - t0
    mb = sum(v.nbytes for v in tables.values()) / 1e6
    p, h = random_states(1000, seed=3)
    keep = ~((p >= TW.P_BAND[0]) & (p <= TW.P_BAND[1]))
    p, h = p[keep], h[keep]
    n = p.size
    print(f"# {n} random states outside the band; table build {build:.2f} CPU s, {mb:.1f} MB")
    print(f"{'call':<34} {'IF97 us/state':>13} {'tables us/state':>15} {'ratio':>6}")
    rows = [
        ("states(p, h), 1000 points", lambda m: m.states(p, h), n),
        (
            "T_rho_u(p, h), 1000 points",
            lambda m: m.T_rho_u(p, h, None, m.states_memo() if m is if97 else None),
            n,
        ),
    ]
    for name, fn, k in rows:
        a = best(lambda fn=fn: fn(if97)) / k * 1e6
        b = best(lambda fn=fn: fn(tab)) / k * 1e6
        print(f"{name:<34} {a:>13.3f} {b:>15.3f} {a / b:>6.1f}")

    def scalar(m):
        base = 3.0e6 + 1e3 * np.random.default_rng(0).random()

        def go():
            for i in range(2000):
                m.state(5e6, base + i)
            m.cache_clear()

        return go

    a = best(scalar(if97)) / 2000 * 1e6
    b = best(scalar(tab)) / 2000 * 1e6
    print(f"{'state(p, h), one state':<34} {a:>13.3f} {b:>15.3f} {a / b:>6.1f}")
    p, h = random_states(args.n)
    r = tab.states(p, h)
    ref = NB.ph_arrays(p, h)
    out = ~((p >= TW.P_BAND[0]) & (p <= TW.P_BAND[1]))
    erho = np.abs(r.rho / ref.rho - 1.0)
    eT = np.abs(r.T - ref.T)
    with np.errstate(invalid="ignore"):
        ecp = np.abs(r.cp / ref.cp - 1.0)
    print()
    print(
        f"# error against IF97 over {args.n} random states (bounds: rho {TW.RHO_REL_BOUND:.0e} "
        f"relative, T {TW.T_ABS_BOUND * 1e3:.0f} mK)"
    )
    print(f"{'region':<14} {'states':>7} {'max rho rel':>11} {'max T [K]':>10} {'max cp rel':>10}")
    for name, reg in (("1 liquid", 1), ("2 vapour", 2), ("3", 3), ("4 dome", 4)):
        sel = out & (ref.region == reg)
        cp = ecp[sel & np.isfinite(ref.cp)]
        cps = f"{cp.max():.1e}" if cp.size else "-"
        print(
            f"{name:<14} {sel.sum():>7} {erho[sel].max():>11.1e} {eT[sel].max():>10.1e} {cps:>10}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
