"""The process environment: one numba cache folder for every command and install kind, workers
that load the parent's kernels, and --workers limits (issue: environment set in four places).

The commands run as subprocesses with HOME and XDG_CACHE_HOME in a temporary folder and neither
EHD_CACHE_DIR nor NUMBA_CACHE_DIR set, as for a new user outside ``make``. ``NUMBA_DEBUG_CACHE=1``
makes every process (parent and dask workers, which share its stdout) print each kernel it saves
to or loads from the cache.
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from solver import _jit

REPO = Path(__file__).resolve().parent.parent
EHD = str(Path(sys.executable).parent / "ehd")

TINY_SWEEP = """
name = "tiny"
store = "tiny.zarr"
[grid]
St = [5.0]
eps = [1e-2, 1e-5]
[numerics]
accuracy = "fast"
"""


def _user_env(home: Path, **extra) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("EHD_CACHE_DIR", "NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "PYTHONPATH")
           and not k.startswith("NUMBA_DEBUG")}
    env.update(HOME=str(home), PYTHONUNBUFFERED="1", NUMBA_DEBUG_CACHE="1", **extra)
    return env


def _run(cmd, env, cwd, ok=(0,)):
    p = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, timeout=300)
    assert p.returncode in ok, f"{cmd} -> {p.returncode}\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    return p


def _saved(out: str) -> list[str]:
    return re.findall(r"data saved to '([^']+)'", out)


def _index_files(*folders: Path) -> set[Path]:
    return {p for f in folders if f.exists() for p in f.rglob("*.nbi")}


def _check_commands(prefix: list[str], env: dict, tmp: Path, kernels_root: Path, scan: Path,
                    scene: bool = True) -> None:
    """Cold cache: a sweep compiles each kernel once (the parent) and its worker loads them;
    then ``run`` (and ``scene``) load the same kernels; every index file is in the documented
    folder ``<HOME>/.cache/ehd-collision/numba/solver-<hash>/`` (none elsewhere in ``scan``, the
    repository's old ``.numba_cache`` or the packages' ``__pycache__``)."""
    (tmp / "tiny.toml").write_text(TINY_SWEEP)
    # index files left by earlier runs (a developer's old .numba_cache): only new ones count
    before = {(f, f.stat().st_mtime_ns) for f in
              _index_files(scan, REPO / ".numba_cache", REPO / "solver", REPO / "pipeline")}
    p = _run([*prefix, "sweep", "tiny.toml", "--executor", "processes", "--workers", "1"],
             env, tmp, ok=(0, 3))
    saved = _saved(p.stdout)
    assert saved, p.stdout[-2000:]
    assert len(saved) == len(set(saved)), "a kernel was compiled twice (parent and worker)"
    assert "data loaded from" in p.stdout, "the worker did not load the parent's kernels"
    # the compile is announced, with where the cache goes (no silent wait on a fresh install)
    notice = [line for line in p.stderr.splitlines() if "compiling the solver" in line]
    assert len(notice) == 1 and str(kernels_root) in notice[0], p.stderr[-2000:]
    p = _run([*prefix, "run", "--St", "5", "--eps", "0.01", "--accuracy", "fast", "--json"],
             env, tmp)
    assert not _saved(p.stdout), "ehd run compiled again instead of loading the sweep's cache"
    assert "compiling the solver" not in p.stderr  # a warm cache: nothing to announce
    assert "data loaded from" in p.stdout
    if scene:
        _run([*prefix, "scene", str(REPO / "examples" / "glass_beads_water.toml")], env, tmp)
    everywhere = _index_files(scan, REPO / ".numba_cache", REPO / "solver", REPO / "pipeline")
    everywhere = {f for f in everywhere if (f, f.stat().st_mtime_ns) not in before}
    documented = _index_files(*kernels_root.glob("solver-*"))
    assert documented and everywhere == documented, sorted(map(str, everywhere - documented))


def test_cache_root_precedence(monkeypatch, tmp_path):
    for var in ("EHD_CACHE_DIR", "NUMBA_CACHE_DIR", "XDG_CACHE_HOME"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert _jit.cache_root() == tmp_path / "home" / ".cache" / "ehd-collision"
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert _jit.cache_root() == tmp_path / "xdg" / "ehd-collision"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "nb"))
    assert _jit.cache_root() == tmp_path / "nb"
    monkeypatch.setenv("EHD_CACHE_DIR", str(tmp_path / "ehd"))
    assert _jit.cache_root() == tmp_path / "ehd"
    assert re.fullmatch(r"solver-[0-9a-f]{16}", Path(_jit.CACHE_DIR).name)
    assert Path(_jit.CACHE_DIR).parent.name == "numba"


def test_unwritable_cache_folder_warns_once_and_falls_back(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    env = _user_env(tmp_path, EHD_CACHE_DIR=str(blocker / "cache"), TMPDIR=str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    p = _run([sys.executable, "-c", "from solver import _jit; print(_jit.CACHE_DIR)"],
             env, tmp_path)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and str(blocker / "cache") in lines[0] and "EHD_CACHE_DIR" in lines[0]
    used = Path(p.stdout.strip().splitlines()[-1])
    assert used.parent == tmp_path / "tmp" / f"ehd-collision-{os.getuid()}" / "numba"
    assert used.is_dir()


@pytest.mark.install
def test_editable_install_commands_share_the_documented_cache(tmp_path):
    home = tmp_path / "home"
    env = _user_env(home)
    _check_commands([EHD], env, tmp_path, home / ".cache" / "ehd-collision" / "numba", tmp_path)
    # XDG_CACHE_HOME moves it, and ehd info says where
    p = _run([EHD, "info"], {**env, "XDG_CACHE_HOME": str(tmp_path / "xdg")}, tmp_path)
    assert str(tmp_path / "xdg" / "ehd-collision" / "numba" / "solver-") in p.stdout


@pytest.mark.install
def test_non_editable_install_caches_in_the_documented_folder_not_site_packages(tmp_path):
    # what `pip install .` puts into site-packages: copies of the two packages (copied here, as
    # building a wheel needs the `wheel` package and possibly the network)
    site = tmp_path / "site"
    for package in ("solver", "pipeline"):
        shutil.copytree(REPO / package, site / package,
                        ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    work = tmp_path / "work"
    work.mkdir()
    home = tmp_path / "home"
    env = _user_env(home, PYTHONPATH=str(site))
    p = _run([sys.executable, "-c", "import solver; print(solver.__file__)"], env, work)
    assert Path(p.stdout.strip()).is_relative_to(site)  # the installed copy, not the repo
    cli = [sys.executable, "-m", "pipeline.cli"]
    _check_commands(cli, env, work, home / ".cache" / "ehd-collision" / "numba", tmp_path,
                    scene=False)  # (no site-packages/.numba_cache nor __pycache__ kernels either)


def test_the_compile_notice_names_each_loop_the_cache_lacks_once(monkeypatch):
    """A user who ran the classic film and then a JFO film waited 19 s in silence: the notice came
    only for an empty cache. Now each compiled loop (solver/integration/kinds.py) the cache lacks
    is announced, once per process, before the solve that compiles it."""
    import io

    from pipeline import environment
    from solver import Physics
    from solver.integration import kinds

    cached = set()
    monkeypatch.setattr(kinds, "is_cached", lambda codes: codes in cached)
    monkeypatch.setattr(environment, "_NOTICED", set())
    jfo = dict(St=5.0, eps=1e-2, Pi=1e-3, cavitation="jfo")
    said = io.StringIO()
    assert "the loop for the classic film" in environment.compile_notice(said)
    assert environment.compile_notice(said, physics=[None]) is None  # once per process
    line = environment.compile_notice(said, physics=[Physics(St=5.0, eps=1e-2), jfo])
    assert "every piece of physics" in line and "classic" not in line
    assert said.getvalue().count("\n") == 2 and "compiling the solver" in said.getvalue()
    # a loop the cache holds is not announced; an invalid scene is its solve's to refuse
    monkeypatch.setattr(environment, "_NOTICED", set())
    cached.update({(), kinds.compiled_pieces(Physics(**jfo).as_array())})
    assert environment.compile_notice(said, physics=[None, jfo, dict(St=-1.0, eps=1e-2)]) is None


def test_too_many_local_workers_are_refused(tmp_path, capsys):
    from pipeline.cli import main
    from pipeline.sweeps.runners import max_local_workers

    (tmp_path / "tiny.toml").write_text(TINY_SWEEP)
    code = main(["sweep", str(tmp_path / "tiny.toml"), "--store", str(tmp_path / "s.zarr"),
                 "--workers", "1000"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert f"more than {max_local_workers()}" in err


def test_waiting_for_scheduler_workers_says_so_and_gives_up():
    import io

    from dask.distributed import LocalCluster

    from pipeline.sweeps.runners import RunnerError, open_runner

    said = io.StringIO()
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        with pytest.raises(RunnerError, match="only 0 of 2 workers connected .* after 1 s"):
            with open_runner(address=cluster.scheduler_address, workers=2, wait_workers=1,
                             stream=said):
                pass
    assert "waiting for 2 workers (0 connected)..." in said.getvalue()


WARMED = []


def _record_warm():
    WARMED.append(os.environ.get("OPENBLAS_NUM_THREADS"))


def test_worker_plugin_sets_up_workers_that_join_later(monkeypatch):
    from dask.distributed import Client, LocalCluster

    from pipeline.sweeps.worker import WorkerSetup

    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    WARMED.clear()
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        client.register_plugin(WorkerSetup(_record_warm))
        cluster.scale(1)
        client.wait_for_workers(1, timeout=30)
        assert client.submit(len, [1, 2]).result(timeout=30) == 2
    assert WARMED == ["1"]  # environment first, then the warm-up, on the late worker
