"""Executors: where the scenes of a sweep run. Chosen at run time; they never change a result.

Every runner offers the same thing, ``run.unordered(fn, jobs)``: an iterator of
``(tag, record)`` in completion order, so the sweep has one loop (progress bar, store writes)
whatever runs the scenes:

- ``serial``: in this process, one scene after another (tests, debugging);
- ``threads``: a pool of threads in this process (``concurrent.futures``; the solver's compiled
  pieces release the GIL, so threads run scenes side by side), which loads nothing more than a
  serial sweep does: the paper sweep costs about as much CPU as ``serial`` and half its wall
  time on 2 cores (benchmarks/sweep.md, "Executors");
- ``processes``: a dask LocalCluster of worker processes, one thread each: a scene that crashes
  its process (a segfault in compiled code) is stored as failed and the sweep goes on, where it
  would end a sweep of threads (the journal keeps what was finished); each worker imports and
  loads the compiled solver once, 3-5 s of CPU;
- ``auto`` (default, ``choose_runner``): threads for a sweep of fewer than
  ``AUTO_PROCESSES_FROM`` scenes to compute, processes from there, where their start-up is a
  small part of the work and a crash costs the most;
- an existing dask.distributed scheduler (``address`` or ``scheduler_file``), e.g. on SLURM.

dask futures go through ``client.get_executor()``, a standard ``concurrent.futures`` executor, and
``concurrent.futures.as_completed``. Compiled code is warmed once in this process *before* any
worker starts (it writes the on-disk numba cache, solver/_jit.py), then every worker loads it
before its first scene (the worker plugin :class:`~pipeline.sweeps.worker.WorkerSetup`, which also
sets the environment; workers that join later run it too), so no worker compiles on its own.

distributed is imported only where a cluster is started or reached (0.3-0.5 s: a sweep with
nothing to do never pays it).
"""

from __future__ import annotations

import logging
import os
import sys
import time
from concurrent.futures import as_completed
from contextlib import contextmanager

from ..errors import SchedulerError, SchedulerLost, raise_lost_interrupt

__all__ = ["open_runner", "check_runner", "check_seconds", "check_address", "probe_scheduler",
           "scheduler_address", "CONNECT_SECONDS", "default_workers", "max_local_workers", "RUNNERS",
           "DEFAULT_RUNNER", "AUTO_PROCESSES_FROM", "choose_runner", "Runner",
           "RunnerError", "WorkerSetup", "WAIT_WORKERS_SECONDS"]

RUNNERS = ("auto", "threads", "processes", "serial")
DEFAULT_RUNNER = "auto"
# From this many scenes to compute, "auto" takes processes: the paper sweep's 448 scenes take
# about 10 s of solver CPU, so 2000 such take ~45 s, against which the workers' start-up (3-5 s
# of CPU each, benchmarks/sweep.md) is under a fifth on 2 cores
AUTO_PROCESSES_FROM = 2000


def choose_runner(kind: str, scenes: int) -> str:
    """The local executor ``kind`` stands for with ``scenes`` to compute: "auto" is threads
    below ``AUTO_PROCESSES_FROM`` scenes and processes from there; any other kind is itself."""
    if kind != "auto":
        return kind
    return "processes" if scenes >= AUTO_PROCESSES_FROM else "threads"
WAIT_WORKERS_SECONDS = 60.0  # how long a sweep waits for --workers N on an existing scheduler
CONNECT_SECONDS = 30.0  # how long a sweep tries to reach an existing scheduler


class RunnerError(SchedulerError, RuntimeError):
    """The executor could not be started or reached (unreachable scheduler, workers that cannot
    import the project)."""


