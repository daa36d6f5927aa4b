"""Nothing wrong stored or shown (issue 27, the store's part): checksums that bind every value
to its place, journal records that are whole and within physics, readers that see one
consistent state while a sweep writes, figures that record the state they read, and bounded,
typed reads of every store file.

Each reproduction of the issue is a case here: the documented exit code and one line (or the
right result). The cases run ``pipeline.cli.main`` in this process on copies of one tiny store
built with the stand-in solver (tests/test_hostile.py: ``base``, ``ws``); the races run a sweep
in a subprocess.
"""

from __future__ import annotations

import functools
import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
import warnings
from contextlib import contextmanager

import numpy as np
import pytest
import xarray as xr

import pipeline.sweeps.run as run_module
from pipeline.errors import EXIT_DAMAGED, EXIT_USAGE, StoreDamaged
from pipeline.sweeps.config import load_sweep
from pipeline.sweeps.manifest import MANIFEST_NAME, READERS_LOCK
from tests.test_hostile import EPS, REPO, ST, _stored, base, ehd, tree_hash, ws  # noqa: F401
from tests.test_pipeline import CALLS, fake_solve, sweep_text


def _one_error(err: str) -> str:
    """The one error line of a command's stderr (no traceback, nothing else)."""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert "error" in lines[0], err
    return lines[0]


def other_solve(physics, accuracy, overrides):
    """The stand-in, with other numbers: a store of the same shape whose chunks are whole and
    checksummed but hold other values."""
    rec = fake_solve(physics, accuracy, overrides)
    if rec["status"] == "ok":
        rec["v_r"] = 0.5 * rec["v_r"]
        rec["h_m_x1"] = 2.0 * rec["h_m_x1"]
    return rec


@pytest.fixture(scope="module")
def other(tmp_path_factory):
    """A second store over the same grid (another sweep name), other values."""
    d = tmp_path_factory.mktemp("other")
    (d / "o.toml").write_text(sweep_text(ST, EPS, store="o.zarr").replace('name = "test"',
                                                                           'name = "other"'))
    run_module.run_sweep(load_sweep(d / "o.toml").with_store(d / "o.zarr"), runner="serial",
                         solve=other_solve, progress=None)
    return d / "o.zarr"


def _all_readers_refuse(ws, capsys, keyword, code=EXIT_DAMAGED):
    """``status``, ``figures``, ``sweep`` and ``open_results``: ``code``, one line with
    ``keyword``; nothing computed, nothing drawn."""
    from pipeline import open_results

    for argv in (["status", "s.zarr"], ["figures", "s.zarr", "--out", "fig"],
                 ["sweep", "s.toml", "--executor", "serial"]):
        got, out, err = ehd(capsys, *argv)
        assert got == code, (argv, err)
        assert keyword in _one_error(err), (argv, err)
    with pytest.raises(StoreDamaged, match=keyword):
        open_results(ws / "s.zarr")
    assert CALLS == [] and not (ws / "fig").exists()


# ==== 4. checksums that bind a value to its place =================================================
def _copy(src, dst):
    return lambda ws, other: shutil.copyfile(ws / src, ws / dst)


def _from_other(rel):
    return lambda ws, other: shutil.copyfile(other / rel, ws / "s.zarr" / rel)


@pytest.mark.parametrize("damage, row", [
    (_copy("s.zarr/v_r/c/0/0", "s.zarr/v_r/c/2/0"), 2),
    (_copy("s.zarr/h_m_x1/c/1/0", "s.zarr/h_m_x0/c/1/0"), 1),
    (_from_other("v_r/c/3/0"), 3),
    (_copy("s.zarr/steps/c/0/0", "s.zarr/steps/c/3/0"), 3),
], ids=["another-cells-chunk", "another-variables-chunk", "another-stores-chunk",
        "another-cells-count"])
