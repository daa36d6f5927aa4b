"""Signals stay signals (issue 27, item 2): a Ctrl-C or SIGTERM that arrives while the compiled
solver runs is handled once it returns, by the handler that was installed, in every executor;
it is never stored as the scene's failure, so a resume recomputes the scene."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from pipeline.errors import EXIT_TERMINATED, Terminated
from solver.interrupts import deferred_interrupt

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_inside_the_block_is_handled_once_after_it(signum):
    seen = []

    def handler(number, frame):
        seen.append((number, inside))

    previous = signal.signal(signum, handler)
    try:
        with deferred_interrupt():
            inside = True
            os.kill(os.getpid(), signum)
            os.kill(os.getpid(), signum)
            time.sleep(0.01)  # Python runs handlers between bytecodes: here, if not deferred
            assert seen == []
            inside = False
        assert seen == [(signum, False)]
        assert signal.getsignal(signum) is handler
    finally:
        signal.signal(signum, previous)


def test_an_ignored_signal_stays_ignored():
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with deferred_interrupt():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.01)
    finally:
        signal.signal(signal.SIGINT, previous)


def test_an_interrupt_wrapped_by_numba_is_raised_not_stored(monkeypatch):
    """numba hands a signal raised while it converts results back as a SystemError caused by
    the interrupt: the task raises the interrupt instead of returning an error record."""
    import solver

    from pipeline.sweeps.tasks import solve_scene

    def wrapped(*args, **kwargs):
        try:
            raise Terminated()
        except Terminated as exc:
            raise SystemError("CPUDispatcher(...) returned a result with an exception set") \
                from exc

    monkeypatch.setattr(solver, "collide", wrapped)
    with pytest.raises(Terminated):
        solve_scene({"St": 5.0, "eps": 0.01}, "fast", {})


DRIVER = textwrap.dedent("""
    import functools, sys
    sys.path.insert(0, {repo!r})
    import pipeline.sweeps.run as r
    from pipeline.sweeps.tasks import solve_scene

    def announced(physics, accuracy, overrides):
        print("solving", flush=True)  # the test sends SIGTERM a second into the solve
        return solve_scene(physics, accuracy, overrides)

    if __name__ == "__main__":
        if sys.argv[1] == "compile":  # fills the numba cache for the solve below
            from solver import Physics, collide
            collide(Physics(St=1000.0, eps=1e-8), accuracy="fast", save_profiles=False)
            sys.exit(0)
        r.run_sweep = functools.partial(r.run_sweep, solve=announced, warm_up=False)
        from pipeline.cli import main
        sys.exit(main(sys.argv[1:]))
    """)
SWEEP = textwrap.dedent("""
    name = "slow"
    store = "slow.zarr"
    [grid]
    St = [1000.0]
    eps = [1e-8]
    [numerics]
    accuracy = "fine"
    rtol = 1e-8
    max_order = 2
    """)


def test_sigterm_inside_the_compiled_solve_of_a_serial_sweep_stores_nothing(tmp_path):
    """SIGTERM a second into a 3 s fine solve of a serial sweep (BDF2: at orders up to 5 the
    solve took 0.8 s on an AMD EPYC, and the signal came after it): 1.8.0 stored the scene as
    failed ("SystemError: CPUDispatcher(...) returned a result with an exception set") in 3 of
    10 tries, exited 3, and the resume never recomputed it. Now: exit 143, one line, nothing
    stored, and the resume solves the scene."""
    (tmp_path / "driver.py").write_text(DRIVER.format(repo=str(REPO)))
    (tmp_path / "slow.toml").write_text(SWEEP)
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    subprocess.run([sys.executable, "driver.py", "compile"], cwd=tmp_path, env=env, check=True)
    proc = subprocess.Popen([sys.executable, "driver.py", "sweep", "slow.toml", "--executor",
                             "serial"], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "solving"
    time.sleep(1.0)
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == EXIT_TERMINATED, (proc.returncode, err)
    assert "Traceback" not in err and "terminated" in err.strip().splitlines()[-1]
    from pipeline import open_results
    from pipeline.sweeps.journal import pending_journal

    assert not pending_journal(tmp_path / "slow.zarr")  # nothing journaled
    with open_results(tmp_path / "slow.zarr") as ds:
        assert set(ds["status"].values.ravel().tolist()) == {0}  # not run, not failed
    # the resume solves what the signal stopped (the real solver)
    resumed = subprocess.run([sys.executable, "driver.py", "sweep", "slow.toml", "--executor",
                              "serial"], cwd=tmp_path, env=env, capture_output=True, text=True,
                             timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert resumed.stdout.count("solving") == 1


@pytest.fixture
def python_ctrl_c():
    """Ctrl-C handled by Python's own handler, as in a terminal, whatever this process
    inherited (a job started in the background ignores SIGINT, and ``ehd`` keeps it ignored)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def _drop_a_ctrl_c():
    """Ctrl-C delivered while a weakref callback runs: Python runs the handler inside it and
    drops its ``KeyboardInterrupt`` (printing "Exception ignored in"), as when the garbage
    collector ran such a callback in CI and the sweep went on to its end with exit 0."""
    import weakref

    class Collected:
        pass

    thing = Collected()
    ref = weakref.ref(thing, lambda r: signal.raise_signal(signal.SIGINT))  # noqa: F841 (alive
    del thing  # while ``thing`` goes: its callback runs here)


