"""``ehd sweep``, ``ehd status``, ``ehd figures`` (registered by ``pipeline.cli``).

Exit codes (``pipeline/errors.py``): 0 success; 2 bad input (sweep file, unusable path, store of
another solver version/numerics/sweep file, busy store, unreachable scheduler), one line on
stderr, nothing computed; 3 the sweep finished but failed scenes remain in it (stored with status
and message; rerun them with ``--retry-failed``); 4 the scheduler went away mid-sweep (finished
scenes kept); 5 ``status``/``figures``: the store is damaged (the cells are listed; ``ehd sweep``
recomputes them; ``sweep``: metadata it cannot repair); 74 a write failed (a full disk: the path
and the free space, nothing partial left; stdout closed or full); 130 interrupted, 143 terminated
(SIGTERM; everything finished so far is kept).
"""

from __future__ import annotations

import math

__all__ = ["register", "cmd_sweep", "cmd_status", "cmd_figures"]


def _positive_int(text: str) -> int:
    import argparse

    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got {text!r}")
    return n


def register(sub) -> None:
    p = sub.add_parser(
        "sweep", help="compute a sweep (grid over Physics fields) into its zarr store (cached, resumable)",
        description="Compute every scene of a sweep file that its store lacks. Exit codes: 0 all "
                    "scenes ok, 2 bad input, 3 finished with failed scenes, 4 scheduler lost "
                    "mid-sweep, 5 damaged metadata the sweep cannot repair, 74 a write failed "
                    "(disk full), 130 interrupted, 143 terminated (SIGTERM).")
    p.add_argument("sweep_file", metavar="SWEEP_FILE",
                   help="sweep definition, e.g. sweeps/paper.toml, or the name of a shipped one: "
                        "paper, quick, cavitation, piezoviscous")
    p.add_argument("--store", metavar="PATH", default=None,
                   help="zarr store to use instead of the one named in the sweep file")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDRESS", default=None,
                       help="run on an existing dask scheduler, e.g. tcp://10.0.0.1:8786")
    where.add_argument("--scheduler-file", metavar="FILE", default=None,
                       help="run on the dask scheduler described by FILE (dask scheduler "
                            "--scheduler-file FILE)")
    where.add_argument("--executor", choices=("auto", "threads", "processes", "serial"),
                       default=None,
                       help="local executor: threads (one per core in this process), processes "
                            "(a dask LocalCluster, one worker process per core: a crash of one "
                            "is a failed scene, not the end of the sweep; 3-5 s of CPU each to "
                            "start), serial; default auto: threads below 2000 scenes to "
                            "compute, processes from there")
    p.add_argument("--workers", metavar="N", type=_positive_int, default=None,
                   help="local workers (default: all usable cores); with --scheduler/"
                        "--scheduler-file: wait for N workers before starting")
    p.add_argument("--wait-workers", metavar="SECONDS", type=float, default=None,
                   help="with --scheduler/--scheduler-file and --workers N: give up (exit 2) when "
                        "N workers are not connected after SECONDS (default 60)")
    p.add_argument("--connect-timeout", metavar="SECONDS", type=float, default=None,
                   help="with --scheduler/--scheduler-file: give up (exit 2) when the scheduler "
                        "does not answer within SECONDS (default 30)")
    p.add_argument("--allow-large", action="store_true",
                   help="run a grid of more than 10^6 scenes (refused otherwise, before anything "
                        "is allocated)")
    p.add_argument("--add-sweep", action="store_true",
                   help="write this sweep file into a store that another sweep file wrote "
                        "(recorded in the store's 'sweeps' attr)")
    p.add_argument("--retry-failed", action="store_true",
                   help="rerun the scenes stored as failed (by default they are kept as they are)")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("status", help="what a sweep store holds: done, failed, missing, damaged "
                                       "(exit 5 when damaged)")
    p.add_argument("store", metavar="STORE", help="sweep store, e.g. results/paper.zarr")
    p.set_defaults(func=cmd_status)

    p = sub.add_parser("figures", help="Figures 12-14, (St, eps) maps and stick/rebound from a "
                                        "sweep store (one set per value of its other axes) (never computes scenes; skipped when the "
                                        "folder is up to date with the store)")
    p.add_argument("store", metavar="STORE", help="sweep store, e.g. results/paper.zarr")
    p.add_argument("--out", metavar="DIR", default="figures", help="output folder (default figures)")
    p.set_defaults(func=cmd_figures)


