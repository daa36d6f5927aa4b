"""The whole trajectory (solver/trajectory.py, solver/model/drag.py) against closed forms, the
far-field restitution it must reproduce in the Stokes limit, its energy budget and bad input
(docs/model.md, "Outer flow: the whole trajectory")."""

import math

import numpy as np
import pytest

from solver import far_field as ff
from solver import trajectory as tj
from solver.model import drag

G = 9.81


def _sphere(radius=1e-3, density=2500.0):
    return radius, density * 4.0 / 3.0 * math.pi * radius ** 3


def _isolated(law, viscosity, fluid_density=1000.0, gravity=G):
    a, m = _sphere()
    return tj.Outer(None, a, m, math.inf, math.inf, fluid_density, viscosity, gravity, law)


@pytest.mark.parametrize("law, viscosity", [("stokes", 1.0), ("schiller-naumann", 0.01),
                                            ("clift-gauvin", 1e-3)])
def test_far_from_walls_the_motion_reaches_the_terminal_velocity(law, viscosity):
    # an isolated sphere released at rest: after 40 relaxation times M / (6 pi mu a f) the speed
    # is the law's terminal speed to exp(-40) of it; 1e-6 leaves the integrator's 1e-9 (RTOL)
    # and the root's 1e-15 far below
    outer = _isolated(law, viscosity)
    v_t = tj.terminal_speed(outer)
    if law == "stokes":  # closed form: the buoyant weight over 6 pi mu a
        assert v_t == pytest.approx(outer.weight / (6 * math.pi * viscosity * outer.a), rel=1e-15)
    else:  # the law's own root: drag = weight
        re = drag.reynolds(v_t, outer.a, outer.fluid_density, viscosity)
        force = 6 * math.pi * viscosity * outer.a * v_t * drag.correction(law, re)
        assert force == pytest.approx(outer.weight, rel=1e-12)
        assert 1.0 < re < drag.DRAG_LAWS[law].re_max  # the case is inside the law's range
    mass = outer.m * (1.0 + 0.5 * outer.phi)
    relax = mass / (6 * math.pi * viscosity * outer.a)  # the slowest: Stokes' (f >= 1)
    t, x, u, loss, ended = tj.motion(outer, 10.0, 0.0, duration=40.0 * relax)
    assert ended == "time" and t[-1] == pytest.approx(40.0 * relax)
    assert -u[-1] == pytest.approx(v_t, rel=1e-6)


def test_drag_laws_and_their_ranges():
    # the correlations at Re = 100: Schiller-Naumann 1 + 0.15 * 100^0.687 = 3.80; Clift-Gauvin
    # adds 0.0175 Re / (1 + 4.25e4 Re^-1.16) = 0.0827
    assert drag.correction("stokes", 100.0) == 1.0
    assert drag.correction("schiller-naumann", 100.0) == pytest.approx(
        1 + 0.15 * 100 ** 0.687, rel=1e-15)
    assert drag.correction("clift-gauvin", 100.0) - drag.correction("schiller-naumann", 100.0) \
        == pytest.approx(0.0175 * 100 / (1 + 4.25e4 * 100 ** -1.16), rel=1e-12)
    for law in drag.DRAG_LAWS.values():
        drag.check_reynolds(law.name, law.re_max)
        with pytest.raises(ValueError) as info:
            drag.check_reynolds(law.name, 1.01 * law.re_max)
        assert f"drag_law = '{law.name}'" in str(info.value)
        assert f"[0, {law.re_max:g}]" in str(info.value)


def _wall(phi, viscosity=1.0, gravity=0.0):
    a, m = _sphere()
    rho_f = phi * 2500.0
    return tj.Outer("wall", a, m, math.inf, math.inf, rho_f, viscosity, gravity, "stokes")


@pytest.mark.parametrize("phi", [0.0, 0.4])
def test_stokes_limit_arrives_with_v0_from_the_outer_start(phi):
    # Stokes' law, no gravity: released at the outer start with far_field's v_outer_start v0, the
    # sphere arrives at x0 with v0 (the energy form, integrated by quadrature, against the
    # equation of motion integrated in time): 1e-6 (the integrator's 1e-9 per step)
    outer = _wall(phi)
    a, st = outer.a, 20.0
    v0 = st * 6 * math.pi * outer.viscosity * a * a / outer.m
    reading = ff.OuterFlow(geometry="wall", x0_over_a=0.01, start_over_a=1.0,
                           density_ratio=outer.phi)
    start = reading.approach_speed(st) * v0
    _, x, u, _, ended = tj.motion(outer, a, -start, until_gap=0.01 * a)
    assert ended == "gap" and x[-1] == pytest.approx(0.01 * a, rel=1e-12)
    assert -u[-1] == pytest.approx(v0, rel=1e-6)


