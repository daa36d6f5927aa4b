"""The whole trajectory: release, approach, the near field, the departure to the top of the bounce.

docs/model.md, "Outer flow: the whole trajectory". SI units throughout (a trajectory is compared
with measured ones in seconds and metres). Outside the near-field start ``x0`` the spheres are
rigid and move along their line of centres; the gap ``x`` (surface to surface) and its rate
``U = dx/dt`` (negative on the approach) obey Lagrange's equation of the relative coordinate
(far_field.py, with the zero-momentum velocities of a pair, outer_flow.pair_velocities):

    M(x) dU/dt + (1/2) M'(x) U^2 = -6 pi mu a R(x, U) U - W,
    M = m (1 + phi C(x)),   R = R_stokes(x) - R_far + R_isolated(Re),

``m``, ``a`` the reduced mass and radius, ``C`` the added mass (outer_flow), ``W`` the buoyant
weight along the line of centres towards contact (``(m1 - rho_f V1) g`` for a sphere above a
wall). Two free spheres under gravity are refused (``TWO_SPHERES_UNDER_GRAVITY``): both fall,
unequal ones each at its own speed through its own drag, so the pair's centre of mass moves and
its drag couples into their relative motion, which the zero-momentum frame of the pair leaves
out (its relative weight ``m g rho_f (1/rho_2 - 1/rho_1)`` gave 0.19x the difference of the
settling speeds of steel and glass spheres of 1 mm diameter in glycerol, and 0 for two glass
spheres of any sizes); equal ones fall together, and a drag law beyond Stokes' at their relative
speed is not the drag of their common fall. The resistance joins the exact Stokes resistance
``R_stokes(x)`` (wall or pair, outer_flow), which holds near contact where the gap's flow is
viscous (its Reynolds number is ``Re x/a``), to the isolated spheres' drag at their Reynolds
numbers: its far-field limit ``R_far`` (each sphere's Stokes drag, ``(a1 s1^2 + a2 s2^2)/a``,
``s_i = m/m_i``) is replaced by ``R_isolated = (a1 s1^2 f(Re1) + a2 s2^2 f(Re2))/a`` with ``f``
the drag law's correction (model/drag.py) and ``Re_i = rho_f |u_i| 2 a_i / mu``. The energy
``E = M U^2/2 + W x`` then falls by the drag's work alone, ``dE/dt = -6 pi mu a R U^2``.

At ``x0`` the near field (``collide``, unchanged) takes over with ``v0`` the arriving speed and
hands back the departure speed ``e0 v0`` (its ``e_x0``); the departure is integrated from ``x0``
until the speed vanishes (the top of the first bounce). The near field keeps the particle's own
mass and no gravity (it lasts microseconds to milliseconds at gaps of micrometres).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import far_field
from .model import drag, outer_flow

__all__ = ["Outer", "Trajectory", "motion", "terminal_speed", "trajectory", "NEAR_FIELD_BUDGET",
           "TWO_SPHERES_UNDER_GRAVITY", "check_release", "frames", "fitted_speed",
           "observed_restitution"]

RTOL = 1e-9  # the outer phase's integrator tolerance (DOP853): 1e-7 in the arrival speed
SUBSTEPS = 16  # samples per integrator step in the returned trajectory
MIN_GAP_OVER_A = 1e-3  # the resistance and added-mass tables' range (far_field.OuterTables)
TWO_SPHERES_UNDER_GRAVITY = (
    "gravity with two free spheres is not modelled: both fall, equal ones together and never "
    "closer, unequal ones each at its own speed through a drag that the pair's relative motion "
    "leaves out (docs/model.md, 'Outer flow: the whole trajectory')")
GEOMETRIES = (None, *outer_flow.GEOMETRIES)  # None: an isolated sphere (no wall, no partner)


@dataclass(frozen=True)
class Outer:
    """The outer motion's bodies and fluid (SI). ``radius2 = mass2 = inf``: a plane wall.

    geometry
        ``"wall"``, ``"spheres"``, ``"pair"`` (outer_flow.GEOMETRIES) or None (an isolated
        sphere: ``radius2``, ``mass2`` ignored; its gap is only a coordinate).
    gravity
        ``g`` [m/s^2] along the line of centres, towards contact (0: none; sphere 1 above); 0
        for two spheres, ``"spheres"`` and ``"pair"`` (``TWO_SPHERES_UNDER_GRAVITY``).
    drag_law
        A name of model/drag.DRAG_LAWS.
    """

    geometry: str | None
    radius1: float
    mass1: float
    radius2: float
    mass2: float
    fluid_density: float
    viscosity: float
    gravity: float = 0.0
    drag_law: str = "stokes"

    def __post_init__(self):
        if self.geometry not in GEOMETRIES:
            raise ValueError(f"geometry = {self.geometry!r}: must be one of {GEOMETRIES}")
        drag.correction(self.drag_law, 0.0)  # the law's name
        if self.geometry in ("spheres", "pair") and self.gravity != 0.0:
            raise ValueError(TWO_SPHERES_UNDER_GRAVITY)
        solo = self.geometry in (None, "wall")
        s1 = 1.0 if solo else self.mass2 / (self.mass1 + self.mass2)
        s2 = 0.0 if solo else self.mass1 / (self.mass1 + self.mass2)
        a = self.radius1 if solo else _reduced(self.radius1, self.radius2)
        object.__setattr__(self, "shares", (s1, s2))
        object.__setattr__(self, "a", a)
        object.__setattr__(self, "m", self.mass1 if solo else _reduced(self.mass1, self.mass2))
        volume1 = 4.0 / 3.0 * math.pi * self.radius1**3
        # the added mass' factor as far_field.OuterFlow defines it (wall and isolated:
        # rho_f V1 / m1; two spheres: rho_f V1 / (2 m))
        object.__setattr__(self, "phi", self.fluid_density * volume1
                           / (self.m if solo else 2.0 * self.m))
        # the buoyant weight of sphere 1 (two free spheres have no gravity here, above)
        weight = (self.mass1 - self.fluid_density * volume1) * self.gravity if solo else 0.0
        object.__setattr__(self, "weight", weight)
        if self.geometry is not None:
            ratios = (self.radius2 / self.radius1, self.mass2 / self.mass1) \
                if self.geometry == "pair" else outer_flow.UNIT_RATIOS
            object.__setattr__(self, "tables", far_field.outer_tables(self.geometry, ratios))
        # R_far: the isolated spheres' Stokes drag in units of 6 pi mu a v
        object.__setattr__(self, "far_resistance", self.isolated_resistance(0.0, "stokes"))

    def isolated_resistance(self, speed: float, law: str | None = None) -> float:
        """``R_isolated``: each sphere's own drag at its Reynolds number, ``6 pi mu a v`` units."""
        law = self.drag_law if law is None else law
        total = 0.0
        for radius, share in zip((self.radius1, self.radius2), self.shares):
            if share:
                re = drag.reynolds(share * speed, radius, self.fluid_density, self.viscosity)
                total += radius * share * share * drag.correction(law, re)
        return total / self.a

    def reynolds_numbers(self, speed: float) -> tuple[float, ...]:
        """The moving spheres' ``Re_i`` at the relative speed ``speed``."""
        return tuple(drag.reynolds(share * speed, radius, self.fluid_density, self.viscosity)
                     for radius, share in zip((self.radius1, self.radius2), self.shares) if share)

    def resistance_and_mass(self, gap: float, speed: float):
        """``(R(x, U), M(x), M'(x))`` at gap ``x = gap`` [m] and speed ``U`` [m/s]."""
        iso = self.isolated_resistance(speed)
        if self.geometry is None:
            return iso, self.m * (1.0 + 0.5 * self.phi), 0.0
        # a trial stage of the integrator can step past the floor event (MIN_GAP_OVER_A) to a
        # gap at or below 0, where ln x is undefined: it sees the floor's values, and the step
        # is rejected or ends on the event (short drops crashed with "math domain error")
        g = min(max(gap / self.a, MIN_GAP_OVER_A), far_field.MAX_OVER_A)
        r, c, dc = self.tables(g)
        dm = self.m * self.phi * dc / self.a if gap / self.a < far_field.MAX_OVER_A else 0.0
        return r - self.far_resistance + iso, self.m * (1.0 + self.phi * c), dm