@pytest.mark.parametrize("kind", ["serial", "threads"])
def test_a_ctrl_c_python_dropped_is_raised_after_the_scene_that_finished(kind, capsys,
                                                                          python_ctrl_c):
    from pipeline.cli import _handle_signals
    from pipeline.errors import interrupt_handled
    from pipeline.sweeps.runners import open_runner

    got = []
    restore = _handle_signals()
    try:
        with pytest.raises(KeyboardInterrupt):
            with open_runner(kind, 1) as run:
                for tag, _ in run.unordered(lambda x: x, [(i, (i,)) for i in range(6)]):
                    got.append(tag)
                    if len(got) == 2:  # the second scene is being stored
                        _drop_a_ctrl_c()
    finally:
        restore()
        interrupt_handled()
    assert len(got) == 2
    assert "Exception ignored" not in capsys.readouterr().err


def test_a_sweep_whose_ctrl_c_python_dropped_is_exit_130_and_keeps_its_scenes(
        tmp_path, capsys, monkeypatch, python_ctrl_c):
    from pipeline import open_results
    from pipeline.sweeps.journal import pending_journal
    from tests.test_pipeline import fake_solve

    solved = []

    def dropping(physics, accuracy, overrides):
        solved.append(physics)
        if len(solved) == 3:
            _drop_a_ctrl_c()
        return fake_solve(physics, accuracy, overrides)

    _interrupted_sweep(dropping, tmp_path, capsys, monkeypatch)
    assert len(solved) == 3  # stopped after the scene during which Ctrl-C came, not at the end
    with open_results(tmp_path / "f.zarr") as ds:
        stored = int((ds["status"].values != 0).sum())
    assert stored + pending_journal(tmp_path / "f.zarr") == 3  # every finished scene kept
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # main put it back


def test_a_ctrl_c_dropped_in_a_command_without_scenes_still_ends_it_as_one(
        tmp_path, capsys, monkeypatch, python_ctrl_c):
    """Where no loop asks (here ``ehd examples``), the boundary asks once the command is done."""
    import pipeline.cli as cli
    from pipeline.errors import EXIT_INTERRUPTED

    real = cli._parser

    def parser_then_drop(argv=None):
        _drop_a_ctrl_c()
        return real(argv)

    monkeypatch.setattr(cli, "_parser", parser_then_drop)
    code = cli.main(["examples", str(tmp_path / "ex")])
    err = capsys.readouterr().err
    assert code == EXIT_INTERRUPTED, err
    assert "Exception ignored" not in err


