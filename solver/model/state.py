"""The film's own state beyond the unknowns ``y``, as named records (NamedTuples of arrays: numba
compiles each once and loads it from its cache), one per piece of physics that keeps state.

The time loop (integration/stepper.py) creates the state once per coupled phase (``new_film``),
carries it and hands it to the film model (model/step.py), which alone reads and writes it.
A value that changes in place but is one number (the work against the floor, the unloading
scale) is a one-entry array, so the records themselves never change. Dimensionless as in
model/film.py; N is the number of nodes, N-1 of cells.

- ``Cavity`` (a film with a pressure floor, docs/model.md "Cavitation"; allocated for every
  film, the classic one leaves it as ``new_film`` made it): the active sets and liquid
  fractions of the iterate and the accepted states, the void's history, the error scale.
- ``Contact`` (rough surfaces, docs/model.md "Surface roughness"; model/contact.py): the contact
  and film pressures of the last gap computed, the unloading's set state, the film pressure's
  history.
- ``Film``: both.
- ``Step``: what a step attempt's residual needs beyond the iterate (the implicit coefficient
  and the BDF history combinations).
- ``Coupling``: how the gap and the force follow the slots, which the Jacobian chains through.
"""

from typing import NamedTuple

import numpy as np

from .._jit import jit


class Cavity(NamedTuple):
    """A floor's state, one entry per cell unless said otherwise."""

    active: np.ndarray  # bool: the cavitated cells of the current iterate
    active_lu: np.ndarray  # bool: ... of the Jacobian the loop solves with
    active0: np.ndarray  # bool: ... of the last accepted state
    active_base: np.ndarray  # bool: ... of the Jacobian it factorised (low-rank updates
    #                          correct it to active_lu)
    theta: np.ndarray  # the liquid fraction of the iterate (1 in full cells, and in every
    #                    cell but a JFO cavity's)
    theta0: np.ndarray  # ... of the last accepted state
    theta1: np.ndarray  # ... of the one before
    dtheta: np.ndarray  # the fraction's Newton update
    h_onset: np.ndarray  # the gap where each cell cavitated (the void volume)
    q_prev: np.ndarray  # the face fluxes of the last accepted state
    worked: np.ndarray  # (1,) the work against the floor so far
    p_abs: np.ndarray  # (1,) the absolute part of the pressure error scale (new_film)
    p_seen: np.ndarray  # (1,) the largest pressure seen
    r_edge: np.ndarray  # (1,) the accepted state's cavity radius


class Contact(NamedTuple):
    """Rough surfaces' state, one entry per node unless said otherwise."""

    pa: np.ndarray  # the contact pressure p_a of the last gap computed
    p_film: np.ndarray  # the film pressure P of the last gap computed
    slope: np.ndarray  # the contact law's slope dp_a/dH at the last gap computed
    t_set: np.ndarray  # the load T_set where the solids began to unload
    w_set: np.ndarray  # the permanent set (1 - c) K T_set
    h_set: np.ndarray  # the gap H_set where the solids began to unload
    p_acc0: np.ndarray  # the film pressure of the last accepted state
    p_acc1: np.ndarray  # ... of the one before
    p_scale: np.ndarray  # the scale step.film_change measures the film pressure by
    load_scale: np.ndarray  # (1,) the solids' unloading scale c: 1 while they load, e_dry^2
    #                         once they unload
    touched: np.ndarray  # (1,) 1 once the asperities carried load on approach
    solid_lost: np.ndarray  # (1,) the energy lost in the solids


class Film(NamedTuple):
    """The film's state: every piece's record."""

    cavity: Cavity
    contact: Contact


class Step(NamedTuple):
    """A step attempt's implicit coefficient ``bh`` (BDF coefficient times the step) and the
    history of the cells' content, ``X`` and ``V`` (``a1 u_0 + a2 u_1``, ``stepper._bdf2``)."""

    bh: float
    c_hist: np.ndarray  # (N,) the cells' content and the boundary node's gap
    x_hist: float
    v_hist: float


class Coupling(NamedTuple):
    """How the gap and the force on the spheres follow the slots ``y`` and ``X`` (film.jacobian):
    ``K``, ones, ``weight`` and 0 for a film whose slots are its pressures; a rough film's
    (model/contact.py) where its contact couples them."""

    dh_dy: np.ndarray  # (N, N) dH/dy
    dh_dx: np.ndarray  # (N,) dH/dX
    force_dp: np.ndarray  # (N,) d force / dy
    force_dx: float  # d force / dX
    dp_dh: np.ndarray  # (N,) dP/dH where the slot is not the pressure (empty: y = P)


@jit
def _one(value):
    out = np.empty(1)
    out[0] = value
    return out


@jit
def new_film(q):
    """The film's state at the start (``q`` the face fluxes of the initial state): no cavity,
    full cells, solids loading."""
    cells_n = q.size
    n = cells_n + 1
    theta = np.ones(cells_n)
    # Absolute part of the pressure error scale. With a floor the film carries almost no
    # pressure once it has cavitated (|P| ~ Pi over the whole rebound), and a scale relative to
    # the instantaneous pressure made the steps collapse to 1e-9 where the last full cells at the
    # axis drained: pressures far below the collision's peak move neither the gap nor the force
    # (both in the norm on their own), so they count as absolute below a fraction of the largest
    # pressure seen so far, from the film's first cavity on (step.record). The classic film (and
    # a film that never cavitates) keeps its instantaneous scale.
    cavity = Cavity(np.zeros(cells_n, dtype=np.bool_), np.zeros(cells_n, dtype=np.bool_),
                    np.zeros(cells_n, dtype=np.bool_), np.zeros(cells_n, dtype=np.bool_),
                    theta, theta.copy(), theta.copy(), np.zeros(cells_n), np.zeros(cells_n),
                    q.copy(), _one(0.0), _one(1e-12), _one(0.0), _one(0.0))
    contact = Contact(np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n),
                      np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), _one(1.0), _one(0.0),
                      _one(0.0))
    return Film(cavity, contact)
