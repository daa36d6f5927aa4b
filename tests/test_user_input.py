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


# ---- 7. accepted errors: a typo in [pairs], a grid point the solver refuses, unused groups ------
PAIR = """[pairs.wet_rock]
materials = [{names}]
e_dry = 0.058
source = "test"
"""


def test_a_typo_in_a_pair_group_is_refused_with_the_near_name(tmp_path, capsys, monkeypatch):
    from pipeline.scenes.commands import load_scene

    typo = tmp_path / "typo.toml"
    typo.write_text(PAIR.format(names='"sandston", "quartz"'))
    no_solve(monkeypatch)
    for args in (["scene", SANDSTONE, "--materials", typo],
                 ["scene", "--list-materials", "--materials", typo]):
        code, out, err = ehd(capsys, *args)
        assert code == EXIT_USAGE and out == ""
        one_error_line(err, str(typo), "[pairs.wet_rock]", "'sandston'",
                       "did you mean 'sandstone'?")
    right = tmp_path / "right.toml"  # spelled right, the group gives the pair's e_dry
    right.write_text(PAIR.format(names='"sandstone", "quartz"'))
    scene = load_scene(str(SANDSTONE), materials=[str(right)], user_files=False)
    assert scene.e_dry == 0.058 and "wet_rock" in scene.e_dry_source


def test_an_unknown_material_or_fluid_suggests_the_near_name(capsys, monkeypatch):
    no_solve(monkeypatch)
    code, _, err = ehd(capsys, "scene", SANDSTONE, "--material1", "sandston")
    assert code == EXIT_USAGE
    one_error_line(err, "body1.material", "did you mean 'sandstone'?")
    code, _, err = ehd(capsys, "scene", SANDSTONE, "--fluid", "watr")
    assert code == EXIT_USAGE
    one_error_line(err, "fluid.name", "did you mean 'water'?")


def test_a_materials_file_with_other_tables_is_refused_naming_the_key(tmp_path, capsys):
    """A misspelt ``[material.x]`` table, or a scene file given as ``--materials``, was read as a
    file of no materials (exit 0 for ``--list-materials``; a scene then named an unknown
    material, pointing at itself): now one line names the key and the table it is near."""
    bad = tmp_path / "mine.toml"
    bad.write_text('[material.my_glass]\nyoungs_modulus = "63 GPa"\n')
    code, _, err = ehd(capsys, "scene", "--materials", str(bad), "--list-materials")
    assert code == EXIT_USAGE
    one_error_line(err, "mine.toml", "'material' (did you mean 'materials'?)")
    code, _, err = ehd(capsys, "scene", SANDSTONE, "--materials", SANDSTONE)
    assert code == EXIT_USAGE
    one_error_line(err, "unknown table or key 'body1'", "[materials.NAME]")


def test_for_dry_without_out_is_refused_as_cfd_dem_is(capsys, monkeypatch):
    """``--for`` chooses what the DEM export writes: given without ``--out`` it would do
    nothing, ``--for dry`` (the default's value) too, which was accepted."""
    no_solve(monkeypatch)
    for kind in ("dry", "cfd-dem"):
        code, _, err = ehd(capsys, "restitution", SANDSTONE, "--for", kind)
        assert code == EXIT_USAGE
        one_error_line(err, f"--for {kind}", "give --out DIR too")


def test_an_x0_beyond_the_default_outer_start_names_x0(capsys, monkeypatch):
    """x0 at 2 a with the default outer start (1 a): the line names x0 and its fix, not the
    outer start the scene never gave."""
    no_solve(monkeypatch)
    code, _, err = ehd(capsys, "scene", SANDSTONE, "--x0-over-a", "2")
    assert code == EXIT_USAGE
    one_error_line(err, "x0_over_a = ", "give a smaller x0_over_a, or an outer_start beyond it")


def test_a_commands_flag_before_the_command_says_to_name_the_command(capsys):
    """``ehd --St 10`` read 10 as the command ("invalid choice: '10'"): now one line saying
    that the flag belongs after a command."""
    code, _, err = ehd(capsys, "--St", "10")
    assert code == EXIT_USAGE
    one_error_line(err, "--St is no flag of ehd itself", "ehd COMMAND --St")
    code, _, err = ehd(capsys, "--version")  # ehd's own flags are untouched
    assert code == 0 and not err


