"""Convergence under refinement (observed order) and independence of where the grid ends."""

import numpy as np
import pytest

from solver import Physics, collide

OBSERVABLES = ("v_r", "h_m_x1", "h_m_approach_x1", "ln_x_e_x1", "peak_force")


def _observables(c):
    return np.array([getattr(c, k) for k in OBSERVABLES])


@pytest.mark.parametrize("stokes", [5.0, 30.0])
def test_grid_convergence_is_second_order(stokes):
    # three grids (inner cells 32, 64, 128, everything else refined alike) with a time
    # tolerance 25x below the standard one, so time errors stay below the grid differences.
    # Design order 2; measured 1.65-2.2 (St = 5) and 1.70-1.89 (St = 30).
    values = np.array([_observables(collide(stokes, 0.01, n_inner=n, rtol=2e-6,
                                            save_profiles=False)) for n in (32, 64, 128)])
    diffs = np.abs(np.diff(values, axis=0))
    orders = np.log2(diffs[0] / diffs[1])
    print(f"St={stokes}: observed orders", dict(zip(OBSERVABLES, orders.round(2))))
    assert np.all(orders > 1.5), dict(zip(OBSERVABLES, orders))


def test_results_do_not_depend_on_where_the_grid_ends():
    # the film is infinite in the model: the far-field tail (force and deflection) and the
    # rigid-exact boundary row must make the grid end irrelevant. Doubling the extent twice
    # changes nothing beyond 2e-5 relative (measured 2e-6 at St = 5 and 30).
    base = None
    for extent in (30.0, 60.0, 120.0):
        values = _observables(collide(10.0, 0.01, outer_extent=extent, save_profiles=False))
        if base is None:
            base = values
        np.testing.assert_allclose(values, base, rtol=2e-5)


def test_time_tolerance_convergence():
    # the time error falls with the step tolerance (BDF2 with local error control: the global
    # error is roughly proportional to rtol); a 4x tighter rtol must cut it at least 2x
    ref = _observables(collide(10.0, 0.01, rtol=1e-6, save_profiles=False))
    errs = [np.abs(_observables(collide(10.0, 0.01, rtol=r, save_profiles=False)) - ref).max()
            for r in (4e-4, 1e-4)]
    assert errs[1] < 0.5 * errs[0], errs


def test_rough_collision_grid_convergence_is_second_order():
    # a rough collision (asperities touch from h = 0.5 x1 on, closest approach 0.29 x1, e_dry
    # 0.9) on the same three grids: the contact law is C^1 at first touch, smooth below it, so
    # the film's second order should survive. Measured 1.68-1.93 (v_r 1.68).
    physics = Physics(St=30.0, eps=0.01, roughness=0.5, asperity_stiffness=5.0, e_dry=0.9)
    values = np.array([_observables(collide(physics, n_inner=n, rtol=2e-6, save_profiles=False))
                       for n in (32, 64, 128)])
    assert values[-1][OBSERVABLES.index("h_m_x1")] < 0.5  # the asperities carried load
    diffs = np.abs(np.diff(values, axis=0))
    orders = np.log2(diffs[0] / diffs[1])
    assert np.all(orders > 1.5), dict(zip(OBSERVABLES, orders))