def test_stokes_limit_without_gravity_reproduces_e_far():
    # today's e_far (departure over approach speed at x_ref, both from the near field's e0 at
    # x0) read off the integrated motion: approach from the outer start to x_ref and x0, the
    # departure from x0 at e0 v0 back to x_ref; Re <= 0.1 at every speed (Stokes' range), to 1e-6
    outer = _wall(2e-4)
    a, st, e0 = outer.a, 15.0, 0.55
    v0 = st * 6 * math.pi * outer.viscosity * a * a / outer.m
    reading = ff.OuterFlow(geometry="wall", x0_over_a=0.01, x_ref_over_a=0.1, start_over_a=1.0,
                           density_ratio=outer.phi)
    start = reading.approach_speed(st) * v0
    tj.check_release(outer, a, start, 0.01 * a)  # inside Stokes' range
    _, _, u_in, _, _ = tj.motion(outer, a, -start, until_gap=0.1 * a)
    _, _, u_out, _, ended = tj.motion(outer, 0.01 * a, e0 * v0, until_gap=0.1 * a)
    assert ended == "gap"
    assert u_out[-1] / -u_in[-1] == pytest.approx(reading.restitution(e0, st), abs=1e-6)


def test_departure_ends_at_the_top():
    # released upwards from x0 with gravity: it ends where the speed vanishes, and the energy
    # M U^2/2 + W x lost equals the drag's work (the integrator's 1e-9, the tables' consistency
    # of C' with C: 1e-6 of the start's kinetic energy)
    outer = _wall(0.3, viscosity=0.05, gravity=G)
    x0 = 0.01 * outer.a
    t, x, u, loss, ended = tj.motion(outer, x0, 0.2, until_gap=None)
    assert ended == "top" and abs(u[-1]) < 1e-9 * 0.2
    start = tj._energy(outer, x0, 0.2)
    assert start - tj._energy(outer, x[-1], u[-1]) == pytest.approx(loss[-1],
                                                                     abs=1e-6 * start)


@pytest.mark.parametrize("gap, speed, x0, needle", [
    (0.0, 0.1, 1e-5, "release_gap = 0 m: must lie beyond the near-field start"),
    (-1e-3, 0.1, 1e-5, "release_gap = -0.001 m"),
    (5e-6, 0.1, 1e-5, "release_gap = 5e-06 m: must lie beyond the near-field start x0 = 1e-05 m"),
    (0.2, 0.1, 1e-5, "at most 100 a = 0.1 m"),
    (1e-3, -0.1, 1e-5, "release_speed = -0.1 m/s: must be a finite speed >= 0"),
    (1e-3, 0.1, 1e-7, "x0 = 1e-07 m: the near-field start must be at least"),
])
def test_bad_release_is_named(gap, speed, x0, needle):
    outer = _wall(0.3, viscosity=1.0, gravity=G)
    with pytest.raises(ValueError) as info:
        tj.check_release(outer, gap, speed, x0)
    assert needle in str(info.value) and "\n" not in str(info.value)


def test_release_outside_the_drag_laws_range_is_named():
    # water and a 2 mm glass bead: settles at Re ~ 700, beyond Stokes' 0.1
    a, m = _sphere()
    outer = tj.Outer("wall", a, m, math.inf, math.inf, 1000.0, 1e-3, G, "stokes")
    with pytest.raises(ValueError) as info:
        tj.check_release(outer, 0.05, 0.0, 1e-5)
    assert "drag_law = 'stokes'" in str(info.value) and "[0, 0.1]" in str(info.value)


def _steel_in_oil():
    # Gondret et al. (2002)'s St 27 run: a 6 mm steel sphere in silicone oil onto a glass wall
    a, m = _sphere(3e-3, 7800.0)
    rho_f = 965.0
    return tj.Outer("wall", a, m, math.inf, math.inf, rho_f, 1.036e-4 * rho_f, G,
                    "schiller-naumann")


