"""Scenes in physical units: hand-computed parameters, wall equivalence, validity checks, errors."""

import json
import math

import pytest

from solver.physics import DEFAULT_CAVITATION

from pipeline.cli import main
from pipeline.scenes.materials import MaterialError, load_table
from pipeline.scenes import checks
from pipeline.scenes.checks import THRESHOLDS, premise_checks
from pipeline.scenes.run import RESULT_KEYS, check_solvable, run_scene
from pipeline.scenes.scene import SceneError
from pipeline.scenes.scene_file import scene_from_dict
from pipeline.scenes.units import FieldSpec, UnitError, to_si


@pytest.fixture(scope="module")
def table():
    return load_table(user_files=False)


@pytest.fixture(autouse=True)
def _no_user_materials(monkeypatch, tmp_path):
    """Tests must not see the developer's own ~/.config/ehd/materials.toml or $EHD_MATERIALS."""
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))
    monkeypatch.delenv("EHD_MATERIALS", raising=False)


def sandstone(**top):
    """The worked example of docs/model.md, "The parameters": 50 um radius sandstone grains, mu = 1 mPa s, v0 = 0.1 m/s."""
    data = {
        "v0": "0.1 m/s",
        "body1": {"material": "sandstone", "radius": "50 um"},
        "body2": {"material": "sandstone", "radius": "50 um"},
        "fluid": {"viscosity": "1 mPa s", "density": "1000 kg/m^3"},
    }
    data.update(top)
    return data


# ---- the worked example, by hand ------------------------------------------------------------
def test_worked_example_matches_hand_computation(table):
    s = scene_from_dict(sandstone(), table)
    # Hand computation (docs/model.md values: a1 = a2 = 50 um, rho = 2600, E = 5.7e10, nu = 0.1,
    # mu = 1e-3, v0 = 0.1, x0 = 0.01 a):
    #   a = 25 um; m = m1/2 = 2600 * (4/3) pi (50e-6)^3 / 2 = 6.80678e-10 kg
    #   St = m v0 / (6 pi mu a^2) = (4/9) rho a1 v0 / mu = (4/9) * 13 = 52/9 = 5.77778
    #   theta = 2 (1 - 0.01) / (pi 5.7e10) = 1.98 / 1.790708e11 = 1.105708e-11 1/Pa
    #   x1 = (4 theta mu a^1.5 v0)^0.4, a^1.5 = 1.25e-7: (5.528540e-22)^0.4 = 3.14083e-9 m
    #   eps = (x1 / x0)^2.5 = (3.14083e-9 / 2.5e-7)^2.5 = 1.76913e-5
    #   Re = rho_f v0 a / mu = 1000 * 0.1 * 25e-6 / 1e-3 = 2.5
    # Tolerances: the exact ones (a, St, Re) only see float rounding of "50 um" -> 1e-12; the
    # six-digit literals are good to half a unit in their last digit (5e-6 relative).
    assert s.reduced_radius == pytest.approx(25e-6, rel=1e-12)
    assert s.reduced_mass == pytest.approx(6.80678e-10, rel=5e-6)
    assert s.stokes == pytest.approx(52.0 / 9.0, rel=1e-12)
    assert s.theta == pytest.approx(1.105708e-11, rel=5e-6)
    assert s.x1 == pytest.approx(3.14083e-9, rel=5e-6)
    assert s.eps == pytest.approx(1.76913e-5, rel=5e-6)
    assert s.x0 == pytest.approx(2.5e-7, rel=1e-12)
    assert s.reynolds == pytest.approx(2.5, rel=1e-12)
    # eps and x1 are tied: eps = (x1/x0)^(5/2) (docs/model.md); two independent formulas in Scene
    assert s.eps == pytest.approx((s.x1 / s.x0) ** 2.5, rel=1e-12)


def test_physical_results_are_the_dimensionless_ones_rescaled(table):
    r = run_scene(scene_from_dict(sandstone(), table), accuracy="fast")
    d, c, s = r.to_dict(), r.collision, r.scene
    assert tuple(d) == RESULT_KEYS
    assert c.ok and c.model == "ehd"
    # conversions are single multiplications: only float rounding separates them
    assert d["closest_approach_nm"] == pytest.approx(c.h_m_x1 * s.x1 * 1e9, rel=1e-12)
    assert d["rebound_speed_m_per_s"] == pytest.approx(c.v_r * 0.1, rel=1e-12)
    assert d["peak_force_N"] == pytest.approx(
        c.peak_force * 6 * math.pi * 1e-3 * (25e-6) ** 2 * 0.1 / s.x1, rel=1e-12)
    assert d["time_to_stop_s"] == pytest.approx(c.tau_v_zero * 2.5e-7 / 0.1, rel=1e-12)
    # the pressure extremes are the solver's (whole collision), rescaled; a rebounding collision
    # has film tension
    assert d["peak_pressure_Pa"] == pytest.approx(c.p_max * s.pressure_scale, rel=1e-12)
    assert d["min_pressure_Pa"] == pytest.approx(c.p_min * s.pressure_scale, rel=1e-12)
    assert d["min_pressure_Pa"] < 0 and c.v_r > 0
    # a scene's report needs no profiles: only the figures ask for them
    assert c.pressure is None or c.pressure.size == 0
    assert c.physics == s.physics()