def scheduler_address(scheduler_file) -> str:
    """The address in a ``dask scheduler --scheduler-file FILE`` file, or RunnerError naming
    what is wrong with the file (checked before anything else happens: distributed itself
    would wait forever for a file that does not exist; a FIFO, a device or a file larger than
    ``reads.MAX_INPUT_BYTES`` is refused unread, ``pipeline.reads``)."""
    import json

    from ..reads import read_input

    where = f"--scheduler-file {scheduler_file}"
    try:
        text = read_input(scheduler_file, where, RunnerError).decode("utf-8")
    except FileNotFoundError:
        raise RunnerError(f"{where}: no such file; start the scheduler first (dask scheduler "
                          f"--scheduler-file {scheduler_file})") from None
    except UnicodeDecodeError:
        raise RunnerError(f"{where}: not a scheduler file (not text)") from None
    except OSError as exc:
        raise RunnerError(f"{where}: cannot read it ({exc.strerror})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RunnerError(f"{where}: not a scheduler file (not JSON: {exc.msg} at line "
                          f"{exc.lineno})") from None
    address = doc.get("address") if isinstance(doc, dict) else None
    if not isinstance(address, str) or "://" not in address:
        raise RunnerError(f"{where}: not a scheduler file (no \"address\" such as "
                          "tcp://10.0.0.1:8786)")
    return address


def check_seconds(flag: str, value, allow_zero: bool = False) -> None:
    """RunnerError unless ``value`` (of ``flag``) is a finite number of seconds > 0 (>= 0)."""
    import math

    if value is None:
        return
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and \
        math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        raise RunnerError(f"{flag} {value!r}: give a finite number of seconds "
                          f"{'>= 0' if allow_zero else '> 0'}, e.g. {flag} 30")


def check_address(address: str) -> str:
    """RunnerError unless ``address`` names a scheduler: ``tcp://HOST:PORT`` (or another dask
    protocol with its port)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    where = f"--scheduler {address}"
    try:
        protocol, location = parse_address(address, strict=True)
    except (ValueError, TypeError) as exc:
        raise RunnerError(f"{where}: not a scheduler address ({exc}); give one such as "
                          "tcp://10.0.0.1:8786") from None
    if protocol in ("tcp", "tls", "ws", "wss"):
        try:
            _, port = parse_host_port(location)
        except (ValueError, TypeError):
            raise RunnerError(f"{where}: no port; give one such as "
                              f"{protocol}://{location or '10.0.0.1'}:8786") from None
        if not 0 < int(port) < 65536:
            raise RunnerError(f"{where}: port {port} is not in 1-65535")
    return address


def check_runner(kind: str | None = DEFAULT_RUNNER, workers: int | None = None,
                 address: str | None = None, scheduler_file: str | None = None,
                 connect_seconds: float | None = None,
                 wait_workers: float | None = None) -> str | None:
    """Everything about the executor that can be checked before any work (the store is not
    touched yet): the executor name, the local worker limit, the timeouts, the scheduler
    address and file. Returns the scheduler address (None: local)."""
    check_seconds("--connect-timeout", connect_seconds)
    check_seconds("--wait-workers", wait_workers, allow_zero=True)
    local = address is None and scheduler_file is None
    if local and kind not in RUNNERS:
        raise RunnerError(f"executor must be one of {RUNNERS}, got {kind!r}")
    if local and kind != "serial" and workers and workers > max_local_workers():
        raise RunnerError(f"--workers {workers} is more than {max_local_workers()} (4 per usable "
                          f"core, {default_workers()} here): extra local workers only queue for "
                          "the cores; use a dask scheduler for more")
    if scheduler_file is not None:
        return check_address(scheduler_address(scheduler_file))
    if address is not None and not address.strip():
        raise RunnerError("--scheduler: empty address; give one such as tcp://10.0.0.1:8786")
    return check_address(address) if address is not None else None


def probe_scheduler(address: str, seconds: float = None, target: str | None = None) -> None:
    """Make sure a dask scheduler answers at ``address`` within ``seconds``, before anything
    is created (no store, no lock): a TCP connection, then the first bytes of the scheduler's
    handshake (a dask scheduler speaks first: an 8-byte frame length, then its handshake).
    RunnerError naming what happened: refused, no answer, a peer that accepts and never speaks
    (e.g. an HTTP server, which waits for a request), or one that sends other bytes. Addresses
    of other protocols than tcp:// are left to distributed."""
    import socket
    import struct

    from distributed.comm.addressing import parse_address, parse_host_port

    seconds = CONNECT_SECONDS if seconds is None else seconds
    target = target or address
    protocol, location = parse_address(address)
    if protocol != "tcp":
        return
    host, port = parse_host_port(location)
    deadline = time.monotonic() + seconds
    fix = "start it, check the address, or raise --connect-timeout"
    try:
        sock = socket.create_connection((host, int(port)), timeout=seconds)
    except socket.timeout:
        raise RunnerError(f"cannot reach the dask scheduler at {target} within {seconds:g} s "
                          f"(no answer); {fix}") from None
    except OSError as exc:
        raise RunnerError(f"cannot reach the dask scheduler at {target} within {seconds:g} s "
                          f"({exc.strerror or type(exc).__name__}); {fix}") from None
    try:
        head = b""
        while len(head) < 8:
            left = deadline - time.monotonic()
            if left <= 0:
                raise socket.timeout()
            sock.settimeout(left)
            chunk = sock.recv(8 - len(head))
            if not chunk:
                raise RunnerError(f"{target} accepted the connection and closed it without a "
                                  "word: not a dask scheduler; check the address")
            head += chunk
    except socket.timeout:
        raise RunnerError(f"{target} accepted the connection but sent no dask handshake within "
                          f"{seconds:g} s: is it a dask scheduler (and not, e.g., an HTTP "
                          "server)? Check the address and port, or raise --connect-timeout"
                          ) from None
    except OSError as exc:
        raise RunnerError(f"cannot reach the dask scheduler at {target} "
                          f"({exc.strerror or type(exc).__name__}); {fix}") from None
    finally:
        sock.close()
    (nbytes,) = struct.unpack("<Q", head)
    if not 0 < nbytes < 2**24:  # a handshake is a few hundred bytes
        raise RunnerError(f"{target} is not a dask scheduler (it answered {head!r}); check the "
                          "address and port")


def _connect(address: str, seconds: float, target: str):
    """``Client(address)`` with a hard deadline: distributed's own timeout does not cover every
    wait (a handshake that stalls); a client still connecting after ``seconds`` (+ 5 s of
    grace for distributed's own timeout to fire) is abandoned in its daemon thread."""
    import threading

    from dask.distributed import Client

    box = {}

    def connect():
        try:
            box["client"] = Client(address, timeout=seconds)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc

    thread = threading.Thread(target=connect, name="ehd-connect", daemon=True)
    thread.start()
    thread.join(seconds + 5.0)
    if thread.is_alive():
        _quiet_dask()
        raise RunnerError(f"the dask scheduler at {target} did not complete the connection "
                          f"within {seconds:g} s; check it, or raise --connect-timeout")
    if "error" in box:
        exc = box["error"]
        if isinstance(exc, (OSError, TimeoutError, ValueError, MemoryError)):
            _quiet_dask()
            raise RunnerError(f"cannot reach the dask scheduler at {target} within "
                              f"{seconds:g} s ({type(exc).__name__}: "
                              f"{str(exc).splitlines()[0] if str(exc) else 'no answer'}); start "
                              "it, check the address, or raise --connect-timeout") from None
        raise exc
    return box["client"]


def default_workers() -> int:
    """Cores this process may use (respects taskset/cgroup affinity)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def max_local_workers() -> int:
    """More local workers than this only queue for the cores (and 1000 of them stall the
    machine starting up): 4 per usable core."""
    return 4 * default_workers()


def __getattr__(name):
    # ``runners.WorkerSetup`` as before; it lives in .worker, which imports distributed
    if name == "WorkerSetup":
        from .worker import WorkerSetup

        return WorkerSetup
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class Runner:
    """Runs jobs; ``description`` says where (for the progress header)."""

    def __init__(self, description: str, executor=None, client=None):
        self.description = description
        self._executor = executor
        self.client = client

    def unordered(self, fn, jobs):
        """Yield ``(tag, result)`` for ``jobs = [(tag, args), ...]`` as they finish.

        An exception raised by ``fn`` (or a lost worker) is yielded as the exception object, so
        the caller can store it as a failed scene and go on. A scene whose workers died under it
        (dask's KilledWorker) is run once more, alone, at the end.
        """
        if self._executor is None:
            for tag, args in jobs:  # lazily: each result reaches the store before the next runs
                try:
                    result = fn(*args)
                except Exception as exc:
                    result = exc
                yield tag, result
                raise_lost_interrupt()  # the scene is stored: a Ctrl-C Python dropped ends here
            return
        futures = {self._executor.submit(fn, *args): (tag, args) for tag, args in jobs}
        # A worker process that dies takes every scene assigned to it, the queued ones too, and
        # dask fails a scene that was on as many such workers as it allows (KilledWorker): the
        # scene that crashed them, or one that only waited behind it. Run again alone, each
        # shows which it is, and no scene is stored as failed for its neighbour's crash.
        killed, done = [], 0
        try:
            for fut in as_completed(futures):
                exc = self._exception(fut, done)
                tag, args = futures.pop(fut)
                if type(exc).__name__ == "KilledWorker":
                    killed.append((tag, args))
                    continue
                done += 1
                yield tag, (exc if exc is not None else fut.result())
                raise_lost_interrupt()
            for tag, args in killed:
                fut = self._executor.submit(fn, *args)
                futures[fut] = (tag, args)
                exc = self._exception(fut, done)
                del futures[fut]
                done += 1
                yield tag, (exc if exc is not None else fut.result())
                raise_lost_interrupt()
        finally:
            if futures:  # interrupted: do not leave scenes running on a shared cluster
                # quiet first: each cancel runs a callback on the client's event loop thread that
                # logs the cancelled future with a traceback (tornado "Exception in callback"),
                # racing the quieting done later on the way out (a flaky Ctrl-C test caught it)
                _quiet_dask()
            for fut in futures:
                fut.cancel()

    def _exception(self, fut, finished: int):
        """The exception ``fut`` raised (None: a result), once it is done; SchedulerLost when
        the scheduler went away (``finished`` scenes were yielded before)."""
        from concurrent.futures import CancelledError

        try:
            exc = fut.exception()
        except CancelledError:  # we cancel nothing: the scheduler went away
            raise self._lost(finished) from None
        if exc is not None and self._scheduler_gone():
            raise self._lost(finished) from None
        return exc

    def _scheduler_gone(self) -> bool:
        return self.client is not None and self.client.status not in ("running", "newly-created")

    def _lost(self, finished: int) -> "SchedulerLost":
        _quiet_dask()
        return SchedulerLost(f"lost the dask scheduler ({self.description}) mid-sweep; the "
                             f"{finished} scenes finished before are kept: restart the scheduler "
                             "and run the same command again to compute the rest")


_NOISY = ("distributed", "tornado", "asyncio")


def _quiet_dask(names=_NOISY, level: int = logging.CRITICAL + 1) -> None:
    """distributed logs every closing comm of a lost or interrupted cluster with a traceback
    (through its own loggers, tornado's and asyncio's "exception was never retrieved"); the one
    line the command prints says what happened. Child loggers that distributed configured with
    their own level (``distributed.client``, ``tornado.application``...) are set too."""
    loggers = [logging.getLogger(n) for n in names]
    loggers += [logging.getLogger(n) for n in list(logging.root.manager.loggerDict)
                if n.startswith(tuple(f"{p}." for p in names))]
    for logger in loggers:
        logger.setLevel(level)


@contextmanager
def open_runner(kind: str | None = DEFAULT_RUNNER, workers: int | None = None,
                address: str | None = None, scheduler_file: str | None = None, warm=None,
                wait_workers: float = WAIT_WORKERS_SECONDS, stream=None,
                connect_seconds: float = CONNECT_SECONDS):
    """Start (or connect to) an executor and yield a :class:`Runner`.

    Parameters
    ----------
    kind : {"threads", "processes", "serial"} or None
        Local executor (``choose_runner`` resolves "auto" first); ignored when ``address`` or
        ``scheduler_file`` is given.
    workers : int, optional
        Local: worker processes (or threads); default all usable cores, at most
        :func:`max_local_workers`. Existing scheduler: wait until this many workers are connected
        before submitting (at most ``wait_workers`` seconds, reporting progress on ``stream``).
    address, scheduler_file : str, optional
        Connect to an existing dask.distributed scheduler instead of starting one.
    warm : callable, optional
        Called once here before any worker starts, then on every worker (:class:`WorkerSetup`).
    """
    address = check_runner(kind, workers, address, scheduler_file, connect_seconds,
                           wait_workers)
    stream = sys.stderr if stream is None else stream
    if warm is not None:
        warm()  # compile once, here: writes the on-disk numba cache the workers will load
    if address is not None:
        target = address + (f" (from {scheduler_file})" if scheduler_file else "")
        with _scheduler_runner(address, target, workers, warm, wait_workers, stream,
                               connect_seconds) as run:
            yield run
    elif kind == "serial":
        yield Runner("serial (this process)")
    elif kind == "threads":
        with _thread_runner(workers or default_workers()) as run:
            yield run
    else:
        with _cluster_runner(workers or default_workers(), warm) as run:
            yield run


@contextmanager
def _scheduler_runner(address, target, workers, warm, wait_workers, stream, connect_seconds):
    """A runner on an existing dask scheduler at ``address`` (``target``: how it was named)."""
    if stream is not None:
        print(f"waiting for the dask scheduler at {target} (up to {connect_seconds:g} s)...",
              file=stream, flush=True)
    # when the scheduler goes away, the client logs every failed reconnect and every closed
    # comm with a traceback (before the loss reaches this thread); the runner reports it as
    # one line (SchedulerLost). Task failures still arrive as records.
    _quiet_dask(("distributed.client", "distributed.comm", "distributed.core",
                 "distributed.batched", "tornado.application", "asyncio"),
                level=logging.CRITICAL)
    probe_scheduler(address, connect_seconds, target)
    client = _connect(address, connect_seconds, target)
    try:
        # at least one worker: a scheduler without workers would take the scenes and never
        # run them
        _wait_for_workers(client, workers or 1, wait_workers, stream)
        yield _dask_runner(client, f"dask scheduler {client.scheduler.address}", warm)
    except BaseException:
        _quiet_dask()  # closing a client of a lost scheduler logs tracebacks
        _close_quietly(client)
        raise
    else:
        client.close()


@contextmanager
def _cluster_runner(n: int, warm):
    """A runner on a local dask cluster of ``n`` single-threaded worker processes."""
    from dask.distributed import Client, LocalCluster

    # no dashboard; the scheduler still serves a small HTTP endpoint, on port 8787 unless told
    # otherwise, and warns when another cluster holds that port: use a free local port instead
    with _workers_ignore_sigint():
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=None,
                               # a task cancelled on Ctrl-C is logged as a warning per worker
                               silence_logs=logging.ERROR,
                               scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
    try:
        client = Client(cluster)
    except BaseException:
        _quiet_dask()
        _close_quietly(cluster)
        raise
    try:
        yield _dask_runner(client, f"local processes x{n}", warm, quiet=True)
    except BaseException:
        # interrupted or failed: dask would log the tracebacks of every comm it closes
        _quiet_dask()
        _close_quietly(client)
        _close_quietly(cluster)
        raise
    else:
        client.close()
        cluster.close()


@contextmanager
def _thread_runner(n: int):
    """A pool of ``n`` threads in this process. On the way out by an exception (Ctrl-C, SIGTERM,
    a lost store) the scenes not started are cancelled and the running ones finish (seconds at
    most) before this returns; their results are not stored."""
    from concurrent.futures import ThreadPoolExecutor

    pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix="ehd-scene")
    try:
        yield Runner(f"local threads x{n}", executor=pool)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


@contextmanager
def _workers_ignore_sigint():
    """Worker processes started in here ignore SIGINT (an ignored signal stays ignored across
    exec): Ctrl-C reaches the whole process group, and only this process should answer it (one
    line, exit 130, the journal keeps every finished scene); the workers are closed by it."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _close_quietly(thing) -> None:
    try:
        thing.close(timeout=2)
    except BaseException:  # noqa: BLE001 - the scheduler is gone; nothing left to close
        pass


def _wait_for_workers(client, n: int, timeout: float, stream) -> None:
    """Wait until ``n`` workers are connected, saying so every 10 s; RunnerError after
    ``timeout`` seconds."""
    t0 = time.monotonic()
    said = None
    while True:
        connected = len(client.nthreads())
        if connected >= n:
            return
        waited = time.monotonic() - t0
        if waited >= timeout:
            if connected == 0 and n == 1:
                raise RunnerError(f"the scheduler has no workers after {timeout:g} s, so no "
                                  "scene could run; start workers (dask worker ADDRESS) or raise "
                                  "--wait-workers")
            raise RunnerError(f"only {connected} of {n} workers connected to the scheduler after "
                              f"{timeout:g} s; start more workers, lower --workers or raise "
                              "--wait-workers")
        if stream is not None and (said is None or waited - said >= 10):
            print(f"waiting for {n} workers ({connected} connected)...", file=stream, flush=True)
            said = waited
        time.sleep(min(0.5, max(timeout - waited, 0.01)))


def _dask_runner(client, description: str, warm, quiet: bool = False) -> Runner:
    from .worker import WorkerSetup

    try:
        # every worker (also one that joins later) sets the environment and loads the cached
        # kernels before its first scene
        client.register_plugin(WorkerSetup(warm, quiet))
    except Exception as exc:
        raise RunnerError(f"setting up the workers failed ({type(exc).__name__}: {exc}); every "
                          "worker needs this project installed (pip install -e .)") from None
    return Runner(description, executor=client.get_executor(pure=False), client=client)
