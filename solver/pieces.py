"""The pieces of physics that change a collision's phases, each declared once.

A collision is a rigid approach, a coupled phase and a rigid departure (solver/collision.py), and
each analytic shortcut is exact only for some physics (solver/shortcuts.py). A ``Piece`` says what
it does to them: where the classic rigid approach stops being exact, whether it has a rigid
approach or a departure of its own and for which physics that is exact, whether the coupled phase
must run on until its film is full again, how wide the grid's inner region and how far the grid
must reach, when the spheres end the coupled phase at rest, and the observables it reads from the
series. ``shortcuts.plan`` and collision.py iterate over ``PIECES`` and name none of them.

The rest of a piece lives where its kind of code lives: its groups and off values in
solver/physics.py (``GROUPS``), its laws and film terms in model/, its scene switch in
pipeline/scenes/pieces.py. docs/model.md, "How to add a term", lists the steps.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .model import cavitation, contact, liquid, piezoviscous, refill, rigid, slip
from .rigid_phases import RigidHead, rigid_block

__all__ = ["Piece", "PIECES", "RUN_ON", "CAVITY_REACH", "WIDEST_CAVITY", "SLIP_REACH",
           "cavity_reach"]

# What a piece's ``depart`` answers where its departure does not hold from the release state
# and the coupled phase must run on until the film is full again (``events.RELAXED_FULL``;
# shortcuts.run_on): a JFO cavity that would grow again, or spheres that stop with it open
# (the time loop asks the same where the phase would end and runs on itself: a safety net)
RUN_ON = "run on"


def _none(*_):
    return None


def _false(*_):
    return False


def _zero(*_):
    return 0.0


@dataclass(frozen=True)
class Piece:
    """One piece of physics as the collision's phases see it (module docstring). Every hook takes
    the scene's ``solver.Physics`` first; a piece that is off for it answers as the classic film
    (``None``, ``False``, 0)."""

    name: str
    # (physics, numerics) -> separation or None: the classic rigid approach is exact only down to
    # here (the coupled phase takes over at the largest of these and the classic hand-over)
    approach_stop: Callable = _none
    # its own rigid approach: the plan's label for it, physics -> it is exact, and
    # (physics, numerics, x_stop) -> RigidHead (x_stop: the other pieces' largest stop, or 0)
    approach: str = ""
    approach_exact: Callable = _false
    rigid_approach: Callable = _none
    # (physics, x, v) -> P(s), the film's pressure where the coupled phase starts on the classic
    # rigid approach at gap x and speed v, or None: the classic film's 3 V/(X + s)^2
    start_pressure: Callable = _none
    # its own rigid departure: the plan's label, physics -> it is exact, and
    # (physics, x, v, t, lost, film) -> (x, v, t, series block) from the release state (``film``
    # a rigid_phases.ReleaseFilm), or None when it does not apply there (e.g. still approaching),
    # or RUN_ON
    departure: str = ""
    departure_exact: Callable = _false
    depart: Callable = _none
    # physics -> its departure starts from spheres apart: with a cavity open, the coupled phase
    # ends at the release only once they separate (events.RELAXED_APART)
    departs_apart: Callable = _false
    # physics -> the coupled phase runs until the film is full again (events.RELAXED_FULL), after
    # which the classic departure is exact
    refills: Callable = _false
    # (physics, x_c, v_c, j, x_ref, cols, film) -> the restitution at x_ref read from row j of
    # the coupled phase (``film``: its last row's, a ReleaseFilm), for the physics whose
    # departure or refill is this piece's
    restitution: Callable = _none
    film_width: Callable = _zero  # physics -> a radius the grid's inner region covers
    film_reach: Callable = _zero  # physics -> a radius the grid reaches
    rests: Callable = _false  # (physics, v at the release) -> the spheres are at rest there
    # (result, cols, tau, blocks) -> None: sets its observables (``observables``) from the
    # coupled phase's series ``cols`` and the departure's blocks, on every coupled result
    observe: Callable = _none
    observables: tuple = ()
    # the coupled phase's history of the film's fluid fraction is kept in this result field
    # where physics -> True
    profile: str = ""
    keeps_profile: Callable = _false


# --- the pressure-dependent liquid (model/liquid.py, model/piezoviscous.py) -------------------

def _law_onset(physics, numerics):
    return rigid.law_onset_separation(physics.x_start, physics.St, rigid.law_slopes(physics)[0],
                                      numerics.switch)


def _barus_exact(physics):
    return physics.viscosity_law == "barus" and piezoviscous.exact_for(physics)


def _barus_approach(physics, numerics, x_stop) -> RigidHead:
    """The Barus liquid's rigid film at constant density (model/piezoviscous.py, a scalar ODE
    with a closed-form force), up to the hand-over on the Barus ``W(0)/X``, near the glass gap,
    or at ``x_stop``."""
    stokes, x_start, tau_per_t = physics.St, physics.x_start, physics.tau_per_t
    path = piezoviscous.approach(x_start, 1.0, 0.0, stokes, physics.beta, numerics.switch,
                                 x_stop=x_stop)
    rests = path.event == "rest"
    # the path without its end when a coupled phase follows (the phase starts there), and
    # without the rest (reached after infinite time)
    keep = np.isfinite(path.t)
    if not rests:
        keep[-1] = False
    block = rigid_block(path.t[keep], path.x[keep], path.v[keep], tau_per_t, 0,
                        1.0 - path.v[keep] ** 2)
    block["F"] = path.force[keep]
    block["W0"] = path.w0[keep]
    block["P_max"] = path.p_axis[keep]
    beta, x, v = physics.beta, path.x_end, path.v_end
    peaks = path.peaks
    if x > piezoviscous.glass_gap(v, beta):
        pressure = lambda s: piezoviscous.rigid_pressure(s, x, v, beta)  # noqa: E731
    else:
        # the start x0 itself lies inside the glass gap (beta > x0^2/3, e.g. 13 at eps 1e-2):
        # no rigid Barus film exists there; the coupled phase starts from the classic
        # pressure, the Kirchhoff pressure of that state, as with the other laws
        pressure = functools.partial(rigid.film_pressure, x=x, v=v)
        peaks = rigid.approach_peaks(x_start, stokes, x_start)
    return RigidHead(x, v, path.t_end, rests, block, peaks, pressure)


def _law_start_pressure(physics, x, v):
    """A pressure-dependent liquid at constant density whose rigid approach is the classic one
    (Roelands, a table; Barus has its own, ``_barus_approach``): the coupled phase starts from
    the law's rigid film, whose Kirchhoff pressure is the classic film's
    (``liquid.pressure_of_kirchhoff``); where the law does not reach it (a glass gap), from the
    classic pressure, as Barus does. It had started from the classic pressure itself: at eps
    1e-2 (the start inside the law's range, ``3 beta / x0^2`` 0.38) a table equal to Barus beta
    5 gave ``v_r`` 0.4 % above the Barus film's, at standard and fine alike."""
    if physics.isoviscous or physics.density_law != "constant" or _barus_exact(physics):
        return None
    phys = physics.as_array()

    def pressure(s):
        classic = rigid.film_pressure(np.asarray(s, dtype=float), x, v)
        out = np.empty_like(classic)
        return out if liquid.pressure_of_kirchhoff(classic, phys, out) else classic

    return pressure


LIQUID_LAW = Piece("pressure-dependent liquid", approach_stop=_law_onset, approach="barus",
                   approach_exact=_barus_exact, rigid_approach=_barus_approach,
                   start_pressure=_law_start_pressure)


# --- the cavitation floor (model/cavitation.py, model/film.py) -----------------------------

# the grid reaches this many times the widest cavity, sqrt(2) (V/Pi)^(1/4) at V = 1
CAVITY_REACH = 4.0
WIDEST_CAVITY = 400.0  # cap for Pi -> 0 (at Pi = 0 the whole opening film cavitates)


def cavity_reach(pi) -> float:
    """How far the grid must reach for a film with the floor ``-pi``: ``CAVITY_REACH`` times the
    widest cavity of the rigid separation at speed ``V = 1``, ``sqrt(2 s_c) ~ sqrt(2) (V/Pi)^(1/4)``
    (docs/model.md, "Cavitation"); 0 without a floor (``pi`` infinite)."""
    if not math.isfinite(pi):
        return 0.0
    return CAVITY_REACH * min(math.sqrt(2.0) * max(pi, 1e-12) ** -0.25, WIDEST_CAVITY)


def _floor_reach(physics):
    return cavity_reach(physics.Pi) if physics.cavitation != "off" else 0.0


def _refills(physics):
    # a JFO cavity has a memory: where its refill departure does not hold (a compressible
    # liquid), the coupled phase goes on until the film is full again
    return (physics.cavitation == "jfo" and not cavitation.exact_for(physics)
            and not refill.exact_for(physics))


def _floor_exact(physics):
    return cavitation.exact_for(physics) or refill.exact_for(physics)


def _refill_departs(physics):
    return refill.exact_for(physics) and not cavitation.exact_for(physics)


def _floor_departure(physics, x, v, t, lost, film):
    """The rigid departure with the floor from the release state, until the cavity closes: the
    Reynolds condition's (model/cavitation.py), or a JFO cavity's refill (``_refill_departure``).
    The Reynolds departure's series: the force ``-U/(X + s_c)``, the axis at the floor while the
    cavity ``R_c = sqrt(2 s_c)`` is open, the energy lost (viscous and to the void) from the
    kinetic energy."""
    if v >= 0.0:
        return None
    if _refill_departs(physics):
        return _refill_departure(physics, x, v, t, lost, film)
    x_end, u_end, t_end, (xs, us, ts) = cavitation.departure(x, -v, t, physics.St, physics.Pi)
    sigma = np.array([cavitation.cavity_fraction(physics.Pi * xi * xi / (6.0 * ui))
                      for xi, ui in zip(xs, us)])
    vs = -us
    block = rigid_block(ts, xs, vs, physics.tau_per_t, 2, lost + (v**2 - vs * vs))
    block["F"] = vs / (xs * (1.0 + sigma))
    block["P_min"] = np.where(sigma > 0.0, -physics.Pi, block["P_min"])
    block["cavity_radius"] = np.sqrt(2.0 * sigma * xs)
    return x_end, -u_end, t_end, block


def _refill_departure(physics, x, v, t, lost, film):
    """A JFO cavity's refill departure (model/refill.py) from the release state ``film``; None
    where the film is full there (the classic departure), RUN_ON where the cavity would grow, the
    spheres stop with it open or its steps run out. Its series as the Reynolds departure's, with
    the refill's force (``refill.force``) and the void the cavity's cells leave empty."""
    code, x_end, u_end, t_end, path = refill.departure(x, -v, t, physics.St, physics.Pi,
                                                       film.s_face, film.theta)
    if code != refill.CLOSED:
        return RUN_ON
    if path.shape[1] == 1:  # no cavity at the release
        return None
    xs, us, ts, qs = path
    vs = -us
    block = rigid_block(ts, xs, vs, physics.tau_per_t, 2, lost + (v**2 - vs * vs))
    block["F"] = refill.force(xs, us, qs, physics.Pi)
    block["P_min"] = np.where(qs > 0.0, -physics.Pi, block["P_min"])
    block["cavity_radius"] = np.sqrt(2.0 * qs)
    block["void_volume"] = refill.void_volume(xs, qs, x, -v, physics.Pi, film.s_face,
                                              film.theta)
    return x_end, -u_end, t_end, block


def outward_crossing(x_c, v_c, x_ref):
    """The separation speed ``-V`` with which the coupled phase's rows ``x_c``, ``v_c`` last cross
    ``x_ref`` outwards, interpolated between the two rows either side; None when they never do."""
    out = np.nonzero((x_c[1:] > x_ref) & (x_c[:-1] <= x_ref) & (v_c[1:] < 0.0))[0]
    if not out.size:
        return None
    k = int(out[-1])
    frac = (x_ref - x_c[k]) / (x_c[k + 1] - x_c[k])
    return float(-(v_c[k] + frac * (v_c[k + 1] - v_c[k])))


def crossing_speed(x_c, v_c, x_ref):
    """``outward_crossing`` where the rows end beyond ``x_ref`` (moving out, or turned back);
    None otherwise."""
    return outward_crossing(x_c, v_c, x_ref) if x_c[-1] > x_ref else None


def _cavity_restitution(physics, x_c, v_c, j, x_ref, cols, film):
    """``e`` at ``x_ref`` with a floor: by the floor's departure from row ``j``; or, for a film
    that refills (from where the classic rigid departure is exact), by the classic departure
    where the film is full from row ``j`` on, else from the coupled phase's own speed where it
    crosses ``x_ref`` (possibly with a cavity open), interpolated, else by the refill departure
    from the release state ``film`` (model/refill.py) where the cavity is still open there."""
    if cavitation.exact_for(physics):
        return cavitation.restitution(x_c[j], v_c[j], physics, x_ref)
    open_cavity = cols["cavity_radius"] + cols["void_volume"]
    if not np.any(open_cavity[j:] > 0.0):  # full from row j on: the classic departure
        return rigid.restitution_of_speed(rigid.departure_speed(x_c[j], v_c[j], physics.St, x_ref),
                                          physics, x_ref)
    speed = crossing_speed(x_c, v_c, x_ref)
    if speed is not None:
        return rigid.restitution_of_speed(speed, physics, x_ref)
    last = len(x_c) - 1
    if _refill_departs(physics) and open_cavity[last] > 0.0 and v_c[last] < 0.0 \
            and x_c[last] <= x_ref:
        speed = refill.speed_at(x_c[last], -v_c[last], physics.St, physics.Pi, film.s_face,
                                film.theta, x_ref)
        # None where its ODE, stepped to x_ref, disagrees with the departure's (not seen in
        # some 600 scenes): the classic departure, as before the refill departure
        if speed is not None:
            return rigid.restitution_of_speed(speed, physics, x_ref)
    return rigid.restitution_of_speed(
        rigid.departure_speed(x_c[last], v_c[last], physics.St, x_ref), physics, x_ref)


def _observe_cavity(result, cols, tau, blocks):
    cavity = np.nonzero(cols["cavity_radius"] > 0.0)[0]
    result.cavitated = bool(cavity.size > 0)
    result.cavity_radius_max = float(np.max(cols["cavity_radius"]))
    if cavity.size:
        result.tau_cavitation_onset = float(tau[cavity[0]])
    result.void_volume_max = float(np.max(cols["void_volume"]))
    if blocks[-1]["phase"][0] == 2:  # the departure's cavity (with a floor) may be the widest,
        departing = [b for b in blocks if b["phase"][0] == 2]  # a refill's void the largest
        widest = max(float(np.max(b["cavity_radius"])) for b in departing)
        result.cavity_radius_max = max(result.cavity_radius_max, widest)
        result.void_volume_max = max(result.void_volume_max,
                                     max(float(np.max(b["void_volume"])) for b in departing))
        result.cavitated = result.cavitated or widest > 0.0


def _jfo(physics):
    return physics.cavitation == "jfo"


CAVITATION = Piece("cavitation", departure="floor", departure_exact=_floor_exact,
                   depart=_floor_departure, departs_apart=_refill_departs, refills=_refills,
                   restitution=_cavity_restitution,
                   film_reach=_floor_reach, observe=_observe_cavity,
                   observables=("cavitated", "cavity_radius_max", "tau_cavitation_onset",
                                "void_volume_max"),
                   profile="fluid_fraction", keeps_profile=_jfo)


# --- asperity contact with e_dry (model/contact.py) -------------------------------------------

def _contact_onset(physics, numerics):
    return rigid.contact_onset_separation(physics.x_start, physics.St, physics.roughness)


def _asperity_width(physics):
    # at a roughness of several x1 the asperities stop the spheres before the solids deform, and
    # the film that does the work is sqrt(2 sigma) wide; on the rigid limit of
    # tests/test_contact.py at roughness 5400 x1 covering it took the outer cells' error in e_wet
    # at St 20 from 3.9e-4 to 7e-5
    return math.sqrt(2.0 * physics.roughness)


def _at_rest_on_asperities(physics, v):
    return not physics.smooth and abs(v) < contact.REST_SPEED


ASPERITY_CONTACT = Piece("asperity contact", approach_stop=_contact_onset,
                         film_width=_asperity_width, rests=_at_rest_on_asperities)


# --- slip at the surfaces (model/slip.py) -----------------------------------------------------

# the grid reaches where the gap is this many slip gaps c = 6 l: the far-field row keeps the
# classic P H^2, which slip changes by 2c/(3H) there, on a load 3V/H^2 that is negligible
SLIP_REACH = 100.0


def _slip_stop(physics, numerics):
    # slip changes the rigid film from the start on, by 2c/(3 x0) in its force
    return physics.x_start if physics.slip_length > 0.0 else None


def _slip_approach(physics, numerics, x_stop) -> RigidHead:
    """The rigid slip film (model/slip.py, closed forms) from the start to the hand-over on its
    own ``W(0)/X``, to ``x_stop``, or to rest."""
    c = slip.mobility_gap(physics)
    path = slip.approach(physics.x_start, physics.St, c, numerics.switch, x_stop)
    rests = path.event == "rest"
    keep = np.isfinite(path.t)
    if not rests:
        keep[-1] = False
    block = _slip_block(path, keep, physics.tau_per_t, 0, 1.0 - path.v[keep] ** 2)
    x, v = float(path.x[-1]), float(path.v[-1])
    best = {"peak_force": int(np.argmax(path.force)), "w0_max": int(np.argmax(path.w0)),
            "p_max": int(np.argmax(path.p_axis))}
    peaks = {"peak_force": float(path.force[best["peak_force"]]),
             "t_peak_force": float(path.t[best["peak_force"]]),
             "w0_max": float(path.w0[best["w0_max"]]),
             "t_max_deformation": float(path.t[best["w0_max"]]),
             "p_max": float(path.p_axis[best["p_max"]]), "t_p_max": float(path.t[best["p_max"]]),
             "x_p_max": float(path.x[best["p_max"]])}
    pressure = None if rests else (lambda s: slip.rigid_pressure(s, x, v, c))  # noqa: E731
    return RigidHead(x, 0.0 if rests else v, math.inf if rests else float(path.t[-1]), rests,
                     block, peaks, pressure)


def _slip_block(path, keep, tau_per_t, phase, dissipated):
    block = rigid_block(path.t[keep], path.x[keep], path.v[keep], tau_per_t, phase, dissipated)
    block["F"] = path.force[keep]
    block["W0"] = path.w0[keep]
    block["P_max"] = np.maximum(path.p_axis[keep], 0.0)
    block["P_min"] = np.minimum(path.p_axis[keep], 0.0)
    return block


def _slip_departure(physics, x, v, t, lost, film):
    """The rigid slip departure from the release state (model/slip.py): out to 0.99 of the way
    to its rest in ``ln X`` or to where slip no longer counts (``slip.departure``), from where
    the classic departure goes on (its rest separation, ``ln_x_e``, is then the classic one's
    from there: within ``0.01 (1 - f*)`` of the slip path's in ``ln X``; ``e`` is read on the
    slip path, ``_slip_restitution``). The state handed on still moves, so no piece takes the
    spheres for resting (the asperity contact's ``rests`` reads its speed)."""
    if v >= 0.0:
        return None
    path = slip.departure(x, v, t, physics.St, slip.mobility_gap(physics))
    keep = np.ones(len(path.t), dtype=bool)
    block = _slip_block(path, keep, physics.tau_per_t, 2, lost + (v * v - path.v ** 2))
    return float(path.x[-1]), float(path.v[-1]), float(path.t[-1]), block


def _slip_restitution(physics, x_c, v_c, j, x_ref, cols, film):
    """``e`` at ``x_ref``: the rigid slip departure's speed there from row ``j`` over the rigid
    slip approach's speed there (which arrives at ``x0`` with speed 1)."""
    c = slip.mobility_gap(physics)
    approach_speed = float(slip.velocity(x_ref, physics.x_start, 1.0, physics.St, c))
    departure_speed = -float(slip.velocity(x_ref, x_c[j], v_c[j], physics.St, c))
    if v_c[j] >= 0.0 or slip.rest_separation(x_c[j], v_c[j], physics.St, c) <= math.log(x_ref):
        return 0.0
    return departure_speed / approach_speed


def _slip_reach(physics):
    return math.sqrt(2.0 * SLIP_REACH * slip.mobility_gap(physics))


def _slip_width(physics):
    # the rigid slip film's pressure falls as 1/H, not 1/H^2, out to H ~ c: its work is done
    # out to s ~ c
    return math.sqrt(2.0 * slip.mobility_gap(physics))


SLIP = Piece("slip", approach_stop=_slip_stop, approach="slip", approach_exact=slip.exact_for,
             rigid_approach=_slip_approach, departure="slip",
             departure_exact=slip.departs_exact, depart=_slip_departure,
             restitution=_slip_restitution, film_width=_slip_width, film_reach=_slip_reach)


PIECES = (LIQUID_LAW, CAVITATION, ASPERITY_CONTACT, SLIP)
