"""Output sinks: where ``simulate`` streams the output rows while the solver runs.

Contract: ``open(names, units)`` once before the first row (names in
``System.output_names()`` order, units name -> unit string), ``write(t, row)``
per output point (t [s], row: ndarray in names order), ``close()`` once at the
end, also after a failure.

``CSVSink`` writes results.csv, ``NetCDFSink`` results.nc (netCDF-4 through h5py,
vectors as dimensions, the left limits of jumps in a group);
``dnasim.read_results`` reads either back.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["AtTimes", "CSVSink", "NetCDFSink", "OutputRows", "RESTART_COLUMN", "netcdf_layout"]

#: last output column: 1 on the row of the state right after a discontinuity (the
#: row before it, at the same time, holds the left limit), else 0 [-]
RESTART_COLUMN = "restart"


class OutputRows:
    """The solver's output points as the rows every sink gets (``simulate`` and
    ``dnasim run`` alike, so their results.csv are the same).

    ``names``/``units``: ``System.output_names()`` and ``output_units()`` and the
    ``RESTART_COLUMN`` ("-"). ``row(t, y, yp)`` -> the row: ``System.output_row``
    and the restart flag. A time repeated right after a point is the state after
    a restart (flag 1). The point before a time event (a set-point step at a
    tstop) is the left limit: the time functions are evaluated just before the
    event (``math.nextafter``), as the state y is.
    """

    def __init__(self, system, t0: float, t_end: float):
        self.system = system
        self.names = list(system.output_names()) + [RESTART_COLUMN]
        self.units = dict(system.output_units())
        self.units[RESTART_COLUMN] = "-"
        self.time_events = set(system.tstops(t0, t_end))
        self.prev_t: float | None = None

    def restart(self, t: float) -> bool:
        """True when t repeats the previous point's time: the state after a restart."""
        return self.prev_t is not None and float(t) == self.prev_t

    def row(self, t, y, yp):
        import numpy as np

        restart = self.restart(t)
        t_row = math.nextafter(t, -math.inf) if not restart and t in self.time_events else t
        values = self.system.output_row(t_row, y, yp)
        self.prev_t = float(t)
        return np.append(values, float(restart))


class AtTimes:
    """The output points at the times ``times`` [s] only (``t_eval`` followed
    literally): of the points the solver hands over at one time (both sides of a
    discontinuity there) the last, the state right after it (the right limit), and
    none at other times (the restarts the solver adds between them, at switches and
    time events). ``emit(t, restart, *payload)`` gets each kept point one point late
    (the next point says whether a later one at the same time follows), with
    ``restart`` True when it replaced an earlier point at its time; ``flush()`` hands
    over the last one. Whatever ``payload`` holds must not change afterwards (copy the
    solver's arrays)."""

    def __init__(self, times, emit):
        self.times = frozenset(float(t) for t in times)
        self.emit = emit
        self.held = None  # (t, restart, *payload) waiting for the next point

    def __call__(self, t, *payload) -> None:
        t = float(t)
        held = self.held
        restart = False
        if held is not None:
            if held[0] == t:
                restart = True
            else:
                self.held = None
                self.emit(*held)
        if t in self.times:
            self.held = (t, restart, *payload)

    def flush(self) -> None:
        held, self.held = self.held, None
        if held is not None:
            self.emit(*held)


class CSVSink:
    """Streams the output rows into a CSV file (``dnasim.run.output.StreamingCSV``):
    header "time [s]", "name [unit]", ...; the file holds whole rows at any time."""

    def __init__(self, path, *, flush_rows: int = 200, flush_seconds: float = 1.0):
        self.path = path
        self.flush_rows, self.flush_seconds = flush_rows, flush_seconds
        self._writer = None

    def open(self, names, units):
        from dnasim.run.output import StreamingCSV, column_header

        header = [column_header("time", "s")] + [column_header(n, units.get(n)) for n in names]
        self._writer = StreamingCSV(
            self.path, header, flush_rows=self.flush_rows, flush_seconds=self.flush_seconds
        )

    def write(self, t, row):
        self._writer.write_row(np.concatenate(([float(t)], np.asarray(row, dtype=float))))

    def close(self):
        if self._writer is not None:
            self._writer.close()

    @property
    def rows(self) -> int:
        """Whole rows on disk."""
        return self._writer.rows_written if self._writer is not None else 0

    @property
    def last_time(self) -> float | None:
        """t [s] of the last whole row on disk (None: no row)."""
        return self._writer.last_time if self._writer is not None else None


