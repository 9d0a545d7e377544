"""Plant files that keep working: the format version and the table of migrations.

A plant file states the version of the schema it is written in::

    [plant]
    format = 2

A file without ``format`` is format 1: every file written before format numbers
existed (up to 2026-12-02). Format 2 is the current one; it reads like format 1
except for what :data:`MIGRATIONS` lists. Each entry is one key that was renamed,
or one convention or default whose meaning changed in this project's history
(the commit and date say where), with what a format-1 file gets:

* ``rename``: the old key is read as the new one, with the same meaning, and a
  notice (one line: file, table, key, line, the new key). In a format-2 file the
  old key is refused with a message naming the new key.
* ``sign``: a changed sign convention, detected where the file shows it (a
  ``MassFlowBoundary`` sink, no h/T/x, with a flow m > 0: before 2026-11-22 m > 0
  meant *out of* the plant at a sink, now always *into* it). The file is not run:
  the message names the convention and the way out (``m = -...`` or
  ``dnasim upgrade``), because the same text means opposite flows in the two
  versions. ``dnasim upgrade`` negates the flow.
* ``default``: a default that changed after a time the file is known to predate
  (it uses a key refused since then, :data:`EVIDENCE`): the old default is
  written into the data, with a notice, so that the file runs as it was written.
* ``review``: a default that changed at a time the file cannot be placed
  against: a notice saying what the default was and which key keeps it.

Nothing here changes a file on disk; ``dnasim upgrade`` (:func:`upgrade_text`)
rewrites one to the current format with tomlkit, keeping comments and layout,
and prints what it changed. Notices go to :data:`NOTICE` (the command line
prints them as ``dnasim: notice: ...``) or, without it, to ``warnings`` as a
:class:`PlantFileNotice`.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass

from dnasim.core.errors import PlantError, Problems

__all__ = [
    "CURRENT_FORMAT",
    "FIRST_FORMAT",
    "MIGRATIONS",
    "Migration",
    "PlantFileNotice",
    "migrate",
    "upgrade_text",
]

#: the format this dnasim writes and reads natively
CURRENT_FORMAT = 2
#: the format of a file without ``[plant] format``
FIRST_FORMAT = 1

#: called with each notice (one line); None: ``warnings.warn(PlantFileNotice)``
NOTICE: Callable[[str], None] | None = None


class PlantFileNotice(UserWarning):
    """A plant file uses a key or convention of an earlier format; it runs with the
    meaning it was written with. ``dnasim upgrade`` rewrites it."""


@dataclass(frozen=True)
class Migration:
    """One change of the plant-file schema.

    ``kind``: "rename", "sign", "default" or "review" (module docstring).
    ``table``: "simulation", or "components.<Type>" for every component of that
    type. ``old``: the key of the earlier format; ``new``: the current key (a
    rename), or the key whose value is changed (sign) or written (default).
    ``value``: the old default (kind "default"/"review"). ``since``: the first
    format in which the old form is refused. ``commit``, ``date``: where the
    change happened in this project's history. ``message``: what changed, for
    the notice."""

    kind: str
    table: str
    old: str
    new: str
    since: int
    commit: str
    date: str
    message: str
    value: object = None
    unless: tuple[str, ...] = ()  # keys whose presence makes a default/review moot
    #: the component still reads the old key itself (a rename kept as an alias): a
    #: format-1 file keeps it in the data (its errors stay located at it)
    alias: bool = False

    @property
    def when(self) -> str:
        return f"{self.date}, {self.commit}"

    @property
    def text(self) -> str:
        """``message`` with its date and commit."""
        return self.message.format(when=self.when)


#: the changes of the schema, oldest first (from ``git log``; docs/plant_files.md)
MIGRATIONS: tuple[Migration, ...] = (
    Migration(
        "review",
        "components.Pipe",
        "internal_energy",
        "internal_energy",
        2,
        "a7d3c5b",
        "2026-11-22 00:12 UTC",
        'the default internal_energy is "outlet" (a mixed volume) since {when}, "mean" '
        "(U = M (u_in + u_out)/2, eq. 10.12c) before",
        value="mean",
    ),
    Migration(
        "sign",
        "components.MassFlowBoundary",
        "m",
        "m",
        2,
        "9f3be42",
        "2026-11-22 03:28 UTC",
        "m > 0 is the flow INTO the plant at every boundary since {when}; before, "
        "m > 0 at a sink (no h, T or x) was the flow OUT of the plant",
    ),
    Migration(
        "review",
        "components.HeatExchanger",
        "hot_k",
        "hot_k",
        2,
        "d12868a",
        "2026-11-22 04:07 UTC",
        "a side without hot_k has the pressure drop hot_dp_nominal (default 0.1 bar) at "
        "m_nominal since {when}, no friction (hot_k = 0) before",
        value=0.0,
        unless=("hot_dp_nominal", "D", "arrangement"),
    ),
    Migration(
        "review",
        "components.HeatExchanger",
        "cold_k",
        "cold_k",
        2,
        "d12868a",
        "2026-11-22 04:07 UTC",
        "a side without cold_k has the pressure drop cold_dp_nominal (default 0.1 bar) at "
        "m_nominal since {when}, no friction (cold_k = 0) before",
        value=0.0,
        unless=("cold_dp_nominal", "D", "arrangement"),
    ),
    Migration(
        "rename",
        "simulation",
        "atol",
        "atol_scaled",
        2,
        "fd6513a",
        "2026-11-22 04:40 UTC",
        "renamed on {when}, same meaning (the absolute tolerance per unit of each "
        "variable's scale)",
    ),
    Migration(
        "rename",
        "components.TemperatureSensor",
        "tau",
        "T_lag",
        2,
        "492a2c6",
        "2026-11-22 06:18 UTC",
        "renamed on {when}, same meaning (the time constant of the sensor's lag)",
        alias=True,
    ),
    Migration(
        "default",
        "components.PIController",
        "anti_windup",
        "anti_windup",
        2,
        "74d6916",
        "2026-11-22 07:32 UTC",
        "the default anti_windup is true since {when}, false (the seed's plain eqs. 10.13) before",
        value=False,
    ),
)

#: old keys whose presence dates a format-1 file: refused by dnasim from the
#: migration's date on, so a file with one was written before it (a key still
#: accepted as an alias, like ``tau``, dates nothing)
EVIDENCE = {("simulation", "atol"): "fd6513a"}

_ORDER = {m.commit: i for i, m in enumerate(MIGRATIONS)}


# --------------------------------------------------------------------------- lines


class _Lines:
    """Line of a key in a table: ``[a.b]`` headers and ``key = ...`` lines."""

    _HEADER = re.compile(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
    _KEY = re.compile(r"^\s*(\"[^\"]*\"|'[^']*'|[A-Za-z0-9_-]+)\s*=")

    def __init__(self, text: str | None):
        self.keys: dict[tuple, int] = {}
        self.headers: dict[tuple, int] = {}
        table: tuple = ()
        for n, line in enumerate((text or "").splitlines(), 1):
            m = self._HEADER.match(line)
            if m:
                table = tuple(p.strip().strip("\"'") for p in m.group(1).split("."))
                self.headers.setdefault(table, n)
                continue
            m = self._KEY.match(line)
            if m:
                self.keys.setdefault((table, m.group(1).strip("\"'")), n)

    def find(self, table, key) -> int | None:
        table = tuple(table)
        if key is None:
            return self.headers.get(table)
        return self.keys.get((table, key)) or self.headers.get(table)


# --------------------------------------------------------------------------- reading


_SEEN: set[str] = set()


def _notify(msg: str) -> None:
    if NOTICE is not None:
        if msg not in _SEEN:  # once per process (a sweep reads the file per case)
            _SEEN.add(msg)
            NOTICE(msg)
    else:
        warnings.warn(msg, PlantFileNotice, stacklevel=4)


def file_format(data: dict, path: str, lines: _Lines) -> int:
    """The file's ``[plant] format`` (FIRST_FORMAT without it); a bad one is a
    ``PlantError`` naming file, table, key and line."""
    meta = data.get("plant") if isinstance(data, dict) else None
    if not isinstance(meta, dict) or "format" not in meta:
        return FIRST_FORMAT
    v = meta["format"]
    errors = Problems(str(path), lines)
    if isinstance(v, bool) or not isinstance(v, int) or v < FIRST_FORMAT:
        errors.add(
            ("plant",),
            "format",
            f"expected the plant-file format as an integer, {FIRST_FORMAT} to "
            f"{CURRENT_FORMAT} (format = {CURRENT_FORMAT} for a file written now), got {v!r}",
        )
    elif v > CURRENT_FORMAT:
        errors.add(
            ("plant",),
            "format",
            f"format {v} is newer than this dnasim reads (formats {FIRST_FORMAT} to "
            f"{CURRENT_FORMAT}): the file was written for a later dnasim; upgrade dnasim",
        )
    errors.raise_if_any()
    return v


def _tables(data: dict, where: str):
    """(table path, table) of the tables a migration's ``table`` names."""
    if where == "simulation":
        t = data.get("simulation")
        if isinstance(t, dict):
            yield ("simulation",), t
        return
    kind = where.split(".", 1)[1]
    comps = data.get("components")
    if not isinstance(comps, dict):
        return
    for name, t in comps.items():
        if isinstance(t, dict) and t.get("type") == kind:
            yield ("components", name), t


