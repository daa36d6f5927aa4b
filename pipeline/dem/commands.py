"""``ehd export-dem STORE_OR_SCENE`` and ``ehd restitution SCENE`` (registered through
``pipeline.cli.COMMAND_MODULES``).

- ``export-dem``: from a sweep store (``.zarr``: every ok scene, grouped by eps) or a scene file
  (solved along its impact speed, ``v0`` times 0.1 to 10), write ``restitution.csv``,
  ``restitution.json`` and the LIGGGHTS, OpenFOAM and YADE snippets into ``--out``; ``--for``
  picks the e the laws realise (``conventions.DEM_KINDS``), ``--allow-invalid`` exports rows
  that all fail the validity checks, ``--fit-range`` (a scene) solves check scenes between the
  rows.
- ``restitution``: e(St) of a scene file along a path in impact speed or size (eps moves with
  both), printed as a table; ``--out`` writes the same export.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["register", "solve_path"]


def solve_path(scene, vary: str, factors, accuracy: str = "standard", progress=None,
               ranges: bool = False):
    """Solve the scenes along a path (export.scene_path); scenes the solver refuses are skipped
    with their reason, and so are scenes whose outer flow stops the spheres before ``x0`` (they
    stick). ``progress``: called with a line per scene once the path has taken more than 2 s.
    ``ranges``: each scene's ranges too (``run_scene``). Returns ``(results, skipped, at)``:
    ``at`` has an entry per factor, its result, None (stopped before ``x0``: sticks) or the
    reason it was skipped (``threshold.sticking_threshold``'s ``results``)."""
    import time

    from pipeline.scenes.run import run_scene
    from pipeline.scenes.scene import SceneError

    from .export import scene_path

    skipped, at = [], []
    path = scene_path(scene, vary, factors)
    t0 = time.perf_counter()
    for k, (factor, s) in enumerate(zip(factors, path)):
        if s.stops_outside:  # no film collision: the outer flow stops them (they stick)
            skipped.append(f"{vary} x {factor:.3g}: sticks, the outer flow stops the spheres "
                           "before x0")
            at.append(None)
            continue
        try:
            at.append(run_scene(s, accuracy=accuracy, save_profiles=False,
                                sensitivity_solves=False, ranges=ranges))
        except SceneError as exc:
            skipped.append(f"{vary} x {factor:.3g}: {exc}")
            at.append(str(exc))
        elapsed = time.perf_counter() - t0
        if progress and elapsed > 2.0:
            progress(f"{vary} x {factor:.3g} solved ({k + 1}/{len(path)}), {elapsed:.1f} s")
    results = [a for a in at if a is not None and not isinstance(a, str)]
    return results, skipped, at


# the most points a path takes (``--n`` of restitution and export-dem): each is a solve, from
# 0.05 s to seconds; 10^10 raised numpy's memory error (exit 70) before the first
MAX_POINTS = 10000


def _check_points(n) -> None:
    from pipeline.cli import UsageError

    if not 1 <= n <= MAX_POINTS:
        raise UsageError(f"--n {n}: give a whole number of points from 1 to {MAX_POINTS} (each "
                         "is a solve)")


def _scene(path, materials):
    from pipeline.cli import UsageError
    from pipeline.scenes.commands import load_scene

    try:
        return load_scene(path, None, materials or ())
    except (ValueError, OSError) as exc:
        raise UsageError(str(exc)) from None


def _cell(v):
    return "-" if v == "" else f"{v:.4f}"


def _print_rows(rows, skipped):
    print(f"{'St':>10} {'St_L':>10} {'eps':>10} {'v0 [m/s]':>10} {'V [m/s]':>10} {'e_wet':>8} "
          f"{'e_far':>8}  note")
    # a scene switches its pieces (the floor, asperity contact) on where they act, so the
    # physics can change along a path, and e with it: the first row and each change say which
    changes = len({r["physics"] for r in rows}) > 1
    before = None
    for r in rows:
        # as ehd scene's verdict, whose first e is e_far: sticking there alone is a dry DEM
        # code's (the CSV's sticks column stays e_wet's)
        far = r["e_far"]
        verdict = "sticks" if r["sticks"] else \
            "sticks in e_far (dry DEM)" if far != "" and far == 0.0 else ""
        physics = f"physics: {r['physics']}" if changes and r["physics"] != before else ""
        before = r["physics"]
        # a premise failure keeps its numbers (solver/collision.py) but is no ordinary row
        premise = "start_deformed: the model's premise fails here (status in the CSV)" \
            if r["status"] == "start_deformed" else ""
        note = "; ".join(part for part in (physics, premise, verdict) if part)
        if r["warning_checks"]:
            note = (note + "; " if note else "") + "warnings: " + r["warning_checks"] + " (see CSV)"
        approach = "-" if r["approach_speed_m_s"] == "" else f"{r['approach_speed_m_s']:.4g}"
        print(f"{r['St']:>10.4g} {r['St_L']:>10.4g} {r['eps']:>10.3g} {r['v0_m_s']:>10.4g} "
              f"{approach:>10} {r['e_wet']:>8.4f} {_cell(r['e_far']):>8}  {note}")
    for s in skipped:
        print(f"skipped: {s}")


def check_rows(rows, kind: str, source: str) -> None:
    """UsageError unless every finished row has the e ``--for kind`` realises."""
    from pipeline.cli import UsageError

    from .conventions import DEM_KINDS
    from .export import missing_e

    missing = missing_e(rows, kind)
    if not missing:
        return
    col = DEM_KINDS[kind].e_column
    raise UsageError(f"{source}: --for {kind} realises {col}, but {len(missing)} of {len(rows)} "
                     f"rows have no {col}; export the resolved CFD-DEM e_wet with --for cfd-dem")


def check_rows_between(scene, rows, fit_range, accuracy, progress):
    """Rows of scenes solved at the ends of ``fit_range`` (our St) and halfway (geometric)
    between the path's rows inside it (``export.check_stokes``): the law is checked there,
    never fitted (role "check"). Returns ``(rows, skipped)``."""
    from .export import check_stokes, scene_rows

    factors = [x / scene.stokes for x in check_stokes([r["St"] for r in rows], *fit_range)]
    if not factors:
        return [], []
    results, skipped, _ = solve_path(scene, "v0", factors, accuracy, progress=progress)
    return scene_rows(results, rows[0]["group"], role="check"), skipped


def store_check_rows(ds, rows, fit_range, density_ratio, progress):
    """As ``check_rows_between`` for a store: each group's check scenes solved with the store's
    physics and numerics (``pipeline.sweeps.tasks.solve_scene``, the solver a sweep runs; a
    fast-path store's rows came from its master curve, within its measured error of this).
    Returns ``(rows, skipped)``."""
    from dataclasses import fields

    from pipeline.sweeps.config import physics_from_json
    from pipeline.sweeps.tasks import solve_scene
    from solver.settings import Numerics

    from .export import check_stokes, store_groups, store_row

    names = {f.name for f in fields(Numerics)} - {"save_profiles"}
    numerics = {k: v for k, v in dict(ds.attrs.get("numerics", {})).items() if k in names}
    accuracy = ds.attrs.get("accuracy", "standard")
    out, skipped = [], []
    for label, raw, _ in store_groups(ds):
        physics = physics_from_json(raw)
        for eps in ds["eps"].values:
            group = [r for r in rows if r["group"] == f"eps={float(eps):.3g}{label}"]
            for st in check_stokes([r["St"] for r in group], *fit_range) if group else ():
                rec = solve_scene({**physics, "St": st, "eps": float(eps)}, accuracy, numerics)
                if rec["status"] != "ok":
                    skipped.append(f"St {st:.4g} eps {float(eps):.3g}{label}: {rec['message']}")
                    continue
                out.append(store_row(st, float(eps), label, raw, rec,
                                     ds.attrs.get("solver_version", ""), density_ratio, "check"))
                if progress:
                    progress(f"check scene St {st:.4g} eps {float(eps):.3g}{label} solved")
    return out, skipped


def _fit_range(args):
    from pipeline.cli import UsageError

    if args.fit_range is None:
        return None
    lo, hi = args.fit_range
    if not (0.0 <= lo < hi < np.inf):
        raise UsageError(f"--fit-range {lo:g} {hi:g}: give 0 <= LO < HI, both finite (our St)")
    return (lo, hi)


def _check_density_ratio(value: float) -> None:
    """UsageError unless ``--density-ratio`` is a ratio the far-field reading takes
    (``solver.far_field.OuterFlow``: finite, in [0, 1e6]; 1e300 overflowed the fits)."""
    from pipeline.cli import UsageError
    from solver.far_field import OuterFlow

    try:
        OuterFlow(density_ratio=value)
    except ValueError as exc:
        raise UsageError(f"--density-ratio {value:g}: {exc}") from None


def _num(v) -> float:
    return math.nan if v == "" else float(v)


def _check_kind(args) -> bool:
    """``--for``: one of ``DEM_KINDS``, ``dry`` where it is left out (``args.kind`` set so);
    returns whether it was given."""
    from pipeline.cli import UsageError

    from .conventions import DEM_KINDS

    given, args.kind = args.kind is not None, args.kind or "dry"
    if args.kind not in DEM_KINDS:
        raise UsageError(f"--for {args.kind!r}: give one of {', '.join(DEM_KINDS)} (dry: "
                         "LIGGGHTS or YADE without fluid coupling; cfd-dem: resolved CFD-DEM)")
    return given


def _check_input_flags(args, store: bool) -> None:
    """``--n`` (a scene file's speeds) and ``--density-ratio`` (a store's) checked, their defaults
    set; each refused with the other kind of input, where it would do nothing."""
    from pipeline.cli import UsageError

    if store and args.n is not None:
        raise UsageError(f"--n acts on a scene file's speeds; {args.path} is a store, whose "
                         "scenes are its rows: drop --n")
    if not store and args.density_ratio is not None:
        raise UsageError(f"--density-ratio acts on a store (a scene file has its densities); "
                         f"drop it for {args.path}")
    args.density_ratio = 0.0 if args.density_ratio is None else args.density_ratio
    args.n = 13 if args.n is None else args.n
    _check_density_ratio(args.density_ratio)
    _check_points(args.n)


def cmd_export_dem(args) -> int:
    from pipeline.cli import UsageError, check_output_dir
    from pipeline.cli_shared import check_accuracy

    from .conventions import DEM_KINDS
    from .export import (EXPORT_FILES, InvalidExport, export_files, progress_to_stderr,
                         scene_rows, write_files)

    _progress = progress_to_stderr("export-dem")

    check_output_dir("--out", args.out, EXPORT_FILES)  # before any solve
    check_accuracy(args.accuracy)
    fit_range = _fit_range(args)
    _check_kind(args)
    if not args.path.strip():
        raise UsageError("STORE_OR_SCENE: empty path; give a sweep store (.zarr) or a scene file")
    path = Path(args.path)
    if not path.exists():
        raise UsageError(f"{args.path}: no such store or scene file")
    _check_input_flags(args, path.is_dir())
    if path.is_dir():
        rows = _store_rows(args, path, fit_range, _progress)
    else:
        scene = _scene(str(path), args.materials)
        factors = np.geomspace(0.1, 10.0, args.n)
        results, skipped, _ = solve_path(scene, "v0", factors, args.accuracy,
                                         progress=_progress)
        rows = scene_rows(results, f"{scene.body1.solid.name}-{scene.body2.solid.name} in "
                                   f"{scene.fluid.name}")
        if not rows:
            for s in skipped:
                print(f"skipped: {s}")
            raise UsageError(f"{args.path}: the solver refused every speed of the path "
                             "(skipped lines above); change the scene")
        check_rows(rows, args.kind, args.path)  # before the solves between the rows
        if fit_range:
            extra, more = check_rows_between(scene, rows, fit_range, args.accuracy, _progress)
            rows, skipped = sorted(rows + extra, key=lambda r: r["St"]), skipped + more
        for s in skipped:
            print(f"skipped: {s}")
    check_rows(rows, args.kind, args.path)
    col = DEM_KINDS[args.kind].e_column
    if not any(_num(r[col]) > 0.0 for r in rows):
        raise UsageError(f"{args.path}: no collision rebounds (every {col} is 0): nothing to fit; "
                         "export a store or scene that reaches higher St")
    try:
        files = export_files(rows, str(path), fit_range=fit_range,
                             density_ratio=args.density_ratio, progress=_progress,
                             kind=args.kind, allow_invalid=args.allow_invalid)
    except InvalidExport as exc:
        raise UsageError(f"{args.path}: {exc}; nothing written: change the scene, or export "
                         "anyway with --allow-invalid (every file then says so)") from None
    if not any(name.startswith("liggghts_") for name in files):
        more = "a sweep over more or higher St" if path.is_dir() else "more points (--n)"
        raise UsageError(f"{args.path}: no group has 3 rebounding collisions"
                         + (" in --fit-range" if fit_range else "") + ": nothing to fit; "
                         f"export {more}")
    paths, removed = write_files(files, args.out)
    print(f"wrote {len(rows)} rows: " + ", ".join(str(p) for p in paths))
    _print_removed(removed)
    return 0


def _store_rows(args, path: Path, fit_range, progress) -> list:
    """The rows of the export of the sweep store at ``path``: its finished scenes (refused in
    one line when there are none or the store lacks St, eps or e_wet) and, with ``fit_range``,
    the checks between them; one line on stderr when finished scenes still wait in its journal
    (they are not in the export), not ``open_results``' Python warning with its file and line
    (a hostile review)."""
    import sys
    import warnings

    from pipeline import open_results
    from pipeline.cli import UsageError
    from pipeline.sweeps.commands import opening_store
    from pipeline.sweeps.journal import _journal_path, pending_journal
    from pipeline.sweeps.store import UnmergedScenes

    from .export import store_rows

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnmergedScenes)  # said below, in one line
        ds = opening_store(str(path), open_results, "export-dem takes a sweep store or a "
                           "scene file")
    pending = pending_journal(path)
    if "St" not in ds.dims or "eps" not in ds.dims:
        raise UsageError(f"{args.path}: export-dem needs a store with St and eps axes")
    if "e_wet" not in ds:
        raise UsageError(f"{args.path}: the store has no e_wet (made before solver 1.4.0); "
                         "rerun the sweep")
    rows = store_rows(ds, args.density_ratio)
    waiting = f"{pending} finished scene{'s' if pending != 1 else ''}"
    if not rows:
        waiting = f" (its journal holds {waiting})" if pending else ""
        raise UsageError(f"{args.path}: no finished (ok) scene in the store{waiting}; run "
                         "ehd sweep on it first (ehd status shows what is done)")
    if pending:
        print(f"ehd export-dem: note: {_journal_path(path)} holds {waiting} of an interrupted "
              "sweep, not yet in the store and not in this export; run the sweep again to "
              "merge them", file=sys.stderr)
    check_rows(rows, args.kind, args.path)  # before the solves between the rows
    if fit_range:
        extra, skipped = store_check_rows(ds, rows, fit_range, args.density_ratio, progress)
        rows = sorted(rows + extra, key=lambda r: (r["group"], r["St"]))
        for s in skipped:
            print(f"skipped: {s}")
    return rows


