"""The film model's residual, Jacobian and linear algebra against independent references.

The Jacobian is assembled from each term's partial derivatives (solver/model/film.py); a wrong
derivative would only show up as more Newton iterations, so it is checked here against central
differences of the residual on random admissible states (positive gaps, pressures of both signs,
a step coefficient from small to large). One test covers every film the physics can build,
through the contract the time loop uses (solver/model/step.py: ``step_residual`` with the active
set held, ``step_jacobian``): each term, the Reynolds constraint rows and the JFO fraction slots.
The compiled LAPACK/BLAS calls are checked against numpy.
"""

import numpy as np
import pytest

from solver import Physics
from solver.collision import scene_grid
from solver.integration.linalg import lu_factor, lu_solve, lu_solve_rows, matmul, matvec
from solver.model import cavity_step, step
from solver.model.film import gap
from solver.model.state import Film, Step
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


def _residual(grid, phys, bh, hist, y, film):
    """The step's residual at the unknowns ``y`` with the active set of ``film`` held; a JFO
    cavity's slot ``y[i]`` is its fraction ``theta_i`` (``P_i`` fixed at ``-Pi`` there), a rough
    film's other slots its total loads; the gap (with a rough film's contact) as the loop
    computes it, ``step.surface_gap``."""
    n = grid.s.size
    yy = y.copy()
    film = _copy(film)
    if cavity_step.held(phys):
        active = film.cavity.active
        film.cavity.theta[active] = y[:n - 1][active]
        yy[:n - 1][active] = -phys[PI]
    w, h, q, res = np.empty(n), np.empty(n), np.empty(n - 1), np.empty(n + 2)
    h[:] = np.nan  # no warm start: the contact gap must not depend on it
    nodes = grid.nodes()
    step.surface_gap(nodes, phys, yy, film, w, h)
    step.step_residual(nodes, phys, Step(bh, *hist), yy, film, False, q, w, h, res)
    return res


def _copy(film):
    """A copy of every array of the film's state (each piece's record, model/state.py)."""
    return Film(*(type(part)(*(getattr(part, f).copy() for f in part._fields))
                  for part in film))


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


FILMS = {  # every film the physics can build: the classic one, each floor, each liquid law
    "classic": {},
    "reynolds": dict(Pi=0.05, cavitation="reynolds"),
    "jfo": dict(Pi=0.05, cavitation="jfo"),
    "barus": dict(beta=3.0),
    "barus-in-tension": dict(beta=3.0, viscosity_in_tension="law"),
    "roelands": dict(beta=3.0, viscosity_law="roelands", roelands_Z=0.6, roelands_PR=0.4),
    "dowson-higginson": dict(density_law="dowson-higginson", dh_c1=0.3, dh_c2=0.85),
    "barus+dowson-higginson": dict(beta=5.0, density_law="dowson-higginson"),
    "table+dh": dict(viscosity_table="0:1, 0.4:2.5, 1.1:30, 2.5:900", density_law="dowson-higginson"),
    "roelands+dh+jfo": dict(beta=2.0, viscosity_law="roelands", density_law="dowson-higginson",
                            Pi=0.05, cavitation="jfo"),
    "barus+reynolds": dict(beta=2.0, Pi=0.05, cavitation="reynolds"),
    # rough films: the roughness is set from the state so that about a third of the nodes touch
    "rough": dict(roughness=1.0, asperity_stiffness=5.0),
    "rough-unloading": dict(roughness=1.0, asperity_stiffness=5.0, e_dry=0.8),
    "rough+jfo": dict(roughness=1.0, asperity_stiffness=5.0, Pi=0.05, cavitation="jfo"),
    "rough+barus+reynolds": dict(roughness=1.0, asperity_stiffness=20.0, beta=2.0, Pi=0.05,
                                 cavitation="reynolds"),
    "slip": dict(slip_length=0.7),
    "slip+barus+dh": dict(slip_length=0.7, beta=2.0, density_law="dowson-higginson"),
    "slip+rough": dict(slip_length=0.7, roughness=1.0, asperity_stiffness=5.0),
}


