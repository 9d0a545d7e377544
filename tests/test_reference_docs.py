"""docs/components.md is the library's own description, regenerated, not hand-kept."""

from pathlib import Path

from dnasim.tools.reference import component_reference_markdown


def test_component_reference_is_up_to_date():
    committed = (Path(__file__).resolve().parent.parent / "docs" / "components.md").read_text()
    assert committed == component_reference_markdown(), (
        "docs/components.md is stale: run `python -m dnasim.tools.reference > docs/components.md`"
    )