def test_a_negative_first_value_of_a_two_value_flag_reaches_its_check(capsys, monkeypatch):
    """``--fit-range -1 10``: the -1 was joined to its flag (``--fit-range=-1``, as ``--Pi -inf``
    must be) and argparse said "expected 2 arguments"; now the range's own line."""
    no_solve(monkeypatch)
    code, _, err = ehd(capsys, "export-dem", SANDSTONE, "--fit-range", "-1", "10")
    assert code == EXIT_USAGE
    one_error_line(err, "--fit-range -1 10: give 0 <= LO < HI")
    code, _, err = ehd(capsys, "run", "--St", "-inf", "--eps", "0.01")  # still joined
    assert code == EXIT_USAGE
    one_error_line(err, "must be finite, got -inf")


def _rough_sweep(roughness, eps="[1e-4, 1e-2]", extra=""):
    return (f'name = "rough"\nstore = "rough.zarr"\n[grid]\nSt = [5.0, 20.0]\neps = {eps}\n'
            f"roughness = {roughness}\n{extra}\n[numerics]\naccuracy = \"fast\"\n")


def test_a_grid_point_the_solver_refuses_is_exit_2_before_any_solve(ws, capsys):
    """roughness >= x0/x1 = eps^-0.4 at some grid point (here roughness 10 at eps 1e-2, where
    x0/x1 = 6.31): refused with the solver's own message, nothing solved, no store made."""
    from tests.test_hostile import CALLS

    (ws / "rough.toml").write_text(_rough_sweep("[1.0, 10.0]"))
    code, _, err = ehd(capsys, "sweep", "rough.toml", "--executor", "serial")
    assert code == EXIT_USAGE
    one_error_line(err, "roughness=10", "eps=0.01", "must be smaller than the start gap")
    assert CALLS == [] and not (ws / "rough.zarr").exists()


@pytest.mark.parametrize("top, ok", [(6.3, True), (6.31, False)])
def test_the_grid_check_is_the_solvers_own(top, ok):
    """The edge is where Physics puts it: x0/x1 = 0.01^-0.4 = 6.3096 at the largest eps."""
    from pipeline.sweeps.config import ConfigError, parse_sweep
    from solver.physics import Physics

    text = _rough_sweep(f"[0.5, {top}]")
    try:
        Physics(St=5.0, eps=1e-2, roughness=top)
        solver_ok = True
    except ValueError:
        solver_ok = False
    assert solver_ok is ok
    if ok:
        assert parse_sweep(text).shape == (2, 2, 2)
    else:
        with pytest.raises(ConfigError, match="must be smaller than the start gap"):
            parse_sweep(text)


@pytest.mark.parametrize("args, flags", [
    (["--e-dry", "0.5"], ["--e-dry 0.5"]),
    (["--asperity-stiffness", "3"], ["--asperity-stiffness 3"]),
    (["--e-dry", "0.5", "--asperity-stiffness", "3"], ["--asperity-stiffness 3", "--e-dry 0.5"]),
], ids=["e-dry", "asperity-stiffness", "both"])
def test_run_contact_flags_without_roughness_are_exit_2(capsys, monkeypatch, args, flags):
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", *args)
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, *flags, "--roughness")


def test_contact_flags_with_roughness_are_accepted(monkeypatch):
    """The same flags with a roughness reach the solver (the check stops only the useless)."""
    import solver
    from pipeline.cli import main

    seen = []

    def stop(physics, **kwargs):
        seen.append(physics)
        raise KeyboardInterrupt

    monkeypatch.setattr(solver, "collide", stop)
    main(["run", "--St", "5", "--eps", "0.01", "--roughness", "1", "--e-dry", "0.5"])
    assert seen and seen[0].e_dry == 0.5 and seen[0].roughness == 1.0


