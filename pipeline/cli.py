"""Command line: ``ehd run`` (one scene), ``ehd info`` (versions, cache folder, threads); other
modules add subcommands (``COMMAND_MODULES``). Importing ``pipeline`` (this module's package) sets
the process environment first (pipeline/environment.py).

The error boundary of every command is :func:`main`: an expected failure is a
``pipeline.errors.EhdError`` (one line on stderr, its exit code); anything else is a bug (its
traceback, one line saying so, exit 70). Exit codes (the table is in ``pipeline/errors.py`` and
docs/pipeline.md): 0 success, 1 a scene failed (its status and message are printed), 2 bad input
(including output paths that cannot be written, checked before any solve), 3/4 a sweep with failed
scenes / a lost scheduler, 5 a damaged store, 70 a bug, 74 an output could not be written (a full
disk, stdout closed or full: one line naming the path and the free space, nothing partial left),
130 interrupted, 143 terminated (SIGTERM, handled like Ctrl-C), 141 the reader of stdout
went away (``ehd run ... | head``): like a Unix tool killed by SIGPIPE (128 + 13), so ``set -o
pipefail`` scripts see the usual code, but without a traceback; the rest of the output goes to
/dev/null (the recipe of the Python docs, "Note on SIGPIPE").

``ehd run`` takes one flag per dimensionless group of ``solver.physics`` (``--St``, ``--eps``),
generated from its declaration, and prints one row per labelled observable of
``solver.observables``: a new group or observable appears here without editing this module.
"""

from __future__ import annotations

import argparse
import gc
import os
import sys

# the shared helpers live in cli_shared (the sub-command modules import them from there); the
# names stay importable from here for code written against them
from .cli_shared import (add_numerics_flags, check_output_dir, check_output_paths, format_value,
                         numerics_overrides)
from .errors import (BUG_REPORT, EXIT_BROKEN_PIPE, EXIT_INTERNAL, EXIT_INTERRUPTED,
                     EXIT_SCENE_FAILED, EXIT_TERMINATED, EXIT_WRITE, EhdError, PathError,
                     Terminated, UsageError, interrupt_cause, interrupt_handled, on_signal,
                     raise_lost_interrupt)

__all__ = ["main", "COMMANDS", "UsageError", "check_output_paths", "check_output_dir"]

_add_numerics_flags = add_numerics_flags  # the former private names
_numerics_overrides = numerics_overrides


def report_rows(d: dict) -> list[tuple[str, object]]:
    """Rows of the ``ehd run`` report of ``Collision.to_dict()``: the physics groups, model and
    status, then every observable with a ``label``, in registry order."""
    from solver.observables import LABELS, OBSERVABLES
    from solver.physics import Physics

    # labels of a result shown as rows; "message" is printed below the table as the failure or
    # note line, "accuracy" is the user's own flag
    rows = [(name, d[name]) for name in Physics.names()]
    rows += [(name, d[name]) for name in LABELS if name in ("model", "status")]
    rows += [(o.label, d[o.name]) for o in OBSERVABLES if o.label]
    return rows


def _print_scene(d: dict) -> None:
    rows = report_rows(d)
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {format_value(v)}")
    if d["status"] != "ok":
        print(f"failure: {d['message']}")
    elif d.get("message"):
        print(f"note: {d['message']}")


def physics_from_args(args):
    """The ``Physics`` of the ``--St``, ``--eps``... flags (``_add_physics_flags``); a group
    given while the group that switches its physics on is off (it would do nothing:
    ``cli_shared.INERT_RULES``, e.g. ``--e-dry`` without ``--roughness``) is refused."""
    from solver.physics import Physics

    from .cli_shared import inert_groups, inert_message

    given = {name: getattr(args, name) for name in Physics.names()}
    try:
        physics = Physics.from_mapping(given)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    found = inert_groups({n: v for n, v in given.items() if v is not None})
    if found:
        def label(name):
            value = given.get(name)
            flag = Physics.group(name).option
            if value is None:
                return flag
            return f"{flag} {value:g}" if isinstance(value, float) else f"{flag} {value}"
        raise UsageError(inert_message(found, label))
    return physics


