"""Hostile inputs and faults (issue 9): every command, a catalogue of bad inputs and damaged
stores, one clear line and the documented exit code, nothing previously stored changed.

The matrix runs ``pipeline.cli.main`` in this process (no subprocess start-up) with the sweep's
solver replaced by the stand-in of tests/test_pipeline.py, so no case solves a real scene. The
fault tests (Ctrl-C, a scheduler killed mid-sweep) run ``ehd sweep`` in a subprocess.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import pipeline.sweeps.run as run_module
from pipeline.cli import main
from pipeline.errors import (EXIT_DAMAGED, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_SCHEDULER_LOST,
                             EXIT_USAGE)
from pipeline.sweeps.config import load_sweep
from pipeline.sweeps.store import StoreBusy, SweepStore
from tests.test_pipeline import CALLS, fake_solve, sweep_text

REPO = Path(__file__).resolve().parents[1]
ST, EPS = [1.0, 3.0, 5.0, 20.0], [1e-4, 1e-2]
EXAMPLE = REPO / "examples" / "glass_beads_water.toml"


# ---- a healthy store, built once; every case works on its own copy ------------------------------
@pytest.fixture(scope="module")
def base(tmp_path_factory):
    d = tmp_path_factory.mktemp("base")
    (d / "s.toml").write_text(sweep_text(ST, EPS, store="s.zarr"))
    cwd = os.getcwd()
    os.chdir(d)
    try:
        run_module.run_sweep(load_sweep("s.toml"), runner="serial", solve=fake_solve,
                             progress=None)
    finally:
        os.chdir(cwd)
    return d


@pytest.fixture
def ws(base, tmp_path, monkeypatch):
    """A working folder (the current directory) with ``s.toml`` and its store ``s.zarr``; the
    sweep's solver is the stand-in."""
    shutil.copy(base / "s.toml", tmp_path / "s.toml")
    shutil.copytree(base / "s.zarr", tmp_path / "s.zarr")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(run_module, "run_sweep",
                        functools.partial(run_module.run_sweep, solve=fake_solve, warm_up=False,
                                          progress=None))
    CALLS.clear()
    return tmp_path


