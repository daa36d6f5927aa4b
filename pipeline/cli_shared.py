"""What the sub-command modules share (``pipeline/cli.py``, ``scenes/commands.py``,
``sweeps/commands.py``, ``dem/commands.py``, ``shipped.py``): the numerics flags, the output-path
checks made before any solve, and the formatting of a report value. Imports nothing heavy: the
presets' numbers are read only when a parser with the numerics flags is built.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os

from .errors import PathError

__all__ = ["add_numerics_flags", "numerics_overrides", "format_value", "check_output_dir",
           "check_output_paths", "check_name_length", "accuracy_help", "check_accuracy", "saved_by_run",
           "SAVED_BY_KEY", "SAVED_BY", "INERT_RULES", "inert_groups", "inert_message",
           "probe_writable"]


def accuracy_help(what: str = "preset") -> str:
    """Help text of ``--accuracy``: its choices and the default."""
    from solver.settings import PRESETS

    return (f"numerical {what}: {', '.join(PRESETS)} (default standard; what each buys: "
            "README, benchmarks/accuracy.md)")


def check_accuracy(value: str) -> None:
    """``--accuracy`` names a preset, or ``UsageError`` (one line, exit 2) before any solve, as
    the solver's own check words it."""
    from solver.settings import PRESETS

    from .errors import UsageError

    if value not in PRESETS:
        raise UsageError(f"--accuracy must be one of {sorted(PRESETS)}, got {value!r}")


def add_numerics_flags(p) -> None:
    """``--accuracy`` and the preset overrides, each with its choices or the preset defaults."""
    from solver.settings import PRESETS

    def preset_values(name):
        return ", ".join(f"{k} {getattr(v, name):g}" for k, v in PRESETS.items())

    # checked by the solver (one line, exit 2), not by argparse's choices (a usage block)
    p.add_argument("--accuracy", default="standard", metavar="{" + ",".join(PRESETS) + "}",
                   help=accuracy_help())
    p.add_argument("--switch", type=float, default=None,
                   help="hand-over threshold on W(0)/X from the rigid approach (default: the "
                        f"preset's: {preset_values('switch')})")
    p.add_argument("--release", type=float, default=None,
                   help="max|W|/X below which the departing spheres are rigid again (default: "
                        f"the preset's: {preset_values('release')})")
    p.add_argument("--n-inner", type=int, default=None,
                   help=f"grid cells across the contact region (default: {preset_values('n_inner')})")
    p.add_argument("--rtol", type=float, default=None,
                   help=f"time-step error tolerance (default: {preset_values('rtol')})")
    p.add_argument("--max-steps", type=int, default=None,
                   help=f"step budget of the coupled solve (default: {preset_values('max_steps')})")
    p.add_argument("--max-order", type=int, default=None,
                   help="highest order of the BDF time stepping, 1-5; above 2 the solver "
                        "chooses each step's order where the film is smooth in time "
                        f"(docs/solver.md; default: {preset_values('max_order')})")
    p.add_argument("--extrapolate", action=argparse.BooleanOptionalAction, default=None,
                   help="solve also on the grid with half the cells and extrapolate the grid "
                        "error away (docs/solver.md, \"Presets\"; default: the preset's: "
                        + ", ".join(f"{k} {'on' if v.extrapolate else 'off'}"
                                    for k, v in PRESETS.items()) + ")")


def numerics_overrides(args) -> dict:
    return {"switch": args.switch, "release": args.release, "n_inner": args.n_inner,
            "rtol": args.rtol, "max_steps": args.max_steps, "max_order": args.max_order,
            "extrapolate": args.extrapolate}


# Groups that act only when another group switches their piece of physics on: (the groups,
# the group that switches them, or a tuple of groups that together do, when a group counts as
# set (None: away from its default), when the switch is on for one value of it (one value of
# each switching group, in their order), why, what to give). A run or a sweep that sets them
# while the switch is off at every grid point would silently compute something else.
INERT_RULES = (
    (("asperity_stiffness", "e_dry"), "roughness", None, lambda v: v != 0.0,
     "act{s} only where rough surfaces touch, and {ctl} is 0 (smooth surfaces)",
     "give {ctl} > 0"),
    (("Pi",), "cavitation", None, lambda v: v != "off",
     "is the cavitation floor, and {ctl} is off", "give {ctl} auto, jfo or reynolds"),
    (("cavitation",), "Pi", lambda v: v in ("jfo", "reynolds"), lambda v: v != float("inf"),
     "needs the floor, and {ctl} is inf (no floor: the classic film)", "give {ctl}"),
    (("beta",), "viscosity_law", None, lambda v: v != "constant",
     "is the pressure dependence of the viscosity, and {ctl} is constant",
     "give {ctl} auto, barus or roelands"),
    # a table replaces the laws of beta (solver.Physics: "auto" is the table where one is
    # given); the constant law is the rule above's
    (("beta",), ("viscosity_law", "viscosity_table"), None,
     lambda law, table: law == "constant" or not table or law in ("barus", "roelands"),
     "is the Barus and Roelands laws' pressure-viscosity group, and {ctl} give the viscosity "
     "by a table", "leave the {viscosity_table} out for a law of beta"),
    (("viscosity_law",), "beta", lambda v: v in ("barus", "roelands"), lambda v: v > 0.0,
     "needs the pressure-viscosity group, and {ctl} is 0", "give {ctl} > 0"),
    (("roelands_Z", "roelands_PR"), "viscosity_law", None, lambda v: v == "roelands",
     "belong{s} to the Roelands law, and {ctl} is not roelands", "give {ctl} roelands"),
    (("dh_c1", "dh_c2"), "density_law", None, lambda v: v == "dowson-higginson",
     "belong{s} to the Dowson-Higginson density, and {ctl} is constant",
     "give {ctl} dowson-higginson"),
    # the law read in tension: a viscosity law that depends on pressure (solver.Physics resolves
    # the law: constant where beta is 0 without a table, or where it is asked for)
    (("viscosity_in_tension",), ("viscosity_law", "beta", "viscosity_table"),
     lambda v: v == "law", lambda law, beta, table: law != "constant" and (beta > 0.0 or table),
     "reads the viscosity's law at negative pressure, and {ctl} give a constant viscosity",
     "give {beta} > 0 or a {viscosity_table}"),
)


