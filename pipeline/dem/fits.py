"""Fitted restitution laws for DEM codes, on a given Stokes-number convention.

- ``exponential``: ``e = e_max exp(-C / St)`` (Legendre et al. 2006's form; LIGGGHTS' and the
  OpenFOAM patch model's law), fitted to the rebounding collisions; a separate sticking threshold
  ``St_stick`` (the last computed St that sticks) goes with it, since the law itself never reaches 0.
- ``threshold``: ``e = e_max (1 - St_c / St)`` for ``St > St_c``, 0 below (the rigid lubrication
  form ``e = 1 - ln(x_ref/x_c)/St``; linear in ``1/St``).

Both take ``e_cap``, the largest ``e_max`` allowed: the pair's dry restitution ``e_dry`` (no
law may promise more than the solids give back dry; 1 without one).

Each fit carries its error (the largest absolute difference from the table it was fitted to) and
the St range of that table's rebounding rows: the range the law is stated to hold for.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy import optimize

__all__ = ["Fit", "fit_exponential", "fit_threshold", "LAWS"]


@dataclass(frozen=True)
class Fit:
    law: str  # "exponential" or "threshold"
    convention: str  # Stokes-number convention of st_* and C / St_c (conventions.CONVENTIONS)
    e_max: float
    c: float  # C of the exponential law, St_c of the threshold law
    st_min: float  # range of the rebounding rows fitted
    st_max: float
    st_stick: float  # largest computed St that sticks below st_min (nan: none computed)
    max_error: float  # max |law - e| over the rebounding rows (absolute, in e)
    n: int

    def __call__(self, st):
        st = np.asarray(st, dtype=float)
        if self.law == "exponential":
            return self.e_max * np.exp(-self.c / st)
        return np.where(st > self.c, self.e_max * (1.0 - self.c / st), 0.0)

    def as_dict(self) -> dict:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in asdict(self).items()}


def _split(st, e):
    st, e = np.asarray(st, float), np.asarray(e, float)
    ok = np.isfinite(st) & np.isfinite(e)
    st, e = st[ok], e[ok]
    order = np.argsort(st)
    st, e = st[order], e[order]
    up = e > 0.0
    if up.sum() < 3:
        raise ValueError(f"a fit needs at least 3 rebounding collisions (e > 0); got {up.sum()}")
    first = np.argmax(up)
    stuck = st[:first][e[:first] == 0.0]
    return st[up], e[up], float(stuck.max()) if stuck.size else math.nan


def fit_exponential(st, e, convention="St", e_cap=1.0) -> Fit:
    """``e = e_max exp(-C/St)``: a start from the line ``ln e = ln e_max - C/St``, then least squares
    in ``e`` (the log fit alone would weight the near-sticking rows far too much)."""
    s, y, st_stick = _split(st, e)
    slope, icpt = np.polyfit(1.0 / s, np.log(y), 1)
    # e_max <= e_cap <= 1: the codes refuse a restitution above 1, and none above e_dry is real
    p0 = (min(math.exp(icpt), e_cap * (1.0 - 1e-9)), max(-slope, 1e-9))
    p, _ = optimize.curve_fit(lambda x, a, c: a * np.exp(-c / x), s, y, p0=p0,
                              bounds=([1e-9, 0.0], [e_cap, np.inf]))
    fit = Fit("exponential", convention, float(p[0]), float(p[1]), float(s[0]), float(s[-1]),
              st_stick, 0.0, int(s.size))
    return _with_error(fit, s, y)


def fit_threshold(st, e, convention="St", e_cap=1.0) -> Fit:
    """``e = e_max (1 - St_c/St)``: linear least squares of ``e = A + B/St`` (``e_max = A``,
    ``St_c = -B/A``) over the rebounding rows; where ``A`` exceeds ``e_cap``, ``A = e_cap`` and
    ``B`` by least squares alone (the constrained minimum: the cost is a convex quadratic)."""
    s, y, st_stick = _split(st, e)
    b, a = np.polyfit(1.0 / s, y, 1)
    if a > e_cap:
        a = e_cap
        b = float(np.sum((y - a) / s) / np.sum(1.0 / s**2))
    fit = Fit("threshold", convention, float(a), float(-b / a), float(s[0]), float(s[-1]),
              st_stick, 0.0, int(s.size))
    return _with_error(fit, s, y)


def _with_error(fit, s, y) -> Fit:
    err = float(np.max(np.abs(fit(s) - y)))
    return Fit(**{**asdict(fit), "max_error": err})


LAWS = {"exponential": fit_exponential, "threshold": fit_threshold}
