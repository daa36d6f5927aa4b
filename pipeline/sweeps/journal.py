"""The sweep journal: where finished scenes are kept until they are merged into the store.

Each finished scene is appended to ``<store>.journal`` (one JSON line
``{"physics": {...}, "key": ..., **record, "record_sha256": ...}``, flushed to the OS) by
:class:`pipeline.sweeps.store.SweepStore` before anything else, then merged into the store in
batches; a new run merges a journal left by a killed run first, so no finished scene is ever
computed twice. This module writes a journal line and finds and reads a journal.

A line is merged only when it is whole and its own: its ``record_sha256`` is the sha256 of the
canonical JSON of the rest (a line cut short by a kill, or edited, fails it), and its values are
of the right types and within what physics allows (``layout.record_problem``: e.g. ``v_r``,
``e_wet``, ``e_far`` in [0, 1]). Any other line is skipped and counted (its scene runs again).
The journal is read as a regular file only (a link, FIFO or device is refused: exit 5), of at
most ``JOURNAL_LIMIT`` bytes (a sweep merges it every few seconds: it never holds more than the
scenes of one merge interval), each line at most ``LINE_LIMIT``.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from ..errors import StoreDamaged
from .files import BadFile, open_regular
from .layout import record_problem

__all__ = ["pending_journal", "read_journal", "journal_line", "JOURNAL_LIMIT", "LINE_LIMIT",
           "CHECKSUM_KEY"]

JOURNAL_LIMIT = 256 * 2**20
LINE_LIMIT = 2**20  # a record is ~2 kB (its message is the longest part)
CHECKSUM_KEY = "record_sha256"


def _journal_path(path: Path) -> Path:
    """``<store>.journal`` next to the store's real path (a store reached through a symlink has
    one journal, like it has one lock)."""
    path = Path(os.path.realpath(path))
    return path.with_name(path.name + ".journal")


def _checksum(payload: dict) -> str:
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def journal_line(payload: dict) -> str:
    """The journal line of ``payload`` (``{"physics", "key", **record}``), its checksum added."""
    return json.dumps({**payload, CHECKSUM_KEY: _checksum(payload)}) + "\n"


def pending_journal(path) -> int:
    """Finished scenes of an interrupted sweep not yet merged into the store at ``path``."""
    return len(read_journal(_journal_path(Path(path)))[0])


def _record(raw: bytes) -> dict | None:
    """The scene record of one journal line, or None: not JSON, not a record, its checksum
    fails, or a value of the wrong type or outside what physics allows."""
    try:
        rec = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None
    if not (isinstance(rec, dict) and isinstance(rec.get("physics"), dict) and "status" in rec):
        return None
    given = rec.pop(CHECKSUM_KEY, None)
    if given != _checksum(rec) or record_problem(rec) is not None:
        return None
    return rec


def read_journal(jpath: Path) -> tuple[list, int]:
    """``(records, skipped)``: the records of a journal and how many lines were skipped (a line
    cut short by a kill, edited, out of range, or any line that is not a scene record: those
    scenes run again).

    Raises
    ------
    StoreDamaged
        The journal is not a regular file (a link, a FIFO, a device) or larger than
        ``JOURNAL_LIMIT``: one line, exit 5.
    """
    try:
        f = open_regular(jpath, JOURNAL_LIMIT)
    except FileNotFoundError:
        return [], 0
    except BadFile as exc:
        raise StoreDamaged(f"the store's journal is not one a sweep writes: {exc}; move it "
                           "aside (its scenes, if any, are computed again)") from None
    except OSError as exc:
        raise StoreDamaged(f"the store's journal {str(jpath)!r} cannot be read "
                           f"({exc.strerror}); move it aside (its scenes are computed "
                           "again)") from None
    out, skipped = [], 0
    with f:
        while True:
            raw = f.readline(LINE_LIMIT + 1)
            if not raw:
                break
            if len(raw) > LINE_LIMIT:  # far longer than a record: skip the rest of the line
                while raw and not raw.endswith(b"\n"):
                    raw = f.readline(LINE_LIMIT)
                skipped += 1
                continue
            if not raw.strip():
                continue
            rec = _record(raw)
            if rec is None:
                skipped += 1
            else:
                out.append(rec)
    return out, skipped