def test_ehd_keeps_an_ignored_ctrl_c_ignored_and_puts_every_handler_back():
    """A job started in the background inherits SIGINT ignored: ``ehd`` leaves it so (Ctrl-C
    in the terminal is not meant for it), takes SIGTERM, and restores both afterwards."""
    from pipeline.cli import _handle_signals
    from pipeline.errors import on_signal

    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    term = signal.getsignal(signal.SIGTERM)
    try:
        restore = _handle_signals()
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is on_signal
        restore()
        assert signal.getsignal(signal.SIGTERM) is term
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)


def test_a_ctrl_c_pressed_again_during_the_merge_waits_for_it(tmp_path, capsys, monkeypatch):
    """Ctrl-C stops a sweep and its finished scenes are merged into the store; a second Ctrl-C
    that comes during that merge waits until it is done (``SweepStore.flush`` under
    ``deferred_interrupt``): exit 130, one line, every finished scene in the store and no
    journal left. A hostile review pressed Ctrl-C four times: the merge was cut short (the 240
    finished scenes waited in the journal for the next run) and, in 2 of 4 tries, Python
    printed a traceback."""
    from pipeline import open_results
    from pipeline.sweeps import store as store_module
    from pipeline.sweeps.journal import pending_journal
    from tests.test_pipeline import fake_solve

    solved = []

    def stopped(physics, accuracy, overrides):
        if len(solved) == 3:
            raise KeyboardInterrupt  # the first Ctrl-C, during the fourth scene
        solved.append(physics)
        return fake_solve(physics, accuracy, overrides)

    flush = store_module.SweepStore.flush
    merges = []

    def pressed_again(self, force=False):
        if self._dirty:
            merges.append(len(self._dirty))
            os.kill(os.getpid(), signal.SIGINT)  # the second Ctrl-C, as the merge starts
        flush(self, force)

    monkeypatch.setattr(store_module.SweepStore, "flush", pressed_again)
    _interrupted_sweep(stopped, tmp_path, capsys, monkeypatch)
    assert merges, "no merge saw the second Ctrl-C"
    assert not pending_journal(tmp_path / "f.zarr")  # merged, not left to the next run
    with open_results(tmp_path / "f.zarr") as ds:
        assert int((ds["status"].values != 0).sum()) == len(solved) == 3


def test_the_executable_ignores_a_signal_once_the_command_is_done(monkeypatch):
    """After the command (its exit code decided), ``executable`` ignores Ctrl-C and SIGTERM:
    one pressed again was raised inside a weakref callback of the last collection and Python
    printed "Exception ignored in ... KeyboardInterrupt" after ehd's line."""
    import pipeline.cli as cli

    monkeypatch.setattr(cli, "main", lambda: 130)
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert cli.executable() == 130
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
        os.kill(os.getpid(), signal.SIGINT)  # nothing raised: the process would just end
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _interrupted_sweep(solve, tmp_path, capsys, monkeypatch) -> None:
    """A serial sweep of 6 stand-in scenes solved by ``solve``, which a Ctrl-C stops: asserts
    exit 130 with ``ehd``'s one line last and no traceback."""
    import functools

    import pipeline.sweeps.run as run_module
    from pipeline.cli import main
    from pipeline.errors import EXIT_INTERRUPTED
    from tests.test_pipeline import sweep_text

    monkeypatch.setattr(run_module, "run_sweep", functools.partial(
        run_module.run_sweep, solve=solve, warm_up=False, progress=None))
    (tmp_path / "f.toml").write_text(sweep_text([1.0, 2.0, 5.0], [1e-2, 1e-3], store="f.zarr"))
    monkeypatch.chdir(tmp_path)
    code = main(["sweep", "f.toml", "--executor", "serial"])
    err = capsys.readouterr().err
    assert code == EXIT_INTERRUPTED, err
    assert "Traceback" not in err and "Exception ignored" not in err
    assert err.strip().splitlines()[-1].startswith("ehd sweep: interrupted")