def inert_groups(values: dict) -> list[tuple]:
    """The groups that ``values`` (``{group: value}`` of one run, or of a sweep with a tuple of
    values per axis; a group left out takes its default) set although the group that switches
    their physics on is off at every point (``INERT_RULES``): ``[(names, switch, reason, fix)]``,
    the reason and fix with ``{ctl}`` for the switch's name or flag and ``{s}`` for the verb's
    ending of one name ("s")."""
    from solver.physics import Physics

    def each(name):
        v = values.get(name, Physics.group(name).default)
        return v if isinstance(v, (tuple, list)) else (v,)

    found = []
    for names, switch, is_set, acts, reason, fix in INERT_RULES:
        switches = switch if isinstance(switch, tuple) else (switch,)
        if any(acts(*point) for point in itertools.product(*map(each, switches))):
            continue
        default = {n: Physics.group(n).default for n in names}
        given = [n for n in names if any(is_set(v) if is_set else v != default[n]
                                         for v in each(n))]
        if given:
            found.append((tuple(given), switch, reason, fix))
    return found


def inert_message(found, label) -> str:
    """One line for ``inert_groups``'s findings, each group and switch written ``label(name)``
    (a flag with its value, or a sweep file's name); a fix names a switching group by
    ``{ctl}`` (all of them) or by its own name (``{beta}``)."""
    parts = []
    for names, switch, reason, fix in found:
        given = " and ".join(label(n) for n in names)
        switches = {n: label(n).split()[0]
                    for n in (switch if isinstance(switch, tuple) else (switch,))}
        ctl = _listed(list(switches.values()))
        parts.append(f"{given} " + reason.format(ctl=ctl, s="" if len(names) > 1 else "s")
                     + f": {fix.format(ctl=ctl, **switches)}, or leave "
                     + " and ".join(label(n).split()[0] for n in names) + " out")
    return "; ".join(parts)


def _listed(words) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return " and ".join(filter(None, (", ".join(words[:-1]), words[-1])))


def format_value(v, spec=".6g"):
    """A value of a report row: numbers with ``spec`` (non-finite as ``inf``/``nan``), flags as
    yes/no, missing (or empty text, e.g. no viscosity table) as "-", anything else as text."""
    if v is None or v == "":
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return format(v, spec) if math.isfinite(v) else str(v)
    return str(v)


def _name_max(folder) -> int:
    """The longest file name (bytes) the file system of ``folder`` (or its nearest existing
    parent) takes: NAME_MAX, 255 on most; 255 where it does not say."""
    from pathlib import Path

    folder = Path(os.path.abspath(folder))
    existing = next((p for p in (folder, *folder.parents) if os.path.isdir(p)), Path("/"))
    try:
        return int(os.pathconf(existing, "PC_NAME_MAX"))
    except (OSError, ValueError, AttributeError):
        return 255


def check_name_length(flag: str, value, siblings=()) -> None:
    """PathError, before any work, when a name in the path ``value`` of ``flag`` is longer than
    its file system takes, counting what the longest name made next to it adds (``siblings``:
    a temporary, a lock, a journal), so that none of them fails halfway through a run."""
    from pathlib import Path

    path = Path(value)
    added = max([len(os.fsencode(Path(s).name)) - len(os.fsencode(path.name)) for s in siblings]
                + [0])
    for p in reversed((path, *path.parents)):  # from the top: the first name too long
        if not p.name:
            continue
        extra = added if p == path else 0
        n, limit = len(os.fsencode(p.name)), _name_max(p.parent)
        if n + extra > limit:
            shown = p.name if len(p.name) <= 20 else p.name[:16] + "..."
            why = (f"; ehd adds up to {extra} bytes to it for the temporary and lock files it "
                   "makes next to it") if extra else ""
            raise PathError(f"{flag} {value}: the name {shown!r} is {n} bytes, at most "
                            f"{limit - extra} fit here (the file system takes {limit}{why}); "
                            "choose a shorter name")