def test_a_chunk_copied_from_elsewhere_is_found_and_recomputed(ws, base, other, capsys, damage,
                                                               row):
    """``cp v_r/c/0/0 v_r/c/2/0``: whole, checksummed chunks, but not the ones written there
    (issue 27: status and figures 0, v_r shown from another row). Every reader refuses them,
    the sweep recomputes that row and nothing else."""
    from pipeline import open_results

    damage(ws, other)
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED and "(replaced)" in _one_error(err), err
    assert f"St={ST[row]:g} " in err
    code, _, err = ehd(capsys, "figures", "s.zarr", "--out", "fig")
    assert code == EXIT_DAMAGED and "(replaced)" in _one_error(err) and not (ws / "fig").exists()
    with pytest.raises(StoreDamaged, match="replaced"):
        open_results(ws / "s.zarr")
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "repaired" in out, out + err
    assert sorted(CALLS) == sorted((ST[row], e) for e in EPS)  # that row, nothing else
    xr.testing.assert_identical(_stored(ws / "s.zarr"), _stored(base / "s.zarr"))
    assert ehd(capsys, "status", "s.zarr")[0] == 0


def test_a_chunk_where_none_was_written_is_found(ws, capsys):
    """A chunk whose cells are all at their fill value has no file (zarr writes none); a copy
    put there is not the store's either."""
    from pipeline.sweeps.layout import VARIABLES
    from pipeline.sweeps.manifest import read_manifest

    chunks = read_manifest(ws / "s.zarr")[0]["chunks"]
    absent = next(f"{n}/c/{i}/0" for n in VARIABLES for i in range(len(ST))
                  if f"{n}/c/{i}/0" not in chunks)
    name = absent.split("/")[0]
    source = next((k for k in sorted(chunks) if k.startswith(f"{name}/")), "v_r/c/0/0")
    shutil.copyfile(ws / "s.zarr" / source, ws / "s.zarr" / absent)
    code, _, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED and f"{name} (replaced)" in _one_error(err), err


def _link_chunk(ws, other):
    target = ws / "s.zarr" / "v_r" / "c" / "0" / "0"
    (ws / "s.zarr" / "v_r" / "c" / "2" / "0").unlink()
    os.symlink(target, ws / "s.zarr" / "v_r" / "c" / "2" / "0")


def _link_folder(ws, other):
    shutil.rmtree(ws / "s.zarr" / "v_r")
    os.symlink(other / "v_r", ws / "s.zarr" / "v_r")


def _link_row_folder(ws, other):
    shutil.rmtree(ws / "s.zarr" / "h_m_x1" / "c" / "1")
    os.symlink(other / "h_m_x1" / "c" / "1", ws / "s.zarr" / "h_m_x1" / "c" / "1")


def _link_to_device(ws, other):
    (ws / "s.zarr" / "steps" / "c" / "1" / "0").unlink()
    os.symlink("/dev/zero", ws / "s.zarr" / "steps" / "c" / "1" / "0")


@pytest.mark.parametrize("link", [_link_chunk, _link_folder, _link_row_folder, _link_to_device],
                         ids=["chunk-to-another-rows", "variable-folder-to-another-store",
                              "row-folder-to-another-store", "chunk-to-dev-zero"])
def test_links_inside_a_store_are_refused(ws, other, capsys, link):
    """A chunk replaced by a link to another row's, a variable folder linked to another store of
    the same shape (issue 27: read as this store's own): every reader refuses the store with
    one line, exit 5, and the sweep writes nothing, into either store."""
    link(ws, other)
    before, theirs = tree_hash(ws / "s.zarr"), tree_hash(other)
    _all_readers_refuse(ws, capsys, "symbolic link")
    assert tree_hash(ws / "s.zarr") == before and tree_hash(other) == theirs


def test_a_store_reached_through_a_link_is_still_read(ws, capsys):
    """Links *inside* a store are refused; the store's own path may be one (one lock, one
    journal: pipeline/sweeps/store.py)."""
    os.symlink(ws / "s.zarr", ws / "link.zarr")
    code, out, err = ehd(capsys, "status", "link.zarr")
    assert code == 0, err


# ---- the metadata and the manifest ----------------------------------------------------------------
def _edit_json(rel, edit):
    def make(ws):
        p = ws / "s.zarr" / rel
        meta = json.loads(p.read_text())
        edit(meta)
        p.write_text(json.dumps(meta))
    return make


def _manifest_from(ws, other):
    shutil.copyfile(other / MANIFEST_NAME, ws / "s.zarr" / MANIFEST_NAME)


def _manifest_digest_edited(meta):
    key = sorted(meta["chunks"])[0]
    meta["chunks"][key] = "0" * 64


