"""Results on disk: streaming CSV while the run goes on, events and steps CSV, PNG plots.

Nothing is lost when a run stops early: :class:`StreamingCSV` keeps its own
buffer of *complete* lines and hands it to the operating system in one
``write`` every ``flush_rows`` rows or ``flush_seconds`` seconds, so the file on
disk always ends with a whole row, even when the process is killed. ``close``
flushes and ``fsync``s.

Nothing stale, nothing torn, nothing followed:

- :func:`clear_results` removes a previous run's files (``RESULT_FILES``) before a
  new run starts, so a run that fails early never leaves old results behind;
- ``results.csv`` is created with ``O_CREAT | O_EXCL | O_NOFOLLOW`` after that
  removal: a symbolic link (or any file) planted in its place is never followed;
  the small tables and the plots go to a fresh temporary file in the same
  directory (``mkstemp``, also ``O_EXCL``) that is renamed over the target, and a
  rename replaces a link instead of writing through it;
- when a write fails (disk full ``ENOSPC``, file size limit ``EFBIG``, ...) the
  file is truncated back to its last whole row and an
  :class:`~dnasim.core.errors.OutputError` names the file and the time of that row.

matplotlib is imported only inside the plotting functions (Agg backend), so
``dnasim --help`` does not pay for it.
"""

from __future__ import annotations

import csv
import errno
import math
import os
import re
import tempfile
import time
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

__all__ = [
    "RESULT_FILES",
    "clear_results",
    "StreamingCSV",
    "column_header",
    "parse_column_header",
    "format_value",
    "read_results_csv",
    "write_events_csv",
    "write_steps_csv",
    "select_variables",
    "plot_steps",
    "EVENT_COLUMNS",
    "STEP_COLUMNS",
    "spreadsheet_safe",
    "spreadsheet_frame",
]

EVENT_COLUMNS = ("event", "iteration", "time", "switch_value", "component", "switch")
STEP_COLUMNS = ("time", "step_size", "order")

#: the files a run writes into its output directory (removed before the next run)
RESULT_FILES = (
    "results.csv",
    "results.nc",
    "events.csv",
    "steps.csv",
    "variables.png",
    "steps.png",
    "report.txt",
    "report.html",
    "plant.json",
)

_O_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)


def _oserror_text(exc: OSError) -> str:
    if exc.errno == errno.ENOSPC:
        return "the disk is full (ENOSPC)"
    if exc.errno == errno.EFBIG:
        return "the file size limit is reached (EFBIG)"
    if exc.errno == getattr(errno, "EDQUOT", None):
        return "the disk quota is exceeded (EDQUOT)"
    return exc.strerror or str(exc)


def clear_results(out_dir: str | os.PathLike) -> list[Path]:
    """Remove a previous run's result files (``RESULT_FILES``) from ``out_dir``.

    A symbolic link is removed itself, never what it points to. Raises
    :class:`~dnasim.core.errors.OutputError` when one of them cannot be removed (a
    directory in its place, no permission). Returns the paths removed.
    """
    from dnasim.core.errors import OutputError

    out = Path(out_dir)
    removed = []
    for name in RESULT_FILES:
        path = out / name
        for leftover in (path, path.with_name(path.name + ".tmp")):
            try:
                os.unlink(leftover)
            except FileNotFoundError:
                continue
            except IsADirectoryError:
                raise OutputError(
                    f"{leftover} is a directory, where dnasim writes its {name}: remove it or "
                    "choose another output directory (-o DIR)",
                    path=leftover,
                ) from None
            except OSError as exc:
                if os.path.isdir(leftover) and not os.path.islink(leftover):
                    raise OutputError(
                        f"{leftover} is a directory, where dnasim writes its {name}: remove it "
                        "or choose another output directory (-o DIR)",
                        path=leftover,
                    ) from None
                raise OutputError(
                    f"cannot remove the previous run's {leftover}: {_oserror_text(exc)}",
                    path=leftover,
                ) from None
            removed.append(leftover)
    return removed