def check_output_dir(flag: str, value: str | None, files=()) -> None:
    """PathError, before any work, when the folder ``value`` of ``flag`` cannot be made or
    written: empty, an existing file, a file among its parents, or a read-only parent; or when
    one of the ``files`` it will write there is taken by a folder (or a FIFO, a device)."""
    if value is None:
        return
    from pathlib import Path  # here: pathlib costs a third of ``ehd --help``'s start-up

    if not str(value).strip():
        raise PathError(f"{flag}: empty path; give a folder")
    check_name_length(flag, value)
    path = Path(value)
    if path.exists() and not path.is_dir():
        raise PathError(f"{flag} {value}: exists and is not a directory")
    existing = next((p for p in (path, *path.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise PathError(f"{flag} {value}: {str(existing)!r} is not a directory")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise PathError(f"{flag} {value}: {str(existing)!r} is not writable")
    probe_writable(flag, value, existing)
    for name in files:
        target = path / name
        if os.path.lexists(target) and not target.is_file():
            raise PathError(f"{flag} {value}: {name} is there and is not a file, where ehd "
                            "writes one: move it away, or choose another folder")


def probe_writable(flag: str, value: str, folder) -> None:
    """PathError when a folder cannot be made in ``folder`` though its permissions allow it
    (``/proc``, a file system that refuses new entries): found before the work, not at its
    write (exit 74 after the solve). The probe folder is removed at once."""
    import tempfile

    try:
        os.rmdir(tempfile.mkdtemp(prefix=".ehd-probe-", dir=folder))
    except OSError as exc:
        raise PathError(f"{flag} {value}: cannot write in {str(folder)!r} "
                        f"({exc.strerror or exc}); choose another path") from None


# the mark of ``ehd run --save``'s own output (an attribute of the saved Dataset): the only
# existing path ``--save`` replaces (docs/pipeline.md, "What ehd never overwrites")
SAVED_BY_KEY, SAVED_BY = "written_by", "ehd run --save"


def saved_by_run(path: str) -> bool:
    """True when ``path`` (a ``.zarr`` folder or a ``.nc`` file, not a link) carries the mark
    of ``ehd run --save``; anything else (a sweep store, a foreign folder or file, one that
    cannot be read) is not its own."""
    from pathlib import Path

    target = Path(path)
    try:
        if target.is_symlink():
            return False
        if path.endswith(".zarr"):
            import json

            from .reads import read_input

            meta = json.loads(read_input(target / "zarr.json", f"--save {path}"))
            attrs = meta.get("attributes") if isinstance(meta, dict) else None
        else:
            import stat

            if not stat.S_ISREG(target.stat().st_mode):
                return False
            import xarray as xr

            with xr.open_dataset(target, engine="scipy") as ds:
                attrs = dict(ds.attrs)
    except Exception:  # noqa: BLE001 - unreadable or not a dataset: not ours
        return False
    return isinstance(attrs, dict) and attrs.get(SAVED_BY_KEY) == SAVED_BY


def check_output_paths(save: str | None = None, plot: str | None = None, figures=()) -> None:
    """PathError, before any solve, when ``--save FILE`` or ``--plot DIR`` (with the file names
    ``figures`` it will hold, ``check_output_dir``) cannot be written:
    a missing or read-only parent directory, or an existing path of the wrong kind (a ``.zarr``
    store and ``DIR`` are directories, a ``.nc`` file is a file), or an existing ``--save``
    path that ``ehd run --save`` did not write (``saved_by_run``: it is never replaced)."""
    from pathlib import Path

    if save is not None:
        if not save.endswith((".nc", ".zarr")):
            raise PathError(f"--save: unknown file type {save!r}; use a .nc or .zarr path")
        from .writes import temporary_paths

        check_name_length("--save", save, temporary_paths(save))
        path = Path(save)
        parent = path.parent
        if not parent.is_dir():
            raise PathError(f"--save {save}: the directory {str(parent)!r} does not exist")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise PathError(f"--save {save}: the directory {str(parent)!r} is not writable")
        probe_writable("--save", save, parent)
        if save.endswith(".zarr") and path.exists() and not path.is_dir():
            raise PathError(f"--save {save}: exists and is not a directory (a .zarr store is one)")
        if save.endswith(".nc") and path.is_dir():
            raise PathError(f"--save {save}: is a directory, not a file")
        if os.path.lexists(save) and not saved_by_run(save):
            raise PathError(f"--save {save}: exists and is not the output of an earlier ehd run "
                            "--save (a sweep store, a link or someone else's files), so it is "
                            "not replaced: give a new path, or move it away yourself")
    check_output_dir("--plot", plot, figures)
