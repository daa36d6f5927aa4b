"""Writes that complete or leave nothing new behind.

Every output of ``ehd`` (a sweep store's temporary layout, its journal and lock, ``run --save``,
``--plot`` and ``--out`` folders) is written through one of these:

- :func:`writing` turns an ``OSError`` of a write (a full disk, a quota, an I/O error) into one
  line naming the path and the free space of its file system (:class:`~pipeline.errors.WriteError`,
  exit 74), after removing the temporary ``cleanup`` path;
- :func:`atomic_path` gives a temporary name next to the target, moved into place by
  ``os.replace`` only once it is complete (a file or a directory, e.g. a ``.zarr`` store);
- :func:`write_all` writes several files all or none (``ehd examples``, a DEM export);
- :func:`guarded_dir` guards a folder that a plotting function fills with several files, each
  announced by :func:`claim`, which hands back a temporary name to write it to: the files move
  into place together once the command has written them all; on a failure (Ctrl-C included)
  the temporaries are removed and the folder holds what it held before, the figures of an
  earlier run included.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from contextlib import contextmanager
from pathlib import Path

from .errors import WriteError, describe_os_error

__all__ = ["writing", "atomic_path", "temporary_paths", "write_all", "guarded_dir", "claim",
           "retire", "write_error"]


def write_error(exc: OSError, what: str, path=None) -> WriteError:
    """The one line of a failed write of ``what`` (e.g. ``--save r.nc``)."""
    import errno

    where = path if path is not None else (exc.filename or what)
    fix = "free some space or choose another path" if exc.errno in (errno.ENOSPC, errno.EDQUOT) \
        else "choose another path"
    return WriteError(f"{what}: cannot write {describe_os_error(exc, where)}; {fix} (nothing "
                      "partial was left behind)")


def _remove(path) -> None:
    if path is None:
        return
    path = Path(path)
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        try:
            path.unlink()
        except OSError:
            pass


def _settle_zarr(timeout: float = 10.0) -> None:
    """After one of zarr's chunk writes failed, cancel the others still pending on its event loop
    and wait for them: left running, they went on writing into the temporary store after it was
    removed and left it behind (seen on a full 200 KiB tmpfs, tests/test_hostile.py, about one
    run in ten). A no-op where zarr never started its loop."""
    import asyncio

    sync = sys.modules.get("zarr.core.sync")
    loop = None if sync is None else sync.loop[0]
    if loop is None or not loop.is_running():
        return

    async def drain():
        tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)

    try:
        asyncio.run_coroutine_threadsafe(drain(), loop).result(timeout)
    except Exception:  # noqa: BLE001 - best effort: the removal below still runs
        pass


def _remove_until_gone(path, quiet: float = 0.05, limit: float = 2.0) -> None:
    """``_remove``, again while ``path`` comes back within ``quiet`` seconds (for ``limit`` seconds
    at most): zarr writes a chunk's file in a thread (``asyncio.to_thread``), which cancelling
    its task (``_settle_zarr``) does not stop, so a write already handed over could create its
    file after the first removal (a temporary store left behind on a full 200 KiB tmpfs,
    tests/test_hostile.py, one full run in four at solver 1.16.0)."""
    _remove(path)
    if path is None or "zarr.core.sync" not in sys.modules:
        return
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        time.sleep(quiet)
        if not Path(path).exists():
            return
        _remove(path)


def _quiet_asyncio() -> None:
    """zarr writes chunks from tasks on its own event loop; after one of them failed, the others
    are destroyed pending and asyncio logs each at exit ("Task was destroyed but it is
    pending!"): the one line of the failure says what happened."""
    import logging

    logging.getLogger("asyncio").setLevel(logging.CRITICAL + 1)
    # and its coroutines closed with the loop at exit ("Exception ignored in ... Event loop is
    # closed"): only after a failed write, when the process is about to exit with its one line
    sys.unraisablehook = lambda unraisable: None


@contextmanager
def writing(cleanup, what: str, path=None):
    """Run a write; on ``OSError`` remove ``cleanup`` (a temporary file or folder, or None) and
    raise ``WriteError`` naming ``what``, the path (the error's file name, else ``path``, else
    ``cleanup``) and the free space. Other errors remove ``cleanup`` too and propagate."""
    try:
        yield
    except OSError as exc:
        _settle_zarr()
        _remove_until_gone(cleanup)
        _quiet_asyncio()
        where = exc.filename or path or cleanup
        raise write_error(exc, what, where) from None
    except BaseException:
        _remove(cleanup)
        raise


def temporary_paths(path) -> tuple[Path, Path]:
    """The names :func:`atomic_path` uses next to ``path``: the temporary it writes, and where
    an old directory waits while the new one moves in."""
    path = Path(path)
    return (path.with_name(f".{path.name}.tmp-{os.getpid()}"),
            path.with_name(f".{path.name}.old-{os.getpid()}"))


@contextmanager
def atomic_path(path, what: str):
    """Yield a temporary path next to ``path``; once the block completes it replaces ``path``
    (a file by ``os.replace``; a directory by two renames). On any failure the temporary is
    removed and ``path`` is left as it was."""
    path = Path(path)
    tmp, old = temporary_paths(path)
    _remove(tmp)
    with writing(tmp, what, path):
        yield tmp
        if tmp.is_dir() and path.is_dir():
            path.rename(old)
            tmp.rename(path)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, path)


