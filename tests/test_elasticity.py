"""Elastic operator: closed-form disk influence, Hertz contact, the deformation integral I."""

import math

import numpy as np
import pytest
from scipy import integrate

from solver.model.elasticity import disk_deflection, force_weights, influence_matrix, kernel
from solver.integration.grid import reference_grid, scaled_grid

from .reference import deformation_integral


@pytest.mark.parametrize("r, c", [(0.0, 1.0), (0.3, 1.0), (0.999, 1.0), (1.0, 1.0), (1.001, 1.0),
                                  (2.5, 1.0), (50.0, 1.0)])
def test_disk_deflection_matches_kernel_quadrature(r, c):
    # closed form (elliptic E, K) against adaptive quadrature of phi across its log singularity;
    # quad reaches ~1e-12 here, so 1e-9 leaves room only for a wrong formula
    ref = integrate.quad(lambda y: kernel(r, y), 0.0, c, points=[r] if 0 < r < c else None,
                         limit=400, epsabs=1e-13, epsrel=1e-12)[0]
    assert disk_deflection(r, c) == pytest.approx(ref, rel=1e-9)


def _hertz_error(n):
    """Max error of W inside a Hertz contact (radius 1) on a uniform grid of n cells per unit."""
    nodes = np.linspace(0.0, 3.0, 3 * n + 1)
    pressure = np.sqrt(np.clip(1.0 - nodes**2, 0.0, None))
    w = influence_matrix(nodes) @ pressure
    # Johnson (Contact Mechanics, 4.4): p0 sqrt(1 - r^2/c^2) deflects the surfaces by
    # pi p0 (2c^2 - r^2) / (4 c E*); here W = Int P phi, i.e. pi^2 P0 (2 C^2 - R^2) / (16 C)
    exact = math.pi**2 * (2.0 - nodes**2) / 16.0
    inside = nodes < 1.0
    return np.abs(w - exact)[inside].max() / exact[0]


def test_hertz_pressure_gives_parabolic_deflection():
    errors = [_hertz_error(n) for n in (25, 50, 100, 200)]
    # the square-root edge of the Hertz pressure limits piecewise-linear interpolation to
    # order 1.5 near the edge (its error ~ h^1.5); smooth pressures converge at order 2 (below)
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 2e-3
    assert np.all(orders > 1.3), orders


def test_deformation_integral_at_axis_and_far_field():
    # rigid pressure P = 1/(1+R^2/2)^2 (V = 1/3, X = 1) deflects the surfaces by W(R) = I(R)
    assert deformation_integral(0.0) == pytest.approx(math.pi**2 / (4 * math.sqrt(2)), rel=1e-10)
    # I ~ pi/(2 xi): the next term is O(ln(xi)/xi^2) (the load's second moment diverges
    # logarithmically), 1.4e-3 at xi = 50 and 4e-4 at xi = 100
    far = [deformation_integral(x) * 2 * x / math.pi - 1 for x in (50.0, 100.0)]
    assert 0 < far[1] < far[0] < 2e-3


@pytest.mark.parametrize("width", [None, 0.25])
def test_influence_matrix_second_order_for_smooth_pressure(width):
    # the discrete operator applied to the rigid pressure against I(R) by quadrature, at
    # R = 0 and the node nearest 0.5 (a node of every refined grid); the design order is 2
    base = reference_grid(8, 0.3, 0.25, 1.2, 30.0, 0.3).radius
    errors = []
    for k in (1, 2, 4):  # every interval split into k: all cells, inner and outer, shrink
        nodes = np.concatenate([base[:-1, None] + np.diff(base)[:, None] * np.arange(k) / k,
                                [[base[-1]]]], axis=None)
        pressure = 1.0 / (1.0 + 0.5 * nodes**2) ** 2
        w = influence_matrix(nodes, width) @ pressure
        at = [0, int(np.argmin(np.abs(nodes - 0.5)))]
        errors.append(max(abs(w[i] - deformation_integral(nodes[i])) for i in at))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.7), (errors, orders)


def test_scaled_grid_matrix_is_exactly_rescaled():
    # D(lam R, lam C) = lam D(R, C): the cached reference matrix serves every scene
    ref = reference_grid(16, 0.3, 0.25, 1.2, 30.0, 0.3)
    lam = 3.7
    direct = influence_matrix(ref.radius * lam, 0.25 * lam**2)
    # entries are differences of disk deflections O(R_L): rounding leaves ~1e-15 |K|max absolute
    np.testing.assert_allclose(scaled_grid(ref, lam).influence, direct, rtol=1e-12,
                               atol=1e-13 * np.abs(direct).max())


def test_force_weights_integrate_the_represented_pressure():
    # rigid film P = 3V/H^2 gives Int P R dR = 3V/X exactly; on the shaped basis with the
    # same width the only error is the tail (R_L/R)^4 vs 1/(X+R^2/2)^2: O(X/R_L^2)
    nodes = reference_grid(16, 0.3, 0.25, 1.2, 30.0, 0.3).radius
    x = 0.25
    force = force_weights(nodes, 0.25) @ (3.0 / (x + 0.5 * nodes**2) ** 2)
    assert force == pytest.approx(3.0 / x, rel=4 * x / nodes[-1] ** 2)
