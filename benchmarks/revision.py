"""A module of dnasim as it was at another git revision, for benchmarks that time the
current code against it (``media_speed.py``, ``pipe_residual.py``)."""

from __future__ import annotations

import importlib.util
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def file_at(rev: str, path: str) -> str | None:
    """The text of the file ``path`` (relative to the repository) at git revision
    ``rev``; None when git cannot show it (no repository, unknown rev or path)."""
    try:
        return subprocess.run(
            ["git", "-C", str(ROOT), "show", f"{rev}:{path}"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    except (OSError, subprocess.CalledProcessError):
        return None


def module_at(rev: str, path: str, name: str):
    """The file ``path`` (relative to the repository) of git revision ``rev``, imported
    as module ``name``; None when git cannot show it (no repository, unknown rev). The
    source is written to a fresh temporary directory, which is kept: numba's cache
    keys on the file."""
    src = file_at(rev, path)
    if src is None:
        return None
    file = Path(tempfile.mkdtemp()) / f"{name}.py"
    file.write_text(src)
    spec = importlib.util.spec_from_file_location(name, file)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod
