"""The process environment of everything that solves scenes, in one place.

- One BLAS/OpenMP thread per process (``configure``), set before numpy/scipy load their BLAS: a
  sweep runs one scene per core, and threaded BLAS is slower for these matrix sizes and changes
  the last digits of results (docs/solver.md). Existing settings win. ``pipeline/__init__.py``
  calls it first thing, and the dask worker plugin (``pipeline.sweeps.runners.WorkerSetup``) on
  every worker, also on workers that join the cluster later. This module imports nothing heavy.
  A worker started by ``dask worker`` has loaded numpy before the plugin runs, so there the
  variables must also be exported by whoever starts it (docs/pipeline.md, SLURM); local clusters
  inherit them from this process.
- Where compiled kernels are cached is the solver's decision (``solver._jit``, documented in
  docs/solver.md), the same for every command and install kind; nothing here changes it.
"""

from __future__ import annotations

import os

__all__ = ["configure", "THREAD_VARS", "info"]

THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def configure() -> None:
    """One BLAS/OpenMP thread unless the user chose otherwise (call before numpy is imported)."""
    for var in THREAD_VARS:
        os.environ.setdefault(var, "1")


def info() -> dict:
    """What a user reporting a problem should paste: solver version, cache folder, threads."""
    from solver import SOLVER_VERSION
    from solver import _jit

    return {"solver_version": SOLVER_VERSION, "cache_dir": _jit.CACHE_DIR,
            **{var: os.environ.get(var, "unset") for var in THREAD_VARS}}
