"""Exception types shared by every layer of dnasim.

This module imports nothing from the rest of the package, so the solver, the
media, the components and the command line can all raise and catch the same
types without depending on each other.
"""

import re
from collections.abc import Sequence


class DnasimError(Exception):
    """Base class of every error dnasim raises on purpose."""


class DAEError(DnasimError):
    """The DAE solver cannot go on: bad input, a singular system, a failed step."""


class ResidualDomainError(DnasimError):
    """A residual evaluation hit a state outside its model's domain.

    Raised from inside ``residual(t, y, yp)`` (for instance when a fluid
    property library refuses a state during a Newton iteration). The solver
    treats it like a failed Newton iteration and cuts the step; only when it
    persists is it reported to the user, with this exception's message.
    """


class PlantError(DnasimError):
    """A plant description is invalid (structure, parameters, connections)."""


class OutputError(DnasimError):
    """A result file cannot be created or written (disk full, file size limit,
    a directory or a foreign file in its place, no permission).

    ``path`` is the file, ``t_reached`` the simulated time [s] of the last whole
    row on disk (None: no row), ``rows`` the number of whole rows on disk.
    This is an environment problem, not a bug: the command line exits with 2.
    """

    def __init__(self, message: str, path=None, t_reached=None, rows: int = 0):
        super().__init__(message)
        self.path = path
        self.t_reached = t_reached
        self.rows = rows


class Problems:
    """Collects problems; each is one paragraph naming file, table, key and (with a
    line index, see ``dnasim.plant.plantfile``) line. ``raise_if_any`` raises one
    ``PlantError`` whose message joins them, one paragraph each."""

    def __init__(self, path: str, lines=None):
        self.path = path
        self.lines = lines
        self.items: list[str] = []

    def add(self, table: Sequence[str], key: str | None, message: str) -> None:
        where = [self.path]
        table = tuple(table)
        if table:
            where.append("[" + ".".join(_quote_key(k) for k in table) + "]")
        if key is not None:
            where.append(f"key '{key}'")
        line = self.lines.find(table, key) if self.lines else None
        if line:
            where.append(f"line {line}")
        self.items.append(", ".join(where) + ": " + message)

    def raise_if_any(self) -> None:
        if self.items:
            err = PlantError("\n\n".join(self.items))
            err.errors = list(self.items)
            raise err


def _quote_key(k: str) -> str:
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else '"' + k + '"'
