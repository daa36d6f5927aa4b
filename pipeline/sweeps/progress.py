"""A progress bar for the completion loop (works for every executor; dask's own ProgressBar prints
nothing under a distributed Client). Counts, rate and ETA; on a terminal it redraws one line, in
a log file it prints a line every ``log_every`` seconds."""

from __future__ import annotations

import sys
import time

__all__ = ["Progress", "format_duration"]


def format_duration(seconds: float) -> str:
    if seconds != seconds or seconds == float("inf"):
        return "--:--"
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m:02d}:{s:02d}"


class Progress:
    """Progress of ``total`` scenes.

    Parameters
    ----------
    total : int
        Scenes to compute in this run.
    stream : file, optional
        Where to draw (default ``sys.stderr``); ``None`` disables output.
    width : int
        Bar width in characters.
    log_every : float
        Seconds between lines when ``stream`` is not a terminal.
    """

    def __init__(self, total: int, stream=sys.stderr, width: int = 28, log_every: float = 10.0):
        self.total = total
        self.stream = stream
        self.width = width
        self.log_every = log_every
        self.done = self.ok = self.failed = self.rigid = 0
        self.start = time.monotonic()
        self._last_draw = -1e9
        self._tty = bool(stream is not None and getattr(stream, "isatty", lambda: False)())

    def update(self, status: str, model: str | None) -> None:
        self.done += 1
        if status == "ok":
            self.ok += 1
        else:
            self.failed += 1
        if model == "rigid":
            self.rigid += 1
        now = time.monotonic()
        interval = 0.1 if self._tty else self.log_every
        if now - self._last_draw >= interval or self.done == self.total:
            self._draw(now)

    def line(self, now: float | None = None) -> str:
        now = time.monotonic() if now is None else now
        elapsed = now - self.start
        frac = self.done / self.total if self.total else 1.0
        fill = int(round(frac * self.width))
        rate = self.done / elapsed if elapsed > 0 else float("nan")
        eta = (self.total - self.done) / rate if self.done and rate > 0 else float("nan")
        bar = "#" * fill + "." * (self.width - fill)
        return (f"[{bar}] {self.done}/{self.total} {100 * frac:3.0f}%  ok {self.ok}  "
                f"failed {self.failed}  rigid {self.rigid}  {rate:.1f} scenes/s  "
                f"elapsed {format_duration(elapsed)}  ETA {format_duration(eta)}")

    def _draw(self, now: float) -> None:
        self._last_draw = now
        if self.stream is None:
            return
        if self._tty:
            self.stream.write("\r" + self.line(now) + "\x1b[K")
        else:
            self.stream.write(self.line(now) + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.stream is not None and self._tty and self.done:
            self.stream.write("\n")
            self.stream.flush()