def test_equal_spheres_equal_sphere_on_wall_with_reduced_radius_and_mass(table):
    pair = scene_from_dict(sandstone(), table)
    # sphere of the reduced radius 25 um with the reduced mass m1/2: its density must be
    # (m1/2) / ((4/3) pi (a1/2)^3) = 4 rho; the wall has the same E, nu so theta is unchanged
    wall = scene_from_dict(sandstone(
        body1={"material": "sandstone", "radius": "25 um", "density": "10400 kg/m^3"},
        body2={"material": "sandstone", "wall": True},
        x0="250 nm"), table)
    for name in ("reduced_radius", "reduced_mass", "theta", "stokes", "eps", "x1"):
        assert getattr(wall, name) == pytest.approx(getattr(pair, name), rel=1e-12), name
    a = run_scene(pair, accuracy="fast").to_dict()
    b = run_scene(wall, accuracy="fast").to_dict()
    for key in ("St", "eps", "x1_m", "v_r", "closest_approach_nm", "equilibrium_separation_m",
                "time_to_stop_s", "peak_force_N", "peak_pressure_Pa", "min_pressure_Pa",
                "dimple_depth_nm"):
        # same (St, eps) up to rounding -> the same solve; 1e-9 allows for the rounding of the
        # inputs propagating through the adaptive stepping
        assert b[key] == pytest.approx(a[key], rel=1e-9), key
    assert (b["model"], b["dimple"], b["escaped"]) == (a["model"], a["dimple"], a["escaped"])


def test_wall_given_first_is_moved_to_body2(table):
    s = scene_from_dict(sandstone(body1={"material": "glass", "wall": True}), table)
    assert s.body2.wall and not s.body1.wall
    assert s.reduced_radius == pytest.approx(50e-6) and s.reduced_mass == s.body1.mass


def test_rigid_scene_reports_why(table):
    # steel ball on a glass wall in glycerol, slowly: St = 0.18, start deformation 5.23 eps ~ 1e-3
    data = {"v0": "10 cm/s", "body1": {"material": "chrome_steel", "radius": "1.5 mm"},
            "body2": {"material": "glass", "wall": True}, "fluid": {"name": "glycerol"}}
    r = run_scene(scene_from_dict(data, table), accuracy="fast")
    d = r.to_dict()
    assert d["model"] == "rigid" and d["model_reason"].startswith("rigid")
    assert d["St"] < 0.4 and d["v_r"] == 0.0 and d["time_to_stop_s"] is None
    # rigid creep ends at x0 exp(-St) (docs/model.md, "Rigid solution")
    assert d["closest_approach_nm"] == pytest.approx(d["x0_m"] * math.exp(-d["St"]) * 1e9, rel=1e-9)


# ---- validity checks ----------------------------------------------------------------------------
KNOWN_ALPHA = {"viscosity": "1 mPa s", "density": "1000 kg/m^3", "pressure_viscosity": "0 1/Pa"}


def names(checks):
    return {c.check for c in checks}


def test_clean_scene_passes_every_check(table):
    # smooth grains (roughness 0): natural sand's 0.5 um fires the roughness check (test below)
    smooth = {"material": "sandstone", "radius": "50 um", "roughness": "0 m"}
    # a liquid whose pressure-viscosity coefficient is known (0, as water's): without one the
    # pressure_viscosity check warns at these pressures (tests/test_scene_piezo.py)
    r = run_scene(scene_from_dict(sandstone(body1=smooth, body2=smooth, fluid=KNOWN_ALPHA),
                                  table), accuracy="fast")
    assert r.warnings == []


def test_roughness_check_fires_on_sand_and_not_on_polished_steel_in_glycerol(table):
    sand = run_scene(scene_from_dict(sandstone(fluid=KNOWN_ALPHA), table), accuracy="fast")
    # 0.71 um combined rms against h_m ~ 0.9 nm: ~800 times the 1/3 threshold
    assert names(sand.warnings) == {"roughness"} and sand.warnings[0].value > 100
    assert "contact mechanics" in sand.warnings[0].message
    # a 6 mm polished chrome-steel ball on glass in glycerol at 1 m/s: h_m ~ 2.4 um, sigma 25 nm
    steel = {"v0": "1 m/s", "body1": {"material": "chrome_steel", "radius": "3 mm"},
             "body2": {"material": "glass", "wall": True}, "fluid": {"name": "glycerol"}}
    r = run_scene(scene_from_dict(steel, table), accuracy="fast")
    assert "roughness" not in names(r.warnings)
    assert checks.combined_roughness(r.scene) == pytest.approx(math.hypot(25e-9, 1e-9))


def test_eps_check(table):
    # x0 = 10 nm: eps = (3.14083 / 10)^2.5 = 0.0553 > 0.0096 (still inside the solver's 0.1)
    s = scene_from_dict(sandstone(x0="10 nm"), table)
    checks = premise_checks(s)
    assert names(checks) == {"eps"}
    assert checks[0].value == pytest.approx(s.eps) and checks[0].threshold == THRESHOLDS["eps"]


def test_x0_over_a_check(table):
    # a 10 mPa s fluid keeps Re x0/a = 0.25 * 0.1 = 0.025 quiet
    fluid = {"viscosity": "10 mPa s", "density": "1000 kg/m^3"}
    checks = premise_checks(scene_from_dict(sandstone(x0_over_a=0.1, fluid=fluid), table))
    assert names(checks) == {"x0_over_a"} and checks[0].value == pytest.approx(0.1)


def test_fluid_inertia_check(table):
    # v0 = 1 m/s: Re = 25, Re x0/a = 0.25 > 0.1; eps = 1.8e-4 and (v0/c)^0.2 = 0.19 stay small
    checks = premise_checks(scene_from_dict(sandstone(v0="1 m/s"), table))
    assert names(checks) == {"Re_x0_over_a"} and checks[0].value == pytest.approx(0.25, rel=1e-9)


