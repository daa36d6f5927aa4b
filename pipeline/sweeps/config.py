"""Sweep definitions: a TOML file -> a frozen :class:`Sweep` (the plan as plain data).

A sweep file holds what decides the *results*: the grid, the accuracy preset and any numerical
overrides, and where the store lives. How the sweep is executed (scheduler, workers) comes from the
command line and never changes a number. Format (``sweeps/paper.toml`` is the reference)::

    name = "paper"
    store = "results/paper.zarr"          # relative paths: from the directory ehd runs in

    [grid]
    St = {start = 0.5, stop = 100.0, num = 64}   # log-spaced, endpoints included (geomspace)
    eps = [1e-2, 1e-3, 1e-4]                     # or an explicit list

    [numerics]
    accuracy = "standard"                 # preset: fast, standard, fine
    # fast_path = true                    # master curve in S = St V_switch (solver/master.py)
    # rtol = 1e-4                         # optional overrides of solver.Numerics fields

The cache key of a sweep is the sha256 of the canonical JSON of the solver version and the fully
resolved numerical settings (never ``dask.base.tokenize``: not stable across interpreters).
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Sweep", "load_sweep", "parse_sweep", "cache_key", "canonical_json", "ConfigError"]

_TOP_KEYS = {"name", "store", "grid", "numerics"}
_AXES = ("St", "eps")
_RANGE_KEYS = {"start", "stop", "num"}
MAX_SCENES = 10**7  # a typo guard (num = 1e9), far above any real sweep


class ConfigError(ValueError):
    """A sweep file is malformed; the message names the file and the offending key."""


def canonical_json(obj) -> str:
    """JSON with sorted keys, no whitespace and no NaN: equal settings give equal bytes."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def cache_key(solver_version: str, numerics: dict) -> str:
    """sha256 (hex) of the canonical JSON of the solver version and the resolved numerics."""
    payload = canonical_json({"solver_version": solver_version, "numerics": numerics})
    return hashlib.sha256(payload.encode()).hexdigest()


@dataclass(frozen=True)
class Sweep:
    """One sweep: the (St, eps) grid, its numerical settings and its store.

    Attributes
    ----------
    name : str
        Short label (defaults to the file's stem).
    St, eps : tuple of float
        Grid values, sorted ascending, each validated against the solver's range.
    accuracy : str
        Solver preset name.
    overrides : dict
        Explicit overrides of ``solver.Numerics`` fields from the ``[numerics]`` table.
    store : Path
        Where the zarr store lives (already resolved against the working directory).
    source : str
        The sweep file verbatim (stamped into the store's attrs).
    path : Path or None
        The file it was read from.
    """

    name: str
    St: tuple
    eps: tuple
    accuracy: str
    overrides: dict = field(default_factory=dict)
    fast_path: bool = False  # answer scenes from a master curve in S = St V_switch (opt-in)
    store: Path = Path("results/sweep.zarr")
    source: str = ""
    path: Path | None = None

    @property
    def n_scenes(self) -> int:
        return len(self.St) * len(self.eps)

    def numerics(self) -> dict:
        """The fully resolved numerical settings of every scene (profiles never kept in sweeps)."""
        from solver.settings import resolve

        numerics = resolve(self.accuracy, **self.overrides, save_profiles=False).as_dict()
        if self.fast_path:  # changes the answers (within its measured error): part of the key
            numerics["fast_path"] = True
        return numerics

    def solver_version(self) -> str:
        from solver import SOLVER_VERSION

        return SOLVER_VERSION

    def cache_key(self) -> str:
        return cache_key(self.solver_version(), self.numerics())

    def with_store(self, store) -> "Sweep":
        from dataclasses import replace

        return replace(self, store=Path(store))


