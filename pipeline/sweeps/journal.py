"""The sweep journal: where finished scenes are kept until they are merged into the store.

Each finished scene is appended to ``<store>.journal`` (one JSON line
``{"physics": {...}, "key": ..., **record}``, flushed to the OS) by
:class:`pipeline.sweeps.store.SweepStore` before anything else, then merged into the store in
batches; a new run merges a journal left by a killed run first, so no finished scene is ever
computed twice. This module finds and reads a journal.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["pending_journal"]


def _journal_path(path: Path) -> Path:
    return path.with_name(path.name + ".journal")


def pending_journal(path) -> int:
    """Finished scenes of an interrupted sweep not yet merged into the store at ``path``."""
    return len(_read_journal(_journal_path(Path(path))))


def _read_journal(jpath: Path) -> list:
    """Records of a journal; a line cut short by a kill is ignored (its scene runs again)."""
    if not jpath.exists():
        return []
    out = []
    with jpath.open() as f:
        for line in f:
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(rec, dict) and isinstance(rec.get("physics"), dict) and "status" in rec:
                out.append(rec)
    return out
