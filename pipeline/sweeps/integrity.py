"""A store that knows its own integrity: which cells, coordinates or metadata cannot be trusted.

A store is checked whole when it is loaded (``load_checked``, used by ``ehd sweep``, ``ehd
status``, ``ehd figures`` and ``pipeline.open_results``; the stores are small, so every chunk is
read once). A reader that needs only some variables (``ehd sweep``: the status, the model and the
messages to plan; ``read=``) has every chunk verified from its bytes (its sha256 and CRC-32C: a
few milliseconds for thousands of chunks, where decoding them through zarr takes about 0.2 ms
each) and decodes only the variables it reads and those the checks below need; the others stay
lazy (:func:`load_rest` decodes them when the writer needs them). A chunk that fails sends the
load to the full decode, so what is found damaged is the same either way. What is checked, in
this order:

- the files: every entry under the store is a directory or a regular file (a symbolic link, a
  FIFO, a device or a socket inside a store is refused: a link would be read, and written, as
  if it were the store's own file, a FIFO blocks a read forever), and every file is read through
  pipeline/sweeps/files.py: never through a link, never more than such a file can hold;
- the root metadata (``zarr.json``): a zarr group whose attributes have the shapes this pipeline
  writes (``store_schema`` a whole number equal to ``STORE_SCHEMA``, ``axes`` a list of names,
  ``fixed_physics`` and ``numerics`` mappings, ...), every variable and coordinate present over
  the right dimensions with checksummed chunks in zarr's default layout, every array's own
  ``zarr.json`` equal to its consolidated copy (zarr's writes read that file), and
  ``metadata_sha256`` equal to the sha256 of the attributes and of every array's metadata: a
  changed byte anywhere in the metadata is found. Metadata damage cannot be repaired cell by
  cell: :class:`~pipeline.errors.StoreDamaged` (exit 5) naming what is wrong. A store of an
  older schema is refused (:class:`~pipeline.errors.StoreMismatch`, exit 2): its chunks are not
  bound to their places (before schema 6 they had no checksum at all);
- the manifest (pipeline/sweeps/manifest.py): its own checksum, and the metadata digest it
  names equal to the store's;
- every chunk of every variable and coordinate (:func:`chunk_damage`): one that cannot be read or
  whose CRC-32C does not match (a truncated, garbled or flipped-byte chunk) is ``unreadable``;
  one whose sha256 differs from the manifest's digest for its place (a chunk copied from another
  cell, variable or store) is ``replaced``; one the manifest lists but whose file is gone is
  ``missing``. It damages every cell of that chunk; nothing about a chunk's file (its size, its
  time stamps) is trusted, only its bytes;
- the coordinates: readable, no NaN (a deleted chunk reads as NaN), strictly increasing, equal
  to the copy in the root attr ``grid``. A damaged coordinate is replaced by that copy
  (protected by ``metadata_sha256``) and listed in ``Damage.coords``; ``ehd sweep`` rewrites it;
- a cell whose status says ``ok`` but whose data say "never written" (``REQUIRED``: variables that
  an ok scene always has, e.g. ``v_r``, read NaN, or ``model`` reads 0);
- a status or model code that is none of ``STATUS_CODES`` / ``MODEL_CODES``.

A lazy variable's chunk whose digest and checksum hold but whose compressed bytes do not decode
(only a writer computing them over garbage makes one) is found when it is decoded: by
``load_rest``, or by any reader that decodes it (``ehd status``, ``ehd figures``, zarr itself).

Damaged cells are never read as data: the sweep turns them into "not run" (the next ``ehd
sweep`` recomputes them and rewrites their chunks); ``ehd status`` lists them (exit 5), ``ehd
figures`` refuses to draw a damaged store (exit 5) and ``open_results`` raises ``StoreDamaged``.

A sweep may write the store while it is read: :func:`load_checked` reads one consistent state
(the manifest is the generation; see there), so a healthy store is never reported damaged.

This module reads only; it imports neither the writer (``store``) nor the runner (``run``).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from solver.observables import MODEL_CODES, STATUS_CODES

from ..errors import EhdError, StoreDamaged, StoreMismatch, UsageError
from .config import format_physics
from .files import BadFile, foreign_entries, read_regular
from .layout import CODECS, STORE_SCHEMA, VARIABLES, zarr_warnings
from .manifest import (MANIFEST_LIMIT, MANIFEST_NAME, ManifestError, chunk_keys, digest,
                       parse_manifest, read_manifest, reading, same_state, writer_gone)

__all__ = ["Damage", "load_checked", "load_rest", "read_root", "metadata_digest",
           "chunk_damage", "REQUIRED", "CHECKED", "DIGEST_KEY"]

# floats an ok scene always has (finite or inf, never NaN): NaN there means a lost chunk
REQUIRED = ("v_r", "h_m_x1", "h_m_x0", "ln_x_e_x1", "ln_x_e_x0")
# the variables the checks below read: decoded by every load, whatever the reader asks for
CHECKED = ("status", "model", *REQUIRED)
DIGEST_KEY = "metadata_sha256"
FIX = "restore the store from a copy, or move it aside and run its sweep again"
METADATA_LIMIT = 64 * 2**20  # a zarr.json: the root holds the sweep files' text, the consolidated copy
STRING_CHUNK_LIMIT = 64 * 2**20  # a chunk of messages (vlen-utf8: no size follows from the shape)
READ_TRIES = 10  # reads of a store that a sweep changed meanwhile, before giving up (exit 2)
WRITING_WAIT = 30.0  # seconds a reader waits for a live writer to publish its next manifest
POLL_SECONDS = 0.02


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
    shown = str(path)
    if not os.path.isdir(path) or not os.path.lexists(meta):
        old = path.with_name(path.name + ".old")
        hint = " (an interrupted re-layout left it in .old; run the sweep again)" \
            if old.exists() else ""
        raise FileNotFoundError(f"no sweep store at {shown!r}{hint}")
    try:
        root = json.loads(read_regular(meta, METADATA_LIMIT).decode("utf-8"))
    except BadFile as exc:
        raise StoreDamaged(f"store {shown!r} is damaged: {exc}; {FIX}") from None
    except (UnicodeDecodeError, json.JSONDecodeError, OSError) as exc:
        if os.path.lexists(path / MANIFEST_NAME):  # a sweep wrote it: a damaged store (exit 5)
            raise StoreDamaged(f"store {shown!r} is damaged: its zarr.json is not readable JSON "
                               f"({type(exc).__name__}); {FIX}") from None
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
            if schema < 6 else (" (its chunks are not bound to their places: a chunk copied "
                                "from another cell passes its checksum)" if schema < 8 else "")
        raise StoreMismatch(f"{shown!r} has store schema {schema}{note}, this pipeline reads and "
                            f"writes schema {STORE_SCHEMA}; move the old store aside and run its "
                            "sweep again, or use --store PATH")
    foreign = foreign_entries(path)
    if foreign:
        rel, what = foreign[0]
        more = f" (and {len(foreign) - 1} more such entries)" if len(foreign) > 1 else ""
        raise StoreDamaged(f"store {shown!r} is damaged: {rel!r} inside it is {what}{more}, "
                           "where a store holds only its own folders and regular files; "
                           f"{FIX}")
    problems = _shape_problems(root)
    if not problems and attrs.get(DIGEST_KEY) != metadata_digest(root):
        problems = [f"its metadata differs from its checksum ({DIGEST_KEY}): zarr.json was "
                    "changed after it was written"]
    if not problems:
        problems = _array_metadata_problems(path, root)
    if problems:
        raise StoreDamaged(f"store {shown!r} is damaged: {'; '.join(problems[:3])}"
                           f"{f' and {len(problems) - 3} more' if len(problems) > 3 else ''}; "
                           f"{FIX}")
    return root


def _array_metadata_problems(path: Path, root: dict) -> list:
    """Arrays whose own ``zarr.json`` is not their consolidated copy (which ``metadata_sha256``
    covers): readers use the copy, zarr's writes the file, so the two must agree."""
    out = []
    for name, meta in root["consolidated_metadata"]["metadata"].items():
        file = path / name / "zarr.json"
        try:
            own = json.loads(read_regular(file, METADATA_LIMIT).decode("utf-8"))
        except FileNotFoundError:
            out.append(f"{name}/zarr.json is missing")
            continue
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            out.append(f"{name}/zarr.json cannot be read ({exc})" if isinstance(exc, BadFile)
                       else f"{name}/zarr.json is not readable JSON")
            continue
        if own != meta:
            out.append(f"{name}/zarr.json differs from its copy in the store's metadata (it was "
                       "changed after it was written)")
    return out


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
        if not all(c in names for c in CODECS) or names[-1:] != [CODECS[-1]]:
            out.append(f"{name} has no checksummed chunks (codecs {names})")
        if chunk_keys(name, meta) is None:
            out.append(f"{name} has chunks in a layout this pipeline never writes")
        if tuple(meta.get("dimension_names") or ()) != dims:
            out.append(f"{name} is over {meta.get('dimension_names')!r}, not {list(dims)}")
        if name in VARIABLES:
            shape = meta.get("shape") if shape is None else shape
            if meta.get("shape") != shape:
                out.append(f"{name} has shape {meta.get('shape')}, status {shape}")
    out += [f"{name} is an array this pipeline never writes"
            for name in sorted(set(arrays) - {*VARIABLES, *axes})]
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


