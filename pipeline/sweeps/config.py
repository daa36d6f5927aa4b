"""Sweep definitions: a TOML file -> a frozen :class:`Sweep` (the plan as plain data).

A sweep file holds what decides the *results*: the grid, the fixed physics, the accuracy preset and
any numerical overrides, and where the store lives. How the sweep is executed (scheduler, workers)
comes from the command line and never changes a number. Format (``sweeps/paper.toml`` is the
reference)::

    name = "paper"
    store = "results/paper.zarr"          # relative paths: from the directory ehd runs in

    [grid]                                # the axes: any fields of solver.Physics (at least one)
    St = {start = 0.5, stop = 100.0, num = 64}   # log-spaced, endpoints included (geomspace)
    eps = [1e-2, 1e-3, 1e-4]                     # or an explicit list

    [physics]                             # optional: fixed values of the other Physics fields
    # eps = 1e-3                          # (a field is an axis or fixed, never both)

    [numerics]
    accuracy = "standard"                 # preset: fast, standard, fine
    # fast_path = true                    # master curve in S = St V_switch (solver/master.py)
    # rtol = 1e-4                         # optional overrides of solver.Numerics fields

Every field of ``solver.Physics`` must be an axis, fixed, or have a default (``Group.default``).
The cache key of a sweep is the sha256 of the canonical JSON of the solver version, the fully
resolved numerical settings, the fixed physics and the axis names (never ``dask.base.tokenize``:
not stable across interpreters).
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..cli_shared import inert_groups, inert_message
from ..errors import UsageError

__all__ = ["Sweep", "load_sweep", "parse_sweep", "cache_key", "canonical_json", "ConfigError",
           "physics_json", "physics_from_json", "format_physics"]

_TOP_KEYS = {"name", "store", "grid", "physics", "numerics"}
_RANGE_KEYS = {"start", "stop", "num"}
MAX_SCENES = 10**7  # a typo guard (num = 1e9), far above any real sweep


class ConfigError(UsageError, ValueError):
    """A sweep file is malformed; the message names the file and the offending key."""


def format_physics(physics: dict) -> str:
    """``St=20 eps=1e-08``: a scene's physics in one short line."""
    return " ".join(f"{k}={v:.6g}" if isinstance(v, float) else f"{k}={v}"
                    for k, v in physics.items())