def test_whole_trajectory_energy_closes():
    # released at rest 20 a above the wall: start = end + drag (approach, departure) + the near
    # field's losses and stores at the hand-back + the added mass' energy dropped at x0; the
    # outer phases close to 1e-6 of the start (RTOL and the tables' C' against C), the near
    # field to its own closure (booked separately, below the solver's limit)
    from solver import collide
    from solver.collision import ENERGY_CLOSURE_LIMIT
    from solver.physics import Physics

    outer = _steel_in_oil()
    a = outer.a

    def near(v0):
        st = outer.m * v0 / (6 * math.pi * outer.viscosity * a * a)
        return collide(Physics(St=st, eps=1e-4), accuracy="fast")

    tr = tj.trajectory(outer, 20 * a, 0.0, 0.01 * a, near)
    assert tr.status == "ok" and 0.0 < tr.v0 < tj.terminal_speed(outer)
    e = tr.energy
    assert abs(tr.energy_residual) < 1e-6 * e["start"]
    half = 0.5 * outer.m * tr.v0 ** 2
    assert abs(e["near_field_closure"]) < ENERGY_CLOSURE_LIMIT * half
    # every loss is a loss; the bounce is lower than the release; time runs forward
    assert min(e[k] for k in ("drag_approach", "drag_departure", "near_field_lost",
                              "added_mass_handover")) >= 0.0
    assert 0.01 * a < tr.rebound_height < 20 * a
    assert all(t1 > t0 for t0, t1 in zip(tr.t, tr.t[1:]))
    # the near field's last sample is the hand-back at x0, the departure's first lies beyond
    k = tr.phases["departure"]
    assert tr.gap[k - 1] == pytest.approx(0.01 * a, rel=1e-9) and tr.gap[k] > 0.01 * a


def test_the_reading_returns_a_known_speed():
    # a synthetic bounce with constant decelerations (a parabola on each side): the fitted
    # parabola is exact, so the speeds at the reading gap come back to round-off (1e-9)
    import numpy as np

    # contact at t = 0 with the speeds u_c (in) and u_out (out), decelerated by g_in and g_out:
    # the speed at gap x is sqrt(u_c^2 + 2 g_in x) on the way in, sqrt(u_out^2 - 2 g_out x) out
    x_r, u_c, u_out, g_in, g_out = 0.3e-3, 0.5, 0.2, 4.0, 12.0
    t = np.linspace(-0.02, 0.0, 41)
    approach = -u_c * t + 0.5 * g_in * t ** 2
    t2 = np.linspace(0.0, 0.03, 181)[1:]  # through the top, u_out / g_out = 1/60 s (a sample)
    depart = u_out * t2 - 0.5 * g_out * t2 ** 2
    times, gaps = np.concatenate([t, t2]), np.concatenate([approach, depart])
    got_in, got_out, e, top = tj.observed_restitution(times, gaps, 3e-3, x_r)
    assert got_in == pytest.approx(math.sqrt(u_c ** 2 + 2 * g_in * x_r), rel=1e-9)
    assert got_out == pytest.approx(math.sqrt(u_out ** 2 - 2 * g_out * x_r), rel=1e-9)
    assert e == pytest.approx(got_out / got_in, rel=1e-15)
    assert top == pytest.approx(u_out ** 2 / (2 * g_out), rel=1e-12)
    # frames: a uniform film of the same motion reads the same speeds
    ft, fg = tj.frames(times, gaps, 3e-3, u_c)
    assert np.allclose(np.diff(ft), 3e-3 / (tj.FRAMES_PER_WINDOW * u_c))
    # no samples before the contact: no approach speed
    assert math.isnan(tj.observed_restitution(t2, depart, 3e-3, x_r)[0])


# ---- ehd scene --trajectory -----------------------------------------------------------------

def _cli(*args):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "pipeline.cli", "scene", *args],
                          capture_output=True, text=True, timeout=900)


GLYCEROL = "examples/steel_ball_glass_wall_glycerol.toml"


