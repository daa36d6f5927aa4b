"""Sweep pipeline: cache, grid extension, crash safety, failures as data, runners, schema, figures.

Tests about the pipeline use ``fake_solve``, a fast stand-in with the solver's record format and a
known answer (it counts its calls); the real solver runs in the end-to-end tests on tiny grids.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pipeline import open_results
from pipeline.sweeps.analysis import critical_stokes
from pipeline.sweeps.config import ConfigError, cache_key, parse_sweep
from pipeline.sweeps.journal import pending_journal
from pipeline.sweeps.layout import FLOATS as FLOAT_FIELDS
from pipeline.sweeps.layout import MODEL_CODES, STATUS_CODES, STORE_SCHEMA, VARIABLES
from solver.physics import GROUPS, Physics

# the fixed physics of a sweep that sets only St and eps: every other group at its default
_DEFAULTS = {g.name: g.default for g in GROUPS if g.name not in ("St", "eps")}
from pipeline.sweeps.run import EXIT_FAILED, run_sweep
from pipeline.sweeps.store import StoreBusy, StoreMismatch, SweepStore

REPO = Path(__file__).resolve().parent.parent

# ---- the stand-in solver ------------------------------------------------------------------------
CALLS: list = []  # (St, eps) of every call in this process
FAILING = {2.0}  # scenes at these St fail with "max_steps"
RAISING = {4.0}  # scenes at these St raise inside the solver


def fake_st_c(eps):
    """The stand-in's critical Stokes number: 7 at eps = 1e-2, 13 at eps = 1e-8."""
    return 5.0 - math.log10(eps)


def fake_solve(physics, accuracy, overrides):
    """A record like ``pipeline.sweeps.tasks.solve_scene``'s, with a known answer; ``ln(x_e/x0)`` is
    linear in ln St and changes sign at ``fake_st_c(eps)``."""
    St, eps = physics["St"], physics["eps"]
    CALLS.append((St, eps))
    if any(math.isclose(St, s) for s in RAISING):
        raise RuntimeError(f"stand-in blew up at St={St}")
    if any(math.isclose(St, s) for s in FAILING):
        return {"status": "max_steps", "message": "step budget exhausted (stand-in)",
                "model": "ehd", "v_r": 0.0, "escaped": False, "dimple": False, "steps": 10,
                "rejected_steps": 1, "newton_iterations": 20, "lu_factorizations": 3,
                "wall_s": 0.001, **{k: math.nan for k in FLOAT_FIELDS if k not in ("v_r", "wall_s")}}
    ln_x_e_x0 = 3.0 * math.log(St / fake_st_c(eps))
    ln_x0_x1 = -0.4 * math.log(eps)
    rec = {k: St * 1e-3 + eps for k in FLOAT_FIELDS}
    rec.update(status="ok", message="", model="rigid" if St < 1.0 else "ehd",
               v_r=St / (St + 10.0), ln_x_e_x0=ln_x_e_x0, ln_x_e_x1=ln_x_e_x0 + ln_x0_x1,
               x_e_x0=math.exp(ln_x_e_x0), x_e_x1=math.exp(ln_x_e_x0 + ln_x0_x1),
               h_m_x1=1.0 / St, tau_v_zero=math.inf if St < 1.0 else St, escaped=ln_x_e_x0 > 0,
               dimple=St > 30.0, steps=int(St * 10), rejected_steps=1, newton_iterations=3,
               lu_factorizations=2, wall_s=0.001)
    return rec


def slow_fake_solve(physics, accuracy, overrides):
    """The stand-in, slowed down and logging each finished scene (for the kill test)."""
    time.sleep(0.03)
    rec = fake_solve(physics, accuracy, overrides)
    with open(os.environ["FAKE_SOLVE_LOG"], "a") as f:
        f.write(json.dumps([physics["St"], physics["eps"]]) + "\n")
    return rec


def sweep_text(St, eps, store="results/test.zarr", extra=""):
    return textwrap.dedent(f"""\
        name = "test"
        store = "{store}"
        [grid]
        St = {json.dumps(list(St)) if not isinstance(St, str) else St}
        eps = {json.dumps(list(eps))}
        [numerics]
        accuracy = "fast"
        {extra}
        """)


def make_sweep(tmp_path, St, eps, extra="", name="s.zarr"):
    return parse_sweep(sweep_text(St, eps, extra=extra)).with_store(tmp_path / name)


def run(sweep, **kw):
    kw.setdefault("runner", "serial")
    kw.setdefault("solve", fake_solve)
    kw.setdefault("progress", None)
    return run_sweep(sweep, **kw)


@pytest.fixture(autouse=True)
def _reset_stand_in():
    CALLS.clear()
    FAILING.clear()
    FAILING.add(2.0)
    yield


def data_vars(ds):
    """The scene data of a store: without the worker's wall time (differs run to run) and the
    store attrs (creation time, sweep file)."""
    out = ds.drop_vars(["wall_s"]).load()
    out.attrs = {}
    return out


# ---- sweep files ---------------------------------------------------------------------------------
def test_paper_sweep_file_meets_the_issue():
    from pipeline.sweeps.config import load_sweep

    s = load_sweep(REPO / "sweeps" / "paper.toml")
    St, eps = s.axes["St"], s.axes["eps"]
    assert len(St) >= 60 and St[0] <= 0.5 and St[-1] >= 100.0
    assert np.allclose(np.diff(np.log(St)), np.log(St[1] / St[0]))  # log-spaced
    assert {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8} <= set(eps)
    # the groups with defaults are fixed at them: the classic film (Pi = inf)
    assert s.axis_names == ("St", "eps") and s.fixed == _DEFAULTS
    assert s.accuracy == "standard" and str(s.store) == "results/paper.zarr"
    q = load_sweep(REPO / "sweeps" / "quick.toml")
    assert q.n_scenes <= 30


@pytest.mark.parametrize("St, eps, extra, words", [
    ("[0.0, 1.0]", [1e-2], "", ["grid.St", "0", "valid range"]),
    ("[1.0]", [0.5], "", ["grid.eps", "0.5", "valid range"]),
    ("{start = 1.0, stop = 2e4, num = 3}", [1e-2], "", ["grid.St.stop", "valid range"]),
    ("{start = 1.0, stop = 10.0, num = 0}", [1e-2], "", ["grid.St.num", ">= 1"]),
    ("[1.0, 1.0]", [1e-2], "", ["repeated"]),
    ("[1.0]", [1e-2], "rtol = -1", ["rtol", "valid range"]),
    ("[1.0]", [1e-2], "bogus = 3", ["bogus"]),
    ("[1.0]", [1e-2], "save_profiles = true", ["save_profiles"]),
])
def test_bad_sweep_file_names_the_parameter(St, eps, extra, words):
    with pytest.raises(ConfigError) as err:
        parse_sweep(sweep_text(St, eps, extra=extra))
    for w in words:
        assert w in str(err.value)