def canonical_json(obj) -> str:
    """JSON with sorted keys, no whitespace and no NaN: equal settings give equal bytes."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def physics_json(values: dict) -> dict:
    """Physics values in a form JSON holds exactly: an infinite value (``Pi = inf``, the classic
    film) as the string "inf" (store attrs, cache keys)."""
    return {k: ("inf" if isinstance(v, float) and math.isinf(v) else v) for k, v in values.items()}


def physics_from_json(values: dict) -> dict:
    """The inverse of :func:`physics_json`."""
    return {k: (math.inf if v == "inf" else v) for k, v in values.items()}


def cache_key(solver_version: str, numerics: dict, fixed_physics: dict | None = None,
              axes=()) -> str:
    """sha256 (hex) of the canonical JSON of the solver version, the resolved numerics, the fixed
    physics and the axis names: stores computed with other physics never share a key."""
    payload = canonical_json({"solver_version": solver_version, "numerics": numerics,
                              "fixed_physics": physics_json(dict(fixed_physics or {})),
                              "axes": list(axes)})
    return hashlib.sha256(payload.encode()).hexdigest()


@dataclass(frozen=True)
class Sweep:
    """One sweep: its axes and fixed physics, its numerical settings and its store.

    Attributes
    ----------
    name : str
        Short label (defaults to the file's stem).
    axes : dict
        ``{name: values}`` for every swept field of ``solver.Physics``, in ``Physics.names()``
        order; values sorted ascending, each validated against its group's range.
    fixed : dict
        ``{name: value}`` for every other field (from ``[physics]`` or the group's default).
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
    axes: dict
    fixed: dict
    accuracy: str
    overrides: dict = field(default_factory=dict)
    fast_path: bool = False  # answer scenes from a master curve in S = St V_switch (opt-in)
    store: Path = Path("results/sweep.zarr")
    source: str = ""
    path: Path | None = None

    @property
    def axis_names(self) -> tuple:
        return tuple(self.axes)

    @property
    def shape(self) -> tuple:
        return tuple(len(v) for v in self.axes.values())

    @property
    def n_scenes(self) -> int:
        return math.prod(self.shape)

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
        """The store's key: solver version, numerics, fixed physics and axis names."""
        return cache_key(self.solver_version(), self.numerics(), self.fixed, self.axis_names)

    def worker_key(self) -> str:
        """The key a worker stamps on its records (``tasks.collision_record``): solver version
        and numerics of the installation that computed it (the scene's physics is the store's
        business)."""
        return cache_key(self.solver_version(), self.numerics())

    def with_store(self, store) -> "Sweep":
        from dataclasses import replace

        return replace(self, store=Path(store))


def load_sweep(path) -> Sweep:
    """Read and validate a sweep file.

    Raises
    ------
    ConfigError
        Unreadable file (also a FIFO, a device or one larger than ``reads.MAX_INPUT_BYTES``),
        unknown keys, bad grid values (naming the parameter and its valid
        range) or unknown numerical settings.
    """
    from ..reads import read_input

    path = Path(path)
    try:  # a UTF-8 byte-order mark is no TOML
        text = read_input(path, f"sweep file {str(path)!r}", ConfigError).decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"sweep file {str(path)!r} is not a text file (byte {exc.start} is not "
                          "UTF-8): give a TOML sweep file such as sweeps/quick.toml") from None
    except OSError as exc:
        raise ConfigError(f"cannot read sweep file {str(path)!r}: {exc.strerror}") from None
    if "\x00" in text:
        raise ConfigError(f"sweep file {str(path)!r} is not a text file (it holds NUL bytes): "
                          "give a TOML sweep file such as sweeps/quick.toml")
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

    axes, fixed = _physics(where, doc)
    numerics = doc.get("numerics", {})
    if not isinstance(numerics, dict):
        raise ConfigError(f"{where}: [numerics] must be a table, got {numerics!r}")
    numerics = dict(numerics)
    accuracy = numerics.pop("accuracy", "standard")
    if not isinstance(accuracy, str):
        raise ConfigError(f"{where}: [numerics] accuracy must be the name of a preset "
                          f"(e.g. accuracy = \"standard\"), got {accuracy!r}")
    fast_path = numerics.pop("fast_path", False)
    if not isinstance(fast_path, bool):
        raise ConfigError(f"{where}: [numerics] fast_path must be true or false, got {fast_path!r}")
    if "save_profiles" in numerics:
        raise ConfigError(f"{where}: [numerics] save_profiles is fixed by the pipeline (sweeps "
                          "store scalars only); remove it")
    sweep = Sweep(name=name, axes=axes, fixed=fixed, accuracy=accuracy,
                  overrides=numerics, fast_path=fast_path, store=Path(store), source=text,
                  path=path)
    try:
        sweep.numerics()
    except ValueError as exc:
        raise ConfigError(f"{where}: [numerics]: {exc}") from None
    return sweep


def _physics(where: str, doc: dict) -> tuple[dict, dict]:
    """``(axes, fixed)`` of a sweep file: ``[grid]`` and ``[physics]`` checked against
    ``solver.Physics``. The grid's size is checked before any array is built."""
    from solver.physics import Physics

    names = Physics.names()
    grid = doc.get("grid")
    if not isinstance(grid, dict) or not grid:
        raise ConfigError(f"{where}: missing [grid] table with at least one axis, one of "
                          f"{list(names)}")
    table = doc.get("physics", {})
    if not isinstance(table, dict):
        raise ConfigError(f"{where}: [physics] must be a table of fixed values, got {table!r}")
    for section, keys in (("grid", grid), ("physics", table)):
        unknown = [k for k in keys if k not in names]
        if unknown:
            raise ConfigError(f"{where}: [{section}] has unknown physics field(s) {unknown}; "
                              f"valid: {list(names)}")
    both = [n for n in names if n in grid and n in table]
    if both:
        raise ConfigError(f"{where}: {both} both in [grid] and [physics]; a field is swept or "
                          "fixed, not both")
    missing = [n for n in names if n not in grid and n not in table
               and Physics.group(n).default is None]
    if missing:
        raise ConfigError(f"{where}: {missing} neither in [grid] nor in [physics]; give each "
                          "field a grid axis or a fixed value")
    choice_axes = [n for n in names if n in grid and not Physics.group(n).numeric]
    if choice_axes:
        raise ConfigError(f"{where}: {choice_axes} name a model or a table, not a number: fix "
                          "it in [physics] (one store per model)")
    n = 1
    for name in names:  # size first: a typo (num = 1e9) must not allocate gigabytes
        if name in grid:
            n *= _axis_size(where, name, grid[name])
    if n > MAX_SCENES:
        raise ConfigError(f"{where}: the grid has {n} scenes; at most {MAX_SCENES} allowed")
    axes = {name: _axis(where, name, grid[name]) for name in names if name in grid}
    fixed = {}
    for name in names:
        if name in grid:
            continue
        if name in table:
            try:
                fixed[name] = Physics.group(name).check(table[name])
            except ValueError as exc:
                raise ConfigError(f"{where}: physics.{exc}") from None
        else:
            fixed[name] = Physics.group(name).default
    _check_grid_points(where, axes, fixed)
    found = inert_groups({**fixed, **axes})
    if found:  # e.g. e_dry without roughness, a Pi axis with cavitation off
        raise ConfigError(f"{where}: at every grid point " + inert_message(found, str)
                          + " ([physics] or [grid])")
    return axes, fixed


def _check_grid_points(where: str, axes: dict, fixed: dict) -> None:
    """The solver's own checks between groups (``Physics``: e.g. a roughness below the start
    gap ``x0/x1 = eps^-0.4``) at the grid's corners (every axis at its smallest and its largest
    value), before any solve; ``Physics`` itself checks, as each task will. Its checks between
    groups are monotone in each value (a rougher or a larger-eps scene fails first), so a grid
    passes them at every point when it does at its corners: 2^axes scenes checked, not all."""
    import itertools

    from solver.physics import Physics

    ends = [sorted({values[0], values[-1]}) for values in axes.values()]
    for corner in itertools.product(*ends):
        point = dict(zip(axes, corner))
        try:
            Physics.from_mapping({**fixed, **point})
        except ValueError as exc:
            raise ConfigError(f"{where}: the grid point {format_physics(point)}: {exc}; every "
                              "grid point must be a valid scene (checked before any solve)"
                              ) from None


def _axis_size(where: str, name: str, spec) -> int:
    """Number of values of one axis, read without building them."""
    if isinstance(spec, dict):
        if set(spec) != _RANGE_KEYS:
            raise ConfigError(f"{where}: grid.{name} as a range needs exactly {sorted(_RANGE_KEYS)} "
                              f"(log-spaced), got {sorted(spec)}")
        num = spec["num"]
        if not isinstance(num, int) or isinstance(num, bool) or num < 1:
            raise ConfigError(f"{where}: grid.{name}.num must be a whole number >= 1, got {num!r}")
        return num
    if isinstance(spec, list):
        if not spec:
            raise ConfigError(f"{where}: grid.{name} is empty")
        return len(spec)
    raise ConfigError(f"{where}: grid.{name} must be a list of numbers or "
                      f"{{start, stop, num}}, got {spec!r}")


def _axis(where: str, name: str, spec) -> tuple:
    """Grid values of one axis: a list of numbers, or {start, stop, num} log-spaced (the spec is
    already checked by :func:`_axis_size`)."""
    from solver.physics import Physics

    group = Physics.group(name)

    def check(label, v):
        try:
            group.check(v)
        except ValueError as exc:
            raise ConfigError(f"{where}: grid.{label}: {exc}") from None

    if isinstance(spec, dict):
        start, stop = (_number(where, f"{name}.{k}", spec[k]) for k in ("start", "stop"))
        check(f"{name}.start", start)
        check(f"{name}.stop", stop)
        if not (start > 0.0 and stop > 0.0):
            raise ConfigError(f"{where}: grid.{name} = {{start = {start:g}, stop = {stop:g}, ...}}"
                              " is log-spaced and cannot reach 0: give the values as a list "
                              f"({name} = [0.0, ...]), or a start > 0")
        if math.isinf(start) or math.isinf(stop):  # a group that takes inf (Pi: no floor)
            raise ConfigError(f"{where}: grid.{name} = {{start = {start:g}, stop = {stop:g}, ...}}"
                              " is log-spaced and cannot reach inf: give the values as a list "
                              f"({name} = [..., inf]), or finite ends")
        if spec["num"] == 1 and start != stop:
            raise ConfigError(f"{where}: grid.{name} = {{start = {start:g}, stop = {stop:g}, num = "
                              f"1}} is one value but two ends: give num >= 2, or the one value as "
                              f"a list ({name} = [{start:g}])")
        values = np.geomspace(start, stop, spec["num"])
    else:
        values = np.array([_number(where, name, v) for v in spec])
    for v in values:
        check(name, float(v))
    values = np.sort(values)
    lo, hi = values[:-1], values[1:]
    with np.errstate(invalid="ignore"):  # inf - inf: two infs are the same value
        same = np.where(np.isinf(hi), hi == lo, hi - lo <= 1e-9 * np.abs(hi))
    if np.any(same):
        raise ConfigError(f"{where}: grid.{name} has repeated values")
    return tuple(float(v) for v in values)


def _number(where, name, v) -> float:
    """A number of a grid axis (its group decides whether inf is allowed: Pi = inf is the
    classic film)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ConfigError(f"{where}: grid.{name} must be a number, got {v!r}")
    if math.isnan(v):
        raise ConfigError(f"{where}: grid.{name} must be a number, got nan (not a number): "
                          "remove it from the list")
    return float(v)