def test_elastic_wave_check(table):
    # steel ball (c = sqrt(210e9/7810) = 5185 m/s) at 6 m/s: (6/5185)^0.2 = 0.259 > 0.25, in a
    # 10 Pa s oil (Re x0/a = 0.026) starting at x0 = 0.03 a (eps = 0.006): only waves warn
    data = {"v0": "6 m/s", "x0_over_a": 0.03,
            "body1": {"material": "chrome_steel", "radius": "1.5 mm"},
            "body2": {"material": "glass", "wall": True},
            "fluid": {"viscosity": "10 Pa s", "density": "970 kg/m^3"}}
    s = scene_from_dict(data, table)
    checks = premise_checks(s)
    assert names(checks) == {"wave_parameter"}
    assert checks[0].value == pytest.approx((6.0 / math.sqrt(210e9 / 7810)) ** 0.2, rel=1e-9)


def test_yield_check_fires_and_stays_quiet_below_yield(table):
    def alu(v0):
        return scene_from_dict({"v0": v0, "body1": {"material": "aluminium", "radius": "100 um"},
                                "body2": {"material": "aluminium", "radius": "100 um"},
                                "fluid": {"name": "water"}}, table)

    fast = run_scene(alu("10 cm/s"), accuracy="fast")
    assert fast.peak_pressure > 276e6  # 6061-T6 yield; the check must then fire for both bodies
    assert {"yield_body1", "yield_body2"} <= names(fast.warnings)
    slow = run_scene(alu("1 mm/s"), accuracy="fast")
    assert slow.peak_pressure < 276e6 and not any(w.check.startswith("yield") for w in slow.warnings)


def test_cavitation_switches_on_where_the_classic_tension_crosses_the_floor(table):
    # water at the default 1 atm: the classic film pulls ~ -100 MPa, far below water's vapour
    # pressure, so the scene re-solves with the Reynolds floor and says why
    r = run_scene(scene_from_dict(sandstone(fluid={"name": "water"}), table), accuracy="fast")
    s, c, d = r.scene, r.collision, r.to_dict()
    assert s.ambient_pressure == 101325.0 and s.cavitation_pressure == 2339.0
    # Pi = (p_amb - p_v) / p*: one formula, float rounding only
    assert c.physics.cavitation == DEFAULT_CAVITATION and d["cavitation"] == DEFAULT_CAVITATION
    assert d["Pi"] == pytest.approx((101325.0 - 2339.0) / s.pressure_scale, rel=1e-12)
    assert d["cavitation_pressure_Pa"] == 2339.0 and d["cavitated"] is True
    assert d["cavitation_reason"].startswith(
        f"{DEFAULT_CAVITATION} cavitation at Pi = {d['Pi']:.3g}: ")
    assert "below the cavitation pressure 2.339 kPa (the vapour pressure of water)" in d["cavitation_reason"]
    # the floor holds: the absolute pressure never falls below p_v (the solver's P >= -Pi, to
    # its round-off)
    assert s.ambient_pressure + r.min_pressure >= 2339.0 - 1e-9 * s.pressure_scale
    assert "cavitation" not in names(r.warnings)
    # the cavity in SI: single multiplications of the dimensionless observables
    assert d["cavity_radius_max_m"] == pytest.approx(
        c.cavity_radius_max * math.sqrt(s.reduced_radius * s.x1), rel=1e-12)
    assert d["void_volume_max_m3"] == pytest.approx(
        c.void_volume_max * 2 * math.pi * s.reduced_radius * s.x1**2, rel=1e-12)
    assert d["cavitation_onset_s"] == pytest.approx(c.tau_cavitation_onset * s.time_scale, rel=1e-12)
    assert 0 < d["cavity_radius_max_m"] < s.reduced_radius and d["void_volume_max_m3"] > 0
    # an ambient pressure above the largest tension (~100 MPa here): the classic film stands
    quiet = run_scene(scene_from_dict(sandstone(fluid={"name": "water", "ambient_pressure": "1 GPa"}),
                                      table), accuracy="fast")
    assert quiet.collision.physics.classic and "cavitation" not in names(quiet.warnings)
    assert quiet.cavitation_reason.startswith("classic film: the film's lowest absolute pressure")
    # forced off: the classic film, and the old warning says the liquid would cavitate
    off = run_scene(scene_from_dict(sandstone(fluid={"name": "water"}, cavitation="off"), table),
                    accuracy="fast")
    (w,) = [w for w in off.warnings if w.check == "cavitation"]
    assert w.value == pytest.approx(101325.0 + off.min_pressure) and w.threshold == 2339.0
    assert off.collision.physics.classic and "as asked for" in off.cavitation_reason
    # a liquid given by numbers, without a vapour pressure: the assumed 0 Pa floor, switched as
    # the named water is (issue 26: the same physics however the liquid is given), and the
    # physics line says it was assumed
    numbers = run_scene(scene_from_dict(sandstone(), table), accuracy="fast")
    assert numbers.scene.cavitation_pressure == 0.0
    assert numbers.collision.physics.cavitation == off_water_model(table)
    assert "assumed" in numbers.cavitation_reason


def off_water_model(table):
    """The cavitation model the sandstone scene in named water switches to."""
    return run_scene(scene_from_dict(sandstone(fluid={"name": "water"}), table),
                     accuracy="fast", sensitivity_solves=False).collision.physics.cavitation