def test_cavitation_sweep_file_has_a_Pi_axis_with_the_classic_limit():
    from pipeline.sweeps.config import load_sweep

    # inf (TOML's inf) is a grid value like any other: the classic film on the same axes
    s = load_sweep(REPO / "sweeps" / "cavitation.toml")
    assert s.axis_names == ("St", "eps", "Pi") and s.axes["Pi"][-1] == math.inf
    assert s.axes["Pi"][0] == 1e-5 and s.fixed["cavitation"] == "jfo"
    with pytest.raises(ConfigError, match="repeated"):
        parse_sweep(sweep_text([1.0], [1e-2]).replace("[numerics]", "Pi = [inf, inf]\n[numerics]"))



def test_piezoviscous_sweep_file_has_a_beta_axis_from_the_classic_film():
    from pipeline.sweeps.config import load_sweep

    s = load_sweep(REPO / "sweeps" / "piezoviscous.toml")
    assert s.axis_names == ("St", "eps", "beta") and s.axes["beta"][0] == 0.0  # the classic film
    assert s.axes["beta"][-1] == 10.0 and s.fixed["viscosity_law"] == "barus"
    St = s.axes["St"]
    assert (St[0], St[-1]) == (1.0, 300.0) and np.allclose(np.diff(np.log(St)), np.log(St[1]))

def test_range_axis_is_log_spaced_and_sorted():
    s = parse_sweep(sweep_text("{start = 100.0, stop = 1.0, num = 3}", [1e-3, 1e-2]))
    assert s.axes["St"] == pytest.approx((1.0, 10.0, 100.0), rel=1e-12)
    assert s.axes["eps"] == (1e-3, 1e-2)


def test_cache_key_is_canonical_sha256():
    a = cache_key("1.0.0", {"rtol": 1e-3, "n_inner": 24})
    assert a == cache_key("1.0.0", {"n_inner": 24, "rtol": 1e-3})  # key order does not matter
    assert len(a) == 64 and int(a, 16) >= 0
    assert a != cache_key("1.0.1", {"rtol": 1e-3, "n_inner": 24})
    assert a != cache_key("1.0.0", {"rtol": 2e-3, "n_inner": 24})


# ---- cache, extension, failures --------------------------------------------------------------------
def test_cache_hit_does_not_call_the_solver(tmp_path):
    sweep = make_sweep(tmp_path, [0.5, 1.0, 3.0], [1e-3, 1e-2])
    first = run(sweep)
    assert len(CALLS) == 6 and first.computed == 6 and first.cached == 0
    before = data_vars(open_results(sweep.store))
    CALLS.clear()
    second = run(sweep)
    assert CALLS == [] and second.computed == 0 and second.cached == 6 and second.done == 6
    xr.testing.assert_identical(before, data_vars(open_results(sweep.store)))


def test_extending_the_grid_computes_only_new_scenes(tmp_path):
    small = make_sweep(tmp_path, [1.0, 3.0, 10.0], [1e-4, 1e-2])
    run(small)
    old = open_results(small.store).load()
    CALLS.clear()
    # new St points in between and beyond, one new eps row; St values reach the store via
    # geomspace round-off too (3.0000000000000004 must match 3.0)
    big = make_sweep(tmp_path, [1.0, 1.5, 3.0 * (1 + 2e-16), 5.0, 10.0, 30.0], [1e-6, 1e-4, 1e-2])
    summary = run(big)
    new_scenes = {(round(St, 9), e) for St in big.axes["St"] for e in big.axes["eps"]} - \
        {(St, e) for St in (1.0, 3.0, 10.0) for e in (1e-4, 1e-2)}
    assert {(round(s, 9), e) for s, e in CALLS} == new_scenes
    assert summary.cached == 6 and summary.computed == 12
    ds = open_results(big.store).load()
    assert ds.sizes == {"St": 6, "eps": 3}
    kept = ds.sel(St=old.St, eps=old.eps)
    xr.testing.assert_identical(data_vars(old), data_vars(kept))
    # a sweep that covers only part of the store leaves the rest alone (union layout)
    CALLS.clear()
    other = make_sweep(tmp_path, [10.0, 50.0], [1e-2])
    run(other)
    assert CALLS == [(50.0, 1e-2)]
    ds2 = open_results(other.store).load()
    assert ds2.sizes == {"St": 7, "eps": 3}
    xr.testing.assert_identical(data_vars(ds), data_vars(ds2.sel(St=ds.St, eps=ds.eps)))


def test_failed_scene_is_stored_and_the_sweep_goes_on(tmp_path):
    sweep = make_sweep(tmp_path, [1.0, 2.0, 3.0, 4.0], [1e-2])
    summary = run(sweep)
    assert summary.computed == 4 and summary.failed == 2 and summary.done == 2
    assert summary.exit_code == EXIT_FAILED
    ds = open_results(sweep.store).load().sel(eps=1e-2)
    assert list(ds.status.values) == [STATUS_CODES[s] for s in ("ok", "max_steps", "ok", "error")]
    assert "step budget" in str(ds.message.sel(St=2.0).values)
    assert "RuntimeError: stand-in blew up at St=4.0" in str(ds.message.sel(St=4.0).values)
    for St in (2.0, 4.0):
        cell = ds.sel(St=St)
        # the stand-in returned v_r = 0 and escaped = False for the failed scene: defaults,
        # not measurements; the store keeps them missing
        assert np.isnan(cell.v_r) and np.isnan(cell.escaped) and np.isnan(cell.ln_x_e_x1)
    assert int(ds.steps.sel(St=2.0)) == 10  # diagnostics of a failure are kept
    assert int(ds.model.sel(St=2.0)) == MODEL_CODES["ehd"]
    assert int(ds.model.sel(St=4.0)) == MODEL_CODES["unknown"]

    CALLS.clear()
    assert run(sweep).computed == 0 and CALLS == []  # failures are cached like successes
    FAILING.clear()
    retried = run(sweep, retry_failed=True)
    assert sorted(CALLS) == [(2.0, 1e-2), (4.0, 1e-2)]  # only the failed ones
    assert retried.done == 3 and retried.failed == 1  # St = 4 still raises


def test_a_result_from_a_worker_with_another_installation_is_not_stored_as_ok(tmp_path):
    sweep = make_sweep(tmp_path, [1.0, 3.0], [1e-2])
    with SweepStore.open(sweep) as st:
        good, bad = st.cells(sweep)
        st.record(good, {**fake_solve(st.scene(good), "fast", {}),
                         "cache_key": sweep.worker_key()})
        st.record(bad, {**fake_solve(st.scene(bad), "fast", {}), "cache_key": "0" * 64})
    ds = open_results(sweep.store).load().sel(eps=1e-2)
    assert int(ds.status.sel(St=1.0)) == STATUS_CODES["ok"]
    assert int(ds.status.sel(St=3.0)) == STATUS_CODES["error"]
    assert "another solver version" in str(ds.message.sel(St=3.0).values)
    assert np.isnan(ds.v_r.sel(St=3.0))


