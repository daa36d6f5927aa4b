"""The rigid phases' records: the state a rigid approach hands over, and the time series of a
rigid path (docs/model.md, "Rigid solution"). solver/collision.py and the pieces' own rigid
phases (solver/pieces.py) write their series through these, so every phase has the same
columns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import rigid
from .observables import SERIES

__all__ = ["RigidHead", "ReleaseFilm", "KEPT", "rigid_path", "rigid_block"]

KEPT = tuple(c for c in SERIES if c.kept)  # the series columns a result keeps


@dataclass
class RigidHead:
    """The rigid approach from the start ``(x0, V = 1, T = 0)`` until the coupled phase takes
    over, or until rest (``rests``: the scene is rigid throughout; ``v = 0``, ``t = inf``, ``x`` the
    rest separation)."""

    x: float
    v: float
    t: float
    rests: bool
    block: dict  # its time series (phase 0), without the end state when a coupled phase follows
    peaks: dict  # rigid.approach_peaks keys, and x_p_max (the gap at the largest pressure)
    pressure: object  # P(s) of the film at the end state, the coupled phase's start


@dataclass(frozen=True)
class ReleaseFilm:
    """The film where the coupled phase ends (the release state), as a departure that remembers
    it reads it: the cells' outer faces in ``s`` (grid.py) and their liquid fractions ``theta``
    (1 in full cells; a JFO cavity's below 1, model/refill.py)."""

    s_face: np.ndarray
    theta: np.ndarray


def rigid_path(x_from, v_from, t_from, stokes, x):
    """Time and speed on the classic rigid path from ``(x_from, v_from, t_from)`` at gaps ``x``."""
    v = rigid.velocity(x, x_from, v_from, stokes)
    t = t_from + rigid.elapsed_time(x, x_from, v_from, stokes)
    return t, v


def rigid_block(t, x, v, tau_per_t, phase, dissipated):
    """Time series of a rigid phase (docs/model.md, "Rigid solution"): ``P = 3V/H^2``,
    so the force is ``V/X`` in our unit, the axis pressure ``3V/X^2`` the extreme one (the far
    field tends to 0), ``W(0)`` the small-deformation estimate ``3 I0 V X^-1.5``."""
    n = len(t)
    p_axis = 3.0 * v / (x * x)
    rigid_film = {
        "T": t, "X": x, "V": v, "F": v / x, "W0": 3.0 * v * x**-1.5 * rigid.I0, "H_min": x,
        "E_k": v * v, "dissipated": dissipated, "P_max": np.maximum(p_axis, 0.0),
        "P_min": np.minimum(p_axis, 0.0),
    }
    # every other column (strain, cavity, void, compression...) is 0 on a rigid path
    block = {c.name: rigid_film.get(c.name, np.zeros(n)) for c in KEPT}
    block.update(tau=t * tau_per_t, phase=np.full(n, phase, dtype=np.int8))
    return block
