"""CPU cost of compile's one-way copy (``compiler.own_components``, issue 21) for the
plants of plants/: compile with the copy, compile with the copy replaced by the plant
itself (the old behaviour; its components then keep their caches from the compile
before, so this is a lower bound), and the copy alone. Best of 5 (20 for the copy),
``time.process_time``.

    python benchmarks/compile_copy_cost.py
"""

from __future__ import annotations

import time
from pathlib import Path

import dnasim.compilation.compiler as C
from dnasim.plant.plantfile import load

ROOT = Path(__file__).resolve().parent.parent


def best(f, n):
    out = float("inf")
    for _ in range(n):
        t = time.process_time()
        f()
        out = min(out, time.process_time() - t)
    return out


def main():
    real = C.own_components
    print(f"{'plant':28s} {'compile [ms]':>13s} {'no copy [ms]':>13s} {'copy [ms]':>10s}")
    for path in sorted((ROOT / "plants").glob("*.toml")):
        plant = load(path).plant
        C.compile(plant)
        with_copy = best(lambda: C.compile(plant), 5)
        C.own_components = lambda p: p
        try:
            without = best(lambda: C.compile(plant), 5)
        finally:
            C.own_components = real
        copy = best(lambda: real(plant), 20)
        print(f"{path.stem:28s} {with_copy * 1e3:13.1f} {without * 1e3:13.1f} {copy * 1e3:10.2f}")


if __name__ == "__main__":
    main()