@pytest.mark.parametrize("setup, keyword", [
    (_edit_json("v_r/zarr.json", lambda m: m.update(codecs=m["codecs"][:2])), "v_r/zarr.json"),
    (_edit_json("status/zarr.json", lambda m: m.update(fill_value=1)), "status/zarr.json"),
    (lambda ws, o: (ws / "s.zarr" / "eps" / "zarr.json").unlink(), "eps/zarr.json is missing"),
    (lambda ws, o: (ws / "s.zarr" / MANIFEST_NAME).unlink(), "manifest"),
    (_edit_json(MANIFEST_NAME, _manifest_digest_edited), "its own checksum"),
    (_manifest_from, "other metadata"),
    (lambda ws, o: (ws / "s.zarr" / MANIFEST_NAME).write_bytes(b"\xff" * 100), "manifest"),
], ids=["array-codecs-edited", "array-fill-value-edited", "array-metadata-deleted",
        "manifest-deleted", "manifest-digest-edited", "manifest-of-another-store",
        "manifest-garbage"])
def test_metadata_and_manifest_damage_is_one_line_for_every_reader(ws, other, capsys, setup,
                                                                   keyword):
    """Every array's own zarr.json is checked against its copy under ``metadata_sha256`` (issue
    27: an edited codec list made every sweep print "repaired 2" and exit 0 while status and
    figures exited 5): no reader and no sweep goes on, each says so in one line, exit 5."""
    if setup.__code__.co_argcount == 2:
        setup(ws, other)
    else:
        setup(ws)
    before = tree_hash(ws / "s.zarr")
    _all_readers_refuse(ws, capsys, keyword)
    assert tree_hash(ws / "s.zarr") == before


def test_an_older_schema_is_refused_with_its_reason(ws, capsys):
    from pipeline.sweeps.layout import STORE_SCHEMA

    p = ws / "s.zarr" / "zarr.json"
    meta = json.loads(p.read_text())
    meta["attributes"]["store_schema"] = 7  # before the manifest: its chunks are not bound
    p.write_text(json.dumps(meta))
    code, _, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_USAGE and "not bound to their places" in _one_error(err), err
    meta["attributes"]["store_schema"] = STORE_SCHEMA - 1  # the last one: another version
    p.write_text(json.dumps(meta))
    code, _, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_USAGE and f"store schema {STORE_SCHEMA - 1}," in _one_error(err), err


def test_every_chunk_is_in_the_manifest_and_the_manifest_is_current(ws):
    from pipeline.sweeps.manifest import digest, read_manifest

    manifest = read_manifest(ws / "s.zarr")[0]
    files = {str(p.relative_to(ws / "s.zarr")) for p in (ws / "s.zarr").rglob("*")
             if p.is_file() and p.name not in ("zarr.json", MANIFEST_NAME, READERS_LOCK)}
    assert set(manifest["chunks"]) == files and manifest["writing"] is None
    for key, d in manifest["chunks"].items():
        assert digest((ws / "s.zarr" / key).read_bytes()) == d, key


# ---- journal records: their own checksum, values within physics ---------------------------------
def _journal_for(ws, extra_st):
    """A journal holding the records of the scenes at ``extra_st`` (a sweep killed before it
    merged them: tests/test_pipeline.py), the grid extended to them."""
    from pipeline.sweeps.store import SweepStore

    (ws / "s.toml").write_text(sweep_text(ST + [extra_st], EPS, store="s.zarr"))
    sweep = load_sweep(ws / "s.toml")
    with SweepStore.open(sweep, flush_seconds=1e9) as st:
        for cell in st.cells(sweep):
            if st.scene(cell)["St"] == extra_st:
                st.record(cell, fake_solve(st.scene(cell), "fast", {}), now=0.0)
        st._dirty.clear()  # the kill: nothing merged
        st._close_journal()
    CALLS.clear()
    return ws / "s.zarr.journal"


def _edit_line(value_edit, reseal=False):
    def make(journal):
        from pipeline.sweeps.journal import CHECKSUM_KEY, journal_line

        lines = journal.read_text().splitlines()
        rec = json.loads(lines[0])
        value_edit(rec)
        if reseal:  # a writer computing the checksum over wrong values: the range check
            rec.pop(CHECKSUM_KEY)
            lines[0] = journal_line(rec).rstrip("\n")
        else:
            lines[0] = json.dumps(rec)
        journal.write_text("\n".join(lines) + "\n")
    return make


