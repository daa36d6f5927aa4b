"""Run a sweep: plan the scenes the store lacks, run them on an executor, keep every result.

Orchestration only: the physics is in ``solver``, the storage rules in :mod:`pipeline.sweeps.store`, the
executors in :mod:`pipeline.sweeps.runners`. One loop consumes finished scenes in completion order, hands
each to the store's single writer and updates the progress bar.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import EXIT_OK, EXIT_SWEEP_FAILED
from .config import format_physics
from .layout import MODEL_CODES, STATUS_CODES
from .progress import Progress
from .runners import (DEFAULT_RUNNER, check_runner, choose_runner, open_runner,
                      probe_scheduler)
from .store import SweepStore
from .tasks import MasterSolve, one_scene_per_set, solve_scene, warm

__all__ = ["run_sweep", "Summary", "EXIT_OK", "EXIT_FAILED", "format_physics"]

# the one exit-code table is pipeline/errors.py; EXIT_FAILED is its EXIT_SWEEP_FAILED (3): the
# sweep finished, but some of its scenes are stored as failed
EXIT_FAILED = EXIT_SWEEP_FAILED

_CODE_NAMES = {v: k for k, v in STATUS_CODES.items()}


@dataclass
class Summary:
    """What a sweep run did. Counts are over the sweep's own grid."""

    name: str
    store: str
    shape: tuple  # points along each axis
    axes: tuple = ()  # axis names (fields of solver.Physics), same order as shape
    runner: str = "-"
    scenes: int = 0
    cached: int = 0  # already in the store (ok or failed) and not recomputed
    computed: int = 0  # computed in this run
    computed_failed: int = 0
    done: int = 0  # stored as ok
    failed: int = 0  # stored as failed (this run or before)
    premise_failed: int = 0  # of those, start_deformed: the model's premise, the same on a retry
    retried: bool = False  # this run reran the failed scenes (--retry-failed)
    not_run: int = 0  # still missing (an interrupted run)
    repaired: int = 0  # damaged cells found when the store was opened (recomputed if in the grid)
    repaired_coords: tuple = ()  # damaged coordinates rewritten from the store's copy
    journal_skipped: int = 0  # journal lines that were not scene records (their scenes rerun)
    rigid: int = 0  # answered by the rigid solution, no PDE solve
    rigid_computed: int = 0
    wall_s: float = 0.0
    failures: list = field(default_factory=list)  # (physics dict, status, message), at most 20

    @property
    def exit_code(self) -> int:
        return EXIT_FAILED if self.failed or self.not_run else EXIT_OK

    @property
    def rate(self) -> float:
        return self.computed / self.wall_s if self.wall_s > 0 else float("nan")

    def text(self) -> str:
        grid = " x ".join(f"{n} {a}" for n, a in zip(self.shape, self.axes))
        lines = [
            f"sweep {self.name!r}: {self.scenes} scenes ({grid}) in {self.store}",
            f"  done        {self.done:6d}   (computed now {self.computed - self.computed_failed}, "
            f"cached {self.done - (self.computed - self.computed_failed)})",
            f"  failed      {self.failed:6d}   (now {self.computed_failed})",
            f"  rigid-only  {self.rigid:6d}   (answered analytically, no PDE solve; "
            f"{self.rigid_computed} of them computed now)",
        ]
        if self.not_run:
            lines.append(f"  not run     {self.not_run:6d}")
        if self.repaired:
            lines.append(f"  repaired    {self.repaired:6d}   (damaged cells found in the store, "
                         "computed again)")
        if self.repaired_coords:
            lines.append(f"  repaired    coordinate(s) {', '.join(self.repaired_coords)} (damaged, "
                         "rewritten from the store's copy)")
        if self.journal_skipped:
            lines.append(f"  journal     {self.journal_skipped:6d}   bad lines skipped (their "
                         "scenes computed again)")
        lines.append(f"  runner      {self.runner}; {self.computed} scenes in {self.wall_s:.1f} s"
                     + (f" ({self.rate:.1f} scenes/s)" if self.computed else ""))
        for physics, status, message in self.failures:
            lines.append(f"  failed: {format_physics(physics)} {status}: {message}")
        if self.failed > len(self.failures):
            lines.append(f"  ... {self.failed - len(self.failures)} more (ehd status {self.store})")
        if self.premise_failed:
            lines.append(f"  {self.premise_failed} of the failed are start_deformed: eps is not "
                         "small for their St, the model's premise (a retry gives the same)")
        if self.failed > self.premise_failed and self.retried:  # a solve gives the same again
            lines.append("  these failed again on this retry, as the same numerics will each "
                         "time: ehd status lists their reasons")
        elif self.failed > self.premise_failed:
            lines.append("  rerun only the failed scenes with --retry-failed")
        return "\n".join(lines)