def _check_inert_options(args) -> None:
    """UsageError for an option that would do nothing (ignored before: a hostile scan)."""
    from ..errors import UsageError

    if args.executor == "serial" and args.workers is not None:
        raise UsageError("--workers with --executor serial: a serial sweep runs in this process "
                         "alone; drop --workers, or choose --executor threads or processes")
    remote = args.scheduler is not None or args.scheduler_file is not None
    for flag, value in (("--wait-workers", args.wait_workers),
                        ("--connect-timeout", args.connect_timeout)):
        if value is not None and not remote:
            raise UsageError(f"{flag} acts only with --scheduler or --scheduler-file (a running "
                             "dask scheduler); drop it for a local sweep")


def cmd_sweep(args) -> int:
    from ..shipped import resolve_sweep
    from .config import load_sweep
    from .run import run_sweep
    from .runners import DEFAULT_RUNNER

    _check_inert_options(args)
    sweep = load_sweep(resolve_sweep(args.sweep_file))  # ConfigError: one line, exit 2 (pipeline/errors.py)
    summary = run_sweep(sweep, store=args.store, runner=args.executor or DEFAULT_RUNNER,
                        workers=args.workers, address=args.scheduler,
                        scheduler_file=args.scheduler_file, retry_failed=args.retry_failed,
                        wait_workers=args.wait_workers, add_sweep=args.add_sweep,
                        connect_seconds=args.connect_timeout, allow_large=args.allow_large)
    print(summary.text())
    return summary.exit_code


def _open_checked(store: str):
    """``(dataset, damage, journal lines skipped)`` of the store at ``store``, read whole and
    checked (pipeline/sweeps/integrity.py); a missing or unreadable store is a one-line error
    (exit 2), metadata that cannot be trusted one line too (exit 5)."""
    from ..errors import PathError
    from .integrity import load_checked
    from .journal import _journal_path, read_journal

    if not str(store).strip():
        raise PathError("STORE: empty path; give a store directory such as results/paper.zarr")
    ds, damage = opening_store(store, load_checked)
    _, skipped = read_journal(_journal_path(store))
    return ds, damage, skipped


def opening_store(store: str, open_fn,
                  fix: str = "give the store a sweep wrote (its sweep file's store)"):
    """``open_fn(store)`` with its failures as one line (exit 2): a missing store or a folder
    that is none says so, with ``fix``; any other unreadable one "cannot be opened as an ehd
    sweep store"; an ``EhdError`` (a damaged store: exit 5) passes unchanged."""
    from ..errors import EhdError, UsageError
    from .store import named_store

    try:
        return open_fn(str(named_store(store)))  # '.' inside a store: the store by its name
    except EhdError:
        raise
    except FileNotFoundError as exc:
        raise UsageError(f"{exc}; {fix}") from None
    except (ValueError, KeyError, OSError) as exc:
        raise UsageError(f"{store!r} cannot be opened as an ehd sweep store "
                         f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
                         ) from None


def cmd_status(args) -> int:
    import sys

    import numpy as np

    from solver.physics import Physics

    from ..errors import EXIT_DAMAGED
    from .analysis import PlaneError, planes
    from .journal import pending_journal
    from .layout import MODEL_CODES, STATUS_CODES
    from .config import format_physics

    ds, damage, skipped = _open_checked(args.store)
    fixed = ds.attrs.get("fixed_physics") or {}
    damage_text = damage.describe(ds, fixed, limit=20) if damage else ""
    for cell in damage.cells:  # never counted or tabulated as data
        ds["status"].values[cell] = 0
    status = ds["status"].values
    model = ds["model"].values
    ok = status == STATUS_CODES["ok"]
    rigid = MODEL_CODES["rigid"]
    a = ds.attrs
    print(f"store {args.store}: sweep {a.get('sweep_name')!r}, solver {a.get('solver_version')}, "
          f"accuracy {a.get('accuracy')}, cache key {str(a.get('cache_key'))[:12]}, "
          f"created {a.get('created')}")
    dims = ds["status"].dims
    grid = " x ".join(f"{ds.sizes[d]} {d} in [{ds[d].values.min():.4g}, {ds[d].values.max():.4g}]"
                      for d in dims)
    fixed = a.get("fixed_physics") or {}
    print(f"grid: {grid} = {status.size} scenes"
          + (f"; fixed {format_physics(fixed)}" if fixed else ""))
    names = {v: k for k, v in STATUS_CODES.items()}
    failed = status >= 2
    print(f"  done      {int(ok.sum()):6d}   (rigid-only {int((ok & (model == rigid)).sum())}, "
          f"escaped {int(np.nansum(ds['escaped'].values[ok]))})")
    by_code = ", ".join(f"{names[c]} {int((status == c).sum())}" for c in sorted(set(status[failed])))
    print(f"  failed    {int(failed.sum()):6d}" + (f"   ({by_code})" if by_code else ""))
    print(f"  not run   {int((status == 0).sum()):6d}")
    pending = pending_journal(args.store)
    if pending:
        print(f"  journal   {pending:6d}   finished scenes not yet in the store (a running "
              "sweep merges them within seconds; after an interrupted one, the next ehd sweep)")
    if skipped:
        print(f"  journal   {skipped:6d}   bad lines skipped (their scenes run again)")
    if len(damage):
        print(f"  damaged   {len(damage):6d}   counted as not run above; the next ehd sweep "
              "computes them again")
    for coord, how in sorted(damage.coords.items()):
        print(f"  damaged   coordinate {coord} ({how}): shown from the store's copy; the next ehd "
              "sweep rewrites it")
    try:
        for extra, plane in planes(ds):
            _status_table(plane, extra, format_physics)
    except PlaneError as exc:
        print(f"  (no St_c table: {exc})")
    cells = np.argwhere(failed)
    for cell in cells[:20]:
        physics = {**fixed, **{d: float(ds[d].values[i]) for d, i in zip(dims, cell)}}
        physics = {n: physics[n] for n in Physics.names() if n in physics}  # as ehd sweep's
        print(f"  failed: {format_physics(physics)} {names[int(status[tuple(cell)])]}: "
              f"{ds['message'].values[tuple(cell)]}")
    if len(cells) > 20:
        print(f"  ... {len(cells) - 20} more failed scenes")
    if damage:
        print(f"ehd status: error: store {args.store} is damaged: {damage_text}; run its sweep "
              "again (ehd sweep SWEEP_FILE) to repair it (damaged cells are computed again)",
              file=sys.stderr)
        return EXIT_DAMAGED
    return 0