@pytest.mark.parametrize("edit", [
    _edit_line(lambda r: r.update(v_r=7.5)),
    _edit_line(lambda r: r.update(e_wet=3.0)),
    _edit_line(lambda r: r.update(v_r=7.5), reseal=True),
    _edit_line(lambda r: r.update(e_wet=3.0), reseal=True),
    _edit_line(lambda r: r.update(e_far=-0.5), reseal=True),
    _edit_line(lambda r: r.update(steps=-3), reseal=True),
    _edit_line(lambda r: r.update(v_r="fast"), reseal=True),
    _edit_line(lambda r: r.update(status=["ok"]), reseal=True),
    # the second hostile run: a count beyond the store's int32 (exit 70 on every rerun), a
    # negative gap, a NaN ln x_e in an ok scene
    _edit_line(lambda r: r.update(steps=2**40), reseal=True),
    _edit_line(lambda r: r.update(h_m_x1=-3.0), reseal=True),
    _edit_line(lambda r: r.update(ln_x_e_x1=float("nan")), reseal=True),
], ids=["v_r-edited", "e_wet-edited", "v_r-7.5-checksummed", "e_wet-3-checksummed",
        "e_far-negative-checksummed", "steps-negative-checksummed", "v_r-text-checksummed",
        "status-a-list-checksummed", "steps-2**40-checksummed", "h_m-negative-checksummed",
        "ln_x_e-nan-checksummed"])
def test_a_bad_journal_record_is_skipped_counted_and_computed_again(ws, capsys, edit):
    """``v_r = 7.5`` or ``e_wet = 3.0`` edited into a journal line (issue 27: merged, then
    protected as cached): an edited line fails its checksum, a value outside what physics
    allows (or of the wrong type) fails the range check; either is skipped and counted like a
    line cut short, and its scene is computed again."""
    journal = _journal_for(ws, 40.0)
    edited = json.loads(journal.read_text().splitlines()[0])["physics"]
    edit(journal)
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == 0 and "1 " in out and "bad lines skipped" in out, out + err
    assert "finished scenes not yet in the store" in out  # the other record is still good
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "bad lines skipped" in out, out + err
    assert CALLS == [(edited["St"], edited["eps"])]  # the edited scene only, computed again
    ds = xr.open_zarr(ws / "s.zarr").sel(St=40.0).load()
    assert np.all(ds.status.values == 1)
    np.testing.assert_array_equal(ds.v_r.values, [40.0 / 50.0] * len(EPS))
    assert np.all((ds.e_wet.values >= 0) & (ds.e_wet.values <= 1))


def test_a_journal_record_off_the_grid_lands_in_no_cell(ws, capsys):
    """A checksummed record whose coordinate is a list (``St: [[40.0]]``) matched the first row
    of a 2-D comparison and wrote its values into another scene's cell (the second hostile
    run); it lands nowhere and its scene is computed again."""
    journal = _journal_for(ws, 40.0)
    physics = json.loads(journal.read_text().splitlines()[0])["physics"]
    _edit_line(lambda r: r.update(v_r=0.9, physics={**r["physics"], "St": [[r["physics"]["St"]]]}),
               reseal=True)(journal)
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0, out + err
    assert "bad lines skipped" in out  # counted, not dropped without a word
    assert CALLS == [(physics["St"], physics["eps"])]
    ds = xr.open_zarr(ws / "s.zarr").load()
    assert not np.any(ds.v_r.values == 0.9)


def test_a_workers_record_outside_physics_is_stored_as_an_error(ws, capsys, monkeypatch):
    def wrong(physics, accuracy, overrides):
        rec = fake_solve(physics, accuracy, overrides)
        rec["v_r"] = 7.5
        return rec

    (ws / "s.toml").write_text(sweep_text(ST + [40.0], EPS, store="s.zarr"))
    monkeypatch.setattr(run_module, "run_sweep",
                        functools.partial(run_module.run_sweep.func, solve=wrong, warm_up=False,
                                          progress=None))
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 3 and "v_r = 7.5 is outside [0, 1]" in out, out + err
    ds = xr.open_zarr(ws / "s.zarr").sel(St=40.0).load()
    assert np.all(ds.status.values == 5) and np.all(np.isnan(ds.v_r.values))


