"""A store that knows its own integrity: which cells cannot be trusted, and why.

Two kinds of damage are detected when a store is loaded whole (``load_checked``, used by ``ehd
sweep``, ``ehd status`` and ``ehd figures``; the stores are small, so every chunk is read once):

- a chunk that cannot be read or decoded (a truncated or garbled chunk file): every cell of that
  chunk is damaged;
- a cell whose status says ``ok`` but whose data say "never written" (``REQUIRED``: variables that
  an ok scene always has, e.g. ``v_r``, read NaN, or ``model`` reads 0): a deleted data chunk
  whose status chunk is intact (zarr reads a missing chunk as its fill value).

Damaged cells are never read as data: ``forget`` turns them into "not run" in memory (the next
``ehd sweep`` recomputes them and rewrites their chunks); ``ehd status`` lists them (exit 5) and
``ehd figures`` refuses to draw a damaged store (exit 5).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from solver.observables import STATUS_CODES

__all__ = ["Damage", "load_checked", "REQUIRED"]

# floats an ok scene always has (finite or inf, never NaN): NaN there means a lost chunk
REQUIRED = ("v_r", "h_m_x1", "h_m_x0", "ln_x_e_x1", "ln_x_e_x0")


@dataclass
class Damage:
    """Damaged cells of a store: ``cells`` (index tuples, one index per axis) and, per cell, the
    variables that are damaged there and how (``"unreadable"`` or ``"missing"``)."""

    dims: tuple = ()
    where: dict = field(default_factory=dict)  # cell -> sorted list of "var (how)"

    def __bool__(self) -> bool:
        return bool(self.where)

    def __len__(self) -> int:
        return len(self.where)

    @property
    def cells(self) -> list:
        return sorted(self.where)

    def add(self, cell, what: str) -> None:
        self.where.setdefault(tuple(int(i) for i in cell), set()).add(what)

    def variables(self) -> list:
        return sorted({w for ws in self.where.values() for w in ws})

    def describe(self, ds, fixed: dict | None = None, limit: int = 3) -> str:
        """One line: how many cells, which variables, the first few cells' physics."""
        from .run import format_physics

        cells = self.cells
        shown = []
        for cell in cells[:limit]:
            physics = {**(fixed or {}),
                       **{d: float(ds[d].values[i]) for d, i in zip(self.dims, cell)}}
            shown.append(format_physics(physics))
        more = f" and {len(cells) - limit} more" if len(cells) > limit else ""
        return (f"{len(cells)} damaged cell(s) ({', '.join(self.variables())}): "
                f"{'; '.join(shown)}{more}")


def load_checked(path):
    """Load a sweep store whole, reading every chunk of every variable once.

    Returns
    -------
    (xarray.Dataset, Damage)
        The loaded dataset (damaged chunks hold their fill value) and what is damaged.
    """
    import xarray as xr

    from .layout import zarr_warnings

    with zarr_warnings():
        lazy = xr.open_zarr(path, consolidated=True, chunks=None)
    dims = tuple(lazy["status"].dims)
    damage = Damage(dims=dims)
    for name in list(lazy.data_vars):
        variable = lazy.variables[name]
        try:
            variable.load()  # in place: the dataset keeps the values
        except Exception:  # noqa: BLE001 - any decode failure of any codec: find the chunks
            variable.data = _read_by_chunk(name, lazy[name], damage)
    ds = lazy.load()
    status = ds["status"].values
    ok = status == STATUS_CODES["ok"]
    for name in REQUIRED:
        if name in ds:
            for cell in np.argwhere(ok & np.isnan(ds[name].values)):
                if f"{name} (unreadable)" not in damage.where.get(tuple(cell), ()):
                    damage.add(cell, f"{name} (missing)")
    if "model" in ds:
        for cell in np.argwhere(ok & (ds["model"].values == 0)):
            damage.add(cell, "model (missing)")
    return ds, damage


def _read_by_chunk(name, var, damage: Damage) -> np.ndarray:
    """Read ``var`` chunk by chunk (chunks are 1 along every axis but the last): damaged chunks
    keep the fill value and add their cells to ``damage``."""
    dtype = var.dtype
    if dtype.kind == "f":
        out = np.full(var.shape, np.nan, dtype=dtype)
    elif dtype.kind in "OUS":
        out = np.full(var.shape, "", dtype=object)
    else:
        out = np.zeros(var.shape, dtype=dtype)
    dims = var.dims
    lead = var.shape[:-1]
    for idx in np.ndindex(*lead):
        sel = dict(zip(dims[:-1], idx))
        try:
            out[idx] = var.isel(sel).values
        except Exception:  # noqa: BLE001
            for j in range(var.shape[-1]):
                damage.add((*idx, j), f"{name} (unreadable)")
    return out
