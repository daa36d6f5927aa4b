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


@pytest.mark.parametrize("stokes, eps", [(10.0, 1e-4), (100.0, 1e-6)])
def test_higher_orders_reach_the_same_solution_in_fewer_steps(stokes, eps):
    """The variable-order BDF (``max_order`` 5, integration/stepper.py) and BDF2 converge in time
    to one solution on one grid, and at the standard tolerance order 5 takes at most half the
    steps with a time error no larger than BDF2's (measured with the tolerance factor 1: 0.32x
    and 0.31x the steps; v_r errors 6.6e-6 against 7.1e-5 and 2.5e-7 against 2.6e-5; the
    presets' factor 4 takes fewer). Compared: the rebound speed and the departure, which the
    integration gives."""
    physics = Physics(St=stokes, eps=eps)

    def run(order, rtol=None):
        c = collide(physics, rtol=rtol, max_order=order, save_profiles=False)
        assert (c.higher_order_steps > 0) == (order > 2)  # the counter of the orders used
        return c.steps, np.array([c.v_r, c.ln_x_e_x1])

    _, ref = run(5, 1e-8)
    # BDF2 at rtol 1e-7 leaves a time error of a few 1e-7 (measured 0.8-6.8e-7 in v_r at rtol
    # 1e-8): 1e-5 relative is far below both methods' errors at the standard rtol
    np.testing.assert_allclose(run(2, 1e-7)[1], ref, rtol=1e-5)
    (steps2, bdf2), (steps5, high) = run(2), run(5)
    assert steps5 <= 0.5 * steps2, (steps5, steps2)
    assert np.abs(high / ref - 1.0).max() <= np.abs(bdf2 / ref - 1.0).max(), (high, bdf2, ref)


@pytest.mark.parametrize("pieces", [dict(roughness=1.0, asperity_stiffness=2.0, e_dry=0.8),
                                    dict(roughness=1.0, asperity_stiffness=2.0, e_dry=0.8,
                                         cavitation="jfo", Pi=1e-3)])
def test_films_not_smooth_in_time_stay_at_order_two(pieces):
    """Rough surfaces (contact and unloading switch at an instant), with a cavitation floor or
    without, stay at BDF2 whatever ``max_order``: bit for bit the same collision (order 5 on a
    rough film gave v_r 0.118 where the converged value is 0.090: model/step.py,
    ``smooth_in_time``)."""
    physics = Physics(St=10.0, eps=1e-2, **pieces)
    a, b = (collide(physics, accuracy="fast", max_order=k, save_profiles=False) for k in (2, 5))
    assert (a.v_r, a.steps, a.newton_iterations) == (b.v_r, b.steps, b.newton_iterations)
    assert b.higher_order_steps == 0
    # and at rtol: the factor on the tolerance above order 2 does not touch them
    c = collide(physics, accuracy="fast", high_order_rtol_factor=1.0, save_profiles=False)
    assert (c.v_r, c.steps, c.newton_iterations) == (b.v_r, b.steps, b.newton_iterations)


@pytest.mark.parametrize("model", ["jfo", "reynolds"])
def test_a_cavitating_film_drops_to_bdf2_at_rtol_once_a_cavity_opens(model):
    """A film with a floor takes the orders above 2 (at the presets' 4 times ``rtol``) until its
    first cavity, then BDF2 at ``rtol`` (model/step.py, ``smooth_from_now``): the steps above
    order 2 all lie before the first row with a cavity; from there on it is the film BDF2 takes
    at ``rtol``, so ``max_order`` 2 from the start gives the same rebound to within the
    approach's time error (the reference's ``ln x_e`` error at this preset is ~5e-4,
    benchmarks/cavitation.md)."""
    physics = Physics(St=10.0, eps=1e-2, Pi=1e-3, cavitation=model)
    preset = collide(physics, accuracy="standard")
    bdf2 = collide(physics, accuracy="standard", max_order=2)
    assert preset.ok and preset.cavitated and bdf2.higher_order_steps == 0
    first_cavity = int(np.argmax(preset.to_xarray()["cavity_radius"].values > 0))
    assert 0 < preset.higher_order_steps <= first_cavity
    assert preset.steps < bdf2.steps
    assert preset.ln_x_e_x1 == pytest.approx(bdf2.ln_x_e_x1, rel=2e-3)


def test_the_tolerance_above_order_two_is_rtol_times_its_factor():
    """A smooth film above order 2 steps at ``rtol * high_order_rtol_factor`` (the presets' 4):
    the same collision as the factor 1 at 4 times the rtol, bit for bit, and another one than
    the factor 1 at rtol."""
    physics = Physics(St=10.0, eps=1e-2)
    preset = collide(physics, save_profiles=False)
    same = collide(physics, rtol=4 * 5e-5, high_order_rtol_factor=1.0, save_profiles=False)
    tight = collide(physics, high_order_rtol_factor=1.0, save_profiles=False)
    assert (preset.v_r, preset.steps) == (same.v_r, same.steps)
    assert tight.steps > preset.steps


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
