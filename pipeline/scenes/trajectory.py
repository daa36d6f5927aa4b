"""``ehd scene --trajectory``: the whole trajectory from a release, read as experiments read it.

docs/scenes.md, "The whole trajectory". The release (where the sphere starts and how fast) is
given by flags; the outer motion (solver/trajectory.py) brings it down to the scene's ``x0``,
where the scene is solved as usual (``run_scene``) with ``v0`` the arriving speed; the departure
is followed to the top of the first bounce. The trajectory is written as CSV (``t_s``, ``gap_m``,
``speed_m_per_s``, ``phase``) and read for ``e_observed`` and ``rebound_height_m``.
"""

from __future__ import annotations

import dataclasses
import math
import time

from .scene import SceneError
from .scene_file import _GAP, _SPEED
from .units import to_si

__all__ = ["add_trajectory_flags", "trajectory_asked", "run_trajectory", "trajectory_keys",
           "trajectory_csv", "write_trajectory", "check_trajectory_path", "trajectory_summary", "STANDARD_GRAVITY", "DEFAULT_RELEASE_GAP_OVER_A", "DRAG_CHOICES"]

STANDARD_GRAVITY = 9.80665  # m/s^2 (the conventional value; sphere 1 above body 2)
DEFAULT_RELEASE_GAP_OVER_A = 10.0  # where the sphere starts by default: 10 a above the wall
DRAG_CHOICES = ("auto", "stokes", "schiller-naumann", "clift-gauvin")
_FLAGS = ("release_gap", "release_gap_over_a", "release_speed", "drag_law")


def add_trajectory_flags(parser) -> None:
    """The ``--trajectory FILE`` flag and the release's flags of ``ehd scene``."""
    g = parser.add_argument_group(
        "whole trajectory (docs/scenes.md, 'The whole trajectory'); a release flag alone runs "
        "it too, without the CSV: v0 is then the speed the release arrives with")
    g.add_argument("--trajectory", metavar="FILE", default=None,
                   help="compute the whole trajectory from the release and write it as CSV "
                        "(t_s, gap_m, speed_m_per_s, phase); adds e_observed and "
                        "rebound_height_m to the report")
    g.add_argument("--release-gap", dest="release_gap", default=None,
                   help="gap at the release, e.g. '3 cm' (default 10 a)")
    g.add_argument("--release-gap-over-a", dest="release_gap_over_a", default=None,
                   help="gap at the release over the reduced radius a")
    g.add_argument("--release-speed", dest="release_speed", default=None,
                   help="approach speed at the release, e.g. '0.2 m/s', or 'settling' (the "
                        "terminal speed of the drag law, the default)")
    g.add_argument("--drag-law", dest="drag_law", default=None, choices=DRAG_CHOICES,
                   help="the isolated sphere's drag (default auto: the first of stokes, "
                        "schiller-naumann, clift-gauvin whose Reynolds range holds the release)")


def trajectory_asked(args) -> bool:
    """A trajectory is computed when ``--trajectory`` or any release flag is given."""
    return args.trajectory is not None or any(getattr(args, k) is not None for k in _FLAGS)


def _outer(scene, law):
    """The outer motion of ``scene`` under gravity with the drag law ``law``: a sphere onto a wall
    (two free spheres are refused: solver/trajectory.py, ``TWO_SPHERES_UNDER_GRAVITY``)."""
    from solver.trajectory import TWO_SPHERES_UNDER_GRAVITY, Outer

    b1, b2 = scene.body1, scene.body2
    if scene.fluid.density is None:
        raise SceneError("the trajectory needs the fluid's density (fluid.density, e.g. "
                         "'998 kg/m^3'): buoyancy, added mass and the drag's Reynolds number")
    if not b2.wall:  # a sphere 1000x the other's is a wall to e_far only: here both would fall
        raise SceneError(f"{TWO_SPHERES_UNDER_GRAVITY}: make body 2 a wall (--wall), or give "
                         "the approach speed itself (approach_speed or v0) without --trajectory "
                         "and the release flags")
    return Outer("wall", b1.radius, b1.mass, b2.radius, b2.mass, scene.fluid.density,
                 scene.fluid.viscosity, STANDARD_GRAVITY, law)