def test_changed_numerics_or_version_never_mix(tmp_path, monkeypatch):
    sweep = make_sweep(tmp_path, [1.0, 3.0], [1e-2])
    run(sweep)
    before = data_vars(open_results(sweep.store))
    changed = make_sweep(tmp_path, [1.0, 3.0, 5.0], [1e-2], extra="rtol = 1e-4")
    with pytest.raises(StoreMismatch) as err:
        run(changed)
    assert "rtol" in str(err.value) and "--store" in str(err.value)
    import pipeline.sweeps.config

    monkeypatch.setattr(pipeline.sweeps.config.Sweep, "solver_version", lambda self: "99.0")
    with pytest.raises(StoreMismatch) as err:
        run(sweep)
    assert "solver_version" in str(err.value) and "99.0" in str(err.value)
    assert len(CALLS) == 2  # nothing computed after the refusals
    xr.testing.assert_identical(before, data_vars(open_results(sweep.store)))


def test_a_store_that_is_not_a_sweep_store_is_refused(tmp_path):
    xr.Dataset({"a": ("x", np.arange(3))}).to_zarr(tmp_path / "plain.zarr", consolidated=False)
    with pytest.raises(StoreMismatch, match="sweep store"):
        run(make_sweep(tmp_path, [1.0], [1e-2], name="plain.zarr"))
    assert CALLS == []


def test_store_schema_and_attrs(tmp_path):
    text = sweep_text([0.5, 1.0, 3.0], [1e-8, 1e-2])
    sweep = parse_sweep(text).with_store(tmp_path / "s.zarr")
    run(sweep)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # plain xarray opens it without any warning
        ds = xr.open_zarr(sweep.store)
    assert ds.status.dims == ("St", "eps")  # the sweep's axes in Physics order
    assert list(ds.eps.values) == [1e-8, 1e-2] and list(ds.St.values) == [0.5, 1.0, 3.0]
    issue_vars = {"v_r", "h_m_x1", "h_m_x0", "h_m_approach_x1", "x_e_x1", "x_e_x0", "escaped",
                  "tau_v_zero", "peak_force", "dimple", "energy_error", "model", "status",
                  "message", "wall_s", "steps"}
    assert issue_vars <= set(ds.data_vars) and set(VARIABLES) == set(ds.data_vars)
    for name in ds.data_vars:
        assert ds[name].attrs["long_name"] and "units" in ds[name].attrs, name
        assert ds[name].encoding["chunks"] == (1, 2), name  # whole along the last axis
    assert {"p_max", "p_min", "start_strain_energy"} <= set(ds.data_vars)
    assert ds.p_max.attrs["units"] == "mu a v0 / x1^2"
    assert ds.status.attrs["flag_meanings"].split() == list(STATUS_CODES)
    assert ds.status.attrs["flag_values"] == list(STATUS_CODES.values())
    a = ds.attrs
    from solver import SOLVER_VERSION

    assert a["solver_version"] == SOLVER_VERSION and a["accuracy"] == "fast"
    assert a["cache_key"] == sweep.cache_key() and a["numerics"] == sweep.numerics()
    assert a["axes"] == ["St", "eps"] and a["store_schema"] == STORE_SCHEMA
    assert a["fixed_physics"] == {**_DEFAULTS, "Pi": "inf"}  # JSON holds inf as "inf"
    assert a["sweep_file"] == text
    assert {"python", "numpy", "numba", "dask", "xarray", "zarr"} <= set(a["package_versions"])
    assert a["created"].startswith("20")
    # values survive the round trip, infinity included (tau_v_zero: never stops)
    cell = ds.sel(St=0.5, eps=1e-2)
    assert int(cell.status) == 1 and float(cell.tau_v_zero) == math.inf
    assert int(cell.model) == MODEL_CODES["rigid"] and float(cell.escaped) == 0.0


def test_store_is_locked_against_a_second_writer(tmp_path):
    sweep = make_sweep(tmp_path, [1.0], [1e-2])
    with SweepStore.open(sweep):
        with pytest.raises(StoreBusy, match="being written"):
            with SweepStore.open(sweep):
                pass
    run(sweep)  # released afterwards


def test_figures_of_a_store_whose_every_scene_failed_say_so_and_open_results_takes_kwargs(
        tmp_path, capsys):
    """A store whose scenes all ran and failed: ``ehd figures`` says so and where to read why
    (it said "no finished scene yet ... run its sweep first" of a sweep that had run). And
    ``open_results(path, consolidated=False)`` passes the keyword on to ``open_zarr`` as its
    docstring says (it raised "got multiple values for keyword argument")."""
    from pipeline.cli import main

    FAILING.update({3.0, 5.0})
    sweep = make_sweep(tmp_path, [2.0, 3.0, 5.0], [1e-2])
    run(sweep)
    capsys.readouterr()
    assert main(["figures", str(sweep.store), "--out", str(tmp_path / "figs")]) == 2
    err = capsys.readouterr().err
    assert "no scene that finished ok (all 3 that ran failed)" in err and "ehd status" in err
    ds = open_results(sweep.store, consolidated=False, chunks=None)
    assert set(ds["status"].values.ravel().tolist()) == {STATUS_CODES["max_steps"]}


def test_open_results_on_a_missing_store(tmp_path):
    with pytest.raises(FileNotFoundError, match="no sweep store"):
        open_results(tmp_path / "nothing.zarr")
    # '/' raised "PosixPath('/') has an empty name" (a hostile review)
    with pytest.raises(FileNotFoundError, match="root folder: no sweep store"):
        open_results("/")


# ---- crash safety -------------------------------------------------------------------------------
def test_journal_of_an_interrupted_run_is_merged_not_recomputed(tmp_path):
    """Scenes that reached the journal but not the store (a kill between merges) are kept."""
    sweep = make_sweep(tmp_path, [1.0, 3.0, 5.0], [1e-2])
    with SweepStore.open(sweep, flush_seconds=1e9) as st:
        cells = st.cells(sweep)
        for cell in cells[:2]:
            st.record(cell, fake_solve(st.scene(cell), "fast", {}), now=0.0)
        st._dirty.clear()  # simulate the kill: nothing merged into the store
        st._close_journal()
    assert pending_journal(sweep.store) == 2
    with pytest.warns(UserWarning, match="journal"):
        ds = open_results(sweep.store)
    assert int((ds.status.values != 0).sum()) == 0  # the store is readable, nothing merged yet
    CALLS.clear()
    summary = run(sweep)
    assert CALLS == [(5.0, 1e-2)] and summary.done == 3
    assert pending_journal(sweep.store) == 0