def column_header(name: str, unit: str | None) -> str:
    """``pipe1.T_out [K]``; a dimensionless quantity gets ``[-]``."""
    if unit is None or unit == "":
        unit = "-"
    if unit == "1":
        unit = "-"
    return f"{name} [{unit}]"


_HEADER_RE = re.compile(r"^(.*?)\s*\[([^\[\]]*)\]\s*$")


def parse_column_header(header: str) -> tuple[str, str]:
    """Inverse of :func:`column_header`: ``"pipe1.T_out [K]"`` -> ``("pipe1.T_out", "K")``."""
    m = _HEADER_RE.match(header)
    if m:
        return m.group(1), m.group(2)
    return header.strip(), ""


def format_value(x) -> str:
    """Shortest text that reads back as the same float (``repr``), empty for missing."""
    if x is None:
        return ""
    x = float(x)
    if math.isnan(x):
        return "nan"
    return repr(x)


class _SignalsBlocked:
    """Hold SIGINT/SIGTERM back while whole lines go to disk (main thread, POSIX).

    The signal is delivered, and its Python handler runs, right after the block:
    a Ctrl-C can stop a run between two flushes but never in the middle of one.
    """

    def __enter__(self):
        import signal
        import threading

        self.old = None
        if (
            hasattr(signal, "pthread_sigmask")
            and threading.current_thread() is threading.main_thread()
        ):
            self.old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        return self

    def __exit__(self, *exc):
        if self.old is not None:
            import signal

            signal.pthread_sigmask(signal.SIG_SETMASK, self.old)