def _print_removed(removed) -> None:
    if removed:
        print("removed an earlier export's snippets, whose laws this CSV no longer holds: "
              + ", ".join(str(p) for p in removed))


def _check_path_flags(args, kind_given: bool) -> None:
    """UsageError for ``ehd restitution`` flags that would do nothing (``--for``, even ``--for
    dry``, or ``--allow-invalid`` without ``--out``, a point repeated, a range of one point) or
    whose path has no factors (not finite positive, or an impossible ``--n``)."""
    from pipeline.cli import UsageError

    inert = [f for f, on in (("--for " + args.kind, kind_given),
                             ("--allow-invalid", args.allow_invalid)) if on]
    if inert and not args.out:  # they choose what the export writes: without one, nothing
        raise UsageError(f"{' and '.join(inert)} choose{'s' if len(inert) == 1 else ''} what "
                         "the DEM export writes: give --out DIR too, or leave "
                         f"{' and '.join(f.split()[0] for f in inert)} out")
    if not (0 < args.start < np.inf and 0 < args.stop < np.inf):
        raise UsageError("--from and --to must be finite positive factors")
    _check_points(args.n)
    if (args.n == 1) != (args.start == args.stop):  # one point is one factor, and back
        raise UsageError(f"--from {args.start:g} --to {args.stop:g} --n {args.n}: " + (
            "one point takes one factor: give --from equal to --to, or --n 2 or more"
            if args.n == 1 else
            "every point would be the same scene: give --to another factor, or --n 1"))


