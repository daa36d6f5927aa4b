"""``ehd scene`` (a collision given in physical units) and ``ehd paper-figures`` (figures 2-11).

``ehd scene FILE.toml`` reads a scene file (format in docs/scenes.md); every field can also be
given, or overridden, by a flag (``--radius1 '50 um'``), declared with the key it fills in
``flags.py`` (the scene's own) and ``pieces.py`` (each piece's). Exit codes: 0 success, 1 the
solve failed (or, with ``--strict``, a validity check warned), 2 bad input.
"""

from __future__ import annotations

import json
import sys

from ..errors import EXIT_SCENE_FAILED
from .flags import GROUPS, SCENE_FLAGS, group_title
from .pieces import PIECES

__all__ = ["register", "cmd_scene", "cmd_paper_figures", "load_scene", "flag_values",
           "format_report", "result_rows"]

# every flag that fills a key of the scene file: the scene's own and each piece's (flags.py)
_SCENE_FLAGS = (*SCENE_FLAGS, *(flag for piece in PIECES for flag in piece.flags))
# flag dest -> (section or None for top level, key)
_FLAG_FIELDS = {dest: (section, key) for flag in _SCENE_FLAGS
                for _, dest, section, key in flag.options()}
# the scene's speed is v0 or approach_speed: one given by a flag replaces the other of the file
_ONE_SPEED = {"v0": "approach_speed", "approach_speed": "v0"}
# keys of which a scene gives one, in SI or over a: one given by a flag replaces the other of
# the file too ("every field has a flag of the same name, which overrides the file")
_ONE_OF = {**_ONE_SPEED, **{k: k + "_over_a" for k in ("x0", "outer_start", "x_ref")},
           **{k + "_over_a": k for k in ("x0", "outer_start", "x_ref")}}


def _e(value):
    return "-" if value is None else f"{value:.4f}"


def _usage_error(msg):
    from ..errors import UsageError

    return UsageError(msg)


def _read_scene_file(path: str) -> dict:
    from ..errors import UsageError
    from .materials import read_toml

    return read_toml(path, "scene file", UsageError)


def load_scene(path=None, flags: dict | None = None, materials=(), *, user_files=True):
    """Scene from a file and/or flag values (flags override the file).

    Parameters
    ----------
    path : str, optional
        TOML scene file.
    flags : dict, optional
        ``{flag dest: value}`` as in ``_FLAG_FIELDS`` (None values ignored); ``wall2=True``
        makes body2 a plane wall.
    materials : sequence of str
        Extra materials files (``--materials``).

    Returns
    -------
    pipeline.scenes.scene.Scene

    Raises
    ------
    ValueError
        With a message naming the field (SceneError, UnitError, MaterialError).
    """
    from .materials import load_table
    from .scene import SceneError
    from .scene_file import scene_from_dict

    if isinstance(materials, (str, bytes)) or hasattr(materials, "__fspath__"):
        materials = (materials,)  # one file, not its name's characters
    if path is not None and not str(path).strip():  # '' read as no file: "missing [body1]"
        raise SceneError("empty scene file path: give a scene file (TOML; see docs/scenes.md)")
    data = _read_scene_file(path) if path else {}
    given = [k for k in _ONE_SPEED if (flags or {}).get(k) not in (None, False)]
    if (flags or {}).get("wall2") and (flags or {}).get("radius2") is not None:
        raise SceneError("--wall and --radius2: a plane wall has no radius; give --wall for a "
                         "wall, or --radius2 for a sphere")
    if len(given) == 2:
        raise ValueError("give either --v0 (the speed at the film's start x0) or "
                         "--approach-speed (the speed at the outer start), not both")
    for dest, value in (flags or {}).items():
        if value is None or value is False:
            continue
        if dest == "wall2":
            body = data.setdefault("body2", {})
            body["wall"] = True
            body.pop("radius", None)
            continue
        if dest not in _FLAG_FIELDS:
            from ..errors import did_you_mean

            known = [*_FLAG_FIELDS, "wall2"]
            raise SceneError(f"unknown scene field {dest!r}{did_you_mean(dest, known)}; the "
                             f"fields: {', '.join(sorted(known))}")
        section, key = _FLAG_FIELDS[dest]
        if section is None and key in _ONE_OF:  # replaces the file's other form of it
            data.pop(_ONE_OF[key], None)
        target = data if section is None else data.setdefault(section, {})
        if not isinstance(target, dict):
            raise ValueError(f"{section} must be a table in the scene file")
        target[key] = value
    inline = {k: data.pop(k) for k in ("materials", "fluids") if k in data}
    table = load_table(materials, user_files=user_files,
                       inline=(inline, f"{path or 'scene'} (inline tables)") if inline else None)
    return scene_from_dict(data, table)


