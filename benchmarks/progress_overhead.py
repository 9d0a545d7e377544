"""CPU cost of the progress bar (tqdm, ``simulate(progress=True)``) on a cheap run with
many output points: plants/air_pipe.toml to 100 s with an output point every 5 ms
(20001 points). The bar is drawn into a StringIO (no terminal I/O counted). Least CPU
of N repeats (time.process_time), without and with the bar, and the ratio; the bar's
updates counted (at most 1000 a run and the end).

    python benchmarks/progress_overhead.py [--repeat N]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    import dnasim
    from dnasim.plant.plantfile import load
    from dnasim.run import progress

    system = dnasim.compile(load(ROOT / "plants" / "air_pipe.toml").plant)
    dnasim.simulate(system, t_end=5.0)  # imports and caches before the clock

    counted = {"updates": 0}
    tqdm_class = progress._tqdm_class()

    class Counting(tqdm_class):
        def update(self, n=1):
            counted["updates"] += 1
            return super().update(n)

    progress._tqdm_class = lambda: Counting

    def cpu(with_bar: bool) -> tuple[float, int]:
        with contextlib.redirect_stderr(io.StringIO()):
            t0 = time.process_time()
            res = dnasim.simulate(system, t_end=100.0, output_interval=0.005, progress=with_bar)
            return time.process_time() - t0, len(res.t)

    cpu(True)  # tqdm imported before the clock
    off, on = [], []
    for _ in range(args.repeat):
        off.append(cpu(False)[0])
        counted["updates"] = 0
        t, points = cpu(True)
        on.append(t)
    updates = counted["updates"]
    print(f"air_pipe to 100 s, {points} output points, least CPU of {args.repeat}")
    print("| bar | CPU [s] | ratio | bar updates |")
    print("|---|---|---|---|")
    print(f"| off | {min(off):.3f} | 1.000 | 0 |")
    print(f"| on | {min(on):.3f} | {min(on) / min(off):.3f} | {updates} |")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