def _reduced(u, v):
    return 1.0 / (1.0 / u + 1.0 / v)


def terminal_speed(outer: Outer) -> float:
    """The speed at which the drag of the isolated spheres balances ``W``: the root of
    ``6 pi mu a v R_isolated(v) = W`` (closed form ``W / (6 pi mu a R_far)`` for Stokes' law);
    0 without a net weight."""
    from scipy import optimize  # here: scipy is a slow import for the paths that need none

    if outer.weight <= 0.0:
        return 0.0
    k = 6.0 * math.pi * outer.viscosity * outer.a
    stokes = outer.weight / (k * outer.far_resistance)
    if outer.drag_law == "stokes":
        return stokes

    def balance(v):
        return k * v * outer.isolated_resistance(v) - outer.weight

    # the drag grows faster than v: the root lies below Stokes' speed
    return optimize.brentq(balance, 0.0, stokes, xtol=1e-15 * stokes, rtol=1e-15)


def motion(outer: Outer, gap: float, speed: float, *, until_gap: float | None = None,
           duration: float = math.inf):
    """Integrate the outer equation from gap ``gap`` [m] with ``U = speed`` [m/s] until the gap
    reaches ``until_gap``, the speed falls to 0 (on the way out: the top; on the approach: the
    motion stopped short), or ``duration`` [s] has passed.

    Returns ``(t, x, u, loss, ended)``: arrays of times, gaps, speeds and the drag's work so far
    [J], and which end was reached (``"gap"``, ``"top"``, ``"stopped"``, ``"time"``, or
    ``"floor"``: the gap fell below ``MIN_GAP_OVER_A a`` without meeting ``until_gap``).
    """
    from scipy import integrate

    k = 6.0 * math.pi * outer.viscosity * outer.a

    def rhs(_t, y):
        r, mass, dmass = outer.resistance_and_mass(y[0], y[1])
        return [y[1], (-k * r * y[1] - outer.weight - 0.5 * dmass * y[1] ** 2) / mass,
                k * r * y[1] ** 2]

    # which way the gap moves: outwards from a positive speed or towards a gap beyond the start
    outward = speed > 0.0 or (until_gap is not None and until_gap > gap)
    events, names = [], []

    def event(function, direction, name):
        function.terminal, function.direction = True, direction
        events.append(function)
        names.append(name)

    if until_gap is not None:
        event(lambda _t, y: y[0] - until_gap, 1.0 if outward else -1.0, "gap")
    # the speed through 0: the top on the way out, or the approach stopped short
    event(lambda _t, y: y[1], -1.0 if outward else 1.0, "top" if outward else "stopped")
    if outer.geometry is not None:  # below the tables' range: not a motion this model follows
        event(lambda _t, y: y[0] - MIN_GAP_OVER_A * outer.a, -1.0, "floor")
    scale = max(abs(speed), terminal_speed(outer), 1e-12)
    # a time span long enough to end on an event: 1e3 crossings of the release gap at the
    # slower of the starting and terminal speeds, or the duration
    span = min(duration, 1e3 * max(gap, outer.a) / scale)
    sol = integrate.solve_ivp(rhs, (0.0, span), [gap, speed, 0.0], method="DOP853", rtol=RTOL,
                              atol=[RTOL * outer.a, RTOL * scale, RTOL * k * scale * outer.a],
                              events=events, dense_output=True)
    if sol.status < 0:
        raise FloatingPointError(f"outer motion: {sol.message}")
    ended = "time"
    for event, name in zip(sol.t_events, names):
        if len(event):
            ended = name
    # the steps are long where the motion is smooth (tens per phase): the trajectory is the
    # integrator's own interpolant (7th order) at SUBSTEPS points per step, the ends exact
    t = np.concatenate([np.linspace(t0, t1, SUBSTEPS, endpoint=False)
                        for t0, t1 in zip(sol.t[:-1], sol.t[1:])] + [sol.t[-1:]])
    x, u, loss = sol.sol(t)
    x[0], u[0], loss[0] = sol.y[:, 0]
    x[-1], u[-1], loss[-1] = sol.y[:, -1]
    return t, x, u, loss, ended


