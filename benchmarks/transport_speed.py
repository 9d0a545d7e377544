"""Microseconds per transport-property call: dnasim's ``transport(p, h)`` against CoolProp.

Run:  .venv/bin/python benchmarks/transport_speed.py [--quick]

For n = 1, 1000 and 100000 points (single-phase states spread over the medium's range;
no cache can help: ``transport`` has none), CPU time (``time.process_time``, best of 3)
per call and per point of

- water: ``get_medium("Water").transport(p, h)`` (IF97 states by the compiled kernel,
  IAPWS R12-08/R15-11 by :mod:`dnasim.media.water_transport`), against CoolProp's
  ``AbstractState("IF97", "Water")`` and ``AbstractState("HEOS", "Water")``, each
  point a (p, h) update and ``viscosity()``, ``conductivity()``, ``cpmass()``;
- flue gas: ``get_medium("FlueGas").transport(p, h)`` (numpy: Wilke / Mason-Saxena),
  against CoolProp's ``HEOS`` nitrogen at the same (p, T) (CoolProp has no transport
  for this mixture; N2 is the nearest pure fluid, for scale only).

CoolProp is called one point at a time (its Python interface has no array call), so its
cost per point does not depend on n; for n = 100000 it is timed on 2000 points.
Table 2: the first call in a fresh process (numba cache load or compile).
"""

from __future__ import annotations

import argparse
import platform
import subprocess
import sys
import time

import numpy as np


def best(fn, reps=3):
    out = []
    for _ in range(reps):
        t0 = time.process_time()
        fn()
        out.append(time.process_time() - t0)
    return min(out)


def water_points(n, water):
    """n single-phase (p, h): a pool of 2000 (p, T) from 1 bar to 300 bar and 300 K to
    850 K (states within 2 K of saturation moved off it), repeated to n."""
    rng = np.random.default_rng(1)
    p = rng.uniform(1e5, 30e6, 2000)
    T = rng.uniform(300.0, 850.0, 2000)
    h = np.array([_h(water, a, b) for a, b in zip(p, T, strict=False)])
    return np.resize(p, n), np.resize(h, n)


def _h(water, p, T):
    try:
        return water.h_pT(p, T)
    except Exception:  # at saturation: 3 K off
        return water.h_pT(p, T + 3.0)


def coolprop_loop(AS, p, h):
    import CoolProp.CoolProp as CP

    HP = CP.HmassP_INPUTS
    failed = 0
    for a, b in zip(p, h, strict=False):
        try:
            AS.update(HP, b, a)
            AS.viscosity()
            AS.conductivity()
            AS.cpmass()
        except (ValueError, IndexError):  # CoolProp's IF97 (p, h) flash fails on a few states
            failed += 1
    return failed


def coolprop_pt_loop(AS, p, T):
    import CoolProp.CoolProp as CP

    PT = CP.PT_INPUTS
    for a, b in zip(p, T, strict=False):
        AS.update(PT, a, b)
        AS.viscosity()
        AS.conductivity()
        AS.cpmass()


def first_call() -> str:
    code = (
        "import time; t=time.process_time();"
        "from dnasim.media import get_medium; w=get_medium('Water');"
        "t1=time.process_time(); w.transport(1e6, 5e5); t2=time.process_time();"
        "print(f'{t1-t:.3f} {t2-t1:.3f}')"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    return r.stdout.strip()


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="n = 1 and 1000 only")
    args = ap.parse_args(argv)
    import CoolProp
    import CoolProp.CoolProp as CP

    from dnasim.media import get_medium

    water = get_medium("Water")
    fg = get_medium("FlueGas")
    sizes = (1, 1000) if args.quick else (1, 1000, 100000)
    print(f"python {platform.python_version()}, CoolProp {CoolProp.__version__}")
    print("CPU us per point (per call for n = 1), best of 3")
    print(f"{'medium':<10} {'n':>7} {'dnasim':>10} {'CP IF97':>10} {'CP HEOS':>10}")
    AS97 = CP.AbstractState("IF97", "Water")
    ASHE = CP.AbstractState("HEOS", "Water")
    for n in sizes:
        p, h = water_points(n, water)
        water.transport(p, h)  # warm
        t = best(lambda: water.transport(p, h)) / n * 1e6
        m = min(n, 2000)
        t97 = best(lambda: coolprop_loop(AS97, p[:m], h[:m])) / m * 1e6
        the = best(lambda: coolprop_loop(ASHE, p[:m], h[:m])) / m * 1e6
        print(f"{'Water':<10} {n:>7} {t:>10.2f} {t97:>10.2f} {the:>10.2f}")
    ASN = CP.AbstractState("HEOS", "Nitrogen")
    for n in sizes:
        T = np.linspace(300.0, 1800.0, n)
        p = np.full(n, 1e5)
        h = fg.h_T(T)
        fg.transport(p, h)
        t = best(lambda: fg.transport(p, h)) / n * 1e6
        m = min(n, 2000)
        tn = best(lambda: coolprop_pt_loop(ASN, p[:m], T[:m])) / m * 1e6
        print(f"{'FlueGas':<10} {n:>7} {t:>10.2f} {'-':>10} {tn:>10.2f}  (CP: HEOS N2)")
    print()
    print("first use in a fresh process (CPU s): import + get_medium('Water'), first transport:")
    print("  " + first_call())


if __name__ == "__main__":
    main()
