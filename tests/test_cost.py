"""Cost ceilings (scipy style): a performance regression fails a test without timing anything.

Counts for St = 10, eps = 0.01 and St = 30, eps = 1e-8 were measured when the presets were
chosen (benchmarks/solver.md); the ceilings allow 30 % drift for harmless changes."""

import pytest

from solver import collide

MEASURED = {  # (accuracy, St, eps): (accepted steps, Newton iterations, LU factorisations)
    ("fast", 10.0, 1e-2): (439, 1303, 61),
    ("standard", 10.0, 1e-2): (874, 2322, 65),
    ("standard", 30.0, 1e-8): (1142, 3201, 83),
    ("fine", 10.0, 1e-2): (1590, 4102, 67),
}


@pytest.mark.parametrize("key", list(MEASURED))
def test_cost_ceiling(key):
    accuracy, stokes, eps = key
    c = collide(stokes, eps, accuracy=accuracy, save_profiles=False)
    steps, newton, lu = MEASURED[key]
    assert c.ok
    assert c.steps < 1.3 * steps
    assert c.newton_iterations < 1.3 * newton
    assert c.lu_factorizations < 1.3 * lu
    assert c.rejected_steps < 0.1 * c.steps
