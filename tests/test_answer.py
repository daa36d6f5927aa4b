"""The answer users bring a scene for (issue 26): the approach speed as an input, the same physics
however the liquid is given, and the verdict with the e per code kind and its range."""

import dataclasses
import json
import math

import pytest

from pipeline.cli import main
from pipeline.scenes import answer as answer_module
from pipeline.scenes.materials import ROUGHNESS_CLASSES, load_table, roughness_class_value
from pipeline.scenes.run import RESULT_KEYS, run_scene
from pipeline.scenes.scene import SceneError
from pipeline.scenes.scene_file import scene_from_dict
from solver.far_field import OuterFlow


@pytest.fixture(scope="module")
def table():
    return load_table(user_files=False)


def beads(**top):
    """2 mm glass beads onto a steel plate in water (issue 26's first scene)."""
    data = {"approach_speed": "0.15 m/s",
            "body1": {"material": "glass", "radius": "1 mm"},
            "body2": {"material": "steel", "wall": True},
            "fluid": {"name": "water"}}
    data.update(top)
    return data


# ---- the approach speed -----------------------------------------------------------------------
def test_approach_speed_arrives_at_x0_with_the_v0_that_reads_back_as_it(table):
    scene = scene_from_dict(beads(), table)
    assert scene.approach_speed == 0.15 and 0.0 < scene.v0 < 0.15
    # the mapping is the exact inverse of the outer flow's reading of v0 (one closed form each
    # way: rounding only, 1e-12)
    outer = scene.outer_flow()
    assert outer.approach_speed(scene.stokes) * scene.v0 == pytest.approx(0.15, rel=1e-12)
    d = run_scene(scene, accuracy="fast").to_dict()
    assert d["approach_speed_m_per_s"] == 0.15
    assert d["outer_start_speed_m_per_s"] == pytest.approx(0.15, rel=1e-12)
    # a scene given that v0 reports the same approach speed
    given_v0 = {k: v for k, v in beads().items() if k != "approach_speed"} | {"v0": scene.v0}
    same = scene_from_dict(given_v0, table)
    d_v0 = run_scene(same, accuracy="fast").to_dict()
    assert d_v0["approach_speed_m_per_s"] == pytest.approx(0.15, rel=1e-12)
    assert d_v0["e_far"] == d["e_far"]  # the same collision


