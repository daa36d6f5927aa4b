"""Cost ceilings (scipy style): a performance regression fails a test without timing anything.

Counts for St = 10, eps = 0.01 and St = 30, eps = 1e-8, measured with the presets of solver 1.12.0
(orders up to 5; benchmarks/accuracy.md); the ceilings allow 30 % drift for harmless changes.
Rejected steps have a ceiling of their own: at orders up to 5 a collision takes a fifth to a third
of BDF2's steps and about as many rejections (13-21 here, 5-8 % of the attempts), so a share of
the accepted steps (BDF2's was under 10 %) no longer says whether the step control regressed."""

import pytest

from solver import collide

MEASURED = {  # (accuracy, St, eps): (accepted steps, Newton iterations, LU factorisations,
    #                                  rejected steps)
    ("fast", 10.0, 1e-2): (156, 548, 63, 13),
    ("standard", 10.0, 1e-2): (232, 740, 76, 15),
    ("standard", 30.0, 1e-8): (286, 980, 106, 21),
    # solver 1.15.0: the fine preset is a pair of solves (80 and 40 inner cells,
    # solver/extrapolation.py), whose counts are both solves'
    ("fine", 10.0, 1e-2): (648, 1939, 176, 27),
}


@pytest.mark.parametrize("key", list(MEASURED))
def test_cost_ceiling(key):
    accuracy, stokes, eps = key
    c = collide(stokes, eps, accuracy=accuracy, save_profiles=False)
    steps, newton, lu, rejected = MEASURED[key]
    assert c.ok
    assert c.steps < 1.3 * steps
    assert c.newton_iterations < 1.3 * newton
    assert c.lu_factorizations < 1.3 * lu
    assert c.rejected_steps < 1.3 * rejected
