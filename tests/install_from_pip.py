"""A pip install works as the README says (issue 20), from a folder outside the clone.

Not part of ``make test`` (a fresh install compiles the solver: 40 s of CPU or more); ``make
test-install`` runs it and ``.ci/run`` calls that. Steps: a copy of the clone's tracked sources
(as ``git clone`` would give) is installed with ``pip install --no-deps`` into a fresh venv whose
dependencies come from this venv (a ``.pth`` line: the packages are not downloaded again; the
build itself runs as pip runs it, isolated); then, from an empty folder, ``ehd --version``, ``ehd
examples DIR``, ``ehd scene DIR/examples/...``, ``ehd sweep quick --store X`` (the shipped sweep by
name: 24 scenes; the paper sweep's 448 would take minutes) and ``ehd figures X`` must work, with
the installed copy (never the clone) doing the work.
"""

import ast
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

pytestmark = pytest.mark.install

REPO = Path(__file__).resolve().parent.parent
SKIP = shutil.ignore_patterns(".venv", ".git", ".ehd-cache", ".numba_cache", "results", "figures",
                              "build", "*.egg-info", "__pycache__", ".pytest_cache", "dem_export")


def _run(cmd, cwd, env, ok=(0,)):
    p = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True, text=True,
                       timeout=900)
    assert p.returncode in ok, f"{cmd} -> {p.returncode}\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}"
    return p


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pip-install")
    clone = tmp / "ehd-collision"
    shutil.copytree(REPO, clone, ignore=SKIP)
    venv = tmp / "venv"
    _run([sys.executable, "-m", "venv", venv], tmp, os.environ)
    site = Path(subprocess.check_output(
        [venv / "bin" / "python", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        text=True).strip())
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "_ehd_test_deps.pth").write_text("\n".join(sorted(deps)) + "\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(EHD_CACHE_DIR=str(tmp / "cache"), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    _run([venv / "bin" / "python", "-m", "pip", "install", "--quiet", "--no-deps", clone], tmp,
         env)
    work = tmp / "work"
    work.mkdir()
    return {"venv": venv, "env": env, "work": work, "clone": clone, "tmp": tmp}


def _ehd(installed, *args, ok=(0,)):
    return _run([installed["venv"] / "bin" / "ehd", *args], installed["work"], installed["env"],
                ok)


def test_the_installed_copy_does_the_work(installed):
    p = _run([installed["venv"] / "bin" / "python", "-c",
              "import pipeline, solver, importlib.metadata as m; print(pipeline.__file__); "
              "print(solver.__file__); print(m.requires('ehd-collision'))"],
             installed["work"], installed["env"])
    pipeline_file, solver_file, requires = p.stdout.strip().splitlines()
    for f in (pipeline_file, solver_file):
        assert Path(f).is_relative_to(installed["venv"]), f
    pytest_reqs = [r for r in ast.literal_eval(requires) if r.startswith("pytest")]
    assert pytest_reqs and all('extra == "test"' in r for r in pytest_reqs)  # the extra only


def test_version(installed):
    from solver import SOLVER_VERSION

    out = _ehd(installed, "--version").stdout.strip()
    assert out == f"ehd-collision {SOLVER_VERSION} (solver {SOLVER_VERSION})"


def test_examples_scene_sweep_figures(installed):
    work = installed["work"]
    _ehd(installed, "examples", "mine")
    for kind in ("examples", "sweeps"):
        names = sorted(p.name for p in (REPO / kind).iterdir() if p.suffix in (".toml", ".py"))
        assert sorted(p.name for p in (work / "mine" / kind).iterdir()) == names
    p = _ehd(installed, "scene", "mine/examples/glass_beads_water.toml", "--accuracy", "fast")
    assert "results" in p.stdout and "max rebound speed" in p.stdout
    notice = [line for line in p.stderr.splitlines() if "compiling the solver" in line]
    # one line per compiled loop, before the solve that compiles it: the classic film's first,
    # then the loop with every piece where the scene's sensitivity solves switch a piece on
    assert notice and "the classic film" in notice[0], p.stderr
    assert len(notice) == len(set(notice)) <= 2, p.stderr
    assert all(str(installed["tmp"] / "cache") in line for line in notice), p.stderr
    p = _ehd(installed, "sweep", "quick", "--store", "q.zarr", "--executor", "threads")
    assert re.search(r"^\s*done\s+24\b", p.stdout, re.M), p.stdout
    p = _ehd(installed, "figures", "q.zarr", "--out", "figs")
    assert (work / "figs" / "fig12_rebound_velocity.png").is_file()
    assert (work / "figs" / "critical_stokes.csv").is_file()
    p = _ehd(installed, "figures", "q.zarr", "--out", "figs")
    assert "up to date" in p.stdout
    # the named sweep's relative store lands here, not in the installed package
    assert not (installed["venv"] / "results").exists()
