"""Command line: ``ehd run`` (one scene), ``ehd info`` (versions, cache folder, threads); other
modules add subcommands (``COMMAND_MODULES``). Importing ``pipeline`` (this module's package) sets
the process environment first (pipeline/environment.py).

Exit codes: 0 success, 1 a scene failed (its status and message are printed), 2 bad input.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

__all__ = ["main", "COMMANDS"]


class UsageError(Exception):
    """Bad input: printed as one line, exit code 2, no traceback."""


def _add_numerics_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--accuracy", default="standard", help="preset: fast, standard or fine")
    p.add_argument("--switch", type=float, default=None,
                   help="hand-over threshold on W(0)/X from the rigid approach (preset default)")
    p.add_argument("--release", type=float, default=None,
                   help="max|W|/X below which the departing spheres are rigid again")
    p.add_argument("--n-inner", type=int, default=None, help="grid cells across the contact region")
    p.add_argument("--rtol", type=float, default=None, help="time-step error tolerance")
    p.add_argument("--max-steps", type=int, default=None, help="step budget of the coupled solve")


def _numerics_overrides(args) -> dict:
    return {"switch": args.switch, "release": args.release, "n_inner": args.n_inner,
            "rtol": args.rtol, "max_steps": args.max_steps}


def _fmt(v, spec=".6g"):
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return format(v, spec) if math.isfinite(v) else str(v)
    return str(v)


def _print_scene(d: dict) -> None:
    rows = [
        ("St", d["St"]), ("eps", d["eps"]), ("model", d["model"]), ("status", d["status"]),
        ("rebound velocity v_r/v0", d["v_r"]),
        ("closest approach h_m/x1", d["h_m_x1"]), ("  h_m/x0", d["h_m_x0"]),
        ("closest approach on approach /x1", d["h_m_approach_x1"]),
        ("equilibrium separation x_e/x1", d["x_e_x1"]), ("  ln(x_e/x1)", d["ln_x_e_x1"]),
        ("  x_e/x0", d["x_e_x0"]),
        ("escaped (x_e > x0: no sticking)", d["escaped"]),
        ("peak force / (6 pi mu a^2 v0/x1)", d["peak_force"]),
        ("max central deformation W(0)/x1", d["w0_max_x1"]),
        ("min separation X/x1 (<0: overlap)", d["x_min_x1"]),
        ("dimple", d["dimple"]), ("  depth /x1", d["dimple_depth_x1"]),
        ("tau at max deformation", d["tau_max_deformation"]),
        ("tau at v = 0", d["tau_v_zero"]), ("tau at max rebound", d["tau_max_rebound"]),
        ("energy closure error", d["energy_error"]),
        ("steps (rejected)", f"{d['steps']} ({d['rejected_steps']})"),
        ("wall time [s]", d["wall_s"]),
    ]
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {_fmt(v)}")
    if d["status"] != "ok":
        print(f"failure: {d['message']}")
    elif d.get("message"):
        print(f"note: {d['message']}")


def cmd_run(args) -> int:
    from solver import collide

    if args.save and not args.save.endswith((".nc", ".zarr")):
        raise UsageError(f"--save: unknown file type {args.save!r}; use a .nc or .zarr path")
    try:
        result = collide(args.St, args.eps, accuracy=args.accuracy,
                         save_profiles=bool(args.save or args.plot), **_numerics_overrides(args))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    d = result.to_dict()
    if args.json:
        print(json.dumps(d))
    else:
        _print_scene(d)
    if args.save:
        _save_dataset(result.to_xarray(), args.save)
        if not args.json:
            print(f"saved {args.save}")
    if args.plot and result.ok:
        from .plots.scene_plots import plot_scene

        paths = plot_scene(result, args.plot)
        if not args.json:
            print(f"figures: {', '.join(str(p) for p in paths if p.suffix == '.png')}")
    return 0 if result.ok else 1


def _save_dataset(ds, path: str) -> None:
    if path.endswith(".zarr"):
        ds.to_zarr(path, mode="w")
    else:
        ds.to_netcdf(path, engine="scipy")  # netCDF3 via scipy: no extra dependency


def _build_run(sub) -> None:
    p = sub.add_parser("run", help="solve one collision given St and eps")
    p.add_argument("--St", type=float, required=True, help="Stokes number m v0 / (6 pi mu a^2)")
    p.add_argument("--eps", type=float, required=True,
                   help="elasticity parameter 4 theta mu v0 a^1.5 / x0^2.5")
    _add_numerics_flags(p)
    p.add_argument("--json", action="store_true", help="print exactly one JSON object")
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
    p = sub.add_parser("info", help="solver version, compiled-code cache folder, BLAS threads")
    p.set_defaults(func=cmd_info)


# name -> builder(subparsers) of the commands defined here
COMMANDS = {"run": _build_run, "info": _build_info}
# modules that add their own subcommands through ``register(subparsers)``
COMMAND_MODULES = ("pipeline.sweeps.commands", "pipeline.scenes.commands")


def _parser() -> argparse.ArgumentParser:
    import importlib

    parser = argparse.ArgumentParser(
        prog="ehd", description="Elastohydrodynamic collision of two elastic spheres in a viscous fluid.")
    sub = parser.add_subparsers(dest="command", required=True)
    for build in COMMANDS.values():
        build(sub)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
            continue
        module.register(sub)
    return parser


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    try:
        return args.func(args)
    except UsageError as exc:
        print(f"ehd {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