def _table_text(path: tuple) -> str:
    return "[" + ".".join(path) + "]"


def _flow_values(v) -> list | None:
    """The flows [kg/s] a MassFlowBoundary's ``m`` can take (a number, a unit string
    or a time-function table), None when they cannot be read here (the file's own
    check reports that)."""
    from dnasim.core.units import UnitError, to_si

    def si(x):
        if isinstance(x, bool) or not isinstance(x, int | float | str):
            raise UnitError("not a quantity")
        return to_si(x, "kg/s")

    try:
        if isinstance(v, dict):
            out = []
            for k in ("value", "before", "after", "start", "end", "mean"):
                if k in v:
                    out.append(si(v[k]))
            if isinstance(v.get("values"), list):
                out += [si(x) for x in v["values"]]
            if "amplitude" in v and "mean" in v:
                a = abs(si(v["amplitude"]))
                out += [out[-1] + a, out[-1] - a] if out else []
            return out
        return [si(v)]
    except (UnitError, ValueError, TypeError, KeyError):
        return None


def _old_sinks(data: dict):
    """(table path, table, flows) of MassFlowBoundary sinks given a flow > 0."""
    for tpath, t in _tables(data, "components.MassFlowBoundary"):
        if any(k in t for k in ("h", "T", "x")) or "m" not in t:
            continue
        flows = _flow_values(t["m"])
        if flows and max(flows) > 0:
            yield tpath, t, flows


