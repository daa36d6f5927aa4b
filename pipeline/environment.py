"""The process environment of everything that solves scenes, in one place.

- One BLAS/OpenMP thread per process (``configure``), set before numpy/scipy load their BLAS: a
  sweep runs one scene per core, and threaded BLAS is slower for these matrix sizes and changes
  the last digits of results (docs/solver.md). Existing settings win. ``pipeline/__init__.py``
  calls it first thing, and the dask worker plugin (``pipeline.sweeps.worker.WorkerSetup``) on
  every worker, also on workers that join the cluster later. This module imports nothing heavy.
  A worker started by ``dask worker`` has loaded numpy before the plugin runs, so there the
  variables must also be exported by whoever starts it (docs/pipeline.md, SLURM); local clusters
  inherit them from this process.
- Where compiled kernels are cached is the solver's decision (``solver._jit``, documented in
  docs/solver.md), the same for every command and install kind; nothing here changes it.
"""

from __future__ import annotations

import os

__all__ = ["configure", "THREAD_VARS", "info", "compile_notice"]

THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def configure() -> None:
    """One BLAS/OpenMP thread unless the user chose otherwise (call before numpy is imported)."""
    for var in THREAD_VARS:
        os.environ.setdefault(var, "1")


def info() -> dict:
    """What a user reporting a problem should paste: versions, cache folder, threads."""
    from importlib.metadata import PackageNotFoundError, version

    from solver import SOLVER_VERSION
    from solver import _jit

    try:
        package = version("ehd-collision")
    except PackageNotFoundError:
        package = "not installed (run from a clone)"
    return {"package_version": package, "solver_version": SOLVER_VERSION,
            "cache_dir": _jit.CACHE_DIR,
            **{var: os.environ.get(var, "unset") for var in THREAD_VARS}}


_NOTICE_GIVEN = False


def compile_notice(stream=None) -> str | None:
    """Before the first solve of a process: one line on ``stream`` (stderr) when the solver's
    compiled-code cache for this solver version is empty, so that the compile (12-18 s of CPU
    for each loop a process solves with: the classic film's, one piece's, all pieces':
    benchmarks/compile.md, longer in wall time on a busy machine; once per solver version and
    cache folder) is not a silent wait. A loop solved with later for the first time compiles
    without a notice (solver/integration/kinds.py). Says where the cache goes. Returns
    the line (None: nothing to say)."""
    global _NOTICE_GIVEN
    import sys
    from pathlib import Path

    if _NOTICE_GIVEN:
        return None
    _NOTICE_GIVEN = True
    from solver import _jit

    folder = _jit.CACHE_DIR
    if folder is None:
        line = ("ehd-collision: compiling the solver (about 15 s on an idle core, minutes on a "
                "busy machine); no writable cache folder, so every process compiles again: set "
                "EHD_CACHE_DIR to a writable folder")
    elif not any(Path(folder).rglob("*.nbi")):
        line = ("ehd-collision: compiling the solver for this version, once per set of physics "
                "(about 15 s on an idle core, minutes on a busy machine); cached in "
                f"{folder} (ehd info; EHD_CACHE_DIR moves it)")
    else:
        return None
    print(line, file=stream or sys.stderr, flush=True)
    return line