@pytest.mark.parametrize("extra, ok", [
    ("[physics]\ne_dry = 0.5", False),
    ("[physics]\nasperity_stiffness = 3.0", False),
    ("e_dry = [0.5, 0.9]", False),  # an axis
    ("[physics]\ne_dry = 1.0", True),  # the default: nothing to refuse
], ids=["e_dry", "asperity_stiffness", "e_dry-axis", "default"])
def test_sweep_contact_groups_without_roughness_are_exit_2(tmp_path, extra, ok):
    from pipeline.sweeps.config import ConfigError, parse_sweep
    from tests.test_pipeline import sweep_text

    text = sweep_text([5.0], [0.01])
    if extra.startswith("e_dry ="):  # into [grid]
        text = text.replace("eps = [0.01]", f"eps = [0.01]\n{extra}")
    else:
        text = text.replace("[numerics]", f"{extra}\n[numerics]")
    if ok:
        parse_sweep(text)
    else:
        with pytest.raises(ConfigError, match="every grid point e_dry|every grid point asperity"):
            parse_sweep(text)


def test_a_sweep_with_smooth_and_rough_points_keeps_its_e_dry():
    from pipeline.sweeps.config import parse_sweep

    sweep = parse_sweep(_rough_sweep("[0.0, 1.0]", extra="[physics]\ne_dry = 0.5"))
    assert sweep.fixed["e_dry"] == 0.5 and sweep.axes["roughness"] == (0.0, 1.0)


@pytest.mark.parametrize("args", [
    [],  # beta 0 and no table: the classic, constant viscosity
    ["--beta", "1", "--viscosity", "constant"],  # a beta the law asked for does not use
], ids=["beta-0", "law-constant"])
def test_run_law_in_tension_with_a_constant_viscosity_is_exit_2(capsys, monkeypatch, args):
    """``--viscosity-in-tension law`` reads a pressure-dependent viscosity at negative pressure;
    with a constant viscosity it would do nothing (it was accepted and ignored)."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", *args,
                         "--viscosity-in-tension", "law")
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, "--viscosity-in-tension law", "constant viscosity", "--beta > 0",
                   "--viscosity-table")


def test_beta_beside_a_viscosity_table_is_exit_2(capsys, monkeypatch, ws):
    """A table gives the viscosity (``auto`` reads it): ``--beta`` then does nothing, and was
    accepted and reported with the table's result; a sweep's beta axis beside a table stored
    the same v_r at every beta (a hostile review)."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--beta", "1",
                         "--viscosity-table", "0:1, 1:2")
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, "--beta 1", "by a table", "leave --beta out")
    (ws / "t.toml").write_text(
        'name = "t"\nstore = "t.zarr"\n[grid]\nSt = [5.0]\neps = [0.01]\nbeta = [0.0, 1.0]\n'
        '[physics]\nviscosity_table = "0:1, 1:2"\n[numerics]\naccuracy = "fast"\n')
    code, _, err = ehd(capsys, "sweep", "t.toml")
    assert code == EXIT_USAGE and "beta" in err and "table" in err, err
    assert not (ws / "t.zarr").exists()


@pytest.mark.parametrize("args, law", [
    (["--beta", "1"], "barus"),
    (["--viscosity-table", "0:1, 1:3"], "table"),
], ids=["barus", "table"])
def test_run_law_in_tension_with_a_pressure_dependent_viscosity_is_accepted(monkeypatch, args,
                                                                            law):
    import solver
    from pipeline.cli import main

    seen = []

    def stop(physics, **kwargs):
        seen.append(physics)
        raise KeyboardInterrupt

    monkeypatch.setattr(solver, "collide", stop)
    main(["run", "--St", "5", "--eps", "0.01", *args, "--viscosity-in-tension", "law"])
    assert seen and (seen[0].viscosity_in_tension, seen[0].viscosity_law) == ("law", law)


@pytest.mark.parametrize("physics, grid, ok", [
    ('viscosity_in_tension = "law"', "", False),
    ('viscosity_in_tension = "law"\nbeta = 2.0\nviscosity_law = "constant"', "", False),
    ('viscosity_in_tension = "law"', "beta = [0.0, 2.0]", True),  # acts where beta is 2
    ('viscosity_in_tension = "law"\nbeta = 2.0', "", True),
], ids=["beta-0", "law-constant", "beta-axis", "barus"])
def test_sweep_law_in_tension_needs_a_pressure_dependent_viscosity(physics, grid, ok):
    from pipeline.sweeps.config import ConfigError, parse_sweep
    from tests.test_pipeline import sweep_text

    text = sweep_text([5.0], [0.01]).replace("[numerics]", f"[physics]\n{physics}\n[numerics]")
    text = text.replace("eps = [0.01]", f"eps = [0.01]\n{grid}")
    if ok:
        assert parse_sweep(text).fixed["viscosity_in_tension"] == "law"
    else:
        with pytest.raises(ConfigError, match="viscosity_in_tension reads the viscosity.s law"):
            parse_sweep(text)