# ==== 5. races: one consistent state per read ======================================================
def test_figures_record_the_state_they_read(ws, capsys, monkeypatch):
    """A sweep that finishes between ``ehd figures``' read of the store and its stamp (issue 27:
    the figures of the half store were then certified "up to date"): the next ``ehd figures``
    reads the store again and redraws."""
    import pipeline.sweeps.commands as commands
    from pipeline.plots import sweep_maps
    from pipeline.plots.sweep_maps import fingerprint
    from pipeline.sweeps.integrity import load_checked
    from tests.test_pipeline import stand_in_render

    monkeypatch.setattr(sweep_maps, "render_all", stand_in_render)  # the stamp is under test
    (ws / "more.toml").write_text(sweep_text(ST + [40.0, 60.0], EPS, store="s.zarr"))
    real = commands._open_checked

    def read_then_sweep(store):
        read = real(store)
        run_module.run_sweep(load_sweep("more.toml"), runner="serial")  # finishes meanwhile
        return read

    monkeypatch.setattr(commands, "_open_checked", read_then_sweep)
    code, out, err = ehd(capsys, "figures", "s.zarr", "--out", "fig")
    assert code == 0 and "up to date" not in out, err
    monkeypatch.setattr(commands, "_open_checked", real)
    code, out, err = ehd(capsys, "figures", "s.zarr", "--out", "fig")
    assert code == 0 and "up to date" not in out, out + err  # drawn again, from the whole store
    stamp = json.loads((ws / "fig" / ".sweep-figures.sha256").read_text())
    assert stamp["fingerprint"] == fingerprint(load_checked(ws / "s.zarr")[0])
    code, out, err = ehd(capsys, "figures", "s.zarr", "--out", "fig")
    assert code == 0 and "up to date" in out


def test_a_read_that_a_sweep_changed_is_read_again(ws, monkeypatch):
    """A merge landing while a reader reads: its data chunks read before the merge, its status
    chunk after (issue 27: exit 5 and StoreDamaged in 1-2 % of reads during a healthy sweep).
    That read sees ok cells without data, but the manifest differs after it: it is read again,
    and the reader gets the new state whole, undamaged."""
    from pipeline.sweeps import integrity
    from pipeline.sweeps.store import SweepStore

    (ws / "s.toml").write_text(sweep_text(ST + [40.0], EPS, store="s.zarr"))
    sweep = load_sweep(ws / "s.toml")
    with SweepStore.open(sweep):
        pass  # the grid extended, St = 40 not run
    real_variable, real_once = integrity._load_variable, integrity._load_once
    merging, reads = [], []

    def load_variable(ds, name, damage, **kwargs):
        if name == "status" and not merging:  # the data is read: now the merge lands
            merging.append(True)
            with SweepStore.open(sweep) as st:
                for cell in st.cells(sweep):
                    if st.scene(cell)["St"] == 40.0:
                        st.record(cell, fake_solve(st.scene(cell), "fast", {}), now=0.0)
            merging[0] = False
        real_variable(ds, name, damage, **kwargs)

    def load_once(*args, **kwargs):
        result = real_once(*args, **kwargs)
        if not any(merging):  # the reader's, not the writer's own read of the store
            reads.append(result)
        return result

    monkeypatch.setattr(integrity, "_load_variable", load_variable)
    monkeypatch.setattr(integrity, "_load_once", load_once)
    # the merge in this very process waits for the read's shared lock, then goes on (as a
    # merge does when a reader holds it past MERGE_WAIT): the case the manifest check is for
    monkeypatch.setattr("pipeline.sweeps.manifest.MERGE_WAIT", 0.1)
    ds, damage = integrity.load_checked(ws / "s.zarr")
    first = reads[0][1]
    assert len(reads) == 2 and "v_r (missing)" in first.variables()  # the race, in that read
    assert not damage and ds is reads[-1][0]
    assert np.all(ds.sel(St=40.0).status.values == 1)


def _mark_writing(ws, pid, keys=("v_r/c/1/0",)):
    """The manifest as a writer (``pid``) leaves it between its two manifests."""
    import socket

    from pipeline.sweeps.manifest import read_manifest, write_manifest

    manifest = read_manifest(ws / "s.zarr")[0]
    write_manifest(ws / "s.zarr", {**manifest, "writing": {
        "keys": list(keys), "metadata": False, "pid": pid, "host": socket.gethostname()}})
    return manifest


