"""What a sweep store looks like: its schema, variables, encoding and attributes.

Layout (``STORE_SCHEMA``): every variable of ``VARIABLES`` (generated from the registry
``solver.observables.OBSERVABLES`` plus ``model``, ``status``, ``message``) is an N-D array over
the sweep's axes (fields of ``solver.Physics``, in ``Physics.names()`` order, e.g. ``(St, eps)``),
chunked 1 along every axis but the last and whole along the last; coordinates are sorted
ascending. Every chunk of every variable and coordinate is zstd-compressed and then carries a
CRC-32C checksum (zarr's ``crc32c`` codec, ``CODECS``): a flipped byte is an error when the chunk
is read, never a changed number. ``status`` (``STATUS_CODES``; 0 = not run) is written *after* a cell's data, so a cell
with a non-zero status always has its data. Root attrs carry the axis names (``axes``), the fixed
physics (``fixed_physics``), the solver version, the cache key and the resolved numerics, the
sweep file verbatim, package versions and the creation time.

No writing here: :class:`pipeline.sweeps.store.SweepStore` is the single writer.
"""

from __future__ import annotations

import datetime
import math
import warnings
from contextlib import contextmanager

import numpy as np

from solver.observables import MODEL_CODES, OBSERVABLES, STATUS_CODES
from solver.physics import Physics

__all__ = ["STORE_SCHEMA", "VARIABLES", "FLOATS", "FLAGS", "COUNTS", "DIAGNOSTIC", "SCALING",
           "STATUS_CODES", "MODEL_CODES", "CODECS", "BOUNDS", "empty_dataset", "record_problem",
           "zarr_warnings"]

# bump when variables, their encoding or their meaning change (an old store is then refused);
# 6: checksummed chunks (crc32c), the coordinates' copy ``grid`` and ``metadata_sha256``;
# 7: the far-field observables e_far and v_outer_start;
# 8: the manifest (pipeline/sweeps/manifest.py): every chunk's sha256 keyed by its place;
# 9: the flag ``extrapolated`` (solver 1.15.0: the fine preset's two grids)
STORE_SCHEMA = 9

_DTYPE = {"float": "f8", "flag": "i1", "count": "i4"}
# name: (dtype, long_name, units), generated from the registry; flags are int8 0/1 with fill -1
# (read back as NaN: unknown)
VARIABLES = {o.name: (_DTYPE[o.kind], o.long_name, o.units) for o in OBSERVABLES}
VARIABLES.update({
    "model": ("i1", "model that answered the scene", "1"),
    "status": ("i1", "scene status (0 = not run; see flag_meanings)", "1"),
    "message": ("str", "solver message or failure reason", ""),
})
FLOATS = tuple(o.name for o in OBSERVABLES if o.kind == "float")
FLAGS = tuple(o.name for o in OBSERVABLES if o.kind == "flag")
COUNTS = tuple(o.name for o in OBSERVABLES if o.kind == "count")
DIAGNOSTIC = frozenset(o.name for o in OBSERVABLES if o.diagnostic)

# what physics allows a stored observable (a record with a value outside is refused: a journal
# line is skipped and counted, a worker's record stored as an error): restitutions and the
# rebound speed in [0, 1] (no collision gives back more energy than it had), counts and the
# wall time never negative
BOUNDS = {"v_r": (0.0, 1.0), "e_wet": (0.0, 1.0), "e_far": (0.0, 1.0), "wall_s": (0.0, math.inf),
          # gaps are positive; the energy closure and the start's strain energy are not negative
          "h_m_x1": (0.0, math.inf), "h_m_approach_x1": (0.0, math.inf),
          "energy_error": (0.0, math.inf), "start_strain_energy": (0.0, math.inf),
          "void_volume_max": (0.0, math.inf), "cavity_radius_max": (0.0, math.inf),
          # counts are stored as int32: a larger one overflowed the write (exit 70, every rerun)
          **{name: (0, 2**31 - 1) for name in COUNTS}}