def test_interrupted_relayout_is_recovered(tmp_path):
    sweep = make_sweep(tmp_path, [1.0, 3.0], [1e-2])
    run(sweep)
    path = Path(sweep.store)
    path.rename(path.with_name(path.name + ".old"))  # killed between the two renames
    (path.with_name(path.name + ".tmp-12345")).mkdir()  # and a half-written new layout
    CALLS.clear()
    assert run(sweep).cached == 2 and CALLS == []
    assert not list(tmp_path.glob("*.old")) and not list(tmp_path.glob("*.tmp-*"))


def test_kill_9_loses_nothing_and_recomputes_nothing(tmp_path):
    St = [round(float(v), 6) for v in np.geomspace(1.0, 50.0, 12)]
    eps = [1e-6, 1e-4, 1e-2]
    store = tmp_path / "k.zarr"
    log = tmp_path / "calls.log"
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(REPO)!r})
        from tests.test_pipeline import slow_fake_solve, sweep_text
        from pipeline.sweeps.config import parse_sweep
        from pipeline.sweeps.run import run_sweep
        sweep = parse_sweep(sweep_text({St!r}, {eps!r})).with_store({str(store)!r})
        run_sweep(sweep, runner="serial", solve=slow_fake_solve, progress=None, flush_seconds=0.2)
        """)
    env = {**os.environ, "FAKE_SOLVE_LOG": str(log)}
    proc = subprocess.Popen([sys.executable, "-c", script], env=env, cwd=tmp_path)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # kill once about half the scenes are done
        if log.exists() and len(log.read_text().splitlines()) >= 17:
            break
        if proc.poll() is not None:
            pytest.fail(f"sweep subprocess ended early with code {proc.returncode}")
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    finished = {tuple(x) for x in map(json.loads, log.read_text().splitlines())}
    assert 17 <= len(finished) < 36

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a pending journal is announced with a warning
        ds = open_results(store).load()  # readable right after the kill
    stored = {(float(ds.St[j]), float(ds.eps[i])) for j, i in zip(*np.nonzero(ds.status.values))}
    journal = {(r["physics"]["St"], r["physics"]["eps"])
               for r in map(json.loads, _lines(Path(str(store) + ".journal")))}
    committed = stored | journal
    assert committed <= finished
    assert len(finished - committed) <= 1  # at most the scene being handed over at the kill

    CALLS.clear()
    summary = run(parse_sweep(sweep_text(St, eps)).with_store(store))
    everything = {(s, e) for s in St for e in eps}
    assert set(CALLS) == everything - committed  # nothing committed is computed again
    assert summary.done == 36 and summary.not_run == 0
    after = open_results(store).load()
    for s, e in stored:  # and nothing stored before the kill changed
        xr.testing.assert_identical(data_vars(ds.sel(St=s, eps=e)),
                                    data_vars(after.sel(St=s, eps=e)))


def _lines(path: Path):
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            json.loads(line)
            out.append(line)
        except json.JSONDecodeError:  # cut short by the kill
            pass
    return out


# ---- runners and the real solver -----------------------------------------------------------------
REAL_ST, REAL_EPS = [0.5, 5.0, 20.0], [1e-8, 1e-2]  # rigid-only and coupled scenes, rebound


def test_real_solver_end_to_end_and_identical_across_runners(tmp_path):
    """The real solver through serial, threaded and process runners: identical stores, equal to
    calling ``solver.collide`` directly."""
    from solver import collide

    base = parse_sweep(sweep_text(REAL_ST, REAL_EPS))
    stores = {}
    for runner in ("serial", "threads", "processes"):
        sweep = base.with_store(tmp_path / f"{runner}.zarr")
        summary = run_sweep(sweep, runner=runner, workers=2, progress=None)
        assert summary.done == 6 and summary.failed == 0
        stores[runner] = data_vars(open_results(sweep.store))
    xr.testing.assert_identical(stores["serial"], stores["threads"])
    xr.testing.assert_identical(stores["serial"], stores["processes"])

    ds = stores["serial"]
    assert summary.rigid == int((ds.model == MODEL_CODES["rigid"]).sum()) >= 1
    assert int((ds.model == MODEL_CODES["ehd"]).sum()) >= 1
    for St in REAL_ST:
        for eps in REAL_EPS:
            c = collide(St, eps, accuracy="fast", save_profiles=False)
            cell = ds.sel(St=St, eps=eps)
            assert int(cell.model) == MODEL_CODES[c.model]
            for name in ("v_r", "h_m_x1", "ln_x_e_x1", "peak_force", "tau_v_zero"):
                # same code, same inputs: bit-identical (NaN where not defined)
                assert float(cell[name]) == pytest.approx(getattr(c, name), rel=0, abs=0,
                                                          nan_ok=True), name
            assert float(cell.escaped) == float(c.escaped)
    assert float(ds.v_r.sel(St=20.0, eps=1e-2)) > 0.3  # it does rebound


def test_existing_scheduler_runner_matches_serial(tmp_path):
    from dask.distributed import LocalCluster

    sweep = make_sweep(tmp_path, [0.5, 1.0, 3.0, 5.0], [1e-3, 1e-2], name="serial.zarr")
    run(sweep)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}) as cluster:
        other = sweep.with_store(tmp_path / "dist.zarr")
        summary = run(other, runner=None, address=cluster.scheduler_address, workers=1)
    assert summary.runner.startswith("dask scheduler") and summary.done == 8
    xr.testing.assert_identical(data_vars(open_results(sweep.store)),
                                data_vars(open_results(other.store)))


def crashing_solve(physics, accuracy, overrides):
    """The stand-in, except that the worker process dies at once at St = 3 (as on a segfault;
    os._exit rather than os.abort, which could leave a core file)."""
    if math.isclose(physics["St"], 3.0):
        os._exit(70)
    return fake_solve(physics, accuracy, overrides)


def test_a_crashing_worker_is_stored_as_an_error_and_the_sweep_goes_on(tmp_path, monkeypatch):
    import dask
    import distributed  # noqa: F401 - its config first: leaving the set below drops what it adds

    monkeypatch.setenv("PYTHONPATH", str(REPO))  # spawned workers import this test module
    sweep = make_sweep(tmp_path, [1.0, 3.0, 5.0], [1e-2])
    # dask gives up on a scene after its workers died allowed-failures + 1 times (3 by default,
    # each a new worker process: 34 s for this test); one is enough to show the sweep goes on
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        summary = run(sweep, runner="processes", workers=2, solve=crashing_solve)
    assert summary.done == 2 and summary.failed == 1 and summary.exit_code == EXIT_FAILED
    ds = open_results(sweep.store).load().sel(eps=1e-2, St=3.0)
    assert int(ds.status) == STATUS_CODES["error"] and "KilledWorker" in str(ds.message.values)


class KilledWorker(Exception):
    """Named as dask's: a scene whose worker processes died while it was assigned to them."""


