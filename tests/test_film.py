"""The film model's residual, Jacobian and linear algebra against independent references.

The Jacobian is assembled from each term's partial derivatives (solver/model/film.py); a wrong
derivative would only show up as more Newton iterations, so it is checked here against central
differences of the residual on random admissible states (positive gaps, pressures of both signs,
a step coefficient from small to large). The compiled LAPACK/BLAS calls are checked against numpy.
"""

import numpy as np
import pytest

from solver import Physics
from solver.collision import scene_grid
from solver.integration.linalg import lu_factor, lu_solve, matvec
from solver.model.film import gap, jacobian, residual
from solver.physics import PI
from solver.settings import resolve


def _state(rng, grid, phys):
    """A random admissible state: a rigid-like pressure with noise, and an X that keeps H > 0."""
    n = grid.s.size
    v = rng.uniform(-1.0, 1.0)
    x = rng.uniform(0.3, 3.0)
    p = 3.0 * v / (x + grid.s) ** 2 * (1.0 + 0.3 * rng.standard_normal(n))
    w, h = np.empty(n), np.empty(n)
    gap(grid.s, grid.influence, x, p, w, h)
    if np.min(h) <= 0.05:
        x += 0.1 - np.min(h)
    return x, v, p


def _residual(grid, phys, bh, hist, y, active):
    """The step's residual at the unknowns ``y``; with the JFO slots: ``y[i]`` is ``theta_i`` in a
    cavitated cell (``P_i`` fixed at ``-Pi`` there), ``P_i`` elsewhere (no cell cavitated: the
    classic film)."""
    n = grid.s.size
    p, theta = y[:n].copy(), np.ones(n - 1)
    theta[active] = y[:n - 1][active]
    p[:n - 1][active] = -phys[PI]
    w, h, q, res = np.empty(n), np.empty(n), np.empty(n - 1), np.empty(n + 2)
    gap(grid.s, grid.influence, y[n], p, w, h)
    residual(grid.s, grid.s_face, grid.area, grid.force_weight, phys, bh, hist[0], hist[1],
             hist[2], y[n], y[n + 1], p, theta, h, q, res)
    return res


def _central_differences(residual_of, y, p, rel_step=3e-4):
    """Central differences of ``residual_of(y)`` in every unknown. Step 3e-4 of each unknown's
    scale (floor: 1e-3 of the largest pressure, for the tiny far-field pressures; theta slots are
    O(1)): measured, the difference error is round-off ~ eps |res| / step below that (1.6e-6 at
    6e-6) and truncation ~ step^2 above it (1e-8 at 1e-3)."""
    fd = np.empty((y.size, y.size))
    for k in range(y.size):
        step = rel_step * max(abs(y[k]), 1e-3 * np.max(np.abs(p)))
        yp, ym = y.copy(), y.copy()
        yp[k] += step
        ym[k] -= step
        fd[:, k] = (residual_of(yp) - residual_of(ym)) / (2.0 * step)
    return fd


@pytest.mark.parametrize("seed", range(6))
def test_jacobian_matches_central_differences(seed):
    rng = np.random.default_rng(seed)
    physics = Physics(St=float(rng.uniform(0.5, 50.0)), eps=1e-4)
    phys = physics.as_array()
    grid = scene_grid(physics.St, 5.0, resolve("fast", n_inner=8))
    n = grid.s.size
    x, v, p = _state(rng, grid, phys)
    bh = 10.0 ** rng.uniform(-4.0, 0.0)
    hist = (x + grid.s + rng.uniform(0.0, 0.1, n), x + 0.01, v + 0.01)
    y = np.concatenate([p, [x, v]])
    w, h = np.empty(n), np.empty(n)
    gap(grid.s, grid.influence, x, p, w, h)
    jac = np.empty((n + 2, n + 2))
    full = np.zeros(n - 1, dtype=bool)
    jacobian(grid.s, grid.s_face, grid.area, grid.force_weight, grid.influence, phys, bh, p,
             np.ones(n - 1), h, full, jac, np.empty((n, 3)))
    fd = _central_differences(lambda yy: _residual(grid, phys, bh, hist, yy, full), y, p)
    scale = np.max(np.abs(jac), axis=1, keepdims=True)  # each row at its own scale
    # 1e-6: above the differences' own error (~3e-8 at their step), far below
    # the 1e-2..1 relative error of a wrong or missing term (a 1 % error in one derivative fails)
    assert np.max(np.abs(jac - fd) / scale) < 1e-6


def test_compiled_linear_algebra_matches_numpy():
    rng = np.random.default_rng(1)
    for n in (3, 17, 130):
        a = rng.standard_normal((n, n)) + n * np.eye(n)
        x = rng.standard_normal(n)
        out = np.empty(n)
        matvec(a, x, out)
        # 1e-12: a sum of n ~ 130 products of O(n) terms, relative to |a||x|: a few ulps each
        np.testing.assert_allclose(out, a @ x, rtol=0, atol=1e-12 * np.abs(a).sum(1).max())
        lu = a.copy()
        piv = np.empty(n, dtype=np.int32)
        assert lu_factor(lu, piv)
        b = rng.standard_normal(n)
        sol = lu_solve(lu, piv, b.copy())
        # diagonally dominant: condition number O(1), so the solve is accurate to ~n ulps
        np.testing.assert_allclose(sol, np.linalg.solve(a, b), rtol=1e-11, atol=1e-13)
    singular = np.zeros((4, 4))
    assert not lu_factor(singular, np.empty(4, dtype=np.int32))