@pytest.mark.parametrize("args, seen", [
    (["--x-ref", "1000"], "10 a"),  # x0 = 0.01 a: 10 a, beyond the outer start 1 a
    (["--x-ref", "60", "--x0-over-a", "0.05", "--outer-start-over-a", "2"], "3 a"),
], ids=["default-outer", "moved-outer"])
def test_run_x_ref_beyond_the_outer_start_is_exit_2(capsys, monkeypatch, args, seen):
    """``--x-ref`` (where e_wet is seen, over x0) beyond the outer start read e_wet on the film's
    lubrication resistance where the outer flow slows the spheres (accepted: e_wet 0.23)."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", *args)
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, f"--x-ref {args[1]}", seen, "beyond the outer start", "--x-ref-over-a")


@pytest.mark.parametrize("args, keywords", [
    (["--for", "cfd-dem"], ["--for cfd-dem", "--out DIR"]),
    (["--allow-invalid"], ["--allow-invalid", "--out DIR"]),
    (["--from", "2", "--to", "2", "--n", "3"], ["the same scene", "--n 1"]),
    (["--n", "1"], ["one point takes one factor"]),
], ids=["for-without-out", "allow-invalid-without-out", "one-factor-many-points",
        "one-point-a-range"])
def test_restitution_flags_that_would_do_nothing_are_exit_2(capsys, monkeypatch, args,
                                                            keywords):
    """Accepted before, and the output was byte for byte the same without them (--for and
    --allow-invalid choose what the export writes), or three rows of the same scene, or the
    range's first factor alone for --n 1 (a hostile scan)."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "restitution", EXAMPLE, *args)
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, *keywords)