# --------------------------------------------------------------------------- netCDF

_VECTOR_RE = None


def netcdf_layout(names) -> list[tuple[str, list[int], str | None]]:
    """How the output columns ``names`` become netCDF variables:
    ``[(variable, column positions, vector dimension or None), ...]``.

    A set of names ``a.b[0]`` .. ``a.b[n-1]`` (all indices present once, and no
    scalar ``a.b``) becomes one variable ``a.b`` over ``(time, dim)``; every other
    name is a scalar variable over ``time``. The vector dimension of component
    ``a``: ``a.volume`` for the length of its mass vector ``a.M`` (one entry per
    finite volume), ``a.face`` for one more (flows between volumes), else ``a.n<len>``.
    """
    import re

    global _VECTOR_RE
    if _VECTOR_RE is None:
        _VECTOR_RE = re.compile(r"^(.+)\[(\d+)\]$")
    names = list(names)
    scalars = set()
    vectors: dict[str, dict[int, int]] = {}
    for j, n in enumerate(names):
        m = _VECTOR_RE.match(n)
        if m:
            vectors.setdefault(m.group(1), {})
            if int(m.group(2)) in vectors[m.group(1)]:
                vectors[m.group(1)][-1 - j] = j  # a repeated index: not a vector
            vectors[m.group(1)][int(m.group(2))] = j
        else:
            scalars.add(n)
    ok = {
        base: idx
        for base, idx in vectors.items()
        if base not in scalars and sorted(idx) == list(range(len(idx)))
    }
    volumes = {
        b.rsplit(".", 1)[0]: len(idx) for b, idx in ok.items() if b.rsplit(".", 1)[-1] == "M"
    }

    def dim(base, n):
        comp = base.rsplit(".", 1)[0] if "." in base else base
        if volumes.get(comp) == n:
            return f"{comp}.volume"
        if volumes.get(comp) is not None and volumes[comp] + 1 == n:
            return f"{comp}.face"
        return f"{comp}.n{n}"

    layout, done = [], set()
    for j, n in enumerate(names):
        m = _VECTOR_RE.match(n)
        if m and m.group(1) in ok:
            base = m.group(1)
            if base in done:
                continue
            done.add(base)
            idx = ok[base]
            layout.append((base, [idx[i] for i in range(len(idx))], dim(base, len(idx))))
        else:
            layout.append((n, [j], None))
    return layout


def netcdf_unit(unit: str | None) -> str:
    """A unit string for a netCDF ``units`` attribute: dimensionless ("", "-") is "1"."""
    return "1" if unit in (None, "", "-") else str(unit)


#: HDF5 format bounds of results.nc: 1.10's, the oldest that has SWMR, readable by
#: netCDF-C and h5py built on HDF5 >= 1.10
_LIBVER = ("v110", "v110")