def cmd_restitution(args) -> int:
    from pipeline.cli import UsageError, check_output_dir
    from pipeline.cli_shared import check_accuracy

    from .export import EXPORT_FILES, progress_to_stderr, scene_path, scene_rows, write_export

    _progress = progress_to_stderr("restitution")

    from pipeline.plots import RESTITUTION_FIGURE, figure_files

    check_output_dir("--out", args.out, EXPORT_FILES)  # before any solve
    check_output_dir("--plot", args.plot, figure_files((RESTITUTION_FIGURE,)))
    if args.range and not args.plot:
        raise UsageError("--range draws each e's range as a band on the figure: give --plot DIR "
                         "too")
    check_accuracy(args.accuracy)
    _check_path_flags(args, _check_kind(args))
    scene = _scene(args.scene, args.materials)
    factors = np.geomspace(args.start, args.stop, args.n)
    try:
        scene_path(scene, args.vary, factors[:1])  # a path the scene has (approach: an outer flow)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    results, skipped, at = solve_path(scene, args.vary, factors, args.accuracy,
                                      progress=_progress, ranges=args.range)
    rows = scene_rows(results, f"{scene.body1.solid.name}-{scene.body2.solid.name} in "
                               f"{scene.fluid.name}, {args.vary} path")
    _print_rows(rows, skipped)
    if all(isinstance(a, str) for a in at):  # as export-dem: nothing to show, fit or bisect
        raise UsageError(f"{args.scene}: the solver refused every point of the path (skipped "
                         "lines above); change the scene or --from/--to")
    if not rows and (args.plot or args.out):  # every point stopped before x0: nothing to draw
        raise UsageError(f"{args.scene}: every point of the path sticks before x0 (skipped lines "
                         "above): no collision to draw or export; move --from/--to up")
    thresholds = []
    if args.threshold:
        from pipeline.scenes.threshold import format_threshold, sticking_threshold

        # in the e of each kind of code: dry DEM (e_far) and resolved CFD-DEM (e_wet)
        for key in ("e_far", "e_wet"):
            thresholds.append(sticking_threshold(scene, args.vary, args.accuracy,
                                                 start=args.start, stop=args.stop, n=args.n,
                                                 results=at, key=key))
            print(format_threshold(thresholds[-1]))
    if args.plot:
        from pipeline.plots.restitution_plot import plot_restitution
        from pipeline.writes import guarded_dir

        with guarded_dir(args.plot, f"--plot {args.plot}"):  # both files or neither
            paths = plot_restitution(results, args.vary, args.plot, thresholds=thresholds,
                                     title=scene.title)
        print("figure: " + ", ".join(str(p) for p in paths))
    if args.out:
        from .export import InvalidExport

        check_rows(rows, args.kind, args.scene)
        try:
            paths, removed = write_export(rows, args.out, args.scene, progress=_progress,
                                          kind=args.kind, allow_invalid=args.allow_invalid)
        except InvalidExport as exc:
            raise UsageError(f"{args.scene}: {exc}; --out not written: change the scene, or "
                             "export anyway with --allow-invalid") from None
        print("wrote " + ", ".join(str(p) for p in paths))
        _print_removed(removed)
    failed = [t for t in thresholds if t.failed]
    if failed:  # the rest is written; the threshold is not
        from pipeline.errors import EXIT_SCENE_FAILED, EhdError

        raise EhdError(f"no sticking threshold in {failed[0].key}: {failed[0].note}",
                       EXIT_SCENE_FAILED)
    return 0


