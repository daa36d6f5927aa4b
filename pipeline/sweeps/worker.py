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
    parent compiled into the on-disk cache instead of compiling them again."""

    name = "ehd-worker-setup"

    def __init__(self, warm=None):
        self.warm = warm

    def setup(self, worker):
        configure()
        if self.warm is not None:
            self.warm()
