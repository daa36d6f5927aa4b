"""The drag of an isolated sphere at a finite Reynolds number: the correction ``f(Re) = C_D Re / 24``.

Pure numerics, no I/O; docs/model.md, "Outer flow: the whole trajectory". A sphere of radius
``a_s`` moving at ``u`` through a fluid at rest feels the drag ``6 pi mu a_s u f(Re)``, with the
sphere's Reynolds number on its diameter, ``Re = rho_f |u| 2 a_s / mu`` (``f = 1``: Stokes' law).
Each law is a correlation of measured steady drag, valid over a stated range of ``Re``; outside it
the law is not used (``check_reynolds`` says which law and which range).

- ``stokes``: ``f = 1`` (Stokes 1851), for ``Re <= 0.1`` (the first inertial correction, Oseen's
  ``(3/16) Re``, is 1.9 % there).
- ``schiller-naumann``: ``f = 1 + 0.15 Re^0.687`` (Schiller & Naumann 1933), for ``Re <= 800``
  (Clift, Grace & Weber 1978, table 5.2: within about 5 % of the standard drag curve there).
- ``clift-gauvin``: ``f = 1 + 0.15 Re^0.687 + 0.0175 Re / (1 + 4.25e4 Re^-1.16)``
  (Clift & Gauvin 1970), for ``Re <= 3e5`` (below the drag crisis; within about 6 %).
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ["DragLaw", "DRAG_LAWS", "correction", "check_reynolds", "reynolds"]


class DragLaw(NamedTuple):
    name: str
    re_max: float  # the law's range is 0 <= Re <= re_max
    source: str


DRAG_LAWS = {
    "stokes": DragLaw("stokes", 0.1, "Stokes (1851)"),
    "schiller-naumann": DragLaw("schiller-naumann", 800.0, "Schiller & Naumann (1933)"),
    "clift-gauvin": DragLaw("clift-gauvin", 3e5, "Clift & Gauvin (1970)"),
}


def _law(name: str) -> DragLaw:
    if name not in DRAG_LAWS:
        raise ValueError(f"drag_law = {name!r}: must be one of {', '.join(DRAG_LAWS)}")
    return DRAG_LAWS[name]


def reynolds(speed: float, radius: float, density: float, viscosity: float) -> float:
    """``Re = rho_f |u| 2 a_s / mu`` of a sphere of radius ``a_s`` moving at ``speed``."""
    return density * abs(speed) * 2.0 * radius / viscosity


def correction(name: str, re: float) -> float:
    """``f(Re) = C_D Re / 24`` of the law ``name`` (``re >= 0``; the range is not checked here)."""
    law = _law(name)
    if law.name == "stokes" or re == 0.0:
        return 1.0
    f = 1.0 + 0.15 * re ** 0.687
    if law.name == "clift-gauvin":
        f += 0.0175 * re / (1.0 + 4.25e4 * re ** -1.16)
    return f


def check_reynolds(name: str, re: float, what: str = "the sphere") -> None:
    """Refuse a Reynolds number outside the law's range, in one line naming the law and its
    range (``ValueError``)."""
    law = _law(name)
    if not (math.isfinite(re) and 0.0 <= re <= law.re_max):
        raise ValueError(f"drag_law = {law.name!r}: the Reynolds number of {what}, {re:.3g}, is "
                         f"outside its range [0, {law.re_max:g}] ({law.source}); choose a law "
                         f"valid there ({', '.join(DRAG_LAWS)})")
