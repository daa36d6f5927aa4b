"""The sweep journal: where finished scenes are kept until they are merged into the store.

Each finished scene is appended to ``<store>.journal`` (one JSON line
``{"physics": {...}, "key": ..., **record}``, flushed to the OS) by
:class:`pipeline.sweeps.store.SweepStore` before anything else, then merged into the store in
batches; a new run merges a journal left by a killed run first, so no finished scene is ever
computed twice. This module finds and reads a journal.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["pending_journal", "read_journal"]


def _journal_path(path: Path) -> Path:
    """``<store>.journal`` next to the store's real path (a store reached through a symlink has
    one journal, like it has one lock)."""
    path = Path(os.path.realpath(path))
    return path.with_name(path.name + ".journal")


def pending_journal(path) -> int:
    """Finished scenes of an interrupted sweep not yet merged into the store at ``path``."""
    return len(_read_journal(_journal_path(Path(path))))


def read_journal(jpath: Path) -> tuple[list, int]:
    """``(records, skipped)``: the records of a journal and how many lines were skipped (a line
    cut short by a kill, or any line that is not a scene record: those scenes run again)."""
    if not jpath.exists():
        return [], 0
    out, skipped = [], 0
    with jpath.open("rb") as f:
        for raw in f:
            if not raw.strip():
                continue
            try:
                rec = json.loads(raw.decode("utf-8"))
            except (UnicodeDecodeError, json.JSONDecodeError):
                skipped += 1
                continue
            if isinstance(rec, dict) and isinstance(rec.get("physics"), dict) and "status" in rec:
                out.append(rec)
            else:
                skipped += 1
    return out, skipped


def _read_journal(jpath: Path) -> list:
    """Records of a journal; bad lines are skipped (:func:`read_journal` counts them)."""
    return read_journal(jpath)[0]