def test_cavitation_pressure_presets_and_tensile_strength(table):
    def scene(**fluid):
        return scene_from_dict(sandstone(fluid={"name": "water", **fluid}), table)

    assert scene().cavitation_pressure == 2339.0  # the default for a liquid: "vapour"
    assert scene(cavitation_pressure="vapour").cavitation_pressure == 2339.0
    gas = scene(cavitation_pressure="gas-saturated", ambient_pressure="2 bar")
    assert gas.cavitation_pressure == 2e5 and gas.Pi == 0.0 and gas.physics("auto").Pi == 0.0
    t = scene(tensile_strength="10 MPa")
    assert t.cavitation_pressure == pytest.approx(101325.0 - 1e7, rel=1e-12)
    assert t.Pi == pytest.approx(1e7 / t.pressure_scale, rel=1e-12)
    assert scene(cavitation_pressure="5 kPa").cavitation_pressure == pytest.approx(5e3)
    # a gas has no cavitation pressure: its scene stays classic even when a model is "auto"
    air = scene_from_dict(sandstone(fluid={"name": "air"}), table)
    assert air.cavitation_pressure is None and air.physics("auto").classic


@pytest.mark.parametrize("fluid, message", [
    ({"name": "water", "cavitation_pressure": "1 kPa", "tensile_strength": "1 MPa"}, "not both"),
    ({"name": "water", "cavitation_pressure": "boiling"}, "must be a pressure .* or one of"),
    ({"name": "water", "cavitation_pressure": "2 bar"}, "above the ambient pressure"),
    ({"name": "water", "cavitation_pressure": "1 m"}, "fluid.cavitation_pressure"),
    ({"viscosity": "1 mPa s", "density": "1000 kg/m^3", "cavitation_pressure": "vapour"},
     "has no vapour_pressure"),
])
def test_bad_cavitation_pressure_names_the_field(table, fluid, message):
    with pytest.raises(ValueError, match=message):
        scene_from_dict(sandstone(fluid=fluid), table)


def test_mean_free_path_check(table):
    air = {"v0": "10 cm/s", "body1": {"material": "glass", "radius": "50 um"},
           "body2": {"material": "glass", "wall": True}, "fluid": {"name": "air"}}
    r = run_scene(scene_from_dict(air, table), accuracy="fast")
    (w,) = [w for w in r.warnings if w.check == "mean_free_path"]
    assert w.threshold == pytest.approx(67.30e-9) and w.value < w.threshold
    air["fluid"] = {"name": "air", "mean_free_path": "0.001 nm"}
    r = run_scene(scene_from_dict(air, table), accuracy="fast")
    assert "mean_free_path" not in names(r.warnings)


def test_out_of_range_scene_is_refused_not_solved(table):
    with pytest.raises(SceneError, match=r"eps = .* outside the model's range"):
        run_scene(scene_from_dict(sandstone(x0="2 nm"), table))
    # steel ball on glass in air at 1 m/s: St = (2/9) rho a v0 / mu = 1.4e5 > 1e4
    fast = scene_from_dict({"v0": "1 m/s", "body1": {"material": "chrome_steel", "radius": "1.5 mm"},
                            "body2": {"material": "glass", "wall": True},
                            "fluid": {"name": "air"}}, table)
    with pytest.raises(SceneError, match=r"St = .* outside the solver's range .* dry Hertz"):
        check_solvable(fast)


def test_scene_physics_is_its_dimensionless_groups(table):
    s = scene_from_dict(sandstone(), table)
    p = check_solvable(s)
    assert p == s.physics() and (p.St, p.eps) == (s.stokes, s.eps)


# ---- bad input ------------------------------------------------------------------------------------
@pytest.mark.parametrize("change, field", [
    ({"body1": {"material": "sandstone"}}, "body1: missing the field 'radius'"),
    ({"body1": {"material": "sandstone", "radius": "-5 um"}}, "body1.radius"),
    ({"body1": {"material": "unobtainium", "radius": "5 um"}}, "unknown material 'unobtainium'"),
    ({"body1": {"material": "sandstone", "radius": "10 m/s"}}, "body1.radius: '10 m/s' has units"),
    ({"body1": {"material": "sandstone", "radius": "5 furlongs per"}}, "body1.radius: cannot read"),
    ({"body1": {"material": "sandstone", "radius": "5 um", "colour": "red"}}, "unknown field"),
    ({"body1": {"radius": "5 um", "youngs_modulus": "1 GPa"}}, "body1: missing the field 'poisson_ratio'"),
    ({"body1": {"material": "sandstone", "radius": "5 um", "poisson_ratio": 0.7}}, r"poisson_ratio = 0.7 is outside"),
    ({"fluid": {"name": "water", "viscosity": "1 m"}}, "fluid.viscosity"),
    ({"v0": "fast"}, "v0: cannot read"),
    ({"x0": "1 um", "x0_over_a": 0.01}, "either x0"),
    ({"body1": {"wall": True, "material": "glass"}, "body2": {"wall": True, "material": "glass"}}, "both plane walls"),
    # e_dry's own range, whichever side it is broken on (0 was refused with "(0, inf)")
    ({"e_dry": 0}, r"e_dry = 0 is outside its valid range \(0, 1\]"),
    ({"e_dry": 1.5}, r"e_dry = 1.5 is outside its valid range \(0, 1\]"),
])
def test_bad_scene_names_the_field(table, change, field):
    data = sandstone()
    data.update(change)
    with pytest.raises(ValueError, match=field):
        scene_from_dict(data, table)


def test_missing_v0(table):
    data = sandstone()
    del data["v0"]
    with pytest.raises(SceneError, match="missing the speed: give approach_speed"):
        scene_from_dict(data, table)