NEAR_FIELD_BUDGET = ("kinetic", "stored", "lost")  # shares of m v0^2 / 2 at the hand-back


def _near_section(result, x0, v0):
    """The near field's ``(t, x, u)`` [s, m, m/s] from the arrival at ``x0`` to the departure's
    return to ``x0`` (or its end when the spheres stay), and its energy shares there
    (``NEAR_FIELD_BUDGET``) of ``m v0^2/2``."""
    s = result.series
    tau, big_x, v = (np.asarray(s[k], dtype=float) for k in ("tau", "X", "V"))
    stored = sum(np.asarray(s[k], dtype=float) for k in ("E_s", "E_c", "E_a"))
    lost = sum(np.asarray(s[k], dtype=float) for k in ("dissipated", "void_work", "solid_loss"))
    kinetic = np.asarray(s["E_k"], dtype=float)
    x_start = result.physics.x_start
    out = np.nonzero((v < 0.0) & (big_x >= x_start))[0]
    if out.size == 0:
        k, w = len(tau) - 1, 1.0
    else:
        k = int(out[0])
        w = (x_start - big_x[k - 1]) / (big_x[k] - big_x[k - 1])

    def at(col):
        return np.append(col[:k], col[k - 1] + w * (col[k] - col[k - 1]))

    t, speed = at(tau) * x0 / v0, -at(v) * v0
    # the kinetic share of the speed handed back (E_k interpolated linearly would differ from
    # the interpolated V squared at second order; that difference goes to the closure)
    budget = {"kinetic": float(speed[-1] / v0) ** 2 if out.size else float(kinetic[-1]),
              "stored": float(at(stored)[-1]), "lost": float(at(lost)[-1])}
    return t, at(big_x) / x_start * x0, speed, budget


