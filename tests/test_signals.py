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
from solver._jit import deferred_interrupt

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
    """)


def test_sigterm_inside_the_compiled_solve_of_a_serial_sweep_stores_nothing(tmp_path):
    """SIGTERM a second into a 3 s fine solve of a serial sweep: 1.8.0 stored the scene as
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