@pytest.mark.parametrize("seed", range(4))
def test_jfo_jacobian_with_cavitated_cells_matches_central_differences(seed):
    rng = np.random.default_rng(100 + seed)
    pi = 0.05
    physics = Physics(St=float(rng.uniform(0.5, 50.0)), eps=1e-4, Pi=pi, cavitation="jfo")
    phys = physics.as_array()
    grid = scene_grid(physics.St, 5.0, resolve("fast", n_inner=8))
    n = grid.s.size
    x, v, p = _state(rng, grid, phys)
    active = np.zeros(n - 1, dtype=bool)
    active[rng.choice(n - 1, size=(n - 1) // 3, replace=False)] = True  # inner, edge and far cells
    theta = np.ones(n - 1)
    theta[active] = rng.uniform(0.2, 0.95, active.sum())
    p[:n - 1][active] = -pi
    bh = 10.0 ** rng.uniform(-4.0, 0.0)
    hist = (x + grid.s + rng.uniform(0.0, 0.1, n), x + 0.01, v + 0.01)
    y = np.concatenate([p, [x, v]])
    y[:n - 1][active] = theta[active]
    w, h = np.empty(n), np.empty(n)
    gap(grid.s, grid.influence, x, p, w, h)
    jac = np.empty((n + 2, n + 2))
    jacobian(grid.s, grid.s_face, grid.area, grid.force_weight, grid.influence, phys, bh, p, theta,
             h, active, jac, np.empty((n, 3)))
    fd = _central_differences(lambda yy: _residual(grid, phys, bh, hist, yy, active), y, p)
    scale = np.max(np.abs(jac), axis=1, keepdims=True)
    # 1e-6: as in the classic test above (difference error ~3e-8, a wrong term fails at 1e-2)
    assert np.max(np.abs(jac - fd) / scale) < 1e-6


PIEZO_CASES = {  # the liquid's laws (model/liquid.py), each with the film's other options
    "barus": dict(beta=3.0),
    "barus-in-tension": dict(beta=3.0, viscosity_in_tension="law"),
    "roelands": dict(beta=3.0, viscosity_law="roelands", roelands_Z=0.6, roelands_PR=0.4),
    "dowson-higginson": dict(density_law="dowson-higginson", dh_c1=0.3, dh_c2=0.85),
    "barus+dowson-higginson": dict(beta=5.0, density_law="dowson-higginson"),
    "table+dh": dict(viscosity_table="0:1, 0.4:2.5, 1.1:30, 2.5:900", density_law="dowson-higginson"),
    "roelands+dh+jfo": dict(beta=2.0, viscosity_law="roelands", density_law="dowson-higginson",
                            Pi=0.05, cavitation="jfo"),
}


@pytest.mark.parametrize("case", list(PIEZO_CASES))
def test_pressure_dependent_jacobian_matches_central_differences(case):
    """The flux through the Kirchhoff difference and the content ``rho theta H``: each derivative
    against central differences, on states whose pressures reach ``beta P ~ 9-15``."""
    rng = np.random.default_rng(sorted(PIEZO_CASES).index(case))
    physics = Physics(St=float(rng.uniform(0.5, 50.0)), eps=1e-4, **PIEZO_CASES[case])
    phys = physics.as_array()
    grid = scene_grid(physics.St, 5.0, resolve("fast", n_inner=8))
    n = grid.s.size
    x, v, p = _state(rng, grid, phys)
    p *= 3.0 / max(np.max(np.abs(p)), 1e-12)  # |P| up to 3: beta P up to 15, a glassy film
    # the laws have a kink at P = 0 (compression only): keep every pressure further from it than
    # the differences' step (at most 3e-4 * 3), which would otherwise straddle the kink
    p = np.where(p < 0.0, np.minimum(p, -0.01), np.maximum(p, 0.01))
    active = np.zeros(n - 1, dtype=bool)
    theta = np.ones(n - 1)
    if physics.cavitation == "jfo":
        active[rng.choice(n - 1, size=(n - 1) // 4, replace=False)] = True
        theta[active] = rng.uniform(0.2, 0.95, active.sum())
        p[:n - 1][active] = -physics.Pi
    w, h = np.empty(n), np.empty(n)
    gap(grid.s, grid.influence, x, p, w, h)
    if np.min(h) <= 0.05:
        x += 0.1 - np.min(h)
        gap(grid.s, grid.influence, x, p, w, h)
    bh = 10.0 ** rng.uniform(-4.0, 0.0)
    hist = (x + grid.s + rng.uniform(0.0, 0.1, n), x + 0.01, v + 0.01)
    y = np.concatenate([p, [x, v]])
    y[:n - 1][active] = theta[active]
    jac = np.empty((n + 2, n + 2))
    jacobian(grid.s, grid.s_face, grid.area, grid.force_weight, grid.influence, phys, bh, p, theta,
             h, active, jac, np.empty((n, 3)))
    # the mobility exp(-beta P) makes the residual's third derivatives large (a plain difference
    # was 7e-6 off at its step, converging to the Jacobian as step^2): Richardson extrapolation
    # of two steps cancels that term
    def differences(rel_step):
        return _central_differences(lambda yy: _residual(grid, phys, bh, hist, yy, active), y, p,
                                    rel_step)

    fd = (4.0 * differences(1.5e-4) - differences(3e-4)) / 3.0
    scale = np.max(np.abs(jac), axis=1, keepdims=True)
    # 1e-6: as in the classic test above (difference error ~3e-8, a wrong term fails at 1e-2)
    assert np.max(np.abs(jac - fd) / scale) < 1e-6
