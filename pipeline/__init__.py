"""ehd-collision pipeline: sweeps over (St, eps), their cached zarr store, figures, command line.

Analysts open a sweep store with ``pipeline.open_results("results/paper.zarr")`` (or plain
``xarray.open_zarr``); docs/pipeline.md describes the store.
"""

from .store import open_results

__all__ = ["open_results"]