class StreamingCSV:
    """A CSV file written row by row while a simulation runs.

    >>> with StreamingCSV("out.csv", ["time [s]", "pipe.T_out [K]"]) as w:  # doctest: +SKIP
    ...     w.write_row([0.0, 300.0])

    Rows are kept in memory as complete lines and written with ``os.write`` every
    ``flush_rows`` rows or ``flush_seconds`` seconds, whichever comes first, with
    SIGINT and SIGTERM held back during the write. The file therefore always holds
    the header and a whole number of rows, and ``last_time`` is the time of the last
    row on disk (the first column).
    """

    def __init__(
        self,
        path: str | os.PathLike,
        header: Sequence[str],
        *,
        flush_rows: int = 200,
        flush_seconds: float = 1.0,
    ):
        self.path = Path(path)
        self.header = list(header)
        self.ncols = len(self.header)
        self.flush_rows = max(1, int(flush_rows))
        self.flush_seconds = float(flush_seconds)
        self.rows_written = 0  # rows on disk
        self.last_time: float | None = None  # first column of the last row on disk
        self._pending: list[tuple[float, Sequence[float]]] = []  # (t, row values)
        self._last_flush = time.monotonic()
        self._size = 0  # bytes of whole lines on disk
        self._fd: int | None = None
        try:
            # a fresh file: an existing file or a planted symbolic link is an error,
            # never overwritten or followed (the caller removes the old results first)
            self._fd = os.open(
                self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_NOFOLLOW | os.O_CLOEXEC, 0o644
            )
        except FileExistsError:
            raise self._error(
                "it already exists (another process created it after the old results were "
                "removed?); it was not overwritten"
            ) from None
        except OSError as exc:
            raise self._error(_oserror_text(exc)) from None
        with _SignalsBlocked():
            self._write_all(_csv_line(self.header))

    def _error(self, why: str, reached: float | None = None):
        from dnasim.core.errors import OutputError

        if self.last_time is None:
            where = "before the first row"
        else:
            where = (
                f"after {self.rows_written} whole rows, at simulated time t = "
                f"{self.last_time:.6g} s"
            )
        if reached is not None and reached != self.last_time:
            where += f" (the simulation had reached t = {reached:.6g} s)"
        return OutputError(
            f"cannot write {self.path}: {why}; the file stops {where}",
            path=self.path,
            t_reached=self.last_time,
            rows=self.rows_written,
        )

    def _write_all(self, text: str) -> None:
        """Write whole lines; on failure cut the file back to the last whole line,
        close it and raise ``OutputError``."""
        try:
            self._write_or_cut(text)
        except OSError as exc:
            reached = self._pending[-1][0] if self._pending else None
            self._give_up(exc, reached)

    def _write_or_cut(self, text: str) -> None:
        """Write ``text`` (whole lines); on an OSError cut the file back to the last
        whole line on disk and re-raise, the file left open."""
        data = text.encode("utf-8")
        view = memoryview(data)
        try:
            while view:
                n = os.write(self._fd, view)
                view = view[n:]
        except OSError:
            try:
                os.ftruncate(self._fd, self._size)
                os.lseek(self._fd, self._size, os.SEEK_SET)
            except OSError:
                pass
            raise
        self._size += len(data)

    def _give_up(self, exc: OSError, reached: float | None):
        self._pending = []
        fd, self._fd = self._fd, None
        try:
            os.close(fd)
        except OSError:
            pass
        raise self._error(_oserror_text(exc), reached) from None

    @property
    def closed(self) -> bool:
        return self._fd is None

    def write_row(self, values: Sequence[float]) -> None:
        if self._fd is None:
            raise ValueError(f"{self.path} is closed")
        if len(values) != self.ncols:
            raise ValueError(f"row of {len(values)} values for {self.ncols} columns in {self.path}")
        # kept as floats; formatted a block at a time in ``flush`` (``_format_rows``)
        self._pending.append((float(values[0]), values))
        if (
            len(self._pending) >= self.flush_rows
            or time.monotonic() - self._last_flush >= self.flush_seconds
        ):
            self.flush()

    def flush(self) -> None:
        """Hand the buffered rows to the operating system, whole lines only."""
        if self._fd is None:
            return
        with _SignalsBlocked():
            if self._pending:
                rows = _format_rows(self._pending)
                try:
                    self._write_or_cut("".join(line for _, line in rows))
                    self.rows_written += len(rows)
                    self.last_time = rows[-1][0]
                except OSError:
                    # The block did not fit (disk full, file size limit): keep as many
                    # whole rows of it as still fit, one at a time, then report.
                    reached = rows[-1][0]
                    for k, (t_row, line) in enumerate(rows):
                        try:
                            self._write_or_cut(line)
                        except OSError as exc:
                            self._pending = rows[k:]
                            self._give_up(exc, reached)
                        self.rows_written += 1
                        self.last_time = t_row
                self._pending = []
            self._last_flush = time.monotonic()

    def close(self) -> None:
        """Flush, fsync and close. Safe to call twice. A failed final write raises
        :class:`~dnasim.core.errors.OutputError` (the file then ends with a whole row)."""
        if self._fd is None:
            return
        try:
            self.flush()
            if self._fd is not None:
                try:
                    os.fsync(self._fd)
                except OSError:
                    pass
        finally:
            if self._fd is not None:
                os.close(self._fd)
                self._fd = None

    def __enter__(self) -> StreamingCSV:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self):  # pragma: no cover - last resort
        try:
            if getattr(self, "_fd", None) is not None:
                self.close()
        except Exception:
            pass


def _format_rows(pending: list) -> list[tuple[float, str]]:
    """(t, values) rows -> (t, CSV line): every value as ``format_value`` writes it
    (``repr`` of the float, the shortest text that reads back as the same number;
    "nan"). A block of rows of equal length is converted to floats in one numpy call
    and ``repr`` is mapped over Python floats, about 10 times faster than a
    ``format_value`` call per value; rows holding None (empty cells) take that path."""
    try:
        block = np.array([v for _, v in pending], dtype=float)
    except (TypeError, ValueError):  # None values or rows of unequal length
        return [(t, ",".join(format_value(x) for x in v) + "\n") for t, v in pending]
    if block.ndim != 2:
        return [(t, ",".join(format_value(x) for x in v) + "\n") for t, v in pending]
    rep = repr
    return [
        (t, ",".join(map(rep, row)) + "\n")
        for (t, _), row in zip(pending, block.tolist(), strict=True)
    ]


#: first characters that make a spreadsheet read a cell as a formula (OWASP, "CSV
#: injection"): = + - @, and tab and carriage return
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
_NUMBER_RE = re.compile(r"^[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf|nan|infinity)$", re.I)


