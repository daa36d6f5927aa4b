"""One collision ("scene"): analytic rigid approach, coupled EHD phase, analytic rigid departure.

Scales (docs/model.md, "Scales"): lengths along the axis by ``x1 = (4 theta mu a^1.5 v0)^0.4``,
radii by ``sqrt(a x1)``, time by ``x1/v0`` (``T``; ``tau = v0 t / x0 = T eps^0.4``), pressure by
``mu a v0 / x1^2``, velocity by ``v0``, energies by the initial kinetic energy ``m v0^2 / 2``.
Forces are reported in units of ``6 pi mu a^2 v0 / x1`` (the rigid film force at gap ``x1`` and
speed ``v0``), so ``F = (1/3) Int P R dR`` and ``dV/dT = -F / St``.

Only the physics a scene needs is switched on, and every analytic piece is used only where
``shortcuts.plan(physics)`` says it is exact: for the classic film the rigid solution is exact
until ``W(0)/X`` reaches ``switch`` (a scene that never gets there is answered analytically,
``model = "rigid"``), and again once the deformation has relaxed below ``release`` on the way
out, which gives the equilibrium separation in closed form.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import replace

import numpy as np

from . import extrapolation, far_field
from .interrupts import deferred_interrupt
from .integration import dense, kinds
from .integration.grid import reference_grid, scaled_grid
from .model import liquid, rigid
from .observables import OBSERVABLES, SERIES, STATUS, failure_message
from .physics import Physics, is_real_number
from . import pieces
from .result import JSON_KEYS, SOLVER_VERSION, Collision
from .rigid_phases import KEPT, ReleaseFilm, RigidHead, rigid_block, rigid_path
from .settings import Numerics, resolve
from .shortcuts import plan, run_on

__all__ = ["collide", "Collision", "SOLVER_VERSION", "hertz_overlap", "JSON_KEYS", "read_far"]

# Not a numerical failure: the model's premise fails. The coupled phase starts from the rigid
# pressure's deformation, whose strain energy is 3.08 eps/St of the kinetic energy when the
# hand-over is at the start; beyond START_STRAIN_LIMIT the start x0 is not deformation-free
# (eps is not small for this St) and the answer depends on that assumption (e.g. v_r > 1 at
# St = 0.05, eps = 0.1). The observables are still reported, with status "start_deformed".
START_STRAIN_LIMIT = 0.1

# An ok result's energy closure (``energy_error``, of m v0^2/2) stays below this. Over 566 ok
# scenes of the supported range (St 0.05-1000 x eps 1e-12-0.1, the classic film, both floors,
# Barus, rough with and without JFO; fast and standard presets) the largest closure error was
# 3.1e-3 (fast), so 0.02 leaves a factor 6 for scenes outside that scan; an error this large
# already moves v_r by 0.01/v_r, more than any preset's stated error. The scene that made it
# (St 0.001, roughness ~ x0, k 1e-6) closed to 0.50 and was reported ok.
ENERGY_CLOSURE_LIMIT = 0.02

DIMPLE_DEPTH = 1e-3  # x1 units: a central gap this much above the minimum counts as a dimple

# x1 units: a failed solve whose last smallest gap is below this had drained the film to
# round-off (a gap of 1e-12 x1 is far below a molecule at any x1 the model takes): the solids
# met with nothing in the model to hold them apart, which a finer accuracy cannot mend. A slip
# length of tens of x1 does it (docs/model.md, "Slip": at St 6, eps 1e-8, slip length 3 the
# gap fell to 1e-20 before the steps underflowed).
DRAINED_GAP = 1e-12

# How far out (over the radius a) a film may carry the spheres before drawing them back from
# there is outside the model (``_pulled_back_from_afar``): the lubrication film is the leading
# order in X/a, so beyond 0.1 a its neglected terms are 10 % of it
LUBRICATION_REACH = 0.1

# A film whose viscosity rises this much over the approach is reported as solidified: it flows
# 1e4 times slower than at ambient pressure, so over a contact of O(10) x1/v0 the liquid trapped
# at the axis moves less than 1e-3 of what the classic film moves there: a frozen ("glassy")
# lens the spheres turn round on (docs/model.md, "Pressure-dependent viscosity and density")
SOLID_VISCOSITY_RATIO = 1e4


def hertz_overlap(stokes):
    """Dry Hertz maximum overlap over ``x1``: ``(90 pi^2 St / 64)^(2/5)`` (docs/model.md,
    "Hertz limit")."""
    return (90.0 * math.pi**2 * stokes / 64.0) ** 0.4


def _parabolic_peak(t, f, i):
    """Vertex of the parabola interpolating samples i-1, i, i+1 (the discrete extremum ``i``)."""
    if i <= 0 or i >= len(f) - 1:
        return t[i], f[i]
    t0, t1, t2 = t[i - 1], t[i], t[i + 1]
    f0, f1, f2 = f[i - 1], f[i], f[i + 1]
    d1 = (f1 - f0) / (t1 - t0)
    d2 = (f2 - f1) / (t2 - t1)
    curv = (d2 - d1) / (t2 - t0)  # half the second derivative
    if curv == 0.0:
        return t1, f1
    tv = 0.5 * (t0 + t1) - d1 / (2.0 * curv)
    if not (t0 <= tv <= t2):
        return t1, f1
    fv = f1 + d1 * (tv - t1) + curv * (tv - t0) * (tv - t1)
    return tv, fv


def _peak(t, f, i, order, lowest):
    """The extremum of the series ``f`` (times ``t``) at its discrete extremum ``i`` (a minimum
    if ``lowest``, else a maximum), read as the loop integrated it (``order``: the series' BDF
    order of the step that ended at each row). Where the steps either side of row ``i`` were of
    order 2 or lower, the vertex of the parabola on rows ``i - 1``, ``i``, ``i + 1``
    (``_parabolic_peak``); above, on each of the two steps' own interpolants, the polynomial
    interpolating the step's ``k + 1`` newest rows (the BDF's dense output, order ``k``), whose
    error follows the method's order where the parabola's goes with the step's cube. The loop's
    own reading of an extremum inside a step (integration/dense.py: ``extremum_in_step``)
    finds it, compiled: with numpy's polynomial fit and roots, a classic collision took 1/0.95
    its CPU time at the standard preset (docs/solver.md)."""
    if i <= 0 or i >= len(f) - 1 or max(order[i], order[i + 1]) <= 2:
        return _parabolic_peak(t, f, i)
    best_t, best_f = t[i], f[i]
    sign = 1.0 if lowest else -1.0
    basis = np.empty((4, int(max(order[i], order[i + 1])) + 1))  # the highest step's k + 1
    for end in (i, i + 1):  # the steps from row end - 1 to row end
        k = int(order[end])
        if k <= 2 or end - k < 0:
            continue
        newest_first = slice(end, end - k - 1 if end > k else None, -1)
        value, when = dense.extremum_in_step(
            np.ascontiguousarray(t[newest_first]),
            np.ascontiguousarray(f[newest_first]).reshape(k + 1, 1), 1, k, sign, basis)
        if (value < best_f) if lowest else (value > best_f):
            best_t, best_f = when, value
    return best_t, best_f


FAR_FIELD_REACH = 8.0  # the grid reaches this many film widths sqrt(2 X) beyond the axis


def scene_grid(stokes, x_switch, numerics: Numerics, width=0.0, reach=0.0):
    """The radial grid of a scene.

    The inner region covers the Hertz contact radius ``sqrt(delta_H)`` (at least 2, the film's
    width at small St), and ``width``, the widest film a piece of physics does its work in
    (``Piece.film_width``, solver/pieces.py). The grid must also reach well beyond the widest
    film the coupled phase sees, ``sqrt(2 X)`` at the hand-over and at the release (where
    ``W(0)/X = release`` on the rigid path with ``V <= 1``), and the radius ``reach`` a piece
    needs (``Piece.film_reach``); its extent doubles until it does (a few outer cells each
    time).
    """
    inner = numerics.inner_factor * max(math.sqrt(hertz_overlap(stokes)), 2.0, width)
    x_release = (rigid.HANDOVER_COEFF / numerics.release) ** 0.4
    reach = max(FAR_FIELD_REACH * math.sqrt(2.0 * max(x_switch, x_release)) / inner,
                reach / inner)
    extent = numerics.outer_extent
    while extent < reach:
        extent *= 2.0
    ref = reference_grid(numerics.n_inner, numerics.axis_ratio, numerics.axis_extent,
                         numerics.stretch, extent, numerics.max_rel)
    return scaled_grid(ref, inner)


def collide(physics, eps=None, *, accuracy: str = "standard", x_ref_x0: float = 1.0,
            outer: far_field.OuterFlow | None = None, attempt_log: bool = False,
            **overrides) -> Collision:
    """Solve one head-on collision of two elastic spheres across a viscous film.

    Parameters
    ----------
    physics : Physics or float
        Every dimensionless group of the scene (solver.Physics); or the Stokes number
        ``m v0 / (6 pi mu a^2)`` in (0, 1e4], with ``eps`` given next.
    eps : float, optional
        Elasticity parameter ``4 theta mu v0 a^1.5 / x0^2.5`` in (0, 0.1], when ``physics`` is the
        Stokes number: ``collide(5.0, 0.01)`` is ``collide(Physics(St=5.0, eps=0.01))``.
    accuracy : {"fast", "standard", "fine"}
        Preset of numerical settings (settings.PRESETS).
    x_ref_x0 : float
        Where the wet restitution ``e_wet`` is seen, over ``x0`` (``>= 1``; default the start
        ``x0``). A reporting option, not physics: the impact Stokes number there is
        ``St_ref = St + ln(x_ref/x0)`` (``Collision.St_ref``, rigid.impact_stokes).
    outer : far_field.OuterFlow, optional
        How ``e_far`` and ``v_outer_start`` read the result from far away (geometry, ``x0/a``,
        ``x_ref/a``, the outer start, the density ratio); default ``far_field.DEFAULT``. A reading,
        not physics: the near-field solve does not depend on it.
    attempt_log : bool
        Keep one entry per step attempt of the coupled phase in ``Collision.attempts`` (its
        time, step, order, outcome, Newton iterations, error and the error's largest term with
        its node; docs/solver.md, "The attempt log"): where a solve spends its steps. A
        diagnostic: the results are the same to the bit.
    **overrides
        Any field of ``settings.Numerics`` (e.g. ``switch=0.005``, ``n_inner=64``).

    Returns
    -------
    Collision
        ``status == "ok"`` or a failure code with ``message``; see solver/result.py.
    """
    if not isinstance(physics, Physics):
        physics = Physics(St=physics, eps=eps)
    elif eps is not None:
        raise TypeError("collide(physics, ...): eps is part of the Physics; do not pass it twice")
    numerics = resolve(accuracy, **overrides)
    if not (is_real_number(x_ref_x0) and math.isfinite(x_ref_x0) and x_ref_x0 >= 1.0):
        raise ValueError(f"x_ref_x0 = {x_ref_x0!r}: the reference separation must be a finite "
                         "number, at least the start x0 (x_ref_x0 >= 1)")
    x_ref_x0 = float(x_ref_x0)  # an int or numpy scalar is stored as the float it means
    if not isinstance(attempt_log, (bool, np.bool_)):
        raise TypeError(f"attempt_log = {attempt_log!r}: True or False (keep the step attempts "
                        "in Collision.attempts, or not)")
    attempt_log = bool(attempt_log)
    wall = time.perf_counter()
    with deferred_interrupt():  # Ctrl-C or SIGTERM inside compiled code: taken on return
        head = rigid_head(physics, numerics)
        if head.rests:
            result = _rigid_only(physics, accuracy, numerics, head, x_ref_x0)
        else:
            result = _coupled(physics, accuracy, numerics, head, x_ref_x0, attempt_log)
            if numerics.extrapolate and result.status == "ok":
                _pair(result, head, x_ref_x0, outer)
        read_far(result, outer)
        check_energy(result)
        _pulled_back_from_afar(result)
    result.wall_s = time.perf_counter() - wall
    return result


def _pair(result, head, x_ref_x0, outer):
    """``result``, an ok solve, combined with the solve of its scene on half its cells
    (solver/extrapolation.py) from the same rigid approach ``head`` (the grid does not enter
    it), which is checked as any result is (``check_energy``: an unphysical one is not
    combined); the peak viscosity and ``solidified`` from the extrapolated approach pressure, as
    a single solve derives them. Where the half grid's solve fails, or raises (a defect, which
    must not take the finer solve with it), ``result`` stays the finer solve's, not
    extrapolated, and its message says why (after a note it had, ``_noted``)."""
    half = replace(result.numerics.halved(), save_profiles=False)
    try:
        coarse = _coupled(result.physics, result.accuracy, half, head, x_ref_x0)
        check_energy(read_far(coarse, outer))
    except Exception as exc:  # noqa: BLE001 - the finer result is kept; the defect is named
        _noted(result, f"not extrapolated: the half grid's solve raised "
                       f"{type(exc).__name__}: {exc}")
        return
    if extrapolation.combine(result, coarse):
        _approach_viscosity(result)
    elif coarse.status != "ok":  # its status alone: its message's advice is for a failure
        _noted(result, f"not extrapolated: the half grid's solve failed ({coarse.status})")


def _noted(result, note):
    """``note`` added to an ok result's message, after the one it has (``_drawn_back``'s)."""
    result.message = f"{result.message}; {note}" if result.message else note


def _drained(h_min) -> str:
    """What a failed solve's message adds when its last accepted state had drained the film to
    round-off (``DRAINED_GAP``): the cause, which no accuracy mends; "" otherwise."""
    if not (h_min.size and h_min[-1] < DRAINED_GAP):
        return ""
    return (f"; the film had drained to round-off (smallest gap {h_min[-1]:.2g} x1) and nothing "
            "in the model held the surfaces apart (asperities would carry such a contact; "
            "docs/model.md, \"Slip\")")


def energy_violation(result) -> str:
    """Why an ok ``result`` breaks the energy balance, or "" when it does not: its closure error
    above ``ENERGY_CLOSURE_LIMIT``, or a speed ratio (``v_r``, ``e_wet``, ``e_far``) above what
    the energy at the start allows, ``sqrt(1 + start_strain_energy + ENERGY_CLOSURE_LIMIT)``
    (no term of the model adds energy: the film, the outer flow and the solids only take it;
    ``x_ref >= x0``, so the approach speed an ``e`` divides by is at least ``v0``); or ``e_wet``
    above the largest separation speed ``v_r`` over the approach speed at ``x_ref``, by more
    than ``ENERGY_CLOSURE_LIMIT`` of it: ``e_wet`` is a speed the spheres had on the way out
    (a departure read from a coupled phase that had turned back gave twice ``v_r``, stored as
    ok: docs/solver.md, Versions, 1.15.4)."""
    why = []
    closure = result.energy_error
    if not closure <= ENERGY_CLOSURE_LIMIT:  # NaN too
        why.append(f"closure error {closure:.3g} of the kinetic energy, above "
                   f"{ENERGY_CLOSURE_LIMIT:g}")
    start = result.start_strain_energy if math.isfinite(result.start_strain_energy) else 0.0
    bound = math.sqrt(1.0 + max(start, 0.0) + ENERGY_CLOSURE_LIMIT)
    for name in ("v_r", "e_wet", "e_far"):
        value = float(getattr(result, name))
        if value > bound:
            why.append(f"{name} = {value:.4g} above {bound:.4g}")
    approach = result.St_ref / result.St  # the approach speed at x_ref, units v0
    if result.e_wet * approach > result.v_r * (1.0 + ENERGY_CLOSURE_LIMIT):
        why.append(f"e_wet = {result.e_wet:.4g} above the largest separation speed "
                   f"v_r = {result.v_r:.4g} over the approach speed at x_ref ({approach:.4g})")
    return "; ".join(why)


def check_energy(result):
    """An ok ``result`` that breaks the energy balance (``energy_violation``) becomes
    ``"unphysical"`` (one whose closure is not finite, ``"nonfinite"``): its message says why,
    and its observables are withheld (NaN, flags None; the cost counters and wall time are
    kept), so no caller can take them for a result."""
    if result.status != "ok":
        return result
    if not math.isfinite(result.energy_error):  # a non-finite balance is no balance at all
        result.status = "nonfinite"
        result.message = (f"{failure_message('nonfinite')}: the energy closure is "
                          f"{result.energy_error}")
        withhold(result)
        return result
    why = energy_violation(result)
    if not why:
        return result
    result.status = "unphysical"
    result.message = failure_message("unphysical", why=why)
    withhold(result)
    return result


def withhold(result):
    """Every observable of a result that is not a result (a failure's) to NaN (flags None),
    except the diagnostic ones (cost counters, wall time)."""
    for o in OBSERVABLES:
        if o.derived or o.diagnostic:
            continue
        setattr(result, o.name, None if o.kind == "flag" else math.nan)
    result.e_x0 = math.nan


def read_far(result, outer=None):
    """``e_far`` and ``v_outer_start`` of ``result`` (its ``e_x0``, the departure speed at x0)
    read by ``outer`` (solver/far_field.py; default ``far_field.DEFAULT``)."""
    outer = far_field.DEFAULT if outer is None else outer
    if not isinstance(outer, far_field.OuterFlow):
        raise TypeError(f"outer must be a solver.far_field.OuterFlow, got {type(outer).__name__}")
    result.outer = outer
    result.e_far = outer.restitution(result.e_x0, result.physics.St)
    result.v_outer_start = outer.approach_speed(result.physics.St)
    return result


def handover_separation(physics, numerics):
    """Where the coupled phase takes over on the classic rigid approach: the first separation
    where the deformation ``W(0)/X`` reaches ``switch`` (rigid.handover_separation), or where a
    piece of physics stops the classic rigid approach being exact (``Piece.approach_stop``: e.g.
    the liquid's pressure dependence changes the rigid film by ``switch``); None when the spheres
    come to rest before any (the scene is rigid all the way)."""
    found = [x for x in (
        rigid.handover_separation(physics.x_start, physics.St, numerics.switch),
        *(p.approach_stop(physics, numerics) for p in pieces.PIECES)) if x is not None]
    return max(found) if found else None


def rigid_head(physics, numerics) -> RigidHead:
    """The rigid approach of ``physics``: the classic closed form (rigid.py) up to
    ``handover_separation``, the film there a piece's own where it has one
    (``Piece.start_pressure``), else the classic film's; or the rigid approach of the piece the
    plan gives one (``Piece.rigid_approach``), which stops where the other pieces stop the
    classic one."""
    stokes, x_start, tau_per_t = physics.St, physics.x_start, physics.tau_per_t
    own = plan(physics).approach_piece
    if own is not None:
        stops = [x for p in pieces.PIECES if p is not own
                 for x in (p.approach_stop(physics, numerics),) if x is not None]
        return own.rigid_approach(physics, numerics, max(stops, default=0.0))
    x_switch = handover_separation(physics, numerics)
    if x_switch is None:
        ln_x_stop = rigid.rest_separation(x_start, 1.0, stokes)
        u = np.linspace(0.0, 0.999 * stokes, 200) if stokes < 30 else np.linspace(0.0, 30.0, 200)
        x = x_start * np.exp(-u)
        t, v = rigid_path(x_start, 1.0, 0.0, stokes, x)
        block = rigid_block(t, x, v, tau_per_t, 0, 1.0 - v * v)
        return RigidHead(math.exp(ln_x_stop), 0.0, math.inf, True, block,
                         rigid.approach_peaks(x_start, stokes, 0.0), None)
    v_switch = float(rigid.velocity(x_switch, x_start, 1.0, stokes))
    t_switch = float(rigid.elapsed_time(x_switch, x_start, 1.0, stokes))
    block = None
    if x_switch < x_start:
        x_head = x_start * np.exp(-np.linspace(0.0, math.log(x_start / x_switch), 60))[:-1]
        t_head, v_head = rigid_path(x_start, 1.0, 0.0, stokes, x_head)
        block = rigid_block(t_head, x_head, v_head, tau_per_t, 0, 1.0 - v_head**2)
    own_start = [f for p in pieces.PIECES
                 for f in (p.start_pressure(physics, x_switch, v_switch),) if f is not None]
    return RigidHead(x_switch, v_switch, t_switch, False, block,
                     rigid.approach_peaks(x_start, stokes, x_switch),
                     own_start[0] if own_start else functools.partial(rigid.film_pressure,
                                                                      x=x_switch, v=v_switch))


def _concat(blocks):
    return {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}


def _rigid_only(physics, accuracy, numerics, head, x_ref_x0):
    """The scene never deforms enough to need the coupled solution: its rigid approach, exact,
    comes to rest at ``head.x``."""
    x_stop = head.x
    result = Collision(
        physics=physics, accuracy=accuracy, numerics=numerics, model="rigid", status="ok",
        message="deformation stays below the hand-over threshold: rigid solution (exact)",
        v_r=0.0, e_wet=0.0, e_x0=0.0, h_m_x1=x_stop, h_m_approach_x1=x_stop, ln_x_e_x1=math.log(x_stop),
        tau_v_zero=math.inf, tau_max_rebound=math.nan, x_min_x1=x_stop, energy_error=0.0,
        p_min=0.0, series=head.block, x_ref_x0=x_ref_x0)
    include_rigid_peaks(result, head.peaks)
    return result


def _approach_viscosity(result):
    """The peak viscosity over the approach, at its peak pressure ``p_max_approach``, and
    whether the film solidified (``SOLID_VISCOSITY_RATIO``)."""
    result.viscosity_ratio_max_approach = float(
        liquid.viscosity_ratio(result.p_max_approach, result.physics.as_array()))
    result.solidified = bool(result.viscosity_ratio_max_approach >= SOLID_VISCOSITY_RATIO)


def include_rigid_peaks(result, head):
    """Peaks are the larger of the coupled phase's (already in ``result``; NaN when none) and
    ``head``, those of the rigid approach before the hand-over (rigid.approach_peaks keys, and
    ``x_p_max``)."""
    tau_per_t = result.physics.tau_per_t
    if not head["p_max"] <= result.p_max_approach:  # also when the result holds NaN
        result.p_max_approach = head["p_max"]
        result.h_axis_at_peak_pressure_x1 = head["x_p_max"]  # rigid: H(0) = X
    _approach_viscosity(result)
    for name, head_name, t_name in (("peak_force", "peak_force", "tau_peak_force"),
                                    ("w0_max_x1", "w0_max", "tau_max_deformation"),
                                    ("p_max", "p_max", None)):
        if not head[head_name] <= getattr(result, name):  # also when the result holds NaN
            setattr(result, name, head[head_name])
            if t_name is not None:
                setattr(result, t_name, head["t_" + t_name[4:]] * tau_per_t)


# Rows of the attempt log (collide's ``attempt_log``): a collision takes a few thousand attempts
# at most (Barus beta 10, standard: 1748 steps and 488 rejected); later ones are not kept
ATTEMPT_LOG_ROWS = 100_000


def _integrate(physics, numerics, head, shortcuts, attempt_log=False):
    """The coupled phase's grid and time loop (integration/stepper.py) from the hand-over state
    ``head`` until the shortcuts' end event (a film that refills: until it is full again): the
    grid, then ``integrate``'s results, its counters by name (``COUNTERS``) and its attempt log
    as ``Collision.attempts`` (None unless asked for), each read with the constants of the loop
    that ran (a copy, integration/kinds.py: a classic film never imports the loop with every
    piece)."""
    stokes, x_switch, v_switch = physics.St, head.x, head.v
    grid = scene_grid(stokes, x_switch, numerics,
                      max(p.film_width(physics) for p in pieces.PIECES),
                      max(p.film_reach(physics) for p in pieces.PIECES))
    p_init = head.pressure(grid.s)  # the rigid film's pressure; K p = asymptotic W
    # the first step (implicit Euler, no error estimate: no history yet) is a small fraction of
    # the film's time scale X/V and of the spheres' deceleration time St X/V: at St 0.001 a
    # first step of 1e-3 X/V spanned the whole stop and dissipated 1.5 times the kinetic energy
    time_scale = x_switch / max(v_switch, 1e-3) * min(1.0, stokes)
    _, stop_params = rigid.release_event(numerics.release, stokes, physics)
    phys = physics.as_array()
    loop = kinds.loop_for(phys, attempt_log)  # compiled for the pieces this physics asks for
    code, counters, rows, p_hist, w_hist, theta_hist, log = loop.integrate(
        grid.nodes(), phys,
        loop.Start(float(head.t), float(x_switch), float(v_switch), p_init,
                   float(1.0 - v_switch**2)),
        loop.Control(float(numerics.rtol), float(1e-3 * time_scale), float(1e-12 * time_scale),
                     int(numerics.max_steps), int(numerics.max_order),
                     float(numerics.high_order_rtol_factor)),
        shortcuts.end_event, stop_params, numerics.save_profiles,
        ATTEMPT_LOG_ROWS if attempt_log else 0)
    counted = {name: int(n) for name, n in zip(loop.COUNTERS, counters)}
    attempts = _attempts(loop, log, physics.tau_per_t) if attempt_log else None
    return grid, code, counted, rows, p_hist, w_hist, theta_hist, attempts


def _save_profiles(result, t_c, x_c, p_hist, w_hist, theta_hist):
    """The coupled phase's profiles into ``result`` (``Numerics.save_profiles``)."""
    result.profile_tau = t_c * result.physics.tau_per_t
    result.pressure = p_hist
    result.deformation = w_hist
    for piece in pieces.PIECES:
        if piece.keeps_profile(result.physics):
            setattr(result, piece.profile, theta_hist)
    result.profile_x = x_c


def _attempts(loop, log, tau_per_t):
    """The attempt log's rows (the ``loop``'s ``LOG_COLUMNS``) as ``Collision.attempts``: time
    and step in ``tau``, the codes as their names."""
    col = {name: log[:, k] for k, name in enumerate(loop.LOG_COLUMNS)}
    largest = np.array(("", *loop.LARGEST_TERMS))
    return {"tau": col["t"] * tau_per_t, "dtau": col["dt"] * tau_per_t,
            "order": col["order"].astype(int),
            "outcome": np.array(loop.ATTEMPT_OUTCOMES)[col["outcome"].astype(int)],
            "newton": col["newton"].astype(int), "fresh_matrix": col["fresh"] != 0.0,
            "set_changes": col["set_changes"].astype(int), "error": col["error"],
            "largest": largest[np.where(np.isnan(col["largest"]), 0, col["largest"] + 1)
                               .astype(int)],
            "cell": np.where(np.isnan(col["cell"]), -1, col["cell"]).astype(int)}


def _coupled(physics, accuracy, numerics, head, x_ref_x0, attempt_log=False, shortcuts=None):
    stokes, x_start, tau_per_t = physics.St, physics.x_start, physics.tau_per_t
    shortcuts = shortcuts or plan(physics)
    grid, code, counters, rows, p_hist, w_hist, theta_hist, attempts = _integrate(
        physics, numerics, head, shortcuts, attempt_log)
    name = next(k for k, (c, _) in STATUS.items() if c == code)
    message = STATUS[name][1]
    cols = {c.name: rows[:, k] for k, c in enumerate(SERIES)}
    cols["F"] = cols["F"] / 3.0  # force unit 6 pi mu a^2 v0 / x1
    t_c, x_c, v_c = cols["T"], cols["X"], cols["V"]
    film = ReleaseFilm(grid.s_face, theta_hist[-1])
    departed = _own_departure(physics, shortcuts, cols, film) if name == "ok" else None
    if departed is pieces.RUN_ON:  # the piece's departure does not hold from this release
        return _coupled(physics, accuracy, numerics, head, x_ref_x0, attempt_log,
                        run_on(shortcuts))

    # rigid approach (analytic, or a piece's own rigid approach) up to the hand-over
    blocks = [head.block] if head.block is not None and len(head.block["T"]) else []
    coupled = {c.name: cols[c.name] for c in KEPT}
    coupled.update(tau=t_c * tau_per_t, phase=np.full(len(t_c), 1, dtype=np.int8))
    blocks.append(coupled)

    result = Collision(
        physics=physics, accuracy=accuracy, numerics=numerics, model="ehd", status=name,
        message=message, steps=counters["steps"], rejected_steps=counters["rejected_steps"],
        newton_iterations=counters["newton_iterations"],
        lu_factorizations=counters["lu_factorizations"],
        higher_order_steps=counters["higher_order_steps"],
        tau_handover=head.t * tau_per_t, radius=grid.radius, x_ref_x0=x_ref_x0)
    if attempt_log:
        result.attempts = attempts
    if numerics.save_profiles:
        _save_profiles(result, t_c, x_c, p_hist, w_hist, theta_hist)
    if name != "ok":
        result.v_r = result.dimple_depth_x1 = math.nan
        result.dimple = None
        for flag in (o.name for o in OBSERVABLES if o.kind == "flag"
                     and any(o.name in p.observables for p in pieces.PIECES)):
            setattr(result, flag, None)
        result.series = _concat(blocks)
        result.message = (f"{message} (St={stokes:g}, eps={physics.eps:g}, after "
                          f"{counters['steps']} steps at tau={t_c[-1] * tau_per_t:.4g})"
                          f"{_drained(cols['H_min'])}")
        _premise_first(result, cols)
        return result

    ln_x_e, resting = _depart(physics, cols, blocks, departed)
    result.series = _concat(blocks)
    result.tau_release = t_c[-1] * tau_per_t
    result.ln_x_e_x1 = ln_x_e
    if resting:  # they stick
        result.e_wet = result.e_x0 = 0.0
    else:
        result.e_wet = _wet_restitution(physics, shortcuts, cols, x_ref_x0 * x_start, film)
        result.e_x0 = result.e_wet if x_ref_x0 == 1.0 else _wet_restitution(
            physics, shortcuts, cols, x_start, film)
    if result.e_wet == 0.0:
        result.message = _drawn_back(physics, cols, x_ref_x0 * x_start) or result.message
    _coupled_observables(result, cols, tau_per_t, ln_x_e, v_c[-1])
    for piece in pieces.PIECES:
        piece.observe(result, cols, t_c * tau_per_t, blocks)
    include_rigid_peaks(result, head.peaks)
    _premise_first(result, cols)
    return result


def _premise_first(result, cols):
    """Status ``start_deformed`` where the start already breaks the model's premise
    (``START_STRAIN_LIMIT``), whether the solve went on to an end or failed: a failure is then
    no numerical one that a finer preset would mend (St 1e-12, eps 1e-2 had reported
    ``max_steps`` after 50000 steps; St 1e-300 ``step_underflow``). A failed solve's
    observables stay withheld, and its message says how it ended."""
    result.start_strain_energy = float(cols["E_s"][0] / cols["E_k"][0])  # strain over kinetic
    if not result.start_strain_energy > START_STRAIN_LIMIT:
        return
    premise = failure_message("start_deformed", ratio=result.start_strain_energy,
                              limit=START_STRAIN_LIMIT)
    if result.status != "ok":
        premise += f"; the solve then ended: {result.message}"
    result.status, result.message = "start_deformed", premise


def _released_energy(cols):
    """The energy lost by the release: dissipated, done against the floor and lost in the
    solids."""
    return cols["dissipated"][-1] + cols["void_work"][-1] + cols["solid_loss"][-1]


def _own_departure(physics, shortcuts, cols, film):
    """The departure piece's own rigid departure from the coupled phase's release state (its
    film ``film``, a ReleaseFilm) where the plan gives one: ``(x, v, t, series block)``, None
    (the classic departure) or ``pieces.RUN_ON``."""
    own = shortcuts.departure_piece
    if own is None:
        return None
    return own.depart(physics, cols["X"][-1], cols["V"][-1], cols["T"][-1],
                      _released_energy(cols), film)


def _depart(physics, cols, blocks, departed):
    """The rigid departure from the coupled phase's release state, its series appended to
    ``blocks``: a piece's own departure ``departed`` (``_own_departure``, until it hands back to
    the classic path), then the classic closed form; or rest, where a piece holds the spheres
    (e.g. on their asperities: the gap they hold is the equilibrium). Returns ``(ln x_e,
    resting)``."""
    stokes, tau_per_t = physics.St, physics.tau_per_t
    t_rel, x_rel, v_rel = cols["T"][-1], cols["X"][-1], cols["V"][-1]
    lost = _released_energy(cols)
    if departed is not None:
        x_rel, v_rel, t_rel, block = departed
        blocks.append(block)
        lost = block["dissipated"][-1]
    if any(p.rests(physics, v_rel) for p in pieces.PIECES):
        return math.log(float(cols["H_min"][-1])), True
    if math.isinf(x_rel):  # a departure without suction (Pi = 0): the spheres never stop
        return math.inf, False
    ln_x_e = rigid.rest_separation(x_rel, v_rel, stokes)
    u_end = max(-30.0, min(30.0, -0.99 * stokes * v_rel))
    if u_end != 0.0:
        x_tail = x_rel * np.exp(np.linspace(0.0, u_end, 41)[1:])
        t_tail, v_tail = rigid_path(x_rel, v_rel, t_rel, stokes, x_tail)
        blocks.append(rigid_block(t_tail, x_tail, v_tail, tau_per_t, 2,
                                  lost + (v_rel**2 - v_tail**2)))
    return ln_x_e, False


def _drawn_back(physics, cols, x_ref) -> str:
    """The note of a result that sticks although its coupled phase carried the spheres out
    past ``x_ref``: the film drew them back inside it before the phase ended (the suction of
    a film that refills late), so they stick (``e_wet`` 0: ``x_e <= x_ref``; docs/model.md,
    "Observables"); the note gives the speed they passed ``x_ref`` with, and its ``e``, which a
    code that resolves the flow beyond ``x_ref`` without that suction would see. "" when they
    never passed it."""
    speed = _drawn_back_speed(cols["X"], cols["V"], x_ref)
    if speed is None:
        return ""
    e_out = rigid.restitution_of_speed(speed, physics, x_ref)
    return (f"the spheres passed x_ref outwards at {speed:.3g} v0 (e {e_out:.3g} there), out to "
            f"{cols['X'].max() / x_ref:.3g} x_ref, and the film drew them back inside it before "
            "the coupled phase ended: they stick (e_wet 0)")


def _drawn_back_speed(x_c, v_c, x_ref):
    """The speed with which the coupled phase's rows ``x_c``, ``v_c`` last passed ``x_ref``
    outwards when they end back inside it (drawn back), else None."""
    return None if x_c[-1] > x_ref else pieces.outward_crossing(x_c, v_c, x_ref)


def _pulled_back_from_afar(result):
    """Adds to the note of an ok result drawn back inside ``x_ref`` (``_drawn_back``) how far out
    the coupled phase carried the spheres, over the radius ``a`` (the outer flow's ``x0/a``
    places ``x0``), when that is beyond ``LUBRICATION_REACH``: the pull-back came from where the
    lubrication premise ``X << a`` fails, so whether they stick is outside the model (a film that
    refills late, at St 2, eps 1e-2, Pi 1e-10, carries them out to 3.6 ``a`` with ``x0 = 0.01 a``;
    docs/model.md, "Observables")."""
    if not (result.ok and result.e_wet == 0.0):
        return
    coupled = result.series["phase"] == 1
    x_c, v_c = result.series["X"][coupled], result.series["V"][coupled]
    if not x_c.size or _drawn_back_speed(x_c, v_c, result.x_ref_x0 * result.x0_over_x1) is None:
        return
    reach = x_c.max() / result.x0_over_x1 * result.x0_over_a
    if reach > LUBRICATION_REACH:
        _noted(result, f"they were drawn back from X = {reach:.3g} a (x0 = "
                       f"{result.x0_over_a:g} a), beyond the lubrication premise X << a: whether "
                       "they stick is outside the model")


def _wet_restitution(physics, shortcuts, cols, x_ref, film):
    """``e_wet`` at ``x_ref`` from the coupled phase's end: the rigid departure (rigid.restitution)
    from the release state; when the coupled phase ends beyond ``x_ref`` (the deformation relaxed,
    or the film filled again, only after the spheres passed it, moving out or already turned
    back), from the last row inside ``x_ref`` on the way out, so the departure crosses ``x_ref``
    on the rigid path of a state whose deformation is ``O(release)``. (From an end turned back,
    the rigid departure took the end as a state reached rigidly from ``x_ref``: a film with a
    floor at St 3, eps 1e-2, Pi 1e-5 that ran to ``X`` 22.7 before it filled again gave
    ``e_wet`` 0.43 with a largest separation speed ``v_r`` of 0.19; docs/solver.md, Versions,
    1.15.4.)
    A piece whose departure or refill the plan gives reads it its own way
    (``Piece.restitution``; ``film``, the release state's ReleaseFilm). Every rigid departure is
    of spheres apart: where that row's mean planes still overlap (``X <= 0``: surfaces whose
    asperities still unload) and the coupled phase crosses ``x_ref``, its own speed there is read
    (``pieces.crossing_speed``; a departure from ``X <= 0`` took ``ln X`` and raised:
    docs/solver.md, Versions, 1.15.3)."""
    x_c, v_c = cols["X"], cols["V"]
    j = len(x_c) - 1
    if x_c[j] > x_ref:
        inside = np.nonzero((x_c <= x_ref) & (v_c < 0.0))[0]
        if inside.size:
            j = int(inside[-1])
    speed = pieces.crossing_speed(x_c, v_c, x_ref) if x_c[j] <= 0.0 else None
    if speed is not None:
        return rigid.restitution_of_speed(speed, physics, x_ref)
    if shortcuts.reader is not None:
        return shortcuts.reader.restitution(physics, x_c, v_c, j, x_ref, cols, film)
    return rigid.restitution(x_c[j], v_c[j], physics, x_ref)


def _gap_minimum(tau, h_min, h_min_step, order, i, end):
    """The smallest gap near row ``i``, the discrete minimum of ``H_min`` over the rows before
    ``end``: at orders up to 2 the parabola's vertex on rows ``i - 1``, ``i``, ``i + 1``; above,
    the smallest gap of the loop's interpolants over the steps either side of row ``i``
    (``H_min_step``, integration/dense.py: ``extremum_in_step``)."""
    if i <= 0 or i >= end - 1:
        return h_min[i]
    if max(order[i], order[i + 1]) <= 2:
        return _parabolic_peak(tau[:end], h_min[:end], i)[1]
    return min(h_min_step[i], h_min_step[i + 1])


def _gap_observables(result, cols, tau, tau_per_t):
    """The closest approach over the coupled phase and over its approach, and the time ``v``
    first reaches 0; returns the rows where ``v <= 0`` and whether ``v`` first reaches 0 inside
    a step above order 2 (where the loop read the values there: ``T_at_v0``)."""
    v_c, order, h_min, h_min_step = cols["V"], cols["order"], cols["H_min"], cols["H_min_step"]
    result.h_m_x1 = float(_gap_minimum(tau, h_min, h_min_step, order, int(np.argmin(h_min)),
                                       len(h_min)))
    below = np.nonzero(v_c <= 0.0)[0]
    stop_in_step = False
    if below.size:
        # approach phase ends at the interpolated v = 0 between rows j-1 and j: on a straight
        # line at orders up to 2; above, on the step's interpolant, with the smallest gap over
        # the cells there, as the loop read them (integration/stepper.py: _record_step)
        j = int(below[0])
        stop_in_step = bool(np.isfinite(cols["T_at_v0"][j]))
        if stop_in_step:
            result.tau_v_zero = float(cols["T_at_v0"][j] * tau_per_t)
            h_at_stop = cols["H_min_at_v0"][j]
        else:
            frac = v_c[j - 1] / (v_c[j - 1] - v_c[j])
            result.tau_v_zero = float(tau[j - 1] + (tau[j] - tau[j - 1]) * frac)
            h_at_stop = h_min[j - 1] + (h_min[j] - h_min[j - 1]) * frac
        h_app = _gap_minimum(tau, h_min, h_min_step, order, int(np.argmin(h_min[:j])), j)
        result.h_m_approach_x1 = float(min(h_app, h_at_stop))
    else:
        result.tau_v_zero = math.inf  # rigid creep to rest: v reaches 0 only as t -> inf
        result.h_m_approach_x1 = result.h_m_x1
    return below, stop_in_step


def _approach_peak_pressure(result, cols, tau, below, stop_in_step):
    """The largest film pressure over the approach (until ``v`` first reaches 0: the pressure
    spike where a trapped lens collapses later does not converge under refinement) and the
    central gap when it is reached."""
    order, p_max = cols["order"], cols["P_max"]
    j_app = int(below[0]) + 1 if below.size else len(tau)
    i = int(np.argmax(p_max[:j_app]))
    if i == j_app - 1 and stop_in_step:
        # still rising when the approach ends, inside a step above order 2: read at v = 0 (not
        # at the row past it), as the loop read it (integration/stepper.py: _record_step)
        result.p_max_approach = float(cols["P_max_at_v0"][i])
        result.h_axis_at_peak_pressure_x1 = float(cols["H0_at_v0"][i])
    elif 0 < i < j_app - 1 and max(order[i], order[i + 1]) > 2:
        # above order 2, the loop's interpolants of the steps either side of row i (the largest
        # over the cells is not smooth in time; integration/dense.py: extremum_in_step)
        p_step = cols["P_max_step"]
        end = i + 1 if p_step[i + 1] > p_step[i] else i
        result.p_max_approach = float(p_step[end])
        result.h_axis_at_peak_pressure_x1 = float(cols["H0_at_P_max_step"][end])
    else:
        t_pk, p_pk = _parabolic_peak(tau[:j_app], p_max[:j_app], i)
        result.p_max_approach = float(p_pk)
        result.h_axis_at_peak_pressure_x1 = float(np.interp(t_pk, tau, cols["H0"]))


def _coupled_observables(result, cols, tau_per_t, ln_x_e, v_rel):
    """Observables from the coupled phase's series (the rigid parts are monotone: only their
    peaks, ``include_rigid_peaks``, and the creep to ``x_e`` can add to them)."""
    t_c, x_c, v_c, order = cols["T"], cols["X"], cols["V"], cols["order"]
    tau = t_c * tau_per_t
    result.v_r = 0.0
    if np.any(v_c < 0.0):
        i = int(np.argmin(v_c))
        t_pk, v_pk = _peak(tau, v_c, i, order, lowest=True)
        result.v_r = float(-v_pk)
        result.tau_max_rebound = float(t_pk)
    below, stop_in_step = _gap_observables(result, cols, tau, tau_per_t)
    _approach_peak_pressure(result, cols, tau, below, stop_in_step)
    i = int(np.argmin(x_c))
    result.x_min_x1 = float(_peak(tau, x_c, i, order, lowest=True)[1])
    if v_rel > 0.0:  # still approaching when released: rigid creep down to x_e
        x_e = math.exp(ln_x_e)
        result.h_m_x1 = min(result.h_m_x1, x_e)
        result.x_min_x1 = min(result.x_min_x1, x_e)
        if below.size == 0:
            result.h_m_approach_x1 = min(result.h_m_approach_x1, x_e)
    i = int(np.argmax(cols["F"]))
    result.tau_peak_force, result.peak_force = map(
        float, _peak(tau, cols["F"], i, order, lowest=False))
    i = int(np.argmax(cols["W0"]))
    result.tau_max_deformation, result.w0_max_x1 = map(
        float, _peak(tau, cols["W0"], i, order, lowest=False))
    result.p_max = float(np.max(cols["P_max_step"]))  # P_max's rows, and the steps above order 2
    if not result.physics.isoviscous:
        # the spike where a glassy lens collapses later does not converge (it doubled with each
        # preset at St 30, eps 1e-4, beta 5): a pressure-dependent film reports the approach's
        result.p_max = result.p_max_approach
    result.p_min = min(0.0, float(np.min(cols["P_min"])))  # the far field tends to 0
    depth = cols["H0"] - cols["H_min"]
    result.dimple_depth_x1 = float(depth.max())
    deep = np.nonzero(depth > DIMPLE_DEPTH)[0]
    result.dimple = bool(deep.size > 0)
    if deep.size:
        result.tau_dimple = float(tau[deep[0]])
    total = cols["E_k"] + cols["E_s"] + cols["E_c"] + cols["E_a"] + cols["dissipated"] \
        + cols["void_work"] + cols["solid_loss"]
    result.energy_error = float(np.max(np.abs(total - total[0])))