def outer_from_args(args):
    """The ``solver.far_field.OuterFlow`` of the ``--outer-geometry``, ``--x0-over-a``... flags:
    how ``e_far`` reads the result (a bad value: exit 2, one line naming the flag's field)."""
    from solver.far_field import OuterFlow

    try:
        return OuterFlow(geometry=args.outer_geometry, x0_over_a=args.x0_over_a,
                         x_ref_over_a=args.x_ref_over_a, start_over_a=args.outer_start_over_a,
                         density_ratio=args.density_ratio)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def add_outer_flags(p) -> None:
    """The flags of the outer-flow reading (``e_far``, ``v_outer_start``; docs/model.md,
    "Outer flow: the far-field restitution")."""
    from solver import far_field as ff

    g = p.add_argument_group("far-field restitution e_far (a reading: the near-field solve does "
                             "not depend on these)")
    g.add_argument("--outer-geometry", choices=("wall", "spheres"), default="wall",
                   help="sphere and plane wall, or two equal spheres; default wall")
    g.add_argument("--x0-over-a", type=float, default=ff.X0_OVER_A, metavar="X0_OVER_A",
                   help=f"the near-field start x0/a, in [{ff.MIN_X0_OVER_A:g}, 1]; default "
                        f"{ff.X0_OVER_A:g}")
    g.add_argument("--x-ref-over-a", type=float, default=ff.X_REF_OVER_A, metavar="X_REF_OVER_A",
                   help="where e_far reads approach and departure speeds, x_ref/a, in "
                        f"[x0/a, outer start]; default {ff.X_REF_OVER_A:g}")
    g.add_argument("--outer-start-over-a", type=float, default=ff.START_OVER_A,
                   metavar="START_OVER_A",
                   help="where the outer approach starts, over a, in (x0/a, "
                        f"{ff.MAX_OVER_A:g}]; default {ff.START_OVER_A:g}")
    g.add_argument("--density-ratio", type=float, default=0.0, metavar="RHO_F_OVER_RHO_P",
                   help="fluid over particle density rho_f/rho_p for the added mass, in "
                        "[0, 1e6]; default 0 (no added mass)")


def cmd_run(args) -> int:
    from solver import collide

    from .plots import SCENE_FIGURES, figure_files

    check_output_paths(args.save, args.plot, figure_files(SCENE_FIGURES))
    physics = physics_from_args(args)
    from .environment import compile_notice

    outer = outer_from_args(args)
    if args.x_ref * outer.x0_over_a > outer.start_over_a:  # collide checks x_ref >= x0 itself
        raise UsageError(
            f"--x-ref {args.x_ref:g}: e_wet would be seen at {args.x_ref * outer.x0_over_a:.3g} "
            f"a, beyond the outer start {outer.start_over_a:g} a, where the outer flow, not the "
            "film's lubrication, slows the spheres; give --x-ref at most "
            f"{outer.start_over_a / outer.x0_over_a:g} (x0 = {outer.x0_over_a:g} a), or read "
            "e far out as e_far (--x-ref-over-a)")
    compile_notice(physics=[physics])
    try:
        result = collide(physics, accuracy=args.accuracy, x_ref_x0=args.x_ref, outer=outer,
                         save_profiles=bool(args.save or args.plot), **_numerics_overrides(args))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    d = result.to_dict()
    from .sweeps.tasks import nonfinite_reason

    failed = not result.ok
    reason = "" if failed else nonfinite_reason(lambda n: getattr(result, n, None))
    if reason:  # an overflow is no result: a failed scene with its reason
        d.update(status="error", message=reason)
        failed = True
    if args.json:
        import json

        print(json.dumps(d))
    else:
        _print_scene(d)
    if args.save:
        _save_dataset(result.to_xarray(), args.save)
        if not args.json:
            print(f"saved {args.save}")
    if args.plot and not failed:
        from .plots.scene_plots import plot_scene
        from .writes import guarded_dir

        with guarded_dir(args.plot, f"--plot {args.plot}"):
            paths = plot_scene(result, args.plot)
        if not args.json:
            print(f"figures: {', '.join(str(p) for p in paths if p.suffix == '.png')}")
    elif args.plot:
        print(f"ehd run: no figures in {args.plot}: the scene failed ({d['status']})",
              file=sys.stderr)
    return EXIT_SCENE_FAILED if failed else 0


