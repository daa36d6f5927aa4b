"""The one place that owns numba's compile flags and cache location.

- ``cache=True``, in a cache folder keyed by a hash of every solver source file: numba checks only
  the defining file's time stamp, so a change in a kernel that another file calls would otherwise
  run stale machine code (numba issues 1833, 9483). The folder sits under ``NUMBA_CACHE_DIR``
  (the Makefile points it at ``.numba_cache/`` in the project) or ``~/.cache/ehd-collision``.
- ``nogil=True`` so threads can run scenes side by side.
- A NaN-safe fastmath subset: ``fastmath=True`` would make ``np.isfinite`` always true
  (numba issues 2919, 6217), and failure detection depends on it. Without ``reassoc``: it let
  the summation order depend on how a kernel was compiled, so freshly compiled and cache-loaded
  code differed in the last digits (the elastic product uses BLAS instead, linalg.matvec).
- ``error_model="numpy"``: division by zero gives inf (checked by the caller), not an exception.
"""

import hashlib
import os
from pathlib import Path

import numba

FASTMATH = {"nsz", "arcp", "contract", "afn"}


def _source_hash() -> str:
    digest = hashlib.sha256()
    root = Path(__file__).parent
    for path in sorted(root.rglob("*.py")):  # sub-packages too: a kernel may call any of them
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _cache_dir() -> str:
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.path.expanduser("~"), ".cache", "ehd-collision", "numba")
    return os.path.join(base, f"solver-{_source_hash()}")


numba.config.CACHE_DIR = _cache_dir()


def jit(func):
    return numba.njit(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy")(func)