def test_a_scene_failed_only_by_its_neighbours_crash_is_run_again_alone():
    """dask fails every scene assigned to a worker that died three times, a queued one too
    (KilledWorker); the runner runs each such scene again, one at a time, after the others.
    Here the first pass fails "b" (it waited behind the crash) and "c" (the crash itself)."""
    from concurrent.futures import Future

    from pipeline.sweeps.runners import Runner

    runs = []

    class Executor:
        def submit(self, fn, *args):
            tag = args[0]
            first = tag not in runs
            runs.append(tag)
            fut = Future()
            if tag == "c" or (tag == "b" and first):
                fut.set_exception(KilledWorker(tag))
            else:
                fut.set_result(fn(*args))
            return fut

    got = list(Runner("fake", executor=Executor()).unordered(str.upper, [(t, (t,)) for t in "abc"]))
    results = {tag: r for tag, r in got}
    assert results["a"] == "A" and results["b"] == "B"  # b ran again and is kept
    assert isinstance(results["c"], KilledWorker) and len(got) == 3
    # the second pass after the first (in the order their failures came, which is any)
    assert runs[:3] == ["a", "b", "c"] and sorted(runs[3:]) == ["b", "c"]


# ---- command line -------------------------------------------------------------------------------
def test_a_sweep_of_start_deformed_scenes_does_not_advise_a_retry(tmp_path, capsys):
    """start_deformed is the model's premise (eps not small for St), the same on every retry:
    the summary says so instead of advising --retry-failed (it advised it for every failure).
    St 0.01 and 0.02 at eps 1e-2 start with 3.08 eps/St = 3.1 and 1.5 of their kinetic energy as
    strain, above the 0.1 limit."""
    from pipeline.cli import main

    path = tmp_path / "deformed.toml"
    path.write_text(sweep_text([0.01, 0.02], [1e-2], store=str(tmp_path / "d.zarr")))
    assert main(["sweep", str(path), "--executor", "serial"]) == 3
    out = capsys.readouterr().out
    assert "2 of the failed are start_deformed" in out and "--retry-failed" not in out


