"""A store that knows its own integrity: which cells, coordinates or metadata cannot be trusted.

A store is checked whole when it is loaded (``load_checked``, used by ``ehd sweep``, ``ehd
status``, ``ehd figures`` and ``pipeline.open_results``; the stores are small, so every chunk is
read once). A reader that needs only some variables (``ehd sweep``: the status, the model and the
messages to plan; ``read=``) has every chunk's checksum verified from its bytes (a few
milliseconds for thousands of chunks, where decoding them through zarr takes about 0.2 ms each)
and decodes only the variables it reads and those the checks below need; the others stay lazy
(:func:`load_rest` decodes them when the writer needs them). A chunk whose checksum fails sends
the load to the full decode, so what is found damaged is the same either way. What is checked,
in this order:

- the root metadata (``zarr.json``): a zarr group whose attributes have the shapes this pipeline
  writes (``store_schema`` a whole number equal to ``STORE_SCHEMA``, ``axes`` a list of names,
  ``fixed_physics`` and ``numerics`` mappings, ...), every variable and coordinate present over
  the right dimensions with checksummed chunks, and ``metadata_sha256`` equal to the sha256 of
  the attributes and of every array's metadata: a changed byte anywhere in the metadata is
  found. Metadata damage cannot be repaired cell by cell: :class:`~pipeline.errors.StoreDamaged`
  (exit 5) naming what is wrong. A store of an older schema is refused
  (:class:`~pipeline.errors.StoreMismatch`, exit 2): it has no checksums to trust.
- the coordinates: readable (their checksum holds), no NaN (a deleted chunk reads as NaN),
  strictly increasing, equal to the copy in the root attr ``grid``. A damaged coordinate is
  replaced by that copy (protected by ``metadata_sha256``) and listed in ``Damage.coords``;
  ``ehd sweep`` rewrites it.
- every chunk of every variable: a chunk that cannot be read or whose CRC-32C does not match (a
  truncated, garbled or flipped-byte chunk) damages every cell of that chunk; nothing about a
  chunk's file (its size, its time stamps) is trusted, only its bytes. A lazy variable's chunk
  whose checksum holds but whose compressed bytes do not decode (only a writer computing a
  checksum over garbage makes one) is found when it is decoded: by ``load_rest``, or by any
  reader that decodes it (``ehd status``, ``ehd figures``, zarr itself);
- a cell whose status says ``ok`` but whose data say "never written" (``REQUIRED``: variables that
  an ok scene always has, e.g. ``v_r``, read NaN, or ``model`` reads 0): a deleted data chunk
  whose status chunk is intact (zarr reads a missing chunk as its fill value);
- a status or model code that is none of ``STATUS_CODES`` / ``MODEL_CODES``.

Damaged cells are never read as data: the sweep turns them into "not run" (the next ``ehd
sweep`` recomputes them and rewrites their chunks); ``ehd status`` lists them (exit 5), ``ehd
figures`` refuses to draw a damaged store (exit 5) and ``open_results`` raises ``StoreDamaged``.

This module reads only; it imports neither the writer (``store``) nor the runner (``run``).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from solver.observables import MODEL_CODES, STATUS_CODES

from ..errors import StoreDamaged, StoreMismatch, UsageError
from .config import format_physics
from .layout import CODECS, STORE_SCHEMA, VARIABLES, zarr_warnings

__all__ = ["Damage", "load_checked", "load_rest", "read_root", "metadata_digest",
           "bad_checksums", "REQUIRED", "CHECKED", "DIGEST_KEY"]

# floats an ok scene always has (finite or inf, never NaN): NaN there means a lost chunk
REQUIRED = ("v_r", "h_m_x1", "h_m_x0", "ln_x_e_x1", "ln_x_e_x0")
# the variables the checks below read: decoded by every load, whatever the reader asks for
CHECKED = ("status", "model", *REQUIRED)
DIGEST_KEY = "metadata_sha256"
FIX = "restore the store from a copy, or move it aside and run its sweep again"


@dataclass
class Damage:
    """Damaged cells of a store: ``cells`` (index tuples, one index per axis) and, per cell, the
    variables that are damaged there and how (``"unreadable"``, ``"missing"``, ``"unknown
    code"``); ``coords``: damaged coordinates (name -> how), replaced by the store's copy."""

    dims: tuple = ()
    where: dict = field(default_factory=dict)  # cell -> sorted list of "var (how)"
    coords: dict = field(default_factory=dict)  # coordinate name -> how

    def __bool__(self) -> bool:
        return bool(self.where) or bool(self.coords)

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
        """One line: damaged coordinates; how many cells, which variables, the first few
        cells' coordinates (the fixed physics, the same for every cell, is not repeated)."""
        parts = [f"coordinate {name} ({how}; its copy in the store's metadata is used)"
                 for name, how in sorted(self.coords.items())]
        cells = self.cells
        if cells:
            shown = [format_physics({d: float(ds[d].values[i]) for d, i in zip(self.dims, cell)})
                     for cell in cells[:limit]]
            more = f" and {len(cells) - limit} more" if len(cells) > limit else ""
            parts.append(f"{len(cells)} damaged cell(s) ({', '.join(self.variables())}): "
                         f"{'; '.join(shown)}{more}")
        return "; ".join(parts)


def metadata_digest(root: dict) -> str:
    """sha256 of the canonical JSON of a store's root attributes (but ``metadata_sha256``) and of
    every array's metadata (the consolidated copy, which is what readers use)."""
    attrs = {k: v for k, v in (root.get("attributes") or {}).items() if k != DIGEST_KEY}
    arrays = (root.get("consolidated_metadata") or {}).get("metadata") or {}
    text = json.dumps({"attributes": attrs, "arrays": arrays}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def read_root(path) -> dict:
    """The parsed root ``zarr.json`` of a sweep store, its shape checked.

    Raises
    ------
    FileNotFoundError
        No store at ``path``, or a zarr store that is not an ehd sweep store.
    UsageError
        ``zarr.json`` is not a zarr group's metadata.
    StoreMismatch
        A store of another schema.
    StoreDamaged
        The metadata has a shape this pipeline never writes, or differs from its checksum.
    """
    path = Path(path)
    meta = path / "zarr.json"
    if not meta.is_file():
        old = path.with_name(path.name + ".old")
        hint = " (an interrupted re-layout left it in .old; run the sweep again)" \
            if old.exists() else ""
        raise FileNotFoundError(f"no sweep store at {str(path)!r}{hint}")
    shown = str(path)
    try:
        root = json.loads(meta.read_bytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, OSError) as exc:
        raise UsageError(f"{shown!r} cannot be opened as an ehd sweep store (its zarr.json is "
                         f"not readable JSON: {type(exc).__name__}); {FIX}") from None
    if not isinstance(root, dict) or root.get("node_type") != "group":
        what = type(root).__name__ if not isinstance(root, dict) else \
            f"node_type {root.get('node_type')!r}"
        raise UsageError(f"{shown!r} cannot be opened as an ehd sweep store (its zarr.json is not "
                         f"a zarr group's metadata: {what}); {FIX}")
    attrs = root.get("attributes")
    if not isinstance(attrs, dict):
        raise StoreDamaged(f"store {shown!r} is damaged: its attributes are a "
                           f"{type(attrs).__name__}, not a mapping; {FIX}")
    if "store_schema" not in attrs:
        raise FileNotFoundError(f"{shown!r} is a zarr store but not an ehd sweep store")
    schema = attrs["store_schema"]
    if not isinstance(schema, int) or isinstance(schema, bool):
        raise StoreDamaged(f"store {shown!r} is damaged: store_schema is {schema!r} (a "
                           f"{type(schema).__name__}); this pipeline writes the whole number "
                           f"{STORE_SCHEMA}; {FIX}")
    if schema != STORE_SCHEMA:
        note = " (its chunks carry no checksum, so its numbers cannot be verified)" \
            if schema < 6 else ""
        raise StoreMismatch(f"{shown!r} has store schema {schema}{note}, this pipeline reads and "
                            f"writes schema {STORE_SCHEMA}; move the old store aside and run its "
                            "sweep again, or use --store PATH")
    problems = _shape_problems(root)
    if not problems and attrs.get(DIGEST_KEY) != metadata_digest(root):
        problems = [f"its metadata differs from its checksum ({DIGEST_KEY}): zarr.json was "
                    "changed after it was written"]
    if problems:
        raise StoreDamaged(f"store {shown!r} is damaged: {'; '.join(problems[:3])}"
                           f"{f' and {len(problems) - 3} more' if len(problems) > 3 else ''}; "
                           f"{FIX}")
    return root


def _shape_problems(root: dict) -> list:
    """What in a schema-``STORE_SCHEMA`` root metadata has a shape this pipeline never writes."""
    attrs = root["attributes"]
    out = []
    axes = attrs.get("axes")
    if not (isinstance(axes, list) and axes and all(isinstance(a, str) for a in axes)):
        out.append(f"axes is {axes!r}, not a list of names")
        axes = None
    for key, kind in (("fixed_physics", dict), ("numerics", dict), ("grid", dict),
                      ("cache_key", str), ("solver_version", str), ("sweeps", list)):
        if not isinstance(attrs.get(key), kind):
            out.append(f"{key} is {_short(attrs.get(key))} (a {type(attrs.get(key)).__name__}), "
                       f"not a {kind.__name__}")
    fixed = attrs.get("fixed_physics")
    if isinstance(fixed, dict):
        bad = [k for k, v in fixed.items()
               if not (isinstance(v, (int, float, str)) or v is None) or isinstance(v, bool)]
        if bad:
            out.append(f"fixed_physics has values of the wrong type ({', '.join(bad)})")
    if isinstance(attrs.get("sweeps"), list) and \
            not all(isinstance(e, dict) for e in attrs["sweeps"]):
        out.append("sweeps is not a list of mappings")
    arrays = (root.get("consolidated_metadata") or {}).get("metadata")
    if not isinstance(arrays, dict):
        return out + ["it has no consolidated metadata"]
    if axes is None:
        return out
    shape = None
    for name in (*VARIABLES, *axes):
        meta = arrays.get(name)
        dims = tuple(axes) if name in VARIABLES else (name,)
        if not isinstance(meta, dict):
            out.append(f"variable {name} is missing")
            continue
        codecs = meta.get("codecs")
        names = [c.get("name") for c in codecs if isinstance(c, dict)] \
            if isinstance(codecs, list) else []
        if not all(c in names for c in CODECS):
            out.append(f"{name} has no checksummed chunks (codecs {names})")
        if tuple(meta.get("dimension_names") or ()) != dims:
            out.append(f"{name} is over {meta.get('dimension_names')!r}, not {list(dims)}")
        if name in VARIABLES:
            shape = meta.get("shape") if shape is None else shape
            if meta.get("shape") != shape:
                out.append(f"{name} has shape {meta.get('shape')}, status {shape}")
    grid = attrs.get("grid")
    if isinstance(grid, dict) and isinstance(shape, list) and len(shape) == len(axes):
        for a, n in zip(axes, shape):
            copy = grid.get(a)
            if not (isinstance(copy, list) and len(copy) == n and all(_is_float(v) for v in copy)):
                out.append(f"grid.{a} (the copy of the coordinate) is not {n} numbers")
            elif (arrays.get(a) or {}).get("shape") != [n]:
                out.append(f"coordinate {a} has shape {(arrays.get(a) or {}).get('shape')}, not "
                           f"[{n}]")
    return out


def _short(v) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _is_float(text) -> bool:
    if not isinstance(text, str):
        return False
    try:
        return not math.isnan(float(text))
    except ValueError:
        return False


def _chunk_files(path: str, meta: dict):
    """``(chunk index, file)`` of every chunk an array's metadata says it has (zarr's default
    chunk key encoding, ``c/i/j``), or None for a layout this pipeline does not write (the
    caller then decodes the array through zarr)."""
    try:
        shape = [int(n) for n in meta["shape"]]
        chunks = [int(n) for n in meta["chunk_grid"]["configuration"]["chunk_shape"]]
        encoding = meta["chunk_key_encoding"]
        sep = (encoding.get("configuration") or {}).get("separator", "/")
    except (KeyError, TypeError, ValueError, AttributeError):
        return None
    if encoding.get("name") != "default" or sep not in ("/", ".") or len(shape) != len(chunks) \
            or not all(c > 0 for c in chunks):
        return None
    grid = [-(-n // c) for n, c in zip(shape, chunks)]
    # plain strings: thousands of pathlib joins cost more than reading the files
    return [(idx, os.path.join(path, sep.join(("c", *map(str, idx)))))
            for idx in np.ndindex(*grid)]


def bad_checksums(path, arrays: dict, names) -> dict | None:
    """The chunks of the arrays ``names`` whose bytes fail their CRC-32C: ``{name: [chunk index,
    ...]}`` (only names with a failing chunk), from the files alone, without zarr.

    The check zarr's ``crc32c`` codec makes when it decodes a chunk (the zarr v3 spec: the last 4
    bytes are the little-endian CRC-32C of the bytes before them): a chunk that cannot be read,
    is shorter than its checksum or whose checksum does not match fails. A missing chunk does not
    (zarr reads it as the fill value: the data checks of :func:`load_checked` find lost ones).
    None: an array whose last codec is not ``crc32c`` or whose chunk layout is not zarr's
    default, which only zarr can check."""
    import google_crc32c  # zarr's own CRC-32C (its crc32c codec imports it)

    bad = {}
    for name in names:
        meta = arrays.get(name) or {}
        codecs = meta.get("codecs") or [{}]
        files = _chunk_files(os.path.join(path, name), meta)
        if files is None or not isinstance(codecs[-1], dict) \
                or codecs[-1].get("name") != "crc32c":
            return None
        for idx, file in files:
            try:
                with open(file, "rb") as f:
                    data = f.read()
            except FileNotFoundError:
                continue
            except OSError:
                data = b""
            if len(data) < 4 or \
                    google_crc32c.value(data[:-4]) != int.from_bytes(data[-4:], "little"):
                bad.setdefault(name, []).append(idx)
    return bad


def load_checked(path, read=None):
    """Load a sweep store, checking its metadata, coordinates and every chunk once.

    Parameters
    ----------
    path : str or Path
        The store.
    read : iterable of str, optional
        The variables the caller reads (default: all, decoded). The others are decoded only if
        a chunk's checksum fails (then everything is, so damage is found as without ``read``);
        otherwise they stay lazy (their checksums verified from the chunks' bytes; decode them
        with :func:`load_rest`). ``CHECKED`` is always decoded.

    Returns
    -------
    (xarray.Dataset, Damage)
        The loaded dataset (damaged chunks hold their fill value, damaged coordinates their copy)
        and what is damaged.

    Raises
    ------
    FileNotFoundError, UsageError, StoreMismatch, StoreDamaged
        As :func:`read_root`: no sweep store, or metadata that cannot be trusted.
    """
    import pandas as pd
    import xarray as xr
    import zarr

    root = read_root(path)
    attrs = root["attributes"]
    dims = tuple(attrs["axes"])
    arrays = root["consolidated_metadata"]["metadata"]
    damage = Damage(dims=dims)
    with zarr_warnings():
        group = zarr.open_group(str(path), mode="r", use_consolidated=True)
        coords = {}
        for d in dims:
            copy = np.array([float(v) for v in attrs["grid"][d]])
            how = None
            try:
                values = np.asarray(group[d][:], dtype=float)
            except Exception:  # noqa: BLE001 - any decode failure of any codec (checksum, zstd)
                how = "unreadable"
            else:
                if np.isnan(values).any():
                    how = "missing"  # a deleted chunk reads as the fill value
                elif not np.array_equal(values, copy):
                    how = "differs from its copy"
            if copy.size > 1 and not np.all(np.diff(copy) > 0):
                raise StoreDamaged(f"store {str(path)!r} is damaged: coordinate {d} is not "
                                   f"strictly increasing; {FIX}")
            if how is not None:
                damage.coords[d] = how
            coord_attrs = {k: v for k, v in (arrays[d].get("attributes") or {}).items()
                           if not k.startswith("_")}
            # a Variable on xarray's fast path, over a pandas Index: the (dims, values, attrs)
            # tuple form, or plain values made into the coordinate's index, make xarray import
            # dask and pint (0.5 s) to ask whether the values are one of their arrays
            coords[d] = xr.Variable(d, pd.Index(copy, name=d), coord_attrs, fastpath=True)
        lazy = xr.open_zarr(path, consolidated=True, chunks=None, drop_variables=list(dims))
    lazy = lazy.assign_coords(coords)
    names = list(lazy.data_vars)
    decode = names
    if read is not None:
        rest = [n for n in names if n not in {*read, *CHECKED}]
        if rest and bad_checksums(path, arrays, rest) == {}:
            decode = [n for n in names if n not in rest]
    for name in decode:
        _load_variable(lazy, name, damage)
    ds = lazy
    status = ds["status"].values
    known = np.isin(status, list(STATUS_CODES.values()))
    for cell in np.argwhere(~known):
        damage.add(cell, f"status (unknown code {int(status[tuple(cell)])})")
    ok = status == STATUS_CODES["ok"]
    for name in REQUIRED:
        if name in ds:
            for cell in np.argwhere(ok & np.isnan(ds[name].values)):
                if f"{name} (unreadable)" not in damage.where.get(tuple(cell), ()):
                    damage.add(cell, f"{name} (missing)")
    if "model" in ds:
        model = ds["model"].values
        for cell in np.argwhere(ok & (model == 0)):
            damage.add(cell, "model (missing)")
        for cell in np.argwhere(~np.isin(model, [0, *MODEL_CODES.values()])):
            damage.add(cell, f"model (unknown code {int(model[tuple(cell)])})")
    return ds, damage


def load_rest(ds, damage: Damage) -> None:
    """Decode, in place, the variables of ``ds`` that ``load_checked(read=...)`` left lazy;
    chunks that do not decode hold their fill value and add their cells to ``damage``."""
    for name in list(ds.data_vars):
        _load_variable(ds, name, damage)  # a decoded variable: nothing to do


def _load_variable(ds, name, damage: Damage) -> None:
    variable = ds.variables[name]
    try:
        variable.load()  # in place: the dataset keeps the values
    except Exception:  # noqa: BLE001 - any decode failure of any codec: find the chunks
        variable.data = _read_by_chunk(name, ds[name], damage)


def _read_by_chunk(name, var, damage: Damage) -> np.ndarray:
    """Read ``var`` chunk by chunk (chunks are 1 along every axis but the last): damaged chunks
    keep the fill value and add their cells to ``damage``."""
    dtype = var.dtype
    if dtype.kind == "f":
        out = np.full(var.shape, np.nan, dtype=dtype)
    elif dtype.kind in "OUST":
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