def test_units_parse_and_convert():
    length = FieldSpec("[length]", "50 um", si_unit="m")
    assert to_si("100 um", length, "r") == pytest.approx(1e-4, rel=1e-12)
    assert to_si("3 mm", length, "r") == pytest.approx(3e-3, rel=1e-12)
    assert to_si(2e-5, length, "r") == 2e-5  # bare numbers are SI
    assert to_si("2e-5", length, "r") == 2e-5  # so are quoted numbers (command-line flags)
    visc = FieldSpec("[pressure] * [time]", "1 mPa s", si_unit="Pa*s")
    assert to_si("1 cP", visc, "mu") == pytest.approx(1e-3, rel=1e-12)
    assert to_si("1.41 Pa s", visc, "mu") == pytest.approx(1.41, rel=1e-12)
    with pytest.raises(UnitError, match="mu: '1 m/s' has units"):
        to_si("1 m/s", visc, "mu")
    with pytest.raises(UnitError, match="expected a number"):
        to_si(True, visc, "mu")


def test_quantities_take_a_prefix_from_atto_to_exa_only():
    """``--v0 '1e-25 m/s'`` was shown as ``100 rm/s`` (pint's ronto): beyond the prefixes a
    reader knows, the SI unit with a power of ten."""
    from pipeline.scenes.units import format_quantity

    assert format_quantity(2.5e-5, "m") == "25 µm"
    assert format_quantity(1e-18, "m") == "1 am"
    assert format_quantity(1e-25, "m/s") == "1×10⁻²⁵ m/s"
    assert format_quantity(3e22, "Pa") == "3×10²² Pa"


