"""The attempt log (collide(..., attempt_log=True); docs/solver.md, "The attempt log"): a
diagnostic that changes no result, and whose rows add up to the solve's counters."""

import numpy as np
import pytest

from solver import Physics, collide

SCENES = {  # a classic film, a JFO cavity that refills, a Barus lens that collapses
    "classic": dict(St=10.0, eps=1e-4),
    "jfo": dict(St=10.0, eps=1e-4, Pi=1e-3, cavitation="jfo"),
    "barus": dict(St=10.0, eps=1e-4, beta=5.0),
}
COMPARED = ("v_r", "e_wet", "h_m_x1", "ln_x_e_x1", "p_max", "energy_error", "steps",
            "rejected_steps", "newton_iterations", "lu_factorizations", "higher_order_steps")


@pytest.fixture(scope="module", params=list(SCENES))
def pair(request):
    physics = Physics(**SCENES[request.param])
    return (collide(physics, accuracy="fast", save_profiles=False),
            collide(physics, accuracy="fast", save_profiles=False, attempt_log=True))


def test_no_loop_but_one_asked_for_the_log_compiles_it():
    # the log's code is pruned from the loop as imported and from its copies (model/kind.py:
    # LOG_CODE): compiled into every loop it cost the cold compile 3-6 %
    from solver.integration import kinds, stepper

    assert stepper.LOG_CODE is False
    for kw in SCENES.values():
        phys = Physics(**kw).as_array()
        assert kinds.loop_for(phys).LOG_CODE is False
        assert kinds.loop_for(phys, log=True).LOG_CODE is True


def test_the_log_changes_no_result(pair):
    plain, logged = pair
    assert plain.attempts == {}  # kept only when asked
    for name in COMPARED:  # the same to the bit: nothing the loop decides reads the log
        assert np.array_equal(getattr(plain, name), getattr(logged, name), equal_nan=True), name
    for name, column in plain.series.items():
        assert np.array_equal(column, logged.series[name], equal_nan=True), name


def test_the_rows_add_up_to_the_counters(pair):
    _, c = pair
    a = c.attempts
    outcome = a["outcome"]
    assert len({len(v) for v in a.values()}) == 1  # one entry per attempt in every column
    assert (outcome == "accepted").sum() == c.steps
    # the loop counts a rejection where it shrinks the step: an error above the tolerance, a
    # Newton iteration that failed from a fresh matrix, a gap that was not positive
    shrunk = np.isin(outcome, ("rejected_error", "diverged_fresh", "gap_not_positive"))
    assert shrunk.sum() == c.rejected_steps
    assert a["newton"].sum() == c.newton_iterations
    assert np.sum(a["order"][outcome == "accepted"] > 2) == c.higher_order_steps


def test_each_row_says_why(pair):
    _, c = pair
    a = c.attempts
    accepted, rejected = a["outcome"] == "accepted", a["outcome"] == "rejected_error"
    assert np.all(a["error"][accepted] <= 1.0) and np.all(a["error"][rejected] > 1.0)
    diverged = np.char.startswith(a["outcome"].astype(str), "diverged")
    assert np.all(np.isnan(a["error"][diverged]))  # no error where Newton did not converge
    assert np.all(a["fresh_matrix"][a["outcome"] == "diverged_fresh"])
    # the accepted attempts step forward in time, each from where the one before ended
    tau, dtau = a["tau"][accepted], a["dtau"][accepted]
    assert np.allclose(tau[1:], tau[:-1] + dtau[:-1], rtol=1e-12, atol=0.0)
    # an error's largest term names a node of the grid for the film's terms, none for X and V
    film = np.isin(a["largest"], ("pressure", "gap"))
    assert np.all((a["cell"][film] >= 0) & (a["cell"][film] < c.radius.size))
    assert np.all(a["cell"][~film] == -1)
    assert np.all(np.isin(a["largest"][rejected], ("pressure", "gap", "X", "V")))
    # the first step has no history to measure an error against: error 0, no largest term
    first = int(np.argmax(accepted))
    assert a["error"][first] == 0.0 and a["largest"][first] == "" and a["cell"][first] == -1


@pytest.mark.parametrize("bad", ["no", 1, None])
def test_the_log_is_asked_for_with_a_bool(bad):
    with pytest.raises(TypeError, match="attempt_log = .*True or False"):
        collide(Physics(St=10.0, eps=1e-4), accuracy="fast", attempt_log=bad)
