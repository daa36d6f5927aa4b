"""The dask worker plugin of a sweep (:class:`WorkerSetup`), apart from the runners because it
subclasses ``distributed.WorkerPlugin``: importing distributed costs 0.3-0.5 s, paid only when a
cluster is started or reached (benchmarks/startup.md), never by a sweep with nothing to do."""

from __future__ import annotations

from distributed import WorkerPlugin

from ..environment import configure

__all__ = ["WorkerSetup"]


class WorkerSetup(WorkerPlugin):
    """Runs on every dask worker before its first task, also on workers that join later: the
    process environment (pipeline/environment.py), then ``warm()``, which loads the kernels the
    parent compiled into the on-disk cache instead of compiling them again.

    ``quiet``: the worker's own dask logging is silenced (below CRITICAL). Set for the local
    cluster, whose workers write to the user's terminal: whatever fails on them reaches the sweep
    as a scene's error (stored with its reason) or as a lost worker, and what they log besides
    is a closing cluster's noise, e.g. a heartbeat to the scheduler the interrupted sweep just
    closed, with its traceback. Workers of an existing scheduler keep their logging."""

    name = "ehd-worker-setup"

    def __init__(self, warm=None, quiet=False):
        self.warm = warm
        self.quiet = quiet

    def setup(self, worker):
        if self.quiet:
            import logging

            from .runners import _quiet_dask

            _quiet_dask(level=logging.CRITICAL)
        configure()
        if self.warm is not None:
            self.warm()