def run_sweep(sweep, *, store=None, runner: str | None = DEFAULT_RUNNER, workers: int | None = None,
              address: str | None = None, scheduler_file: str | None = None,
              retry_failed: bool = False, solve=solve_scene, warm_up: bool | None = None,
              progress=sys.stderr, flush_seconds: float | None = None,
              wait_workers: float | None = None, add_sweep: bool = False,
              connect_seconds: float | None = None, allow_large: bool = False) -> Summary:
    """Compute every scene of ``sweep`` that its store lacks.

    Parameters
    ----------
    sweep : pipeline.sweeps.config.Sweep
        Grid, numerics, store location.
    store : path, optional
        Store location overriding ``sweep.store``.
    runner : {"auto", "threads", "processes", "serial"}
        Local executor (ignored with ``address``/``scheduler_file``; runners.py says which to
        take).
    workers : int, optional
        Local workers (default: usable cores); with a scheduler, workers to wait for.
    address, scheduler_file : str, optional
        An existing dask.distributed scheduler.
    retry_failed : bool
        Also rerun scenes stored as failed (otherwise they count as cached).
    solve : callable
        ``solve(physics: dict, accuracy, overrides) -> record``; the real solver by default (tests pass
        a stand-in). Must be importable by workers.
    warm_up : bool, optional
        Warm the compiled solver before workers start; default: only for the real solver.
    progress : file or None
        Stream for the progress bar.
    flush_seconds : float, optional
        Journal -> store merge interval (default ``store.FLUSH_SECONDS``).
    wait_workers : float, optional
        With a scheduler: seconds to wait for ``workers`` (default ``runners.WAIT_WORKERS_SECONDS``).
    add_sweep : bool
        Allow another sweep file to write into an existing store (recorded in its ``sweeps``).
    connect_seconds : float, optional
        With a scheduler: seconds to try to reach it (default ``runners.CONNECT_SECONDS``).
    allow_large : bool
        Run a grid of more than ``LARGE_SCENES`` scenes (refused otherwise, before anything is
        allocated: a typo in ``num`` should not start weeks of work).

    Returns
    -------
    Summary
        Counts; ``summary.exit_code`` is ``EXIT_FAILED`` (3) when failed scenes remain.
    """
    t0 = time.monotonic()
    check_store_name(sweep.store if store is None else store,
                     "store" if store is None else "--store")
    check_memory(sweep.n_scenes, progress, allow_large)  # before any allocation
    kwargs = {} if flush_seconds is None else {"flush_seconds": flush_seconds}
    if warm_up is None:
        warm_up = solve is solve_scene
    overrides = dict(sweep.overrides)
    address = _check_executor(runner, workers, address, scheduler_file, connect_seconds,
                              wait_workers, progress)
    runner_kw = {} if wait_workers is None else {"wait_workers": wait_workers}
    if connect_seconds is not None:
        runner_kw["connect_seconds"] = connect_seconds
    with SweepStore.open(sweep, store, add_sweep=add_sweep, **kwargs) as st:
        summary = Summary(name=sweep.name, store=st.shown, shape=sweep.shape,
                          axes=sweep.axis_names, retried=bool(retry_failed))
        cells, todo = _plan(st, sweep, summary, retry_failed, progress)
        if todo and sweep.fast_path and solve is solve_scene:
            solve = _master_solve(sweep, progress)
        if todo:
            jobs = [(cell, (st.scene(cell), sweep.accuracy, overrides)) for cell in todo]
            warm_fn = _Warm(sweep.accuracy, overrides, one_scene_per_set(
                job[1][0] for job in jobs)) if warm_up else None
            if warm_up and progress is not None:  # the warm-up compiles on a fresh install
                from ..environment import compile_notice

                compile_notice(progress, physics=[None, *warm_fn.scenes])
            runner_at = open_runner(choose_runner(runner, len(jobs)), workers, address, None,
                                    warm=warm_fn, stream=progress, **runner_kw)
            _compute(st, summary, jobs, solve, runner_at, progress)
        _count(summary, st, cells)
    summary.wall_s = time.monotonic() - t0
    return summary