def _save_dataset(ds, path: str) -> None:
    """Write under a temporary name and move into place: a failed write (a full disk) leaves
    neither a partial file nor a changed old one (pipeline/writes.py). The file carries the mark
    (``cli_shared.SAVED_BY``) by which a later ``--save`` knows it may replace it."""
    from .cli_shared import SAVED_BY, SAVED_BY_KEY
    from .writes import atomic_path

    ds.attrs[SAVED_BY_KEY] = SAVED_BY
    with atomic_path(path, f"--save {path}") as tmp:
        if path.endswith(".zarr"):
            from .sweeps.layout import zarr_warnings

            with zarr_warnings():  # we consolidate on purpose, as the sweep stores do
                ds.to_zarr(tmp, mode="w")
        else:
            ds.to_netcdf(tmp, engine="scipy")  # netCDF3 via scipy: no extra dependency


def _add_physics_flags(p: argparse.ArgumentParser) -> None:
    """One flag per dimensionless group (``solver.physics.GROUPS``): ``--St``, ``--eps`` (required),
    ``--Pi``, ``--cavitation``, ``--beta``, ``--viscosity``... (with their defaults)."""
    from solver.physics import GROUPS

    for group in GROUPS:
        default = "" if group.default is None else f"; default {group.default}"
        if group.choices:
            p.add_argument(*group.options, dest=group.name, choices=group.choices,
                           default=group.default, help=f"{group.long_name}{default}")
            continue
        if group.table:
            p.add_argument(*group.options, dest=group.name, default=group.default,
                           metavar="P:MU_RATIO,...", help=group.long_name)
            continue
        lb = "[" if group.closed_lo else "("
        p.add_argument(*group.options, dest=group.name, type=float,
                       required=group.default is None, default=group.default,
                       metavar=group.name.upper(),
                       help=f"{group.long_name}, in {lb}{group.lo:g}, {group.hi:g}]{default}")


def _build_run(sub) -> None:
    p = sub.add_parser("run", description="Solve one collision given its dimensionless groups "
                       "and print its observables (one row each; --json: one JSON object).")
    _add_physics_flags(p)
    _add_numerics_flags(p)
    p.add_argument("--json", action="store_true", help="print exactly one JSON object")
    p.add_argument("--x-ref", type=float, default=1.0, metavar="X_REF_X0",
                   help="where e_wet is seen, over x0 (>= 1; the impact Stokes number there is "
                        "St + ln(x_ref/x0)); default 1")
    add_outer_flags(p)
    p.add_argument("--save", metavar="FILE", default=None,
                   help="write time series and profiles (.nc or .zarr)")
    p.add_argument("--plot", metavar="DIR", default=None,
                   help="write the collision's figures (PNG and PDF) into DIR")
    p.set_defaults(func=cmd_run)


def cmd_info(args) -> int:
    from .environment import info

    for key, value in info().items():
        print(f"{key:<22}{value if value is not None else 'none (not writable: not cached)'}")
    return 0


def _build_info(sub) -> None:
    p = sub.add_parser("info", description="What to paste into a bug report: the versions, the "
                       "compiled-code cache folder in use, the BLAS threads.")
    p.set_defaults(func=cmd_info)


def register(sub) -> None:
    """Add ``run`` and ``info`` (the commands defined here)."""
    _build_run(sub)
    _build_info(sub)


# The command registry: name -> (the module whose ``register(subparsers)`` adds it, the line
# ``ehd --help`` shows). Only the chosen command's module is imported, so ``ehd --help`` and
# ``ehd sweep`` do not load numba or the solver (benchmarks/startup.md); this line is the one
# help of each command (a module's own ``help=`` is not used; tests/test_docs.py).
COMMANDS = {
    "run": ("pipeline.cli", "solve one collision given its dimensionless groups (--St, --eps, ...)"),
    "info": ("pipeline.cli", "versions, compiled-code cache folder, BLAS threads"),
    "sweep": ("pipeline.sweeps.commands",
              "compute a sweep (grid over Physics fields) into its zarr store (cached, resumable); "
              "a shipped sweep by name: ehd sweep paper"),
    "status": ("pipeline.sweeps.commands",
               "what a sweep store holds: done, failed, missing, damaged (exit 5 when damaged)"),
    "figures": ("pipeline.sweeps.commands",
                "Figures 12-14, (St, eps) maps and stick/rebound from a sweep store (one set per "
                "value of its other axes; never computes scenes; skipped when the folder is up to "
                "date with the store)"),
    "scene": ("pipeline.scenes.commands",
              "solve a collision given in physical units (bodies, fluid, speed)"),
    "paper-figures": ("pipeline.scenes.commands",
                      "write the in-depth figures 2-11 (kernel, I(xi), St = 2.5/5/10 at "
                      "eps = 0.01)"),
    "export-dem": ("pipeline.dem.commands",
                   "wet restitution e(St) for DEM codes: CSV, fits, LIGGGHTS / OpenFOAM / YADE "
                   "settings"),
    "restitution": ("pipeline.dem.commands",
                    "e(St) of a scene along a path in impact speed or size"),
    "examples": ("pipeline.shipped",
                 "copy the shipped example scenes and sweep files into a folder"),
}
# the modules that add commands (each once, in the order of the registry)
COMMAND_MODULES = tuple(dict.fromkeys(module for module, _ in COMMANDS.values()))