def register(sub) -> None:
    p = sub.add_parser("export-dem", help="restitution laws for DEM codes (--for dry: e_far; "
                                          "cfd-dem: e_wet): CSV, fits, LIGGGHTS / OpenFOAM / "
                                          "YADE settings")
    p.add_argument("path", metavar="STORE_OR_SCENE", help="a sweep store (.zarr) or a scene file")
    p.add_argument("--out", default="dem_export", help="output folder (default dem_export)")
    p.add_argument("--density-ratio", type=float, default=None,
                   help="stores only: rho_f/rho_p for Legendre's St_L (default 0)")
    p.add_argument("--n", type=int, default=None,
                   help="scenes only: speeds, log-spaced from 0.1 to 10 v0 (default 13)")
    p.add_argument("--fit-range", nargs=2, type=float, default=None, metavar=("LO", "HI"),
                   help="fit and calibrate only on rows with LO <= St <= HI (our St, at v0: where "
                        "your collisions are); a scene also solves scenes at LO, HI and halfway "
                        "between its rows there, to state the law's error over the whole range "
                        "(never fitted on); errors are still reported on every row")
    _add_export_flags(p)
    _add_solve_flags(p)
    p.set_defaults(func=cmd_export_dem)

    p = sub.add_parser("restitution", help="e(St) of a scene along a path in impact speed or size")
    p.add_argument("scene", help="scene file (TOML; see docs/scenes.md)")
    p.add_argument("--vary", choices=("v0", "approach_speed", "radius"), default="v0",
                   help="what moves along the path: the speed v0 at x0, the approach speed at "
                        "the outer start (the speed far out), or both radii (default v0)")
    p.add_argument("--from", dest="start", type=float, default=0.1,
                   help="first factor on v0 or the radii (default 0.1)")
    p.add_argument("--to", dest="stop", type=float, default=10.0, help="last factor (default 10)")
    p.add_argument("--n", type=int, default=9, help="points, log-spaced (default 9)")
    p.add_argument("--out", default=None, help="also write the DEM export into this folder: "
                   "the rows' CSV and JSON, the fitted laws and snippets where 3 rows rebound; "
                   "nothing where every row of a group fails a validity check, unless "
                   "--allow-invalid (--for and --allow-invalid as in export-dem)")
    p.add_argument("--plot", metavar="DIR", default=None,
                   help="write e against St and the path's v0 or radius, the sticking threshold "
                        "marked, as DIR/restitution.png and .pdf")
    p.add_argument("--threshold", action="store_true",
                   help="also find the sticking threshold St_c (and its speed or radius) by "
                        "bisection along the path, in the e of a dry DEM code (e_far) and of a "
                        "resolved CFD-DEM code (e_wet)")
    p.add_argument("--range", action="store_true",
                   help="with --plot: draw each e's range over what the scene does not know as "
                        "a band (each scene solved again at the ends of each unknown, as ehd "
                        "scene does: 2-6 more solves per point)")
    _add_export_flags(p)
    _add_solve_flags(p)
    p.set_defaults(func=cmd_restitution)


def _add_export_flags(p) -> None:
    """``--for`` and ``--allow-invalid``: which e the exported laws realise, and whether rows
    that all fail the validity checks may still be exported."""
    p.add_argument("--for", dest="kind", default=None, metavar="{dry,cfd-dem}",
                   help="the kind of DEM code: dry (default; LIGGGHTS or YADE without fluid "
                        "coupling) realises e_far, the whole loss the fluid causes, at the "
                        "approach speed at x_ref; cfd-dem (resolved CFD-DEM) realises e_wet at "
                        "v0")
    p.add_argument("--allow-invalid", action="store_true",
                   help="export even when every row of a group fails a validity check (e.g. "
                        "a film thinner than a gas's mean free path); every snippet and the "
                        "JSON then say so. Without it such an export is refused (exit 2)")


def _add_solve_flags(p) -> None:
    """The flags of the scenes' solves that export-dem and restitution share."""
    from ..cli_shared import accuracy_help

    p.add_argument("--accuracy", default="standard", help=accuracy_help("preset of the solves"))
    p.add_argument("--materials", action="append", default=None, metavar="FILE",
                   help="extra materials/fluids TOML file (repeatable; overrides shipped entries)")