def test_a_reader_waits_for_a_live_writer_between_its_manifests(ws, monkeypatch):
    from pipeline.sweeps import integrity
    from pipeline.sweeps.manifest import write_manifest

    shutil.copyfile(ws / "s.zarr" / "v_r" / "c" / "0" / "0", ws / "s.zarr" / "v_r" / "c" / "1"
                    / "0")  # what the writer is writing: not in the manifest yet
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        manifest = _mark_writing(ws, sleeper.pid)
        from pipeline.sweeps.manifest import digest

        data = (ws / "s.zarr" / "v_r" / "c" / "1" / "0").read_bytes()
        sealed = {**manifest, "generation": manifest["generation"] + 1,
                  "chunks": {**manifest["chunks"], "v_r/c/1/0": digest(data)}}
        timer = threading.Timer(0.5, write_manifest, (ws / "s.zarr", sealed))
        t = time.monotonic()
        timer.start()
        ds, damage = integrity.load_checked(ws / "s.zarr")
        assert time.monotonic() - t >= 0.5 and not damage  # waited, then read the new state
    finally:
        sleeper.kill()
        sleeper.wait()


def test_a_dead_writers_manifest_is_not_waited_for_and_is_settled(ws, capsys):
    """A writer killed between its two manifests: readers go on at once (the chunks it was
    writing checked by their CRC-32C) and the next sweep publishes the manifest again."""
    from pipeline.sweeps.integrity import load_checked
    from pipeline.sweeps.manifest import read_manifest

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    _mark_writing(ws, gone.pid)
    t = time.monotonic()
    ds, damage = load_checked(ws / "s.zarr")
    assert not damage and time.monotonic() - t < 10
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and CALLS == [], out + err
    assert read_manifest(ws / "s.zarr")[0]["writing"] is None


RACE_SWEEP = textwrap.dedent("""\
    import functools, sys, time
    sys.path.insert(0, {repo!r})
    import pipeline.sweeps.run as r
    import pipeline.sweeps.store as s
    from tests.test_pipeline import fake_solve

    def slow(physics, accuracy, overrides):
        time.sleep(0.05)
        return fake_solve(physics, accuracy, overrides)

    if __name__ == "__main__":
        s.FLUSH_SECONDS = 0.2  # ten times the merges of a real sweep: chances to race
        r.run_sweep = functools.partial(r.run_sweep, solve=slow, warm_up=False)
        from pipeline.cli import main
        sys.exit(main(sys.argv[1:]))
    """)


