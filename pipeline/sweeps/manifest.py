"""The store's manifest: the digest of every chunk, keyed by its place, and the generation.

A chunk's CRC-32C (zarr's ``crc32c`` codec) says its bytes are whole, not where they belong: a
chunk copied over another cell's (``cp v_r/c/0/0 v_r/c/2/0``) passes it. The manifest
(``<store>/ehd_manifest.json``, written by the single writer only) binds every chunk to its
place: ``chunks`` maps each chunk's key (``v_r/c/2/0``, the path inside the store) to the sha256
of its bytes (a key that is absent: no file there, zarr's "every cell at its fill value"). It
names the metadata it belongs with (``metadata_sha256``, the root attribute that covers every
attribute and array's metadata) and carries the sha256 of its own canonical JSON, so neither it
nor the metadata can be swapped alone.

It is also the store's generation. A merge (pipeline/sweeps/store.py) publishes ``writing``
(which chunk keys it is about to replace, whether the metadata changes, its pid and host; phase
"waiting") *before* it touches any of them; new readers then wait for it. It waits for the reads
under way to end (they hold a shared flock on ``ehd_readers.lock``; it takes it exclusively, at
most ``MERGE_WAIT`` seconds, after which it publishes phase "writing" and goes on), writes, and
publishes the new manifest (the new digests, ``generation`` + 1, ``writing`` null). Each
manifest is written to a temporary file and renamed, so a reader sees one or the other, whole.
A reader that found the manifest the same before and after its read (or only a "waiting" marker
added: :func:`same_state`) read one consistent state (pipeline/sweeps/integrity.py:
``load_checked``); otherwise it reads again. A writer killed between its manifests leaves
``writing`` behind; the next sweep (holding the store's lock) digests those chunks as they are
and publishes the manifest again, their CRC-32C still checked by every reader.

No zarr here: plain files (pipeline/sweeps/files.py reads them).
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import time
from contextlib import contextmanager
from pathlib import Path

from .files import read_regular

__all__ = ["MANIFEST_NAME", "MANIFEST_LIMIT", "ManifestError", "digest", "chunk_keys", "build",
           "redigest", "read_manifest", "parse_manifest", "write_manifest", "writing_marker",
           "sealed", "writer_gone", "WRITING_HERE", "READERS_LOCK", "reading", "merging",
           "same_state"]

MANIFEST_NAME = "ehd_manifest.json"
# readers hold a shared flock on it while they read, the writer an exclusive one while it merges:
# a merge waits for the reads under way (at most MERGE_WAIT) and a read for the merge
READERS_LOCK = "ehd_readers.lock"
MERGE_WAIT = 10.0  # seconds a merge waits for readers before it goes on (they then read again)
FORMAT = 1
# ~100 bytes a chunk: 5 million chunks (10^7 scenes with rows of 90 over 45 variables)
MANIFEST_LIMIT = 512 * 2**20


class ManifestError(ValueError):
    """The manifest is missing, unreadable or of a shape this pipeline never writes; ``str()``
    is one clause saying which."""


def digest(data: bytes) -> str:
    """sha256 hex of a chunk's bytes."""
    return hashlib.sha256(data).hexdigest()


def _canonical(body: dict) -> bytes:
    return json.dumps(body, sort_keys=True, separators=(",", ":")).encode()