GLYCEROL = REPO / "examples" / "steel_ball_glass_wall_glycerol.toml"


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
@pytest.mark.parametrize("args, flag", [
    (["scene", str(EXAMPLE), "--plot", "/proc/nope"], "--plot"),
    (["scene", str(GLYCEROL), "--trajectory", "/proc/t.csv"], "--trajectory"),
    (["run", "--St", "5", "--eps", "0.01", "--save", "/proc/x.nc"], "--save"),
    (["restitution", str(EXAMPLE), "--out", "/proc/nope"], "--out"),
    (["export-dem", str(EXAMPLE), "--out", "/proc/nope"], "--out"),
], ids=["scene-plot", "trajectory", "run-save", "restitution-out", "export-dem-out"])
def test_an_output_path_no_folder_can_be_made_in_is_exit_2_before_the_solve(capsys, monkeypatch,
                                                                            args, flag):
    """/proc lets root write by its permissions but makes no entry: the write failed with exit
    74 after the solve (a hostile scan); the documented exit is 2 before any solve."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, *args)
    assert code == EXIT_USAGE and out == ""
    line = one_error_line(err, flag, "'/proc'")  # root: the probe; anyone else: permissions
    assert "cannot write in" in line or "is not writable" in line, line


@pytest.mark.parametrize("args, taken", [
    (["run", "--St", "5", "--eps", "0.01", "--plot", "{out}"], "gap.png"),
    (["scene", str(GLYCEROL), "--trajectory", "{tmp}/t.csv", "--plot", "{out}"],
     "trajectory.pdf"),
    (["restitution", str(EXAMPLE), "--plot", "{out}"], "restitution.png"),
    (["export-dem", str(EXAMPLE), "--out", "{out}"], "restitution.csv"),
    (["paper-figures", "--out", "{out}"], "fig02_kernel.png"),
], ids=["run-plot", "scene-trajectory-plot", "restitution-plot", "export-dem-out",
        "paper-figures"])
def test_a_folder_where_a_figure_or_export_file_goes_is_exit_2_before_the_solve(
        tmp_path, capsys, monkeypatch, args, taken):
    """A folder named like a file ehd writes into --plot or --out was found only at the write,
    exit 74 after the solve (the results printed first); now before it, one line."""
    no_solve(monkeypatch)
    (tmp_path / "out" / taken).mkdir(parents=True)
    args = [a.format(out=tmp_path / "out", tmp=tmp_path) for a in args]
    code, out, err = ehd(capsys, *args)
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, f"{taken} is there and is not a file", "move it away")


def test_scene_e_dry_without_roughness_is_exit_2(capsys, monkeypatch):
    from pipeline.scenes.commands import load_scene

    no_solve(monkeypatch)
    smooth = ["--material1", "pmma", "--radius1", "50 um", "--wall", "--material2", "pmma",
              "--fluid", "water", "--v0", "1 m/s"]
    code, _, err = ehd(capsys, "scene", *smooth, "--e-dry", "0.5")
    assert code == EXIT_USAGE
    one_error_line(err, "e_dry", "neither body has a roughness")
    flags = {"material1": "pmma", "radius1": "50 um", "wall2": True, "material2": "pmma",
             "fluid": "water", "v0": "1 m/s", "e_dry": "0.5", "roughness1": "0.3 um"}
    assert load_scene(None, flags, user_files=False).e_dry == 0.5  # with a roughness: taken
    # with the contact switched off it would do nothing too (accepted, the JSON then said
    # e_dry 1 from "the scene's e_dry")
    code, _, err = ehd(capsys, "scene", *smooth, "--roughness1", "0.3 um", "--e-dry", "0.5",
                       "--asperity-contact", "off")
    assert code == EXIT_USAGE
    one_error_line(err, "e_dry", "asperity_contact is off", "--asperity-contact")


# ---- 8. user input that ended as a bug (exit 70) -------------------------------------------------
@pytest.mark.parametrize("make, keyword", [
    (lambda tmp: [str(tmp)], "no sweep store"),  # a folder that is no store
    (lambda tmp: [""], "empty path"),
    (lambda tmp: [str(EXAMPLE), "--n", "-1"], "--n -1"),
    (lambda tmp: [str(EXAMPLE), "--n", "0"], "--n 0"),
    (lambda tmp: ["s.zarr", "--density-ratio", "1e300"], "--density-ratio"),
    (lambda tmp: ["s.zarr", "--density-ratio", "nan"], "--density-ratio"),
    (lambda tmp: ["s.zarr", "--density-ratio", "-1"], "--density-ratio"),
    # a flag for the other kind of input, which it ignored (a hostile scan)
    (lambda tmp: ["s.zarr", "--n", "5"], "--n acts on a scene file"),
    (lambda tmp: [str(EXAMPLE), "--density-ratio", "0.4"], "--density-ratio acts on a store"),
], ids=["folder", "empty", "n-negative", "n-zero", "density-ratio-huge", "density-ratio-nan",
        "density-ratio-negative", "n-on-a-store", "density-ratio-on-a-scene"])
def test_export_dem_user_errors_are_exit_2(ws, tmp_path, capsys, make, keyword):
    folder = tmp_path / "plain"
    folder.mkdir()
    code, _, err = ehd(capsys, "export-dem", *make(folder), "--out", "dem")
    assert code == EXIT_USAGE
    one_error_line(err, keyword)
    assert not (ws / "dem").exists()


@pytest.mark.parametrize("spec, keyword", [
    ("roughness = {start = 0.0, stop = 1.0, num = 3}", "cannot reach 0"),
    ("roughness = {start = 0.1, stop = 0.0, num = 3}", "cannot reach 0"),
    ("Pi = {start = 1e-3, stop = inf, num = 3}", "cannot reach inf"),  # numpy's warning, then
    ("Pi = {start = inf, stop = inf, num = 1}", "cannot reach inf"),  # "repeated values" before
], ids=["start-0", "stop-0", "stop-inf", "both-inf"])
def test_a_log_range_from_zero_or_to_inf_is_exit_2(ws, capsys, spec, keyword):
    (ws / "z.toml").write_text(f'store = "z.zarr"\n[grid]\nSt = [5.0]\n{spec}\n'
                               "[physics]\neps = 0.01\n")
    code, _, err = ehd(capsys, "sweep", "z.toml", "--executor", "serial")
    assert code == EXIT_USAGE
    one_error_line(err, f"grid.{spec.split()[0]}", keyword, "as a list")


@pytest.mark.parametrize("numerics, keyword", [
    ('accuracy = ["fast"]', "accuracy must be the name of a preset"),
    ("accuracy = 3", "accuracy must be the name of a preset"),
], ids=["list", "number"])
def test_a_bad_accuracy_type_is_exit_2(ws, capsys, numerics, keyword):
    (ws / "a.toml").write_text(f'store = "a.zarr"\n[grid]\nSt = [5.0]\n[physics]\neps = 0.01\n'
                               f"[numerics]\n{numerics}\n")
    code, _, err = ehd(capsys, "sweep", "a.toml", "--executor", "serial")
    assert code == EXIT_USAGE
    one_error_line(err, keyword)
    (ws / "n.toml").write_text('store = "a.zarr"\nnumerics = 3\n[grid]\nSt = [5.0]\n'
                               "[physics]\neps = 0.01\n")
    code, _, err = ehd(capsys, "sweep", "n.toml", "--executor", "serial")
    assert code == EXIT_USAGE
    one_error_line(err, "[numerics] must be a table")


def test_restitution_threshold_with_a_failed_solve_is_exit_1(tmp_path, capsys, monkeypatch):
    """The path is solved; the bisection's first solve fails: the table, --out and the line
    saying which solve failed (exit 1, the documented code of a failed scene), no traceback."""
    import types

    import pipeline.scenes.run as run

    real, calls = run.run_scene, []

    def first_bisection_fails(scene, **kwargs):
        calls.append(scene.v0)
        if len(calls) <= 5:  # the path's 5 speeds
            return real(scene, **kwargs)
        return types.SimpleNamespace(collision=types.SimpleNamespace(
            ok=False, status="max_steps", message="step budget exhausted (stand-in)"))

    monkeypatch.setattr(run, "run_scene", first_bisection_fails)
    monkeypatch.chdir(tmp_path)
    code, out, err = ehd(capsys, "restitution", EXAMPLE, "--accuracy", "fast", "--n", "5",
                         "--threshold", "--out", "dem")
    assert code == 1, err
    one_error_line(err, "no sticking threshold", "failed (max_steps)", "step budget exhausted")
    assert "sticking threshold in e_far (dry DEM): not found" in out and "sticks" in out
    assert (tmp_path / "dem" / "restitution.csv").exists()  # the rest was written


@pytest.mark.parametrize("args", [["--from", "inf"], ["--to", "nan"], ["--from", "0"]])
def test_restitution_path_factors_must_be_finite_and_positive(capsys, monkeypatch, args):
    no_solve(monkeypatch)
    code, _, err = ehd(capsys, "restitution", EXAMPLE, *args)
    assert code == EXIT_USAGE
    one_error_line(err, "--from and --to")


# ---- the second hostile run (issue 27's "done when") -------------------------------------------
@pytest.mark.parametrize("args", [
    ["restitution", str(EXAMPLE), "--accuracy", "bogus"],
    ["restitution", str(EXAMPLE), "--accuracy", "", "--threshold"],
    ["export-dem", str(EXAMPLE), "--accuracy", "FAST", "--out", "x"],
], ids=["restitution", "restitution-threshold", "export-dem"])
def test_an_unknown_accuracy_is_exit_2_before_any_solve(ws, capsys, monkeypatch, args):
    """A traceback (exit 70) from the solver's check in the second hostile run."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, *args)
    assert code == EXIT_USAGE
    one_error_line(err, "--accuracy must be one of", "standard")


