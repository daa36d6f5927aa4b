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


_NOTICED = set()  # the loops (solver/integration/kinds.py: compiled_pieces) already announced


def _loop_name(codes) -> str:
    """A loop (its pieces, ``kinds.compiled_pieces``) as the notice names it, with its cold
    compile in CPU seconds (benchmarks/compile.md: 11.3; 19.0-20.0; a tenth more in a busier
    hour): the classic film's copy, or the loop with every piece, which any piece runs on
    (``kinds.MOST_PIECES`` is 0)."""
    if not codes:
        return "the loop for the classic film (about 11 s on an idle core)"
    return "the loop for every piece of physics (about 20 s on an idle core)"


def compile_notice(stream=None, physics=None) -> str | None:
    """Before a process first solves with a compiled loop its cache lacks: one line on ``stream``
    (stderr), so that the compile is not a silent wait. ``physics``: what is about to be solved
    (``Physics`` records, mappings of their fields, or None for the classic film; None: the
    classic film alone). Each loop (solver/integration/kinds.py: the classic film's copy, the
    loop with every piece) compiles once per solver version and cache folder, about 11 and 20 s
    of CPU (benchmarks/compile.md; longer in wall time on a busy machine), and is announced once
    per process. Says where the cache goes. Returns the line (None: nothing to say)."""
    import sys

    from solver import Physics, _jit
    from solver.integration import kinds

    asked = []
    for p in physics if physics is not None else [None]:
        try:
            p = p if p is None or isinstance(p, Physics) else Physics.from_mapping(p)
        except ValueError:  # an invalid scene: its solve says so, and compiles nothing
            continue
        codes = () if p is None else kinds.compiled_pieces(p.as_array())
        if codes not in asked:
            asked.append(codes)
    new = [codes for codes in asked if codes not in _NOTICED and not kinds.is_cached(codes)]
    _NOTICED.update(asked)
    if not new:
        return None
    what = " and ".join(_loop_name(codes) for codes in new)
    folder = _jit.CACHE_DIR
    if folder is None:
        line = (f"ehd-collision: compiling the solver: {what}, minutes on a busy machine; no "
                "writable cache folder, so every process compiles again: set EHD_CACHE_DIR to a "
                "writable folder")
    else:
        line = (f"ehd-collision: compiling the solver for this version: {what}, minutes on a "
                f"busy machine; cached in {folder} (ehd info; EHD_CACHE_DIR moves it)")
    print(line, file=stream or sys.stderr, flush=True)
    return line