def spreadsheet_safe(text: str) -> str:
    """``text`` as a CSV cell that a spreadsheet shows as text, never evaluates: a
    cell starting with = + - @, a tab or a carriage return gets a leading single
    quote (the OWASP rule), ``'=HYPERLINK(...)``. Numbers stay numbers: ``-1.5``,
    ``+2e5``, ``-inf`` are left as they are."""
    if text and text.startswith(FORMULA_START) and not _NUMBER_RE.match(text):
        return "'" + text
    return text


def spreadsheet_frame(frame):
    """A copy of a pandas DataFrame whose text cells and column names are
    ``spreadsheet_safe`` (numbers untouched), for ``to_csv``."""
    out = frame.copy()
    out.columns = [spreadsheet_safe(str(c)) for c in out.columns]
    for j in range(out.shape[1]):
        col = out.iloc[:, j]
        if col.dtype.kind not in "biufcmM":  # text (object or pandas' str dtype)
            out.iloc[:, j] = [spreadsheet_safe(v) if isinstance(v, str) else v for v in col]
    return out


def _csv_line(fields: Iterable) -> str:
    out = []
    for f in fields:
        s = spreadsheet_safe(str(f))
        if any(c in s for c in ',"\n\r'):
            s = '"' + s.replace('"', '""') + '"'
        out.append(s)
    return ",".join(out) + "\n"


def _atomic_write(path: str | os.PathLike, write) -> Path:
    """``write(file_object)`` into a fresh temporary file next to ``path`` (created
    with ``O_EXCL``, so nothing planted there is followed), fsync, then rename it
    over ``path`` (a rename replaces a symbolic link, it does not write through it).
    Failures raise :class:`~dnasim.core.errors.OutputError` naming ``path``; the
    temporary file is removed and ``path`` is left as it was."""
    from dnasim.core.errors import OutputError

    path = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {_oserror_text(exc)}", path=path) from None
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            try:
                os.fsync(f.fileno())
            except OSError as exc:
                if exc.errno in (errno.ENOSPC, errno.EFBIG, errno.EIO):
                    raise
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, IsADirectoryError) or (path.is_dir() and not path.is_symlink()):
            raise OutputError(f"cannot write {path}: it is a directory", path=path) from None
        raise OutputError(f"cannot write {path}: {_oserror_text(exc)}", path=path) from None
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path


def _write_table(path: str | os.PathLike, header: Sequence[str], rows: Iterable[Sequence]) -> None:
    """Write a small CSV completely: temporary file, fsync, rename."""

    def write(f):
        f.write(_csv_line(header).encode("utf-8"))
        for row in rows:
            f.write(
                _csv_line(
                    format_value(v) if isinstance(v, float) else ("" if v is None else v)
                    for v in row
                ).encode("utf-8")
            )

    _atomic_write(path, write)


def _split_event_name(entry: dict) -> tuple[str, str]:
    comp = entry.get("component")
    switch = entry.get("switch")
    name = entry.get("name") or ""
    if comp is None or switch is None:
        if "." in name:
            c, s = name.rsplit(".", 1)
        else:
            c, s = "", name
        comp = c if comp is None else comp
        switch = s if switch is None else switch
    return str(comp), str(switch)


def event_rows(event_log: Sequence[dict]) -> list[tuple]:
    """One row per iterate of each located discontinuity (the seed's Table 10.1).

    ``event`` numbers the discontinuities in the order they were located (1, 2, ...);
    ``iteration`` numbers the iterates of one location (1 is the last accepted step
    before the sign change, 2 the step that detected it, then the refinements).
    """
    rows = []
    for k, entry in enumerate(event_log, start=1):
        comp, switch = _split_event_name(entry)
        iterates = entry.get("iterates") or []
        if not iterates and entry.get("t") is not None:
            iterates = [(entry["t"], float("nan"))]
        for i, it in enumerate(iterates, start=1):
            t, g = it[0], it[1]
            rows.append((k, i, float(t), float(g), comp, switch))
    return rows


def write_events_csv(path: str | os.PathLike, event_log: Sequence[dict]) -> int:
    """Write ``events.csv``; returns the number of rows."""
    rows = event_rows(event_log or [])
    _write_table(path, EVENT_COLUMNS, rows)
    return len(rows)


