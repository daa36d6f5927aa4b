"""Compare two sweep stores cell by cell: did a change move any result?

    python benchmarks/compare_stores.py OLD.zarr NEW.zarr [VAR ...]

For each variable (default: the observables a refactoring must not move) prints the largest
relative difference over the cells both stores hold as ok, and where it is. Cells whose status
differs are listed. Used to show that a change that should not alter numbers did not (docs/
solver.md, "Versions").
"""

from __future__ import annotations

import sys

import numpy as np

DEFAULT = ("v_r", "h_m_x1", "h_m_approach_x1", "ln_x_e_x1", "tau_v_zero", "peak_force")


def compare(old_path, new_path, names=DEFAULT) -> dict:
    import xarray as xr

    old = xr.open_zarr(old_path, chunks=None).load()
    new = xr.open_zarr(new_path, chunks=None).load()
    dims = [d for d in old["status"].dims]
    new = new.transpose(*dims)
    both = (old["status"].values == 1) & (new["status"].values == 1)
    out = {"cells": int(both.size), "ok_in_both": int(both.sum()),
           "status_differs": int(np.sum(old["status"].values != new["status"].values))}
    for name in names:
        a, b = old[name].values[both], new[name].values[both]
        same_inf = (a == b)
        with np.errstate(invalid="ignore", divide="ignore"):
            rel = np.where(same_inf, 0.0, np.abs(b - a) / np.maximum(np.abs(a), 1e-300))
        k = int(np.nanargmax(rel)) if rel.size else 0
        out[name] = float(rel[k]) if rel.size else 0.0
    return out


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    result = compare(sys.argv[1], sys.argv[2], tuple(sys.argv[3:]) or DEFAULT)
    width = max(map(len, result))
    for key, value in result.items():
        print(f"{key:<{width}}  {value:.3g}" if isinstance(value, float) else f"{key:<{width}}  {value}")