def _dated_before(data: dict) -> str | None:
    """The earliest migration commit the file is known to predate, or None."""
    best = None
    for (table, key), commit in EVIDENCE.items():
        found = any(key in t for _p, t in _tables(data, table))
        if found and (best is None or _ORDER[commit] < _ORDER[best]):
            best = commit
    return best


def _sink_message(m: Migration, file_fmt: int, value, path) -> str:
    shown = _short(value)
    if file_fmt >= m.since:
        return (
            f"m = {shown} at a sink (no h, T or x): m > 0 is the flow INTO the plant, "
            "and a sink cannot supply fluid; write m < 0 for a flow out of the plant "
            '(e.g. m = "-2 kg/s"), or give h, T or x for fluid entering the plant'
        )
    return (
        f"m = {shown} at a sink (no h, T or x) is ambiguous: {m.text}. "
        "The file is not run, because the same m means opposite "
        "flows in the two versions. If the file was written for the earlier convention, "
        f"run 'dnasim upgrade {path} --in-place' (it negates m and sets [plant] format = "
        f"{CURRENT_FORMAT}) or write "
        'm < 0 yourself (e.g. m = "-2 kg/s" for 2 kg/s out of the plant); if fluid '
        "should enter the plant here, give its state with h, T or x"
    )


def migrate(data, path: str = "<plant>", text: str | None = None) -> dict:
    """The decoded TOML of a plant file read as the current format: the ``format``
    key checked and removed from ``[plant]``, old keys renamed and old defaults
    written in (each with a notice), ambiguous or refused forms a ``PlantError``.
    ``data`` is changed in place and returned."""
    if not isinstance(data, dict):
        return data
    lines = _Lines(text)
    fmt = file_format(data, path, lines)
    meta = data.get("plant")
    if isinstance(meta, dict):
        meta.pop("format", None)
    errors = Problems(str(path), lines)
    notes = Problems(str(path), lines)
    upgrade = f" ('dnasim upgrade {path}' rewrites the file)"
    before = _dated_before(data) if fmt < CURRENT_FORMAT else None
    for m in MIGRATIONS:
        if m.kind == "rename":
            for tpath, t in _tables(data, m.table):
                if m.old not in t:
                    continue
                if fmt >= m.since:
                    errors.add(
                        tpath,
                        m.old,
                        f"unknown key in format {fmt}: '{m.old}' was renamed '{m.new}' "
                        f"({m.when}); write {m.new} = {_toml(t[m.old])}",
                    )
                elif m.alias:
                    notes.add(
                        tpath,
                        m.old,
                        f"'{m.old}' is the former name of '{m.new}', read as it: {m.text}"
                        + upgrade,
                    )
                elif m.new in t:
                    errors.add(
                        tpath,
                        m.old,
                        f"'{m.old}' is the former name of '{m.new}': give one of them",
                    )
                else:
                    t[m.new] = t.pop(m.old)
                    notes.add(
                        tpath,
                        m.old,
                        f"'{m.old}' read as '{m.new}' = {_toml(t[m.new])}: {m.text}" + upgrade,
                    )
        elif m.kind == "sign":
            for tpath, t, _flows in _old_sinks(data):
                errors.add(tpath, m.old, _sink_message(m, fmt, t[m.old], path))
        elif m.kind in ("default", "review") and fmt < m.since:
            known_old = before is not None and _ORDER[m.commit] > _ORDER[before]
            for tpath, t in _tables(data, m.table):
                if m.new in t or any(k in t for k in m.unless):
                    continue
                if m.kind == "default" and known_old:
                    t[m.new] = m.value
                    notes.add(
                        tpath,
                        None,
                        f"read with {m.new} = {_toml(m.value)}, the default of its time: "
                        f"{m.text}, and the file predates "
                        f"{_evidence_text(before)}" + upgrade,
                    )
                elif m.kind == "review" and before is not None:
                    notes.add(
                        tpath,
                        None,
                        f"{m.new} not given, today's default used: {m.text}; the file "
                        f"predates {_evidence_text(before)}, perhaps not "
                        f"this change: write {m.new} = {_toml(m.value)} for the earlier default",
                    )
    errors.raise_if_any()
    for note in notes.items:
        _notify(note)
    return data