def test_a_failed_plot_removes_only_the_files_it_wrote(tmp_path, capsys, monkeypatch):
    """``--plot DIR`` cut short (here SIGTERM's exception after one figure): the figure it wrote
    goes, a user's file that changed in DIR meanwhile stays (the second hostile run: a thesis
    chapter edited under ``--plot`` during the plot was deleted)."""
    import pipeline.plots.scene_plots as scene_plots
    from pipeline.errors import EXIT_TERMINATED, Terminated

    folder = tmp_path / "pk"
    mine = folder / "mywork" / "thesis.txt"
    mine.parent.mkdir(parents=True)
    mine.write_text("chapter 1\n")
    real = scene_plots.save_figure

    def one_then_terminated(fig, out_dir, stem):
        real(fig, out_dir, stem)
        with mine.open("a") as f:  # the user edits a file meanwhile
            f.write("chapter 2\n")
        (folder / "notes.txt").write_text("new")  # and makes another
        raise Terminated()

    monkeypatch.setattr(scene_plots, "save_figure", one_then_terminated)
    code, _, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--accuracy", "fast",
                       "--plot", str(folder))
    assert code == EXIT_TERMINATED
    assert mine.read_text() == "chapter 1\nchapter 2\n"
    assert sorted(p.name for p in folder.iterdir()) == ["mywork", "notes.txt"]