def _status_table(plane, extra: dict, format_physics) -> None:
    """Counts and St_c per eps row of one (eps, St) plane."""
    from .analysis import critical_stokes_plane
    from .layout import MODEL_CODES

    rows = critical_stokes_plane(plane, extra)
    rigid = MODEL_CODES["rigid"]
    status = plane["status"].values
    model = plane["model"].values
    ok = status == 1
    failed = status >= 2
    if extra:
        print(f"  {format_physics(extra)}:")
    print(f"  {'eps':>8} {'ok':>5} {'failed':>6} {'not run':>7} {'rigid':>5}  St_c")
    for i, (e, r) in enumerate(zip(plane["eps"].values, rows)):
        st_c = f"{r['St_c']:.4g}" if math.isfinite(r["St_c"]) else (r["note"] or "-")
        print(f"  {e:8.2g} {int(ok[i].sum()):5d} {int(failed[i].sum()):6d} "
              f"{int((status[i] == 0).sum()):7d} {int((ok[i] & (model[i] == rigid)).sum()):5d}  {st_c}")


def cmd_figures(args) -> int:
    from ..cli import check_output_dir
    from ..plots.stamp import store_state, up_to_date

    check_output_dir("--out", args.out)
    if up_to_date(args.store, args.out):  # the store's files unchanged since the last render
        print(f"figures in {args.out} are up to date with {args.store}")
        return 0
    # the file state the stamp records, taken before the read: a sweep writing the store after
    # it changes the state, and the next ehd figures reads the store again (stamp.py)
    state = store_state(args.store)
    from ..errors import StoreDamaged, UsageError
    from ..plots.sweep_maps import update_figures
    from ..writes import guarded_dir
    from .analysis import PlaneError
    from .layout import STATUS_CODES

    checked, damage, _skipped = _open_checked(args.store)
    if damage:
        raise StoreDamaged(f"store {args.store} is damaged: "
                           f"{damage.describe(checked, checked.attrs.get('fixed_physics') or {})}; no "
                           "figures drawn from it: run its sweep again (ehd sweep SWEEP_FILE) to "
                           "repair it (damaged cells are computed again)")
    if not (checked["status"].values == STATUS_CODES["ok"]).any():
        failed = int((checked["status"].values >= 2).sum())
        if failed:  # it ran: every scene failed (ehd status lists them with their reasons)
            raise UsageError(f"store {args.store} holds no scene that finished ok (all {failed} "
                             "that ran failed): nothing to draw; ehd status lists them with "
                             "their reasons")
        raise UsageError(f"store {args.store} holds no finished scene yet: nothing to draw; run "
                         "its sweep first (ehd sweep SWEEP_FILE)")
    try:  # the store as read and checked above: one read per command
        with guarded_dir(args.out, f"--out {args.out}"):
            paths, rendered = update_figures(checked, args.out, state=state)
    except PlaneError as exc:
        raise UsageError(f"no figures for {args.store}: {exc}") from None
    if not rendered:
        print(f"figures in {args.out} are up to date with {args.store}")
    else:
        for path in paths:
            print(path)
    return 0