class _OneLine(argparse.ArgumentParser):
    """argparse's parser whose usage error is one line naming the problem and where the fix is
    (argparse prints the whole usage first: 18 lines for ``ehd run --St abc``), exit 2. Every
    command's parser is one too (``add_subparsers`` makes its parsers of this class)."""

    stray = None  # the top level's: a command's flag given before any command (``ehd --St 10``)

    def error(self, message):
        if self.stray is not None:
            self.exit(2, f"{self.prog}: error: {self.stray} is no flag of ehd itself: name the "
                         f"command first, ehd COMMAND {self.stray} ... (the commands: ehd "
                         "--help; a command's flags: ehd COMMAND --help)\n")
        self.exit(2, f"{self.prog}: error: {message} (the flags: {self.prog} --help)\n")


class _OnlyChosen:
    """The sub-parsers seen by a module's ``register``: only the chosen command is built (with
    the registry's help line); the module's other commands go to a parser that is dropped."""

    def __init__(self, sub, chosen: str):
        self._sub, self._chosen = sub, chosen

    def add_parser(self, name, **kwargs):
        if name != self._chosen:
            return argparse.ArgumentParser(add_help=False)
        kwargs["help"] = COMMANDS[name][1]
        self.parser = self._sub.add_parser(name, **kwargs)
        return self.parser