def _q(value, unit, spec=".4g"):
    """A value with a readable SI prefix, e.g. '25 µm'."""
    from .units import format_quantity

    return format_quantity(value, unit, spec)


def _g(value, spec=".4g"):
    from ..cli_shared import format_value

    return format_value(value, spec)


# a law's constants are report rows only where that law is used (the JSON has them all):
# Physics field -> (the piece's switch, the laws that use it)
_LAW_ROWS = {name: (piece.field, laws) for piece in PIECES
             for name, laws in piece.law_rows.items()}


def _physics_rows(d: dict) -> list[str]:
    """The Physics fields shown in the report: all, except the constants of a law not used."""
    from solver.physics import Physics

    return [name for name in Physics.names()
            if name not in _LAW_ROWS or d[_LAW_ROWS[name][0]] in _LAW_ROWS[name][1]]


def _shown(when: str, d: dict) -> bool:
    """``SceneKey.when`` against the scene's JSON: ``"key"`` true, ``"key!=value"`` not value."""
    if not when:
        return True
    key, _, off = when.partition("!=")
    return d[key] != off if off else bool(d[key])


def _si_text(value, key) -> str:
    """The value of ``key`` (a ``SceneKey``) for the report, in the unit its name ends with."""
    from solver.observables import si_unit

    if value is None:
        return key.null or "-"
    unit = "" if key.form == "log10" else si_unit(key.key)[0]
    if unit in ("m", "s", "N", "Pa", "m/s", "Pa*s"):  # with a readable prefix (25 µm)
        return _q(value, unit)
    return f"{_g(value)} {unit}".rstrip()


def result_rows(d: dict) -> list[tuple[str, str]]:
    """The report's result rows: every labelled ``SceneKey`` of the observable registry
    (solver/observables.py), in its order, where its ``when`` holds."""
    from .run import scene_keys

    return [(k.label, _si_text(d[k.key], k)) for _, k in scene_keys()
            if k.label and _shown(k.when, d)]