class NetCDFSink:
    """Streams the output rows into a netCDF-4 file (HDF5, written with h5py),
    in blocks while the run goes on.

    Layout (:func:`netcdf_layout`): one unlimited, strictly increasing dimension
    ``time`` [s]; a vector output (``pipe.T[0..N-1]``) is one variable over
    ``(time, pipe.volume)``; every variable has ``units`` (SI; "1" for
    dimensionless), ``long_name`` and ``dnasim_columns`` (its positions among the
    output names, so the names' order can be rebuilt). At a restart (a located
    switch, a time event) the solver hands over two rows at one time: the root
    group keeps the state after the jump, flagged in ``restart`` (CF
    ``flag_values``/``flag_meanings``), and the state before it (the left limit)
    goes to the group ``left_limit``, with the same variables over its own
    ``time``. So ``xr.open_dataset(path).sel(time=t_event)`` works, and
    ``xr.open_dataset(path, group="left_limit")`` has the limits from the left.
    ``attrs`` become global attributes (plant name, description, solver
    settings); ``final_attrs`` (set before ``close``: status, message) are added
    when the file is closed.

    Whole rows on disk: the rows are kept in memory and written every
    ``flush_rows`` rows or ``flush_seconds`` seconds, with SIGINT/SIGTERM held
    back during the write; the data variables are written and flushed first,
    the ``time`` coordinate (which says how many rows there are) last. The file is
    written in HDF5's single-writer/multiple-reader (SWMR) mode, whose ordered
    metadata writes keep the file readable when the process is killed (SIGKILL)
    at any moment; such a file must then be opened in SWMR mode
    (:func:`dnasim.read_results` does). After a normal end, a failure, Ctrl-C or
    SIGTERM the file is closed normally and any netCDF reader opens it. Created
    with ``O_EXCL | O_NOFOLLOW`` like results.csv: a planted file or symbolic link
    is never written through.
    """

    def __init__(
        self,
        path,
        *,
        flush_rows: int = 200,
        flush_seconds: float = 1.0,
        attrs=None,
        expected_rows: float | None = None,
    ):
        from pathlib import Path

        self.path = Path(path)
        # HDF5 allocates whole chunks: rows per chunk near the rows expected (an
        # output_interval's count, 16 .. 512), 64 when not known, 4 for the left limits
        n = 64 if expected_rows is None or not expected_rows > 0 else expected_rows
        self._chunk_rows = int(max(16, min(512, n)))
        self.flush_rows = max(1, int(flush_rows))
        self.flush_seconds = float(flush_seconds)
        self.attrs = dict(attrs or {})
        #: attributes added when the file is closed (``run_plant``: status and message);
        #: "closed" says only that the writer closed the file normally
        self.final_attrs: dict = {"status": "closed"}
        self._h5 = None
        self._pending: list[tuple[float, np.ndarray]] = []
        self._rows = 0  # rows of the root group on disk
        self._left = 0  # rows of the left_limit group on disk
        self._last_time: float | None = None
        self._prev_t: float | None = None  # time of the last row written
        self._ino = None

    # -- errors
    def _error(self, why: str, reached: float | None = None):
        from dnasim.core.errors import OutputError

        if self._last_time is None:
            where = "before the first row"
        else:
            where = f"after {self._rows} whole rows, at simulated time t = {self._last_time:.6g} s"
        if reached is not None and reached != self._last_time:
            where += f" (the simulation had reached t = {reached:.6g} s)"
        return OutputError(
            f"cannot write {self.path}: {why}; the file stops {where}",
            path=self.path,
            t_reached=self._last_time,
            rows=self._rows,
        )

    @staticmethod
    def _why(exc: BaseException) -> str:
        from dnasim.run.output import _oserror_text

        if isinstance(exc, OSError) and exc.errno is not None:
            return _oserror_text(exc)
        text = str(exc)
        if "No space left" in text or "errno = 28" in text:
            return "the disk is full (ENOSPC)"
        if "File too large" in text or "errno = 27" in text:
            return "the file size limit is reached (EFBIG)"
        return text or type(exc).__name__

    # -- the sink contract
    def open(self, names, units):
        import os

        from dnasim.run.output import _O_NOFOLLOW, _oserror_text

        self.names = list(names)
        self.units = dict(units)
        self.layout = netcdf_layout([n for n in self.names if n != RESTART_COLUMN])
        # signals held back from the creation of the file to its first valid state: an
        # interrupt never leaves an empty or half-defined results.nc behind
        with _signals_blocked():
            try:
                fd = os.open(
                    self.path,
                    os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_NOFOLLOW | os.O_CLOEXEC,
                    0o644,
                )
            except FileExistsError:
                raise self._error(
                    "it already exists (another process created it after the old results "
                    "were removed?); it was not overwritten"
                ) from None
            except OSError as exc:
                raise self._error(_oserror_text(exc)) from None
            self._ino = os.fstat(fd).st_ino
            os.close(fd)
            try:
                import h5py

                self._h5 = h5py.File(self.path, "w", libver=_LIBVER, track_order=True)
                self._check_same_file(self._h5)
                self._define(self._h5, self.attrs)
                self._h5.flush()
                self._h5.swmr_mode = True
                self._datasets = {
                    g: [self._h5[f"{g}/{_h5name(v)}"] for v, _, _ in self.layout]
                    + [self._h5[f"{g}/restart"]]
                    for g in ("", "left_limit")
                }
                self._times = {g: self._h5[f"{g}/time"] for g in ("", "left_limit")}
                # (rows, bytes) of each dataset's chunks, for the room a block needs
                self._chunking = {
                    g: [
                        (d.chunks[0], int(np.prod(d.chunks)) * d.dtype.itemsize)
                        for d in [*ds, self._times[g]]
                    ]
                    for g, ds in self._datasets.items()
                }
                self._fd = self._h5.id.get_vfd_handle()
            except BaseException as exc:
                self._abandon()
                self._remove_own_file()
                if isinstance(exc, Exception) and not isinstance(exc, OutputErrorType()):
                    raise self._error(self._why(exc)) from None
                raise
        self._columns = [np.asarray(cols, dtype=np.intp) for _, cols, _ in self.layout]
        self._last_flush = time_monotonic()

    def _remove_own_file(self):
        """Remove the file this sink created (never a link or a file put in its place)."""
        import os

        try:
            st = os.lstat(self.path)
            if st.st_ino == self._ino and not os.path.islink(self.path):
                os.unlink(self.path)
        except OSError:
            pass

    def _check_same_file(self, h5file):
        import os

        fd = h5file.id.get_vfd_handle()
        if os.fstat(fd).st_ino != self._ino or os.path.islink(self.path):
            raise self._error("it was replaced while it was being opened; it was not written")

    def _define(self, f, attrs):
        """Dimensions, variables and attributes, in the root group and in left_limit,
        as netCDF-4 lays them out in HDF5 (a dimension is a dimension-scale dataset,
        here always a coordinate variable; each variable's axes are attached to their
        scales), written with h5py directly: h5netcdf's ``create_variable`` looks at
        every variable defined before, which is quadratic in their number."""
        scales = {}
        for gname in ("", "left_limit"):
            g = f if gname == "" else f.create_group(gname, track_order=True)
            # the left limits: one row per restart, few; small chunks
            rows = self._chunk_rows if gname == "" else 4
            t = g.create_dataset(
                "time", (0,), maxshape=(None,), chunks=(rows,), dtype="f8", fillvalue=np.nan
            )
            t.make_scale("time")
            t.attrs.update(
                {"units": "s", "long_name": "simulated time", "standard_name": "time", "axis": "T"}
            )
            t.attrs["_FillValue"] = np.float64(np.nan)
            for var, cols, dim in self.layout:
                if dim is None:
                    v = g.create_dataset(
                        _h5name(var),
                        (0,),
                        maxshape=(None,),
                        chunks=(rows,),
                        dtype="f8",
                        fillvalue=np.nan,
                    )
                    v.dims[0].attach_scale(t)
                else:
                    n = len(cols)
                    if dim not in scales:
                        c = f.create_dataset(dim, data=np.arange(n, dtype="i4"))
                        c.make_scale(dim)
                        c.attrs["long_name"] = f"index along {dim}"
                        c.attrs["units"] = "1"
                        scales[dim] = c
                    c = max(1, min(rows, (1 << 17) // n))
                    v = g.create_dataset(
                        _h5name(var),
                        (0, n),
                        maxshape=(None, n),
                        chunks=(c, n),
                        dtype="f8",
                        fillvalue=np.nan,
                    )
                    v.dims[0].attach_scale(t)
                    v.dims[1].attach_scale(scales[dim])
                v.attrs["_FillValue"] = np.float64(np.nan)
                unit = self.units.get(self.names[cols[0]])
                v.attrs["units"] = netcdf_unit(unit)
                if unit is not None and unit != v.attrs["units"]:
                    v.attrs["dnasim_unit"] = unit  # as System.output_units() says it
                v.attrs["long_name"] = var
                v.attrs["dnasim_columns"] = np.asarray(cols, dtype="i4")
            r = g.create_dataset("restart", (0,), maxshape=(None,), chunks=(rows,), dtype="i1")
            r.dims[0].attach_scale(t)
            r.attrs.update(
                {
                    "long_name": "row holds the state right after a restart at this time",
                    "flag_values": np.array([0, 1], dtype="i1"),
                    "flag_meanings": "continuous state_after_restart",
                    "units": "1",
                }
            )
        f.attrs["dnasim_results"] = 1  # the layout's version
        f.attrs["history"] = f"written by dnasim while the simulation ran ({_utc_now()})"
        f.attrs["source"] = "dnasim " + _version()
        for k, v in attrs.items():
            f.attrs[k] = _attr_value(v)

    def write(self, t, row):
        if self._h5 is None:
            raise ValueError(f"{self.path} is closed")
        self._pending.append((float(t), np.asarray(row, dtype=float)))
        if (
            len(self._pending) > self.flush_rows
            or time_monotonic() - self._last_flush >= self.flush_seconds
        ):
            self.flush()

    def flush(self, final: bool = False) -> None:
        """Write the rows kept in memory: all of them when ``final``, else all but
        the last (which is a left limit if the next row has its time)."""
        if self._h5 is None:
            return
        pending = self._pending
        n = len(pending) if final else len(pending) - 1
        if n <= 0:
            self._last_flush = time_monotonic()
            return
        main, left = [], []
        prev_t = self._prev_t
        rc = self.names.index(RESTART_COLUMN) if RESTART_COLUMN in self.names else None
        for k in range(n):
            t, row = pending[k]
            nxt = pending[k + 1][0] if k + 1 < len(pending) else None
            # both sides of a jump: the row before (same time as the next) is the left limit;
            # the row after it is flagged, as is a row whose restart column says so (with
            # t_eval only the right limit is handed over: ``AtTimes``)
            flag = prev_t == t or (rc is not None and row[rc] == 1.0)
            (left if nxt == t else main).append((t, row, flag))
            prev_t = t
        with _signals_blocked():
            try:
                for g, block, start in (("left_limit", left, self._left), ("", main, self._rows)):
                    if block:
                        self._append(g, block, start)
                        if g:
                            self._left += len(block)
                        else:
                            self._rows += len(block)
                            self._last_time = block[-1][0]
            except Exception as exc:
                reached = pending[n - 1][0]
                self._pending = []
                # refused before HDF5 wrote anything (no room): the file closes cleanly,
                # with the rows written so far; else HDF5's state is unknown
                self._abandon(clean=isinstance(exc, _NoRoom))
                raise self._error(self._why(exc), reached) from None
            self._pending = pending[n:]
            self._prev_t = prev_t
        self._last_flush = time_monotonic()

    def _check_room(self, g, start, n):
        """Raise OSError (EFBIG, ENOSPC) before HDF5 is asked to write a block that
        cannot fit: HDF5 keeps the blocks it failed to write in its caches and fails
        again at every later call, so the file could not be closed cleanly. The room
        needed is bounded by the chunks the block touches and 64 kB of metadata."""
        import errno
        import os
        import resource

        need = 65536
        for rows, nbytes in self._chunking[g]:
            need += ((start + n - 1) // rows - start // rows + 1) * nbytes
        size = os.fstat(self._fd).st_size
        soft, _ = resource.getrlimit(resource.RLIMIT_FSIZE)
        if soft != resource.RLIM_INFINITY and size + need > soft:
            raise _NoRoom(errno.EFBIG, "File too large")
        st = os.fstatvfs(self._fd)
        if st.f_bavail * st.f_frsize < need:
            raise _NoRoom(errno.ENOSPC, "No space left on device")

    def _append(self, g, block, start):
        self._check_room(g, start, len(block))
        rows = np.array([r for _, r, _ in block])
        stop = start + len(block)
        for ds, cols in zip(self._datasets[g], self._columns, strict=False):
            ds.resize(stop, axis=0)
            ds[start:stop] = rows[:, cols] if ds.ndim == 2 else rows[:, cols[0]]
        flags = self._datasets[g][-1]
        flags.resize(stop, axis=0)
        flags[start:stop] = [1 if r else 0 for _, _, r in block]
        self._h5.flush()  # the data first ...
        times = self._times[g]
        times.resize(stop, axis=0)
        times[start:stop] = [t for t, _, _ in block]
        self._h5.flush()  # ... then the time coordinate, which counts the rows

    def close(self) -> None:
        """Write the rows left, close the file and add ``final_attrs``. Safe to call
        twice. A failed write raises :class:`~dnasim.core.errors.OutputError`."""
        if self._h5 is None:
            return
        self.flush(final=True)
        h5, self._h5 = self._h5, None
        try:
            with _signals_blocked():
                h5.close()
                import h5py

                with h5py.File(self.path, "r+", libver=_LIBVER) as f:
                    self._check_same_file(f)
                    f.attrs["rows"] = self._rows
                    for k, v in self.final_attrs.items():
                        f.attrs[k] = _attr_value(v)
        except OutputErrorType():
            raise
        except Exception as exc:
            raise self._error(self._why(exc)) from None

    def _abandon(self, clean: bool = True):
        """Close the file after a failure. ``clean`` False (HDF5 failed inside a
        write): HDF5 would retry its failed writes at close, and at the interpreter's
        exit, and can crash doing so (HDF5 2.0, seen under RLIMIT_FSIZE); the file is
        then left open, its handles kept, and holds the rows of its last whole block
        (SWMR). HDF5 still retries those writes when the interpreter exits, and may
        crash there; ``_check_room`` refuses the blocks that cannot fit before HDF5
        sees them, so this is left for what it cannot foresee (another process
        filling the disk between the check and the write, an I/O error)."""
        h5, self._h5 = self._h5, None
        if h5 is None:
            return
        if not clean:
            _UNCLOSED.append(
                (h5, self.__dict__.pop("_datasets", None), self.__dict__.pop("_times", None))
            )
            return
        self._datasets = self._times = None
        try:
            h5.close()
        except Exception:
            pass

    @property
    def rows(self) -> int:
        """Whole rows of the root group (the states after any jump) on disk."""
        return self._rows

    @property
    def last_time(self) -> float | None:
        """t [s] of the last whole row on disk (None: no row)."""
        return self._last_time


class _NoRoom(OSError):
    """A block refused before HDF5 was asked to write it (``_check_room``)."""


def _h5name(name: str) -> str:
    """An output name as an HDF5 dataset name: "/" separates groups there, so it is
    written %2F (``long_name`` keeps the name itself)."""
    return name.replace("%", "%25").replace("/", "%2F")


#: files whose writes failed inside HDF5 (``NetCDFSink._abandon``), never closed
_UNCLOSED: list = []


def OutputErrorType():
    from dnasim.core.errors import OutputError

    return OutputError


def time_monotonic() -> float:
    import time

    return time.monotonic()


def _signals_blocked():
    from dnasim.run.output import _SignalsBlocked

    return _SignalsBlocked()


def _utc_now() -> str:
    import datetime

    return datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _version() -> str:
    """The installed dnasim's version (package metadata: ``dnasim.__version__`` is in
    the command-line stage, which this module may not import)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("dnasim")
    except PackageNotFoundError:
        return "unknown"


def _attr_value(v):
    """A netCDF attribute value: numbers and strings as they are, None as "",
    booleans as 0/1, a sequence of numbers (``t_eval``) as a float array, anything
    else as its text."""
    if v is None:
        return ""
    if isinstance(v, tuple | list | np.ndarray) and all(
        isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool) for x in v
    ):
        return np.asarray(v, dtype=float)
    if isinstance(v, bool | np.bool_):
        return int(v)
    if isinstance(v, int | float | str | np.integer | np.floating):
        return v
    return str(v)
