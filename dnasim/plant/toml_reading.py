"""Reading a plant file: bytes -> TOML data, with the line of every table and key
(``_LineIndex``, for messages that name the line), refusing deep nesting before the
TOML parser sees it, and the plant-file format's migrations (``dnasim.plant.migrations``)
applied as the data is decoded."""

from __future__ import annotations

import re
import tomllib
from collections.abc import Sequence
from pathlib import Path

from dnasim.core.errors import PlantError


class _LineIndex:
    """Best-effort map (table path, key) -> line number, by scanning the TOML text."""

    _HEADER = re.compile(r"^\s*\[\[?\s*(.+?)\s*\]\]?\s*(#.*)?$")
    _KEY = re.compile(
        r"^\s*((?:[A-Za-z0-9_-]+|\"[^\"]*\"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_-]+|\"[^\"]*\"|'[^']*'))*)\s*="
    )
    _INLINE_KEY = re.compile(r"[{,]\s*([A-Za-z0-9_-]+|\"[^\"]*\")\s*=")

    def __init__(self, text: str):
        self.map: dict[tuple[str, ...], int] = {}
        table: tuple[str, ...] = ()
        in_multiline = None
        for lineno, line in enumerate(text.splitlines(), start=1):
            if in_multiline:
                if in_multiline in line:
                    in_multiline = None
                continue
            m = self._HEADER.match(line)
            if m and not self._KEY.match(line):
                table = self._split(m.group(1))
                self.map.setdefault(table, lineno)
                continue
            m = self._KEY.match(line)
            if m:
                path = table + self._split(m.group(1))
                self.map.setdefault(path, lineno)
                rest = line[m.end() :]
                for q in ('"""', "'''"):
                    if rest.count(q) == 1:
                        in_multiline = q
                if "{" in rest:
                    for km in self._INLINE_KEY.finditer(rest):
                        self.map.setdefault(path + (km.group(1).strip("\"'"),), lineno)

    @staticmethod
    def _split(dotted: str) -> tuple[str, ...]:
        parts = re.findall(r"\"[^\"]*\"|'[^']*'|[^.\s]+", dotted)
        return tuple(p.strip("\"'") for p in parts)

    def find(self, table: Sequence[str], key: str | None) -> int | None:
        path = tuple(table) + ((key,) if key is not None else ())
        while path:
            if path in self.map:
                return self.map[path]
            path = path[:-1]
        return None


def read_plant_file(path: str | Path) -> tuple[dict, str]:
    """Read and decode a TOML file; malformed TOML becomes a ``PlantError`` with its line."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise PlantError(f"{path}: no such plant file") from None
    except IsADirectoryError:
        raise PlantError(f"{path}: is a directory, not a plant file") from None
    except OSError as exc:
        raise PlantError(f"{path}: cannot read the plant file: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line, col = _byte_line_column(raw, exc.start)
        raise PlantError(
            f"{path}, line {line}, column {col}: not a UTF-8 text file (byte "
            f"0x{raw[exc.start]:02x}: {exc.reason}); save the plant file as UTF-8"
        ) from None
    return _decode(text, str(path)), text


def _byte_line_column(raw: bytes, pos: int) -> tuple[int, int]:
    """Line and column (in characters, both from 1) of byte ``pos`` of ``raw``."""
    start = raw.rfind(b"\n", 0, pos) + 1
    return raw.count(b"\n", 0, pos) + 1, len(raw[start:pos].decode("utf-8", "replace")) + 1


#: nesting of arrays and inline tables that a plant file never needs
DEEP_NESTING = 50


def _deep_line(text: str, limit: int = DEEP_NESTING) -> int | None:
    """The line where arrays and inline tables first nest ``limit`` deep (strings
    and comments skipped), or None."""
    depth, line, i, n = 0, 1, 0, len(text)
    while i < n:
        ch = text[i]
        if ch == "\n":
            line += 1
        elif ch == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        elif ch in "\"'":
            q = text[i : i + 3] if text[i : i + 3] in ('"""', "'''") else ch
            j = i + len(q)
            while j < n and text[j : j + len(q)] != q:
                if text[j] == "\\" and ch == '"':
                    j += 1
                elif text[j] == "\n":
                    if len(q) == 1:
                        break
                    line += 1
                j += 1
            i = j + len(q)
            continue
        elif ch in "[{":
            depth += 1
            if depth >= limit:
                return line
        elif ch in "]}":
            depth = max(0, depth - 1)
        i += 1
    return None


def _decode(text: str, path: str) -> dict:
    from dnasim.plant.migrations import migrate  # [plant] format, old keys (docs/plant_files.md)

    try:
        return migrate(tomllib.loads(text), path, text)
    except RecursionError:
        line = _deep_line(text)
        where = f"{path}, line {line}" if line else path
        raise PlantError(
            f"{where}: malformed plant file: arrays or tables nested too deeply (a plant file "
            "needs at most a few levels)"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        msg = str(exc)
        m = re.search(r"\(at line (\d+), column (\d+)\)", msg)
        why = re.sub(r"\s*\(at line \d+, column \d+\)", "", msg).strip()
        where = f"{path}"
        if m:
            where += f", line {m.group(1)}, column {m.group(2)}"
        elif "end of document" in msg:
            where += f", line {text.count(chr(10)) + 1}"
        if "Cannot declare" in why or "Cannot overwrite" in why:
            why += " (a name is used twice: each component table and each key may appear once)"
        raise PlantError(f"{where}: malformed TOML: {why}") from None