@pytest.mark.parametrize("args, needle", [
    (["--release-gap-over-a", "0.005"], "release_gap = 7.5e-06 m: must lie beyond the near-field"),
    (["--release-gap", "0 m"], "release_gap"),
    (["--release-gap-over-a", "200"], "at most 100 a = 0.15 m"),
    (["--release-speed", "-1 m/s"], "release_speed"),
    (["--release-speed", "2 m/s", "--drag-law", "stokes"], "drag_law = 'stokes': the Reynolds"),
    (["--release-gap", "1 cm", "--release-gap-over-a", "3"], "not both"),
])
def test_cli_bad_release_exits_2_with_one_line(args, needle, tmp_path):
    out = _cli(GLYCEROL, "--trajectory", str(tmp_path / "t.csv"), *args)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in out.stderr
    assert not (tmp_path / "t.csv").exists()


def test_cli_trajectory_never_replaces_what_it_did_not_write(tmp_path):
    """--trajectory over the scene file itself replaced it with the CSV (exit 0; a hostile scan),
    as it would any file or a device: refused before the solve, the file unchanged. Its own CSV
    of an earlier run is replaced."""
    import shutil

    scene = tmp_path / "s.toml"
    shutil.copy(GLYCEROL, scene)
    before = scene.read_bytes()
    (tmp_path / "other.csv").write_text("t,x\n1,2\n")
    for target in (scene, tmp_path / "other.csv", ""):
        out = _cli(str(scene), "--trajectory", str(target), "--accuracy", "fast", "--no-range")
        lines = out.stderr.strip().splitlines()
        assert out.returncode == 2 and len(lines) == 1 and "--trajectory" in lines[0], out.stderr
    assert scene.read_bytes() == before
    # its own CSV (either line end) and an empty file (as mktemp makes) are replaced
    for own, text in (("t.csv", "t_s,gap_m,speed_m_per_s,phase\n"),
                      ("crlf.csv", "t_s,gap_m,speed_m_per_s,phase\r\n"), ("empty.csv", "")):
        (tmp_path / own).write_text(text, newline="")
        out = _cli(str(scene), "--trajectory", str(tmp_path / own), "--accuracy", "fast",
                   "--no-range")
        assert out.returncode in (0, 1), out.stderr
        assert len((tmp_path / own).read_text().splitlines()) > 10
        # the report's last trajectory line names the CSV once it is written
        assert f"  written to {tmp_path / own}" in out.stdout.splitlines()


def test_cli_trajectory_report_is_printed_before_a_full_disk(tmp_path, capsys, monkeypatch):
    """The CSV is written after the report: a full disk (exit 74, one line) loses no number
    computed (the report came only after the write, and was lost; a hostile scan)."""
    import errno

    import pipeline.writes as writes
    from pipeline.cli import main
    from pipeline.errors import EXIT_WRITE

    def full(contents, what):
        raise writes.write_error(OSError(errno.ENOSPC, "No space left on device"), what)

    monkeypatch.setattr(writes, "write_all", full)
    code = main(["scene", GLYCEROL, "--trajectory", str(tmp_path / "t.csv"), "--accuracy",
                 "fast", "--no-range"])
    out, err = capsys.readouterr()
    assert code == EXIT_WRITE and "trajectory: released at" in out and "e_wet" in out, err
    assert len(err.strip().splitlines()) == 1 and "No space left" in err
    assert "written to" not in out  # the CSV was not written: no line says it was