def _release(scene, args):
    """``(gap [m], speed [m/s] or None for settling, law)`` from the flags."""
    from solver.model import drag

    a = scene.reduced_radius
    if args.release_gap is not None and args.release_gap_over_a is not None:
        raise SceneError("give release_gap or release_gap_over_a, not both")
    if args.release_gap is not None:
        gap = to_si(args.release_gap, _GAP, "release_gap")
    elif args.release_gap_over_a is not None:
        try:
            gap = float(args.release_gap_over_a) * a
        except ValueError:
            raise SceneError(f"release_gap_over_a = {args.release_gap_over_a!r}: must be a "
                             "number (the gap over a)") from None
    else:
        gap = DEFAULT_RELEASE_GAP_OVER_A * a
    text = args.release_speed
    speed = None if text in (None, "settling") else to_si(text, _SPEED, "release_speed")
    law = args.drag_law or "auto"
    if law == "auto":
        law = auto_drag_law(scene, speed)
    return gap, speed, law


def auto_drag_law(scene, speed=None) -> str:
    """The first drag law whose Reynolds range holds the faster of ``speed`` [m/s] and the
    terminal speed (checked again where it is used)."""
    from solver.model import drag

    for name in drag.DRAG_LAWS:
        outer = _outer(scene, name)
        fastest = max(speed or 0.0, _terminal(outer))
        if all(re <= drag.DRAG_LAWS[name].re_max for re in outer.reynolds_numbers(fastest)):
            return name
    return "clift-gauvin"


def settling_arrival(scene) -> tuple:
    """``(terminal speed, speed at x0, speed at the outer start [m/s], drag law)`` of body 1
    settling onto body 2: released at ``DEFAULT_RELEASE_GAP_OVER_A a`` with the drag law's
    terminal speed, followed with gravity, buoyancy, the added mass and the drag joined to the
    exact Stokes resistance (solver/trajectory.py) down to ``x0``; 0 where it stops before (a
    sphere lighter than the fluid rises: refused). An overdamped sphere (``QUASI_STEADY_BELOW``)
    moves at the speed at which the drag balances its weight. The speed at the outer start is
    the settling motion's (beyond the release: the terminal speed), not the outer flow's map of
    ``v0``, which knows no gravity (a steel ball settling in glycerol at 23 mm/s read 2.9 m/s)."""
    from solver.trajectory import motion

    law = auto_drag_law(scene)
    outer = _outer(scene, law)
    terminal = _terminal(outer)
    if not terminal > 0.0:
        raise SceneError("approach_speed = 'settling' needs body1 denser than the fluid (it "
                         "would rise, not settle): give the approach speed itself")
    release = DEFAULT_RELEASE_GAP_OVER_A * scene.reduced_radius
    start = scene.outer_start_distance
    if scene.stokes_of(terminal) < QUASI_STEADY_BELOW:
        return (terminal, _balance_speed(outer, scene.x0, terminal),
                terminal if start >= release else _balance_speed(outer, start, terminal), law)
    _, x, u, _, ended = motion(outer, release, -terminal, until_gap=scene.x0)
    at_start = _approach_speed_where(x, -u, start)  # None: the outer start lies beyond the release
    return (terminal, abs(float(u[-1])) if ended == "gap" else 0.0,
            terminal if at_start is None else at_start, law)


# Below this Stokes number of the terminal speed a settling sphere is overdamped: its inertia
# relaxes in St_V of the time it takes to cross a radius, so it moves at the speed where the drag
# balances its weight, and the explicit integration of the motion (solver/trajectory.py) would
# take ~1/St_V times the steps of an inertial one (a 20 um glass bead in 80 % glycerol-water,
# St_V 1e-5: minutes). The speed it leaves out is a fraction ~St_V of v0.
QUASI_STEADY_BELOW = 1e-2


def _balance_speed(outer, gap: float, terminal: float) -> float:
    """The speed [m/s] at which the drag at ``gap`` balances the buoyant weight (the resistance
    grows near the wall and with the speed: one root below the terminal speed)."""
    from scipy import optimize

    k = 6.0 * math.pi * outer.viscosity * outer.a

    def balance(v):
        return k * v * outer.resistance_and_mass(gap, -v)[0] - outer.weight

    return optimize.brentq(balance, 0.0, terminal, xtol=1e-15 * terminal, rtol=1e-13)


def _terminal(outer):
    from solver.trajectory import terminal_speed

    return terminal_speed(outer)