def test_readers_see_a_consistent_store_while_a_sweep_writes_it(ws, capsys):
    """``ehd status`` and ``open_results`` during a healthy sweep (issue 27: exit 5 and
    ``StoreDamaged`` in 1-2 % of reads, with a merge every 2 s; here every 0.2 s): never
    damaged, and they see the sweep's progress."""
    from pipeline import open_results

    st = [round(float(v), 6) for v in np.geomspace(1.0, 50.0, 20)]
    (ws / "r.toml").write_text(sweep_text(st, EPS, store="r.zarr"))
    run_module.run_sweep(load_sweep(ws / "r.toml"), runner="serial")
    (ws / "race.py").write_text(RACE_SWEEP.format(repo=str(REPO)))
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
    (ws / "r.toml").write_text(sweep_text(st + [60.0 + i for i in range(20)], EPS,
                                          store="r.zarr"))
    proc = subprocess.Popen([sys.executable, "race.py", "sweep", "r.toml", "--executor",
                             "serial"], cwd=ws, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    seen, reads = set(), 0
    try:
        while proc.poll() is None or reads < 4:
            if reads % 2:
                with warnings.catch_warnings():  # the journal of scenes not merged yet
                    warnings.simplefilter("ignore")
                    ds = open_results(ws / "r.zarr", chunks=None)
                seen.add(int((ds.status.values == 1).sum()))
            else:
                code, out, err = ehd(capsys, "status", "r.zarr")
                assert code == 0, err
            reads += 1
    finally:
        proc.wait(timeout=120)
    assert proc.returncode == 0, proc.stderr.read()
    assert len(seen) >= 3, seen  # read while the sweep wrote, not only before or after it


# ==== 6. bounded, typed input ========================================================================
def _fifo(rel):
    def make(ws):
        p = ws / rel
        p.unlink(missing_ok=True)
        os.mkfifo(p)
    return make


def _sparse(rel, size):
    def make(ws):
        with open(ws / rel, "wb") as f:
            f.truncate(size)
    return make


def _device(rel):
    def make(ws):
        import stat

        p = ws / rel
        p.unlink(missing_ok=True)
        try:
            os.mknod(p, 0o644 | stat.S_IFCHR, os.makedev(1, 7))  # /dev/full's numbers
        except PermissionError:
            pytest.skip("no permission to make a device node here")
    return make


@contextmanager
def _deadline(seconds):
    """SIGALRM after ``seconds``: a blocking open or an endless read in this thread raises."""
    def expired(signum, frame):
        raise TimeoutError(f"still reading after {seconds} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.mark.parametrize("setup, argv, code, keyword", [
    (lambda ws: os.symlink("/dev/full", ws / "s.zarr.journal"), ["sweep", "s.toml"],
     EXIT_DAMAGED, "symbolic link"),
    (lambda ws: os.symlink("/dev/full", ws / "s.zarr.journal"), ["status", "s.zarr"],
     EXIT_DAMAGED, "symbolic link"),
    (_fifo("s.zarr.journal"), ["sweep", "s.toml"], EXIT_DAMAGED, "FIFO"),
    (_fifo("s.zarr.journal"), ["status", "s.zarr"], EXIT_DAMAGED, "FIFO"),
    (_sparse("s.zarr.journal", 300 * 2**20), ["sweep", "s.toml"], EXIT_DAMAGED, "more than"),
    (_fifo("s.zarr/v_r/c/1/0"), ["status", "s.zarr"], EXIT_DAMAGED, "FIFO"),
    (_fifo("s.zarr/steps/c/2/0"), ["sweep", "s.toml"], EXIT_DAMAGED, "FIFO"),
    (_fifo("s.zarr/zarr.json"), ["figures", "s.zarr", "--out", "fig"], EXIT_DAMAGED, "FIFO"),
    (_fifo(f"s.zarr/{MANIFEST_NAME}"), ["status", "s.zarr"], EXIT_DAMAGED, "FIFO"),
    (_fifo("s.zarr/v_r/zarr.json"), ["status", "s.zarr"], EXIT_DAMAGED, "FIFO"),
    (_device("s.zarr/status/c/0/0"), ["status", "s.zarr"], EXIT_DAMAGED, "character device"),
    (_fifo("s.zarr.lock"), ["sweep", "s.toml"], EXIT_USAGE, "FIFO"),
    (lambda ws: os.symlink("/dev/full", ws / "s.zarr.lock"), ["sweep", "s.toml"], EXIT_USAGE,
     "symbolic link"),
], ids=["journal-to-dev-full-sweep", "journal-to-dev-full-status", "journal-fifo-sweep",
        "journal-fifo-status", "journal-300MiB", "chunk-fifo-status", "chunk-fifo-sweep",
        "root-metadata-fifo", "manifest-fifo", "array-metadata-fifo", "chunk-device",
        "lock-fifo", "lock-to-dev-full"])
def test_store_files_are_regular_and_bounded(ws, capsys, setup, argv, code, keyword):
    """A journal linked to /dev/full (issue 27: ``ehd sweep`` grew to 24 GB until the kernel
    killed it), a FIFO as a chunk or a journal (blocked forever): one line and the documented
    code, at once, nothing computed. Under a deadline: a read that blocks or never ends fails
    the test instead of hanging it."""
    setup(ws)
    with _deadline(10):
        got, out, err = ehd(capsys, *argv, *(["--executor", "serial"] if argv[0] == "sweep"
                                             else []))
    assert got == code, err
    assert keyword in _one_error(err), err
    assert CALLS == []


def test_a_chunk_larger_than_a_chunk_can_be_is_damage_not_a_read(ws, base, capsys):
    """A sparse 1 GiB file as a chunk is not read into memory: it is unreadable, and the sweep
    recomputes its row."""
    _sparse("s.zarr/steps/c/3/0", 2**30)(ws)
    code, _, err = ehd(capsys, "status", "s.zarr")
    assert code == EXIT_DAMAGED and "steps (unreadable)" in _one_error(err), err
    code, out, err = ehd(capsys, "sweep", "s.toml", "--executor", "serial")
    assert code == 0 and "repaired" in out, out + err
    assert sorted(CALLS) == sorted((ST[3], e) for e in EPS)
    xr.testing.assert_identical(_stored(ws / "s.zarr"), _stored(base / "s.zarr"))


