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
import os
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


def _same_file(src: Path, dst: Path) -> bool:
    """``dst`` is a regular file (not a link) with the bytes of ``src``."""
    import stat

    try:
        return stat.S_ISREG(dst.lstat().st_mode) and filecmp.cmp(src, dst, shallow=False)
    except OSError:
        return False


def _refuse_unsafe(target: Path, plan) -> None:
    """PathError before anything is written, also with ``--force``: a link where a folder of
    ``target`` goes (writing through it would write outside DIR), or a folder where a shipped
    file goes (``ehd examples`` deletes nothing it did not make)."""
    from .errors import PathError

    for kind in FOLDERS:
        folder = target / kind
        if folder.is_symlink():
            raise PathError(f"{folder} is a symbolic link: ehd examples writes only inside DIR, "
                            "never through a link; remove the link, or choose another folder")
        if folder.exists() and not folder.is_dir():
            raise PathError(f"{folder} exists and is not a folder; move it away, or choose "
                            "another folder")
    for _, dst in plan:
        if dst.is_dir() and not dst.is_symlink():
            raise PathError(f"{dst} is a folder where a shipped file goes; ehd examples never "
                            "deletes a folder (not with --force either): move it away, or "
                            "choose another folder")


def copy_examples(target: str | Path, force: bool = False) -> list[Path]:
    """Copy the shipped files into ``target/examples`` and ``target/sweeps`` (the clone's
    layout, so the README's commands run as written from ``target``). A different file already
    there (or a link, a FIFO...) is kept unless ``force``: ``FileExistsError`` names it; with
    ``force`` it is replaced by the shipped file (a link itself, never what it points to). A
    link in place of ``examples``/``sweeps`` or a folder in place of a file is refused
    (``PathError``). The files are written all or none (``writes.write_all``): a failed write
    (a full disk) leaves no file changed and no partial copy. Returns the files written."""
    target = Path(target)
    plan = [(src, target / kind / src.name) for kind in FOLDERS for src in _files(kind)]
    if not plan:
        raise FileNotFoundError("this installation carries no example or sweep files; "
                                "reinstall ehd-collision (pip install ehd-collision)")
    _refuse_unsafe(target, plan)
    todo = [(src, dst) for src, dst in plan if not _same_file(src, dst)]
    clash = [dst for _, dst in todo if os.path.lexists(dst)]
    if clash and not force:
        raise FileExistsError(f"{clash[0]} exists and differs from the shipped file"
                              + (f" (and {len(clash) - 1} more)" if len(clash) > 1 else "")
                              + "; use --force to overwrite, or another folder")
    from .writes import write_all

    return write_all({dst: src.read_bytes() for src, dst in todo}, f"DIR {target}")


def cmd_examples(args) -> int:
    from .cli_shared import check_output_dir
    from .errors import PathError

    check_output_dir("DIR", args.dir)
    for kind in FOLDERS:  # a read-only DIR/examples or DIR/sweeps too (it was exit 74)
        check_output_dir("DIR", str(Path(args.dir) / kind))
    try:
        copy_examples(args.dir, force=args.force)
    except (FileExistsError, FileNotFoundError) as exc:
        raise PathError(str(exc)) from None
    for kind in FOLDERS:
        names = [p.name for p in _files(kind)]
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