def step_rows(step_history) -> list[tuple]:
    rows = []
    if step_history is None:
        return rows
    for rec in step_history:
        t, h, order = rec[0], rec[1], float(rec[2])
        rows.append((float(t), float(h), int(round(order)) if math.isfinite(order) else None))
    return rows


def write_steps_csv(path: str | os.PathLike, step_history) -> int:
    """Write ``steps.csv`` (``time,step_size,order``, one row per accepted step)."""
    rows = step_rows(step_history)
    _write_table(path, STEP_COLUMNS, rows)
    return len(rows)


def read_results_csv(path: str | os.PathLike):
    """Read a ``results.csv`` written by :class:`StreamingCSV`.

    Returns ``(names, units, data)`` with ``data`` a dict name -> numpy array; the
    first name is ``time``. A final partial line (from a machine crash) is ignored.
    """
    import numpy as np

    path = Path(path)
    with open(path, newline="", encoding="utf-8") as f:
        text = f.read()
    lines = text.splitlines(keepends=True)
    if not lines:
        raise ValueError(f"{path} is empty")
    if not lines[-1].endswith("\n") and len(lines) > 1:
        lines = lines[:-1]
    reader = csv.reader(lines)
    header = next(reader)
    names, units = zip(*(parse_column_header(h) for h in header), strict=True)
    rows = []
    for lineno, row in enumerate(reader, start=2):
        if not row:
            continue
        if len(row) != len(header):
            raise ValueError(f"{path}, line {lineno}: {len(row)} values for {len(header)} columns")
        rows.append([float(v) if v != "" else float("nan") for v in row])
    arr = np.array(rows, dtype=float).reshape(-1, len(header))
    data = {n: arr[:, j] for j, n in enumerate(names)}
    return list(names), dict(zip(names, units, strict=True)), data


def select_variables(names: Sequence[str], patterns: Sequence[str] | None) -> list[str]:
    """Names matching any of the shell-style ``patterns`` (``pipe1.*``, ``*.T_out``).

    A pattern without wildcards also matches as a prefix component (``pipe1`` selects
    every ``pipe1.*``). No patterns: every name. Order follows ``names``.
    """
    import fnmatch

    if not patterns:
        return list(names)
    out = []
    for n in names:
        for p in patterns:
            if fnmatch.fnmatchcase(n, p) or n.startswith(p + "."):
                out.append(n)
                break
    return out


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def plot_steps(
    step_history,
    path: str | os.PathLike,
    *,
    title: str | None = None,
    event_times: Sequence[float] = (),
) -> Path:
    """Step size (log scale) and order over time (the seed's Figs. 10.3 and 10.7)."""
    import numpy as np

    plt = _pyplot()
    rows = np.array(
        [(t, h, math.nan if q is None else q) for t, h, q in step_rows(step_history)], dtype=float
    ).reshape(-1, 3)
    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(9, 5.5))
    t = rows[:, 0]
    t_scale, t_label = _time_axis(t)
    if len(rows):
        ax1.semilogy(t / t_scale, rows[:, 1], ".-", ms=3, lw=0.8)
        ax2.step(t / t_scale, rows[:, 2], where="post", lw=1.0)
    for te in event_times:
        for ax in (ax1, ax2):
            ax.axvline(te / t_scale, color="r", ls=":", lw=0.8)
    ax1.set_ylabel("step size [s]")
    ax2.set_ylabel("order")
    ax2.set_xlabel(t_label)
    ax2.set_yticks(range(1, 7))
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    try:
        _atomic_write(
            path, lambda f: fig.savefig(f, dpi=110, format=path.suffix.lstrip(".") or "png")
        )
    finally:
        plt.close(fig)
    return path


def _time_axis(t) -> tuple[float, str]:
    try:
        span = float(t[-1]) if len(t) else 0.0
    except TypeError:
        span = 0.0
    if span >= 3 * 3600:
        return 3600.0, "time [h]"
    if span >= 3 * 60:
        return 60.0, "time [min]"
    return 1.0, "time [s]"