def _chunk_limit(meta: dict) -> int:
    """The most bytes a chunk of an array can take: its values (zstd's worst case, 1/128 over,
    plus a frame) and the checksum; strings (vlen-utf8) are capped at ``STRING_CHUNK_LIMIT``."""
    import numpy as np

    try:
        n = int(np.prod([int(c) for c in meta["chunk_grid"]["configuration"]["chunk_shape"]]))
        item = np.dtype(meta["data_type"]).itemsize
    except (KeyError, TypeError, ValueError):
        return STRING_CHUNK_LIMIT
    raw = n * item
    return raw + raw // 128 + 2**16


def _chunk_cells(idx, meta: dict) -> tuple:
    """The cells of chunk ``idx``: one slice per axis, within the array's shape."""
    chunk = [int(c) for c in meta["chunk_grid"]["configuration"]["chunk_shape"]]
    shape = [int(n) for n in meta["shape"]]
    return tuple(slice(i * c, min((i + 1) * c, n)) for i, c, n in zip(idx, chunk, shape))


def chunk_damage(path, arrays: dict, names, manifest: dict, pending=frozenset()) -> dict:
    """The chunks of the arrays ``names`` that cannot be trusted: ``{name: {chunk index: how}}``
    (only names with such a chunk), from the files' bytes alone, without zarr.

    ``how`` is ``"unreadable"`` (it cannot be read, is larger than such a chunk can be, shorter
    than its checksum or its CRC-32C fails: the zarr v3 spec's crc32c, the last 4 bytes the
    little-endian CRC-32C of the bytes before them), ``"missing"`` (the manifest has a digest for
    it, there is no file) or ``"replaced"`` (whole, but not the chunk written there: its sha256
    differs from the manifest's, or there is a file where the manifest says none was written).
    Chunks in ``pending`` (an interrupted writer's, pipeline/sweeps/manifest.py) are checked by
    their CRC-32C alone."""
    import google_crc32c  # zarr's own CRC-32C (its crc32c codec imports it)

    digests = manifest["chunks"]
    bad = {}
    for name in names:
        meta = arrays[name]
        limit = STRING_CHUNK_LIMIT if VARIABLES.get(name, ("",))[0] == "str" \
            else _chunk_limit(meta)
        for idx, key in chunk_keys(name, meta):
            how = None
            try:
                data = read_regular(os.path.join(path, key), limit)
            except FileNotFoundError:
                if key in digests and key not in pending:
                    bad.setdefault(name, {})[idx] = "missing"
                continue
            except OSError:  # BadFile too: larger than a chunk can be, or no longer a file
                data = b""
            if len(data) < 4 or \
                    google_crc32c.value(data[:-4]) != int.from_bytes(data[-4:], "little"):
                how = "unreadable"
            elif key not in pending and digests.get(key) != digest(data):
                how = "replaced"
            if how is not None:
                bad.setdefault(name, {})[idx] = how
    return bad