def tree_hash(path) -> str:
    """sha256 over every file under ``path`` (relative name and bytes)."""
    h = hashlib.sha256()
    path = Path(path)
    for f in sorted(p for p in path.rglob("*") if p.is_file()):
        h.update(str(f.relative_to(path)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def ehd(capsys, *args):
    """``(exit code, stdout, stderr)`` of ``ehd ARGS`` run in this process."""
    capsys.readouterr()
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


# ---- the catalogue: how to make each bad input -----------------------------------------------------
def _write(name, data):
    def make(ws):
        p = ws / name
        p.parent.mkdir(parents=True, exist_ok=True)
        (p.write_bytes if isinstance(data, bytes) else p.write_text)(data)
    return make


def _binary(name):
    return _write(name, bytes(np.random.default_rng(0).integers(0, 256, 3000, dtype=np.uint8)))


def _mkdir(name):
    return lambda ws: (ws / name).mkdir(parents=True)


def _truncate(rel, size=5):
    def make(ws):
        with open(ws / rel, "r+b") as f:
            f.truncate(size)
    return make


def _remove(rel):
    return lambda ws: (ws / rel).unlink()


def _other_sweep(ws):
    (ws / "other.toml").write_text(sweep_text([7.0], EPS, store="s.zarr").replace(
        'name = "test"', 'name = "other"'))


def _other_numerics(ws):
    (ws / "num.toml").write_text(sweep_text(ST, EPS, store="s.zarr", extra="rtol = 1e-3"))


def _huge(ws):
    (ws / "huge.toml").write_text(sweep_text("{start = 1.0, stop = 50.0, num = 100000000}", EPS))


def _schema(ws):
    meta = json.loads((ws / "s.zarr" / "zarr.json").read_text())
    meta["attributes"]["store_schema"] = 2
    (ws / "s.zarr" / "zarr.json").write_text(json.dumps(meta))


def _nothing_done(ws):
    (ws / "e.toml").write_text(sweep_text(ST, EPS, store="e.zarr"))
    with SweepStore.open(load_sweep(ws / "e.toml")):
        pass  # an empty store: laid out, no scene run


def _closed_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


NO_SETUP = None
# (case id, setup, argv, exit code, keyword of the one error line)
CASES = [
    # --- ehd sweep: the sweep file
    ("sweep-binary-file", _binary("g.toml"), ["sweep", "g.toml"], 2, "not a text file"),
    ("sweep-latin1-file", _write("l.toml", "name = 'caf\xe9'\n".encode("latin-1")),
     ["sweep", "l.toml"], 2, "UTF-8"),
    ("sweep-nul-bytes", _write("n.toml", b"name = 'x'\x00\n"), ["sweep", "n.toml"], 2, "NUL"),
    ("sweep-file-is-dir", _mkdir("d.toml"), ["sweep", "d.toml"], 2, "cannot read"),
    ("sweep-file-missing", NO_SETUP, ["sweep", "none.toml"], 2, "cannot read"),
    ("sweep-not-toml", _write("t.toml", "name = [\n"), ["sweep", "t.toml"], 2, "TOML"),
    ("sweep-empty-file", _write("empty.toml", ""), ["sweep", "empty.toml"], 2, "store"),
    ("sweep-huge-grid", _huge, ["sweep", "huge.toml"], 2, "at most"),
    ("sweep-bad-range", _write("r.toml", sweep_text(ST, [0.5])), ["sweep", "r.toml"], 2,
     "grid.eps"),
    # --- ehd sweep: the store path
    ("sweep-store-empty", NO_SETUP, ["sweep", "s.toml", "--store", ""], 2, "empty path"),
    # a folder named by its place: Path.with_name raised ValueError (exit 70)
    ("sweep-store-dot", NO_SETUP, ["sweep", "s.toml", "--store", "."], 2, "by its place"),
    ("sweep-store-root", NO_SETUP, ["sweep", "s.toml", "--store", "/"], 2, "by its place"),
    ("sweep-store-blank", NO_SETUP, ["sweep", "s.toml", "--store", "  "], 2, "empty path"),
    ("sweep-store-is-file", _write("f.zarr", "x"), ["sweep", "s.toml", "--store", "f.zarr"], 2,
     "not a directory"),
    ("sweep-store-under-file", _write("f", "x"), ["sweep", "s.toml", "--store", "f/s.zarr"], 2,
     "not a directory"),
    ("sweep-store-not-zarr", _mkdir("plain.zarr"), ["sweep", "s.toml", "--store", "plain.zarr"],
     2, "not a zarr store"),
    # a store a sweep wrote (its manifest) whose zarr.json is not JSON: damaged (exit 5, as a
    # truncated variable's zarr.json; it was 2); without a manifest, no store of ours (2)
    ("sweep-store-zarr-json-garbage", _write("s.zarr/zarr.json", "{"), ["sweep", "s.toml"],
     EXIT_DAMAGED, "is damaged"),
    ("sweep-store-plain-zarr", _write("pz.zarr/zarr.json", '{"zarr_format": 3, "node_type": '
                                      '"group", "attributes": {}}'),
     ["sweep", "s.toml", "--store", "pz.zarr"], 2, "is a zarr store but not an ehd sweep store; "
                                                  "choose"),
    ("sweep-store-zarr-json-garbage-no-manifest", _write("p.zarr/zarr.json", "{"),
     ["sweep", "s.toml", "--store", "p.zarr"], 2, "cannot be opened"),
    ("sweep-store-other-schema", _schema, ["sweep", "s.toml"], 2, "schema"),
    ("sweep-store-other-numerics", _other_numerics, ["sweep", "num.toml"], 2, "never mix"),
    ("sweep-store-other-sweep-file", _other_sweep, ["sweep", "other.toml"], 2, "--add-sweep"),
    # --- ehd sweep: the executor (checked before the store is touched)
    ("sweep-scheduler-file-missing", NO_SETUP,
     ["sweep", "s.toml", "--scheduler-file", "nope.json"], 2, "no such file"),
    ("sweep-scheduler-file-binary", _binary("b.json"),
     ["sweep", "s.toml", "--scheduler-file", "b.json"], 2, "not a scheduler file"),
    ("sweep-scheduler-file-not-json", _write("j.json", "{'address': 1"),
     ["sweep", "s.toml", "--scheduler-file", "j.json"], 2, "not JSON"),
    ("sweep-scheduler-file-no-address", _write("a.json", '{"id": "x"}'),
     ["sweep", "s.toml", "--scheduler-file", "a.json"], 2, "address"),
    ("sweep-scheduler-file-is-dir", _mkdir("sd.json"),
     ["sweep", "s.toml", "--scheduler-file", "sd.json"], 2, "cannot read"),
    ("sweep-scheduler-empty", NO_SETUP, ["sweep", "s.toml", "--scheduler", ""], 2,
     "empty address"),
    ("sweep-workers-1000", NO_SETUP, ["sweep", "s.toml", "--workers", "1000"], 2, "more than"),
    ("sweep-workers-0", NO_SETUP, ["sweep", "s.toml", "--workers", "0"], 2, "--workers"),
    ("sweep-workers-text", NO_SETUP, ["sweep", "s.toml", "--workers", "many"], 2, "--workers"),
    # options that would do nothing (ignored before)
    ("sweep-serial-workers", NO_SETUP, ["sweep", "s.toml", "--executor", "serial", "--workers",
                                        "2"], 2, "serial sweep runs in this process alone"),
    ("sweep-wait-workers-local", NO_SETUP, ["sweep", "s.toml", "--wait-workers", "5"], 2,
     "acts only with --scheduler"),
    ("sweep-connect-timeout-local", NO_SETUP, ["sweep", "s.toml", "--connect-timeout", "5"], 2,
     "acts only with --scheduler"),
    # --- ehd run: output paths and physics (all before any solve)
    ("run-save-missing-dir", NO_SETUP,
     ["run", "--St", "5", "--eps", "0.01", "--save", "/nonexistent/d/x.nc"], 2, "does not exist"),
    ("run-save-bad-type", NO_SETUP, ["run", "--St", "5", "--eps", "0.01", "--save", "x.txt"], 2,
     "unknown file type"),
    ("run-save-nc-is-dir", _mkdir("x.nc"), ["run", "--St", "5", "--eps", "0.01", "--save", "x.nc"],
     2, "is a directory"),
    ("run-save-zarr-is-file", _write("x.zarr", "x"),
     ["run", "--St", "5", "--eps", "0.01", "--save", "x.zarr"], 2, "not a directory"),
    ("run-plot-is-file", _write("afile", "x"),
     ["run", "--St", "5", "--eps", "0.01", "--plot", "afile"], 2, "not a directory"),
    ("run-plot-under-file", _write("afile", "x"),
     ["run", "--St", "5", "--eps", "0.01", "--plot", "afile/sub"], 2, "not a directory"),
    ("run-plot-empty", NO_SETUP, ["run", "--St", "5", "--eps", "0.01", "--plot", ""], 2,
     "empty path"),
    ("run-St-nan", NO_SETUP, ["run", "--St", "nan", "--eps", "0.01"], 2, "finite"),
    ("run-eps-out-of-range", NO_SETUP, ["run", "--St", "5", "--eps", "0.5"], 2, "valid range"),
    ("run-bad-accuracy", NO_SETUP, ["run", "--St", "5", "--eps", "0.01", "--accuracy", "x"], 2,
     "accuracy"),
    # --- ehd scene
    ("scene-binary-file", _binary("b.toml"), ["scene", "b.toml"], 2, "not a text file"),
    ("scene-file-missing", NO_SETUP, ["scene", "none.toml"], 2, "not found"),
    ("scene-file-is-dir", _mkdir("sc.toml"), ["scene", "sc.toml"], 2, "is a directory"),
    ("scene-plot-is-file", _write("afile", "x"), ["scene", EXAMPLE, "--plot", "afile"], 2,
     "not a directory"),
    ("scene-plot-under-file", _write("afile", "x"), ["scene", EXAMPLE, "--plot", "afile/x"], 2,
     "not a directory"),
    # --- ehd scene: the pressure-dependent viscosity and density (checked before any solve)
    ("scene-viscosity-law-unknown", NO_SETUP, ["scene", EXAMPLE, "--viscosity-law", "quadratic"],
     2, "invalid choice"),
    ("scene-viscosity-law-alpha-zero", NO_SETUP, ["scene", EXAMPLE, "--viscosity-law", "barus"],
     2, "pressure_viscosity = 0"),
    ("scene-viscosity-law-no-alpha", NO_SETUP,
     ["scene", EXAMPLE, "--fluid", "silicone_oil_10cst", "--viscosity-law", "roelands"], 2,
     "--pressure-viscosity"),
    ("scene-density-law-no-constants", NO_SETUP,
     ["scene", EXAMPLE, "--density-law", "dowson-higginson"], 2, "dowson_higginson_c1"),
    ("scene-viscosity-flag-given-a-law", NO_SETUP, ["scene", EXAMPLE, "--viscosity", "barus"], 2,
     "--viscosity-law"),
    ("scene-pressure-viscosity-units", NO_SETUP,
     ["scene", EXAMPLE, "--pressure-viscosity", "5 Pa"], 2, "fluid.pressure_viscosity"),
    ("scene-roelands-half", NO_SETUP, ["scene", EXAMPLE, "--roelands-index", "0.6"], 2,
     "without roelands_pressure"),
    # --- ehd figures
    ("figures-out-is-file", _write("afile", "x"), ["figures", "s.zarr", "--out", "afile"], 2,
     "not a directory"),
    ("figures-out-under-file", _write("afile", "x"), ["figures", "s.zarr", "--out", "afile/f"], 2,
     "not a directory"),
    ("figures-store-missing", NO_SETUP, ["figures", "none.zarr"], 2, "no sweep store"),
    ("figures-store-empty", NO_SETUP, ["figures", ""], 2, "empty path"),
    ("figures-store-is-file", _write("f.zarr", "x"), ["figures", "f.zarr"], 2, "no sweep store"),
    ("figures-nothing-finished", _nothing_done, ["figures", "e.zarr", "--out", "fig"], 2,
     "no finished scene"),
    ("figures-truncated-chunk", _truncate("s.zarr/v_r/c/1/0"), ["figures", "s.zarr"],
     EXIT_DAMAGED, "damaged"),
    ("figures-deleted-chunk", _remove("s.zarr/v_r/c/1/0"), ["figures", "s.zarr"], EXIT_DAMAGED,
     "damaged"),
    ("figures-truncated-status-chunk", _truncate("s.zarr/status/c/2/0", 3),
     ["figures", "s.zarr"], EXIT_DAMAGED, "damaged"),
    # --- ehd paper-figures
    ("paper-figures-out-is-file", _write("afile", "x"), ["paper-figures", "--out", "afile"], 2,
     "not a directory"),
    ("paper-figures-out-under-file", _write("afile", "x"), ["paper-figures", "--out", "afile/p"],
     2, "not a directory"),
    # --- ehd export-dem, ehd restitution (output checked before any solve)
    ("export-dem-input-missing", NO_SETUP, ["export-dem", "none.toml"], 2, "no such store"),
    ("export-dem-out-is-file", _write("afile", "x"),
     ["export-dem", str(REPO / "examples" / "glass_beads_water.toml"), "--out", "afile"], 2,
     "not a directory"),
    ("restitution-out-under-file", _write("afile", "x"),
     ["restitution", str(REPO / "examples" / "glass_beads_water.toml"), "--out", "afile/r"], 2,
     "not a directory"),
    # --- ehd status
    ("status-store-missing", NO_SETUP, ["status", "none.zarr"], 2, "no sweep store"),
    ("status-store-empty", NO_SETUP, ["status", ""], 2, "empty path"),
    # '.' is read by its real name ('.' inside a store reads it); the root is no store
    ("status-store-dot", NO_SETUP, ["status", "."], 2, "no sweep store at"),
    ("status-store-root", NO_SETUP, ["status", "/"], 2, "the root folder"),
    ("figures-store-root", NO_SETUP, ["figures", "/"], 2, "the root folder"),
    ("export-dem-store-root", NO_SETUP, ["export-dem", "/"], 2, "the root folder"),
    ("status-store-not-zarr", _mkdir("plain.zarr"), ["status", "plain.zarr"], 2, "no sweep store"),
    ("status-zarr-json-garbage", _write("s.zarr/zarr.json", "{"), ["status", "s.zarr"],
     EXIT_DAMAGED, "is damaged"),
    ("status-truncated-chunk", _truncate("s.zarr/v_r/c/1/0"), ["status", "s.zarr"],
     EXIT_DAMAGED, "damaged"),
    ("status-deleted-chunk", _remove("s.zarr/v_r/c/1/0"), ["status", "s.zarr"], EXIT_DAMAGED,
     "damaged"),
    ("status-truncated-model-chunk", _truncate("s.zarr/model/c/0/0", 2), ["status", "s.zarr"],
     EXIT_DAMAGED, "damaged"),
    ("status-truncated-ln_x_e-chunk", _truncate("s.zarr/ln_x_e_x1/c/3/0", 7),
     ["status", "s.zarr"], EXIT_DAMAGED, "damaged"),
    # --- any command
    ("unknown-command", NO_SETUP, ["frobnicate"], 2, "invalid choice"),
]


@pytest.mark.parametrize("setup, argv, code, keyword", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_gives_one_line_and_changes_nothing(ws, capsys, setup, argv, code, keyword):
    if setup is not None:
        setup(ws)
    before = tree_hash(ws / "s.zarr")
    got, out, err = ehd(capsys, *argv)
    assert got == code, err
    assert "Traceback" not in err and "Traceback" not in out
    lines = [line for line in err.splitlines() if line.strip()]
    errors = [line for line in lines if "error" in line]
    assert len(errors) == 1, err
    assert keyword in errors[0], err
    assert tree_hash(ws / "s.zarr") == before  # nothing stored was changed
    assert CALLS == []  # and nothing was computed


@pytest.mark.parametrize("argv, words", [
    (["run", "--St", "abc", "--eps", "0.01"], "ehd run: error: argument --St: invalid float"),
    (["sweep", "s.toml", "--workers", "0"], "ehd sweep: error: argument --workers"),
    (["run", "--St", "5", "--eps", "0.01", "--bogus"], "ehd run: error: unrecognized arguments"),
    (["run"], "ehd run: error: the following arguments are required"),
    ([], "ehd: error: the following arguments are required: COMMAND"),
])
def test_a_usage_error_is_one_line_naming_the_command(ws, capsys, argv, words):
    """argparse printed the whole usage before its error (18 lines for a bad --St), and an
    unknown flag of a command as "ehd: error" (a hostile scan): one line, exit 2, the command's
    name and where its flags are listed."""
    got, _, err = ehd(capsys, *argv)
    lines = [line for line in err.splitlines() if line.strip()]
    assert got == 2 and len(lines) == 1 and lines[0].startswith(words), err
    assert "--help" in lines[0]


def test_a_failed_scene_with_plot_says_why_there_is_no_figure(ws, capsys):
    """ehd run --plot of a scene that fails drew nothing and said nothing of it (a hostile
    scan): one line names the folder and the failure; exit 1 as for any failed scene."""
    got, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--max-steps", "11",
                        "--plot", "figs")
    assert got == 1 and "max_steps" in out
    assert err.strip() == "ehd run: no figures in figs: the scene failed (max_steps)", err


@pytest.mark.parametrize("make", [lambda p: p.write_text("x"), lambda p: p.mkdir()],
                         ids=["file", "folder-that-is-no-store"])
def test_a_refused_store_leaves_no_lock(ws, capsys, make):
    """--store naming a file, or a folder that is no store, is refused (exit 2); its lock file,
    made before the check, was left behind (a hostile scan)."""
    make(ws / "taken")
    got, _, err = ehd(capsys, "sweep", "s.toml", "--store", "taken")
    assert got == 2 and not (ws / "taken.lock").exists(), err


def test_the_catalogue_size():
    """The closing note of issue 9 quotes this count."""
    assert len(CASES) >= 60


# ---- the store repairs itself -------------------------------------------------------------------
def _stored(path):
    ds = xr.open_zarr(path).drop_vars("wall_s").load()
    ds.attrs = {}
    return ds


@pytest.mark.parametrize("damage", [_truncate("s.zarr/v_r/c/1/0"), _remove("s.zarr/v_r/c/1/0"),
                                    _truncate("s.zarr/status/c/2/0", 3),
                                    _truncate("s.zarr/h_m_x1/c/0/0", 0)],
                         ids=["truncated-data", "deleted-data", "truncated-status", "empty-data"])
def test_a_sweep_recomputes_damaged_cells_and_nothing_else(ws, base, capsys, damage):
    damage(ws)
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "Traceback" not in err
    assert "repaired" in out
    row = {(1, 3.0), (0, 1.0), (2, 5.0)}
    assert set(CALLS) <= {(s, e) for _, s in row for e in EPS} and len(CALLS) == len(EPS)
    xr.testing.assert_identical(_stored(ws / "s.zarr"), _stored(base / "s.zarr"))
    assert ehd(capsys, "status", "s.zarr")[0] == 0  # healthy again


def test_status_lists_the_damaged_cells(ws, capsys):
    _remove("s.zarr/v_r/c/1/0")(ws)
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED
    assert "damaged" in out and "St=3 eps=0.0001" in err and "v_r (missing)" in err


def test_bad_journal_lines_are_skipped_and_counted(ws, capsys):
    good = {"physics": {"St": 7.0, "eps": 1e-2}, "key": "x", "status": "ok"}
    (ws / "s.zarr.journal").write_bytes(b"\xff\xfe garbage\n[1, 2]\n{\"physics\": 3}\n"
                                        + json.dumps(good).encode() + b"\n{\"cut")
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == 0 and "4 " in out and "bad lines skipped" in out
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "bad lines skipped" in out
    assert not (ws / "s.zarr.journal").exists()


# ---- locks, provenance, the boundary itself -----------------------------------------------------
def test_the_lock_is_keyed_on_the_real_path(ws):
    os.symlink(ws / "s.zarr", ws / "link.zarr")
    sweep = load_sweep(ws / "s.toml")
    with SweepStore.open(sweep, ws / "s.zarr"):
        with pytest.raises(StoreBusy, match="being written"):
            with SweepStore.open(sweep, ws / "link.zarr"):
                pass
    with SweepStore.open(sweep, ws / "link.zarr") as st:  # a store through a link works
        assert st.path == (ws / "s.zarr").resolve()
    assert (ws / "link.zarr").is_symlink()


def test_a_busy_store_is_one_line(ws, capsys):
    with SweepStore.open(load_sweep(ws / "s.toml")):
        code, _, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == EXIT_USAGE and "being written" in err and len(err.strip().splitlines()) == 1


def test_another_sweep_file_needs_add_sweep_and_is_recorded(ws, capsys):
    _other_sweep(ws)
    code, out, err = ehd(capsys, "sweep", "other.toml", "--executor", "serial", "--add-sweep")
    assert code == 0, err
    sweeps = xr.open_zarr(ws / "s.zarr").attrs["sweeps"]
    assert [s["name"] for s in sweeps] == ["test", "other"]
    assert all(len(s["sha256"]) == 64 and s["time"] for s in sweeps)
    # the first sweep file again, and the other one again: both known now, no flag needed
    assert ehd(capsys, "sweep", "s.toml", "--executor", "serial")[0] == 0
    assert ehd(capsys, "sweep", "other.toml", "--executor", "serial")[0] == 0
    assert len(xr.open_zarr(ws / "s.zarr").attrs["sweeps"]) == 2
    # the same sweep edited (same name: a grid extended) is recorded, no flag needed
    (ws / "s.toml").write_text(sweep_text(ST + [40.0], EPS, store="s.zarr"))
    code, _, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0, err
    assert len(xr.open_zarr(ws / "s.zarr").attrs["sweeps"]) == 3


def test_a_read_only_store_is_refused_before_any_solve(ws, capsys, monkeypatch):
    (ws / "more.toml").write_text(sweep_text(ST + [40.0], EPS, store="s.zarr"))
    real_access = os.access
    store = str((ws / "s.zarr").resolve())
    monkeypatch.setattr(os, "access", lambda p, mode, *a, **k: False
                        if str(p).startswith(store) and mode & os.W_OK else
                        real_access(p, mode, *a, **k))  # chmod is no use when tests run as root
    before = tree_hash(ws / "s.zarr")
    code, _, err = ehd(capsys, "sweep", "more.toml", "--executor", "serial")
    assert code == EXIT_USAGE and "not writable" in err and CALLS == []
    assert tree_hash(ws / "s.zarr") == before
    # with nothing to do, a read-only store is only read
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "cached 8" in out, err


def test_an_unexpected_exception_is_a_bug_with_its_traceback(ws, capsys, monkeypatch):
    import pipeline.cli

    def broken(args):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(pipeline.cli, "cmd_info", broken)
    code, _, err = ehd(capsys, "info")
    assert code == EXIT_INTERNAL
    assert "Traceback" in err and "ZeroDivisionError: boom" in err
    assert "internal error" in err.splitlines()[-1] and "bug" in err.splitlines()[-1]


def test_an_unreachable_scheduler_gives_up_with_one_line(ws, capsys):
    (ws / "more.toml").write_text(sweep_text([7.0], EPS, store="m.zarr"))
    t = time.monotonic()
    code, _, err = ehd(capsys, "sweep", "more.toml", "--scheduler",
                       f"tcp://127.0.0.1:{_closed_port()}", "--connect-timeout", "1")
    assert code == EXIT_USAGE and time.monotonic() - t < 15
    assert "cannot reach" in err.splitlines()[-1] and "Traceback" not in err


# ---- faults: Ctrl-C and a scheduler that dies, in a real ehd sweep ------------------------------
SLOW_SWEEP = textwrap.dedent("""
    import functools, sys, time
    sys.path.insert(0, {repo!r})
    import pipeline.sweeps.run as r
    from tests.test_pipeline import fake_solve

    def slow(physics, accuracy, overrides):
        time.sleep(0.5)
        rec = fake_solve(physics, accuracy, overrides)
        with open({log!r}, "a") as f:  # the test waits for a few finished scenes
            f.write("done\\n")
        return rec

    if __name__ == "__main__":  # dask's worker processes import this file too
        r.run_sweep = functools.partial(r.run_sweep, solve=slow, warm_up=False)
        from pipeline.cli import main
        sys.exit(main(sys.argv[1:]))
    """)
FAULT_ST = [round(float(v), 6) for v in np.geomspace(1.0, 50.0, 12)]


def _fault_setup(tmp_path):
    (tmp_path / "slow.py").write_text(SLOW_SWEEP.format(repo=str(REPO),
                                                        log=str(tmp_path / "done.log")))
    (tmp_path / "f.toml").write_text(sweep_text(FAULT_ST, EPS, store="f.zarr"))
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
    return env


def _wait_for(proc, tmp_path, n=4, timeout=60):
    """Until the stand-in has finished ``n`` scenes."""
    log = tmp_path / "done.log"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if log.exists() and len(log.read_text().splitlines()) >= n:
            return
        if proc.poll() is not None:
            pytest.fail(f"ended early ({proc.returncode}): {(tmp_path / 'err.txt').read_text()}")
        time.sleep(0.02)
    pytest.fail(f"{n} scenes never finished: {(tmp_path / 'err.txt').read_text()}")


def _finished_kept(tmp_path, capsys):
    """Scenes stored or journaled after the fault; the rerun computes exactly the rest."""
    import warnings

    from pipeline import open_results
    from pipeline.sweeps.journal import pending_journal

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = open_results(tmp_path / "f.zarr").load()
    kept = int((ds.status.values != 0).sum()) + pending_journal(tmp_path / "f.zarr")
    return kept


@pytest.mark.parametrize("executor", ["processes", "threads"])
def test_ctrl_c_is_exit_130_one_line_and_keeps_every_finished_scene(tmp_path, capsys, executor):
    env = _fault_setup(tmp_path)
    err_path = tmp_path / "err.txt"
    with err_path.open("w") as err_file:
        # SIGINT at its default, as in a terminal: a suite started in the background by a
        # shell without job control (`cmd &`) ignores it, its children inherit that, Python then
        # installs no KeyboardInterrupt handler, and the sweep ran to its end (exit 0)
        proc = subprocess.Popen([sys.executable, "slow.py", "sweep", "f.toml", "--executor",
                                 executor, "--workers", "2"], cwd=tmp_path, env=env,
                                stdout=subprocess.DEVNULL, stderr=err_file,
                                start_new_session=True,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        _wait_for(proc, tmp_path)  # a few scenes done
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C reaches the whole process group
        proc.wait(timeout=60)
    err = err_path.read_text()
    assert proc.returncode == EXIT_INTERRUPTED, err
    assert "Traceback" not in err and "interrupted" in err.splitlines()[-1]
    assert "WARNING" not in err and "ERROR" not in err
    kept = _finished_kept(tmp_path, capsys)
    assert 1 <= kept < len(FAULT_ST) * len(EPS)  # scenes done on workers may not have arrived
    # nothing lost: the rerun computes exactly the scenes not kept
    os.chdir(tmp_path)
    try:
        summary = run_module.run_sweep(load_sweep("f.toml"), runner="serial", solve=fake_solve,
                                       progress=None)
    finally:
        os.chdir(REPO)
    assert summary.computed == len(FAULT_ST) * len(EPS) - kept and summary.done == summary.scenes


LOGGING_WORKER = """
import logging, sys
sys.path.insert(0, {repo!r})
from pipeline.sweeps.runners import open_runner

def log_on_the_worker():
    logging.getLogger("distributed.worker").error("a worker's own ERROR line")
    return 1

if __name__ == "__main__":
    with open_runner("processes", 1) as run:
        print(run.client.run(log_on_the_worker), file=sys.stderr, flush=True)
"""


def test_a_local_workers_own_log_lines_never_reach_the_terminal(tmp_path):
    """An interrupted sweep closes its local cluster; a worker whose heartbeat meets the closed
    scheduler logs an ERROR with its traceback (seen on a loaded machine after Ctrl-C). Whatever
    fails on a local worker reaches the sweep as a scene's error, so the workers' own logging is
    silenced: here a worker logs an ERROR line itself, and the terminal must not show it."""
    (tmp_path / "logs.py").write_text(LOGGING_WORKER.format(repo=str(REPO)))
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "logs.py"], cwd=tmp_path, env=env, text=True,
                          capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert ": 1}" in done.stderr  # the function ran on the worker
    assert "a worker's own ERROR line" not in done.stderr, done.stderr


def test_a_scheduler_killed_mid_sweep_is_one_line_and_keeps_finished_scenes(tmp_path, capsys):
    env = _fault_setup(tmp_path)
    bin_dir = Path(sys.executable).parent
    sched_file = tmp_path / "sched.json"
    sched = subprocess.Popen([str(bin_dir / "dask"), "scheduler", "--host", "127.0.0.1",
                              "--port", "0", "--no-dashboard", "--scheduler-file",
                              str(sched_file)], cwd=tmp_path, env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        deadline = time.monotonic() + 30
        while not sched_file.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.2)  # the file is written whole before the scheduler listens
        worker = subprocess.Popen([str(bin_dir / "dask"), "worker", "--scheduler-file",
                                   str(sched_file), "--nthreads", "2", "--no-nanny", "--host",
                                   "127.0.0.1"], cwd=tmp_path, env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        err_path = tmp_path / "err.txt"
        with err_path.open("w") as err_file:
            proc = subprocess.Popen([sys.executable, "slow.py", "sweep", "f.toml",
                                     "--scheduler-file", str(sched_file), "--workers", "1"],
                                    cwd=tmp_path, env=env, stdout=subprocess.DEVNULL,
                                    stderr=err_file)
            _wait_for(proc, tmp_path)
            sched.kill()
            sched.wait()
            proc.wait(timeout=90)
    finally:
        for p in (sched, worker):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait()
    err = err_path.read_text()
    assert proc.returncode == EXIT_SCHEDULER_LOST, err
    assert "Traceback" not in err and "lost the dask scheduler" in err.splitlines()[-1]
    kept = _finished_kept(tmp_path, capsys)
    assert 1 <= kept < len(FAULT_ST) * len(EPS)  # scenes done on workers may not have arrived


def test_docs_list_every_exit_code_and_model_code():
    import pipeline.errors as errors
    from solver.observables import MODEL_CODES, STATUS

    doc = (REPO / "docs" / "pipeline.md").read_text()
    codes = {v for k, v in vars(errors).items() if k.startswith("EXIT_")}
    for code in codes:
        assert f"\n| {code} | " in doc, code
    for name, code in MODEL_CODES.items():
        assert f"{code} `{name}`" in doc, name
    for name, (code, _) in STATUS.items():
        assert f"| {code} | `{name}` |" in doc, name
    from pipeline.sweeps.layout import STORE_SCHEMA

    assert f"Store schema {STORE_SCHEMA}" in doc and f"`store_schema` ({STORE_SCHEMA})" in doc


def test_ctrl_c_inside_compiled_code_is_an_interrupt_not_a_bug(monkeypatch, capsys):
    """numba hands a Ctrl-C that arrives in compiled code back as a SystemError caused by the
    KeyboardInterrupt: still exit 130 and one line, as for an interrupt anywhere else."""
    import pipeline.cli as cli

    def interrupted_in_numba(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher returned a result with an exception set") from exc

    monkeypatch.setattr(cli, "cmd_run", interrupted_in_numba)
    assert cli.main(["run", "--St", "5", "--eps", "0.01"]) == EXIT_INTERRUPTED
    err = capsys.readouterr().err
    assert "Traceback" not in err and err.strip().splitlines() == [
        "ehd run: interrupted before it finished; run it again"]


REAL_CTRL_C = textwrap.dedent("""
    import sys
    sys.path.insert(0, {repo!r})
    from pipeline.cli import main
    from solver import Physics, collide

    if sys.argv[1] == "compile":  # fills the numba cache (another process: see the test)
        collide(Physics(St=1000.0, eps=1e-8), accuracy="fast", save_profiles=False)
        sys.exit(0)
    print("ready", flush=True)
    sys.exit(main(["run", "--St", "1000", "--eps", "1e-8", "--accuracy", "fine",
                   "--rtol", "1e-8", "--max-order", "2"]))
    """)


def test_a_real_ctrl_c_during_the_compiled_solve_is_exit_130_one_line(tmp_path):
    """Ctrl-C while the compiled time loop runs its first call in a process (the kernels loaded
    from a warm cache): raised inside it, where numba converts the results back to Python
    objects, it killed ``ehd run`` with a segmentation fault (exit -11, every time at 0.5-2 s);
    it is taken once the loop returns (solver.interrupts.deferred_interrupt): exit 130, one line."""
    (tmp_path / "run.py").write_text(REAL_CTRL_C.format(repo=str(REPO)))
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    subprocess.run([sys.executable, "run.py", "compile"], cwd=tmp_path, env=env, check=True)
    proc = subprocess.Popen([sys.executable, "run.py", "solve"], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline().strip() == "ready"
    # inside the solve: loading the kernels takes about 0.5 s, then the fine solve at BDF2 3.1 s
    # on an AMD EPYC (2026-12-04; at orders up to 5 it took 0.8 s there, and the interrupt
    # came after it: exit 0)
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_INTERRUPTED, (proc.returncode, err)
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == "ehd run: interrupted before it finished; run it again"


# ==== issue 19: nothing wrong is ever stored or shown ============================================
# ---- silent corruption: checksummed chunks, coordinates and metadata in the integrity check ----
def _flip(rel, back=3):
    """Flip one bit of the byte ``back`` bytes from the end of a chunk (its checksum no longer
    matches; before schema 6 the chunk decoded to another number)."""
    def make(ws):
        p = ws / rel
        data = bytearray(p.read_bytes())
        data[-back] ^= 0x01
        p.write_bytes(bytes(data))
    return make


def _edit_root(edit):
    def make(ws):
        p = ws / "s.zarr" / "zarr.json"
        meta = json.loads(p.read_text())
        meta = edit(meta)
        p.write_text(json.dumps(meta))
    return make


def _set_attr(key, value):
    def edit(meta):
        meta["attributes"][key] = value
        return meta
    return _edit_root(edit)


def _bless(ws, key):
    """Record the chunk ``key``'s bytes as it is now in the store's manifest: a chunk a writer
    wrote (wrongly) through the proper path, not one changed behind it (which the manifest
    finds: tests/test_store_integrity.py)."""
    from pipeline.sweeps.manifest import read_manifest, redigest, write_manifest

    manifest = read_manifest(ws / "s.zarr")[0]
    redigest(ws / "s.zarr", manifest, [key])
    write_manifest(ws / "s.zarr", manifest)


def _status_code(code):
    def make(ws):
        import zarr

        from pipeline.sweeps.layout import zarr_warnings

        with zarr_warnings():
            zarr.open_group(str(ws / "s.zarr"), mode="r+")["status"][0, 0] = code
        _bless(ws, "status/c/0/0")
    return make


@pytest.mark.parametrize("damage, where", [
    (_flip("s.zarr/v_r/c/1/0"), "v_r (unreadable)"),
    (_flip("s.zarr/steps/c/2/0", 5), "steps (unreadable)"),
    (_status_code(99), "status (unknown code 99)"),
], ids=["flipped-byte-data", "flipped-byte-count", "status-code-99"])
def test_damaged_data_is_listed_refused_raised_and_recomputed(ws, base, capsys, damage, where):
    from pipeline import open_results
    from pipeline.errors import StoreDamaged

    damage(ws)
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED and where in err and "Traceback" not in err, err
    code, _, err = ehd(capsys, "figures", "s.zarr", "--out", "fig")
    assert code == EXIT_DAMAGED and "damaged" in err and not (ws / "fig").exists()
    with pytest.raises(StoreDamaged, match="damaged"):
        open_results(ws / "s.zarr")
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "repaired" in out, err
    assert 1 <= len(CALLS) <= len(EPS)  # one chunk: one St row at most
    xr.testing.assert_identical(_stored(ws / "s.zarr"), _stored(base / "s.zarr"))
    assert ehd(capsys, "status", "s.zarr")[0] == 0


@pytest.mark.parametrize("damage, how", [
    (_truncate("s.zarr/St/c/0", 3), "unreadable"),
    (_remove("s.zarr/eps/c/0"), "missing"),
    (_flip("s.zarr/St/c/0"), "unreadable"),
], ids=["truncated-St", "deleted-eps", "flipped-St"])
def test_a_damaged_coordinate_is_listed_refused_and_rewritten(ws, base, capsys, damage, how):
    from pipeline import open_results
    from pipeline.errors import StoreDamaged

    damage(ws)
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED and f"({how}" in err and "Traceback" not in err, err
    assert "nan" not in out  # the rows are shown at their true coordinates (the store's copy)
    assert ehd(capsys, "figures", "s.zarr", "--out", "fig")[0] == EXIT_DAMAGED
    with pytest.raises(StoreDamaged, match="coordinate"):
        open_results(ws / "s.zarr")
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "coordinate" in out + err and CALLS == [], err
    xr.testing.assert_identical(_stored(ws / "s.zarr"), _stored(base / "s.zarr"))
    assert ehd(capsys, "status", "s.zarr")[0] == 0


METADATA = [
    ("root-is-a-list", _edit_root(lambda m: []), EXIT_USAGE, "not a zarr group"),
    ("root-is-a-number", _edit_root(lambda m: 5), EXIT_USAGE, "not a zarr group"),
    ("attributes-a-list", _set_attr_root := _edit_root(lambda m: {**m, "attributes": []}),
     EXIT_DAMAGED, "attributes"),
    ("fixed-physics-a-string", _set_attr("fixed_physics", "St=5"), EXIT_DAMAGED, "fixed_physics"),
    ("axes-a-string", _set_attr("axes", "St"), EXIT_DAMAGED, "axes"),
    ("schema-a-string", _set_attr("store_schema", "6"), EXIT_DAMAGED, "store_schema"),
    ("schema-5-old", _set_attr("store_schema", 5), EXIT_USAGE, "checksum"),
    ("schema-true", _set_attr("store_schema", True), EXIT_DAMAGED, "store_schema"),
    ("grid-copy-short", _set_attr("grid", {"St": ["1.0"], "eps": ["0.0001", "0.01"]}),
     EXIT_DAMAGED, "grid.St"),
    ("an-edited-number", _set_attr("accuracy", "fine"), EXIT_DAMAGED, "checksum"),
    ("fill-value-edited", _edit_root(lambda m: (m["consolidated_metadata"]["metadata"]["v_r"]
                                                .update(fill_value=0.0), m)[1]),
     EXIT_DAMAGED, "checksum"),
    ("codecs-stripped", _edit_root(lambda m: (m["consolidated_metadata"]["metadata"]["v_r"]
                                              .update(codecs=[{"name": "bytes"}]), m)[1]),
     EXIT_DAMAGED, "no checksummed chunks"),
    ("variable-dropped", _edit_root(lambda m: (m["consolidated_metadata"]["metadata"]
                                               .pop("status"), m)[1]), EXIT_DAMAGED, "missing"),
]


@pytest.mark.parametrize("setup, code, keyword", [c[1:] for c in METADATA],
                         ids=[c[0] for c in METADATA])
def test_metadata_of_the_wrong_shape_is_one_line_for_every_reader(ws, capsys, setup, code, keyword):
    from pipeline import open_results
    from pipeline.errors import EhdError

    setup(ws)
    before = tree_hash(ws / "s.zarr")
    for argv in (["status", "s.zarr"], ["figures", "s.zarr", "--out", "fig"],
                 ["sweep", "s.toml", "--executor", "serial"]):
        got, out, err = ehd(capsys, *argv)
        assert got == code, (argv, err)
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
        assert keyword in err, err
    with pytest.raises(EhdError, match=keyword):
        open_results(ws / "s.zarr")
    assert tree_hash(ws / "s.zarr") == before and CALLS == []


def _same_stat(damage, rel):
    """``damage``, then the chunk's size and time stamps put back as they were: a change that a
    check of the files' sizes and mtimes would miss."""
    def make(ws):
        p = ws / rel
        st = p.stat()
        damage(ws)
        assert p.stat().st_size == st.st_size
        os.utime(p, ns=(st.st_atime_ns, st.st_mtime_ns))
    return make


def _undecodable(rel):
    """Replace a chunk by bytes that are no zstd stream, under a valid CRC-32C: only decoding it
    tells (a writer computing a checksum over garbage)."""
    def make(ws):
        import google_crc32c

        data = b"no zstd frame here"
        (ws / rel).write_bytes(data + google_crc32c.value(data).to_bytes(4, "little"))
        _bless(ws, str(Path(rel).relative_to("s.zarr")))
    return make


def test_a_sweep_with_nothing_to_do_checks_the_chunks_it_does_not_decode(ws, base, capsys):
    """A sweep with nothing to do decodes only what it plans with (pipeline/sweeps/store.py
    PLANNED, integrity.CHECKED); the other variables' chunks are verified from their bytes: one
    flipped byte in a chunk of ``steps``, with its size and mtime as before, is still found and
    its row recomputed."""
    from pipeline.sweeps.integrity import CHECKED
    from pipeline.sweeps.store import PLANNED

    assert "steps" not in {*PLANNED, *CHECKED}  # the case this test is about: a lazy variable
    _same_stat(_flip("s.zarr/steps/c/2/0", 5), "s.zarr/steps/c/2/0")(ws)
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "repaired" in out, out + err
    assert sorted(CALLS) == sorted((ST[2], e) for e in EPS)  # that row, nothing else
    xr.testing.assert_identical(_stored(ws / "s.zarr"), _stored(base / "s.zarr"))
    assert ehd(capsys, "status", "s.zarr")[0] == 0


def test_a_chunk_that_only_decoding_finds_is_found_before_a_sweep_writes(ws, base, capsys):
    """A chunk with a valid checksum over bytes that do not decode, in a variable a sweep does
    not plan with: ``ehd status`` (it decodes everything) lists it; a sweep with work decodes
    every variable before its first solve, turns those cells into "not run" and computes them
    again with its own work."""
    _undecodable("s.zarr/steps/c/1/0")(ws)
    code, _, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED and "steps (unreadable)" in err, err
    (ws / "s.toml").write_text(sweep_text([*ST, 40.0], EPS, store="s.zarr"))  # one more St
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "repaired" in out, out + err
    assert sorted(CALLS) == sorted((s, e) for s in (ST[1], 40.0) for e in EPS)
    assert ehd(capsys, "status", "s.zarr")[0] == 0
    grown = _stored(ws / "s.zarr").sel(St=ST)
    xr.testing.assert_identical(grown, _stored(base / "s.zarr"))


def test_every_chunk_of_every_array_is_checksummed(ws):
    from pipeline.sweeps.layout import VARIABLES

    root = json.loads((ws / "s.zarr" / "zarr.json").read_text())
    arrays = root["consolidated_metadata"]["metadata"]
    assert set(arrays) == set(VARIABLES) | {"St", "eps"}
    for name, meta in arrays.items():
        assert [c["name"] for c in meta["codecs"]][-1] == "crc32c", name


# ---- a full disk: one line naming the path and the free space, nothing partial left -----------
def _enospc(*args, **kwargs):
    import errno

    raise OSError(errno.ENOSPC, "No space left on device")


def _leftovers(ws, before):
    return sorted(str(p.relative_to(ws)) for p in ws.rglob("*") if p not in before)


def _assert_full_disk_line(code, err):
    from pipeline.errors import EXIT_WRITE

    assert code == EXIT_WRITE, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert "No space left on device" in err and "free on its file system" in err, err


def test_a_full_disk_while_laying_out_a_store_leaves_nothing(ws, capsys, monkeypatch):
    import pipeline.sweeps.store as store

    (ws / "n.toml").write_text(sweep_text(ST, EPS, store="n.zarr"))
    before = set(ws.rglob("*"))
    monkeypatch.setattr(store, "seal", _enospc)  # after xarray wrote the temporary layout
    code, _, err = ehd(capsys, "sweep", "n.toml", "--executor", "serial")
    _assert_full_disk_line(code, err)
    assert "n.zarr" in err and _leftovers(ws, before) == [] and CALLS == []


def test_a_full_disk_while_merging_keeps_every_finished_scene(ws, capsys, monkeypatch):
    """The store cannot take the merge: the journal keeps the scenes; the next sweep merges
    them and computes nothing again."""
    (ws / "s.toml").write_text(sweep_text(ST + [40.0], EPS, store="s.zarr"))
    code, _, _ = ehd(capsys, "sweep", "s.toml", "--executor", "serial")  # the new layout
    assert code == 0 and len(CALLS) == len(EPS)
    _remove("s.zarr/v_r/c/1/0")(ws)  # a damaged row: recomputed, then merged (fails)
    CALLS.clear()
    real = xr.Dataset.to_zarr

    def full(self, *a, **k):
        if k.get("region") is not None and CALLS:  # the merge of the recomputed scenes
            _enospc()
        return real(self, *a, **k)

    monkeypatch.setattr(xr.Dataset, "to_zarr", full)
    code, _, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    _assert_full_disk_line(code, err)
    computed = list(CALLS)
    assert computed and (ws / "s.zarr.journal").exists()
    monkeypatch.setattr(xr.Dataset, "to_zarr", real)
    CALLS.clear()
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0, err
    assert CALLS == []  # nothing finished was lost: the journal had every scene
    assert ehd(capsys, "status", "s.zarr")[0] == 0


def test_a_full_disk_at_the_journal_cuts_it_back_to_whole_records(ws, capsys, monkeypatch):
    (ws / "s.toml").write_text(sweep_text(ST + [40.0], EPS, store="s.zarr"))

    class Full:
        def __init__(self, f):
            self.f, self.n = f, 0

        def write(self, text):
            self.n += 1
            if self.n > 1:  # the first record fits, the second half does not
                self.f.write(text[: len(text) // 2])
                self.f.flush()
                _enospc()
            return self.f.write(text)

        def __getattr__(self, name):
            return getattr(self.f, name)

    import pipeline.sweeps.store as store

    real_open_append = store.open_append  # the journal's one opening (pipeline/sweeps/files.py)
    monkeypatch.setattr(store, "open_append", lambda path: Full(real_open_append(path)))
    monkeypatch.setattr("pipeline.sweeps.store.FLUSH_SECONDS", 1e9)
    code, _, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    _assert_full_disk_line(code, err)
    assert "journal" in err
    journal = ws / "s.zarr.journal"  # merged and dropped, or cut back to whole records
    assert not journal.exists() or all(json.loads(line) for line in
                                       journal.read_text().splitlines())
    assert ehd(capsys, "status", "s.zarr")[0] == 0


def test_run_save_on_a_full_disk_leaves_no_file(ws, capsys, monkeypatch):
    def partial(self, path, *a, **k):
        Path(path).write_bytes(b"CDF\x01")  # a few bytes, then the disk is full
        _enospc()

    monkeypatch.setattr(xr.Dataset, "to_netcdf", partial)
    before = set(ws.rglob("*"))
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--accuracy", "fast",
                         "--save", "r.nc")
    _assert_full_disk_line(code, err)
    assert "r.nc" in err and "v_r" in out  # the result was shown before the save failed
    assert _leftovers(ws, before) == []


def test_run_save_replaces_an_old_file_only_when_complete(ws, capsys, monkeypatch):
    from pipeline.cli_shared import SAVED_BY, SAVED_BY_KEY

    # an earlier --save output (only that may be replaced: tests/test_user_input.py)
    xr.Dataset(attrs={SAVED_BY_KEY: SAVED_BY}).to_netcdf(ws / "r.nc", engine="scipy")
    old = (ws / "r.nc").read_bytes()
    monkeypatch.setattr(xr.Dataset, "to_netcdf", _enospc)
    code, _, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--accuracy", "fast",
                       "--save", "r.nc")
    _assert_full_disk_line(code, err)
    assert (ws / "r.nc").read_bytes() == old
    assert [p.name for p in ws.iterdir() if "r.nc" in p.name] == ["r.nc"]


# the commands that draw figures into a folder, and the function that draws them
FIGURE_COMMANDS = [
    (["run", "--St", "5", "--eps", "0.01", "--accuracy", "fast", "--plot", "figs/run"],
     "pipeline.plots.scene_plots.plot_scene"),
    (["figures", "s.zarr", "--out", "figs/sweep"], "pipeline.plots.sweep_maps.update_figures"),
    (["restitution", str(REPO / "examples" / "glass_beads_water.toml"), "--n", "2", "--accuracy",
      "fast", "--plot", "figs/restitution"], "pipeline.plots.restitution_plot.plot_restitution"),
]


@pytest.mark.parametrize("argv, target", FIGURE_COMMANDS)
def test_figures_on_a_full_disk_leave_nothing_new(ws, capsys, monkeypatch, argv, target):
    import importlib

    module, name = target.rsplit(".", 1)
    folder = ws / argv[-1]

    def half(*a, **k):
        from pipeline.writes import claim

        folder.mkdir(parents=True, exist_ok=True)
        # as every writer of a guarded folder does: to the name claim hands back
        claim(folder / "fig.png").write_bytes(b"\x89PNG")  # one figure half written
        _enospc()

    monkeypatch.setattr(importlib.import_module(module), name, half)
    before = set(ws.rglob("*"))
    code, _, err = ehd(capsys, *argv)
    _assert_full_disk_line(code, err)
    assert _leftovers(ws, before) == []


@pytest.mark.parametrize("argv, target", FIGURE_COMMANDS)
def test_an_interrupted_redraw_keeps_the_figures_of_the_last_run(ws, capsys, monkeypatch, argv,
                                                                 target):
    """Ctrl-C while a command redraws the figures of an earlier run into the same folder: the
    earlier figures and the stamp stay as they were, and no temporary is left (a hostile review
    found an interrupted ``ehd figures`` had removed the figures it had redrawn so far, the
    earlier run's with them: 19 files became 11)."""
    import importlib

    module, name = target.rsplit(".", 1)
    folder = ws / argv[-1]
    folder.mkdir(parents=True)
    earlier = {folder / "fig.png": b"earlier png", folder / "fig.pdf": b"earlier pdf",
               folder / ".sweep-figures.sha256": b"{}"}
    for path, data in earlier.items():
        path.write_bytes(data)

    def interrupted(*a, **k):
        from pipeline.writes import claim

        claim(folder / "fig.png").write_bytes(b"\x89PNG redrawn")  # one figure redrawn
        raise KeyboardInterrupt  # Ctrl-C before the next

    monkeypatch.setattr(importlib.import_module(module), name, interrupted)
    code, _, err = ehd(capsys, *argv)
    assert code == 130, err
    assert {p: p.read_bytes() for p in folder.iterdir()} == earlier


def test_a_scene_plot_leaves_no_figure_of_an_earlier_scene_it_does_not_draw(ws, capsys):
    """``--plot DIR`` reused: a scene without a dimple (St 0.5) after one with (St 5) leaves no
    ``dimple`` figure, a rigid scene (eps 1e-6) no profiles, and a file of another name stays
    (a hostile review found the earlier scene's dimple beside the later scene's figures)."""
    (ws / "figs").mkdir()
    (ws / "figs" / "notes.txt").write_text("the user's")
    drawn = []
    for st, eps in (("5", "0.01"), ("0.5", "0.01"), ("2", "1e-6")):
        code, _, err = ehd(capsys, "run", "--St", st, "--eps", eps, "--accuracy", "fast",
                           "--plot", "figs")
        assert code == 0, err
        drawn.append(sorted(p.stem for p in (ws / "figs").glob("*.png")))
    assert drawn == [["deformation", "dimple", "energy", "gap", "motion", "pressure"],
                     ["deformation", "energy", "gap", "motion", "pressure"],
                     ["energy", "motion"]]
    assert sorted(p.name for p in (ws / "figs").iterdir() if p.suffix not in (".png", ".pdf")) \
        == ["notes.txt"]


def test_figures_of_a_store_with_a_plane_of_no_finished_scene(ws, capsys):
    """Two sweeps into one store on other axes (Pi and beta) leave planes in which no scene
    ran: their figures say so instead of failing to log-scale no data (a hostile review: exit 70,
    matplotlib's traceback)."""
    for pi, beta in ((1e-2, 0.0), (1e-3, 1.0)):
        text = sweep_text([10.0, 20.0], [1e-2], store="m.zarr")
        (ws / "m.toml").write_text(text.replace("[grid]\n",
                                                f"[grid]\nPi = [{pi}]\nbeta = [{beta}]\n"))
        code, _, err = ehd(capsys, "sweep", "m.toml", "--executor", "serial")
        assert code == 0, err
    code, out, err = ehd(capsys, "figures", "m.zarr", "--out", "figs")
    assert code == 0, err
    assert (ws / "figs" / "fig13_closest_approach_Pi=0.001_beta=0.png").is_file()


def test_a_complete_redraw_replaces_the_figures_and_retires_the_last_runs_own(ws, capsys):
    """A redraw that completes moves its figures into place together; a figure the last render
    drew and this one does not (named in the last render's stamp) goes, and no temporary stays.
    The stand-in store's figures drawn twice: the second time with a stale name in the stamp."""
    from pipeline.plots.stamp import STAMP_NAME, read_stamp

    code, _, err = ehd(capsys, "figures", "s.zarr", "--out", "figs")
    assert code == 0, err
    drawn = sorted(p.name for p in (ws / "figs").iterdir())
    stamp = ws / "figs" / STAMP_NAME
    data = read_stamp(ws / "figs")
    (ws / "figs" / "fig99_gone.png").write_bytes(b"drawn by an earlier render")
    stamp.write_text(json.dumps({**data, "fingerprint": "changed", "store_state": None,
                                 "files": data["files"] + ["fig99_gone.png"]}))
    code, _, err = ehd(capsys, "figures", "s.zarr", "--out", "figs")
    assert code == 0, err
    assert sorted(p.name for p in (ws / "figs").iterdir()) == drawn
    assert read_stamp(ws / "figs")["fingerprint"] != "changed"


def _can_mount_tmpfs(path) -> bool:
    if os.geteuid() != 0 or shutil.which("mount") is None:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(path)],
                          capture_output=True, timeout=10).returncode == 0


def test_a_sweep_on_a_real_full_disk(tmp_path):
    """The issue's reproduction on a 200 KiB tmpfs (root only; the simulated cases above hold
    everywhere)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if not _can_mount_tmpfs(disk):
        pytest.skip("needs root and mount to make a small tmpfs")
    try:
        (disk / "s.toml").write_text(sweep_text(ST, EPS, store="s.zarr"))
        env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
        proc = subprocess.run([sys.executable, "-m", "pipeline.cli", "sweep", "s.toml",
                               "--executor", "serial"], cwd=disk, env=env, capture_output=True,
                              text=True, timeout=120)
        _assert_full_disk_line(proc.returncode, proc.stderr)
        assert sorted(p.name for p in disk.iterdir()) == ["s.toml"]
    finally:
        subprocess.run(["umount", str(disk)], capture_output=True, timeout=10)


# ---- stdout closed or full ------------------------------------------------------------------------
def _ehd_subprocess(args, stdout, timeout=120, **kw):
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *map(str, args)], env=env,
                          stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=timeout,
                          **kw)


@pytest.mark.parametrize("args", [["info"], ["run", "--St", "5", "--eps", "0.01"],
                                  ["scene", EXAMPLE], ["status", "none.zarr"]],
                         ids=["info", "run", "scene", "status"])
def test_a_closed_stdout_is_one_line_before_any_work(tmp_path, args):
    from pipeline.errors import EXIT_WRITE

    t = time.monotonic()
    proc = _ehd_subprocess(args, None, cwd=tmp_path, preexec_fn=lambda: os.close(1))
    assert proc.returncode == EXIT_WRITE, proc.stderr
    assert "Traceback" not in proc.stderr and "stdout is closed" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert time.monotonic() - t < 60  # nothing solved (a bound, not a speed target)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("args", [["info"], ["run", "--St", "5", "--eps", "0.01", "--accuracy",
                                             "fast"]], ids=["info", "run"])
def test_a_full_stdout_is_one_line(tmp_path, args):
    from pipeline.errors import EXIT_WRITE

    with open("/dev/full", "w") as full:
        proc = _ehd_subprocess(args, full, cwd=tmp_path)
    assert proc.returncode == EXIT_WRITE, proc.stderr
    assert "Traceback" not in proc.stderr and "cannot write to stdout" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_the_error_boundary_never_raises(monkeypatch, capsys):
    import pipeline.cli

    class Nasty(Exception):
        def __str__(self):
            raise RuntimeError("no text either")

    def broken(args):
        raise Nasty()

    monkeypatch.setattr(pipeline.cli, "cmd_info", broken)
    monkeypatch.setattr(sys, "stderr", None)  # and nowhere to say it
    assert main(["info"]) == EXIT_INTERNAL


# ---- SIGTERM: like Ctrl-C, its own code ---------------------------------------------------------
def test_sigterm_is_exit_143_one_line_and_keeps_every_finished_scene(tmp_path, capsys):
    from pipeline.errors import EXIT_TERMINATED

    env = _fault_setup(tmp_path)
    err_path = tmp_path / "err.txt"
    with err_path.open("w") as err_file:
        proc = subprocess.Popen([sys.executable, "slow.py", "sweep", "f.toml", "--executor",
                                 "threads", "--workers", "2"], cwd=tmp_path, env=env,
                                stdout=subprocess.DEVNULL, stderr=err_file)
        _wait_for(proc, tmp_path)
        proc.send_signal(signal.SIGTERM)  # kill PID, or a batch system's time limit
        proc.wait(timeout=60)
    err = err_path.read_text()
    assert proc.returncode == EXIT_TERMINATED, err
    assert "Traceback" not in err and "terminated" in err.splitlines()[-1]
    kept = _finished_kept(tmp_path, capsys)
    assert 1 <= kept < len(FAULT_ST) * len(EPS)
    os.chdir(tmp_path)
    try:
        summary = run_module.run_sweep(load_sweep("f.toml"), runner="serial", solve=fake_solve,
                                       progress=None)
    finally:
        os.chdir(REPO)
    assert summary.computed == len(FAULT_ST) * len(EPS) - kept and summary.done == summary.scenes


# ---- the scheduler: every wait bounded, only a dask scheduler accepted, nothing made before ----
@pytest.fixture
def silent_peer():
    """A TCP server on 127.0.0.1 that accepts and never speaks."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held = []
    stop = threading.Event()

    def accept():
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                held.append(server.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join(2)
    for conn in held:
        conn.close()
    server.close()


@pytest.fixture
def http_peer():
    """An HTTP server on 127.0.0.1 (answers requests with HTML, never speaks first)."""
    import http.server
    import threading

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0),
                                             http.server.SimpleHTTPRequestHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.mark.parametrize("peer", ["silent_peer", "http_peer"])
def test_a_peer_that_is_no_scheduler_is_refused_within_the_timeout(ws, capsys, request, peer):
    address = request.getfixturevalue(peer)
    (ws / "m.toml").write_text(sweep_text([7.0], EPS, store="m.zarr"))
    t = time.monotonic()
    code, _, err = ehd(capsys, "sweep", "m.toml", "--scheduler", address,
                       "--connect-timeout", "1")
    assert code == EXIT_USAGE and time.monotonic() - t < 10, err  # 1 s, and slack for a loaded CI
    assert "dask" in err and "Traceback" not in err
    assert [line for line in err.splitlines() if "error" in line][0].count("error") >= 1
    assert not any(p.name.startswith("m.zarr") for p in ws.iterdir())  # no store, no lock


def test_an_unreachable_scheduler_leaves_no_store_and_no_lock(ws, capsys):
    (ws / "m.toml").write_text(sweep_text([7.0], EPS, store="m.zarr"))
    code, _, err = ehd(capsys, "sweep", "m.toml", "--scheduler",
                       f"tcp://127.0.0.1:{_closed_port()}", "--connect-timeout", "1")
    assert code == EXIT_USAGE and "cannot reach" in err
    assert not any(p.name.startswith("m.zarr") for p in ws.iterdir())


def test_a_scheduler_without_workers_is_reported_after_the_wait(ws, capsys):
    from distributed import LocalCluster

    (ws / "m.toml").write_text(sweep_text([7.0], EPS, store="m.zarr"))
    # its HTTP server on a free local port (8787 may be taken by another cluster)
    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1",
                      dashboard_address="127.0.0.1:0") as cluster:
        t = time.monotonic()
        code, _, err = ehd(capsys, "sweep", "m.toml", "--scheduler", cluster.scheduler_address,
                           "--connect-timeout", "5", "--wait-workers", "1")
    assert code == EXIT_USAGE and time.monotonic() - t < 20, err
    assert "no workers" in err and CALLS == []


@pytest.mark.parametrize("argv, keyword", [
    (["--scheduler", "tcp://127.0.0.1"], "no port"),
    (["--scheduler", "tcp://127.0.0.1:99999"], "65535"),
    (["--scheduler", "nonsense"], "not a scheduler address"),
    (["--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "nan"], "finite"),
    (["--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "-1"], "> 0"),
    (["--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "0"], "> 0"),
    (["--scheduler", "tcp://127.0.0.1:1", "--connect-timeout", "inf"], "finite"),
    (["--scheduler", "tcp://127.0.0.1:1", "--wait-workers", "nan"], "finite"),
    (["--scheduler", "tcp://127.0.0.1:1", "--wait-workers", "-5"], ">= 0"),
], ids=["no-port", "port-too-big", "not-an-address", "timeout-nan", "timeout-negative",
        "timeout-zero", "timeout-inf", "wait-nan", "wait-negative"])
def test_scheduler_options_are_checked_before_any_work(ws, capsys, argv, keyword):
    (ws / "m.toml").write_text(sweep_text([7.0], EPS, store="m.zarr"))
    t = time.monotonic()
    code, _, err = ehd(capsys, "sweep", "m.toml", *argv)
    assert code == EXIT_USAGE and keyword in err and "Traceback" not in err, err
    assert time.monotonic() - t < 5  # nothing waited for
    assert not any(p.name.startswith("m.zarr") for p in ws.iterdir())


# ---- scenes and sweep files: text is read, never evaluated; absurd values refused -------------
def _scene_with(ws, name, **fields):
    text = EXAMPLE.read_text()
    for key, value in fields.items():
        lines = [line for line in text.splitlines() if not line.startswith(f"{key} =")]
        text = "\n".join(lines)
        text = text.replace("[body1]", f"[body1]\n{key} = {value}") if key == "radius" \
            else f"{key} = {value}\n{text}"
    (ws / name).write_text(text)
    return name


SCENE_CASES = [
    ("v0-import", dict(v0="'__import__(\"os\")'"), "cannot read"),
    ("v0-semicolon", dict(v0="'1 m/s; import os'"), "cannot read"),
    ("v0-lambda", dict(v0="'lambda: 1'"), "cannot read"),
    ("v0-units-only", dict(v0="'m/s'"), "cannot read"),
    ("v0-unknown-unit", dict(v0="'1 furlong__x/s'"), "cannot read"),
    ("radius-subnormal", dict(radius="1e-320"), "subnormal"),
    ("radius-subnormal-text", dict(radius="'1e-320 m'"), "subnormal"),
    ("radius-absurd", dict(radius="1e-40"), "valid range"),
    ("v0-absurd", dict(v0="'1e40 m/s'"), "valid range"),
    # a number among the units, which pint multiplies in (200 um, 500 mm/s, 25 um were solved)
    ("radius-stray-number", dict(radius="'100 um 2'"), "number among its units"),
    ("v0-stray-number", dict(v0="'10 cm/s 5'"), "number among its units"),
    ("v0-times-number", dict(v0="'10 cm/s * 2'"), "number among its units"),
    ("radius-over-number", dict(radius="'100 um / 4'"), "number among its units"),
]


@pytest.mark.parametrize("fields, keyword", [c[1:] for c in SCENE_CASES],
                         ids=[c[0] for c in SCENE_CASES])
def test_scene_values_are_read_never_evaluated(ws, capsys, fields, keyword):
    name = _scene_with(ws, "bad.toml", **fields)
    code, _, err = ehd(capsys, "scene", name)
    assert code == EXIT_USAGE and keyword in err and "Traceback" not in err, err
    assert len(err.strip().splitlines()) == 1


def test_a_scene_file_with_a_byte_order_mark_is_read(ws):
    from pipeline.scenes.commands import load_scene

    (ws / "bom.toml").write_bytes(b"\xef\xbb\xbf" + EXAMPLE.read_bytes())
    assert load_scene("bom.toml", {}, ()) == load_scene(EXAMPLE, {}, ())


def test_a_sweep_file_with_a_byte_order_mark_is_read(ws, capsys):
    (ws / "bom.toml").write_bytes(b"\xef\xbb\xbf" + (ws / "s.toml").read_bytes())
    code, out, err = ehd(capsys, "sweep", "bom.toml", "--executor", "serial")
    assert code == 0 and "cached 8" in out, err


SWEEP_CASES = [
    ("range-one-value-two-ends", "{start = 1.0, stop = 5.0, num = 1}", "one value but two ends"),
]


@pytest.mark.parametrize("grid, keyword", [c[1:] for c in SWEEP_CASES],
                         ids=[c[0] for c in SWEEP_CASES])
def test_sweep_grids_are_honest(ws, capsys, grid, keyword):
    (ws / "g.toml").write_text(sweep_text(grid, EPS, store="g.zarr"))
    code, _, err = ehd(capsys, "sweep", "g.toml", "--executor", "serial")
    assert code == EXIT_USAGE and keyword in err, err
    assert not (ws / "g.zarr").exists()


def test_a_range_of_one_value_with_equal_ends_is_that_value():
    sweep = load_sweep_text(sweep_text("{start = 5.0, stop = 5.0, num = 1}", EPS))
    assert sweep.axes["St"] == (5.0,)


def load_sweep_text(text):
    from pipeline.sweeps.config import parse_sweep

    return parse_sweep(text)


RUN_CASES = [
    ("Pi-minus-inf", ["--Pi", "-inf"], "got -inf"),
    ("St-minus-1e3", ["--St", "-1e3"], "valid range"),
    ("table-and-barus", ["--viscosity", "barus", "--beta", "1", "--viscosity-table", "0:1,1:2"],
     "not both"),
    ("table-and-constant", ["--viscosity", "constant", "--viscosity-table", "0:1,1:2"],
     "not both"),
    ("table-overflows", ["--viscosity-table", "0:1,1:1e308"], "overflows"),
]


@pytest.mark.parametrize("extra, keyword", [c[1:] for c in RUN_CASES],
                         ids=[c[0] for c in RUN_CASES])
def test_run_refuses_conflicts_and_names_the_value(ws, capsys, extra, keyword):
    args = ["run", "--St", "5", "--eps", "0.01"]
    if extra[0] == "--St":
        args = ["run", "--eps", "0.01"]
    code, _, err = ehd(capsys, *args, *extra)
    assert code == EXIT_USAGE and keyword in err and "Traceback" not in err, err
    assert "expected one argument" not in err


@pytest.mark.parametrize("value", ["5", True, b"5", None, [5]])
def test_physics_takes_numbers_only(value):
    from solver.physics import Physics

    with pytest.raises(ValueError, match="must be a number"):
        Physics(St=value, eps=1e-2)


# ---- a grid too large: refused before any allocation, with its size --------------------------
def test_a_grid_too_large_for_memory_is_refused_before_any_allocation(ws, capsys, monkeypatch):
    monkeypatch.setattr(run_module, "available_memory", lambda: 2**30)  # a 1 GiB machine
    eps = json.dumps([float(v) for v in np.geomspace(1e-8, 1e-2, 1000)])
    (ws / "big.toml").write_text(sweep_text("{start = 1.0, stop = 50.0, num = 10000}", [])
                                 .replace("eps = []", f"eps = {eps}").replace(
                                     "results/test.zarr", "big.zarr"))
    for confirm in ([], ["--allow-large"]):  # too large to run unconfirmed; too large for 1 GiB
        t = time.monotonic()
        code, _, err = ehd(capsys, "sweep", "big.toml", "--executor", "serial", *confirm)
        assert code == EXIT_USAGE and "10000000 scenes" in err and "GiB" in err, err
        assert ("--allow-large" in err) == (not confirm)
        assert time.monotonic() - t < 10 and not (ws / "big.zarr").exists() and CALLS == []


def test_planning_a_large_grid_is_announced(capsys):
    import io

    stream = io.StringIO()
    run_module.check_memory(run_module.PLANNING_NOTE, stream)
    assert f"planning {run_module.PLANNING_NOTE} scenes" in stream.getvalue()


# ---- a non-finite result is a failed scene with its reason ---------------------------------------
def test_a_non_finite_result_is_a_failure_with_its_reason(ws, capsys, monkeypatch):
    import math as m

    import solver

    real = solver.collide

    def overflowing(*a, **k):
        c = real(*a, **k)
        c.h_m_x1 = m.inf  # an overflow the solver called ok
        return c

    monkeypatch.setattr(solver, "collide", overflowing)
    code, out, err = ehd(capsys, "run", "--St", "5", "--eps", "0.01", "--accuracy", "fast",
                         "--json")
    d = json.loads(out)
    assert code == 1 and d["status"] == "error" and "non-finite" in d["message"], err
    code, out, err = ehd(capsys, "scene", EXAMPLE, "--accuracy", "fast", "--json")
    d = json.loads(out)
    assert code == 1 and d["status"] == "error" and "non-finite" in d["message"], err
    from pipeline.sweeps.tasks import solve_scene

    rec = solve_scene({"St": 5.0, "eps": 0.01}, "fast", {})
    assert rec["status"] == "error" and "h_m_x1 = inf" in rec["message"]


def test_a_viscosity_ratio_beyond_the_double_range_is_a_result(ws, capsys):
    """Barus beta 10 at St 1.44482, eps 1e-2 (a grid point of sweeps/piezoviscous.toml): the peak
    viscosity ratio exp(beta P) passes the double range, inf as docs/pipeline.md's Variables
    table says, and the solve is ok (v_r 0.0108); it was stored as failed (exit 3)."""
    from pipeline.sweeps.tasks import solve_scene

    scene = {"St": 1.4448217623573683, "eps": 0.01, "beta": 10.0, "viscosity_law": "barus"}
    rec = solve_scene(scene, "fast", {})
    assert rec["status"] == "ok" and rec["viscosity_ratio_max_approach"] == float("inf"), rec
    assert 0.0 < rec["v_r"] < 0.05
    code, out, err = ehd(capsys, "run", "--St", "1.4448217623573683", "--eps", "0.01", "--beta",
                         "10", "--viscosity", "barus", "--accuracy", "fast", "--json")
    assert code == 0 and json.loads(out)["status"] == "ok", err


def test_main_leaves_the_sigterm_handler_as_it_found_it(capsys):
    before = signal.getsignal(signal.SIGTERM)
    assert ehd(capsys, "info")[0] == 0
    assert signal.getsignal(signal.SIGTERM) is before


# ---- ehd restitution along paths that leave the model's range (a helper's scan) --------------
STEEL = REPO / "examples" / "steel_ball_glass_wall_glycerol.toml"


def test_restitution_threshold_keeps_the_path_where_a_point_is_refused(tmp_path, capsys):
    """A path whose smallest size leaves the model (eps 0.215 > 0.1) is skipped in the table; the
    threshold solved the whole path again, met the refusal and ended with exit 2, --out and
    --plot not written. It now reads the path's solved points and bisects between them."""
    out, fig = tmp_path / "out", tmp_path / "fig"
    code = main(["restitution", str(STEEL), "--vary", "radius", "--from", "0.01", "--to", "10",
                 "--n", "4", "--threshold", "--accuracy", "fast", "--out", str(out),
                 "--plot", str(fig)])
    text = capsys.readouterr().out
    assert code == 0 and "skipped: radius x 0.01: eps = 0.215" in text
    assert text.count("St_c = ") == 2 and (out / "restitution.csv").is_file()
    assert (fig / "restitution.png").is_file()


def test_restitution_threshold_on_a_path_run_downwards(capsys):
    """--from above --to: the table ran from 10 down to 0.1 with one change from rebound to
    stick, and the threshold said the spheres alternate; the factors are now taken in order."""
    args = ["restitution", str(EXAMPLE), "--n", "5", "--threshold", "--accuracy", "fast"]
    assert main(args + ["--from", "0.1", "--to", "10"]) == 0
    text = capsys.readouterr().out
    up = [line for line in text.splitlines() if "St_c = " in line]
    # the scene's own speed (x 1): ehd scene's verdict is "stick" (its e_far is 0, a dry DEM
    # code's), while e_wet is 0.18; the row had no note, it now says in which e it sticks
    assert any(line.split()[3] == "0.1" and line.endswith("sticks in e_far (dry DEM)")
               for line in text.splitlines()), text
    assert main(args + ["--from", "10", "--to", "0.1"]) == 0
    down = [line for line in capsys.readouterr().out.splitlines() if "St_c = " in line]
    assert len(up) == 2 and len(down) == 2

    def st_c(line):
        return float(line.split("St_c = ")[1].split()[0])

    # the same bracket from the same points (bisected to RTOL 1e-3, printed to 4 digits): equal
    # to within one bracket, not to the bit (a path's factors may round differently either way)
    for a, b in zip(up, down):
        assert st_c(a) == pytest.approx(st_c(b), rel=2e-3), (a, b)


def test_restitution_names_only_the_points_it_solved(capsys):
    """--n 1 solved x 0.1 alone and said the spheres stick at every v0 from 0.1 to 10 (they
    rebound at 10). One point now takes one factor (--n 1 with the range 0.1-10 solved 0.1
    quietly: refused, as a sweep's range of one point is)."""
    assert main(["restitution", str(EXAMPLE), "--from", "0.1", "--to", "0.1", "--n", "1",
                 "--threshold", "--accuracy", "fast"]) == 0
    text = capsys.readouterr().out
    assert "stick at v0 x 0.1;" in text and "from 0.1 to 10" not in text
    assert main(["restitution", str(EXAMPLE), "--n", "1", "--accuracy", "fast"]) == EXIT_USAGE
    assert "one point takes one factor" in capsys.readouterr().err


@pytest.mark.parametrize("flags", [["--n", "10000000000"], ["--n", "0"]])
def test_restitution_refuses_a_path_of_impossible_length(flags, capsys):
    """10^10 points raised numpy's memory error (exit 70) before the first solve."""
    assert main(["restitution", str(EXAMPLE), *flags]) == EXIT_USAGE
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--n" in err[0] and "from 1 to 10000" in err[0]


def test_restitution_of_a_settling_scene_has_a_path_in_size_only(tmp_path, capsys):
    """A settling scene's speed follows from its bodies: along --vary v0 its approach speed was
    mapped through the outer flow without gravity (2.9 m/s where it settles at 23 mm/s), and
    along --vary approach_speed every point stopped before x0, x 1 too; refused, exit 2. Its
    path in size settles at each size, as before."""
    scene = tmp_path / "settling.toml"
    scene.write_text(STEEL.read_text().replace('v0 = "1 m/s"', 'approach_speed = "settling"'))
    for vary in ("v0", "approach_speed"):
        assert main(["restitution", str(scene), "--vary", vary, "--n", "2"]) == EXIT_USAGE
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "settles at its own speed" in err[0], err
    assert main(["restitution", str(scene), "--vary", "radius", "--from", "1", "--to", "2",
                 "--n", "2", "--accuracy", "fast"]) == 0
    # x 1: the approach speed the scene settles at (ehd scene: 22.77 mm/s), in the V column
    row = capsys.readouterr().out.splitlines()[1].split()
    assert row[4] == "0.02277", row


def test_examples_into_a_read_only_subfolder_is_refused_before_writing(tmp_path, capsys,
                                                                      monkeypatch):
    """DIR writable, DIR/examples read-only: the copy failed with exit 74 ("Permission denied"),
    where docs/pipeline.md says a read-only folder is exit 2 before any work. (os.access is
    the check; its answer is faked here, since root writes anywhere.)"""
    import pipeline.cli_shared as shared

    (tmp_path / "examples").mkdir()
    locked = str(tmp_path / "examples")
    real = os.access
    monkeypatch.setattr(shared.os, "access",
                        lambda p, mode: False if str(p) == locked else real(p, mode))
    assert main(["examples", str(tmp_path)]) == EXIT_USAGE
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is not writable" in err[0] and "examples" in err[0]
    assert not any((tmp_path / "examples").iterdir())


@pytest.mark.parametrize("command", ["scene", "restitution"])
def test_an_empty_scene_path_is_named(command, capsys):
    """'' was read as no file, and the refusal said "missing the table [body1]"."""
    assert main([command, ""]) == EXIT_USAGE
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "empty scene file path" in err[0]
