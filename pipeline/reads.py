"""Reads of the user's input files: a regular file of bounded size, or one line saying why not.

A scene file, a materials file, a sweep file and a scheduler file are small text files. A path
that names anything else would hang or exhaust the memory before any check could speak: opening
a FIFO (named pipe) for reading blocks until a writer comes, and ``/dev/zero`` never ends.
:func:`read_input` refuses a FIFO, a device or a socket from its ``stat`` (before opening it),
opens the file without blocking, checks again what it opened (the path may have been replaced
in between), and reads at most ``MAX_INPUT_BYTES`` (docs/pipeline.md, "Input files"): a larger
file is refused, also one whose size the file system does not report (``/proc``).

The error class is the caller's (``UsageError``, ``ConfigError``, ``MaterialError``,
``RunnerError``: all exit 2). A missing file, a directory and a file that cannot be read raise
the ``OSError`` of ``os.stat``/``os.open`` (``FileNotFoundError``, ``IsADirectoryError``,
``PermissionError``), which each caller words with its own hint. Imports nothing heavy.
"""

from __future__ import annotations

import errno
import os
import stat

from .errors import UsageError

__all__ = ["read_input", "MAX_INPUT_BYTES", "file_kind"]

# the largest input file read: a scene, materials, sweep or scheduler file is a few kB (the
# shipped materials table, the largest, about 20 kB); 1 MiB leaves room for any real one
MAX_INPUT_BYTES = 1 << 20

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def file_kind(mode: int) -> str:
    """What a non-regular file of ``mode`` (``st_mode``) is, in words: "a FIFO (named pipe)"."""
    return next((what for test, what in _KINDS if test(mode)), "not a regular file")


def _refuse(label: str, mode: int, error) -> None:
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), label)
    if not stat.S_ISREG(mode):
        raise error(f"{label}: is {file_kind(mode)}, not a regular file; give the file itself "
                    "(a FIFO, a device or a socket is never read)")


def _too_large(label: str, limit: int, error):
    from .errors import _bytes as size

    return error(f"{label}: larger than {size(limit)}, the most an input file may hold "
                 "(docs/pipeline.md, \"Input files\"); a scene, materials, sweep or scheduler "
                 "file is a few kB: check the path")


def read_input(path, label: str, error=UsageError, limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of the regular file ``path`` (at most ``limit``), or ``error`` naming ``label``
    (e.g. ``"scene file 'x.toml'"``) when it is a FIFO, a device, a socket or larger than
    ``limit``; ``OSError`` when it is missing, a directory or unreadable."""
    st = os.stat(path)
    _refuse(label, st.st_mode, error)  # a FIFO is refused before any open
    if st.st_size > limit:
        raise _too_large(label, limit, error)
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    fd = os.open(path, flags)  # O_NONBLOCK: a FIFO put there since the stat does not block
    try:
        _refuse(label, os.fstat(fd).st_mode, error)
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, min(1 << 16, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    finally:
        os.close(fd)
    if size > limit:  # grew since the stat, or a size the file system does not report
        raise _too_large(label, limit, error)
    return b"".join(chunks)