SCALING = ("lengths along the axis in x1 = (4 theta mu a^1.5 v0)^0.4 (suffix _x1) or x0 (suffix "
           "_x0); eps = (x1/x0)^2.5; tau = v0 t / x0; velocity / v0; force / (6 pi mu a^2 v0 / x1); "
           "energies / (m v0^2 / 2)")


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def record_problem(rec: dict) -> str | None:
    """Why a scene record cannot be stored, as one clause (a value of the wrong type, or outside
    ``BOUNDS``), or None. Missing values are fine (a failed scene has only some); NaN is
    "unknown", within any bound (the store's checks find an ok scene without its data)."""
    for key in ("status", "model", "message"):
        if key in rec and not isinstance(rec[key], str):
            return f"{key} is {rec[key]!r}, not text"
    for name in (*FLOATS, *COUNTS):
        value = rec.get(name)
        if value is None:
            continue
        whole = isinstance(value, int) or (_is_number(value) and math.isfinite(value)
                                           and value == int(value))
        if not _is_number(value) or (name in COUNTS and not whole):
            return f"{name} is {str(value)[:40]!r}, not a {'whole ' if name in COUNTS else ''}number"
        low, high = BOUNDS.get(name, (-math.inf, math.inf))
        if not (math.isnan(value) or low <= value <= high):
            return f"{name} = {value!r} is outside [{low:g}, {high:g}], which physics allows"
    for name in FLAGS:
        value = rec.get(name)
        if value is not None and not isinstance(value, bool) and value not in (0, 1):
            return f"{name} is {str(value)[:40]!r}, not true or false"
    if rec.get("status") == "ok":  # what an ok scene has finite (tasks.nonfinite_reason)
        from .tasks import nonfinite_reason

        return nonfinite_reason(rec.get) or None
    return None


@contextmanager
def zarr_warnings():
    """The one place that silences zarr 3's notice that consolidated metadata is not part of the
    v3 spec (we consolidate on purpose, so plain ``xr.open_zarr(path)`` opens the store without
    falling back, and warning, to listing every array) and its notice that the manifest is no
    zarr node when it lists the store's members."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Consolidated metadata is currently not part",
                                category=UserWarning)
        # the store's manifest and readers' lock (pipeline/sweeps/manifest.py): files of ours
        warnings.filterwarnings("ignore", message=r"Object at ehd_\w+\.\w+ is not",
                                category=UserWarning)
        yield


def _package_versions() -> dict:
    import platform
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": platform.python_version()}
    for name in ("numpy", "scipy", "numba", "dask", "distributed", "xarray", "zarr"):
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _fill(dtype: str):
    return {"f8": math.nan, "i1": 0, "i4": 0, "str": ""}[dtype]


def empty_dataset(axes: dict, attrs: dict):
    """An in-memory store layout over ``axes`` (``{name: values}``) with every cell "not run"
    (decoded form, as read back)."""
    import xarray as xr

    dims = tuple(axes)
    coords = {}
    for name, values in axes.items():
        g = Physics.group(name)
        coords[name] = (name, np.asarray(values, dtype=float),
                        {"long_name": g.long_name, "units": g.units})
    shape = tuple(len(v) for v in axes.values())
    data = {}
    for name, (dtype, long_name, units) in VARIABLES.items():
        if name in FLAGS:
            arr = np.full(shape, np.nan, dtype="f4")  # decoded view of int8 with fill -1
        elif dtype == "str":
            arr = np.full(shape, "", dtype=object)
        else:
            arr = np.full(shape, _fill(dtype), dtype=dtype)
        var_attrs = {"long_name": long_name, "units": units}
        if name == "status":
            var_attrs.update(flag_values=list(STATUS_CODES.values()),
                             flag_meanings=" ".join(STATUS_CODES))
        elif name == "model":
            var_attrs.update(flag_values=list(MODEL_CODES.values()),
                             flag_meanings=" ".join(MODEL_CODES))
        elif name in FLAGS:
            var_attrs.update(flag_values=[0, 1], flag_meanings="no yes",
                             comment="missing (NaN when read) where status != 1")
        elif name not in DIAGNOSTIC and name != "message":
            var_attrs["comment"] = "NaN where status != 1 (not run or failed)"
        data[name] = (dims, arr, var_attrs)
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _chunks(ds) -> tuple:
    """1 along every axis but the last, whole along the last: a flush rewrites only the chunks
    of the cells it touched."""
    dims = ds["status"].dims
    return tuple(1 for _ in dims[:-1]) + (ds.sizes[dims[-1]],)


def codecs() -> tuple:
    """The bytes-to-bytes codecs of every array: zstd, then a CRC-32C of the compressed chunk
    (zarr 3's ``crc32c`` codec; a chunk whose checksum does not match raises when read)."""
    from zarr.codecs import Crc32cCodec, ZstdCodec

    return (ZstdCodec(), Crc32cCodec())


CODECS = ("zstd", "crc32c")  # names of codecs() in an array's zarr.json (checked when read)


def _encoding(ds) -> dict:
    chunks = _chunks(ds)
    enc = {}
    for name in VARIABLES:
        enc[name] = {"chunks": chunks, "compressors": codecs()}
        if name in FLAGS:
            enc[name].update(dtype="i1", _FillValue=-1)
    for name in ds["status"].dims:  # the coordinates: one chunk each, checksummed too
        enc[name] = {"compressors": codecs()}
    return enc


def grid_copy(ds) -> dict:
    """The coordinates as the root attr ``grid`` holds them: ``{axis: [repr(value), ...]}``
    (``float(text)`` gives back the same float, inf included)."""
    return {d: [repr(float(v)) for v in ds[d].values] for d in ds["status"].dims}