def test_the_free_space_of_a_full_folder_is_its_own_file_systems(tmp_path, monkeypatch):
    """A folder may be a mount point (a full tmpfs given as ``--plot DIR``): its free space is
    asked of the folder itself, not of its parent's file system (the second hostile run: 73.5
    GiB said free where the tmpfs had 12 KiB)."""
    import errno
    import shutil
    from collections import namedtuple

    from pipeline.errors import describe_os_error

    asked = []
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: asked.append(p) or usage(1, 1, 12288))
    full = OSError(errno.ENOSPC, "No space left on device")
    folder = tmp_path / "figs"
    folder.mkdir()
    assert "12.0 KiB free" in describe_os_error(full, folder)
    assert asked[-1] == str(folder)
    describe_os_error(full, folder / "fig.png")  # a file: its folder's file system
    assert asked[-1] == str(folder)


@pytest.mark.parametrize("args, keywords", [
    (["--cavitation", "jfo"], ["--cavitation jfo", "--Pi"]),
    (["--Pi", "1e-3", "--cavitation", "off"], ["--Pi 0.001", "--cavitation"]),
    (["--beta", "2", "--viscosity", "constant"], ["--beta 2", "--viscosity"]),
    (["--viscosity", "barus"], ["--viscosity barus", "--beta"]),
    (["--roelands-Z", "0.5"], ["--roelands-Z 0.5", "roelands"]),
    (["--dh-c1", "5"], ["--dh-c1 5", "--density"]),
], ids=["jfo-without-Pi", "Pi-with-cavitation-off", "beta-with-constant", "barus-without-beta",
        "roelands-Z-without-roelands", "dh-c1-without-dowson-higginson"])
def test_run_flags_whose_physics_is_off_are_exit_2(capsys, monkeypatch, args, keywords):
    """A flag that would silently do nothing (the second hostile run: ``--cavitation jfo``
    without ``--Pi`` ran the classic film, ``--roelands-Z`` and ``--dh-c1`` were echoed in the
    JSON as if applied) is refused before any solve, with the flag that switches it on."""
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", *args)
    assert code == EXIT_USAGE and out == ""
    one_error_line(err, *keywords)


@pytest.mark.parametrize("extra, keyword", [
    ('[physics]\ncavitation = "off"\n', "Pi"),
    ('[physics]\nviscosity_law = "constant"\n', "beta"),
], ids=["Pi-axis-with-cavitation-off", "beta-axis-with-constant-viscosity"])
def test_a_sweep_axis_that_changes_nothing_is_refused(extra, keyword):
    """A grid axis whose physics is off at every point stored identical cells (the second
    hostile run)."""
    from pipeline.sweeps.config import ConfigError, parse_sweep

    axis = {"Pi": "Pi = [1e-3, 1e-2]", "beta": "beta = [1.0, 2.0]"}[keyword]
    text = f'name = "t"\nstore = "t.zarr"\n[grid]\nSt = [5.0]\neps = [1e-2]\n{axis}\n{extra}'
    with pytest.raises(ConfigError, match=keyword):
        parse_sweep(text)


def test_a_default_materials_file_that_is_no_file_is_refused(tmp_path, capsys, monkeypatch, fifo):
    """``~/.config/ehd/materials.toml`` (or under ``$XDG_CONFIG_HOME``) that is a FIFO or a
    folder was skipped without a word (the second hostile run), while the same given by
    ``--materials`` is refused: now refused the same way."""
    config = tmp_path / "config"
    (config / "ehd").mkdir(parents=True)
    os.mkfifo(config / "ehd" / "materials.toml")
    monkeypatch.setenv("XDG_CONFIG_HOME", str(config))
    no_solve(monkeypatch)
    code, out, err = ehd(capsys, "scene", str(EXAMPLE))
    assert code == EXIT_USAGE
    one_error_line(err, "materials.toml", "FIFO")
