"""Fingerprints of every plant in plants/: a sha256 over the result arrays and the
solver counters, to show that a refactoring keeps every number to the bit.

    python benchmarks/bit_identity.py > before.txt     # on the old revision
    python benchmarks/bit_identity.py > after.txt      # on the new one
    python benchmarks/bit_identity.py --compare before.txt after.txt

Each plant runs through ``dnasim.load_plant(path).simulate(t_end)``, with its file's
settings, to its file's t_end (cut at ``T_END_MAX`` seconds of plant time). The
digest covers t, the restart flags, every output column (sorted by name), the
solver's y and yp, the events and the steps; the counters are printed beside it
(steps, residual evaluations, Jacobians, LU decompositions). The plants are those of
plants/, tests/plants/ and tests/field/ (names prefixed with their folder); a plant
that fails to load or run is fingerprinted by its error's type and message.
"""

from __future__ import annotations

import hashlib
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
T_END_MAX = 7200.0  # s of plant time per plant (longer ones would be cut; none is today)


def digest(res) -> str:
    h = hashlib.sha256()

    def add(a):
        a = np.ascontiguousarray(np.asarray(a, dtype=float))
        h.update(str(a.shape).encode())
        h.update(a.tobytes())

    add(res.t)
    add(np.asarray(res.restart, dtype=float))
    for name in sorted(res):
        h.update(name.encode())
        add(res[name])
    for extra in ("y", "yp"):
        val = getattr(res, extra, None)
        if val is not None:
            add(val)
    h.update(repr(getattr(res, "events", None)).encode())
    steps = getattr(res, "steps", None)
    if steps is not None:
        h.update(repr(steps).encode())
    return h.hexdigest()[:16]


def run(path: Path) -> tuple[str, str, float, float]:
    import dnasim

    try:
        plant = dnasim.load_plant(path)
    except Exception as err:  # noqa: BLE001 - an input error is a result too
        msg = f"{type(err).__name__}: {err}"
        return hashlib.sha256(msg.encode()).hexdigest()[:16], "load error", 0.0, 0.0
    t_end = min(plant.simulation.t_end, T_END_MAX)
    c0 = time.process_time()
    try:
        res = plant.simulate(t_end)
    except Exception as err:  # noqa: BLE001 - a refused run is a result too
        msg = f"{type(err).__name__}: {err}"
        return hashlib.sha256(msg.encode()).hexdigest()[:16], "run error", 0.0, t_end
    cpu = time.process_time() - c0
    st = res.stats
    counts = "steps={} res={} jac={} lu={}".format(
        st.get("steps"), st.get("residual_evals"), st.get("jac_evals"), st.get("lu_decomps")
    )
    return digest(res), counts, cpu, t_end


def table(path) -> dict[str, str]:
    """plant -> the rest of its line (t_end, digest, counts, cpu) of a file this
    script printed; other lines (a shell's timing) are left out."""
    out = {}
    for line in Path(path).read_text().splitlines()[1:]:
        if line.count("\t") >= 3:
            name, rest = line.split("\t", 1)
            out[name] = rest
    return out


def main(argv):
    if argv[:1] == ["--compare"]:
        before, after = table(argv[1]), table(argv[2])
        print("| plant | before | after | identical |")
        print("|---|---|---|---|")
        for name in sorted(set(before) | set(after)):
            b = before.get(name, "-").split("\t")
            a = after.get(name, "-").split("\t")
            same = b[:3] == a[:3]
            print(f"| {name} | {' '.join(b[:3])} | {' '.join(a[:3])} | {'yes' if same else 'NO'} |")
        return 0
    paths = []
    for folder in ("plants", "tests/plants", "tests/field"):
        paths += sorted((ROOT / folder).glob("*.toml"))
    if argv:
        paths = [p for p in paths if p.stem in argv]
    print("plant\tt_end\tdigest\tcounts\tcpu_s")
    for p in paths:
        d, counts, cpu, t_end = run(p)
        name = str(p.relative_to(ROOT).with_suffix(""))
        print(f"{name}\t{t_end:g}\t{d}\t{counts}\t{cpu:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