def run_trajectory(scene, args, accuracy, **overrides):
    """``(SceneResult at the arriving speed, solver Trajectory, reading dict, timings)``; bad
    release input raises ``SceneError`` (one line naming the field and its range)."""
    from solver import trajectory as tj

    from .run import run_scene

    check_trajectory_path(args.trajectory)
    gap, speed, law = _release(scene, args)
    outer = _outer(scene, law)
    start = _terminal(outer) if speed is None else speed
    try:
        tj.check_release(outer, gap, start, scene.x0)
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    results = []

    def near_field(v0):
        # the arriving speed is the scene's v0 (not one mapped from an approach speed)
        results.append(run_scene(dataclasses.replace(scene, v0=v0, approach_speed=None),
                                 accuracy=accuracy,
                                 **overrides))
        return results[-1].collision

    wall = time.perf_counter()
    try:
        tr = tj.trajectory(outer, gap, start, scene.x0, near_field)
    except ValueError as exc:
        raise SceneError(str(exc)) from None
    wall = time.perf_counter() - wall
    a = scene.reduced_radius
    window, reading = tj.READ_WINDOW_OVER_A * a, tj.READ_GAP_OVER_A * a
    ft, fg = tj.frames(tr.t, tr.gap, window, tr.v0)
    u_in, u_out, e, _ = tj.observed_restitution(ft, fg, window, reading)
    read = {"release_gap_m": gap, "release_speed_m_per_s": start,
            "release_speed_is_settling": speed is None, "drag_law": law,
            "arrival_speed_m_per_s": tr.v0, "e_observed": e,
            "observed_speed_in_m_per_s": u_in, "observed_speed_out_m_per_s": u_out,
            "observed_window_m": window, "observed_reading_gap_m": reading,
            "rebound_height_m": tr.rebound_height,
            "trajectory_energy_J": dict(tr.energy), "trajectory_energy_residual_J":
                tr.energy_residual}
    timings = {"trajectory_s": wall, "near_field_s": tr.collision.wall_s}
    return results[-1], tr, read, timings


# the approach speed's source in ``inputs`` where it is read off the released trajectory
ON_TRAJECTORY = "the released trajectory"


def approach_on_trajectory(d: dict, tr, scene) -> None:
    """Set the approach speed of ``ehd scene``'s JSON object ``d`` (``approach_speed_m_per_s``,
    the speed at the outer start, with its source, and the results' ``outer_start_speed_m_per_s``)
    to the released trajectory ``tr``'s."""
    d["approach_speed_m_per_s"] = _speed_at(tr, scene.outer_start_distance)
    d["inputs"]["approach_speed_source"] = ON_TRAJECTORY
    # the results' row too, not the outer flow's map of v0
    d["outer_start_speed_m_per_s"] = d["approach_speed_m_per_s"]


def _speed_at(tr, gap: float) -> float | None:
    """The approach speed [m/s] of the trajectory ``tr`` where its gap first comes down to ``gap``
    (None when it is released inside it): the speed at the outer start, in place of the one
    that would arrive at ``x0`` with ``v0`` through the outer flow alone, which knows neither
    the release nor gravity (a steel ball released at 23 mm/s read 2.9 m/s there)."""
    end = tr.phases["near_field"]
    return _approach_speed_where(tr.gap[:end], -tr.speed[:end], gap) if end else None


def _approach_speed_where(gaps, speeds, gap: float) -> float | None:
    """The speed [m/s] where an approach's ``gaps`` (falling, with its ``speeds``) come down to
    ``gap``; None where it starts inside it. The samples are the integrator's own interpolant
    at ``SUBSTEPS`` points a step (solver/trajectory.py), so a straight line between two is
    close: 2.5e-8 of the speed an integration ended at the gap gives (a steel ball settling in
    glycerol, at 1 a)."""
    import numpy as np

    if gaps[0] < gap:
        return None
    # the approach's gap falls monotonically: interpolate in it, reversed to increase
    return float(np.interp(gap, gaps[::-1], speeds[::-1]))


def trajectory_keys(read: dict) -> dict:
    """The JSON keys a trajectory adds to ``ehd scene --json`` (docs/scenes.md): finite numbers
    or null."""
    def num(v):
        if isinstance(v, dict):
            return {k: num(x) for k, x in v.items()}
        if isinstance(v, (bool, str)) or v is None:
            return v
        return float(v) if math.isfinite(v) else None

    return {k: num(v) for k, v in read.items()}


def _replacing(scene) -> str:
    """``, in place of the given ...`` for the speed the scene was given, which the release
    replaces (a settling approach is the release's own default: nothing replaced)."""
    if scene is None:
        return ""
    if scene.approach_speed is not None and scene.approach_speed_source == "given":
        return f", in place of the given approach speed {scene.approach_speed:.4g} m/s"
    if scene.approach_speed is None and scene.v0 is not None:
        return f", in place of the given v0 {scene.v0:.4g} m/s"
    return ""


