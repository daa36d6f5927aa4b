"""The stamp that says a folder's sweep figures are up to date, and the quick look at it that
``ehd figures`` takes before it reads anything (imports nothing heavy).

``update_figures`` writes ``<out>/.sweep-figures.sha256`` after a render: the fingerprint of the
store's contents and the figure code (``sweep_maps.fingerprint``, which needs the store read
whole), and the store's file state (every entry's path, type, size, inode, modification and
change times, which needs only a directory listing) with the figure code and matplotlib version.
The file state is the one taken *before* the store was read (``ehd figures`` takes it first): a
sweep that writes the store during or after the read changes it, so the next ``ehd figures``
reads the store again and redraws what changed, never certifying figures of a half-written store
as up to date. When the file state is unchanged since then the contents are unchanged too (a
sweep writes its chunks through new files; a no-op ``ehd sweep`` touches nothing inside the
store; a file's change time cannot be set back, unlike its modification time), so the figures
are up to date without reading the store: this is what makes a no-op ``make sweep`` cheap
(benchmarks/startup.md). Anything else goes to the full check.
"""

from __future__ import annotations

import hashlib
import json
import os

__all__ = ["STAMP_NAME", "store_state", "read_stamp", "stamp_text", "up_to_date"]

STAMP_NAME = ".sweep-figures.sha256"  # in the figures folder
_CODE = ("sweep_maps.py", "stamp.py", os.path.join("..", "sweeps", "analysis.py"))


def _code_key() -> str:
    from importlib.metadata import PackageNotFoundError, version

    h = hashlib.sha256()
    here = os.path.dirname(os.path.abspath(__file__))
    for name in _CODE:
        with open(os.path.join(here, name), "rb") as f:
            h.update(f.read())
    try:
        h.update(version("matplotlib").encode())
    except PackageNotFoundError:  # pragma: no cover - matplotlib is a dependency
        pass
    return h.hexdigest()


def store_state(store) -> str | None:
    """sha256 of every entry under the store directory (relative path, type, size, inode, mtime
    and ctime in ns; links not followed) and the figure code; None when the store is not a
    directory or holds no zarr group at its top (not a store: ``ehd figures /`` walked the whole
    file system, 24 s here, before it said the root folder is no store)."""
    root = os.path.realpath(store)
    if not any(os.path.isfile(os.path.join(root, name)) for name in ("zarr.json", ".zgroup")):
        return None
    entries = []
    for folder, dirs, files in os.walk(root):
        dirs.sort()
        for name in sorted(files) + sorted(d for d in dirs if os.path.islink(
                os.path.join(folder, d))):
            path = os.path.join(folder, name)
            try:
                st = os.lstat(path)
            except FileNotFoundError:  # gone while a sweep writes (a temporary, a re-layout):
                entries.append(f"{os.path.relpath(path, root)}|gone")  # a state no stamp
                continue  # matches later, so the next ehd figures reads the store again
            entries.append(f"{os.path.relpath(path, root)}|{st.st_mode}|{st.st_size}|"
                           f"{st.st_ino}|{st.st_mtime_ns}|{st.st_ctime_ns}")
    h = hashlib.sha256(_code_key().encode())
    h.update("\n".join(entries).encode())
    return h.hexdigest()


def stamp_text(fingerprint: str, state: str | None, files) -> str:
    return json.dumps({"fingerprint": fingerprint, "store_state": state,
                       "files": [os.path.basename(str(p)) for p in files]}, indent=1) + "\n"


def read_stamp(out) -> dict:
    """The stamp in folder ``out`` as ``{"fingerprint", "store_state", "files"}`` (empty when
    missing or unreadable; a stamp of an older version held the fingerprint alone)."""
    try:
        with open(os.path.join(out, STAMP_NAME), encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError):
        return {}
    try:
        data = json.loads(text)
    except ValueError:
        return {"fingerprint": text.strip()}
    return data if isinstance(data, dict) else {}


def up_to_date(store, out) -> list[str] | None:
    """The figure files in ``out`` when they were drawn from ``store`` as it is now (its file
    state unchanged since) and are all there; else None (the full check decides)."""
    stamp = read_stamp(out)
    files = stamp.get("files")
    if not stamp.get("store_state") or not isinstance(files, list) or not files:
        return None
    if stamp["store_state"] != store_state(store):
        return None
    paths = [os.path.join(out, name) for name in files]
    return paths if all(os.path.isfile(p) for p in paths) else None