@dataclass
class Trajectory:
    """A whole trajectory (SI): times ``t``, gaps ``gap`` and gap rates ``speed`` (the approach,
    the near field, the departure, joined), where each phase starts (``phases``: name -> first
    index), the arriving speed ``v0`` at ``x0``, the near field's result, the top of the first
    bounce ``rebound_height`` (0 when the spheres stay), the energy budget [J] and ``status``."""

    t: np.ndarray
    gap: np.ndarray
    speed: np.ndarray
    phases: dict
    v0: float
    x0: float
    collision: object
    rebound_height: float
    energy: dict = field(default_factory=dict)
    status: str = "ok"

    @property
    def energy_residual(self) -> float:
        """What the budget fails to close [J]: start - (end + every loss and store)."""
        e = self.energy
        return e["start"] - sum(e[k] for k in ("end", "drag_approach", "drag_departure",
                                               "near_field_lost", "near_field_stored",
                                               "added_mass_handover", "near_field_closure"))


def trajectory(outer: Outer, release_gap: float, release_speed: float, x0: float,
               near_field) -> Trajectory:
    """The whole trajectory from ``release_gap`` [m] with the approach speed ``release_speed``
    [m/s] (>= 0), down to ``x0`` [m], where ``near_field(v0)`` (a callable returning the
    ``Collision`` of the arriving speed ``v0``, e.g. ``collide`` of the scene at ``v0``) takes
    over, then the departure from ``x0`` at ``e_x0 v0`` to the top of the first bounce."""
    check_release(outer, release_gap, release_speed, x0)
    ta, xa, ua, la, ended = motion(outer, release_gap, -release_speed, until_gap=x0)
    if ended != "gap":
        raise ValueError(f"release: the spheres stop before x0 ({ended}); start faster or closer")
    v0 = -float(ua[-1])
    c = near_field(v0)
    tn, xn, un, share = _near_section(c, x0, v0)
    t, gap, speed = [ta, ta[-1] + tn[1:]], [xa, xn[1:]], [ua, un[1:]]
    phases = {"approach": 0, "near_field": len(ta), "departure": len(ta) + len(tn) - 1}
    e0 = float(c.e_x0) if c.ok else math.nan
    mass0 = outer.resistance_and_mass(x0, v0)[1]
    half = 0.5 * outer.m * v0 * v0
    energy = {"start": _energy(outer, release_gap, -release_speed),
              "drag_approach": float(la[-1]), "drag_departure": 0.0,
              "near_field_lost": share["lost"] * half, "near_field_stored": share["stored"] * half,
              # the near field carries the particle's own mass: the potential flow's energy
              # (M(x0) - m) v^2/2 arrives with v0 and leaves with the departure speed
              "added_mass_handover": 0.5 * (mass0 - outer.m) * v0 * v0 * (1.0 - share["kinetic"]),
              "near_field_closure": half * (1.0 - sum(share.values()))}
    rebound = 0.0
    if c.ok and e0 > 0.0 and share["kinetic"] > 0.0:
        td, xd, ud, ld, ended = motion(outer, x0, float(un[-1]))
        t.append(t[0][-1] + tn[-1] + td[1:])
        gap.append(xd[1:])
        speed.append(ud[1:])
        rebound = float(np.max(xd))
        energy["drag_departure"] = float(ld[-1])
        energy["end"] = _energy(outer, xd[-1], ud[-1])
    else:
        # the spheres stay in the near field (which has no gravity: its weight's work is not
        # booked, the end's potential energy is taken at x0)
        energy["end"] = outer.weight * x0 + 0.5 * mass0 * share["kinetic"] * v0 * v0
    return Trajectory(t=np.concatenate(t), gap=np.concatenate(gap), speed=np.concatenate(speed),
                      phases=phases, v0=v0, x0=x0, collision=c, rebound_height=rebound,
                      energy=energy, status=c.status)


def _energy(outer, gap, speed):
    """``M U^2/2 + W x`` [J]."""
    return 0.5 * outer.resistance_and_mass(gap, speed)[1] * speed * speed + outer.weight * gap


