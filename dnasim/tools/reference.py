"""The component reference, generated from the library: ``python -m dnasim.tools.reference``.

It writes Markdown with, for every component type of the library (not plugins), exactly what
``dnasim components NAME`` prints (ports, parameters with units, defaults and
ranges, equations). ``docs/components.md`` is this module's output; a test keeps
the two in step.
"""

from __future__ import annotations

import sys


def component_reference_markdown() -> str:
    """Markdown text of the whole component library."""
    from dnasim.plant.plantfile import _registry, component_info
    from dnasim.run.runner import format_component

    registry = _registry()
    parts = [
        "# Component reference",
        "",
        "Generated from the library by `python -m dnasim.tools.reference > docs/components.md`;",
        "`dnasim components NAME` prints the same for one type. All quantities in SI units.",
        "",
    ]
    library = [n for n in sorted(registry) if registry[n].__module__.startswith("dnasim.")]
    for name in library:  # plugins document themselves
        info = component_info(registry[name])
        parts += [f"## {name}", "", "```", format_component(info).rstrip(), "```", ""]
    return "\n".join(parts)


if __name__ == "__main__":
    sys.stdout.write(component_reference_markdown())
