"""How the System evaluates a component: its view of the plant-wide vectors
(``LocalVector``) and the unit that evaluates the scalar rows of many components at
once (``ScalarRows``, for the components with ``Component.row_reads``; their
``batch_key`` is ``ROWS_KEY``). ``dnasim.compilation.system`` builds both from its
blocks; ``dnasim.model.component`` re-exports every name here.
"""

from __future__ import annotations

import numpy as np

from dnasim.core.errors import PlantError

__all__ = ["LocalVector", "ROWS_KEY", "ScalarRows"]


class LocalVector:
    """A component's view of the global vector: ``x["inlet.p"]``, ``x["M"]``.

    Scalars come back as floats, vector variables as numpy arrays (views).
    Assignment writes through (used for initial guesses). ``modes``: the
    component's discrete modes (a dict owned by the ``System``; e.g. a
    controller's "free"/"high"/"low"), read and written by the component.
    """

    __slots__ = ("data", "index", "modes", "work")

    def __init__(self, data: np.ndarray, index: dict, modes: dict | None = None):
        self.data = data
        self.index = index
        self.modes = {} if modes is None else modes
        #: what ``Component.prepare`` computed for this evaluation (None without it)
        self.work = None

    def __getitem__(self, name):
        k = self.index[name]
        if isinstance(k, slice):
            return self.data[k]
        return float(self.data[k])

    def __setitem__(self, name, value):
        self.data[self.index[name]] = value

    def __contains__(self, name):
        return name in self.index


#: the ``Component.batch_key`` of components evaluated by ``ScalarRows``, whatever their class
ROWS_KEY = "ScalarRows"


class ScalarRows:
    """The residual rows of several components with ``row_reads``, evaluated as one
    unit of the System (``dnasim.compilation.system.evaluation_units``): the values each one reads
    gathered from the plant-wide y and y' through index arrays made once (one gather and
    one ``tolist`` for all of them), each component's ``row_values`` on its part, and
    all rows written into F at once. Each such component writes its equations once,
    in ``row_values`` (on plain floats); its ``equations()`` declare their names,
    dependencies, units and docs without residual functions, and its
    ``Component.residual`` (the path of tests and of callers outside the System's
    evaluation) looks the names of ``row_reads`` up in x, xp and calls the same
    ``row_values``, so both paths give the same rows to the bit
    (tests/test_scalar_rows.py).

    ``blocks``: the System's ``ComponentBlock``s (component, local -> global indices
    ``gidx``, local names ``index``, rows ``eq_slice``, discrete ``modes``)."""

    def __init__(self, blocks):
        self.blocks = list(blocks)
        #: the components' names, in the order of their rows (as ``PipeBatch.names``)
        self.names = [b.comp.name for b in self.blocks]
        y_at, yp_at, rows, self.items = [], [], [], []
        for b in self.blocks:
            reads_y, reads_yp = b.comp.row_reads()
            sy = slice(len(y_at), len(y_at) + len(reads_y))
            syp = slice(len(yp_at), len(yp_at) + len(reads_yp))
            y_at += [b.gidx[_position(b, name)] for name in reads_y]
            yp_at += [b.gidx[_position(b, name)] for name in reads_yp]
            rows += range(b.eq_slice.start, b.eq_slice.stop)
            self.items.append((b.comp.row_values, sy, syp, b.modes))
        self.y_at = np.array(y_at, dtype=np.intp)
        self.yp_at = np.array(yp_at, dtype=np.intp)
        self.rows = np.array(rows, dtype=np.intp)

    def residual_into(self, t, y, yp, F) -> None:
        """F[rows of the components] = their residuals at (t, y, y') (global vectors)."""
        v = y[self.y_at].tolist()
        vp = yp[self.yp_at].tolist()
        out = []
        for values, sy, syp, modes in self.items:
            out += values(t, v[sy], vp[syp], modes)
        if len(out) != self.rows.size:
            self._count_error(t, v, vp)
        F[self.rows] = out

    def _count_error(self, t, v, vp):
        for b, (values, sy, syp, modes) in zip(self.blocks, self.items, strict=True):
            n, declared = len(values(t, v[sy], vp[syp], modes)), b.eq_slice.stop - b.eq_slice.start
            if n != declared:
                raise PlantError(
                    f"component '{b.comp.name}' ({type(b.comp).__name__}): row_values gave {n} "
                    f"residuals but it declares {declared} equations"
                )


def _position(block, name) -> int:
    """The local position of ``name`` in a System block (a scalar: not a whole vector)."""
    k = block.index.get(name)
    if k is None or isinstance(k, slice):
        raise PlantError(
            f"component '{block.comp.name}' ({type(block.comp).__name__}): row_reads names "
            f"'{name}', which is not one of its scalar variables, port values or signal inputs"
        )
    return k