def chunk_keys(name: str, meta: dict):
    """``[(chunk index, key), ...]`` of every chunk an array's metadata says it has (zarr's
    default chunk key encoding with ``/``: ``name/c/i/j``), or None for a layout this pipeline
    does not write."""
    import numpy as np

    try:
        shape = [int(n) for n in meta["shape"]]
        chunks = [int(n) for n in meta["chunk_grid"]["configuration"]["chunk_shape"]]
        encoding = meta["chunk_key_encoding"]
        sep = (encoding.get("configuration") or {}).get("separator", "/")
    except (KeyError, TypeError, ValueError, AttributeError):
        return None
    if encoding.get("name") != "default" or sep != "/" or len(shape) != len(chunks) \
            or not all(c > 0 for c in chunks):
        return None
    grid = [-(-n // c) for n, c in zip(shape, chunks)]
    # plain strings: thousands of pathlib joins cost more than reading the files
    return [(idx, "/".join((name, "c", *map(str, idx)))) for idx in np.ndindex(*grid)]


def _digest_file(path: str, limit: int | None = None) -> str | None:
    try:
        return digest(read_regular(path, limit))
    except FileNotFoundError:
        return None


def build(path, arrays: dict, metadata_sha256: str) -> dict:
    """The manifest of the store at ``path`` as its files are now (a new layout, written by
    this process): every chunk of every array in ``arrays`` (name -> metadata)."""
    chunks = {}
    for name, meta in arrays.items():
        for _, key in chunk_keys(name, meta) or ():
            d = _digest_file(os.path.join(path, key))
            if d is not None:
                chunks[key] = d
    return {"ehd_manifest": FORMAT, "generation": 0, "metadata_sha256": metadata_sha256,
            "writing": None, "chunks": chunks}


def redigest(path, manifest: dict, keys) -> None:
    """Update, in place, the digests of the chunks ``keys`` from the files as they are now."""
    chunks = manifest["chunks"]
    for key in keys:
        d = _digest_file(os.path.join(path, key))
        if d is None:
            chunks.pop(key, None)
        else:
            chunks[key] = d


def write_manifest(path, manifest: dict) -> None:
    """Write ``manifest`` into the store at ``path``: a temporary file renamed into place (a
    reader sees the old manifest or the new one, whole; ``*.partial`` leftovers of a kill are
    removed by the writer's recovery)."""
    body = {k: v for k, v in manifest.items() if k != "sha256"}
    text = _canonical({**body, "sha256": hashlib.sha256(_canonical(body)).hexdigest()})
    target = Path(path) / MANIFEST_NAME
    tmp = target.with_name(f"{MANIFEST_NAME}.{os.getpid()}.partial")
    try:
        with open(tmp, "wb") as f:
            f.write(text)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def parse_manifest(raw: bytes) -> dict:
    """The manifest in ``raw``, its shape and its own checksum verified (ManifestError)."""
    try:
        data = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise ManifestError("its manifest is not readable JSON") from None
    if not isinstance(data, dict) or data.get("ehd_manifest") != FORMAT:
        raise ManifestError("its manifest is not an ehd manifest of format "
                            f"{FORMAT}")
    body = {k: v for k, v in data.items() if k != "sha256"}
    if data.get("sha256") != hashlib.sha256(_canonical(body)).hexdigest():
        raise ManifestError("its manifest differs from its own checksum (it was changed after "
                            "it was written)")
    chunks, writing = data.get("chunks"), data.get("writing")
    if not (isinstance(chunks, dict) and all(isinstance(v, str) for v in chunks.values())
            and isinstance(data.get("metadata_sha256"), str)
            and isinstance(data.get("generation"), int)
            and (writing is None or (isinstance(writing, dict)
                                     and isinstance(writing.get("keys"), list)))):
        raise ManifestError("its manifest has a shape this pipeline never writes")
    return data


def read_manifest(path) -> tuple[dict, bytes]:
    """``(manifest, raw bytes)`` of the store at ``path`` (ManifestError when missing, not a
    regular file, too large, unreadable or damaged)."""
    from .files import BadFile

    target = Path(path) / MANIFEST_NAME
    try:
        raw = read_regular(target, MANIFEST_LIMIT)
    except FileNotFoundError:
        raise ManifestError(f"its manifest ({MANIFEST_NAME}, the digest of every chunk) is "
                            "missing") from None
    except BadFile as exc:
        raise ManifestError(f"its manifest: {exc}") from None
    except OSError as exc:
        raise ManifestError(f"its manifest cannot be read ({exc.strerror})") from None
    return parse_manifest(raw), raw


def writing_marker(keys, metadata: bool = False, phase: str = "waiting") -> dict:
    """What ``writing`` holds while a writer replaces the chunks ``keys`` (and the metadata):
    ``phase`` "waiting" (for the reads under way; nothing touched yet) or "writing"."""
    return {"keys": sorted(keys), "metadata": bool(metadata), "phase": phase,
            "pid": os.getpid(), "host": socket.gethostname()}


def same_state(before: bytes | None, after: bytes | None) -> bool:
    """Whether a read that started at the manifest ``before`` and ended at ``after`` read one
    state: the same manifest, or the same one with only a writer's "waiting" marker added (a
    writer publishes it before it waits for the reads under way, and touches nothing until they
    are done or it publishes "writing")."""
    if before == after:
        return True
    if before is None or after is None:
        return False
    try:
        old, new = parse_manifest(before), parse_manifest(after)
    except ManifestError:
        return False
    marker = new.get("writing") or {}
    strip = ("writing", "sha256")
    return old.get("writing") is None and marker.get("phase") == "waiting" and \
        {k: v for k, v in old.items() if k not in strip} == \
        {k: v for k, v in new.items() if k not in strip}


def sealed(manifest: dict, metadata_sha256: str) -> dict:
    """The manifest of the next generation: ``writing`` cleared, the metadata digest set."""
    return {**manifest, "writing": None, "metadata_sha256": metadata_sha256,
            "generation": int(manifest.get("generation", 0)) + 1}


# the stores (real paths) this process is writing now: its own ``writing`` is not a dead writer's
WRITING_HERE: set = set()


def writer_gone(writing: dict, path) -> bool:
    """True when the writer that published ``writing`` in the store at ``path`` is known to
    have stopped (a process of this host that no longer exists, or this process outside its
    write); False when it may still be writing."""
    if writing.get("host") != socket.gethostname():
        return False
    try:
        pid = int(writing.get("pid"))
    except (TypeError, ValueError):
        return True
    if pid == os.getpid():
        return os.path.realpath(path) not in WRITING_HERE
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # EPERM: it exists, someone else's
        return False
    return False


def _flock_within(f, mode: int, seconds: float) -> bool:
    """Take the flock ``mode`` on the open file ``f`` within ``seconds`` (polling, never
    blocking longer); False when it was not had in time or locks are not available here."""
    import fcntl

    deadline = time.monotonic() + seconds
    while True:
        try:
            fcntl.flock(f, mode | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.01)
        except OSError:  # a file system without locks: the manifest alone keeps reads honest
            return False


@contextmanager
def reading(path, seconds: float):
    """Hold the readers' shared lock of the store at ``path`` while a read runs (waiting at most
    ``seconds`` for a merge under way; a store without the lock file, or a lock not had in
    time, is read anyway: the manifest before and after the read decides)."""
    from .files import open_regular

    try:
        f = open_regular(Path(path) / READERS_LOCK, 0)
    except OSError:  # missing, or not a regular file (the store's check says so)
        yield
        return
    with f:
        _flock_within(f, _fcntl("LOCK_SH"), seconds)
        yield


@contextmanager
def merging(path):
    """Hold the readers' lock of the store at ``path`` exclusively while the writer merges
    (waiting at most ``MERGE_WAIT`` for the reads under way; then it merges anyway and those
    readers read again). Yields whether the lock was had. Makes the lock file when it is
    missing."""
    from .files import BadFile, open_update

    try:
        f = open_update(Path(path) / READERS_LOCK)
    except (BadFile, OSError):
        yield False
        return
    with f:
        yield _flock_within(f, _fcntl("LOCK_EX"), MERGE_WAIT)


def _fcntl(name: str) -> int:
    import fcntl

    return getattr(fcntl, name)