# ---- the command line -------------------------------------------------------------------------
def write(tmp_path, text, name="scene.toml"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


SCENE = """
title = "sandstone"
v0 = "10 cm/s"
[body1]
material = "sandstone"
radius = "50 um"
[body2]
material = "sandstone"
radius = "50 um"
[fluid]
name = "water"
"""


def test_cli_json_is_one_object_with_documented_keys(tmp_path, capsys):
    assert main(["scene", write(tmp_path, SCENE), "--json", "--accuracy", "fast"]) == 0
    d = json.loads(capsys.readouterr().out)
    # natural sand's roughness is the one warning (test_roughness_check_fires_on_sand...)
    assert tuple(d) == RESULT_KEYS and d["model"] == "ehd"
    assert [w["check"] for w in d["warnings"]] == ["roughness"]


def test_cli_flags_override_the_file_and_build_a_scene_alone(tmp_path, capsys):
    assert main(["scene", write(tmp_path, SCENE), "--json", "--accuracy", "fast",
                 "--v0", "1 m/s"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["inputs"]["v0_m_per_s"] == 1.0
    assert main(["scene", "--material1", "glass", "--radius1", "1 mm", "--wall",
                 "--material2", "glass", "--fluid", "water", "--v0", "1 cm/s", "--json",
                 "--accuracy", "fast"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["inputs"]["body2"]["wall"] and d["reduced_radius_m"] == pytest.approx(1e-3)


def test_cli_wall_and_radius2_flags_together_are_exit_2(capsys):
    """--wall dropped --radius2 without a word (a file with both is refused: ``wall = true but
    radius``)."""
    assert main(["scene", "--material1", "glass", "--radius1", "100 um", "--material2", "glass",
                 "--wall", "--radius2", "5 um", "--fluid", "water", "--v0", "10 cm/s"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--wall and --radius2" in err


@pytest.mark.parametrize("line, flag, value, read, want", [
    ('x0 = "1 um"', "x0_over_a", "0.005", lambda s: s.x0 / s.reduced_radius, 0.005),
    ("x0_over_a = 0.02", "x0", "250 nm", lambda s: s.x0, 250e-9),
    ("x_ref_over_a = 0.3", "x_ref", "2 um", lambda s: s.x_ref_distance, 2e-6),
    ('outer_start = "40 um"', "outer_start_over_a", "2",
     lambda s: s.outer_start_distance / s.reduced_radius, 2.0),
], ids=["x0", "x0_over_a", "x_ref", "outer_start"])
def test_a_flag_overrides_the_files_other_form_of_its_key(tmp_path, line, flag, value, read,
                                                           want):
    """A scene gives x0, x_ref or the outer start in SI or over a; the flag of one form refused a
    file holding the other ("give either x0 or x0_over_a, not both", though only one was given
    of each), as a speed's flag already replaced the file's other speed."""
    from pipeline.scenes.commands import load_scene

    path = write(tmp_path, SCENE.replace('v0 = "10 cm/s"', f'v0 = "10 cm/s"\n{line}'))
    assert read(load_scene(path, {flag: value})) == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('v0 = "10 cm/s"', ""), "missing the speed: give approach_speed"),
    (lambda t: t.replace('radius = "50 um"', 'radius = "-50 um"', 1), "body1.radius"),
    (lambda t: t.replace('material = "sandstone"', 'material = "kryptonite"', 1), "unknown material"),
    (lambda t: t.replace('radius = "50 um"', 'radius = "50 kg"', 1), "body1.radius: '50 kg' has units"),
    (lambda t: t + "[[oops", "not valid TOML"),
])
def test_cli_bad_file_exits_2_with_one_line(tmp_path, capsys, edit, message):
    assert main(["scene", write(tmp_path, edit(SCENE))]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_cli_missing_file_and_no_scene(capsys, tmp_path):
    assert main(["scene", str(tmp_path / "nope.toml")]) == 2
    assert "not found" in capsys.readouterr().err
    assert main(["scene"]) == 2
    assert "give a scene file" in capsys.readouterr().err


def test_cli_scene_plot_onto_a_file_exits_2_before_solving(tmp_path, capsys, monkeypatch):
    import pipeline.scenes.run as run_module

    monkeypatch.setattr(run_module, "run_scene", lambda *a, **k: pytest.fail("solved"))
    not_a_dir = tmp_path / "figs"
    not_a_dir.write_text("")
    assert main(["scene", write(tmp_path, SCENE), "--plot", str(not_a_dir)]) == 2
    err = capsys.readouterr().err.strip()
    assert "not a directory" in err and len(err.splitlines()) == 1


def test_cli_strict_exits_1_on_warnings(tmp_path, capsys):
    path = write(tmp_path, SCENE)
    assert main(["scene", path, "--accuracy", "fast", "--cavitation", "off"]) == 0
    out = capsys.readouterr().out
    assert "[cavitation]" in out and "physics: classic film, as asked for" in out
    assert main(["scene", path, "--accuracy", "fast", "--cavitation", "off", "--strict"]) == 1


# ---- cavitation: the shipped examples and the override ------------------------------------------
EXAMPLES = __import__("pathlib").Path(__file__).resolve().parent.parent / "examples"


@pytest.mark.parametrize("name", ["sandstone_water.toml", "glass_beads_water.toml"])
def test_shipped_water_examples_switch_cavitation_on_and_say_why(name, capsys):
    assert main(["scene", str(EXAMPLES / name), "--json", "--accuracy", "fast"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["cavitation"] == DEFAULT_CAVITATION and d["cavitated"] is True
    # the liquid scenes sit at Pi ~ 1e-4 to 6e-4 (issue 10)
    assert 1e-4 < d["Pi"] < 1e-3
    reason = d["cavitation_reason"]
    assert reason.startswith(f"{DEFAULT_CAVITATION} cavitation at Pi = ")
    assert "the vapour pressure of water" in reason and "MPa" in reason
    assert "cavitation" not in [w["check"] for w in d["warnings"]]
    assert main(["scene", str(EXAMPLES / name), "--accuracy", "fast"]) == 0
    out = capsys.readouterr().out
    assert f"physics: {DEFAULT_CAVITATION} cavitation at Pi = " in out
    assert "largest cavity radius" in out


def test_glycerol_and_air_examples_keep_the_film_without_a_floor(capsys):
    # the steel ball in glycerol barely rebounds: its film pulls a few kPa at most, far from
    # glycerol's ~0.01 Pa vapour pressure at 1 atm, so no floor (its viscosity law is switched
    # on instead: tests/test_scene_piezo.py)
    assert main(["scene", str(EXAMPLES / "steel_ball_glass_wall_glycerol.toml"), "--json",
                 "--accuracy", "fast"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["cavitation"] == "off" and d["Pi"] > 0 and d["cavitated"] is not True
    assert 101325.0 + d["min_pressure_Pa"] > 0.5 * 101325.0 > d["cavitation_pressure_Pa"]
    assert d["cavitation_reason"].startswith(
        "no cavitation floor: the film's lowest absolute pressure")
    # a gas film does not cavitate; its (unphysical) tension below zero absolute is a warning
    assert main(["scene", str(EXAMPLES / "glass_bead_wall_air.toml"), "--json",
                 "--accuracy", "fast"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["cavitation"] == "off" and d["Pi"] is None and d["cavitation_pressure_Pa"] is None
    assert d["cavitation_reason"] == ("classic film: a gas film does not cavitate, so the film "
                                      "is not switched")
    assert {"gas_tension", "mean_free_path"} <= {w["check"] for w in d["warnings"]}


@pytest.mark.parametrize("argv, message", [
    (["--fluid", "air", "--cavitation", "reynolds"], "needs a cavitation pressure"),
])
def test_cli_cavitation_override_errors_exit_2_with_one_line(tmp_path, capsys, argv, message):
    assert main(["scene", write(tmp_path, SCENE), "--accuracy", "fast", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "Traceback" not in err and len(err.splitlines()) == 1


def test_cli_cavitation_override_selects_the_model(tmp_path, capsys):
    assert main(["scene", write(tmp_path, SCENE), "--accuracy", "fast", "--cavitation", "jfo",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["cavitation"] == "jfo" and d["dimensionless"]["cavitation"] == "jfo"


# ---- materials ------------------------------------------------------------------------------------
def test_every_shipped_entry_has_a_source_and_sane_values(table):
    assert {"glass", "quartz", "sandstone", "steel", "aluminium", "pmma", "polystyrene"} <= set(table.solids)
    assert {"water", "air", "glycerol", "glycerol_water_50", "silicone_oil_100cst"} <= set(table.fluids)
    for s in table.solids.values():
        assert len(s.source) > 20 and 1e8 < s.youngs_modulus < 1e12 and 500 < s.density < 2e4
    for f in table.fluids.values():
        assert len(f.source) > 20 and 1e-6 < f.viscosity < 1e3


def test_experiment_entries_load_with_the_experiments_values(table):
    """The entries benchmarks/bench_experiments.py needs (issue 17) load, and the Gondret et al.
    (2002) liquids give the runs' tabulated kinematic viscosities and density ratios (Biegert
    et al. 2017, Table 1) with the steel of the table."""
    assert {"nylon", "delrin", "pmma", "chrome_steel"} <= set(table.solids)
    assert {"silicone_oil_104cst", "silicone_oil_11cst", "glycerol_water_70",
            "glycerol_water_90"} <= set(table.fluids)
    steel = table.solids["chrome_steel"].density
    # nu to 0.1 %: the entries' viscosity is nu rho rounded to 4 digits; rho_p/rho_f to 0.5 %:
    # the ratios are tabulated to 3 digits and the table's steel is 7810 kg/m^3, not 7800
    for name, nu, ratio in (("silicone_oil_104cst", 1.036e-4, 8.08),
                            ("silicone_oil_11cst", 1.07e-5, 8.34)):
        f = table.fluids[name]
        assert f.viscosity / f.density == pytest.approx(nu, rel=1e-3)
        assert steel / f.density == pytest.approx(ratio, rel=5e-3)
    # glycerol-water: viscosity and density rise with the glycerol fraction (a typo would break it)
    mixtures = [table.fluids[f"glycerol_water_{w}"] for w in (50, 70, 80, 90)]
    assert all(a.viscosity < b.viscosity and a.density < b.density
               for a, b in zip(mixtures, mixtures[1:]))
    assert all(a.vapour_pressure > b.vapour_pressure for a, b in zip(mixtures, mixtures[1:]))


def test_user_materials_file_env_and_inline(tmp_path, monkeypatch, capsys):
    mine = write(tmp_path, """
[materials.unobtainium]
youngs_modulus = "1 TPa"
poisson_ratio = 0.1
density = "1000 kg/m^3"
source = "own measurement"
""", "mine.toml")
    scene = SCENE.replace('material = "sandstone"', 'material = "unobtainium"', 1)
    path = write(tmp_path, scene)
    assert main(["scene", path, "--json", "--accuracy", "fast"]) == 2  # not known yet
    assert "unknown material 'unobtainium'" in capsys.readouterr().err
    assert main(["scene", path, "--json", "--accuracy", "fast", "--materials", mine]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["inputs"]["body1"]["youngs_modulus_Pa"] == 1e12
    monkeypatch.setenv("EHD_MATERIALS", mine)
    assert main(["scene", path, "--json", "--accuracy", "fast"]) == 0
    capsys.readouterr()
    monkeypatch.delenv("EHD_MATERIALS")
    inline = scene + '\n[materials.unobtainium]\nyoungs_modulus = "1 TPa"\npoisson_ratio = 0.1\n' \
                     'density = 1000\nsource = "inline"\n'
    assert main(["scene", write(tmp_path, inline), "--json", "--accuracy", "fast"]) == 0


def test_user_entry_without_source_is_refused(tmp_path):
    bad = write(tmp_path, '[fluids.goo]\nviscosity = "1 Pa s"\ndensity = 1000\n', "bad.toml")
    with pytest.raises(MaterialError, match=r"\[fluids.goo\] needs a 'source'"):
        load_table([bad], user_files=False)


def test_list_materials(capsys):
    assert main(["scene", "--list-materials"]) == 0
    out = capsys.readouterr().out
    assert "sandstone" in out and "source:" in out and "water" in out


def _pair_scene(m1, m2, **top):
    data = {"v0": "0.5 m/s", "body1": {"material": m1, "radius": "3 mm"},
            "body2": {"material": m2, "wall": True}, "fluid": {"name": "silicone_oil_104cst"}}
    data.update(top)
    return data


def test_the_pairs_table_gives_a_scenes_e_dry(table):
    """A pair both of whose materials one group of the shipped table holds takes its e_dry,
    also with a property of a body given in the scene (its surfaces are still that material's);
    the scene's own e_dry wins, and a pair no group holds is elastic (1)."""
    scene = scene_from_dict(_pair_scene("chrome_steel", "glass"), table)
    assert scene.e_dry == table.pairs["glass_and_hard_metals"].e_dry == 0.97
    assert "glass_and_hard_metals" in scene.e_dry_source
    rough = _pair_scene("chrome_steel", "glass")
    rough["body1"]["roughness"] = "0.3 um"
    assert scene_from_dict(rough, table).e_dry == 0.97
    assert scene_from_dict(_pair_scene("chrome_steel", "glass", e_dry=0.8), table).e_dry == 0.8
    plastic = scene_from_dict(_pair_scene("nylon", "pmma"), table)
    assert plastic.e_dry == 1.0 and "no pair group" in plastic.e_dry_source
    for pair in table.pairs.values():
        assert len(pair.source) > 20 and pair.materials <= set(table.solids)


def test_a_user_pair_group_replaces_the_shipped_one_and_bad_groups_are_refused(tmp_path):
    mine = write(tmp_path, """
[pairs.glass_and_hard_metals]
materials = ["glass", "chrome_steel"]
e_dry = 0.9
source = "own measurement"
""", "pairs.toml")
    table = load_table([mine], user_files=False)
    assert table.dry_restitution("chrome_steel", "glass").e_dry == 0.9
    assert table.dry_restitution("steel", "glass") is None  # the replaced group held it
    for body, message in (('materials = "glass"\ne_dry = 0.9\nsource = "x"',
                           "materials must be a list"),
                          ('materials = ["glass"]\ne_dry = 1.5\nsource = "x"', r"e_dry = 1.5"),
                          ('materials = ["glass"]\ne_dry = 0.9', "needs a 'source'")):
        bad = write(tmp_path, f"[pairs.odd]\n{body}\n", "bad_pairs.toml")
        with pytest.raises(MaterialError, match=message):
            load_table([bad], user_files=False)


# ---- the Python API as examples/scene_in_python.py uses it (a hostile scan) --------------------
def test_v0_given_by_dataclasses_replace_is_read_and_checked():
    """``dataclasses.replace(scene, v0=...)``: read and checked as the scene file's v0 (a string
    with units, a number of m/s in its range); a bool (solved as 1 m/s), a negative speed
    (named as a negative St), NaN or None are refused naming v0; 0 is a stopped scene's."""
    import dataclasses

    from pipeline.scenes.commands import load_scene

    import numpy as np

    scene = load_scene(str(EXAMPLES / "glass_beads_water.toml"), {})
    assert dataclasses.replace(scene, v0="20 cm/s").v0 == pytest.approx(0.2, rel=1e-15)
    assert dataclasses.replace(scene, v0=1).v0 == 1.0
    assert dataclasses.replace(scene, v0=np.int64(1)).v0 == 1.0
    assert dataclasses.replace(scene, v0=0).v0 == 0.0  # a scene the outer flow stops
    for bad in (True, -0.1, math.nan, None, 1e40):  # as the scene file's v0 is checked
        with pytest.raises(ValueError, match=r"^v0"):
            dataclasses.replace(scene, v0=bad)


def test_run_scene_of_spheres_the_outer_flow_stops_says_so():
    """An approach speed the outer flow stops before x0 (v0 0): run_scene raised
    ZeroDivisionError; it names the case and the report that describes it."""
    from pipeline.scenes.commands import load_scene
    from pipeline.scenes.run import stopped_result

    scene = load_scene(str(EXAMPLES / "glass_beads_water.toml"), {"approach_speed": "1 mm/s"})
    assert scene.stops_outside
    with pytest.raises(ValueError, match="stops the spheres before x0.*stopped_result"):
        run_scene(scene, accuracy="fast")
    assert stopped_result(scene)["status"] == "ok"


def test_a_sphere_over_a_thousand_times_larger_is_a_wall_to_the_outer_flow():
    """10 um against 10 cm (listed either way): the pair's series took 110 s (10 m: did not
    converge); the larger sphere is a wall to the outer flow (e_far of St 30 3.4e-5 from the
    pair's at 1e3, solver/far_field.py PAIR_RATIO_MAX), the added mass the small sphere's."""
    from pipeline.scenes.commands import load_scene
    from solver.far_field import PAIR_RATIO_MAX

    path = str(EXAMPLES / "glass_beads_water.toml")
    for first, second in (("10 um", "10 cm"), ("10 cm", "10 um")):
        scene = load_scene(path, {"radius1": first, "radius2": second})
        outer = scene.outer_flow()
        assert scene.outer_geometry == "wall" and outer.geometry == "wall"
        small = min(scene.body1, scene.body2, key=lambda b: b.radius)
        phi = scene.fluid.density * 4.0 / 3.0 * math.pi * small.radius**3 / scene.reduced_mass
        assert outer.density_ratio == pytest.approx(phi, rel=1e-12)
    near = load_scene(path, {"radius1": "10 um", "radius2": f"{PAIR_RATIO_MAX * 5} um"})
    assert near.outer_geometry == "pair"
    edge = load_scene(path, {"radius1": "1 mm", "radius2": "1 um"})  # 1000 up to rounding
    assert edge.outer_geometry == "pair" and edge.outer_flow().geometry == "pair"


def test_load_scene_names_an_unknown_field_and_takes_one_materials_file():
    """A bare KeyError for an unknown field, and a materials path taken character by character
    ("materials file 'e' not found"; a hostile scan)."""
    from pipeline.scenes.commands import load_scene
    from pipeline.scenes.materials import MaterialError

    path = str(EXAMPLES / "glass_beads_water.toml")
    with pytest.raises(ValueError, match="unknown scene field 'v00' \\(did you mean 'v0'\\?\\)"):
        load_scene(path, {"v00": "1 m/s"})
    with pytest.raises(MaterialError, match="'nowhere.toml' not found"):
        load_scene(path, materials="nowhere.toml")


@pytest.mark.parametrize("body2, release", [
    ({"material2": "glass", "radius2": "100 um"}, {"approach_speed": "settling"}),
    ({"material2": "steel", "radius2": "1 mm"}, {"approach_speed": "settling"}),
    ({"material2": "glass", "radius2": "0.8 mm"}, {"v0": "0.1 m/s", "trajectory": "t.csv"}),
    ({"material2": "glass", "radius2": "2 m"}, {"approach_speed": "settling"}),
    ({"material2": "glass", "radius2": "1 mm"},
     {"v0": "0.1 m/s", "release_speed": "0.05 m/s", "trajectory": "t.csv"}),
])
def test_two_free_spheres_settling_is_refused(body2, release, tmp_path, capsys):
    """Settling and the whole trajectory of two free spheres: refused (exit 2, one line) instead
    of solved with the pair's zero-momentum relative weight, which gave two glass spheres no
    approach at all ("needs body1 denser than the fluid") and steel onto glass 0.19x their
    relative settling speed, with exit 0; a sphere 2 m across is a wall to e_far only (both would
    fall); two equal spheres released towards each other had e_observed 0.0099 read from a
    bounce no weight brings back (its departure crossed the reading gap at 0.26 of its approach
    speed), exit 0."""
    flags = {"material1": "glass", "radius1": "1 mm", "fluid": "water", **body2, **release}
    argv = ["scene"]
    for key, value in flags.items():
        argv += [f"--{key.replace('_', '-')}", str(tmp_path / value) if key == "trajectory"
                 else value]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gravity with two free spheres is not modelled" in err[0]
    assert "--wall" in err[0] and not (tmp_path / "t.csv").exists()


def test_settling_two_equal_spheres_is_refused_for_the_right_reason():
    """Glass beads in water: the message said "needs body1 denser than the fluid", but glass is
    denser; two equal spheres fall together, never closer."""
    from pipeline.scenes.commands import load_scene

    with pytest.raises(ValueError, match="equal ones together and never closer"):
        load_scene(str(EXAMPLES / "glass_beads_water.toml"), {"approach_speed": "settling"})


def test_run_scene_of_a_scene_given_v0_0_says_what_to_give():
    """``dataclasses.replace(scene, v0=0.0)`` (the pattern of examples/scene_in_python.py) made
    ``run_scene`` fail formatting its own message ("unsupported format string passed to
    NoneType"): now a ValueError that says to give a positive v0."""
    import dataclasses
    from pathlib import Path

    from pipeline.scenes.commands import load_scene

    scene = load_scene(str(Path(__file__).resolve().parents[1] / "examples"
                           / "glass_beads_water.toml"))
    with pytest.raises(ValueError, match="v0 = 0: the spheres never reach x0.*positive v0"):
        run_scene(dataclasses.replace(scene, v0=0.0), accuracy="fast")
