"""The expected failures of ``ehd`` and their exit codes: one hierarchy, one error boundary.

Every expected failure is an :class:`EhdError` carrying a one-line message (what is wrong and
what would fix it) and its exit code; ``pipeline.cli.main`` is the one place that turns it into
``ehd <command>: error: <message>`` on stderr and that code. Anything else that escapes a
command is a bug: its traceback is printed with one line saying so, exit ``EXIT_INTERNAL``.

Exit codes of every ``ehd`` command (docs/pipeline.md, "Exit codes"):

| code | meaning |
|---:|---|
| 0 | success |
| 1 | ``run``/``scene``: the scene failed (its status and message are printed); ``restitution --threshold``: a solve of the bisection failed |
| 2 | bad input: arguments, sweep/scene/materials/scheduler file (also a FIFO, a device, over 1 MiB), unusable path (also an existing ``--save`` path ``run --save`` did not write, a name too long), store of other physics or numerics, busy store (or one a sweep changed during every read), scheduler unreachable (nothing computed) |
| 3 | ``sweep``: finished, but failed scenes remain in the store |
| 4 | ``sweep``: the scheduler went away mid-sweep (every scene finished so far is kept; rerun) |
| 5 | damaged store: ``status`` found damaged cells (unreadable, replaced or missing chunks), coordinates or metadata (listed), ``figures`` refuses to draw them, ``sweep`` refuses what it cannot repair (metadata, the manifest, a link, FIFO or device inside the store, a journal that is not a regular file or too large) |
| 70 | internal error: a bug (traceback printed; please report it) |
| 74 | an output could not be written: disk full or another I/O error (the line names the path and the free space; nothing partial is left behind), or stdout closed or full (also for ``--version``/``--help``) |
| 130 | interrupted (Ctrl-C): a sweep keeps every scene finished so far |
| 141 | the reader of stdout went away (``ehd ... | head``) |
| 143 | terminated (SIGTERM, e.g. ``kill`` or a batch system's time limit): as Ctrl-C |

No project imports here (stdlib only, imported lazily): every module may import this one.
"""

from __future__ import annotations

__all__ = ["EhdError", "UsageError", "PathError", "SchedulerError", "SchedulerLost",
           "StoreDamaged", "StoreMismatch", "WriteError", "Terminated", "EXIT_OK", "EXIT_SCENE_FAILED", "EXIT_USAGE", "EXIT_SWEEP_FAILED",
           "EXIT_SCHEDULER_LOST", "EXIT_DAMAGED", "EXIT_INTERNAL", "EXIT_INTERRUPTED",
           "EXIT_BROKEN_PIPE", "EXIT_WRITE", "EXIT_TERMINATED", "BUG_REPORT", "interrupt_cause",
           "on_signal", "raise_lost_interrupt", "interrupt_handled"]

EXIT_OK = 0
EXIT_SCENE_FAILED = 1
EXIT_USAGE = 2
EXIT_SWEEP_FAILED = 3
EXIT_SCHEDULER_LOST = 4
EXIT_DAMAGED = 5
EXIT_INTERNAL = 70  # EX_SOFTWARE of sysexits.h
EXIT_WRITE = 74  # EX_IOERR of sysexits.h
EXIT_INTERRUPTED = 130  # 128 + SIGINT
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE
EXIT_TERMINATED = 143  # 128 + SIGTERM

BUG_REPORT = "the project's issue tracker, with the command and the traceback above"


class EhdError(Exception):
    """An expected failure: a one-line ``message`` and the ``exit_code`` of the command."""

    exit_code = EXIT_USAGE

    def __init__(self, message: str = "", exit_code: int | None = None):
        super().__init__(message)
        if exit_code is not None:
            self.exit_code = exit_code

    def line(self) -> str:
        """The message as one line (a multi-line message is joined with '; ')."""
        parts = [p.strip() for p in str(self).splitlines() if p.strip()]
        return "; ".join(parts) or type(self).__name__


class UsageError(EhdError):
    """Bad input (arguments, a sweep or scene file): exit 2."""


