"""Bounded, typed reads of a store's files: regular files only, never more than a limit.

A store, its journal and its lock are files other people can replace: a chunk copied from
elsewhere is found by its digest (:mod:`pipeline.sweeps.manifest`), but a symbolic link, a FIFO
or a device where a file belongs would be followed, block a read forever (a FIFO) or never end
(``/dev/zero``), and a huge file would be read into memory whole. Every file of a store is
therefore looked at with ``lstat`` before it is opened, opened without following a link and
without blocking, checked again on the open descriptor (the same regular file) and read up to a
limit; anything else is a :class:`BadFile` whose message says what the path is instead.
"""

from __future__ import annotations

import os
import stat

__all__ = ["BadFile", "kind", "read_regular", "open_regular", "open_append", "open_update",
           "foreign_entries"]

_FLAGS = os.O_NOFOLLOW | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)


class BadFile(OSError):
    """A path that is not a regular file, or a regular file larger than its limit; ``str()`` is
    one clause naming the path and what it is instead (``'x' is a FIFO, not a regular file``)."""


def kind(mode: int) -> str:
    """What a file of ``mode`` (``st_mode``) is, as a noun phrase: ``a FIFO``, ``a symbolic
    link``, ..."""
    for test, name in ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a directory"),
                       (stat.S_ISREG, "a regular file")):
        if test(mode):
            return name
    return "not a regular file"


def _size(n: int) -> str:
    from ..errors import _bytes

    return _bytes(n)


def _open_fd(path, flags: int, limit: int | None = None) -> int:
    """A descriptor of the regular file ``path`` opened with ``flags`` (never through a link,
    never blocking on a FIFO), checked on the descriptor: the regular file ``lstat`` saw (or a
    new one, with ``O_CREAT``), within ``limit`` bytes. FileNotFoundError when it is missing
    (without ``O_CREAT``), BadFile when it is not a regular file or too large."""
    try:
        before = os.lstat(path)
    except FileNotFoundError:
        if not flags & os.O_CREAT:
            raise
        before = None
    if before is not None and not stat.S_ISREG(before.st_mode):
        raise BadFile(f"{str(path)!r} is {kind(before.st_mode)}, not a regular file")
    try:
        fd = os.open(path, flags | _FLAGS, 0o644)
    except OSError as exc:
        if exc.errno == getattr(os, "ELOOP", -1):  # became a link after the lstat
            raise BadFile(f"{str(path)!r} is a symbolic link, not a regular file") from None
        raise
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise BadFile(f"{str(path)!r} is {kind(st.st_mode)}, not a regular file")
        if before is not None and (st.st_dev, st.st_ino) != (before.st_dev, before.st_ino):
            raise BadFile(f"{str(path)!r} was replaced while it was opened")
        if limit is not None and st.st_size > limit:
            raise BadFile(f"{str(path)!r} is {_size(st.st_size)}, more than the {_size(limit)} "
                          "such a file can reach")
    except BaseException:
        os.close(fd)
        raise
    return fd


def open_regular(path, limit: int | None = None):
    """A binary file object of the regular file ``path`` (never through a link, never a FIFO
    or device), refused when it is larger than ``limit`` bytes.

    Raises
    ------
    FileNotFoundError
        No such file.
    BadFile
        Not a regular file, or larger than ``limit``.
    OSError
        It cannot be opened.
    """
    return os.fdopen(_open_fd(path, os.O_RDONLY, limit), "rb")


def read_regular(path, limit: int | None = None) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` (as :func:`open_regular`; a
    file that grows past the limit while it is read is refused too)."""
    fd = _open_fd(path, os.O_RDONLY, limit)
    try:
        parts, size = [], 0
        while True:  # one read for a small file; a file that grows is read to its end or limit
            want = 2**20 if limit is None else min(limit + 1 - size, 2**24)
            part = os.read(fd, want)
            parts.append(part)
            size += len(part)
            if limit is not None and size > limit:
                raise BadFile(f"{str(path)!r} grew past the {_size(limit)} such a file can "
                              "reach while it was read")
            if len(part) < want:  # a regular file's short read is its end
                break
    finally:
        os.close(fd)
    return b"".join(parts)


def open_append(path):
    """A text file object appending to the regular file ``path`` (made if missing; never
    through a link, never a FIFO or device: BadFile)."""
    return os.fdopen(_open_fd(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT), "a",
                     encoding="utf-8")


def open_update(path):
    """A text file object reading and writing the regular file ``path`` from its start (made if
    missing; never through a link, never a FIFO or device: BadFile)."""
    return os.fdopen(_open_fd(path, os.O_RDWR | os.O_CREAT), "r+", encoding="utf-8")


def foreign_entries(root) -> list[tuple[str, str]]:
    """Everything under the directory ``root`` that is neither a directory nor a regular file
    (symbolic links, FIFOs, devices, sockets): ``[(relative path, what it is), ...]``, sorted.
    Links are not followed (a linked folder is one entry); only directory entries are read (no
    file is opened)."""
    out = []
    stack = [str(root)]
    while stack:
        folder = stack.pop()
        with os.scandir(folder) as it:
            for entry in it:
                if entry.is_dir(follow_symlinks=False):
                    stack.append(entry.path)
                elif not entry.is_file(follow_symlinks=False):
                    out.append((os.path.relpath(entry.path, root),
                                kind(entry.stat(follow_symlinks=False).st_mode)))
    return sorted(out)