def check_release(outer: Outer, release_gap: float, release_speed: float, x0: float) -> None:
    """Refuse a release the outer motion cannot start from, in one line naming the field and its
    range (``ValueError``): the gap in ``(x0, 100 a]``, ``x0 >= 1e-3 a``, a speed ``>= 0`` (or a
    weight that moves the spheres), Reynolds numbers inside the drag law's range."""
    a = outer.a
    if not (math.isfinite(x0) and MIN_GAP_OVER_A * a <= x0):
        raise ValueError(f"x0 = {x0:.3g} m: the near-field start must be at least "
                         f"{MIN_GAP_OVER_A:g} a = {MIN_GAP_OVER_A * a:.3g} m for a trajectory")
    top = far_field.MAX_OVER_A * a
    if not (math.isfinite(release_gap) and x0 < release_gap <= top):
        raise ValueError(f"release_gap = {release_gap:.3g} m: must lie beyond the near-field start "
                         f"x0 = {x0:.3g} m and at most {far_field.MAX_OVER_A:g} a = {top:.3g} m")
    if not (math.isfinite(release_speed) and release_speed >= 0.0):
        raise ValueError(f"release_speed = {release_speed!r} m/s: must be a finite speed >= 0")
    if release_speed == 0.0 and outer.weight <= 0.0:
        raise ValueError("release_speed = 0 m/s: without a net weight towards contact the "
                         "spheres never move; give a release speed > 0")
    fastest = max(release_speed, terminal_speed(outer))
    for re in outer.reynolds_numbers(fastest):
        drag.check_reynolds(outer.drag_law, re, f"the release ({fastest:.3g} m/s)")


# ---- the restitution as experiments read it (docs/model.md, "Reading e as experiments do") -------
READ_WINDOW_OVER_A = 3.0  # the samples fitted: gaps up to 1.5 diameters (3 a) from the wall
READ_GAP_OVER_A = 0.1  # where the fitted speeds are compared
FRAMES_PER_WINDOW = 20  # a computed trajectory is sampled like a film: 20 frames across the window


def frames(t, gap, window, speed):
    """``(t, gap)`` sampled at a uniform interval, ``window / (FRAMES_PER_WINDOW speed)`` (the
    film's frame interval: ``FRAMES_PER_WINDOW`` frames while the sphere crosses the window at
    ``speed``), so that the near field's dense samples do not weigh in the fit."""
    step = window / (FRAMES_PER_WINDOW * speed)
    times = np.arange(t[0], t[-1], step)
    return times, np.interp(times, t, gap)


def fitted_speed(t, gap, window, reading_gap):
    """The speed ``|dx/dt|`` where the least-squares parabola ``gap(t)`` through the samples with
    ``gap <= window`` crosses ``reading_gap`` (the crossing nearest the samples' lowest gap); NaN
    with fewer than 3 such samples."""
    inside = gap <= window
    if np.count_nonzero(inside) < 3:
        return math.nan
    ts, xs = t[inside], gap[inside]
    c2, c1, c0 = np.polyfit(ts - ts[0], xs, 2)
    roots = np.roots([c2, c1, c0 - reading_gap])
    roots = roots[np.isreal(roots)].real
    if roots.size == 0:
        return math.nan
    lowest = ts[np.argmin(xs)] - ts[0]
    root = roots[np.argmin(np.abs(roots - lowest))]
    return abs(2.0 * c2 * root + c1)


def observed_restitution(t, gap, window, reading_gap):
    """``(u_in, u_out, e, rebound)`` read from a sampled trajectory as experiments read theirs:
    split at the first local minimum of the gap (the first contact; that sample itself, which
    may lie on either side of a contact between two frames, is left out of both fits), fit each
    side over the gaps up to ``window`` (the departure only up to the top of the bounce, its
    largest gap), compare the fitted speeds at ``reading_gap``: ``e = u_out / u_in``;
    ``rebound`` the largest gap after the contact (0 when it never rises again). ``u_in`` NaN
    when there are fewer than 3 approach samples (then ``e`` is too)."""
    t, gap = np.asarray(t, dtype=float), np.asarray(gap, dtype=float)
    rising = np.nonzero(np.diff(gap) > 0.0)[0]
    if rising.size == 0:  # it never rises: no bounce
        return fitted_speed(t, gap, window, reading_gap), 0.0, 0.0, 0.0
    k = int(rising[0])
    top = k + int(np.argmax(gap[k:]))
    u_in = fitted_speed(t[:k], gap[:k], window, reading_gap)
    u_out = fitted_speed(t[k + 1:top + 1], gap[k + 1:top + 1], window, reading_gap)
    return u_in, u_out, u_out / u_in, float(gap[top])
