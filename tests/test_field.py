"""Field tests (issue 7): plant files written as a user writes them, run to the end
through the CLI and judged against physics (see tests/field_checks.py).

Each plant in tests/field/ must finish (exit 0, t_end reached), close its mass and
energy balances over the whole run to 1e-6 of the throughput, and pass its own
checks (closed forms, hand calculations with CoolProp's IF97, maximum principle).
The 1000-volume pipes carry the marker ``field_slow``: ``pytest -m field_slow`` runs
them alone, ``-m "not field_slow"`` skips them; CI runs everything.
"""

import pytest
from field_checks import CASES, evaluate, run_plant


def _param(case):
    marks = [pytest.mark.field_slow] if case.slow else []
    return pytest.param(case, id=case.name, marks=marks)


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_field_plant(case, tmp_path):
    run = run_plant(case.name, tmp_path / case.name)
    checks = evaluate(case, run)
    failed = [f"{name}: {detail}" for name, ok, detail in checks if not ok]
    assert not failed, f"{case.name}:\n  " + "\n  ".join(failed)