def write_all(contents: dict, what: str) -> list[Path]:
    """Write every file of ``contents`` (``{path: bytes or str}``) or none: each to a temporary
    name next to it (its folders made as needed), all moved into place only once every one is
    written. On a failure every temporary and every folder made here is removed and no file has
    changed; an ``OSError`` becomes ``WriteError`` naming the file being written (not the
    temporary, nor where the bytes came from). Returns the paths written."""
    made, pending, current = [], [], None
    try:
        for path, data in contents.items():
            current = path = Path(path)
            missing = [p for p in (path.parent, *path.parent.parents) if not p.exists()]
            path.parent.mkdir(parents=True, exist_ok=True)
            made += [p for p in missing if p not in made]
            tmp = temporary_paths(path)[0]
            pending.append((tmp, path))
            with open(tmp, "wb") as f:
                f.write(data.encode("utf-8") if isinstance(data, str) else data)
        for tmp, path in pending:
            current = path
            os.replace(tmp, path)  # a rename: no new space needed
    except BaseException as exc:
        for tmp, _ in pending:
            _remove(tmp)  # those moved into place already are whole files
        for folder in sorted(made, key=lambda p: -len(p.parts)):  # innermost first
            try:
                folder.rmdir()
            except OSError:
                pass
        if isinstance(exc, OSError):
            raise write_error(exc, what, current) from None
        raise
    return [path for _, path in pending]


class _Claims:
    """What the code inside one open ``guarded_dir`` said it writes: each file with the
    temporary it is written to (``temporary_paths``), and the folders that did not exist, made
    for them."""

    def __init__(self, folder: Path):
        self.files: dict = {}
        self.retired: list[Path] = []
        self.folders = [p for p in (folder, *folder.parents) if not p.exists()]

    def add(self, path: Path) -> Path:
        self.folders += [p for p in path.parents if not p.exists() and p not in self.folders]
        return self.files.setdefault(path, temporary_paths(path)[0])

    def target(self, filename):
        """The claimed file whose temporary is ``filename`` (an error's), else ``filename``."""
        if filename is None:
            return None
        named = Path(filename).absolute()
        return next((path for path, tmp in self.files.items() if tmp == named), filename)

    def commit(self) -> None:
        """Remove the retired files, then move every temporary into place, in the order claimed
        (renames: no new space)."""
        for path in self.retired:
            _remove(path)
        for path, tmp in self.files.items():
            os.replace(tmp, path)

    def undo(self) -> None:
        """Remove every temporary still there, then the folders made for them that are empty
        (a user's file inside keeps its folder)."""
        for tmp in self.files.values():
            _remove(tmp)
        for path in sorted(self.folders, key=lambda p: -len(p.parts)):  # innermost first
            try:
                path.rmdir()
            except OSError:
                pass


# the claims of each open guarded_dir; the innermost is last
_CLAIMS: list[_Claims] = []


def claim(path) -> Path:
    """The running command is about to write the file ``path`` (a figure, a table, a stamp)
    into a folder that ``guarded_dir`` guards: returns the name to write it to, a temporary
    that replaces ``path`` once the command completes (should it fail, the temporary is removed
    and ``path`` stays as it was). ``path`` itself outside a guarded_dir. Name the format when
    writing it (matplotlib: ``format=``): the temporary's name does not end in ``path``'s."""
    if _CLAIMS:
        return _CLAIMS[-1].add(Path(path).absolute())
    return Path(path)


def retire(path) -> None:
    """The file ``path`` (one the command wrote in an earlier run, which this run replaces with
    no file) is removed once the command completes, before the claimed files move into place;
    now outside a guarded_dir."""
    if _CLAIMS:
        _CLAIMS[-1].retired.append(Path(path).absolute())
    else:
        _remove(Path(path))


@contextmanager
def guarded_dir(folder, what: str):
    """A folder filled by code that writes files, each announced by ``claim`` and written to
    the temporary name it returns: once the block completes, every temporary replaces its file
    (``os.replace``, in the order claimed); on an ``OSError`` (or any failure, Ctrl-C and
    SIGTERM included) the temporaries are removed, and the folders made for them (and for
    ``folder``) that are left empty, then it raises (``WriteError`` for an ``OSError``). The
    files in place are never touched on a failure: an interrupted ``ehd figures`` had removed
    the figures it had redrawn so far, the earlier run's with them (a hostile review); the first
    version removed every file that changed under ``folder`` while it ran, the user's included
    (a file edited in a subfolder of ``--plot DIR`` during the plot was deleted by a SIGTERM)."""
    folder = Path(folder).absolute()
    claims = _Claims(folder)
    _CLAIMS.append(claims)
    try:
        yield folder
        claims.commit()
    except BaseException as exc:
        claims.undo()
        if isinstance(exc, OSError):
            _quiet_asyncio()
            raise write_error(exc, what, claims.target(exc.filename) or folder) from None
        raise
    finally:
        _CLAIMS.remove(claims)
