"""Microseconds per ``Medium.state(p, h)`` call for each backend of dnasim.media.

Run:  .venv/bin/python benchmarks/media_speed.py [--n N]

"miss": every call has a new h (h + k * 1 mJ/kg), so the cache never hits and
each call is one full evaluation (T, rho, u, s, cp, quality and both
derivatives). "hit": the same (p, h) again, i.e. a dict lookup. Each figure is
the best of three runs (the machine may be shared). For
comparison, ``PropsSI`` is timed for the *single* output T from (H, P), which
is the cheapest thing PropsSI can do; a full state through PropsSI costs about
five times that.
"""

from __future__ import annotations

import argparse
import datetime
import platform
import time

import CoolProp
import CoolProp.CoolProp as CP

from dnasim.media import get_medium

WATER_STATES = {
    "liquid": (1e6, 4.0e5),  # 1 MPa, 95 degC
    "two-phase": (1e6, 1.5e6),  # 1 MPa, x = 0.31
    "vapour": (1e6, 3.0e6),  # 1 MPa, 280 degC
    "supercrit.": (25e6, 2.0e6),  # 25 MPa, 655 K (IF97 region 3)
}
AIR_STATE = (1e5, 3.0e4)  # 1 bar, 303 K


def time_misses(fn, p, h, n, repeats=3):
    """us per call of fn(p, h_k) with a new h_k each call (best of ``repeats``); nan if fn fails."""
    try:
        fn(p, h)
    except (ValueError, IndexError):  # CoolProp's own IF97 (p, h) flash fails in region 3 above p_c
        return float("nan")
    best = float("inf")
    for r in range(repeats):
        hs = [h + 1e-3 * (k + r * n + 1) for k in range(n)]
        t0 = time.perf_counter()
        for hk in hs:
            fn(p, hk)
        best = min(best, (time.perf_counter() - t0) / n * 1e6)
    return best


def time_hits(fn, p, h, n, repeats=3):
    fn(p, h)
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn(p, h)
        best = min(best, (time.perf_counter() - t0) / n * 1e6)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--n", type=int, default=2000, help="calls per (backend, state) for the fast backends"
    )
    args = ap.parse_args()
    n = args.n

    t0 = time.perf_counter()
    bicubic = get_medium("Water", backend="BICUBIC&HEOS")
    bicubic.state(1e5, 1e5)  # triggers loading (or building) the tables
    t_bicubic = time.perf_counter() - t0
    t0 = time.perf_counter()
    ttse = get_medium("Water", backend="TTSE&HEOS")
    ttse.state(1e5, 1e5)
    t_ttse = time.perf_counter() - t0

    rows = []
    media = [
        ("IF97 water", get_medium("Water"), n),
        ("HEOS water", get_medium("Water", backend="HEOS"), max(n // 10, 50)),
        ("BICUBIC&HEOS water", bicubic, n),
        ("TTSE&HEOS water", ttse, n),
    ]
    for label, medium, nn in media:
        medium.cache_clear()
        misses = [time_misses(medium.state, p, h, nn) for p, h in WATER_STATES.values()]
        hit = time_hits(medium.state, *WATER_STATES["liquid"], 20 * n)
        rows.append((label, misses, hit))

    air = get_medium("Air")
    air.cache_clear()
    rows.append(
        (
            "ideal-gas air",
            [time_misses(air.state, *AIR_STATE, 10 * n)] + [None] * 3,
            time_hits(air.state, *AIR_STATE, 20 * n),
        )
    )

    for backend in ("IF97", "HEOS"):
        fluid = f"{backend}::Water"

        def props(p, h, fluid=fluid):
            return CP.PropsSI("T", "H", h, "P", p, fluid)

        nn = n if backend == "IF97" else max(n // 10, 50)
        rows.append(
            (
                f"PropsSI T only, {backend}",
                [time_misses(props, p, h, nn) for p, h in WATER_STATES.values()],
                None,
            )
        )

    # the raw low-level flash, for reference: update(HmassP) + T() + rhomass()
    for backend in ("IF97", "HEOS"):
        AS = CP.AbstractState(backend, "Water")

        def raw(p, h, AS=AS):
            AS.update(CP.HmassP_INPUTS, h, p)
            return AS.T(), AS.rhomass()

        nn = n if backend == "IF97" else max(n // 10, 50)
        misses = [time_misses(raw, p, h, nn) for p, h in WATER_STATES.values()]
        rows.append((f"raw AbstractState {backend} (T, rho)", misses, None))

    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    py = platform.python_version()
    print(
        f"dnasim.media speed, {now}; CoolProp {CoolProp.__version__}, "
        f"Python {py}, {platform.machine()}"
    )
    print(
        f"table load: BICUBIC&HEOS {t_bicubic:.2f} s, TTSE&HEOS {t_ttse:.2f} s (~/.CoolProp/Tables)"
    )
    print("us per state(p, h) call; miss = no cache hit (h varied each call); water states at")
    print(
        "  "
        + ", ".join(
            f"{k} (p={p / 1e6:g} MPa, h={h / 1e3:g} kJ/kg)" for k, (p, h) in WATER_STATES.items()
        )
    )
    print(f"  air: p={AIR_STATE[0] / 1e5:g} bar, h={AIR_STATE[1] / 1e3:g} kJ/kg")
    print("  nan: CoolProp's own IF97 (p, h) flash fails there (region 3 above p_c)")
    head = f"{'backend':34s}" + "".join(f"{k:>12s}" for k in WATER_STATES) + f"{'hit':>9s}"
    print(head)
    print("-" * len(head))
    for label, misses, hit in rows:
        cells = "".join(f"{'-':>12s}" if m is None else f"{m:12.1f}" for m in misses)
        print(f"{label:34s}{cells}" + (f"{hit:9.2f}" if hit is not None else f"{'-':>9s}"))


if __name__ == "__main__":
    main()
