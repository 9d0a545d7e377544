"""Old module paths keep working after the move into stage packages (docs/architecture.md).

Each old path of ``MOVED`` is imported in a fresh interpreter (so that nothing is cached
from another test): it must give the very module object of its new path, and warn
with a ``DeprecationWarning`` that names the new path.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from dnasim.moved_modules import MOVED

SCRIPT = r"""
import importlib, json, sys, warnings
import dnasim
from dnasim.moved_modules import MOVED
out = {}
for old, new in MOVED.items():
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m_old = importlib.import_module(old)
    m_new = importlib.import_module(new)
    out[old] = [m_old is m_new, [str(x.message) for x in w if x.category is DeprecationWarning]]
print(json.dumps(out))
"""


def test_every_old_path_is_the_new_module_with_a_warning():
    got = json.loads(
        subprocess.run(
            [sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True
        ).stdout
    )
    assert set(got) == set(MOVED)
    for old, (same, warnings) in got.items():
        assert same, old
        assert any(MOVED[old] in w for w in warnings), (old, warnings)


def test_packages_that_replaced_modules_hand_out_the_old_names():
    from dnasim.cli import main
    from dnasim.cli.commands import main as main_new
    from dnasim.plant import Plant
    from dnasim.plant.plant import Plant as PlantNew
    from dnasim.start import initial_values
    from dnasim.start.initial import initial_values as iv_new

    assert Plant is PlantNew and initial_values is iv_new and main is main_new
    import dnasim.plant

    assert dnasim.plant.graph.__name__ == "dnasim.plant.graph"  # a submodule, not a name
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        dnasim.plant.nonexistent  # noqa: B018


def test_an_old_component_path_builds_the_same_class():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        from dnasim.components.pipe import Pipe as OldPipe
    from dnasim.library.pipe import Pipe

    assert OldPipe is Pipe
