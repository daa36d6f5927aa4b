"""The user's input and the user's data (issue 27): nothing of the user's destroyed, no input
read without bound, no user error accepted silently or reported as a bug.

Each reproduction of the issue is a case here, with its documented exit code and one line on
stderr (or the right result). In-process runs use ``pipeline.cli.main`` (tests/test_hostile.py's
``ehd``); a case that would hang or exhaust memory if it regressed runs in a subprocess with a
time limit and an address-space limit instead.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from pipeline.errors import EXIT_USAGE, EXIT_WRITE
from tests.test_hostile import base, ehd, tree_hash, ws  # noqa: F401 - fixtures

REPO = Path(__file__).resolve().parents[1]
EXAMPLE = REPO / "examples" / "glass_beads_water.toml"
SANDSTONE = REPO / "examples" / "sandstone_water.toml"


def one_error_line(err: str, *keywords) -> str:
    """The one line on stderr, with no traceback, holding every keyword."""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    for keyword in keywords:
        assert keyword in lines[0], err
    return lines[0]


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))  # a regression cannot eat the box


def ehd_subprocess(*args, stdout=subprocess.PIPE, timeout=60, env=None, **kw):
    """``ehd ARGS`` in a child with a time and an address-space limit (a hang or an unbounded
    read fails the test instead of the machine)."""
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1", **(env or {})}
    kw.setdefault("preexec_fn", _limit_memory)
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *map(str, args)], env=env,
                          stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=timeout,
                          **kw)


def no_solve(monkeypatch):
    """Any solve fails the test (the refusals come before)."""
    import solver

    monkeypatch.setattr(solver, "collide", lambda *a, **k: pytest.fail("solved"))


# ---- 6. unbounded reads: FIFOs and devices refused unread, sizes bounded -----------------------
@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "pipe.toml"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("args, label", [
    (["scene", "{fifo}"], "scene file"),
    (["scene", "/dev/zero"], "scene file"),
    (["scene", EXAMPLE, "--materials", "/dev/zero"], "materials file"),
    (["scene", EXAMPLE, "--materials", "{fifo}"], "materials file"),
    (["sweep", "{fifo}"], "sweep file"),
    (["sweep", "quick", "--scheduler-file", "/dev/zero"], "--scheduler-file"),
    (["sweep", "quick", "--scheduler-file", "{fifo}"], "--scheduler-file"),
    (["restitution", "{fifo}"], "scene file"),
], ids=["scene-fifo", "scene-dev-zero", "materials-dev-zero", "materials-fifo", "sweep-fifo",
        "scheduler-file-dev-zero", "scheduler-file-fifo", "restitution-fifo"])
def test_a_fifo_or_a_device_is_refused_unread(tmp_path, fifo, args, label):
    proc = ehd_subprocess(*(str(a).format(fifo=fifo) for a in args), cwd=tmp_path)
    assert proc.returncode == EXIT_USAGE, proc.stderr
    line = one_error_line(proc.stderr, label, "not a regular file")
    assert "FIFO" in line or "character device" in line


def test_an_input_file_larger_than_the_limit_is_refused(tmp_path, capsys, monkeypatch):
    from pipeline.reads import MAX_INPUT_BYTES

    big = tmp_path / "big.toml"
    with open(big, "wb") as f:  # sparse: no disk used
        f.truncate(MAX_INPUT_BYTES + 1)
    no_solve(monkeypatch)
    for args in (["scene", big], ["scene", EXAMPLE, "--materials", big], ["sweep", big]):
        code, _, err = ehd(capsys, *args)
        assert code == EXIT_USAGE
        one_error_line(err, str(big), "larger than 1.0 MiB")
    exact = tmp_path / "exact.toml"  # at the limit: read (and then refused as TOML, not size)
    exact.write_bytes(b"#" * MAX_INPUT_BYTES)
    code, _, err = ehd(capsys, "scene", exact)
    assert code == EXIT_USAGE and "larger than" not in err


def test_a_proc_file_without_a_size_is_read_to_the_limit_only(tmp_path):
    """A file whose size the file system does not report (st_size 0) is still bounded."""
    from pipeline.errors import UsageError
    from pipeline.reads import read_input

    status = Path("/proc/self/status")
    if not status.exists() or status.stat().st_size != 0:
        pytest.skip("needs Linux /proc")
    assert b"Name:" in read_input(status, "a file")
    with pytest.raises(UsageError, match="larger than"):
        read_input(status, "a file", limit=16)


# ---- 3. --save replaces only its own earlier output ------------------------------------------
def _foreign_folder(ws):
    (ws / "results" / "quick.zarr").mkdir(parents=True)
    (ws / "results" / "quick.zarr" / "notes.txt").write_text("mine")


def _sweep_store(ws):
    (ws / "results").mkdir()
    (ws / "s.zarr").rename(ws / "results" / "quick.zarr")


def _foreign_file(ws):
    (ws / "results").mkdir()
    (ws / "results" / "quick.nc").write_bytes(b"CDF\x01 not from ehd")


def _foreign_dataset(ws):
    import xarray as xr

    (ws / "results").mkdir()
    xr.Dataset(attrs={"title": "a colleague's"}).to_netcdf(ws / "results" / "quick.nc",
                                                         engine="scipy")


def _link(ws):
    (ws / "results").mkdir()
    (ws / "results" / "quick.zarr").symlink_to(ws / "s.zarr")


@pytest.mark.parametrize("make, target", [
    (_sweep_store, "results/quick.zarr"), (_foreign_folder, "results/quick.zarr"),
    (_foreign_file, "results/quick.nc"), (_foreign_dataset, "results/quick.nc"),
    (_link, "results/quick.zarr"),
], ids=["sweep-store", "foreign-folder", "foreign-file", "foreign-dataset", "link"])
def test_save_never_replaces_what_ehd_run_did_not_write(ws, capsys, monkeypatch, make, target):
    make(ws)
    before = tree_hash(ws)
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--save", target)
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, f"--save {target}", "not replaced", "give a new path")
    assert tree_hash(ws) == before  # every file as it was, the linked store too


@pytest.mark.parametrize("name", ["r.zarr", "r.nc"])
def test_save_replaces_its_own_earlier_output(tmp_path, capsys, monkeypatch, name):
    import xarray as xr

    from pipeline.cli_shared import SAVED_BY, SAVED_BY_KEY

    monkeypatch.chdir(tmp_path)
    for st in ("5", "6"):
        code, out, err = ehd(capsys, "run", "--St", st, "--eps", "0.01", "--accuracy", "fast",
                             "--save", name)
        assert code == 0, err
    engine = "zarr" if name.endswith(".zarr") else "scipy"
    with xr.open_dataset(tmp_path / name, engine=engine) as ds:
        assert ds.attrs[SAVED_BY_KEY] == SAVED_BY and ds.attrs["St"] == 6.0  # the second run's
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary left


# ---- 8. names longer than the file system takes: exit 2 before any work ------------------------
# (a store and --save make names up to ~12 bytes longer next to theirs: a lock, a temporary; a
# --plot folder holds short names, so only a name over 255 bytes is refused there)
@pytest.mark.parametrize("flag, length", [("--save", 251), ("--save", 255), ("--save", 256),
                                          ("--store", 251), ("--store", 255), ("--store", 256),
                                          ("--plot", 256)])
def test_a_name_too_long_for_the_file_system_is_exit_2(ws, capsys, monkeypatch, flag, length):
    from tests.test_hostile import CALLS

    name = "s" * (length - 5) + ".zarr"
    no_solve(monkeypatch)
    before = set(ws.iterdir())
    argv = {"--save": ["run", "--St", "5", "--eps", "0.01", "--save", name],
            "--plot": ["run", "--St", "5", "--eps", "0.01", "--plot", f"{name}/figs"],
            "--store": ["sweep", "s.toml", "--executor", "serial", "--store", name]}[flag]
    code, _, err = ehd(capsys, *argv)
    assert code == EXIT_USAGE, err
    one_error_line(err, flag, f"is {length} bytes", "choose a shorter name")
    assert set(ws.iterdir()) == before and CALLS == []


def test_a_sweep_file_store_name_too_long_is_exit_2(ws, capsys):
    from tests.test_pipeline import sweep_text

    (ws / "long.toml").write_text(sweep_text([5.0], [0.01], store="s" * 248 + ".zarr"))
    code, _, err = ehd(capsys, "sweep", "long.toml", "--executor", "serial")
    assert code == EXIT_USAGE
    one_error_line(err, "store ", "is 253 bytes")


# ---- 8. --version and --help into a full or closed stdout --------------------------------------
@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("args", [["--version"], ["--help"], ["run", "--help"]],
                         ids=["version", "help", "run-help"])
def test_version_and_help_into_a_full_stdout_are_exit_74(tmp_path, args):
    with open("/dev/full", "w") as full:
        proc = ehd_subprocess(*args, stdout=full, cwd=tmp_path)
    assert proc.returncode == EXIT_WRITE, proc.stderr
    one_error_line(proc.stderr, "cannot write to stdout", "No space left on device")


@pytest.mark.parametrize("args", [["--version"], ["--help"], ["scene", "--help"]],
                         ids=["version", "help", "scene-help"])
def test_version_and_help_into_a_closed_stdout_are_exit_74(tmp_path, args):
    proc = ehd_subprocess(*args, stdout=None, cwd=tmp_path,
                          preexec_fn=lambda: (_limit_memory(), os.close(1)))
    assert proc.returncode == EXIT_WRITE, proc.stderr
    one_error_line(proc.stderr, "stdout is closed")  # and not the help text instead


def test_version_and_help_into_an_open_stdout_still_print(tmp_path):
    proc = ehd_subprocess("--version", cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.startswith("ehd-collision ") and not proc.stderr
    proc = ehd_subprocess("--help", cwd=tmp_path)
    assert proc.returncode == 0 and "usage: ehd" in proc.stdout and not proc.stderr


# ---- 8. a report on an ASCII stdout --------------------------------------------------------------
@pytest.mark.parametrize("args", [["scene", EXAMPLE, "--accuracy", "fast"],
                                  ["scene", "--list-materials"]], ids=["report", "materials"])
def test_a_report_on_an_ascii_stdout_uses_ascii_spellings(tmp_path, args):
    proc = ehd_subprocess(*args, cwd=tmp_path, timeout=300, env={"PYTHONIOENCODING": "ascii"})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.isascii() and "Traceback" not in proc.stderr
    assert " um" in proc.stdout or "mPa*s" in proc.stdout  # µm, mPa·s spelled in ASCII


def test_ascii_spellings():
    from pipeline.cli import ascii_spelling

    assert ascii_spelling("25 µm, 1 mPa·s, 3×10⁶ µm³, 2 m⁻²") == \
        "25 um, 1 mPa*s, 3x10^6 um^3, 2 m^-2"
    assert ascii_spelling("Glas ö") == "Glas ?"  # anything else: replaced, never a crash
    assert ascii_spelling("25 µm", "latin-1") == "25 um"


# ---- 3. ehd examples: only inside DIR, never through a link, no folder deleted, all or none -------
def _shipped(kind, name):
    return (REPO / kind / name).read_bytes()


def test_examples_force_replaces_a_link_never_what_it_points_to(tmp_path, capsys):
    outside = tmp_path / "outside.toml"
    outside.write_text("my own scene\n")
    target = tmp_path / "dir"
    (target / "examples").mkdir(parents=True)
    link = target / "examples" / "sandstone_water.toml"
    link.symlink_to(outside)
    code, _, err = ehd(capsys, "examples", target)
    assert code == EXIT_USAGE
    one_error_line(err, str(link), "--force")
    code, _, err = ehd(capsys, "examples", target, "--force")
    assert code == 0, err
    assert outside.read_text() == "my own scene\n"  # nothing written outside DIR
    assert not link.is_symlink() and link.read_bytes() == _shipped("examples", link.name)


def test_examples_never_writes_through_a_linked_folder(tmp_path, capsys):
    outside = tmp_path / "outside"
    outside.mkdir()
    target = tmp_path / "dir"
    target.mkdir()
    (target / "sweeps").symlink_to(outside)
    for force in ([], ["--force"]):
        code, _, err = ehd(capsys, "examples", target, *force)
        assert code == EXIT_USAGE
        one_error_line(err, str(target / "sweeps"), "symbolic link")
    assert list(outside.iterdir()) == [] and sorted(p.name for p in target.iterdir()) == ["sweeps"]


def test_examples_never_deletes_a_folder_where_a_file_goes(tmp_path, capsys):
    target = tmp_path / "dir"
    mine = target / "sweeps" / "quick.toml"
    mine.mkdir(parents=True)
    (mine / "results.txt").write_text("a week of work")
    code, _, err = ehd(capsys, "examples", target, "--force")
    assert code == EXIT_USAGE
    one_error_line(err, str(mine), "never deletes a folder")
    assert (mine / "results.txt").read_text() == "a week of work"
    assert sorted(p.relative_to(target) for p in target.rglob("*")) == \
        [Path("sweeps"), Path("sweeps/quick.toml"), Path("sweeps/quick.toml/results.txt")]


def test_examples_on_a_full_disk_names_the_destination_and_changes_nothing(tmp_path, capsys,
                                                                            monkeypatch):
    """The third file meets a full disk half-way: no file of DIR changed (the user's edited
    one kept, with --force), no temporary or new folder left, and the line names the file in
    DIR, not the installed source."""
    import builtins
    import errno

    import pipeline.writes as writes

    target = tmp_path / "dir"
    mine = target / "examples" / "glass_beads_water.toml"
    mine.parent.mkdir(parents=True)
    mine.write_text("# my edits\n")
    before = {p: p.read_bytes() if p.is_file() else None for p in target.rglob("*")}
    opened = []

    class HalfFull:
        def __init__(self, f):
            self.f = f

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

        def write(self, data):
            self.f.write(data[: len(data) // 2])
            self.f.flush()
            raise OSError(errno.ENOSPC, "No space left on device")

    def full_open(path, mode="r", *a, **k):
        f = builtins.open(path, mode, *a, **k)
        opened.append(path)
        return HalfFull(f) if "w" in mode and len(opened) == 3 else f

    monkeypatch.setattr(writes, "open", full_open, raising=False)
    code, _, err = ehd(capsys, "examples", target, "--force")
    assert code == EXIT_WRITE
    line = one_error_line(err, "No space left on device", "nothing partial")
    named = Path(opened[2]).name.split(".tmp-")[0].lstrip(".")
    assert str(target / "examples" / named) in line or str(target / "sweeps" / named) in line
    assert str(REPO) not in line and "site-packages" not in line
    after = {p: p.read_bytes() if p.is_file() else None for p in target.rglob("*")}
    assert after == before  # the edited file kept, nothing new (no temporary, no sweeps/)


def _mount_tmpfs(path, size) -> bool:
    import shutil

    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                          capture_output=True, timeout=10).returncode == 0


def test_examples_on_a_real_full_disk(tmp_path):
    """The issue's reproduction on a 12 KiB tmpfs (root only; the simulated case above holds
    everywhere)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if not _mount_tmpfs(disk, "12k"):
        pytest.skip("needs root and mount to make a small tmpfs")
    try:
        proc = ehd_subprocess("examples", disk / "dir", cwd=tmp_path)
        assert proc.returncode == EXIT_WRITE, proc.stderr
        line = one_error_line(proc.stderr, str(disk / "dir"), "No space left on device")
        assert str(REPO) not in line.replace(str(disk), "")  # the destination, not the source
        assert list(disk.iterdir()) == []  # no partial copy, no folder made
    finally:
        subprocess.run(["umount", str(disk)], capture_output=True, timeout=10)
