"""Slow, independent reference computations used only by the tests (scipy quadrature)."""

import numpy as np
from scipy import integrate

from solver.model.elasticity import kernel


def deformation_integral(xi):
    """``I(xi) = Int_0^inf phi(xi, eta) / (1 + eta^2/2)^2 d eta`` by adaptive quadrature,
    split at the log singularity ``eta = xi`` (docs/model.md, "Small deformation")."""
    f = lambda e: kernel(xi, e) / (1.0 + 0.5 * e * e) ** 2  # noqa: E731
    cut = 2.0 * xi + 10.0
    near = integrate.quad(f, 0.0, cut, points=[xi] if xi > 0 else None, limit=400,
                          epsabs=1e-13, epsrel=1e-11)[0]
    far = integrate.quad(f, cut, np.inf, limit=400, epsabs=1e-13, epsrel=1e-11)[0]
    return near + far