class _Version(argparse.Action):
    """``--version``, worked out only when asked for (it imports the solver's version)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(version_line())  # on stdout, as argparse's own version action
        parser.exit()


def version_line() -> str:
    """``ehd-collision 1.5.0 (solver 1.5.0)``: the installed package and the solver whose
    version keys every store and cache (they are one number; a difference means the installed
    metadata is stale: reinstall)."""
    from importlib.metadata import PackageNotFoundError, version

    from solver.result import SOLVER_VERSION

    try:
        package = version("ehd-collision")
    except PackageNotFoundError:
        package = "not installed (run from a clone)"
    stale = "" if package in (SOLVER_VERSION,) or package.startswith("not") else \
        "; the installed metadata is stale: reinstall (make install)"
    return f"ehd-collision {package} (solver {SOLVER_VERSION}{stale})"


def _chosen_command(argv) -> str | None:
    """The command named on the command line (the first word that is not an option; the top
    level has only -h and --version), or None."""
    for token in argv:
        if not token.startswith("-"):
            return token if token in COMMANDS else None
    return None


def _parser(argv=None) -> argparse.ArgumentParser:
    """The ``ehd`` parser: every command is listed, the chosen one (from ``argv``) built in full.
    ``_parser()`` without ``argv`` builds none in full (``ehd --help``)."""
    import importlib

    parser = _OneLine(
        prog="ehd", description="Elastohydrodynamic collision of two elastic spheres in a viscous "
        "fluid. Every command: ehd COMMAND --help. Example files: ehd examples DIR.")
    parser.add_argument("--version", action=_Version,
                        help="print the package and solver version and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    argv = sys.argv[1:] if argv is None else argv
    chosen = _chosen_command(argv)
    if argv and argv[0].startswith("-") and argv[0].split("=")[0] not in ("-h", "--help",
                                                                          "--version"):
        parser.stray = argv[0].split("=")[0]
    parser.chosen = None  # the chosen command's parser, built in full
    for name, (module, help_line) in COMMANDS.items():
        if name == chosen:
            only = _OnlyChosen(sub, name)
            importlib.import_module(module).register(only)
            parser.chosen = getattr(only, "parser", None)
        else:
            sub.add_parser(name, help=help_line, add_help=False)
    return parser


def _interrupted(name: str, terminated: bool = False) -> int:
    interrupt_handled()
    _quiet_dask()
    _flush_quietly()
    how = "terminated (SIGTERM)" if terminated else "interrupted"
    if name == "ehd sweep":  # its journal keeps every finished scene
        _say(f"{name}: {how}; everything finished so far is kept (run it again to resume)")
    else:  # no other command keeps a partial result
        _say(f"{name}: {how} before it finished; run it again")
    return EXIT_TERMINATED if terminated else EXIT_INTERRUPTED


def _handle_signals():
    """Ctrl-C and SIGTERM raise ``KeyboardInterrupt`` and ``Terminated`` through
    ``errors.on_signal``, which remembers them: one that Python drops (raised inside a weakref
    callback or a ``__del__``) is raised again by the next ``raise_lost_interrupt`` (the sweep
    calls it after each scene, ``_main`` after the command), and its "Exception ignored"
    traceback is not printed. SIGTERM unwinds like Ctrl-C (the journal keeps every finished
    scene; exit 143). An ignored SIGINT (a job started in the background) stays ignored.
    Returns a function that puts the previous handlers back (``main`` called from Python code,
    e.g. a test, leaves the process as it found it)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    previous = {signal.SIGTERM: signal.signal(signal.SIGTERM, on_signal)}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, on_signal)
    previous_hook = sys.unraisablehook

    def unraisable(report):
        if report.exc_type is not None and issubclass(report.exc_type,
                                                      (KeyboardInterrupt, Terminated)):
            return  # raised again where it can propagate
        previous_hook(report)

    sys.unraisablehook = unraisable

    def restore():
        sys.unraisablehook = previous_hook
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    return restore


def _closed_stdout() -> bool:
    """fd 1 is closed (``ehd ... >&-``); it is pointed at /dev/null at once, so no file opened
    later takes fd 1 and receives what C code prints. Also fd 2 when closed (messages are then
    lost, the exit code still says what happened)."""
    closed = False
    for fd in (1, 2):
        try:
            os.fstat(fd)
        except OSError:
            devnull = os.open(os.devnull, os.O_WRONLY)
            if devnull != fd:
                os.dup2(devnull, fd)
                os.close(devnull)
            closed = closed or fd == 1
    return closed or sys.stdout is None


def _say(line: str) -> None:
    """One line on stderr; never raises (stderr may be closed or full too)."""
    try:
        stream = sys.stderr if sys.stderr is not None else sys.__stderr__
        print(line, file=stream, flush=True)
    except Exception:  # noqa: BLE001 - nowhere left to say it: the exit code says it
        pass


def _stdout_lost(name: str, exc: OSError) -> int:
    """stdout could not take the output (``> /dev/full``, an I/O error): one line, exit 74; the
    rest of the output goes to /dev/null so the interpreter's last flush cannot fail again."""
    _to_devnull()
    _say(f"{name}: error: cannot write to stdout ({exc.strerror or type(exc).__name__}); the "
         "output was lost: send it to a file with room (> FILE)")
    return EXIT_WRITE


def _to_devnull() -> None:
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.close(devnull)
    except OSError:
        pass


def main(argv=None) -> int:
    """Run one ``ehd`` command: the error boundary of them all (see the module docstring).
    Never raises but ``SystemExit`` of argparse (``--help``, a bad flag: exit 2)."""
    interrupt_handled()  # nothing left over from an earlier call in this process
    restore = _handle_signals()
    try:
        return _main(argv)
    except SystemExit:
        raise
    except BaseException as exc:  # noqa: BLE001 - the boundary of the boundary
        if interrupt_cause(exc) is not None:
            interrupt_handled()
            return EXIT_TERMINATED if isinstance(interrupt_cause(exc), Terminated) \
                else EXIT_INTERRUPTED
        try:
            what = f"{type(exc).__name__}: {exc}"
        except Exception:  # noqa: BLE001 - an exception whose text fails too
            what = type(exc).__name__
        _say(f"ehd: internal error ({what}): this is a bug in ehd-collision; please report it "
             f"at {BUG_REPORT}")
        return EXIT_INTERNAL
    finally:
        try:
            restore()
        except Exception:  # noqa: BLE001 - the boundary never raises
            pass