def format_report(d: dict) -> str:
    """Human-readable report of ``SceneResult.to_dict()``."""
    from .answer import answer_lines
    from .checks import per_gpa

    ins = d["inputs"]
    lines = []
    if d["title"]:
        lines.append(d["title"])
    lines += answer_lines(d)
    for label in ("body1", "body2"):
        b = ins[label]
        shape = "plane wall" if b["wall"] else f"sphere, radius {_q(b['radius_m'], 'm')}"
        extra = "" if b["yield_strength_Pa"] is None else f", yield {_q(b['yield_strength_Pa'], 'Pa')}"
        lines.append(f"  {label}: {shape}, {b['material']} (E = {_q(b['youngs_modulus_Pa'], 'Pa')}, "
                     f"nu = {b['poisson_ratio']:g}, rho = {_g(b['density_kg_per_m3'], 'g')} kg/m^3"
                     f"{extra})")
    f = ins["fluid"]
    alpha = f["pressure_viscosity_per_Pa"]
    alpha = "" if alpha is None else f", alpha = {per_gpa(alpha)}"
    lines.append(f"  fluid: {f['name']} (mu = {_q(f['viscosity_Pa_s'], 'Pa*s')}, "
                 f"rho = {f['density_kg_per_m3']:g} kg/m^3{alpha})")
    lines.append(f"  v0 = {_q(ins['v0_m_per_s'], 'm/s')}, x0 = {_q(d['x0_m'], 'm')} "
                 f"(x0/a = {d['x0_over_a']:.3g})")
    if d["inputs"]["v0_m_per_s"] == 0.0:  # run.stopped_result: no film collision
        lines.append(f"note: {d['message']}")
        return "\n".join(lines)
    rows = [
        ("reduced radius a", _q(d["reduced_radius_m"], "m")),
        ("reduced mass m", _q(d["reduced_mass_kg"], "kg")),
        ("theta", f"{d['theta_per_Pa']:.4g} 1/Pa (E* = {_q(d['effective_modulus_Pa'], 'Pa')})"),
        ("film scale x1", _q(d["x1_m"], "m")),
        *((name, _g(d[name])) for name in _physics_rows(d)),
        ("Re (Re x0/a)", f"{d['Re']:.4g} ({d['Re_x0_over_a']:.3g})"),
        ("(v0/c)^(1/5)", "-" if d["wave_parameter"] is None else
         f"{d['wave_parameter']:.3g} (c = {_q(d['sound_speed_m_per_s'], 'm/s')})"),
        ("e_far reads at x_ref", f"{_q(d['x_ref_m'], 'm')} = {d['x_ref_over_a']:.3g} a (exact "
         f"Stokes resistance, added mass at rho_f/rho_p = {_g(d['density_ratio'], '.3g')}; outer "
         f"start {d['outer_start_over_a']:.3g} a)"),
    ]
    results = [*result_rows(d),
               *((f"{v['code']} takes {v['key']}", f"{_g(v['value'])}: {v['why']}")
                 for v in d["dem_restitution"].values())]
    width = max(len(k) for k, _ in rows + results)
    lines.append("derived")
    lines += [f"  {k:<{width}}  {v}" for k, v in rows]
    lines.append(f"model: {d['model_reason']}")
    lines += [f"{piece.report}: {d[piece.reason_key]}" for piece in PIECES]
    if d["status"] != "ok":
        lines.append(f"solve FAILED ({d['status']}): {d['message']}")
    else:
        lines.append("results")
        lines += [f"  {k:<{width}}  {v}" for k, v in results]
    if d["sensitivity"]:
        lines.append(f"sensitivity (as solved: e_wet {_e(d['e_wet'])}, e_far {_e(d['e_far'])})")
        lines += [f"  {label:<{width}}  e_wet {_e(r['e_wet'])}, e_far {_e(r['e_far'])}"
                  + ("" if r["status"] == "ok" else f" ({r['status']})")
                  for label, r in d["sensitivity"].items()]
    if d["warnings"]:
        lines.append(f"validity warnings ({len(d['warnings'])}):")
        lines += [f"  - [{w['check']}] {w['message']}" for w in d["warnings"]]
    else:
        lines.append("validity: all checks passed")
    lines += [f"note: {n}" for n in d["notes"]]
    return "\n".join(lines)


def _report_stopped(scene, args) -> int:
    """The report of a scene whose outer flow stops the spheres before ``x0``: no film
    collision to solve or draw."""
    from .run import stopped_result

    d = stopped_result(scene, ranges=not args.no_range)
    print(json.dumps(d) if args.json else format_report(d))
    if args.plot:
        print(f"ehd scene: no figures in {args.plot}: the spheres stop before x0, so there is "
              "no film collision to draw", file=sys.stderr)
    return 0


def _solve(scene, args):
    """``(SceneResult, the trajectory's parts or None)``: the scene solved as asked, or, with
    ``--trajectory``, at the speed its release arrives with (the range of that scene, not of
    every near-field solve)."""
    from ..cli_shared import numerics_overrides
    from .run import run_scene
    from .trajectory import trajectory_asked

    numerics = numerics_overrides(args)
    # profiles only for the figures: the pressure extremes come from the solver
    if not trajectory_asked(args):
        return run_scene(scene, accuracy=args.accuracy, save_profiles=bool(args.plot),
                         ranges=not args.no_range, **numerics), None
    from .answer import answer
    from .trajectory import run_trajectory

    result, *whole = run_trajectory(scene, args, args.accuracy, save_profiles=bool(args.plot),
                                    **numerics)
    result.answer = answer(result, args.accuracy, numerics, ranges=not args.no_range)
    return result, whole


def flag_values(args) -> dict:
    """``{flag dest: value}`` of the parsed ``ehd scene`` flags, as ``load_scene`` takes them."""
    return {**{dest: getattr(args, dest) for dest in _FLAG_FIELDS}, "wall2": args.wall}