def _evidence_text(commit: str) -> str:
    m = next(x for x in MIGRATIONS if x.commit == commit)
    return f"{m.date} (it has '{m.old}', refused from then on)"


def _toml(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    return repr(v)


# --------------------------------------------------------------------------- upgrade


def _negate(v):
    """-v for a number or a unit string ("2 kg/s" -> "-2 kg/s")."""
    if isinstance(v, bool):
        return v
    if isinstance(v, int | float):
        return -v
    s = str(v).strip()
    if s.startswith("-"):
        return s[1:].lstrip()
    if s.startswith("+"):
        return "-" + s[1:].lstrip()
    return "-" + s


def _set_keep(table, key: str, value) -> None:
    """``table[key] = value`` in a tomlkit table, keeping the key's comment."""
    import tomlkit

    old = table[key]
    item = tomlkit.item(value)
    if hasattr(old, "trivia"):
        item.trivia.comment_ws = old.trivia.comment_ws
        item.trivia.comment = old.trivia.comment
        item.trivia.trail = old.trivia.trail
    table.value._replace(key, key, item)


def _negate_flow(table, key: str) -> None:
    """The flow ``table[key]`` (tomlkit) negated: a number, a unit string, or a time
    function value by value (its layout kept)."""
    import tomlkit

    item = table[key]
    if isinstance(item, dict):
        for k in ("value", "before", "after", "start", "end", "mean", "amplitude"):
            if k in item:
                item[k] = _negate(_plain(item[k]))
        if "values" in item and isinstance(item["values"], list):
            new = tomlkit.array()
            for x in item["values"]:
                new.append(_negate(_plain(x)))
            item["values"] = new
        return
    _set_keep(table, key, _negate(_plain(item)))


def _plain(item):
    return item.unwrap() if hasattr(item, "unwrap") else item


def _rename_key(table, old: str, new: str) -> None:
    """Rename ``old`` to ``new`` in a tomlkit table in place (value, comment and
    position kept)."""
    table.value._replace(old, new, table[old])


def _with_plant_table(text: str) -> str:
    """``text`` with an empty ``[plant]`` table before its first table (after the
    leading comments), for a file that has none."""
    lines = text.splitlines(keepends=True)
    for i, line in enumerate(lines):
        if re.match(r"^\s*\[", line):
            return "".join(lines[:i]) + "[plant]\n\n" + "".join(lines[i:])
    return text + ("" if text.endswith("\n") or not text else "\n") + "[plant]\n"


def upgrade_text(text: str, path: str = "<plant>") -> tuple[str, list[str], list[str]]:
    """The plant file ``text`` rewritten in the current format: (new text, changes,
    reviews), each one line naming file, table, key and line (of the old file).
    Comments and layout are kept (tomlkit). A file already in the current format
    comes back unchanged. A file that does not decode is a ``PlantError``."""
    import tomllib

    import tomlkit

    try:
        plain = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise PlantError(f"{path}: malformed TOML: {exc}") from None
    lines = _Lines(text)
    fmt = file_format(plain, path, lines)
    changes = Problems(str(path), lines)
    reviews = Problems(str(path), lines)
    if fmt >= CURRENT_FORMAT:
        return text, [], []
    before = _dated_before(plain)
    doc = tomlkit.parse(text if "plant" in plain else _with_plant_table(text))

    def doc_table(tpath):
        t = doc
        for p in tpath:
            t = t[p]
        return t

    for m in MIGRATIONS:
        if m.kind == "rename":
            for tpath, t in _tables(plain, m.table):
                if m.old in t and m.new in t:
                    errors = Problems(str(path), lines)
                    errors.add(
                        tpath,
                        m.old,
                        f"'{m.old}' is the former name of '{m.new}': "
                        "give one of them, then upgrade",
                    )
                    errors.raise_if_any()
                if m.old in t:
                    _rename_key(doc_table(tpath), m.old, m.new)
                    changes.add(tpath, m.old, f"'{m.old}' -> '{m.new}' ({m.text})")
        elif m.kind == "sign":
            for tpath, t, _flows in _old_sinks(plain):
                dt = doc_table(tpath)
                _negate_flow(dt, m.old)
                changes.add(
                    tpath,
                    m.old,
                    f"m negated: {_short(t[m.old])} -> {_short(_plain(dt[m.old]))} ({m.text})",
                )
        elif m.kind in ("default", "review"):
            known_old = before is not None and _ORDER[m.commit] > _ORDER[before]
            for tpath, t in _tables(plain, m.table):
                if m.new in t or any(k in t for k in m.unless):
                    continue
                if m.kind == "default" and known_old:
                    doc_table(tpath)[m.new] = m.value
                    changes.add(
                        tpath,
                        None,
                        f"{m.new} = {_toml(m.value)} added ({m.text}; the file predates "
                        f"{_evidence_text(before)})",
                    )
                elif m.kind == "review" and before is not None:
                    reviews.add(
                        tpath,
                        None,
                        f"review: {m.new} not given: {m.text}; "
                        f"left as it is (today's default); add {m.new} = {_toml(m.value)} "
                        "if the file was written before that date",
                    )
    doc["plant"]["format"] = CURRENT_FORMAT
    changes.add(("plant",), "format", f"format = {CURRENT_FORMAT} added (was {fmt}: no format)")
    new_text = tomlkit.dumps(doc)
    tomllib.loads(new_text)  # the result must decode
    return new_text, changes.items, reviews.items


def _short(v) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml(x)}" for k, x in v.items()) + "}"
    return _toml(v)
