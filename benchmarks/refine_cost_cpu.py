"""CPU of the output points between steps decided before the solve (``choose``) against
solved first (``choose0``): the least of ``--repeat`` runs of each way
(``refine_cost.run_way``, time.process_time of the run with its start).

    .venv/bin/python benchmarks/refine_cost_cpu.py tests/plants/pump_shutoff.toml \\
        plants/drum_boiler.toml plants/msl_drum_boiler.toml
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import refine_cost as rc  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("plants", nargs="+", help="plant files")
    ap.add_argument("--t-end", type=float, default=1e9, help="longest span [s] (default 1e9)")
    ap.add_argument("--repeat", type=int, default=3, help="runs of each way (default 3)")
    args = ap.parse_args(argv)
    for plant in args.plants:
        cpu = {"choose0": [], "choose": []}
        for _ in range(args.repeat):
            for w in cpu:
                cpu[w].append(rc.run_way(Path(plant), args.t_end, w)["cpu"])
        a, b = min(cpu["choose0"]), min(cpu["choose"])
        print(
            f"{Path(plant).stem:<18} choose0 {a:.2f} s  choose {b:.2f} s  ratio {b / a:.2f}  "
            f"(least of {args.repeat})",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