def trajectory_csv(tr) -> str:
    """The trajectory as CSV text: ``t_s,gap_m,speed_m_per_s,phase`` (``speed`` the gap's
    rate, negative on the approach)."""
    names = sorted(tr.phases, key=tr.phases.get)
    starts = [tr.phases[n] for n in names]
    rows = [CSV_HEADER]
    phase = 0
    for k, (t, x, u) in enumerate(zip(tr.t, tr.gap, tr.speed)):
        while phase + 1 < len(starts) and k >= starts[phase + 1]:
            phase += 1
        rows.append(f"{t:.9e},{x:.9e},{u:.9e},{names[phase]}")
    return "\n".join(rows) + "\n"


CSV_HEADER = "t_s,gap_m,speed_m_per_s,phase"  # the first line of a trajectory's CSV


def _written_by_trajectory(path) -> bool:
    """Whether the regular file at ``path`` is empty (nothing to lose) or starts as a
    trajectory's CSV does (``CSV_HEADER``, its line ended either way)."""
    try:
        with open(path, "rb") as f:
            start = f.read(len(CSV_HEADER) + 2)
    except OSError:
        return False
    return not start or start.splitlines()[0] == CSV_HEADER.encode()


def check_trajectory_path(path) -> None:
    """PathError before any solve when ``--trajectory FILE`` cannot be written (no name, a missing
    or read-only folder, a folder where the file should be), or names something that is not an
    earlier trajectory's CSV (a scene file, a device, a link: replaced, it would be lost)."""
    import os
    from pathlib import Path

    from ..errors import PathError

    if path is None:
        return
    if not str(path).strip():
        raise PathError("--trajectory: the file name is empty; give the CSV file to write")
    parent = Path(path).parent
    if not parent.is_dir():
        raise PathError(f"--trajectory {path}: the directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise PathError(f"--trajectory {path}: the directory {str(parent)!r} is not writable")
    from ..cli_shared import probe_writable

    probe_writable("--trajectory", path, parent)
    if Path(path).is_dir():
        raise PathError(f"--trajectory {path}: is a directory, not a file")
    if os.path.lexists(path) and (os.path.islink(path) or not Path(path).is_file()
                                  or not _written_by_trajectory(path)):
        raise PathError(f"--trajectory {path}: exists and is not an earlier trajectory's CSV (a "
                        "scene file, someone else's file, a device or a link), so it is not "
                        "replaced: give a new path, or move it away yourself")


def write_trajectory(whole, args, failed) -> None:
    """Write the CSV (``--trajectory``; the text report's line naming it follows its write, so a
    failed write, or a failed figure after it, never follows a line that is not true) and the
    figure (``--plot``) of a computed trajectory (its JSON keys: ``trajectory_keys``)."""
    tr, read, timings = whole
    if args.trajectory is not None:
        from ..writes import write_all

        write_all({args.trajectory: trajectory_csv(tr)}, "--trajectory")
        if not args.json:  # the report's line on it, once it is written
            print(f"  written to {args.trajectory}")
    if args.plot and not failed:
        from ..plots.trajectory_plot import plot_trajectory
        from ..writes import guarded_dir

        with guarded_dir(args.plot, f"--plot {args.plot}"):
            plot_trajectory(tr, args.plot, reading=read)


def trajectory_summary(d: dict, path=None, replaced=None) -> str:
    """The report's lines on the trajectory (``d`` the JSON object with ``trajectory_keys``), and
    one naming the CSV at ``path`` if given: ``ehd scene`` leaves it out and says it once the CSV
    is written (``write_trajectory``). ``replaced``: the scene as given, whose own speed (v0 or
    the approach speed, from its file or a flag) the release replaces, said on the first line."""
    def num(v, spec):
        return "-" if v is None else format(v, spec)

    speed = num(d["release_speed_m_per_s"], ".4g")
    lines = [f"trajectory: released at {num(d['release_gap_m'], '.4g')} m with {speed} m/s"
             f"{' (settling)' if d['release_speed_is_settling'] else ''}, drag "
             f"{d['drag_law']}; arrives at x0 with {num(d['arrival_speed_m_per_s'], '.4g')} m/s "
             f"(the scene's v0{_replacing(replaced)})",
             f"  e_observed = {num(d['e_observed'], '.4f')} (speeds "
             f"{num(d['observed_speed_out_m_per_s'], '.4g')} / "
             f"{num(d['observed_speed_in_m_per_s'], '.4g')} m/s at "
             f"{num(d['observed_reading_gap_m'], '.3g')} m), top of the first bounce "
             f"{num(d['rebound_height_m'], '.4g')} m"]
    if path is not None:
        lines.append(f"  written to {path}")
    return "\n".join(lines)