def cmd_scene(args) -> int:
    if args.list_materials:
        return _list_materials(args)
    flags = flag_values(args)
    if args.file is None and not any(v for v in flags.values()):
        raise _usage_error("give a scene file (ehd scene FILE.toml) or the scene as flags "
                           "(see ehd scene --help)")
    from .trajectory import trajectory_asked

    try:
        scene = load_scene(args.file, flags, args.materials or ())
    except ValueError as exc:
        raise _usage_error(str(exc)) from None
    from ..cli_shared import check_output_paths
    from ..plots import SCENE_FIGURES, TRAJECTORY_FIGURE, figure_files

    figures = SCENE_FIGURES + ((TRAJECTORY_FIGURE,) if trajectory_asked(args) else ())
    check_output_paths(plot=args.plot, figures=figure_files(figures))
    if scene.stops_outside and not trajectory_asked(args):
        return _report_stopped(scene, args)
    try:
        result, whole = _solve(scene, args)
    except ValueError as exc:
        raise _usage_error(str(exc)) from None
    except ArithmeticError as exc:  # a numerical failure inside the solver: report, no traceback
        print(f"ehd scene: the solver failed for St = {scene.stokes:.4g}, eps = {scene.eps:.3g}: "
              f"{type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_SCENE_FAILED
    d = result.to_dict()
    from ..sweeps.tasks import nonfinite_reason

    failed = not result.collision.ok
    reason = "" if failed else nonfinite_reason(lambda n: getattr(result.collision, n, None))
    if reason:  # an overflow is no result: a failed scene with its reason
        d.update(status="error", message=reason)
        failed = True
    if whole:
        from .trajectory import approach_on_trajectory, trajectory_keys

        d.update(trajectory_keys(whole[1]))
        approach_on_trajectory(d, whole[0], scene)
    if args.json:
        print(json.dumps(d))
        for w in d["warnings"]:
            print(f"warning: [{w['check']}] {w['message']}", file=sys.stderr)
    else:
        print(format_report(d))
        if whole:
            from .trajectory import trajectory_summary

            print(trajectory_summary(d, replaced=scene))
    if whole:  # after the report: a failed write (a full disk) loses no number computed
        from .trajectory import write_trajectory

        write_trajectory(whole, args, failed)
    if args.plot and not failed:
        from ..plots.scene_plots import plot_scene, si_scales

        from ..writes import guarded_dir

        with guarded_dir(args.plot, f"--plot {args.plot}"):
            paths = plot_scene(result.collision, args.plot, title=scene.title,
                               scales=si_scales(scene))
        if not args.json:
            print(f"figures: {', '.join(str(p) for p in paths if p.suffix == '.png')}")
    elif args.plot:
        print(f"ehd scene: no figures in {args.plot}: the scene failed ({d['status']})",
              file=sys.stderr)
    if failed:
        return EXIT_SCENE_FAILED
    if args.strict and d["warnings"]:
        print(f"ehd scene: {len(d['warnings'])} validity warning(s) (--strict)", file=sys.stderr)
        return EXIT_SCENE_FAILED
    return 0


def _list_materials(args) -> int:
    from .checks import per_gpa
    from .materials import load_table

    try:
        table = load_table(args.materials or ())
    except ValueError as exc:
        raise _usage_error(str(exc)) from None
    print("materials (solids):")
    for name, s in sorted(table.solids.items()):
        y = "" if s.yield_strength is None else f", yield {_q(s.yield_strength, 'Pa')}"
        print(f"  {name:<20} E = {_q(s.youngs_modulus, 'Pa')}, nu = {s.poisson_ratio:g}, "
              f"rho = {s.density:g} kg/m^3{y}")
        print(f"  {'':<20} source: {s.source} [{table.origins[('materials', name)]}]")
    print("fluids:")
    for name, f in sorted(table.fluids.items()):
        extra = ""
        if f.vapour_pressure is not None:
            extra += f", vapour pressure {_q(f.vapour_pressure, 'Pa')}"
        if f.mean_free_path is not None:
            extra += f", mean free path {_q(f.mean_free_path, 'm')}"
        if f.pressure_viscosity is not None:
            extra += f", alpha {per_gpa(f.pressure_viscosity)}"
        if f.has_roelands:
            extra += f", Roelands Z {f.roelands_index:g}, p_R {_q(f.roelands_pressure, 'Pa')}"
        if f.has_dowson_higginson:
            extra += (f", Dowson-Higginson c1 {per_gpa(f.dowson_higginson_c1)}, "
                      f"c2 {per_gpa(f.dowson_higginson_c2)}")
        print(f"  {name:<20} mu = {_q(f.viscosity, 'Pa*s')}, rho = {f.density:g} kg/m^3{extra}")
        print(f"  {'':<20} source: {f.source} [{table.origins[('fluids', name)]}]")
        if f.pressure_source:
            print(f"  {'':<20} pressure dependence: {f.pressure_source}")
    print("pairs (dry restitution e_dry of any two of the materials):")
    for name, pair in table.pairs.items():
        print(f"  {name:<20} e_dry = {pair.e_dry:g}: {', '.join(sorted(pair.materials))}")
        print(f"  {'':<20} source: {pair.source} [{table.origins[('pairs', name)]}]")
    return 0


def cmd_paper_figures(args) -> int:
    from ..cli_shared import check_output_dir
    from ..plots.paper_figures import paper_figures
    from ..writes import guarded_dir

    from ..plots.paper_figures import FIGURES
    from ..plots import figure_files

    check_output_dir("--out", args.out, figure_files(FIGURES))
    try:
        with guarded_dir(args.out, f"--out {args.out}"):
            paths = paper_figures(args.out, accuracy=args.accuracy)
    except ValueError as exc:
        raise _usage_error(str(exc)) from None
    except RuntimeError as exc:
        print(f"ehd paper-figures: {exc}", file=sys.stderr)
        return EXIT_SCENE_FAILED
    print(f"wrote {len(paths)} files to {args.out}: "
          f"{', '.join(p.name for p in paths if p.suffix == '.png')}")
    return 0


def _add_scene_flags(p) -> None:
    """The flags that fill the scene file's keys (``_SCENE_FLAGS``), in their groups of
    ``--help`` (``flags.GROUPS``), and ``--wall`` after the bodies'."""
    by_group = {}
    for flag in _SCENE_FLAGS:
        by_group.setdefault(flag.help_group, []).append(flag)
    unknown = sorted(set(by_group) - set(GROUPS))
    if unknown:  # a declaration's mistake, not the user's
        raise RuntimeError(f"scene flags in groups not in flags.GROUPS: {unknown}")
    for group in GROUPS:
        for n in ((1, 2) if group == "body" else (None,)):
            g = p.add_argument_group(group_title(group, n)) if group else p
            for flag in by_group.get(group, ()):
                for name, dest, section, _ in flag.options():
                    if n is None or section == f"body{n}":  # a body's group: its own flags
                        g.add_argument(name, dest=dest, default=None, choices=flag.choices,
                                       help=flag.help)
        if group == "body":
            p.add_argument("--wall", action="store_true",
                           help="body2 is a plane wall (infinite radius and mass)")


def _build_scene(sub) -> None:
    from ..cli_shared import add_numerics_flags
    from .answer import SOLVED_UNKNOWNS

    p = sub.add_parser(
        "scene", description="Solve one collision given in physical units, check the model's premises, "
                    "and report the results in SI and in the scalings. Values are SI numbers or "
                    "strings with units ('50 um', '10 cm/s', '1 mPa s'). Flags override the file.")
    p.add_argument("file", nargs="?", default=None, help="scene file (TOML; see docs/scenes.md)")
    _add_scene_flags(p)
    p.add_argument("--materials", action="append", metavar="FILE",
                   help="extra materials/fluids TOML file (repeatable; overrides shipped entries)")
    p.add_argument("--list-materials", action="store_true",
                   help="print the known materials and fluids with their sources, then exit")
    add_numerics_flags(p)
    p.add_argument("--json", action="store_true",
                   help="print exactly one JSON object (keys in docs/scenes.md)")
    p.add_argument("--plot", metavar="DIR", default=None,
                   help="write the scene's figures (PNG and PDF) into DIR")
    p.add_argument("--no-range", dest="no_range", action="store_true",
                   help=f"skip the range's solves (one or two per unknown: "
                        f"{', '.join(SOLVED_UNKNOWNS)}); e_for_dem_range and the others are then "
                        "null")
    p.add_argument("--strict", action="store_true",
                   help="exit 1 when any validity check warns")
    from .trajectory import add_trajectory_flags

    add_trajectory_flags(p)
    p.set_defaults(func=cmd_scene)


def _build_paper_figures(sub) -> None:
    from ..cli_shared import accuracy_help

    p = sub.add_parser("paper-figures", description="Write the classic paper's in-depth figures "
                       "2-11: the elastic kernel, I(xi), and the collisions at St = 2.5, 5, 10 "
                       "with eps = 0.01 (PNG and PDF).")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--accuracy", default="standard", metavar="{fast,standard,fine}",
                   help=accuracy_help("preset of the solves"))
    p.set_defaults(func=cmd_paper_figures)


def register(subparsers) -> None:
    """Add ``scene`` and ``paper-figures`` to the ``ehd`` command line."""
    _build_scene(subparsers)
    _build_paper_figures(subparsers)