class _Writing(Exception):
    """The manifest says a writer is between its two manifests (pipeline/sweeps/manifest.py)."""


def _manifest_raw(path) -> bytes | None:
    """The manifest's bytes as they are now (None: none readable), the token a reader compares
    before and after its read."""
    try:
        return read_regular(Path(path) / MANIFEST_NAME, MANIFEST_LIMIT)
    except OSError:
        return None


def _relayout_underway(path) -> bool:
    path = Path(path)
    return path.with_name(path.name + ".old").exists()


def manifest_token(path) -> bytes | None:
    """What a reader takes before a read to tell afterwards whether a sweep changed the store
    meanwhile (``changed_since``)."""
    return _manifest_raw(path)


def changed_since(path, token) -> bool:
    """A sweep changed the store at ``path`` since ``manifest_token`` gave ``token``, or is
    re-laying it out now: a read that failed in between is to be read again."""
    return _manifest_raw(path) != token or _relayout_underway(path)


def load_checked(path, read=None):
    """Load a sweep store, checking its files, metadata, manifest, coordinates and every chunk
    once, from one consistent state of the store.

    Parameters
    ----------
    path : str or Path
        The store.
    read : iterable of str, optional
        The variables the caller reads (default: all, decoded). The others are decoded only if
        a chunk's bytes fail (then everything is, so damage is found as without ``read``);
        otherwise they stay lazy (their digests and checksums verified from the chunks' bytes;
        decode them with :func:`load_rest`). ``CHECKED`` is always decoded.

    Returns
    -------
    (xarray.Dataset, Damage)
        The loaded dataset (damaged chunks of decoded variables hold their fill value, damaged
        coordinates their copy) and what is damaged.

    Raises
    ------
    FileNotFoundError, UsageError, StoreMismatch, StoreDamaged
        As :func:`read_root`: no sweep store, or metadata that cannot be trusted; StoreDamaged
        also for a manifest that cannot be trusted. UsageError (exit 2, a busy store) when a
        sweep changed the store during every one of ``READ_TRIES`` reads.

    Notes
    -----
    A sweep may be writing the store meanwhile (pipeline/sweeps/manifest.py): the read starts
    from the manifest's bytes and is kept only when they are the same after it; a writer between
    its two manifests is waited for (at most ``WRITING_WAIT`` seconds; one known to have died is
    not: the chunks it was writing are then checked by their CRC-32C alone). Otherwise the read
    starts again.
    """
    path = Path(path)
    deadline = time.monotonic() + WRITING_WAIT
    for attempt in range(READ_TRIES):
        before = None
        try:
            with reading(path, WRITING_WAIT):  # a merge waits for this read, or it for the merge
                before = _manifest_raw(path)
                result = _load_once(path, read, before, force=time.monotonic() > deadline)
                after = _manifest_raw(path)
        except _Writing:
            while _manifest_raw(path) == before and time.monotonic() <= deadline:
                time.sleep(POLL_SECONDS)
            continue
        except Exception:  # noqa: BLE001 - a re-layout swaps the whole store under a read
            if attempt + 1 < READ_TRIES and changed_since(path, before):
                time.sleep(POLL_SECONDS)
                continue  # read while a sweep changed it: read again
            raise
        if same_state(before, after):
            return result
        time.sleep(POLL_SECONDS)
    raise UsageError(f"store {str(path)!r} changed while it was read, {READ_TRIES} times in a "
                     "row (a sweep is writing it); try again, or when the sweep has finished")