def executable() -> int:
    """``main`` as the ``ehd`` executable (and ``python -m pipeline.cli``) runs it: the process
    ends after it, so what it leaves is collected once and the rest frozen out of the collector
    (``gc.freeze``). The interpreter's collections at exit, after its modules are cleared, walk
    every object numba made loading the solver (85,000 after a collision) to free memory the
    process hands back anyway: 0.04 s of a 0.5 s warm ``ehd run`` (benchmarks/startup.md). Not
    done by ``main``, which tests and scripts call in a process that goes on."""
    code = main()
    try:
        # the command is done and its exit code decided: a Ctrl-C or SIGTERM from now on (one
        # pressed again, a batch system's late signal) is ignored, not raised into a weakref
        # callback of the collection below or the interpreter's teardown, which printed
        # "Exception ignored in ... KeyboardInterrupt" after the line (a hostile review: a
        # sweep stopped by four Ctrl-C, 2 of 4 tries)
        import signal

        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        gc.collect()
        gc.freeze()
    except KeyboardInterrupt:  # one that came before the signals were ignored
        pass
    return code


def _stdout_closed_line(name: str) -> int:
    _say(f"{name}: error: stdout is closed (>&-): the output would be lost; run with stdout "
         "open (> FILE, or > /dev/null to discard it)")
    return EXIT_WRITE


def _parse(argv, stdout_closed: bool):
    """The parsed arguments, or None when ``--help`` or ``--version`` printed into a closed
    stdout. Their output (argparse prints it to stdout, then exits 0) is flushed here, so a
    full stdout is exit 74 like any command's (``_StdoutLost``)."""
    try:
        parser = _parser(argv)
        args, unknown = parser.parse_known_args(argv)
        if unknown:  # named by the command's parser: "ehd run: error: ...", not "ehd: error"
            (parser.chosen or parser).error(f"unrecognized arguments: {' '.join(unknown)}")
        return args
    except SystemExit as exc:
        if exc.code not in (0, None):  # a usage error: argparse said it on stderr
            raise
        if stdout_closed:
            return None
        sys.stdout.flush()
        raise


def _main(argv=None) -> int:
    import errno
    import io

    stdout_closed = _closed_stdout()
    argv = _negative_values(sys.argv[1:] if argv is None else list(argv))
    name = "ehd"
    real_stdout = sys.stdout
    # a closed stdout takes nothing: what --help would print is dropped, then one line says so
    sys.stdout = _Stdout(io.StringIO() if stdout_closed else sys.stdout)
    try:
        chosen = _chosen_command(argv)
        name = f"ehd {chosen}" if chosen else "ehd"  # for --help into a full stdout, too
        args = _parse(argv, stdout_closed)
        if stdout_closed:
            return _stdout_closed_line(name)
        name = f"ehd {args.command}"
        code = args.func(args)
        raise_lost_interrupt()  # a Ctrl-C Python dropped still ends as one
        sys.stdout.flush()  # a closed pipe or a full stdout shows here, not at interpreter exit
        return code
    except _StdoutLost as exc:
        return _stdout_lost(name, exc.error)
    except EhdError as exc:
        _flush_quietly()
        _say(f"{name}: error: {exc.line()}")
        return exc.exit_code
    except KeyboardInterrupt:
        return _interrupted(name)
    except Terminated:
        return _interrupted(name, terminated=True)
    except BrokenPipeError:
        # the reader went away (``ehd ... | head``): no traceback, and the interpreter's final
        # flush must not raise again, so stdout points to /dev/null (Python docs, SIGPIPE note)
        _to_devnull()
        return EXIT_BROKEN_PIPE
    except OSError as exc:
        if exc.errno not in (errno.ENOSPC, getattr(errno, "EDQUOT", -1), errno.EIO,
                             errno.EFBIG, errno.EROFS):
            return _bug(name, exc)
        if exc.filename is None and not _stdout_ok():
            return _stdout_lost(name, exc)
        from .writes import write_error

        _flush_quietly()
        _say(f"{name}: error: {write_error(exc, name, exc.filename).line()}")
        return EXIT_WRITE
    except Exception as exc:
        return _bug(name, exc)
    finally:
        sys.stdout = real_stdout