def test_cli_trajectory_of_a_bouncing_sphere(tmp_path):
    # Gondret et al.'s St 152 run settling from 40 a: the CSV (t_s, gap_m, ...), the figure and
    # the JSON keys of the contract; the arriving speed is the scene's v0
    import csv
    import json

    path = tmp_path / "t.csv"
    out = _cli("--material1", "chrome_steel", "--radius1", "1.5 mm", "--wall", "--material2",
               "glass", "--fluid", "silicone_oil_11cst", "--v0", "0.585 m/s", "--accuracy",
               "fast", "--trajectory", str(path), "--release-gap-over-a", "40", "--json",
               "--plot", str(tmp_path / "fig"))
    assert out.returncode in (0, 1), out.stderr
    d = json.loads(out.stdout)
    rows = list(csv.DictReader(path.open()))
    assert {"t_s", "gap_m", "speed_m_per_s", "phase"} <= set(rows[0])
    gaps = [float(r["gap_m"]) for r in rows]
    assert gaps[0] == pytest.approx(40 * 1.5e-3, rel=1e-12)
    assert d["drag_law"] == "schiller-naumann" and d["release_speed_is_settling"]
    assert d["inputs"]["v0_m_per_s"] == pytest.approx(d["arrival_speed_m_per_s"], rel=1e-12)
    assert 0.0 < d["e_observed"] < 1.0 and d["rebound_height_m"] == pytest.approx(
        max(gaps[gaps.index(min(gaps)):]), rel=1e-12)
    assert (tmp_path / "fig" / "trajectory.png").exists()
    # the approach speed at the outer start (1 a) is the trajectory's own there, not the speed
    # the outer flow alone would map from v0 (it knows neither the release nor gravity: a steel
    # ball released at 23 mm/s in glycerol read 2.9 m/s)
    approach = [(float(r["gap_m"]), -float(r["speed_m_per_s"])) for r in rows
                if r["phase"] == "approach"]
    above = max(i for i, (g, _) in enumerate(approach) if g >= 1.5e-3)
    (g1, u1), (g2, u2) = approach[above], approach[above + 1]
    assert d["inputs"]["approach_speed_source"] == "the released trajectory"
    # linear interpolation between two CSV rows (16 samples an integrator step, RTOL 1e-9)
    assert d["approach_speed_m_per_s"] == pytest.approx(
        u1 + (u2 - u1) * (1.5e-3 - g1) / (g2 - g1), rel=1e-6)
    # and so is the results' row under e_far, which had kept the outer flow's map of v0
    assert d["outer_start_speed_m_per_s"] == d["approach_speed_m_per_s"]


def test_report_lines_of_a_trajectory():
    from pipeline.scenes.trajectory import trajectory_summary

    d = {"release_gap_m": 0.06, "release_speed_m_per_s": 0.57, "release_speed_is_settling": True,
         "drag_law": "schiller-naumann", "arrival_speed_m_per_s": 0.536, "e_observed": 0.819,
         "observed_speed_out_m_per_s": 0.456, "observed_speed_in_m_per_s": 0.556,
         "observed_reading_gap_m": 1.5e-4, "rebound_height_m": 9.3e-3}
    text = trajectory_summary(d)
    assert "e_observed = 0.8190" in text and "(settling)" in text
    assert "written to" not in text  # ehd scene says it once the CSV is written
    assert trajectory_summary(d, "t.csv").endswith("\n  written to t.csv")
    assert "top of the first bounce 0.0093 m" in text


def test_the_speeds_line_of_a_trajectory_says_the_release_set_them():
    """With --trajectory the speeds line called v0 "given" and showed the approach speed the
    outer flow maps from it (2.9 m/s for a ball released at 23 mm/s); it now names the
    trajectory, and the trajectory's line the speed the scene gave, which the release replaces."""
    import dataclasses

    from types import SimpleNamespace

    from pipeline.scenes.answer import answer_lines
    from pipeline.scenes.commands import _si_text, load_scene
    from pipeline.scenes.run import scene_keys
    from pipeline.scenes.trajectory import (ON_TRAJECTORY, approach_on_trajectory,
                                            trajectory_summary)

    d = {"verdict": None, "approach_speed_m_per_s": 0.01077, "outer_start_over_a": 1.0,
         "x0_over_a": 0.01, "inputs": {"approach_speed_source": ON_TRAJECTORY,
                                       "approach_speed_m_per_s": None, "v0_m_per_s": 2.236e-4}}
    line = answer_lines(d)[-1]
    assert line == ("speeds: approach 10.77 mm/s at the outer start 1 a (on the released "
                    "trajectory), v0 223.6 µm/s at x0 = 0.01 a (what the release arrives with)")
    d["approach_speed_m_per_s"] = None  # released inside the outer start
    assert "approach - (released inside the outer start 1 a)" in answer_lines(d)[-1]
    scene = load_scene(GLYCEROL, None)
    # nor has the results' row a speed there (it had kept the outer flow's map of v0, 2.9 m/s)
    inside = SimpleNamespace(phases={"near_field": 2}, gap=np.array([7.5e-4, 1e-4, 1.5e-5]),
                             speed=np.array([-0.01, -0.005, -2.2e-4]))
    row = {"outer_start_speed_m_per_s": 2.893, "inputs": {}}
    approach_on_trajectory(row, inside, scene)
    assert row["outer_start_speed_m_per_s"] is None and row["approach_speed_m_per_s"] is None
    key = next(k for _, k in scene_keys() if k.key == "outer_start_speed_m_per_s")
    assert "a release inside the outer start" in _si_text(None, key)
    read = {"release_gap_m": 0.015, "release_speed_m_per_s": 0.0228,
            "release_speed_is_settling": True, "drag_law": "stokes",
            "arrival_speed_m_per_s": 2.236e-4, "e_observed": None,
            "observed_speed_out_m_per_s": None, "observed_speed_in_m_per_s": None,
            "observed_reading_gap_m": 1.5e-4, "rebound_height_m": 0.0}
    first = trajectory_summary(read, replaced=scene).splitlines()[0]
    assert first.endswith(f"(the scene's v0, in place of the given v0 {scene.v0:.4g} m/s)")
    given = dataclasses.replace(scene, approach_speed=0.5, approach_speed_source="given")
    assert "in place of the given approach speed 0.5 m/s" in trajectory_summary(
        read, replaced=given)