def _load_once(path: Path, read, raw: bytes | None, force: bool = False):
    """One read of the store at ``path`` against the manifest ``raw`` (its bytes before the
    read): :func:`load_checked` without the retries. Raises ``_Writing`` when the manifest says
    a live writer is replacing chunks (``force``: it is not waited for any longer)."""
    import pandas as pd
    import xarray as xr
    import zarr

    root = read_root(path)
    attrs = root["attributes"]
    manifest = _trusted_manifest(path, raw, attrs[DIGEST_KEY], force)
    writing = manifest.get("writing") or {}
    pending = frozenset(writing.get("keys") or ())
    dims = tuple(attrs["axes"])
    arrays = root["consolidated_metadata"]["metadata"]
    damage = Damage(dims=dims)
    names = list(VARIABLES)
    lazy_names = [] if read is None else [n for n in names if n not in {*read, *CHECKED}]
    bad = chunk_damage(path, arrays, [*dims, *names], manifest, pending)
    if any(n in bad for n in lazy_names):
        lazy_names = []  # a chunk failed: decode everything, so damage is found as in a full read
    with zarr_warnings():
        group = zarr.open_group(str(path), mode="r", use_consolidated=True)
        coords = {}
        for d in dims:
            copy = np.array([float(v) for v in attrs["grid"][d]])
            how = next(iter(bad.get(d, {}).values()), None)
            if how is None:
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
    ds = lazy.assign_coords(coords)
    for name in (n for n in names if n not in lazy_names):
        # a chunk known damaged from its bytes is never decoded: its cells keep the fill value
        _load_variable(ds, name, damage, skip={idx[:-1] for idx in bad.get(name, ())})
    for name, chunks in bad.items():
        for idx, how in chunks.items():
            if name in dims:
                continue
            cells = _chunk_cells(idx, arrays[name])
            for offset in np.ndindex(*(s.stop - s.start for s in cells)):
                damage.add(tuple(s.start + o for s, o in zip(cells, offset)), f"{name} ({how})")
    _check_cells(ds, damage)
    return ds, damage


