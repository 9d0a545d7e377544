"""The docs against the code: names resolve, examples run (issue 24 item 6).

Every dotted ``dnasim.…`` name in README.md and docs/*.md must import (module, class,
function or attribute): a renamed module or a removed function fails here, not in a
reader's notebook. Every ```python block of the README and docs/*.md runs, in a
scratch folder with the repository's plant files, in the order of the page (a block may
use what an earlier one made), with the few names a snippet takes as given defined
first (docs/tutorial.md's block has its own test, tests/test_tutorial.py).
"""

from __future__ import annotations

import importlib
import re
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

#: what a snippet takes as given (the page says so in its text)
GIVEN = {
    "docs/correlations.md": "p, h = 40e5, 3.2e6\n",
    "docs/plant_files.md": (
        "import numpy as np\n"
        "import subprocess, sys\n"
        "subprocess.run([sys.executable, '-m', 'dnasim', 'run', 'plants/attemperator.toml',"
        " '-o', 'results/attemperator', '-q'], check=True)\n"
    ),
}


def _resolves(name: str) -> bool:
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for a in parts[i:]:
                obj = getattr(obj, a)
        except AttributeError:
            return False
        return True
    return False


def test_every_dnasim_name_in_the_docs_resolves():
    names = set()
    for page in PAGES:
        names |= {
            (page.name, m.rstrip("."))
            for m in re.findall(r"\bdnasim(?:\.[A-Za-z_]\w*)+", page.read_text())
        }
    bad = sorted(f"{page}: {n}" for page, n in names if not _resolves(n))
    assert not bad, "names in the docs that do not resolve:\n" + "\n".join(bad)


def test_the_check_finds_a_stale_name():
    assert _resolves("dnasim.plant.plant.Plant")
    assert not _resolves("dnasim.network.Plant")  # the name the docs had until issue 24
    assert not _resolves("dnasim.plant.plant.Nothing")


def _blocks(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


@pytest.mark.parametrize(
    "page",
    [p for p in PAGES if _blocks(p) and p.name != "tutorial.md"],
    ids=lambda p: p.name,
)
def test_the_pages_python_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plants").symlink_to(ROOT / "plants")
    rel = str(page.relative_to(ROOT))
    env: dict = {"__name__": "__docs__"}
    exec(compile(GIVEN.get(rel, ""), f"{rel} (given)", "exec"), env)
    blocks = _blocks(page)
    if rel == "docs/sweeps.md":  # the sweep makes the sweep.nc the first block opens
        blocks = blocks[1:] + blocks[:1]
    for i, block in enumerate(blocks):
        exec(compile(block, f"{rel}, python block {i + 1}", "exec"), env)
