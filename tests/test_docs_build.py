"""The documentation site builds without a warning (``mkdocs build --strict``).

mkdocstrings reads every API page's modules (docs/api/*.md) statically: a module that
was moved or renamed, a broken link between pages or a page missing from the nav fails
here. mkdocs is in the dev extra, so CI has it.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytest.importorskip("mkdocs")
pytest.importorskip("mkdocstrings")


def test_site_builds_strictly(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    page = (tmp_path / "site" / "api" / "plant" / "index.html").read_text()
    assert "build_plant" in page and "load_plant" in page  # the API pages have content
    assert (tmp_path / "site" / "tutorial" / "index.html").exists()