def test_an_approach_too_slow_for_the_outer_flow_stops_before_x0(table, capsys):
    scene = scene_from_dict(beads(approach_speed="1 mm/s"), table)
    assert scene.stops_outside and scene.v0 == 0.0
    outer = scene.outer_flow()
    st_v = scene.stokes_of(scene.approach_speed)
    stop = outer.stopping_gap(st_v)
    assert outer.x0_over_a < stop < outer.start_over_a
    # where it stops, an outer flow starting there is just reached: arrival speed 0 (the
    # bisection's 1e-10 in ln x moves the integral by ~1e-10 of its size)
    at_stop = dataclasses.replace(outer, x0_over_a=stop, x_ref_over_a=stop)
    assert abs(at_stop.arrival_speed(st_v)) < 1e-8
    with pytest.raises(ValueError, match="reach x0"):
        scene_from_dict(beads(), table).outer_flow().stopping_gap(
            scene.stokes_of(0.15))
    assert main(["scene", "--material1", "glass", "--radius1", "1 mm", "--material2", "steel",
                 "--wall", "--fluid", "water", "--approach-speed", "1 mm/s", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert tuple(d) == RESULT_KEYS
    assert d["verdict"] == "sticks" and d["e_for_dem"] == 0.0 and d["e_for_cfd_dem"] == 0.0
    assert f"{stop:.3g} a" in d["message"] and d["closest_approach_nm"] is None


def test_speed_input_errors_are_one_line(table, tmp_path, capsys):
    with pytest.raises(SceneError, match="either v0 .* or approach_speed"):
        scene_from_dict(beads(v0="0.1 m/s"), table)
    with pytest.raises(ValueError, match="approach_speed"):
        scene_from_dict(beads(approach_speed="-1 m/s"), table)
    # two unequal spheres map it through their own outer flow (geometry "pair")
    unequal = scene_from_dict(beads(body2={"material": "glass", "radius": "2 mm"}), table)
    assert unequal.outer_flow().geometry == "pair"
    assert unequal.outer_flow().approach_speed(unequal.stokes) * unequal.v0 == \
        pytest.approx(0.15, rel=1e-12)
    # a flag for one speed replaces the file's other speed
    path = tmp_path / "s.toml"
    path.write_text('v0 = "0.1 m/s"\n[body1]\nmaterial = "glass"\nradius = "1 mm"\n'
                    '[body2]\nmaterial = "steel"\nwall = true\n[fluid]\nname = "water"\n')
    assert main(["scene", str(path), "--approach-speed", "0", "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "approach_speed" in err


# ---- the liquid given by numbers --------------------------------------------------------------
def test_a_liquid_by_its_numbers_is_switched_as_the_named_one(table):
    named = {"name": "glycerol_water_50", "viscosity": "10.8 mPa s", "density": "1150 kg/m^3"}
    numbers = {"viscosity": "10.8 mPa s", "density": "1150 kg/m^3"}
    top = {"approach_speed": "0.3 m/s", "body1": {"material": "glass", "radius": "1 mm"},
           "body2": {"material": "glass", "radius": "1 mm"}}
    a = run_scene(scene_from_dict(top | {"fluid": named}, table), accuracy="fast")
    b = run_scene(scene_from_dict(top | {"fluid": numbers}, table), accuracy="fast")
    assert b.scene.cavitation_pressure == 0.0 and "assumed" in b.cavitation_reason
    pa, pb = a.collision.physics, b.collision.physics
    assert (pa.cavitation, pa.viscosity_law, pa.density_law, pa.smooth) == \
        (pb.cavitation, pb.viscosity_law, pb.density_law, pb.smooth)
    assert pa.cavitation != "off"
    # the two differ only in p_cav (1.96 kPa named, 0 assumed: Pi 1.9 % apart), which moves
    # e_far by far less than the 0.60 against 0.40 of the floor switched or not
    assert b.collision.e_far == pytest.approx(a.collision.e_far, abs=0.02)


# ---- the answer and its range -----------------------------------------------------------------
def test_roughness_classes_parse_and_bad_ones_are_refused(table):
    s = scene_from_dict(beads(body2={"material": "steel", "wall": True,
                                     "roughness": "As-Received"}), table)
    assert s.body2.solid.roughness_class == "as received"
    lo, hi = ROUGHNESS_CLASSES["as received"]
    assert s.body2.solid.roughness == pytest.approx(math.sqrt(lo * hi), rel=1e-15)
    assert roughness_class_value("polished") < roughness_class_value("as received")
    with pytest.raises(SceneError, match="surface class"):
        scene_from_dict(beads(body2={"material": "steel", "wall": True,
                                     "roughness": "shiny"}), table)


def test_ranges_envelope_the_drivers_and_name_them(table):
    scene = scene_from_dict(beads(), table)
    r = run_scene(scene, accuracy="fast", ranges=True)
    d = r.to_dict()
    assert d["verdict"] == "rebounds" and d["e_for_dem"] == r.collision.e_far
    assert d["e_for_cfd_dem"] == r.collision.e_wet
    drivers = {x["unknown"]: x for x in d["range_drivers"]}
    # steel has no roughness: the unknown band; water: the cavitation onset; water's alpha is
    # known (0), so no pressure-viscosity driver
    assert set(drivers) == {"roughness", "cavitation onset", "reading distance"}
    assert "body2 (steel) unknown" in drivers["roughness"]["detail"]
    for key in ("e_for_dem", "e_for_cfd_dem"):
        lo, hi = d[f"{key}_range"]
        ends = [v for x in drivers.values() if x[key] for v in x[key]]
        assert lo == min(ends + [d[key]]) and hi == max(ends + [d[key]])
    assert sum(x["share"] for x in drivers.values()) == pytest.approx(1.0, rel=1e-12)
    # the reading distance: e_far of the same collision read at the band's ends
    outer, c = r.outer, r.collision
    reads = [dataclasses.replace(outer, x_ref_over_a=x).restitution(c.e_x0, c.physics.St)
             for x in answer_module.READING_BAND_OVER_A]
    assert drivers["reading distance"]["e_for_dem"] == [min(reads), max(reads)]
    # full tension keeps more of the rebound than a gas-saturated floor
    cav = drivers["cavitation onset"]["e_for_dem"]
    assert cav[0] < cav[1]
    # a roughness given as a number is known: no roughness driver
    known = scene_from_dict(beads(body2={"material": "steel", "wall": True,
                                         "roughness": "0.2 um"}), table)
    names = [x["unknown"] for x in run_scene(known, accuracy="fast", ranges=True)
             .to_dict()["range_drivers"]]
    assert "roughness" not in names


def test_report_leads_with_the_verdict_and_the_e_per_code(capsys):
    assert main(["scene", "--material1", "glass", "--radius1", "1 mm", "--material2", "steel",
                 "--wall", "--fluid", "water", "--approach-speed", "0.15 m/s",
                 "--accuracy", "fast"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("verdict: the spheres rebound")
    assert lines[1].startswith("e for a dry DEM code (e_far): ") and ", range " in lines[1]
    assert lines[2].startswith("e for a resolved CFD-DEM code (e_wet): ")
    assert any(line.startswith("speeds: approach 150 mm/s") for line in lines[:6])


def test_no_range_skips_the_solves(monkeypatch, capsys):
    calls = []
    real = answer_module._solve
    monkeypatch.setattr(answer_module, "_solve", lambda *a: calls.append(a) or real(*a))
    assert main(["scene", "--material1", "glass", "--radius1", "1 mm", "--material2", "steel",
                 "--wall", "--fluid", "water", "--v0", "0.15 m/s", "--accuracy", "fast",
                 "--json", "--no-range"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert calls == [] and d["e_for_dem_range"] is None and d["verdict"] == "rebounds"


# ---- restitution curves in the e each code needs, along the approach speed ---------------------
def test_a_path_in_approach_speed_keeps_each_scene_at_its_factor(table):
    from pipeline.dem.export import path_value, scene_path

    scene = scene_from_dict(beads(), table)
    path = scene_path(scene, "approach_speed", [0.5, 1.0, 2.0])
    for f, s in zip((0.5, 1.0, 2.0), path):
        assert s.approach_speed == pytest.approx(0.15 * f, rel=1e-15)
        # each mapped again through the outer flow (its St moves with the speed)
        assert s.outer_flow().approach_speed(s.stokes) * s.v0 == pytest.approx(0.15 * f,
                                                                               rel=1e-12)
    # a scene given v0 has the approach speed its v0 reads back as
    given_v0 = {k: v for k, v in beads().items() if k != "approach_speed"} | {"v0": path[1].v0}
    assert path_value(scene_from_dict(given_v0, table), "approach_speed") == \
        pytest.approx(0.15, rel=1e-12)
    # along the size, the approach speed is kept and v0 mapped again
    bigger = scene_path(scene, "radius", [2.0])[0]
    assert bigger.approach_speed == 0.15 and bigger.v0 != scene.v0


def test_thresholds_in_e_far_and_e_wet_bracket_the_change(table, tmp_path, capsys):
    from pipeline.dem.export import scene_path
    from pipeline.scenes.threshold import RTOL, format_threshold, sticking_threshold
    from pipeline.scenes.units import format_quantity

    scene = scene_from_dict(beads(approach_speed="0.05 m/s", body1={
        "material": "glass", "radius": "100 um"}), table)
    for key in ("e_far", "e_wet"):
        t = sticking_threshold(scene, "approach_speed", "fast", start=0.5, stop=8.0, n=5,
                               key=key)
        assert t.St_c is not None and t.key == key
        below, above = scene_path(scene, "approach_speed",
                                  [t.bracket[0] * (1 - RTOL), t.bracket[1] * (1 + RTOL)])
        assert getattr(run_scene(below, accuracy="fast").collision, key) == 0.0
        assert getattr(run_scene(above, accuracy="fast").collision, key) > 0.0
        assert t.value == pytest.approx(0.05 * t.factor, rel=1e-12)
        # the line gives v0 there too, which the path moved (docs/scenes.md: "each St_c with
        # its v0, approach speed (or radius)"; it gave the approach speed alone)
        at = scene_path(scene, "approach_speed", [t.factor])[0]
        assert f", v0 {format_quantity(at.v0, 'm/s')}" in format_threshold(t)
    # the dry DEM code's threshold lies above the CFD-DEM code's: the outer flow takes more
    wet = sticking_threshold(scene, "approach_speed", "fast", start=0.5, stop=8.0, n=5)
    far = sticking_threshold(scene, "approach_speed", "fast", start=0.5, stop=8.0, n=5,
                             key="e_far")
    assert far.St_c > wet.St_c
    # the command: a factor too slow to reach x0 is listed as sticking, both thresholds printed
    code = main(["restitution", "--accuracy", "fast", "--vary", "approach_speed", "--from",
                 "0.02", "--to", "8", "--n", "4", "--threshold", "--plot",
                 str(tmp_path / "fig"), _scene_file(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0
    assert "approach_speed x 0.02: sticks, the outer flow stops the spheres before x0" in out
    assert "sticking threshold in e_far (dry DEM): St_c = " in out
    assert "sticking threshold in e_wet (resolved CFD-DEM): St_c = " in out
    assert (tmp_path / "fig" / "restitution.png").stat().st_size > 1000


def _scene_file(tmp_path):
    path = tmp_path / "beads.toml"
    path.write_text('approach_speed = "0.05 m/s"\n[body1]\nmaterial = "glass"\n'
                    'radius = "100 um"\n[body2]\nmaterial = "steel"\nwall = true\n'
                    '[fluid]\nname = "water"\n')
    return str(path)


def test_a_rough_scene_ranges_over_the_asperity_stiffness_from_its_sensitivity(table):
    from pathlib import Path

    from pipeline.scenes.commands import load_scene

    air = Path(__file__).resolve().parent.parent / "examples" / "glass_bead_wall_air.toml"
    r = run_scene(load_scene(str(air)), accuracy="fast", ranges=True)
    assert not r.collision.physics.smooth  # the example switches the asperity contact on
    (driver,) = [d for d in r.answer["range_drivers"] if d["unknown"] == "asperity stiffness"]
    rows = [r.sensitivity[k] for k in answer_module.STIFFNESS_LABELS]
    wet = [x["e_wet"] for x in rows] + [float(r.collision.e_wet)]
    assert driver["e_for_cfd_dem"] == [min(wet), max(wet)]


# ---- what a hostile run found (issue 26 review) -----------------------------------------------
def test_both_speed_flags_are_refused(capsys):
    assert main(["scene", "--material1", "glass", "--radius1", "1 mm", "--material2", "steel",
                 "--wall", "--fluid", "water", "--approach-speed", "0.3", "--v0", "0.1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "either --v0" in err and "not both" in err


def test_a_roughness_end_above_x0_is_left_out_with_its_reason(table):
    # a 50 um bead: x0 = 0.5 um, below the 2 um top of the unknown band of the steel plate
    scene = scene_from_dict(beads(approach_speed="2 m/s",
                                  body1={"material": "glass", "radius": "50 um"}), table)
    r = run_scene(scene, accuracy="fast", ranges=True)
    (rough,) = [d for d in r.answer["range_drivers"] if d["unknown"] == "roughness"]
    assert rough["status"].startswith("failed (high: not solved: the rms roughness")
    assert "not below the film's start x0" in rough["status"]


def test_a_gas_typed_by_its_numbers_gets_a_gas_physics(table):
    air = {"v0": "10 cm/s", "body1": {"material": "glass", "radius": "50 um"},
           "body2": {"material": "glass", "wall": True},
           "fluid": {"viscosity": "18.32 uPa s", "density": "1.19 kg/m^3"}}
    scene = scene_from_dict(air, table)
    assert scene.fluid.gas and scene.cavitation_pressure is None
    assert "a gas film does not cavitate" in scene.cavitation_pressure_source
    named = scene_from_dict(air | {"fluid": {"name": "air"}}, table)
    assert named.cavitation_pressure is None  # the same switch as the named air


def test_stopped_scene_ranges_follow_no_range_and_v0_paths_are_refused(tmp_path, capsys):
    flags = ["--material1", "glass", "--radius1", "1 mm", "--material2", "steel", "--wall",
             "--fluid", "water", "--approach-speed", "1 mm/s", "--json"]
    assert main(["scene", *flags, "--no-range"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["verdict"] == "sticks" and d["e_for_dem_range"] is None
    path = tmp_path / "stop.toml"
    path.write_text('approach_speed = "1 mm/s"\n[body1]\nmaterial = "glass"\nradius = "1 mm"\n'
                    '[body2]\nmaterial = "steel"\nwall = true\n[fluid]\nname = "water"\n')
    assert main(["restitution", str(path), "--n", "3", "--accuracy", "fast"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--vary approach_speed" in err


def test_restitution_range_needs_a_plot_and_fit_range_is_finite(capsys):
    from pathlib import Path

    example = str(Path(__file__).resolve().parent.parent / "examples" / "glass_beads_water.toml")
    assert main(["restitution", example, "--n", "3", "--range"]) == 2
    assert "give --plot DIR" in capsys.readouterr().err
    assert main(["export-dem", example, "--n", "3", "--fit-range", "15", "inf"]) == 2
    assert "both finite" in capsys.readouterr().err


def test_a_tiny_rebound_is_not_shown_as_zero():
    from pipeline.scenes.answer import _e3

    assert _e3(1.1e-4) == "0.00011" and _e3(0.0) == "0.000" and _e3(0.7584) == "0.758"


def test_a_settling_approach_is_the_terminal_speed_and_arrives_slowed(table):
    """approach_speed = "settling": Stokes' terminal speed in the Stokes regime (closed form,
    2 (rho_p - rho_f) g a^2 / (9 mu), to the root finder's 1e-12), and v0 below it: the wall
    slows the sphere on its way from 10 a to x0."""
    from pipeline.scenes.trajectory import STANDARD_GRAVITY

    top = {"approach_speed": "settling", "body1": {"material": "glass", "radius": "20 um"},
           "body2": {"material": "glass", "wall": True},
           "fluid": {"name": "glycerol_water_80"}}
    scene = scene_from_dict(top, table)
    rho_p, rho_f, mu = scene.body1.solid.density, scene.fluid.density, scene.fluid.viscosity
    stokes = 2.0 * (rho_p - rho_f) * STANDARD_GRAVITY * 20e-6 ** 2 / (9.0 * mu)
    assert scene.approach_speed_source.startswith("settling (stokes drag")
    assert scene.approach_speed == pytest.approx(stokes, rel=1e-9)
    assert 0.0 < scene.v0 < scene.approach_speed
    # a sphere lighter than the fluid does not settle: one line
    with pytest.raises(SceneError, match="denser than the fluid"):
        scene_from_dict(top | {"body1": {"material": "polystyrene", "radius": "20 um"},
                               "fluid": {"name": "glycerol_water_80"}}, table)


def test_a_settling_sphere_with_inertia_arrives_as_the_integrated_motion_and_near_the_balance(
        table):
    """Above QUASI_STEADY_BELOW the motion is integrated; its arrival speed lies below the
    terminal speed and above the overdamped balance speed at x0 (inertia carries it in)."""
    from pipeline.scenes import trajectory as tr

    scene = scene_from_dict({"approach_speed": "settling",
                             "body1": {"material": "steel", "radius": "1.5 mm"},
                             "body2": {"material": "glass", "wall": True},
                             "fluid": {"name": "silicone_oil_104cst"}}, table)
    assert scene.stokes_of(scene.approach_speed) > tr.QUASI_STEADY_BELOW
    outer = tr._outer(scene, tr.auto_drag_law(scene))
    balance = tr._balance_speed(outer, scene.x0, scene.approach_speed)
    assert balance < scene.v0 < scene.approach_speed
    # the results' speed at the outer start (1 a) is the settling motion's there: slowed from
    # the terminal speed, not yet to v0 (the outer flow's map of v0, which knows no gravity,
    # had read 2.9 m/s for a steel ball settling at 23 mm/s in glycerol)
    assert scene.v0 < scene.settling_outer_start_speed < scene.approach_speed
    result = run_scene(scene, accuracy="fast", sensitivity_solves=False)
    d = result.to_dict()
    assert d["outer_start_speed_m_per_s"] == scene.settling_outer_start_speed
