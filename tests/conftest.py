"""Shared test set-up: Agg backend, figures closed after each test.

There is no "slow" tier: every test runs in ``make test`` (a couple of minutes on 2 cores). The
long convergence and accuracy studies are benchmarks (``make bench``, benchmarks/accuracy.md);
tests/test_convergence.py checks the observed orders on a short refinement ladder by default.
"""

import os

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("NUMBA_BOUNDSCHECK", "0")


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