def _check_executor(runner, workers, address, scheduler_file, connect_seconds, wait_workers,
                    progress):
    """The executor's settings and a scheduler file, checked before the store is touched; a
    scheduler must answer before any store or lock is made. Returns its address (None:
    local)."""
    address = check_runner(runner, workers, address, scheduler_file, connect_seconds,
                           wait_workers)
    if address is not None:
        target = address + (f" (from {scheduler_file})" if scheduler_file else "")
        if progress is not None:
            print(f"checking the dask scheduler at {target}...", file=progress, flush=True)
        probe_scheduler(address, connect_seconds, target)
    return address


def _plan(st, sweep, summary: Summary, retry_failed: bool, progress):
    """``(cells, todo)``: every cell of the sweep and those the store lacks (or holds as failed,
    with ``retry_failed``); damaged cells are computed again and counted in ``summary``."""
    summary.repaired = len(st.damage)
    summary.repaired_coords = tuple(sorted(st.damage.coords))
    summary.journal_skipped = st.journal_skipped
    if st.damage and progress is not None:
        print(f"store {st.shown} is damaged: {st.damage_text}; "
              "those cells are computed again", file=progress, flush=True)
    if progress is not None and sweep.n_scenes >= PLANNING_NOTE:
        print(f"store {st.shown} ready; listing the scenes it lacks...", file=progress,
              flush=True)
    cells = st.cells(sweep)

    def lacking():
        status = st.status_of(cells)
        rerun = (status == 0) | (retry_failed & (status >= 2))
        return [c for c, r in zip(cells, rerun) if r]

    todo = lacking()
    if todo:
        st.require_writable()  # before any solve, not at the first merge
        late = st.load_all()  # the variables planning did not need, before any solve
        if late:  # cells damaged in a way only decoding finds: computed again too
            summary.repaired += late
            todo = lacking()
    summary.scenes, summary.cached = len(cells), len(cells) - len(todo)
    return cells, todo


def _compute(st, summary: Summary, jobs, solve, runner_at, progress) -> None:
    """Solve ``jobs`` (``[(cell, args)]``) on the runner ``runner_at`` (an ``open_runner``
    context) and record each in the store as it finishes, counting into ``summary``."""
    bar = Progress(len(jobs), stream=progress)
    try:
        with runner_at as run:
            summary.runner = run.description
            if progress is not None:
                print(f"{len(jobs)} scenes to compute ({summary.cached} cached) on "
                      f"{run.description}", file=progress, flush=True)
            bar.start = time.monotonic()
            for cell, rec in run.unordered(solve, jobs):
                if isinstance(rec, BaseException):
                    rec = {"status": "error", "model": "unknown",
                           "message": f"task failed: {type(rec).__name__}: {rec}"}
                st.record(cell, rec)
                summary.computed += 1
                summary.computed_failed += rec.get("status") != "ok"
                summary.rigid_computed += rec.get("model") == "rigid"
                bar.update(rec.get("status"), rec.get("model"))
    finally:
        bar.close()
    # what the store kept, not what the workers said (it turns a record from a worker with
    # another installation into an error)
    stored = st.status_of([cell for cell, _ in jobs])
    summary.computed_failed = int(np.sum(stored >= 2))


def check_store_name(path, label: str = "store") -> None:
    """PathError, before anything is made, when the store's name or a name the store makes
    next to it (its lock, journal, temporary layout, old copy: pipeline/sweeps/store.py) is
    longer than the file system takes: the lock would fail first, as a bug (exit 70)."""
    from pathlib import Path

    from ..cli_shared import check_name_length
    from ..errors import PathError
    from .journal import _journal_path
    from .store import _lock_path, _old_path, _tmp_path, unnamed

    if not str(path).strip():
        return  # the store says "empty path" itself
    if unnamed(path):
        raise PathError(f"{label} {path}: a folder named by its place ('.', '..', '/') cannot be "
                        "a sweep store (its lock and journal are named after it); give the "
                        "store's own name, e.g. results.zarr")
    path = Path(path)
    check_name_length(label, path, [made(path) for made in (_lock_path, _journal_path,
                                                            _old_path, _tmp_path)])


