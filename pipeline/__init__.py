"""ehd-collision pipeline: sweeps over (St, eps), their cached zarr store, figures, command line.

Analysts open a sweep store with ``pipeline.open_results("results/paper.zarr")`` (or plain
``xarray.open_zarr``); docs/pipeline.md describes the store.
"""

# First, before anything loads numpy: one BLAS/OpenMP thread per process (pipeline/environment.py).
from .environment import configure as _configure  # noqa: E402  (imports nothing heavy)

_configure()

from .sweeps.store import open_results  # noqa: E402

__all__ = ["open_results"]
