"""ehd-collision pipeline: sweeps over (St, eps), their cached zarr store, figures, command line.

Analysts open a sweep store with ``pipeline.open_results("results/paper.zarr")`` (or plain
``xarray.open_zarr``); docs/pipeline.md describes the store.
"""

import os

# One BLAS/OpenMP thread per process, set before numpy/scipy load their BLAS (importing the store
# below loads numpy): a sweep runs one scene per core, and threaded BLAS is slower for these
# matrix sizes and changes the last digits of results (docs/solver.md). Existing settings win.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from .sweeps.store import open_results  # noqa: E402

__all__ = ["open_results"]