class _StdoutLost(Exception):
    """A write to stdout failed (not a closed pipe): ``error`` is the ``OSError``."""

    def __init__(self, error: OSError):
        super().__init__(str(error))
        self.error = error


# ASCII spellings of the characters a report prints (pint's units: 25 µm, mPa·s, 3×10⁶ µm³),
# for a stdout that cannot encode them (PYTHONIOENCODING=ascii, LANG=C on old systems)
_ASCII = str.maketrans({"µ": "u", "μ": "u", "·": "*", "×": "x", "°": " deg"})
_SUPERSCRIPTS = dict(zip("⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺", "0123456789-+"))


def ascii_spelling(text: str, encoding: str = "ascii") -> str:
    """``text`` as ``encoding`` can print it: µ as u, · as *, × as x, a superscript run as
    ``^`` and its digits (``µm³`` -> ``um^3``); any other character it cannot encode (e.g. in a
    scene's title) as ``?`` (docs/pipeline.md, "Output encoding")."""
    import re

    text = re.sub("[" + "".join(_SUPERSCRIPTS) + "]+",
                  lambda m: "^" + "".join(_SUPERSCRIPTS[c] for c in m.group()),
                  text.translate(_ASCII))
    return text.encode(encoding, errors="replace").decode(encoding)


class _Stdout:
    """stdout as the commands see it: a failed write (``> /dev/full``) is told apart from a
    failed write of a file (the error boundary reports each with its own line), and text the
    stream cannot encode is printed in ASCII spellings (``ascii_spelling``)."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            try:
                return self._stream.write(text)
            except UnicodeEncodeError:  # nothing was written: the whole text is encoded first
                return self._stream.write(ascii_spelling(text, self._stream.encoding or "ascii"))
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _StdoutLost(exc) from None

    def flush(self):
        try:
            return self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _StdoutLost(exc) from None

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _negative_values(argv: list) -> list:
    """``--Pi -inf`` as ``--Pi=-inf``: argparse takes a value that starts with '-' and is not
    a plain negative number (``-inf``, ``-1e3``, ``-nan``) for an unknown option ("expected one
    argument"); joined to its flag, the value reaches the check that names it. A plain one
    (``-1``, ``-0.5``) argparse reads itself, and stays apart: joined, the first of a flag's
    two values (``--fit-range -1 10``) left it one short ("expected 2 arguments")."""
    import re

    out = []
    for token in argv:
        prev = out[-1] if out else ""
        if (token.startswith("-") and prev.startswith("--") and "=" not in prev
                and prev != "--" and _is_number(token)
                and not re.fullmatch(r"-\d+|-\d*\.\d+", token)):  # argparse's own pattern
            out[-1] = f"{prev}={token}"
        else:
            out.append(token)
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _stdout_ok() -> bool:
    try:
        sys.stdout.flush()
        return True
    except (OSError, ValueError, AttributeError):
        return False


def _bug(name: str, exc: BaseException) -> int:
    import traceback

    interrupt = interrupt_cause(exc)
    if interrupt is not None:
        return _interrupted(name, terminated=isinstance(interrupt, Terminated))
    if isinstance(exc, OSError) and not _stdout_ok():
        return _stdout_lost(name, exc)
    _flush_quietly()
    try:
        traceback.print_exc()
    except Exception:  # noqa: BLE001
        pass
    _say(f"{name}: internal error: this is a bug in ehd-collision, not in your input; please "
         f"report it at {BUG_REPORT}")
    return EXIT_INTERNAL


def _flush_quietly() -> None:
    try:
        sys.stdout.flush()
    except (OSError, ValueError, AttributeError):
        _to_devnull()  # what is left in the buffer goes nowhere, quietly, at exit


def _quiet_dask() -> None:
    """After Ctrl-C: dask's loggers would print the tracebacks of its closing comms and
    workers; what matters was already said (and kept by the journal)."""
    try:
        if "distributed" in sys.modules:
            from .sweeps.runners import _quiet_dask as quiet

            quiet()
    except Exception:  # noqa: BLE001 - quieting is a courtesy
        pass


if __name__ == "__main__":
    sys.exit(executable())
