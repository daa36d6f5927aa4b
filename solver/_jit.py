"""The one place that owns numba's compile flags.

- ``cache=True`` with ``NUMBA_CACHE_DIR`` set by the Makefile (``make clean-cache`` after editing a
  kernel that another file imports: numba does not track cross-file changes, numba issue 1833).
- ``nogil=True`` so threads can run scenes side by side.
- A NaN-safe fastmath subset: ``fastmath=True`` would make ``np.isfinite`` always true
  (numba issues 2919, 6217), and failure detection depends on it.
- ``error_model="numpy"``: division by zero gives inf (checked by the caller), not an exception.
"""

import numba

FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}


def jit(func):
    return numba.njit(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy")(func)