@pytest.mark.parametrize("radius2, density2", [(1e-3, 2500.0), (2e-3, 7800.0)])
def test_two_spheres_arrive_with_v0_from_the_outer_start(radius2, density2):
    # two free spheres (equal, or the unequal pair at zero momentum) without gravity: the same
    # check as the wall's, against far_field's "spheres" / "pair" reading (1e-6)
    a1, m1 = _sphere()
    m2 = density2 * 4.0 / 3.0 * math.pi * radius2 ** 3
    geometry = "spheres" if radius2 == a1 and m2 == m1 else "pair"
    outer = tj.Outer(geometry, a1, m1, radius2, m2, 800.0, 1.0, 0.0, "stokes")
    assert outer.weight == 0.0
    a, st = outer.a, 20.0
    v0 = st * 6 * math.pi * outer.viscosity * a * a / outer.m
    ratios = {} if geometry == "spheres" else {"radius_ratio": radius2 / a1,
                                                "mass_ratio": m2 / m1}
    reading = ff.OuterFlow(geometry=geometry, x0_over_a=0.01, start_over_a=1.0,
                           density_ratio=outer.phi, **ratios)
    start = reading.approach_speed(st) * v0
    _, x, u, _, ended = tj.motion(outer, a, -start, until_gap=0.01 * a)
    assert ended == "gap" and -u[-1] == pytest.approx(v0, rel=1e-6)


def test_two_free_spheres_under_gravity_are_refused():
    """Two free spheres both fall: unequal ones each at its own speed through its own drag, which
    the pair's zero-momentum relative motion leaves out (its relative weight gave 0.19x the
    relative settling speed of 1 mm steel and glass spheres in glycerol, and none for two glass
    spheres of different sizes); equal ones together, where a drag law beyond Stokes' at their
    relative speed is not that of their fall. Refused with gravity, under either geometry's
    name (unequal bodies named "spheres" were taken); without gravity both stay."""
    a1, m1 = _sphere()
    for geometry, radius2, density2 in [("pair", 0.5e-3, 2500.0), ("pair", 1e-3, 7800.0),
                                        ("spheres", 1e-3, 2500.0), ("spheres", 0.5e-3, 7800.0)]:
        a2, m2 = _sphere(radius2, density2)
        with pytest.raises(ValueError, match="gravity with two free spheres is not modelled"):
            tj.Outer(geometry, a1, m1, a2, m2, 1000.0, 1e-3, G, "stokes")
        assert tj.Outer(geometry, a1, m1, a2, m2, 1000.0, 1e-3, 0.0, "stokes").weight == 0.0


def test_a_short_drop_reaches_x0_without_leaving_the_tables():
    """A sphere dropped from rest 0.3 a above the wall (a trial stage of the integrator stepped
    to a gap below 0, where ln x is undefined: 'math domain error') reaches x0 = 0.01 a, slower
    than the terminal speed, the gap falling all the way."""
    a, rho_p, rho_f, mu = 1.5e-3, 7800.0, 935.0, 1e-2
    m = rho_p * 4.0 / 3.0 * math.pi * a ** 3
    outer = tj.Outer("wall", a, m, math.inf, math.inf, rho_f, mu, G, "schiller-naumann")
    t, x, u, loss, ended = tj.motion(outer, 0.3 * a, -1e-6, until_gap=0.01 * a)
    assert ended == "gap" and x[-1] == pytest.approx(0.01 * a, rel=1e-9)
    assert np.all(np.diff(x) < 0.0) and 0.0 < -u[-1] < tj.terminal_speed(outer)
