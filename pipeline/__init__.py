"""ehd-collision pipeline: sweeps over (St, eps), their cached zarr store, figures, command line.

Analysts open a sweep store with ``pipeline.open_results("results/paper.zarr")`` (or plain
``xarray.open_zarr``); docs/pipeline.md describes the store.
"""

# First, before anything loads numpy: one BLAS/OpenMP thread per process (pipeline/environment.py).
from .environment import configure as _configure  # noqa: E402  (imports nothing heavy)

_configure()

__all__ = ["open_results"]


def __getattr__(name):
    # loaded on first use (PEP 562): every ``ehd`` command imports this package, and the store
    # brings in xarray, zarr and the solver's registry, which most commands do not need
    if name == "open_results":
        from .sweeps.store import open_results

        return open_results
    raise AttributeError(f"module 'pipeline' has no attribute {name!r}")