def test_a_journal_line_longer_than_any_record_is_skipped(ws, capsys):
    (ws / "s.zarr.journal").write_bytes(b"[" * (3 * 2**20) + b"\n" + b"{}\n")
    code, out, err = ehd(capsys, "status", "s.zarr")
    assert code == 0 and "2 " in out and "bad lines skipped" in out, out + err


class _Killed(BaseException):
    """A kill -9 at this instant, as far as the files are concerned."""


def test_a_kill_while_the_sweep_file_is_recorded_leaves_a_readable_store(ws, monkeypatch):
    """A sweep whose file text changed records it in the root attributes. Through zarr that was
    two writes, the first without the consolidated metadata: a kill -9 between them (2 of 46
    kill timings in the second hostile run) left a store every reader and sweep refused, every
    scene lost. Now one atomic replace: killed at any write of it, the store reads as before."""
    import zarr

    import pipeline.sweeps.store as store_module
    from pipeline import open_results

    def killed(*a, **k):
        raise _Killed()

    (ws / "s.toml").write_text(sweep_text(ST, EPS, store="s.zarr") + "# a comment\n")
    with monkeypatch.context() as m:
        m.setattr(zarr, "consolidate_metadata", killed)  # the second write of zarr's way
        try:
            run_module.run_sweep(load_sweep(ws / "s.toml"), runner="serial", solve=fake_solve,
                                 progress=None)
        except _Killed:
            pass
    with open_results(ws / "s.zarr") as ds:
        assert int((ds.status.values == 1).sum()) == len(ST) * len(EPS)
    # killed at the one write it takes now, before the replace: the old metadata stands
    (ws / "s.toml").write_text(sweep_text(ST, EPS, store="s.zarr") + "# another comment\n")
    real = store_module.os.replace

    def killed_at_the_metadata(src, dst, *a, **k):
        if str(dst).endswith("s.zarr/zarr.json"):
            raise _Killed()
        return real(src, dst, *a, **k)

    with monkeypatch.context() as m, pytest.raises(_Killed):
        m.setattr(store_module.os, "replace", killed_at_the_metadata)
        run_module.run_sweep(load_sweep(ws / "s.toml"), runner="serial", solve=fake_solve,
                             progress=None)
    with open_results(ws / "s.zarr") as ds:
        assert int((ds.status.values == 1).sum()) == len(ST) * len(EPS)


def test_the_store_state_survives_a_file_that_goes_while_it_is_walked(ws, monkeypatch):
    """A file a sweep removes while ``ehd figures`` takes the store's state (a zarr temporary,
    a re-layout's old store) raised FileNotFoundError: exit 70 in the second hostile run."""
    import os as os_module

    from pipeline.plots import stamp

    real = os_module.lstat
    gone = []

    def vanishing(path, *a, **k):
        if not gone and str(path).endswith("zarr.json") and "v_r" in str(path):
            gone.append(path)
            raise FileNotFoundError(path)
        return real(path, *a, **k)

    monkeypatch.setattr(stamp.os, "lstat", vanishing)
    first = stamp.store_state(ws / "s.zarr")
    monkeypatch.undo()
    assert gone and first is not None and first != stamp.store_state(ws / "s.zarr")


def test_a_folder_without_a_zarr_group_has_no_store_state(tmp_path, monkeypatch):
    """``ehd figures /`` walked the whole file system to take the "store's" state (24 s here)
    before it said the root folder is no store: a folder without a zarr group at its top is not
    walked at all."""
    from pipeline.plots import stamp

    (tmp_path / "deep" / "er").mkdir(parents=True)
    (tmp_path / "deep" / "er" / "zarr.json").write_text("{}")
    walked = []
    monkeypatch.setattr(stamp.os, "walk", lambda *a, **k: walked.append(a) or iter(()))
    assert stamp.store_state(tmp_path) is None and walked == []
    (tmp_path / "zarr.json").write_text("{}")
    assert stamp.store_state(tmp_path) is not None and walked == [(os.path.realpath(tmp_path),)]
