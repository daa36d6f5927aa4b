"""The files shipped with the package: the example scenes and the sweep files, and ``ehd
examples DIR``, which copies them out.

One copy of each file lives in the clone's top-level ``examples/`` and ``sweeps/`` folders (the
README and ``make sweep`` use them). A wheel carries them under ``pipeline/shipped_data/``
(copied there at build time by ``setup.py``); an editable install or a clone on ``PYTHONPATH``
reads the top-level folders. A named sweep (``ehd sweep paper``) is ``sweeps/paper.toml`` of
whichever copy this is. Imports nothing heavy.
"""

from __future__ import annotations

import filecmp
import shutil
from pathlib import Path

__all__ = ["FOLDERS", "folder", "sweep_names", "resolve_sweep", "copy_examples", "register"]

FOLDERS = ("examples", "sweeps")  # setup.py: SHIPPED
_SUFFIXES = (".toml", ".py")
_HERE = Path(__file__).resolve().parent


def folder(kind: str) -> Path | None:
    """The folder of shipped ``kind`` files ("examples" or "sweeps"): the wheel's copy, else the
    clone's top-level folder; None if neither exists (a broken install)."""
    if kind not in FOLDERS:
        raise ValueError(f"unknown kind {kind!r}; one of {', '.join(FOLDERS)}")
    for candidate in (_HERE / "shipped_data" / kind, _HERE.parent / kind):
        if candidate.is_dir() and any(candidate.glob("*.toml")):
            return candidate
    return None


def _files(kind: str) -> list[Path]:
    where = folder(kind)
    if where is None:
        return []
    return sorted(p for p in where.iterdir() if p.is_file() and p.suffix in _SUFFIXES)


def sweep_names() -> list[str]:
    """Names of the shipped sweep files (``paper``, ``quick``, ...)."""
    return [p.stem for p in _files("sweeps") if p.suffix == ".toml"]


def resolve_sweep(text: str) -> str:
    """``SWEEP_FILE`` as given: an existing path is itself; a bare name without a folder or
    suffix (``paper``) is the shipped ``sweeps/paper.toml``, and a bare name that is neither a
    UsageError listing the shipped names; any other path is returned unchanged (reading it names
    the problem)."""
    path = Path(text)
    if path.exists() or path.suffix or len(path.parts) != 1:
        return text
    where = folder("sweeps")
    if where is not None and (where / f"{text}.toml").is_file():
        return str(where / f"{text}.toml")
    from .errors import UsageError

    raise UsageError(f"no sweep file {text!r} here and no shipped sweep of that name (shipped: "
                     f"{', '.join(sweep_names()) or 'none'}); give a path, e.g. sweeps/paper.toml")


def copy_examples(target: str | Path, force: bool = False) -> list[Path]:
    """Copy the shipped files into ``target/examples`` and ``target/sweeps`` (the clone's
    layout, so the README's commands run as written from ``target``). A different file already
    there is kept unless ``force``: ``FileExistsError`` names it."""
    target = Path(target)
    plan = [(src, target / kind / src.name) for kind in FOLDERS for src in _files(kind)]
    if not plan:
        raise FileNotFoundError("this installation carries no example or sweep files; "
                                "reinstall ehd-collision (pip install ehd-collision)")
    clash = [dst for src, dst in plan
             if dst.exists() and not (dst.is_file() and filecmp.cmp(src, dst, shallow=False))]
    if clash and not force:
        raise FileExistsError(f"{clash[0]} exists and differs from the shipped file"
                              + (f" (and {len(clash) - 1} more)" if len(clash) > 1 else "")
                              + "; use --force to overwrite, or another folder")
    written = []
    for src, dst in plan:
        dst.parent.mkdir(parents=True, exist_ok=True)
        if dst.is_dir():
            shutil.rmtree(dst)
        shutil.copyfile(src, dst)
        written.append(dst)
    return written


def cmd_examples(args) -> int:
    from .cli_shared import check_output_dir
    from .errors import PathError

    check_output_dir("DIR", args.dir)
    try:
        written = copy_examples(args.dir, force=args.force)
    except (FileExistsError, FileNotFoundError) as exc:
        raise PathError(str(exc)) from None
    for kind in FOLDERS:
        names = [p.name for p in written if p.parent.name == kind]
        print(f"{Path(args.dir) / kind}: {', '.join(names)}")
    print(f"then, from {args.dir}: ehd scene examples/sandstone_water.toml; "
          "ehd sweep sweeps/quick.toml (or by name: ehd sweep quick)")
    return 0


def register(sub) -> None:
    p = sub.add_parser(
        "examples", description="Copy the example scene files and the sweep files shipped with "
        "ehd-collision into DIR/examples and DIR/sweeps, so the README's commands run as written "
        "from DIR. A shipped sweep also runs by name without copying: ehd sweep paper.")
    p.add_argument("dir", metavar="DIR", help="folder to copy into (created if missing)")
    p.add_argument("--force", action="store_true",
                   help="overwrite files in DIR that differ from the shipped ones")
    p.set_defaults(func=cmd_examples)
