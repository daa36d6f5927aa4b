"""Slow, independent reference computations used only by the tests (scipy quadrature)."""

import numpy as np
from scipy import integrate, special


def _kernel(r, y):
    """``phi(r, y) = y/(y+r) K(4ry/(r+y)^2)`` (solver/model/elasticity.py: ``kernel``) with SciPy's
    elliptic integral, independent of the solver's own (solver/special.py) and its kernel. (The
    solver's through numpy arrays cost 0.1 ms a call, and quadrature makes some 10^5: 23 s of
    test_collision's asymptotics; one value now takes special.py's scalar path.)"""
    return y / (y + r) * special.ellipkm1(((r - y) / (r + y)) ** 2)


def deformation_integral(xi):
    """``I(xi) = Int_0^inf phi(xi, eta) / (1 + eta^2/2)^2 d eta`` by adaptive quadrature,
    split at the log singularity ``eta = xi`` (docs/model.md, "Small deformation")."""
    f = lambda e: _kernel(xi, e) / (1.0 + 0.5 * e * e) ** 2  # noqa: E731
    cut = 2.0 * xi + 10.0
    near = integrate.quad(f, 0.0, cut, points=[xi] if xi > 0 else None, limit=400,
                          epsabs=1e-13, epsrel=1e-11)[0]
    far = integrate.quad(f, cut, np.inf, limit=400, epsabs=1e-13, epsrel=1e-11)[0]
    return near + far
