"""The film's own state beyond the unknowns ``y``, as named records, one per piece of physics that
keeps state (``array_record``: a numba StructRef of arrays, passed as one reference however many
fields it has, loaded from numba's cache).

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

import sys
from typing import NamedTuple

import numba
import numpy as np
from numba.core import types
from numba.experimental import structref

from .._jit import copy_into, filled, jit


def array_record(name: str, fields: tuple, doc: str, module: str = __name__):
    """A record of arrays that compiled code passes as one reference: a numba ``StructRef``
    (fields in ``fields``' order; its proxy constructs it from Python and from compiled code,
    and reads its fields by name; ``_fields`` lists them). Why not a NamedTuple: a call counts a
    reference to each of a NamedTuple's arrays, and with the film's state, the work arrays and
    the Newton matrix as NamedTuples (26, 12 and 14 arrays, passed to the Newton iteration's
    functions) the classic film took 1.40x the CPU time of the packed arrays (standard preset,
    15 scenes St 2-300 x eps 1e-2-1e-6, alternated, 7 rounds; 0.98x as StructRefs). StructRefs
    load from numba's cache as NamedTuples do. The type is registered as ``<name>Type`` in
    ``module``, where the cache finds it by name."""
    type_class = type(name + "Type", (types.StructRef,), {
        "__module__": module,
        "preprocess_fields": lambda self, fs: tuple((n, types.unliteral(t)) for n, t in fs)})
    structref.register(type_class)
    proxy = type(name, (structref.StructRefProxy,), {"__module__": module, "__doc__": doc,
                                                     "_fields": tuple(fields)})
    structref.define_proxy(proxy, type_class, list(fields))
    for field in fields:  # read from Python (tests, inspection): a compiled getter per field
        setattr(proxy, field, property(_getter(field)))
    setattr(sys.modules[module], type_class.__name__, type_class)
    return proxy


def _getter(field: str):
    """A function that returns ``record.<field>`` of a record from Python (compiled on first use,
    not cached: Python-side only)."""
    namespace = {}
    exec(f"def get(record):\n    return record.{field}\n", namespace)
    compiled = numba.njit(namespace["get"])
    return lambda record: compiled(record)


# The fields of ``Cavity``, a floor's state, one entry per cell unless said otherwise:
# ``active``, ``active_lu``, ``active0``, ``active_base``, ``active_was`` (bool): the cavitated
#   cells of the current iterate, of the Jacobian the loop solves with, of the last accepted
#   state, of the Jacobian it factorised (which low-rank updates correct to ``active_lu``), and
#   of the iterate before its set was last decided (model/cavity_step.py: ``decide``);
# ``theta``, ``theta0``: the liquid fraction of the iterate and of the last accepted state (1 in
#   full cells, and in every cell but a JFO cavity's); ``dtheta``: its
#   Newton update; ``h_onset``: the gap where each cell cavitated (the void volume); ``q_prev``:
#   the face fluxes of the last accepted state;
# ``worked``, ``p_abs``, ``p_seen``, ``r_edge`` (1,): the work against the floor so far, the
#   absolute part of the pressure error scale (``new_film``), the largest pressure seen, the
#   accepted state's cavity radius;
# ``since_switch`` (int): the accepted steps since each cell last cavitated or refilled (0: in
#   the last one; ``NEVER_SWITCHED`` at the start).
NEVER_SWITCHED = 2**40  # beyond any history: a cell that never switched

Cavity = array_record("Cavity", (
    "active", "active_lu", "active0", "active_base", "active_was", "theta", "theta0", "dtheta",
    "h_onset", "q_prev", "worked", "p_abs", "p_seen", "r_edge", "since_switch"),
    "A floor's state (model/state.py).")

# The fields of ``Contact``, rough surfaces' state, one entry per node unless said otherwise:
# ``pa``, ``p_film``, ``slope``: the contact pressure p_a, the film pressure P and the contact
#   law's slope dp_a/dH at the last gap computed;
# ``t_set``, ``w_set``, ``h_set``: the load T_set, the permanent set (1 - c) K T_set and the gap
#   H_set where the solids began to unload;
# ``p_scale``: the scale step.film_change measures the film pressure by;
# ``load_scale``, ``touched``, ``solid_lost`` (1,): the solids' unloading scale c (1 while they
#   load, e_dry^2 once they unload), 1 once the asperities carried load on approach, the energy
#   lost in the solids;
# work arrays, so that a Newton iteration allocates nothing: ``held`` (N, bool) the nodes whose
# slot is not their load (contact_step._held); ``load`` (N) the elastic load of every node and
# ``touching`` (N, int) the held nodes that touch (contact.contact_gap).
Contact = array_record("Contact", (
    "pa", "p_film", "slope", "t_set", "w_set", "h_set", "p_scale",
    "load_scale", "touched", "solid_lost", "held", "load", "touching"),
    "Rough surfaces' state (model/state.py).")


class Film(NamedTuple):
    """The film's state: every piece's record."""

    cavity: Cavity
    contact: Contact


class Step(NamedTuple):
    """A step attempt's implicit coefficient ``bh`` (BDF coefficient times the step) and the
    history of the cells' content, ``X`` and ``V`` (``sum_j a_j u_j`` over the accepted states,
    integration/stepper.py: ``_coefficients``)."""

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
def new_film(q):
    """The film's state at the start (``q`` the face fluxes of the initial state): no cavity,
    full cells, solids loading."""
    cells_n = q.size
    n = cells_n + 1
    # Absolute part of the pressure error scale. With a floor the film carries almost no
    # pressure once it has cavitated (|P| ~ Pi over the whole rebound), and a scale relative to
    # the instantaneous pressure made the steps collapse to 1e-9 where the last full cells at the
    # axis drained: pressures far below the collision's peak move neither the gap nor the force
    # (both in the norm on their own), so they count as absolute below a fraction of the largest
    # pressure seen so far, from the film's first cavity on (step.record). The classic film (and
    # a film that never cavitates) keeps its instantaneous scale.
    q_start = np.empty(cells_n)
    copy_into(q_start, q)
    cavity = Cavity(filled(cells_n, False), filled(cells_n, False), filled(cells_n, False),
                    filled(cells_n, False), filled(cells_n, False), filled(cells_n, 1.0),
                    filled(cells_n, 1.0), filled(cells_n, 0.0), filled(cells_n, 0.0), q_start,
                    filled(1, 0.0), filled(1, 1e-12), filled(1, 0.0), filled(1, 0.0),
                    filled(cells_n, NEVER_SWITCHED))
    contact = Contact(filled(n, 0.0), filled(n, 0.0), filled(n, 0.0), filled(n, 0.0),
                      filled(n, 0.0), filled(n, 0.0), filled(n, 0.0), filled(1, 1.0),
                      filled(1, 0.0), filled(1, 0.0), filled(n, False), filled(n, 0.0),
                      filled(n, 0))
    return Film(cavity, contact)