@pytest.mark.parametrize("seed", range(2))
@pytest.mark.parametrize("film", list(FILMS))
def test_every_films_jacobian_matches_central_differences(film, seed):
    """Each derivative of the step's residual against central differences, on states whose
    pressures reach ``beta P ~ 9-15`` (a glassy film) and, with a floor, a third of the cells
    cavitated: inner, edge and far cells."""
    rng = np.random.default_rng(17 * sorted(FILMS).index(film) + seed)
    physics = Physics(St=float(rng.uniform(0.5, 50.0)), eps=1e-4, **FILMS[film])
    phys = physics.as_array()
    grid = scene_grid(physics.St, 5.0, resolve("fast", n_inner=8))
    n = grid.s.size
    x, v, p = _state(rng, grid, phys)
    p *= 3.0 / max(np.max(np.abs(p)), 1e-12)  # |P| up to 3: beta P up to 15
    # the laws have a kink at P = 0 (compression only): keep every pressure further from it than
    # the differences' step (at most 3e-4 * 3), which would otherwise straddle the kink
    p = np.where(p < 0.0, np.minimum(p, -0.01), np.maximum(p, 0.01))
    y = np.concatenate([p, [x, v]])
    film = step.new_film(np.zeros(n - 1))
    cavity, contact = film.cavity, film.contact
    if step.has_active_set(phys):
        active = np.zeros(n - 1, dtype=bool)
        active[rng.choice(n - 1, size=(n - 1) // 3, replace=False)] = True
        cavity.active[:] = active
        if physics.cavitation == "jfo":
            cavity.theta[active] = rng.uniform(0.2, 0.95, active.sum())
            p[:n - 1][active] = -physics.Pi
            y[:n - 1][active] = cavity.theta[active]
    w, h = np.empty(n), np.empty(n)
    gap(grid.s, grid.influence, x, p, w, h)
    if np.min(h) <= 0.05:
        x += 0.1 - np.min(h)
        y[n] = x
        gap(grid.s, grid.influence, x, p, w, h)
    yp = y.copy()
    yp[:n] = p  # the Jacobian reads the pressures (a JFO slot's P is the floor)
    if physics.roughness:
        if physics.e_dry < 1.0:  # unloading: c = e_dry^2 through a set load
            contact.load_scale[0] = physics.e_dry ** 2
            contact.t_set[:] = np.abs(p) * rng.uniform(0.5, 1.5, n)
            contact.h_set[:] = h * rng.uniform(0.97, 1.0, n)
        # the slots of a rough film are its total loads; a roughness from the state's gaps puts
        # a third to a half of the nodes in contact (the law is smooth at first touch, so the
        # differences may straddle it)
        for _ in range(50):
            physics = physics.replace(roughness=float(np.quantile(h, rng.uniform(0.3, 0.5))))
            phys = physics.as_array()
            step.surface_gap(grid.nodes(), phys, yp, film, w, h)
            if np.count_nonzero(contact.pa) >= 2:
                break
        else:
            raise AssertionError("no roughness found that puts two nodes in contact")
    bh = 10.0 ** rng.uniform(-4.0, 0.0)
    hist = (x + grid.s + rng.uniform(0.0, 0.1, n), x + 0.01, v + 0.01)
    jac = np.empty((n + 2, n + 2))
    step.step_jacobian(grid.nodes(), phys, bh, yp, h, film, jac, np.empty((n, 3)))
    assert step.settled(film)  # the Jacobian records the set it was built with

    # the mobility exp(-beta P) makes the residual's third derivatives large (a plain difference
    # was 7e-6 off at its step, converging to the Jacobian as step^2): Richardson extrapolation
    # of two steps cancels that term
    def differences(rel_step):
        return _central_differences(
            lambda yy: _residual(grid, phys, bh, hist, yy, film), y, p, rel_step)

    fd = (4.0 * differences(1.5e-4) - differences(3e-4)) / 3.0
    scale = np.max(np.abs(jac), axis=1, keepdims=True)  # each row at its own scale
    # 1e-6: above the differences' own error (~3e-8 at their step), far below the 1e-2..1
    # relative error of a wrong or missing term (a 1 % error in one derivative fails)
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
        rows = rng.standard_normal((5, n))  # several right-hand sides, one per row, in one call
        sols = lu_solve_rows(lu, piv, rows.copy())
        np.testing.assert_allclose(sols, np.linalg.solve(a, rows.T).T, rtol=1e-11, atol=1e-13)
    singular = np.zeros((4, 4))
    assert not lu_factor(singular, np.empty(4, dtype=np.int32))


def test_matmul_is_numbas_product_to_the_bit():
    """A rough film's contact multiplies two matrices with ``linalg.matmul`` (BLAS dgemm called as
    numba's ``a @ b`` calls it) instead of numba's product: the same sums, so every number is
    the same, for the shapes the contact makes (N rows, a few held cells, N + 1 columns) and
    square ones (with one row or column numba takes a matrix-vector product instead)."""
    import numba

    product = numba.njit(lambda a, b: a @ b)
    rng = np.random.default_rng(5)
    for rows, inner, cols in ((5, 1, 6), (3, 2, 4), (100, 37, 101), (130, 130, 131)):
        a, b = rng.standard_normal((rows, inner)), rng.standard_normal((inner, cols))
        out = np.empty((rows, cols))
        matmul(a, b, out)
        assert np.array_equal(out, product(a, b))
    # BLAS would read and write past the arrays: a wrong shape or layout is refused (a review
    # wrote past `out` and the process aborted at exit)
    a, b = rng.standard_normal((6, 8)), rng.standard_normal((8, 5))
    for args in ((a, b, np.empty((2, 2))), (a, b[:4], np.empty((6, 5))),
                 (a[::2], b, np.empty((3, 5))), (a, np.asfortranarray(b), np.empty((6, 5)))):
        with pytest.raises(ValueError, match="shapes or layouts"):
            matmul(*args)


def test_filled_allocates_what_np_full_does_in_compiled_code():
    """``filled`` (solver/_jit.py) replaces ``np.zeros``, ``np.ones`` and ``np.full`` in compiled
    code: the dtype follows the value (float64, int64, bool), for an int or a tuple shape."""
    import numba

    from solver._jit import filled

    made = numba.njit(lambda n: (filled(n, 0.0), filled((n, 2), np.nan), filled(n, 2**40),
                                 filled(n, True), filled(1, 1e-12)))(3)
    expected = (np.zeros(3), np.full((3, 2), np.nan), np.full(3, 2**40), np.ones(3, bool),
                np.array([1e-12]))
    for got, want in zip(made, expected):
        assert got.dtype == want.dtype and got.shape == want.shape
        np.testing.assert_array_equal(got, want)


def test_lowrank_update_solves_the_matrix_with_replaced_rows_and_columns():
    """After a change of the active set the loop solves with the factorised matrix whose rows
    and columns of the changed slots are a fresh Jacobian's (linalg.lowrank_prepare): against
    numpy's solve of that matrix, built explicitly; and with no slot changed, the factorised
    matrix itself."""
    from solver.integration.linalg import MAX_SLOTS, lowrank_prepare, lowrank_solve

    rng = np.random.default_rng(3)
    n = 40
    a = rng.standard_normal((n, n)) + n * np.eye(n)
    fresh = a + 0.5 * rng.standard_normal((n, n))
    lu, piv = a.copy(), np.empty(n, dtype=np.int32)
    assert lu_factor(lu, piv)
    u, v, z = (np.empty((2 * MAX_SLOTS, n)) for _ in range(3))
    cap, t = np.empty(4 * MAX_SLOTS**2), np.empty(2 * MAX_SLOTS)
    cpiv = np.empty(2 * MAX_SLOTS, np.int32)
    b = rng.standard_normal(n)
    for changed in ([0], [3, 17, 39], list(range(0, 2 * MAX_SLOTS, 2))):
        slots = np.zeros(MAX_SLOTS, dtype=np.int64)
        slots[:len(changed)] = changed
        target = a.copy()
        target[changed, :] = fresh[changed, :]
        target[:, changed] = fresh[:, changed]
        assert lowrank_prepare(lu, piv, a, fresh, slots, len(changed), u, v, z, cap, cpiv)
        x = lowrank_solve(lu, piv, len(changed), v, z, cap, cpiv, b.copy(), t)
        # a well-conditioned matrix (diagonally dominant): the solve is accurate to ~n ulps
        np.testing.assert_allclose(x, np.linalg.solve(target, b), rtol=1e-11, atol=1e-13)
    x = lowrank_solve(lu, piv, 0, v, z, cap, cpiv, b.copy(), t)
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-11, atol=1e-13)