def _check_cells(ds, damage: Damage) -> None:
    """Cells whose status is an unknown code, ok cells without their data (``REQUIRED`` NaN or
    ``model`` 0: a lost chunk behind an intact status chunk), unknown model codes."""
    status = ds["status"].values
    known = np.isin(status, list(STATUS_CODES.values()))
    for cell in np.argwhere(~known):
        damage.add(cell, f"status (unknown code {int(status[tuple(cell)])})")
    ok = status == STATUS_CODES["ok"]
    for name in REQUIRED:
        if name in ds:
            for cell in np.argwhere(ok & np.isnan(ds[name].values)):
                if not any(w.startswith(f"{name} (")
                           for w in damage.where.get(tuple(cell), ())):
                    damage.add(cell, f"{name} (missing)")
    if "model" in ds:
        model = ds["model"].values
        for cell in np.argwhere(ok & (model == 0)):
            damage.add(cell, "model (missing)")
        for cell in np.argwhere(~np.isin(model, [0, *MODEL_CODES.values()])):
            damage.add(cell, f"model (unknown code {int(model[tuple(cell)])})")


def _trusted_manifest(path: Path, raw: bytes | None, metadata_sha256: str, force: bool) -> dict:
    """The manifest in ``raw``, checked: its own checksum, its shape, the metadata it belongs
    with. StoreDamaged when it cannot be trusted; ``_Writing`` while a writer that may still be
    alive is between its two manifests (unless ``force``)."""
    shown = str(path)
    if raw is None:
        try:
            _, raw = read_manifest(path)
        except ManifestError as exc:
            raise StoreDamaged(f"store {shown!r} is damaged: {exc}; {FIX}") from None
    try:
        manifest = parse_manifest(raw)
    except ManifestError as exc:
        raise StoreDamaged(f"store {shown!r} is damaged: {exc}; {FIX}") from None
    writing = manifest.get("writing")
    if writing is not None and not force and not writer_gone(writing, path):
        raise _Writing()
    metadata_changing = bool(writing and writing.get("metadata"))
    if manifest["metadata_sha256"] != metadata_sha256 and not metadata_changing:
        raise StoreDamaged(f"store {shown!r} is damaged: its manifest belongs with other "
                           f"metadata ({DIGEST_KEY} {manifest['metadata_sha256'][:12]}, the "
                           f"store's {metadata_sha256[:12]}): one of them was replaced; {FIX}")
    return manifest


def load_rest(ds, damage: Damage) -> None:
    """Decode, in place, the variables of ``ds`` that ``load_checked(read=...)`` left lazy;
    chunks that do not decode hold their fill value and add their cells to ``damage``."""
    for name in list(ds.data_vars):
        _load_variable(ds, name, damage)  # a decoded variable: nothing to do


def _load_variable(ds, name, damage: Damage, skip=frozenset()) -> None:
    """Decode ``name`` in place; the chunks whose rows are in ``skip`` (known damaged from their
    bytes: never handed to zarr, which would read a file of any size) keep the fill value."""
    variable = ds.variables[name]
    if skip:
        variable.data = _read_by_chunk(name, ds[name], damage, skip)
        return
    try:
        variable.load()  # in place: the dataset keeps the values
    except Exception:  # noqa: BLE001 - any decode failure of any codec: find the chunks
        variable.data = _read_by_chunk(name, ds[name], damage)


def _read_by_chunk(name, var, damage: Damage, skip=frozenset()) -> np.ndarray:
    """Read ``var`` chunk by chunk (chunks are 1 along every axis but the last), but the rows in
    ``skip``: damaged chunks keep the fill value and add their cells to ``damage``."""
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
        if idx in skip:
            continue
        sel = dict(zip(dims[:-1], idx))
        try:
            out[idx] = var.isel(sel).values
        except Exception:  # noqa: BLE001
            for j in range(var.shape[-1]):
                damage.add((*idx, j), f"{name} (unreadable)")
    return out