class PathError(UsageError):
    """A path that cannot be used (missing directory, a file where a directory belongs, not
    writable, empty): exit 2, before any work."""


class SchedulerError(EhdError):
    """The executor could not be started or reached: exit 2, nothing computed."""


class SchedulerLost(SchedulerError):
    """The scheduler went away while the sweep ran: exit 4; finished scenes are kept."""

    exit_code = EXIT_SCHEDULER_LOST


class StoreDamaged(EhdError):
    """Chunks of a store cannot be read or contradict its status: exit 5."""

    exit_code = EXIT_DAMAGED


class StoreMismatch(UsageError, ValueError):
    """The store belongs to another solver version, numerics, physics or schema: refuse to mix
    (exit 2)."""


class WriteError(EhdError):
    """An output could not be written (disk full, I/O error; stdout closed or full): exit 74.
    Whatever was partly written has been removed."""

    exit_code = EXIT_WRITE


class Terminated(BaseException):
    """SIGTERM arrived (raised by the handler ``pipeline.cli.main`` installs): unwinds like
    Ctrl-C, so every scene finished so far is kept; exit 143. A ``BaseException``, like
    ``KeyboardInterrupt``, so no ``except Exception`` swallows it."""


# the signals whose handler (``on_signal``) has raised and whose exception ``ehd``'s boundary has
# not handled yet. Python drops an exception raised where it cannot propagate (a weakref callback,
# a ``__del__``, run by the garbage collector at any moment; it prints "Exception ignored in"): a
# Ctrl-C that arrived there was lost, and a sweep went on to its end with exit 0 (seen in CI, a
# loaded machine, the local cluster's objects being collected). Kept here, it is raised again.
_RAISED: list = []


def on_signal(signum, frame):
    """The handler ``pipeline.cli.main`` installs for SIGINT and SIGTERM: raises
    ``KeyboardInterrupt`` or ``Terminated``, and remembers it until ``interrupt_handled``, so
    that ``raise_lost_interrupt`` raises it again should Python drop it."""
    _RAISED.append(signum)
    raise _interrupt(signum)


def _interrupt(signum) -> BaseException:
    import signal

    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def raise_lost_interrupt() -> None:
    """Raise again the first Ctrl-C or SIGTERM that arrived and was not handled (Python dropped
    its exception: ``_RAISED``); nothing otherwise. Loops over scenes call it after each one."""
    if _RAISED:
        raise _interrupt(_RAISED[0])


def interrupt_handled() -> None:
    """The boundary has answered the interrupt (one line, its exit code): forget it."""
    _RAISED.clear()


def interrupt_cause(exc: BaseException | None):
    """The Ctrl-C (``KeyboardInterrupt``) or SIGTERM (``Terminated``) behind ``exc``, or None.
    One that arrived inside compiled code can come back wrapped: numba re-raises it as a
    ``SystemError`` ("returned a result with an exception set") whose cause is the interrupt."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, (KeyboardInterrupt, Terminated)):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def did_you_mean(name: str, known) -> str:
    """`` (did you mean 'x'?)`` with the known name nearest ``name`` where one is close (a typo),
    else ""."""
    import difflib

    near = difflib.get_close_matches(str(name), list(known), n=1)
    return f" (did you mean {near[0]!r}?)" if near else ""


def describe_os_error(exc: OSError, path) -> str:
    """``'<path>': <reason>`` for a failed write, with the free space of its file system when
    the disk is full (ENOSPC, EDQUOT)."""
    import errno
    import os
    import shutil

    reason = exc.strerror or type(exc).__name__
    where = str(path)
    if exc.errno in (errno.ENOSPC, getattr(errno, "EDQUOT", -1)):
        probe = os.path.abspath(where)  # a folder is its own file system (a mount point)
        if not os.path.isdir(probe):
            probe = os.path.dirname(probe) or "."
        while probe and not os.path.exists(probe):
            probe = os.path.dirname(probe)
        try:
            free = shutil.disk_usage(probe or ".").free
            reason += f", {_bytes(free)} free on its file system"
        except OSError:
            pass
    return f"{where!r}: {reason}"


def _bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n} B"  # pragma: no cover
