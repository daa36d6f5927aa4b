"""The sweep store: one zarr store per sweep, dims = the sweep's axes, and its single writer.

The layout (variables, encoding, attributes) is in :mod:`pipeline.sweeps.layout`, the journal in
:mod:`pipeline.sweeps.journal`.

Rules this module enforces (docs/pipeline.md):

- Cache: a store belongs to one cache key (solver version + numerics + fixed physics + axis
  names). Opening it for a sweep with another key raises :class:`StoreMismatch` naming the
  difference: old and new results never mix. A new grid is laid out as the union of the old and
  the new coordinates along every axis, existing cells copied over.
- One writer: :class:`SweepStore` is the only code that writes a store; an exclusive lock
  (``<store>.lock``, released by the OS even after ``kill -9``) keeps a second sweep out.
- Integrity: every chunk is checked when a sweep opens the store (:mod:`pipeline.sweeps.integrity`):
  the variables a sweep plans with (``PLANNED``) and those the checks need are decoded, the
  others' checksums verified from their bytes and decoded, chunk by chunk where a chunk cannot
  be, only before the first write (:meth:`SweepStore.load_all`): a sweep with nothing to do
  decodes a fifth of the store. Damaged cells are turned into "not run" and their chunks
  rewritten, so the sweep recomputes them and never reads them as data.
- Provenance: the root attr ``sweeps`` lists every sweep file that wrote into the store (name,
  path, sha256 of the file, time); another sweep file needs ``add_sweep`` (``--add-sweep``).
- The store is known by its real path (symlinks resolved): one lock and one journal per store.
- Crash safety: each finished scene is appended to a journal (``<store>.journal``, one JSON line
  ``{"physics": {...}, "key": ..., **record}``, flushed to the OS) before anything else, then merged into the store in batches; a new run
  merges a journal left by a killed run first, so no finished scene is ever computed twice.
  New layouts are written to a temporary directory and moved into place by ``rename``; zarr
  writes each chunk atomically, so a reader always sees a valid store.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from solver.interrupts import deferred_interrupt
from solver.observables import MODEL_CODES, STATUS_CODES
from solver.physics import Physics

from ..errors import EhdError, PathError, StoreDamaged, StoreMismatch, UsageError
from ..writes import write_error, writing
from .config import physics_from_json, physics_json
from .files import BadFile, open_append, open_update, read_regular
from .integrity import (DIGEST_KEY, METADATA_LIMIT, Damage, load_checked, load_rest,
                        metadata_digest, read_root)
from .journal import _journal_path, journal_line, pending_journal, read_journal
from .layout import (COUNTS, DIAGNOSTIC, FLAGS, FLOATS, SCALING, STORE_SCHEMA, VARIABLES, _encoding,
                     _fill, _now, _package_versions, empty_dataset, grid_copy, record_problem,
                     zarr_warnings)
from .manifest import (READERS_LOCK, WRITING_HERE, ManifestError, build, merging, read_manifest,
                       redigest, sealed, write_manifest, writing_marker)

__all__ = ["open_results", "SweepStore", "StoreMismatch", "StoreBusy", "seal"]

RTOL_COORD = 1e-9  # grid values this close are the same scene (geomspace round-off is ~1e-16)
FLUSH_SECONDS = 2.0  # journal -> store merge interval: the journal already makes results durable
PLANNED = ("status", "model", "message")  # what a sweep reads to plan its work and count it


class StoreBusy(EhdError, RuntimeError):
    """Another process is writing the store."""


class UnmergedScenes(UserWarning):
    """``open_results``: finished scenes of an interrupted sweep wait in the store's journal,
    not yet in the store (the next ``ehd sweep`` merges them). ``ehd`` commands that read a
    store say so in one line of their own instead (``ehd status`` counts them)."""


def unnamed(path) -> bool:
    """Whether ``path`` names a folder by its place (``.``, ``..``, ``/``): never a store, whose
    lock, journal and copies are named after it."""
    return Path(path).name in ("", "..")


def named_store(path) -> Path:
    """``path`` by its own name: a store named by its place (``.``, ``..``, inside it) is read as
    the folder it names; FileNotFoundError where that is the root folder."""
    path = Path(path)
    if unnamed(path):
        path = Path(os.path.realpath(path))
        if unnamed(path):
            raise FileNotFoundError(f"{str(path)!r} is the root folder: no sweep store there")
    return path


def _lock_path(path: Path) -> Path:
    path = Path(os.path.realpath(path))
    return path.with_name(path.name + ".lock")


def _old_path(path: Path) -> Path:
    return path.with_name(path.name + ".old")


def _tmp_path(path: Path) -> Path:
    return path.with_name(f"{path.name}.tmp-{os.getpid()}")


def open_results(path, check: bool = True, **open_kwargs):
    """Open a sweep store for analysis.

    Parameters
    ----------
    path : str or Path
        The store directory (e.g. ``results/paper.zarr``).
    check : bool
        Read the whole store once first and raise ``StoreDamaged`` if any chunk, coordinate or
        metadata is damaged (default; the stores are small). ``False`` skips the check (to look
        at a damaged store: ``ehd status`` says which cells are damaged).
    **open_kwargs
        Passed to ``xarray.open_zarr`` (e.g. ``chunks=None``: no dask arrays, quicker for a
        store that is read whole).

    Returns
    -------
    xarray.Dataset
        Lazily loaded, dims = the sweep's axes (``ds.attrs["axes"]``, e.g. ``(St, eps)``); the
        fixed physics in ``ds.attrs["fixed_physics"]``. Use ``ds.status == 1`` for valid cells (codes in
        ``ds.status.attrs["flag_meanings"]``); ``escaped``/``dimple`` read as float (NaN unknown).
        Plain ``xarray.open_zarr(path)`` gives the same Dataset, unchecked (a chunk whose
        checksum fails still raises when read).

    Raises
    ------
    FileNotFoundError
        No sweep store at ``path``.
    pipeline.errors.StoreDamaged
        A damaged chunk, coordinate or metadata (``check=True``): its message lists them; ``ehd
        sweep`` recomputes damaged cells.
    pipeline.errors.StoreMismatch
        A store of another schema.
    """
    import xarray as xr

    import time

    from .integrity import POLL_SECONDS, READ_TRIES, changed_since, manifest_token

    path = named_store(path)
    for attempt in range(READ_TRIES):
        before = manifest_token(path)
        if check:
            checked, damage = load_checked(path)
            if damage:
                raise StoreDamaged(f"store {str(path)!r} is damaged: "
                                   f"{damage.describe(checked, checked.attrs.get('fixed_physics'))}"
                                   "; run its sweep again (ehd sweep SWEEP_FILE) to repair it")
        else:
            read_root(path)
        try:
            with zarr_warnings():
                ds = xr.open_zarr(path, **{"consolidated": True, **open_kwargs})
            break
        except Exception:  # noqa: BLE001 - a re-layout swapped the store after the check
            if attempt + 1 < READ_TRIES and changed_since(path, before):
                time.sleep(POLL_SECONDS)
                continue  # read again, checks included
            raise
    n = pending_journal(path)
    if n:
        warnings.warn(f"{n} finished scenes of an interrupted sweep are in {_journal_path(path)} "
                      "and not yet in the store; run the sweep again to merge them",
                      UnmergedScenes, stacklevel=2)
    return ds


def seal(path: Path) -> None:
    """Write ``metadata_sha256`` (pipeline/sweeps/integrity.py) into the root attributes and
    consolidate: the last write of every metadata change."""
    import zarr

    with zarr_warnings():
        zarr.consolidate_metadata(str(path))
        root = json.loads((Path(path) / "zarr.json").read_text())
        group = zarr.open_group(str(path), mode="r+", use_consolidated=False)
        group.attrs[DIGEST_KEY] = metadata_digest(root)
        zarr.consolidate_metadata(str(path))


def _root(path: Path) -> dict:
    """The root ``zarr.json`` as this process wrote it (the writer's own reads)."""
    return json.loads(read_regular(Path(path) / "zarr.json", METADATA_LIMIT).decode("utf-8"))


def _write_new(ds, path: Path) -> None:
    """Write a complete store next to ``path`` and move it into place (readers never see a
    half-written layout). An existing store at ``path`` is replaced only after the new one is
    complete; a kill in between is repaired by :func:`_recover`; a failed write (a full disk)
    removes the temporary directory and leaves ``path`` as it was."""
    tmp = _tmp_path(path)
    shutil.rmtree(tmp, ignore_errors=True)
    ds = ds.copy()
    ds.attrs["grid"] = grid_copy(ds)
    with writing(tmp, "writing the store", path):
        with zarr_warnings():
            # one call is enough: nobody sees the temporary directory until the rename below
            ds.to_zarr(tmp, mode="w-", consolidated=True, encoding=_encoding(ds))
        seal(tmp)
        root = _root(tmp)
        write_manifest(tmp, build(tmp, root["consolidated_metadata"]["metadata"],
                                  root["attributes"][DIGEST_KEY]))
        (tmp / READERS_LOCK).touch()
    if path.exists():
        old = _old_path(path)
        path.rename(old)
        tmp.rename(path)
        shutil.rmtree(old)
    else:
        tmp.rename(path)


def _recover(path: Path) -> None:
    """Finish or undo a re-layout interrupted by a kill; drop temporary leftovers."""
    old = _old_path(path)
    if old.exists():
        if path.exists():
            shutil.rmtree(old)  # the new layout was already in place
        else:
            old.rename(path)  # killed between the two renames: the old store is intact
    for tmp in path.parent.glob(f"{path.name}.tmp-*"):
        shutil.rmtree(tmp, ignore_errors=True)
    if path.exists():  # a kill during zarr's (or the manifest's) atomic write leaves its
        for partial in path.rglob("*.partial"):  # temporary file behind
            partial.unlink(missing_ok=True)


def _reopen_truncated(f, path: Path, size: int):
    """Close ``f`` (its buffer dropped), cut ``path`` to ``size`` bytes, return None (the journal
    is opened again by the next record)."""
    try:
        f.close()
    except OSError:
        pass
    try:
        os.truncate(path, size)
    except OSError:
        pass
    return None


def _union(old: np.ndarray, new) -> np.ndarray:
    """Sorted union of grid values, keeping the old values where a new one matches."""
    extra = [v for v in new if not np.any(np.isclose(old, v, rtol=RTOL_COORD, atol=0.0))]
    return np.sort(np.concatenate([old, np.asarray(extra, dtype=float)]))


def _index(coord: np.ndarray, values) -> np.ndarray:
    idx = []
    for v in values:
        if not isinstance(v, (int, float, np.number)) or isinstance(v, bool):
            # a list or a text where a coordinate belongs (a journal record's ``St: [[10.0]]``
            # matched the first row of the 2-D comparison: cell 0 took another scene's data)
            raise TypeError(f"{v!r} is not a number on the store's grid")
        hit = np.nonzero(np.isclose(coord, v, rtol=RTOL_COORD, atol=0.0))[0]
        if hit.size != 1:
            raise KeyError(f"{v!r} is not on the store's grid")
        idx.append(int(hit[0]))
    return np.asarray(idx, dtype=int)


def _sha256(text: str) -> str:
    import hashlib

    return hashlib.sha256(str(text).encode()).hexdigest()


def _provenance(sweep) -> dict:
    """An entry of the store's ``sweeps`` attr: which sweep file wrote into it, and when."""
    path = str(Path(sweep.path).resolve()) if sweep.path is not None else ""
    return {"name": sweep.name, "path": path, "sha256": _sha256(sweep.source), "time": _now()}


class SweepStore:
    """The single writer of a sweep store (use :meth:`open` as a context manager).

    Parameters
    ----------
    path : Path
        Store directory.
    key : str
        Cache key of the sweep (sha256 hex).
    flush_seconds : float, optional
        Interval of journal -> store merges (default ``FLUSH_SECONDS``, read when the store is
        made, so a test that sets the module's value is obeyed).
    """

    def __init__(self, path: Path, key: str, flush_seconds: float | None = None,
                 worker_key: str | None = None, fixed: dict | None = None):
        if not str(path).strip():
            raise PathError("--store: empty path; give a store directory such as "
                            "results/NAME.zarr")
        self.shown = str(path)  # as the user typed it (messages, the summary)
        # the real path: the same store through a symlink has one lock, one journal, and its
        # re-layouts rename the directory, not the link
        self.path = Path(os.path.realpath(path))
        self.key = key
        self.worker_key = worker_key  # what records of this installation carry (None: any)
        self.fixed = dict(fixed or {})
        self.flush_seconds = FLUSH_SECONDS if flush_seconds is None else flush_seconds
        self._journal = None
        self._lock = None
        self._dirty: set[tuple] = set()  # leading indices (all axes but the last) to write
        self._last_flush = 0.0
        self.ds = None
        # cells found damaged when the store was opened (now not run), indexed on the grid it
        # had then
        self.damage = Damage()
        self._lazy = False  # variables beyond PLANNED not decoded yet (load_all)
        self._writable = False  # require_writable() passed
        self.damage_text = ""  # one line: how many cells, which variables, where
        self.journal_skipped = 0  # journal lines that were not records (skipped, scenes rerun)
        self.manifest = None  # the store's manifest as this writer last published it

    # ---- opening --------------------------------------------------------------------------------
    @classmethod
    @contextmanager
    def open(cls, sweep, path=None, flush_seconds: float | None = None,
             add_sweep: bool = False):
        """Lock, recover, check, extend and load the store of ``sweep``; flush and unlock on exit.

        Raises
        ------
        StoreMismatch
            The store at ``path`` was computed with another solver version, numerics, fixed
            physics, axes or schema.
        StoreBusy
            Another process holds the store's lock.
        PathError
            The store or its folder cannot be written.
        """
        path = path if path is not None else sweep.store
        self = cls(path, sweep.cache_key(), flush_seconds, worker_key=sweep.worker_key(),
                   fixed=sweep.fixed)
        new_lock = not os.path.lexists(_lock_path(self.path))
        new_store = not self.path.exists()
        self._acquire_lock()
        try:
            try:
                self._prepare(sweep, add_sweep)
            except BaseException:
                if new_lock and not (new_store and self.path.exists()):
                    # nothing was made (a full disk, a mismatch), or what was there is refused
                    # (a file, a folder that is no store): no lock file of ours is left either
                    # (unlinked while we hold it: no other sweep can be waiting on it)
                    _lock_path(self.path).unlink(missing_ok=True)
                raise
            try:
                yield self
            except BaseException:
                # also on Ctrl-C or an error: everything finished so far is merged; if this
                # flush fails too (a full disk), the journal still holds it for the next run,
                # and the first failure is the one reported. A Ctrl-C pressed again meanwhile
                # waits for the merge (it had cut it short, leaving the scenes to the next run)
                try:
                    with deferred_interrupt():
                        self.flush()
                except Exception:  # noqa: BLE001
                    pass
                raise
            else:
                with deferred_interrupt():
                    self.flush()
        finally:
            self._close_journal()
            self._release_lock()

    def _acquire_lock(self) -> None:
        import fcntl

        where = f"--store {self.shown}"
        parent = next((p for p in (self.path.parent, *self.path.parent.parents) if p.exists()),
                      Path("/"))
        if not parent.is_dir():
            raise PathError(f"{where}: {str(parent)!r} is not a directory")
        lock = _lock_path(self.path)
        new_lock = not os.path.lexists(lock)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            f = open_update(lock)
        except BadFile as exc:
            raise PathError(f"{where}: the store's lock file {exc}; remove it (a sweep makes "
                            "its own)") from None
        except OSError as exc:
            raise PathError(f"{where}: cannot write next to the store in {str(self.path.parent)!r} "
                            f"({exc.strerror}); choose a writable --store") from None
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            holder = f.read().strip() or "another process"
            f.close()
            raise StoreBusy(f"store {self.shown!r} is being written by {holder}; wait for it "
                            "to finish (only one sweep writes a store)") from None
        try:
            f.seek(0)
            f.truncate()
            f.write(f"pid {os.getpid()}\n")
            f.flush()
        except OSError as exc:  # a full disk: no lock file of ours left behind
            f.close()
            if new_lock:
                lock.unlink(missing_ok=True)
            raise write_error(exc, "writing the store's lock", lock) from None
        self._lock = f

    def _release_lock(self) -> None:
        if self._lock is not None:
            self._lock.close()  # closing releases the flock
            self._lock = None

    def _attrs(self, sweep) -> dict:
        return {
            "title": "ehd-collision sweep: elastohydrodynamic collision of two elastic spheres",
            "store_schema": STORE_SCHEMA,
            "axes": list(sweep.axis_names),
            "fixed_physics": physics_json(sweep.fixed),
            "solver_version": sweep.solver_version(),
            "cache_key": self.key,
            "accuracy": sweep.accuracy,
            "numerics": sweep.numerics(),
            "sweep_name": sweep.name,
            "sweep_path": str(sweep.path) if sweep.path is not None else "",
            "sweep_file": sweep.source,
            "sweeps": [_provenance(sweep)],
            "package_versions": _package_versions(),
            "created": _now(),
            "scaling": SCALING,
        }

    def _prepare(self, sweep, add_sweep: bool = False) -> None:
        _recover(self.path)
        if self.path.exists() and not self.path.is_dir():
            raise PathError(f"--store {self.shown}: exists and is not a directory (a store is "
                            "one); choose another --store")
        if not self.path.exists():
            _write_new(empty_dataset(sweep.axes, self._attrs(sweep)), self.path)
        elif not (self.path / "zarr.json").is_file():
            raise StoreMismatch(f"{self.shown!r} exists but is not a zarr store; choose "
                                "another --store")
        try:
            self._settle_manifest()
            self._load()
        except EhdError:  # the integrity check's own line (schema, damaged metadata)
            raise
        except FileNotFoundError as exc:  # the integrity check's: a zarr store, none of ours
            raise StoreMismatch(f"{exc}; choose another --store") from None
        except (ValueError, KeyError, OSError) as exc:  # e.g. a zarr store without consolidation
            raise StoreMismatch(f"{self.shown!r} cannot be opened as an ehd sweep store "
                                f"({type(exc).__name__}: {exc}); choose another --store") from None
        self._check(sweep)
        self._check_provenance(sweep, add_sweep)
        self.damage_text = self.damage.describe(self.ds, self.fixed) if self.damage else ""
        self._repair_coords(self.damage)
        self._forget(self.damage)
        self._replay()
        self._extend(sweep)

    def _load(self) -> None:
        # every chunk checked once, the planned variables decoded; chunks that cannot be decoded
        # and ok cells without data are reported in self.damage (pipeline/sweeps/integrity.py)
        self.ds, self.damage = load_checked(self.path, read=PLANNED)
        self.manifest = read_manifest(self.path)[0]  # under the lock: what was just checked
        self._lazy = True

    def _settle_manifest(self) -> None:
        """A manifest left ``writing`` by a writer that was killed between its two manifests
        (pipeline/sweeps/manifest.py): digest the chunks it was writing as they are (every
        reader still checks their CRC-32C) and publish it again, once the metadata is known to
        be intact. Under the lock: no other writer is between its manifests."""
        try:
            manifest = read_manifest(self.path)[0]
        except ManifestError:
            return  # load_checked says what is wrong with it
        marker = manifest.get("writing")
        if marker is None:
            return
        root = read_root(self.path)  # the metadata checked first: nothing damaged is blessed
        redigest(self.path, manifest, marker.get("keys") or ())
        self.require_writable()
        with writing(None, "writing the store's manifest", self.path):
            write_manifest(self.path, sealed(manifest, root["attributes"][DIGEST_KEY]))

    @contextmanager
    def _changing(self, keys=(), metadata: bool = False):
        """Publish that the chunks ``keys`` (and the metadata) are about to change, run the
        block that changes them, then publish their new digests as the next generation (also
        after a failed block, as far as the disk lets it: the next sweep settles the rest)."""
        keys = sorted(set(keys))
        WRITING_HERE.add(str(self.path))
        try:
            with writing(None, "writing the store's manifest", self.path):
                write_manifest(self.path, {**self.manifest,  # new readers wait from here on
                                           "writing": writing_marker(keys, metadata)})
            with merging(self.path) as alone:  # the reads under way finish first
                if not alone:  # they did not within MERGE_WAIT: they read again
                    with writing(None, "writing the store's manifest", self.path):
                        write_manifest(self.path, {**self.manifest, "writing": writing_marker(
                            keys, metadata, phase="writing")})
                try:
                    yield
                except BaseException:
                    try:
                        self._seal_manifest(keys)
                    except Exception:  # noqa: BLE001 - the first failure is the one reported
                        pass
                    raise
                with writing(None, "writing the store's manifest", self.path):
                    self._seal_manifest(keys)
        finally:
            WRITING_HERE.discard(str(self.path))

    def _seal_manifest(self, keys) -> None:
        manifest = {**self.manifest, "chunks": dict(self.manifest["chunks"])}
        redigest(self.path, manifest, keys)
        manifest = sealed(manifest, _root(self.path)["attributes"][DIGEST_KEY])
        write_manifest(self.path, manifest)
        self.manifest = manifest

    def _chunk_keys(self, lead_ranges) -> list:
        """The keys of the chunks of every variable over the rows ``lead_ranges`` (one range
        per axis but the last; chunks are whole along the last)."""
        import itertools

        rows = list(itertools.product(*lead_ranges))
        return ["/".join((name, "c", *map(str, row), "0")) for name in VARIABLES for row in rows]

    def load_all(self) -> int:
        """Decode every variable not decoded yet (before the in-memory copy changes: a flush
        writes whole chunks of every variable). Returns the number of cells found damaged only
        now (a chunk whose checksum holds but which does not decode), turned into "not run"."""
        if not self._lazy:
            return 0
        self._lazy = False
        before = set(self.damage.where)
        load_rest(self.ds, self.damage)
        late = Damage(dims=self.damage.dims,
                      where={c: w for c, w in self.damage.where.items() if c not in before})
        self._forget(late)
        return len(late)

    def require_writable(self) -> None:
        """PathError when a folder of the store cannot be written (every chunk is replaced by a
        rename inside its folder). Checked once, before the first write and before any scene is
        solved (``run_sweep``): a read-only store with nothing to do is still readable."""
        if self._writable:
            return
        for d in (self.path, *(p for p in self.path.rglob("*") if p.is_dir())):
            if not os.access(d, os.W_OK | os.X_OK):
                raise PathError(f"store {self.shown!r} is not writable ({str(d)!r}); make it "
                                "writable (chmod -R u+w) or write the sweep elsewhere with "
                                "--store PATH")
        self._writable = True

    def _check_provenance(self, sweep, add_sweep: bool) -> None:
        """The same sweep (same file content, or same ``name``: an edited grid) may write again,
        each new version recorded; another sweep needs ``add_sweep`` and is recorded in the
        ``sweeps`` attr."""
        attrs = self.ds.attrs
        entries = list(attrs.get("sweeps") or [])
        if not entries and attrs.get("sweep_file") is not None:  # a store of an earlier schema 3
            old_path = attrs.get("sweep_path") or ""
            entries = [{"name": attrs.get("sweep_name"),
                        "path": str(Path(old_path).resolve()) if old_path else "",
                        "sha256": _sha256(attrs.get("sweep_file", "")),
                        "time": attrs.get("created")}]
        new = _provenance(sweep)
        same_content = any(e.get("sha256") == new["sha256"] for e in entries)
        # a sweep is known by its name (an edited grid, a checkout moved elsewhere), a version
        # of it by the file's hash
        same_sweep = any(e.get("name") == new["name"] for e in entries)
        if not (same_content or same_sweep or add_sweep):
            last = entries[-1] if entries else {}
            raise StoreMismatch(
                f"store {self.shown!r} holds sweep {last.get('name')!r} "
                f"({last.get('path') or 'no file'}); this is another sweep file "
                f"({new['name']!r}, {new['path'] or 'no file'}): add --add-sweep to write it into "
                "the same store (recorded in its 'sweeps' attr) or use --store PATH")
        if not same_content:
            entries.append(new)
        update = {}
        if entries != list(attrs.get("sweeps") or []):
            update["sweeps"] = entries
        if attrs.get("sweep_file") != sweep.source:
            update.update(sweep_file=sweep.source, sweep_name=sweep.name, sweep_path=new["path"])
        if update:
            self._set_attrs(**update)

    def _repair_coords(self, damage: Damage) -> None:
        """Rewrite damaged coordinates from their copy (the root attr ``grid``, checked by
        ``metadata_sha256``; ``self.ds`` already holds it)."""
        if not damage.coords:
            return
        import zarr

        self.require_writable()
        with self._changing(f"{name}/c/0" for name in damage.coords), \
                writing(None, "writing the store", self.path), zarr_warnings():
            group = zarr.open_group(str(self.path), mode="r+", use_consolidated=False)
            for name in damage.coords:
                group[name][:] = self.ds[name].values

    def _forget(self, damage: Damage) -> None:
        """Damaged cells become "not run" (every variable at its fill value) and their chunks
        are rewritten at the next flush: the sweep recomputes them, nobody reads them as data."""
        if not damage:
            return
        self.load_all()
        for cell in damage.cells:
            for name in FLOATS:
                self.ds[name].values[cell] = math.nan
            for name in FLAGS:
                self.ds[name].values[cell] = math.nan
            for name in COUNTS:
                self.ds[name].values[cell] = 0
            self.ds["model"].values[cell] = 0
            self.ds["message"].values[cell] = ""
            self.ds["status"].values[cell] = 0
            self._dirty.add(cell[:-1])

    def _check(self, sweep) -> None:
        attrs = self.ds.attrs
        if "store_schema" not in attrs:
            raise StoreMismatch(f"{self.shown!r} is a zarr store but not an ehd sweep store; "
                                "choose another --store")
        if attrs.get("store_schema") != STORE_SCHEMA:
            raise StoreMismatch(
                f"{str(self.path)!r} has store schema {attrs.get('store_schema')!r}, this "
                f"pipeline writes schema {STORE_SCHEMA}; move the old store aside or use --store")
        self._check_physics(sweep)
        if attrs.get("cache_key") == self.key:
            return
        old_num, new_num = attrs.get("numerics", {}), sweep.numerics()
        diffs = []
        if attrs.get("solver_version") != sweep.solver_version():
            diffs.append(f"solver_version {attrs.get('solver_version')} -> {sweep.solver_version()}")
        diffs += [f"{k} {old_num.get(k)!r} -> {new_num.get(k)!r}"
                  for k in sorted(set(old_num) | set(new_num)) if old_num.get(k) != new_num.get(k)]
        if not diffs:
            # same solver version and numerics: the key differs only in the fixed physics'
            # spelling (a group added to solver.Physics since, at its off value), which
            # _check_physics has accepted as the same physics
            return
        version = attrs.get("solver_version", "old")
        raise StoreMismatch(
            f"store {str(self.path)!r} holds results of another solver version or numerics "
            f"({'; '.join(diffs) or 'cache key differs'}); results never mix: keep the old store "
            f"(e.g. mv {self.path} {self.path.with_name(self.path.stem + '-' + version)}"
            f"{self.path.suffix}) or write this sweep elsewhere with --store PATH")

    def _check_physics(self, sweep) -> None:
        """Same axes and same fixed physics, or one line naming the difference and the fix."""
        attrs = self.ds.attrs
        fix = f"write this sweep elsewhere with --store PATH (store {str(self.path)!r})"
        axes = list(attrs.get("axes", []))
        if axes != list(sweep.axis_names):
            raise StoreMismatch(f"the store's axes are {axes}, this sweep's are "
                                f"{list(sweep.axis_names)}; results never mix: {fix}")
        old = physics_from_json(dict(attrs.get("fixed_physics", {})))
        for k in Physics.names():  # a group added since the store was made: its physics was off
            if k not in old and k in sweep.fixed and Physics.group(k).off is not None:
                old[k] = Physics.group(k).off
        diffs = [f"{k} = {old.get(k, 'unset')!r} in the store, {sweep.fixed.get(k, 'unset')!r} "
                 "in this sweep" for k in Physics.names() if old.get(k) != sweep.fixed.get(k)]
        diffs += [f"{k} = {old[k]!r} in the store, unknown to this solver"
                  for k in old if k not in Physics.names()]
        if diffs:
            raise StoreMismatch(f"the store was computed with other fixed physics "
                                f"({'; '.join(diffs)}); results never mix: {fix}")

    def _set_attrs(self, **attrs) -> None:
        """Update root attributes in one atomic replace of the root ``zarr.json``, its digest
        and consolidated copy with them. Through zarr (attrs, then ``seal``) it took two writes,
        the first without the consolidated metadata: a kill -9 between them (a sweep file whose
        text changed, 2 of 46 kill timings) left a store every reader and sweep refused."""
        import zarr

        self.require_writable()
        with self._changing(metadata=True), writing(None, "writing the store", self.path):
            root = _root(self.path)
            root["attributes"] = {**(root.get("attributes") or {}), **attrs}
            root["attributes"][DIGEST_KEY] = metadata_digest(root)
            meta = Path(self.path) / "zarr.json"
            # beside the store, not in it (a file the manifest does not list is damage there)
            tmp = Path(self.path).parent / f".{Path(self.path).name}.zarr.json.tmp-{os.getpid()}"
            try:
                with open(tmp, "w") as f:
                    f.write(json.dumps(root, indent=zarr.config.get("json_indent"),
                                       allow_nan=True))
                os.replace(tmp, meta)
            finally:
                if tmp.exists():
                    tmp.unlink()
        self.ds.attrs.update(attrs)

    def _extend(self, sweep) -> None:
        """Re-lay the store out on the union grid if the sweep adds values on any axis."""
        union = {a: _union(self.ds[a].values, sweep.axes[a]) for a in sweep.axis_names}
        if all(union[a].size == self.ds.sizes[a] for a in union):
            return
        self.load_all()
        fills = {}
        for name, (dtype, _, _) in VARIABLES.items():
            fills[name] = math.nan if name in FLAGS else _fill(dtype)
        grown = self.ds.reindex(union, fill_value=fills)
        for name in VARIABLES:  # reindex keeps values; restore dtypes the fill may have widened
            grown[name] = grown[name].astype(self.ds[name].dtype)
        grown.attrs.update(updated=_now())
        self.require_writable()
        _write_new(grown, self.path)
        found = self.damage  # what the store had when opened (the summary counts it)
        self._load()
        self.damage = found

    # ---- work list ------------------------------------------------------------------------------
    @property
    def axes(self) -> tuple:
        return tuple(self.ds["status"].dims)

    def cells(self, sweep):
        """Store index tuples (one index per axis, in the store's order) of every scene of
        ``sweep`` (row-major)."""
        import itertools

        idx = [_index(self.ds[a].values, sweep.axes[a]) for a in self.axes]
        return [tuple(int(i) for i in cell) for cell in itertools.product(*idx)]

    def status_of(self, cells) -> np.ndarray:
        st = self.ds["status"].values
        return np.array([st[cell] for cell in cells], dtype=int)

    def scene(self, cell) -> dict:
        """The physics of a cell: ``{name: value}`` for every field, in ``Physics.names()``
        order (axes from the coordinates, the rest from the fixed physics)."""
        values = dict(self.fixed)
        for a, i in zip(self.axes, cell):
            values[a] = float(self.ds[a].values[i])
        return {n: values[n] for n in Physics.names() if n in values}

    # ---- writing --------------------------------------------------------------------------------
    def record(self, cell, rec: dict, now: float | None = None) -> None:
        """Keep one finished scene: journal first (durable), then the in-memory copy; merge into
        the store when the flush interval has passed."""
        import time

        physics = self.scene(cell)
        jpath = _journal_path(self.path)
        line = journal_line({"physics": physics, "key": self.key, **rec})
        try:
            if self._journal is None:
                self.require_writable()
                try:
                    self._journal = open_append(jpath)
                except BadFile as exc:
                    raise StoreDamaged(f"the store's journal is not one a sweep writes: {exc}; "
                                       "move it aside") from None
            start = self._journal.tell()
            try:
                self._journal.write(line)
                self._journal.flush()  # in the OS page cache: survives the process being killed
            except OSError:
                # a full disk: cut the journal back to its last whole record (a part of a line
                # would be skipped anyway, but nothing partial is left behind)
                self._journal = _reopen_truncated(self._journal, jpath, start)
                raise
        except OSError as exc:
            raise write_error(exc, "writing the store's journal", jpath) from None
        self._apply(cell, rec)
        now = time.monotonic() if now is None else now
        if now - self._last_flush >= self.flush_seconds:
            self.flush()

    def _apply(self, cell, rec: dict) -> None:
        self.load_all()
        cell = tuple(cell)
        status = rec.get("status")
        message = str(rec.get("message", ""))
        code = STATUS_CODES.get(status) if isinstance(status, str) else None
        problem = record_problem(rec)
        if problem is not None:  # never stored as data: the scene's values are not trusted
            rec = {"model": "unknown"}
            code = STATUS_CODES["error"]
            message = f"refused the solver's record: {problem}"
        elif code is None or code == 0:
            code = STATUS_CODES["error"]
            message = f"unknown solver status {status!r}: {message}"
        key = rec.get("cache_key")
        if key is not None and self.worker_key is not None and key != self.worker_key:
            # never store another installation's numbers as ok
            code = STATUS_CODES["error"]
            message = (f"computed by a worker with another solver version or numerics (key "
                       f"{str(key)[:12]}, expected {self.worker_key[:12]}): every worker must run "
                       "the same installation; rerun with --retry-failed once it does")
        ok = code == STATUS_CODES["ok"]
        ds = self.ds
        for name in FLOATS:
            keep = ok or name in DIAGNOSTIC
            value = rec.get(name, math.nan)
            ds[name].values[cell] = float(math.nan if value is None else value) if keep \
                else math.nan
        for name in FLAGS:
            value = rec.get(name)
            ds[name].values[cell] = float(bool(value)) if ok and value is not None else math.nan
        for name in COUNTS:
            ds[name].values[cell] = int(rec.get(name, 0) or 0) if ok or name in DIAGNOSTIC else 0
        ds["model"].values[cell] = MODEL_CODES.get(rec.get("model"), 0)
        ds["message"].values[cell] = message
        ds["status"].values[cell] = code
        self._dirty.add(cell[:-1])

    def _replay(self) -> None:
        """Merge the journal of an interrupted run: records of this cache key whose physics
        matches the store on every axis and in its fixed values; any other is counted in
        ``journal_skipped`` (its scene runs again)."""
        recs, self.journal_skipped = read_journal(_journal_path(self.path))
        axes = self.axes
        for rec in recs:  # a record that fits no cell is counted with the bad lines
            physics = rec["physics"]
            if rec.get("key") != self.key or \
                    any(physics.get(k) != v for k, v in self.fixed.items()):
                self.journal_skipped += 1
                continue
            try:
                cell = tuple(int(_index(self.ds[a].values, [physics[a]])[0]) for a in axes)
            except (KeyError, TypeError):
                self.journal_skipped += 1
                continue
            self._apply(cell, {k: v for k, v in rec.items() if k not in ("physics", "key")})
        self.flush(force=True)

    def flush(self, force: bool = False) -> None:
        """Write the touched cells: data first, status last; then drop the merged journal.

        The region written is the bounding box of the touched chunks (1 along every axis but the
        last, whole along the last)."""
        import time

        if self._dirty:
            self.require_writable()
            axes = self.axes
            lead = np.array(sorted(self._dirty), dtype=int).reshape(len(self._dirty), -1)
            region = {a: slice(int(lead[:, k].min()), int(lead[:, k].max()) + 1)
                      for k, a in enumerate(axes[:-1])}
            region[axes[-1]] = slice(None)
            block = self.ds.isel({a: r for a, r in region.items()}).drop_vars(list(axes))
            keys = self._chunk_keys([range(region[a].start, region[a].stop) for a in axes[:-1]])
            # zarr writes each chunk through a temporary file it removes on failure
            with self._changing(keys), writing(None, "writing the store", self.path), \
                    zarr_warnings():
                block.drop_vars("status").to_zarr(self.path, region=region, mode="r+",
                                                  consolidated=False)
                block[["status"]].to_zarr(self.path, region=region, mode="r+",
                                          consolidated=False)
            self._dirty.clear()
            force = True
        if force:
            self._close_journal()
            _journal_path(self.path).unlink(missing_ok=True)
        self._last_flush = time.monotonic()

    def _close_journal(self) -> None:
        if self._journal is not None:
            self._journal.close()
            self._journal = None
