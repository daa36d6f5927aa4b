"""The benchmark harness (benchmarks/harness.py) on synthetic timings: alternation order, medians
and spreads of per-round ratios, the verdict "moved", and the provenance every result file
carries. Nothing here times anything: speed is measured by ``make bench``, never in tests."""

import importlib.util
import json
import os
import subprocess
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"
PROVENANCE = ("solver_version", "commit", "machine", "load")


def _load(name):
    spec = importlib.util.spec_from_file_location(f"bench_{name}_under_test", BENCH / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def harness():
    return _load("harness")


def test_rounds_rotate_the_order_and_drop_the_warmup(harness):
    log = []

    def side(label):
        def measure():
            log.append(label)
            return {"wall_s": float(len(log))}
        return measure

    runs = harness.alternate({"a": side("a"), "b": side("b"), "c": side("c")}, rounds=3, warmup=1)
    assert log == ["a", "b", "c", "a", "b", "c", "b", "c", "a", "c", "a", "b"]
    # the warm-up round (the first three calls) is not kept; each side has one entry a round
    assert [r["wall_s"] for r in runs["a"]] == [4.0, 9.0, 11.0]
    assert [r["wall_s"] for r in runs["c"]] == [6.0, 8.0, 10.0]


def test_ratio_is_the_median_of_per_round_ratios_with_their_spread(harness):
    # a burst of load in round 3 slows both sides alike: the per-round ratio is immune, the
    # ratio of medians is not what is quoted
    this = [1.0, 1.1, 5.0, 0.9, 1.0]
    base = [2.0, 2.0, 10.0, 2.0, 2.5]
    got = harness.compare(this, base)
    assert got["ratio"]["rounds"] == pytest.approx([0.5, 0.55, 0.5, 0.45, 0.4])
    assert got["ratio"]["median"] == pytest.approx(0.5)
    assert (got["ratio"]["min"], got["ratio"]["max"]) == pytest.approx((0.4, 0.55))
    assert got["ratio"]["n"] == 5
    assert got["this"]["median"] == 1.0 and got["baseline"]["median"] == 2.0
    assert got["moved"] == "faster"


def test_a_ratio_whose_rounds_straddle_one_has_not_moved(harness):
    noisy = harness.compare([1.0, 1.8, 0.9, 1.0, 1.0], [2.0, 1.0, 1.0, 1.0, 1.0])
    assert noisy["ratio"]["median"] == pytest.approx(1.0)
    assert (noisy["ratio"]["min"], noisy["ratio"]["max"]) == pytest.approx((0.5, 1.8))
    assert noisy["moved"] == "no"
    assert harness.compare([1.2, 1.3, 1.1, 1.2, 1.2], [1.0] * 5)["moved"] == "slower"


def test_a_change_smaller_than_the_tolerance_or_from_too_few_rounds_is_not_a_result(harness):
    # every round 1 % faster: consistent, but identical code lands that far apart
    assert harness.compare([0.99] * 7, [1.0] * 7)["moved"] == "no"
    assert harness.compare([0.5] * 3, [1.0] * 3)["moved"] == "too few rounds"


def test_rounds_not_alternated_in_one_run_are_refused(harness):
    with pytest.raises(ValueError, match="not alternated"):
        harness.round_ratios([1.0, 2.0], [1.0])


def test_the_table_marks_what_moved(harness):
    def runs(cpu, wall):
        return [{"cpu_s": c, "wall_s": w} for c, w in zip(cpu, wall)]

    rows = harness.figure_rows({
        "fast one": harness.compare_runs(runs([1.0] * 5, [1.0, 3.0, 1.0, 3.0, 2.0]),
                                         runs([2.0] * 5, [2.0] * 5)),
        "same": harness.compare_runs(runs([1.0, 2.0, 1.0, 2.0, 1.5], [1.0] * 5),
                                     runs([2.0, 1.0, 2.0, 1.0, 1.5], [2.0] * 5))})
    assert rows[2] == ("| fast one | 1000 | 2000 | 0.50 | 0.50-0.50 | **faster** | 1.00 | "
                       "0.50-1.50 | 5 |")
    # the verdict is the CPU time's: a wall time that moved (every round 0.5) is context
    assert rows[3] == "| same | 1500 | 1500 | 1.00 | 0.50-2.00 | no | 0.50 | 0.50-0.50 | 5 |"


def test_written_results_keep_their_keys_and_add_the_provenance(harness, tmp_path):
    from solver import SOLVER_VERSION

    path = tmp_path / "r.json"
    harness.write_json(path, {"meta": {"load": "3.1"}, "results": [1, 2]}, [0.5, 0.4, 0.3])
    doc = json.loads(path.read_text())
    assert doc["meta"] == {"load": "3.1"} and doc["results"] == [1, 2]
    head = subprocess.run(["git", "-C", str(BENCH), "rev-parse", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    assert doc["commit"] == head and isinstance(doc["dirty"], bool)
    assert doc["solver_version"] == SOLVER_VERSION
    assert doc["load"]["start"] == [0.5, 0.4, 0.3] and len(doc["load"]["end"]) == 3
    assert doc["machine"]["cores"] >= 1


def test_the_machine_names_its_cpu_and_the_instruction_sets_that_move_the_last_bits(harness):
    """numba compiles for the host CPU: fused multiply-add and the vector width can change a
    result's last bits between machines, so a result file says which it ran on."""
    cpu = harness.machine()["cpu"]
    assert cpu and cpu in harness.describe({"machine": harness.machine(), "load": None})
    info = Path("/proc/cpuinfo")
    if info.exists():  # each flag named exactly when the kernel lists it
        flags = next(line for line in info.read_text().splitlines() if line.startswith("flags"))
        listed = set(flags.split(":", 1)[1].split())
        named = set(cpu.rsplit("(", 1)[1].rstrip(")").split())
        assert {f for f in harness._CPU_FLAGS if f in listed} == named & set(harness._CPU_FLAGS)


def test_solver_version_read_from_history_matches_the_source(harness):
    from solver import SOLVER_VERSION

    assert harness.solver_version() == SOLVER_VERSION
    assert harness.solver_version(commit="HEAD") == harness.solver_version()


def test_every_result_file_names_its_solver_commit_machine_and_load():
    files = sorted(BENCH.glob("*.json"))
    assert files
    for path in files:
        doc = json.loads(path.read_text())
        missing = [k for k in PROVENANCE if k not in doc]
        assert not missing, f"{path.name} lacks {missing}"
        assert doc["solver_version"] and doc["commit"]


def test_the_mirrored_checkout_keeps_time_stamps_and_drops_stale_files(harness, tmp_path):
    dest = tmp_path / "this"
    (dest / "solver" / "__pycache__").mkdir(parents=True)
    (dest / "solver" / "__pycache__" / "x.pyc").write_bytes(b"")
    (dest / "solver" / "gone.py").write_text("stale")
    harness.sync_worktree(dest)
    src = harness.REPO / "benchmarks" / "harness.py"
    copy = dest / "benchmarks" / "harness.py"
    assert copy.read_bytes() == src.read_bytes()
    # numba's cache of an earlier run stays valid only if the stamp is the source's
    assert copy.stat().st_mtime_ns == src.stat().st_mtime_ns
    assert not (dest / "solver" / "gone.py").exists()
    assert (dest / "solver" / "__pycache__" / "x.pyc").exists()


def test_the_suite_report_names_what_moved_against_the_baseline(harness, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))  # suite.py imports harness as its neighbour
    suite = _load("suite")

    def runs(cpu):
        return [{"cpu_s": c, "wall_s": c} for c in cpu]

    doc = {"baseline": {"ref": "main", "commit": "a" * 40, "solver_version": "1.0.0"},
           "rounds": 5, "errors": {"old physics": "TypeError: no such field"},
           "figures": {
               "slower one": {"group": "solver", **harness.compare_runs(
                   runs([2.0, 2.1, 1.9, 2.0, 2.2]), runs([1.0] * 5))},
               "steady one": {"group": "solver", **harness.compare_runs(
                   runs([1.0, 1.1, 0.9, 1.0, 1.0]), runs([1.0] * 5))}},
           **harness.provenance([1.0, 1.0, 1.0])}
    text = suite.render(doc)
    assert "Moved beyond the rounds' spread: slower one (slower, 2.00x in CPU time)." in text
    assert "steady one (" not in text
    assert "old physics: TypeError: no such field" in text
    assert "`main` = commit aaaaaaa (solver 1.0.0)" in text


def test_a_report_from_a_loaded_machine_says_its_times_are_not_results(harness):
    doc = harness.provenance([3.8, 3.0, 2.0])
    doc["machine"]["cores"] = 2
    assert "a shared machine" in harness.describe(doc)
    doc["load"] = {"start": [0.2, 0.2, 0.2], "end": [0.4, 0.3, 0.2]}
    assert "shared" not in harness.describe(doc)
    assert "load not recorded" in harness.describe(harness.historical_provenance(
        BENCH / "accuracy.json"))


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="the system cannot pin")
def test_the_two_solver_processes_take_turns_on_one_core_and_the_report_says_so(harness,
                                                                                 tmp_path):
    with harness.SolverProcess(BENCH.parent, str(tmp_path)) as a, \
            harness.SolverProcess(BENCH.parent, str(tmp_path)) as b:
        core = harness.SolverProcess.pin_together([a, b])
        assert core in os.sched_getaffinity(0)
        assert os.sched_getaffinity(a.proc.pid) == {core} == os.sched_getaffinity(b.proc.pid)
    doc = harness.provenance([0.1, 0.1, 0.1])
    assert "pinned" not in harness.describe(doc)
    assert f"pinned together to core {core}" in harness.describe({**doc, "pinned_core": core})


def test_profile_names_numba_functions_and_sums_their_specialisations():
    """bench_refcount.py --functions: a numba symbol reads as its module and function, every
    other symbol as it is, and the shares of one function's specialisations add up."""
    bench = _load("bench_refcount")
    basis = ("_ZN6solver11integration7stepper6_basisB4v226B96c8tJTIeFIjxB2IKSgI4CrvQCk0Z4yRYcWsC"
             "AgXrKFt1X1ep5xVXqOgrqyfl5JUWJySUgdmJaHpgqSi5Qr9UExRM8hYGt0AQAE5ArrayIdLi1E1C7mutable7")
    assert bench.function_name(basis) == "solver.integration.stepper._basis"
    assert bench.function_name("dgemm_kernel_SKYLAKEX") == "dgemm_kernel_SKYLAKEX"
    report = "\n".join([
        f"    18.56%  libpython.so  [.] {basis}",
        f"     1.00%  [JIT] tid 7  [.] {basis.replace('B4v226', 'B4v227')}",
        "    11.48%  libscipy_openblas.so  [.] dgemm_kernel_SKYLAKEX",
        "     0.10%  libc.so  [.] memcpy",
    ])
    shares = bench.by_function(report)
    assert shares == {"solver.integration.stepper._basis": pytest.approx(19.56),
                      "dgemm_kernel_SKYLAKEX": 11.48}  # memcpy is below the 0.2 % floor


def test_profile_counts_an_entrys_own_copies_of_the_runtime_as_reference_counting():
    """bench_refcount.py: an entry's own copy of the runtime's reference counting, which a map
    names with the entry's suffix (solver/_jit.py), is reference counting; a function whose name
    only begins alike is not."""
    bench = _load("bench_refcount")
    report = "\n".join([
        "     2.00%  perf-123.map  [.] NRT_incref.0561b3d7b6b39f48",
        "     1.50%  perf-123.map  [.] NRT_decref",
        "     0.50%  perf-123.map  [.] NRT_increfs_all",
        "    10.00%  libscipy_openblas.so  [.] dgemm_kernel_SKYLAKEX",
    ])
    shares = bench.shares(report)
    assert shares["reference counting"] == pytest.approx(3.5)
    assert shares["compiled model code"] == pytest.approx(0.5)
    assert shares["BLAS/LAPACK"] == pytest.approx(10.0)


@pytest.mark.parametrize("scene", [["nonsense=1"], ["beta=-3"], ["beta"]])
def test_a_profiling_scripts_bad_scene_is_one_line_exit_2(harness, scene, tmp_path, capsys):
    """``--scene`` of bench_refcount.py and refcount_callers.py: a field that is malformed or
    that ``Physics`` refuses is one usage line and exit 2 in the parent, not a child that dies
    with a traceback."""
    import argparse

    parser = argparse.ArgumentParser(prog="bench")
    harness.add_scene_options(parser, tmp_path / "report.md")
    args = parser.parse_args(["--scene", *scene, "--out", str(tmp_path / "x.md")])
    with pytest.raises(SystemExit) as exit_:
        harness.scene_options(parser, args, tmp_path / "report.md")
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("bench: error: --scene") and "Traceback" not in "\n".join(err)