def test_cli_sweep_status_and_exit_codes(tmp_path, capsys):
    from pipeline.cli import main

    # max_steps = 20 makes the coupled scenes fail for real; the rigid-only one succeeds
    path = tmp_path / "fail.toml"
    path.write_text(sweep_text([0.5, 20.0], [1e-8], store=str(tmp_path / "f.zarr"),
                               extra="max_steps = 20"))
    assert main(["sweep", str(path), "--executor", "serial"]) == 3
    out = capsys.readouterr().out
    assert "failed           1" in out and "rigid-only       1" in out and "--retry-failed" in out
    # retried, it fails again (the same numerics): the summary no longer advises a retry
    assert main(["sweep", str(path), "--executor", "serial", "--retry-failed"]) == 3
    out = capsys.readouterr().out
    assert "--retry-failed" not in out and "failed again on this retry" in out
    assert main(["status", str(tmp_path / "f.zarr")]) == 0
    out = capsys.readouterr().out
    assert "max_steps 1" in out and "St=20" in out and "done           1" in out

    bad = tmp_path / "bad.toml"
    bad.write_text(sweep_text([1.0], [0.5]))
    assert main(["sweep", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "grid.eps" in err and "valid range" in err and len(err.strip().splitlines()) == 1
    assert main(["status", str(tmp_path / "none.zarr")]) == 2
    with pytest.raises(SystemExit):
        main(["sweep", str(path), "--workers", "0"])
    assert "--workers" in capsys.readouterr().err


# ---- analysis and figures -----------------------------------------------------------------------
def stand_in_render(ds, out):
    """For ``sweep_maps.render_all`` where the stamp's logic is under test, not the drawing
    (which takes ~15 s): writes a stand-in of every file the real one names."""
    from pipeline.plots import sweep_maps

    paths = [out / f"{n}.{f}" for n in sweep_maps.FIGURES for f in sweep_maps.FORMATS]
    paths.append(out / sweep_maps.CSV_NAME)
    out.mkdir(parents=True, exist_ok=True)
    for p in paths:
        p.write_text("x")
    return paths


def synthetic_store(tmp_path):
    """Stand-in results with a failed column (St = 2), a raised scene and a not-run corner."""
    St = [round(float(v), 6) for v in np.geomspace(0.5, 60.0, 14)] + [2.0, 4.0]
    eps = [1e-8, 1e-6, 1e-4, 1e-2]
    sweep = make_sweep(tmp_path, sorted(St), eps)
    run(sweep)
    run(make_sweep(tmp_path, [100.0], [1e-3]))  # adds a row and a column, mostly not run
    return open_results(sweep.store)


def test_critical_stokes_is_interpolated_between_grid_points(tmp_path):
    ds = synthetic_store(tmp_path)
    rows = {r["eps"]: r for r in critical_stokes(ds)}
    for eps in (1e-8, 1e-6, 1e-4, 1e-2):
        r = rows[eps]
        # ln(x_e/x0) of the stand-in is linear in ln St: interpolation in ln St is exact
        assert r["St_c"] == pytest.approx(fake_st_c(eps), rel=1e-12)
        assert r["St_stuck"] < r["St_c"] < r["St_escaped"] and r["transitions"] == 1
    assert rows[1e-3]["note"] == "all escaped" and math.isnan(rows[1e-3]["St_c"])


def test_figures_render_from_a_synthetic_store_with_reproducible_bytes(tmp_path):
    from pipeline.plots.sweep_maps import FIGURES, render_all, update_figures

    ds = synthetic_store(tmp_path)
    first, rendered = update_figures(ds, tmp_path / "a")
    assert rendered
    render_all(open_results(tmp_path / "s.zarr"), tmp_path / "b")
    names = {p.name for p in first}
    assert names == {f"{n}.{f}" for n in FIGURES for f in ("png", "pdf")} | {"critical_stokes.csv"}
    for p in first:
        assert p.stat().st_size > 1000 or p.suffix == ".csv"
        assert p.read_bytes() == (tmp_path / "b" / p.name).read_bytes(), p.name
    table = (tmp_path / "a" / "critical_stokes.csv").read_text().splitlines()
    assert table[0] == "eps,St_c,St_stuck,St_escaped,transitions,note"
    assert table[1].startswith("1e-08,13,") and "all escaped" in table[4]


def test_progress_line_has_counts_rate_and_eta():
    import io

    from pipeline.sweeps.progress import Progress

    p = Progress(4, stream=io.StringIO())
    p.start -= 2.0  # two seconds ago
    p.update("ok", "rigid")
    p.update("max_steps", "ehd")
    line = p.line()
    assert "2/4" in line and "ok 1" in line and "failed 1" in line and "rigid 1" in line
    assert "ETA 00:02" in line and "scenes/s" in line


def test_figures_are_redrawn_only_when_the_store_changes(tmp_path, monkeypatch):
    import pipeline.plots.sweep_maps as figures

    sweep = make_sweep(tmp_path, [1.0, 10.0], [1e-4, 1e-2])
    run(sweep)
    drawn = []
    monkeypatch.setattr(figures, "render_all", lambda ds, out: drawn.append(out) or [])
    for _ in range(2):
        figures.update_figures(open_results(sweep.store), tmp_path / "f")
    assert len(drawn) == 2  # the stub writes no files: "missing files" forces a redraw
    # with the files present, an unchanged store is not drawn again, a changed one is
    for name in figures.FIGURES:
        for fmt in figures.FORMATS:
            (tmp_path / "f" / f"{name}.{fmt}").write_text("x")
    (tmp_path / "f" / figures.CSV_NAME).write_text("x")
    drawn.clear()
    figures.update_figures(open_results(sweep.store), tmp_path / "f")
    assert drawn == []
    run(make_sweep(tmp_path, [3.0], [1e-2]))
    figures.update_figures(open_results(sweep.store), tmp_path / "f")
    assert len(drawn) == 1


# ---- axes and fixed physics (the sweep's axes come from solver.Physics) ---------------------------
def physics_sweep_text(grid: str, physics: str = "", store="results/test.zarr"):
    return textwrap.dedent(f"""\
        name = "physics"
        store = "{store}"
        [grid]
        {grid}
        [physics]
        {physics}
        [numerics]
        accuracy = "fast"
        """)


def test_a_fixed_eps_and_an_St_axis_run_end_to_end(tmp_path, capsys):
    from pipeline.cli import main
    from pipeline.sweeps.analysis import critical_stokes_csv

    text = physics_sweep_text("St = [1.0, 3.0, 10.0, 30.0]", "eps = 1e-2",
                              store=str(tmp_path / "one.zarr"))
    sweep = parse_sweep(text)
    assert sweep.axis_names == ("St",)
    assert sweep.fixed == {"eps": 1e-2, **_DEFAULTS}
    assert sweep.n_scenes == 4
    summary = run(sweep)
    assert summary.done == 4 and sorted(CALLS) == [(s, 1e-2) for s in (1.0, 3.0, 10.0, 30.0)]
    ds = open_results(sweep.store).load()
    assert ds.status.dims == ("St",) and ds.attrs["fixed_physics"] == {"eps": 1e-2, **_DEFAULTS,
                                                                     "Pi": "inf"}
    assert ds.attrs["axes"] == ["St"]
    assert ds.status.encoding["chunks"] == (4,)  # one axis: one chunk
    (row,) = critical_stokes(ds)  # the fixed eps is a plane one row high
    assert row["eps"] == 1e-2 and row["St_c"] == pytest.approx(fake_st_c(1e-2), rel=1e-12)
    assert critical_stokes_csv([row]).splitlines()[0].startswith("eps,St_c")
    assert main(["status", str(sweep.store)]) == 0
    out = capsys.readouterr().out
    assert "4 St in [1, 30]" in out and "fixed eps=0.01" in out and "done           4" in out
    CALLS.clear()
    assert run(sweep).cached == 4 and CALLS == []


def test_axes_in_either_order_give_the_same_sweep():
    a = parse_sweep(physics_sweep_text("St = [1.0, 2.0]\neps = [1e-3, 1e-2]"))
    b = parse_sweep(physics_sweep_text("eps = [1e-2, 1e-3]\nSt = [2.0, 1.0]"))
    assert a.axis_names == b.axis_names == ("St", "eps")
    assert a.axes == b.axes and a.cache_key() == b.cache_key()
    fixed = parse_sweep(physics_sweep_text("St = [1.0, 2.0]", "eps = 1e-3"))
    other = parse_sweep(physics_sweep_text("St = [1.0, 2.0]", "eps = 1e-2"))
    assert len({a.cache_key(), fixed.cache_key(), other.cache_key()}) == 3


@pytest.mark.parametrize("grid, physics, words", [
    ("St = [1.0]\ngamma = [0.1]", "eps = 1e-2", ["unknown physics field", "gamma", "valid", "'St'"]),
    ("St = [1.0]\ncavitation = ['off']", "eps = 1e-2", ["cavitation", "model", "[physics]"]),
    ("St = [1.0]", "eps = 1e-2\ncavitation = 'bubbly'", ["cavitation", "one of"]),
    ("St = [1.0]\nPi = [-1.0]", "eps = 1e-2", ["Pi", "valid range"]),
    ("St = [1.0]", "eps = 1e-2\nbogus = 1", ["[physics]", "bogus", "valid"]),
    ("St = [1.0]\neps = [1e-2]", "eps = 1e-2", ["eps", "both"]),
    ("St = [1.0]", "", ["eps", "neither"]),
    ("St = [1.0]", "eps = 0.5", ["physics.eps", "valid range"]),
    ("St = [1.0]", "eps = true", ["physics.eps", "number"]),
    ("St = [1.0]\nviscosity_table = ['0:1, 1:2']", "eps = 1e-2", ["viscosity_table", "a table"]),
    ("St = [1.0]", "eps = 1e-2\nviscosity_table = '1:2'", ["physics.viscosity_table", "0:1"]),
])
def test_bad_axes_or_fixed_physics_are_named(grid, physics, words):
    with pytest.raises(ConfigError) as err:
        parse_sweep(physics_sweep_text(grid, physics))
    for w in words:
        assert w in str(err.value)


def test_a_huge_grid_is_refused_before_any_array_is_built(monkeypatch):
    import pipeline.sweeps.config as config

    def no_arrays(*a, **k):
        raise AssertionError("grid values built before the size check")

    monkeypatch.setattr(config.np, "geomspace", no_arrays)
    monkeypatch.setattr(config.np, "array", no_arrays)
    with pytest.raises(ConfigError, match="100000000 scenes"):
        parse_sweep(physics_sweep_text("St = {start = 1.0, stop = 10.0, num = 100000000}",
                                       "eps = 1e-2"))
    with pytest.raises(ConfigError, match="scenes; at most"):
        parse_sweep(physics_sweep_text("St = {start = 1.0, stop = 10.0, num = 10000}\n"
                                       "eps = {start = 1e-8, stop = 1e-2, num = 10000}"))


def test_a_store_made_before_a_new_piece_of_physics_is_the_same_physics(tmp_path):
    """A group added to solver.Physics after a store was made (here ``slip_length``, as the
    store of solver 1.8.0 before it) is at its off value in the sweep: the store's fixed
    physics, which lacks it, is the same physics; nothing is refused or recomputed. At another
    value it is other physics, refused as before."""
    store = tmp_path / "older.zarr"
    sweep = parse_sweep(physics_sweep_text("St = [1.0, 3.0]", "eps = 1e-2")).with_store(store)
    run(sweep)
    before = data_vars(open_results(store))
    older = {k: v for k, v in sweep.fixed.items() if k != "slip_length"}
    with SweepStore.open(sweep) as opened:
        fixed = {k: v for k, v in opened.ds.attrs["fixed_physics"].items() if k != "slip_length"}
        opened._set_attrs(fixed_physics=fixed, cache_key=cache_key(
            sweep.solver_version(), sweep.numerics(), older, sweep.axis_names))
    CALLS.clear()
    run(sweep)
    assert CALLS == []
    xr.testing.assert_identical(before, data_vars(open_results(store)))
    slipping = parse_sweep(physics_sweep_text("St = [1.0, 3.0]", "eps = 1e-2\nslip_length = 1.0"))
    with pytest.raises(StoreMismatch, match="slip_length = 0.0 in the store, 1.0 in this sweep"):
        run(slipping.with_store(store))


def test_a_store_refuses_a_sweep_with_other_fixed_physics_or_axes(tmp_path):
    store = tmp_path / "fixed.zarr"
    first = parse_sweep(physics_sweep_text("St = [1.0, 3.0]", "eps = 1e-2")).with_store(store)
    run(first)
    before = data_vars(open_results(store))
    CALLS.clear()
    other = parse_sweep(physics_sweep_text("St = [1.0, 3.0, 5.0]", "eps = 1e-3")).with_store(store)
    with pytest.raises(StoreMismatch) as err:
        run(other)
    msg = str(err.value)
    assert "fixed physics" in msg and "eps = 0.01 in the store, 0.001 in this sweep" in msg
    assert "--store" in msg and len(msg.splitlines()) == 1
    grid = parse_sweep(physics_sweep_text("St = [1.0, 3.0]\neps = [1e-2]")).with_store(store)
    with pytest.raises(StoreMismatch, match=r"axes are \['St'\], this sweep's are \['St', 'eps'\]"):
        run(grid)
    assert CALLS == []
    xr.testing.assert_identical(before, data_vars(open_results(store)))


def test_journal_lines_hold_the_physics_and_replay_matches_every_axis(tmp_path):
    sweep = make_sweep(tmp_path, [1.0, 3.0], [1e-3, 1e-2])
    with SweepStore.open(sweep, flush_seconds=1e9) as st:
        cells = st.cells(sweep)
        for cell in cells[:3]:
            st.record(cell, fake_solve(st.scene(cell), "fast", {}), now=0.0)
        st._dirty.clear()  # killed before the merge
        st._close_journal()
    lines = [json.loads(line) for line in Path(str(sweep.store) + ".journal").read_text().splitlines()]
    assert [list(r["physics"]) for r in lines] == [list(Physics.names())] * 3
    assert {(r["physics"]["St"], r["physics"]["eps"]) for r in lines} == \
        {(1.0, 1e-3), (1.0, 1e-2), (3.0, 1e-3)}
    CALLS.clear()
    assert run(sweep).done == 4 and CALLS == [(3.0, 1e-2)]
    ds = open_results(sweep.store).load()
    for St, eps in ((1.0, 1e-3), (1.0, 1e-2), (3.0, 1e-3)):  # each record on its own cell
        assert float(ds.v_r.sel(St=St, eps=eps)) == pytest.approx(St / (St + 10.0))


def test_a_three_axis_store_end_to_end(tmp_path, capsys, monkeypatch):
    """The real third axis: the cavitation number Pi (fake solves only)."""
    from pipeline.cli import main
    from pipeline.plots.sweep_maps import _suffix
    from pipeline.sweeps.analysis import critical_stokes_csv, planes

    text = physics_sweep_text("Pi = [0.001, 0.01]\nSt = [1.0, 3.0, 10.0, 30.0]\neps = [1e-3, 1e-2]",
                              store=str(tmp_path / "three.zarr"))
    sweep = parse_sweep(text)
    assert sweep.axis_names == ("St", "eps", "Pi") and sweep.n_scenes == 16
    assert run(sweep).done == 16 and len(CALLS) == 16
    ds = open_results(sweep.store).load()
    assert ds.status.dims == ("St", "eps", "Pi") and ds.status.encoding["chunks"] == (1, 1, 2)
    # extend along the third axis only: just the new plane is computed, old cells kept
    CALLS.clear()
    bigger = parse_sweep(text.replace("Pi = [0.001, 0.01]", "Pi = [0.001, 0.01, 0.1]"))
    assert bigger.cache_key() == sweep.cache_key()
    assert run(bigger).computed == 8 and len(CALLS) == 8
    ds3 = open_results(sweep.store).load()
    xr.testing.assert_identical(data_vars(ds), data_vars(ds3.sel(Pi=ds.Pi)))
    # one (eps, St) plane per Pi value; St_c per eps row per plane
    assert [extra for extra, _ in planes(ds3)] == [{"Pi": 0.001}, {"Pi": 0.01}, {"Pi": 0.1}]
    assert all(p.status.dims == ("eps", "St") for _, p in planes(ds3))
    rows = critical_stokes(ds3)
    assert len(rows) == 6 and rows[0]["Pi"] == 0.001
    assert rows[0]["St_c"] == pytest.approx(fake_st_c(1e-3), rel=1e-12)
    assert critical_stokes_csv(rows).splitlines()[0] == \
        "Pi,eps,St_c,St_stuck,St_escaped,transitions,note"
    assert _suffix({"Pi": 0.001}) == "_Pi=0.001"
    assert main(["status", str(sweep.store)]) == 0
    out = capsys.readouterr().out
    assert "Pi=0.001:" in out and "Pi=0.1:" in out and "done          24" in out
    # one set of figures per Pi value, file names suffixed with it (png only: quicker)
    import pipeline.plots.sweep_maps as figures

    monkeypatch.setattr(figures, "FORMATS", ("png",))
    paths, rendered = figures.update_figures(ds3, tmp_path / "figs")
    # ... and, with Pi an axis, the cavitation figures: per eps the curves against St, one per
    # Pi, and St_c against Pi
    assert rendered and {p.name for p in paths} == {
        f"{n}_Pi={v}.png" for n in figures.FIGURES for v in ("0.001", "0.01", "0.1")} | \
        {"critical_stokes.csv", "cavitation_eps=0.001.png", "cavitation_eps=0.01.png",
         "critical_stokes_vs_Pi.png"}
    drawn = dict(figures.axis_figures(ds3))
    fig = drawn["cavitation_eps=0.01"]()
    assert [len(ax.get_lines()) for ax in fig.axes] == [3, 4, 3]  # + the ln(x_e/x0) = 0 line
    (ax,) = drawn["critical_stokes_vs_Pi"]().axes
    x, y = ax.get_lines()[0].get_data()  # the first curve: the largest eps, St_c at each Pi
    assert list(x) == [0.001, 0.01, 0.1]
    assert list(y) == [r["St_c"] for r in rows if r["eps"] == 1e-2]
    # no St_c at any Pi (one St: nothing brackets it): the St_c figure says so (it raised
    # matplotlib's "cannot be log-scaled" on saving, a hostile scan)
    paths, rendered = figures.update_figures(ds3.isel(St=[0]), tmp_path / "figs_one")
    assert rendered and "critical_stokes_vs_Pi.png" in {p.name for p in paths}
    # a store without St or eps has no plane: figures refused with one line
    ds_flat = ds3.isel(eps=0).drop_vars("eps")
    ds_flat.attrs = {**ds3.attrs, "fixed_physics": {}}
    from pipeline.sweeps.analysis import PlaneError

    with pytest.raises(PlaneError, match="no eps axis"):
        list(planes(ds_flat))


def test_a_beta_axis_sweep_end_to_end_draws_the_piezoviscous_figures(tmp_path, capsys,
                                                                    monkeypatch):
    """The real solver on a tiny St x beta grid (beta = 0: the classic film on the same axes),
    through the command line: the (eps, St) figures per beta and the piezoviscous ones."""
    import pipeline.plots.sweep_maps as figures
    from pipeline.cli import main

    path = tmp_path / "piezo.toml"  # viscosity_law left at "auto": Barus where beta > 0
    path.write_text(physics_sweep_text("St = [3.0, 30.0]\nbeta = [0.0, 2.0]", "eps = 1e-2",
                                       store=str(tmp_path / "piezo.zarr")))
    assert main(["sweep", str(path), "--executor", "serial"]) == 0
    assert "done             4" in capsys.readouterr().out
    monkeypatch.setattr(figures, "FORMATS", ("png",))  # quicker
    out = tmp_path / "figs"
    assert main(["figures", str(tmp_path / "piezo.zarr"), "--out", str(out)]) == 0
    assert {p.name for p in out.iterdir() if not p.name.startswith(".")} == {
        f"{n}_beta={v}.png" for n in figures.FIGURES for v in ("0", "2")} | {
        "critical_stokes.csv", "piezoviscous_eps=0.01.png", "critical_stokes_vs_beta.png"}

    ds = open_results(tmp_path / "piezo.zarr").load()
    drawn = dict(figures.axis_figures(ds))
    assert set(drawn) == {"piezoviscous_eps=0.01", "critical_stokes_vs_beta"}
    fig = drawn["piezoviscous_eps=0.01"]()
    assert "barus viscosity" in fig.get_suptitle()  # "auto" as the solver resolves it
    # v_r, h_m, ln(x_e/x0) (+ its threshold) and the peak viscosity (+ the solidification line),
    # a curve per beta
    _, hm, _, mu = fig.axes
    assert [len(ax.get_lines()) for ax in fig.axes] == [2, 2, 3, 3]
    assert mu.get_yscale() == hm.get_yscale() == "log"
    classic, piezo = (line.get_ydata() for line in mu.get_lines()[:2])
    assert list(classic) == [1.0, 1.0] and piezo[1] > 2.0  # the film thickens under pressure
    assert hm.get_lines()[1].get_ydata()[1] > hm.get_lines()[0].get_ydata()[1]  # ... and stays thicker
    (ax,) = drawn["critical_stokes_vs_beta"]().axes
    rows = critical_stokes(ds)
    x, y = ax.get_lines()[0].get_data()  # St_c against beta, the classic film included
    assert list(x) == [0.0, 2.0] and list(y) == [r["St_c"] for r in rows]
    assert 3.0 < y[1] < y[0] < 30.0  # a piezoviscous film sticks less
    dashed = [line for line in ax.get_lines() if line.get_linestyle() == "--"]
    assert dashed[0].get_ydata()[0] == y[0]  # the classic film's St_c as the dashed line


def test_a_store_with_pi_and_beta_axes_gets_both_figure_families(tmp_path):
    """Each further axis draws its figures once per value of the other (fake solves only)."""
    import pipeline.plots.sweep_maps as figures

    sweep = parse_sweep(physics_sweep_text(
        "St = [1.0, 10.0, 30.0]\neps = [1e-2]\nPi = [0.01, inf]\nbeta = [0.0, 5.0]",
        store=str(tmp_path / "both.zarr")))
    assert run(sweep).done == 12
    drawn = dict(figures.axis_figures(open_results(sweep.store).load()))
    assert set(drawn) == {"cavitation_eps=0.01_beta=0", "cavitation_eps=0.01_beta=5",
                          "critical_stokes_vs_Pi_beta=0", "critical_stokes_vs_Pi_beta=5",
                          "piezoviscous_eps=0.01_Pi=0.01", "piezoviscous_eps=0.01_Pi=inf",
                          "critical_stokes_vs_beta_Pi=0.01", "critical_stokes_vs_beta_Pi=inf"}
    fig = drawn["piezoviscous_eps=0.01_Pi=0.01"]()
    assert "Pi = 0.01" in fig.texts[-1].get_text()  # the footer names the plane
    assert [line.get_label() for line in fig.axes[0].get_lines()] == [
        r"classic film ($\beta = 0$)", r"$\beta = 5$"]


def test_a_capped_axis_says_how_far_the_curves_go():
    from matplotlib.figure import Figure

    from pipeline.plots.sweep_maps import _cap

    ax = Figure().add_subplot()
    St = np.array([1.0, 2.0, 3.0])
    y = np.array([[1.0, 1e3, 1e40], [1.0, math.inf, 1e5]])
    ax.plot(St, y[0])
    ax.set_yscale("log")
    _cap(ax, y, 1e30, St)
    assert ax.get_ylim()[1] == 1e30 and 1e-2 < ax.get_ylim()[0] < 1.0  # 5 % of the range below
    note = ax.texts[0].get_text()
    assert "$10^{40}$ at St = 3" in note and "(1 scene(s), St = 2)" in note
    ax2 = Figure().add_subplot()
    _cap(ax2, y[:, :2].clip(max=1e3), 1e30, St[:2])  # nothing above the cap: untouched
    assert not ax2.texts and ax2.get_ylim()[1] < 1e30


def test_docs_list_every_store_variable_and_status_code():
    from solver.observables import STATUS

    doc = (REPO / "docs" / "pipeline.md").read_text()
    for name in VARIABLES:
        assert f"`{name}`" in doc, name
    for name, (code, _) in STATUS.items():
        assert f"| {code} | `{name}` |" in doc, name