def load_sweep(path) -> Sweep:
    """Read and validate a sweep file.

    Raises
    ------
    ConfigError
        Unreadable file, unknown keys, bad grid values (naming the parameter and its valid
        range) or unknown numerical settings.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read sweep file {str(path)!r}: {exc.strerror}") from None
    return parse_sweep(text, path=path)


def parse_sweep(text: str, path: Path | None = None) -> Sweep:
    """Parse sweep-file text (see the module docstring for the format)."""
    where = str(path) if path is not None else "<sweep>"
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML: {exc}") from None
    unknown = set(doc) - _TOP_KEYS
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {sorted(unknown)}; valid: {sorted(_TOP_KEYS)}")
    name = doc.get("name", path.stem if path is not None else "sweep")
    if not isinstance(name, str) or not name:
        raise ConfigError(f"{where}: name must be a non-empty string, got {name!r}")
    store = doc.get("store")
    if not isinstance(store, str) or not store.strip():
        raise ConfigError(f"{where}: store must be a path string, e.g. store = \"results/{name}.zarr\"")

    grid = doc.get("grid")
    if not isinstance(grid, dict):
        raise ConfigError(f"{where}: missing [grid] table with St and eps")
    unknown = set(grid) - set(_AXES)
    if unknown or any(a not in grid for a in _AXES):
        raise ConfigError(f"{where}: [grid] must hold exactly St and eps, got {sorted(grid)}")
    axes = {a: _axis(where, a, grid[a]) for a in _AXES}
    n = len(axes["St"]) * len(axes["eps"])
    if n > MAX_SCENES:
        raise ConfigError(f"{where}: the grid has {n} scenes; at most {MAX_SCENES} allowed")

    numerics = dict(doc.get("numerics", {}))
    accuracy = numerics.pop("accuracy", "standard")
    fast_path = numerics.pop("fast_path", False)
    if not isinstance(fast_path, bool):
        raise ConfigError(f"{where}: [numerics] fast_path must be true or false, got {fast_path!r}")
    if "save_profiles" in numerics:
        raise ConfigError(f"{where}: [numerics] save_profiles is fixed by the pipeline (sweeps "
                          "store scalars only); remove it")
    sweep = Sweep(name=name, St=axes["St"], eps=axes["eps"], accuracy=accuracy,
                  overrides=numerics, fast_path=fast_path, store=Path(store), source=text,
                  path=path)
    try:
        sweep.numerics()
    except ValueError as exc:
        raise ConfigError(f"{where}: [numerics]: {exc}") from None
    return sweep


def _axis(where: str, name: str, spec) -> tuple:
    """Grid values of one axis: a list of numbers, or {start, stop, num} log-spaced."""
    from solver.settings import EPS_RANGE, STOKES_RANGE

    lo, hi = STOKES_RANGE if name == "St" else EPS_RANGE
    valid = f"valid range ({lo:g}, {hi:g}]"
    if isinstance(spec, dict):
        if set(spec) != _RANGE_KEYS:
            raise ConfigError(f"{where}: grid.{name} as a range needs exactly {sorted(_RANGE_KEYS)} "
                              f"(log-spaced), got {sorted(spec)}")
        num = spec["num"]
        if not isinstance(num, int) or isinstance(num, bool) or num < 1:
            raise ConfigError(f"{where}: grid.{name}.num must be a whole number >= 1, got {num!r}")
        start, stop = (_number(where, f"{name}.{k}", spec[k]) for k in ("start", "stop"))
        for k, v in (("start", start), ("stop", stop)):
            if not lo < v <= hi:
                raise ConfigError(f"{where}: grid.{name}.{k} = {v!r} is outside the {valid}")
        values = np.geomspace(start, stop, num)
    elif isinstance(spec, list):
        if not spec:
            raise ConfigError(f"{where}: grid.{name} is empty")
        values = np.array([_number(where, name, v) for v in spec])
    else:
        raise ConfigError(f"{where}: grid.{name} must be a list of numbers or "
                          f"{{start, stop, num}}, got {spec!r}")
    for v in values:
        if not lo < v <= hi:
            raise ConfigError(f"{where}: grid.{name} value {v!r} is outside the {valid}")
    values = np.sort(values)
    if np.any(np.diff(values) <= 1e-9 * values[1:]):
        raise ConfigError(f"{where}: grid.{name} has repeated values")
    return tuple(float(v) for v in values)


def _number(where, name, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ConfigError(f"{where}: grid.{name} must be a finite number, got {v!r}")
    return float(v)