# bytes one scene takes while a sweep is planned and run: its cell in the in-memory store (every
# variable of the layout) plus the work list (the cell's index tuple, its job with the physics
# dict; measured ~0.5 kB with sys.getsizeof on CPython 3.11)
PLAN_BYTES_PER_SCENE = 500
MEMORY_SHARE = 0.5  # of the memory available: a sweep planning more is refused
PLANNING_NOTE = 100_000  # scenes above which planning is announced (it takes seconds)
LARGE_SCENES = 1_000_000  # scenes above which a sweep needs allow_large (--allow-large)


def plan_bytes(n_scenes: int) -> int:
    """Memory a sweep of ``n_scenes`` needs to be planned: the layout's bytes per cell (dtype
    sizes; strings as a pointer) plus ``PLAN_BYTES_PER_SCENE``."""
    from .layout import FLAGS, VARIABLES

    per_cell = sum(8 if dtype == "str" else (4 if name in FLAGS else int(dtype[1:]))
                   for name, (dtype, _, _) in VARIABLES.items())
    return int(n_scenes) * (per_cell + PLAN_BYTES_PER_SCENE)


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (MemAvailable of /proc/meminfo), or None
    where it cannot be read."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_memory(n_scenes: int, progress=None, allow_large: bool = False) -> None:
    """UsageError, before anything is allocated, when a grid of ``n_scenes`` would take more
    than ``MEMORY_SHARE`` of the available memory to plan, or has more than ``LARGE_SCENES``
    scenes without ``allow_large`` (``--allow-large``); a large grid is announced."""
    from ..errors import UsageError
    from ..errors import _bytes as size

    need = plan_bytes(n_scenes)
    if n_scenes > LARGE_SCENES and not allow_large:
        raise UsageError(f"the sweep has {n_scenes} scenes (planning them takes about "
                         f"{size(need)} of memory; at 0.1 s a scene, {n_scenes * 0.1 / 86400:.0f} "
                         f"core-days): more than {LARGE_SCENES}, so it needs --allow-large to "
                         "run; check the grid's num values")
    have = available_memory()
    if have is not None and need > MEMORY_SHARE * have:
        raise UsageError(f"the sweep has {n_scenes} scenes; planning them needs about "
                         f"{size(need)} of memory and {size(have)} is available: split it into "
                         "smaller sweeps (fewer values per axis), or run it on a larger machine")
    if progress is not None and n_scenes >= PLANNING_NOTE:
        print(f"planning {n_scenes} scenes (about {size(need)} of memory)...", file=progress,
              flush=True)


def _master_solve(sweep, progress) -> MasterSolve:
    """Build the master curve once, here, before the workers start (solver/master.py)."""
    from solver.master import MasterCurve

    t = time.monotonic()
    curve = MasterCurve.build(sweep.accuracy, **sweep.overrides)
    if progress is not None:
        print(f"fast path: master curve of {len(curve.s)} coupled solves in "
              f"{time.monotonic() - t:.1f} s", file=progress, flush=True)
    return MasterSolve(curve)


class _Warm:
    """Picklable warm-up call (run on every worker by ``runners.WorkerSetup``)."""

    def __init__(self, accuracy, overrides, scenes=()):
        self.accuracy, self.overrides, self.scenes = accuracy, overrides, list(scenes)

    def __call__(self):
        return warm(self.accuracy, self.overrides, self.scenes)


def _count(summary: Summary, st, cells) -> None:
    index = tuple(np.array(cells, dtype=int).reshape(len(cells), -1).T)
    status = st.ds["status"].values[index]
    model = st.ds["model"].values[index]
    messages = st.ds["message"].values[index]
    summary.done = int(np.sum(status == STATUS_CODES["ok"]))
    summary.failed = int(np.sum(status >= 2))
    summary.premise_failed = int(np.sum(status == STATUS_CODES["start_deformed"]))
    summary.not_run = int(np.sum(status == 0))
    summary.rigid = int(np.sum((status == STATUS_CODES["ok"]) & (model == MODEL_CODES["rigid"])))
    for k in np.nonzero(status >= 2)[0][:20]:
        summary.failures.append((st.scene(cells[k]), _CODE_NAMES.get(int(status[k]), "?"),
                                 str(messages[k])))
