"""Pressure-dependent viscosity and density in scenes (issue 11): the fluids' constants, the
automatic switches with their reasons, the overrides, bad inputs.

The decisions are checked against an independent classic solve (the scene forced to the constant
viscosity and density), never against numbers written here.
"""

import json
import math
import tomllib
from pathlib import Path

import pytest

import solver
from pipeline.cli import main
from pipeline.scenes import checks
from pipeline.scenes.checks import DENSITY_SWITCH, VISCOSITY_SWITCH, per_gpa
from pipeline.scenes.materials import MaterialError, load_table
from pipeline.scenes.run import RESULT_KEYS, run_scene
from pipeline.scenes.scene import SceneError
from pipeline.scenes.scene_file import scene_from_dict

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
GLYCEROL = EXAMPLES / "steel_ball_glass_wall_glycerol.toml"
WATER = EXAMPLES / "sandstone_water.toml"


# the shipped table, and no user materials (~/.config/ehd, $EHD_MATERIALS): test_scene's fixtures
from tests.test_scene import _no_user_materials, table  # noqa: E402,F401


def example(path=GLYCEROL, fluid=None, **top) -> dict:
    """A shipped example as a parsed scene document, with ``fluid`` replaced and top-level
    keys added."""
    data = tomllib.loads(Path(path).read_text())
    if fluid is not None:
        data["fluid"] = fluid
    data.update(top)
    return data


@pytest.fixture
def solves(monkeypatch):
    """The Physics of every solve ``run_scene`` asks for, with the returned Collision."""
    calls = []
    real = solver.collide

    def recording(physics, *args, **kwargs):
        c = real(physics, *args, **kwargs)
        calls.append((physics, c))
        return c

    monkeypatch.setattr(solver, "collide", recording)
    return calls


def p_star(d: dict) -> float:
    """The pressure scale ``mu a v0 / x1^2`` recomputed from a scene's JSON."""
    return (d["inputs"]["fluid"]["viscosity_Pa_s"] * d["reduced_radius_m"]
            * d["inputs"]["v0_m_per_s"] / d["x1_m"] ** 2)


# ---- the fluids table ---------------------------------------------------------------------------
def test_fluids_carry_their_pressure_dependence_with_a_source(table):
    fluids = table.fluids
    # water and gases: no piezoviscosity (docs/scenes.md: cold water's slightly negative alpha
    # is entered as 0, a dilute gas's viscosity does not depend on pressure)
    assert fluids["water"].pressure_viscosity == 0.0 and fluids["air"].pressure_viscosity == 0.0
    assert fluids["glycerol"].pressure_viscosity > 0.0
    oil = fluids["mineral_oil"]
    assert oil.pressure_viscosity > 0.0 and oil.has_roelands and oil.has_dowson_higginson
    for name, f in fluids.items():
        given = [getattr(f, k) for k in ("pressure_viscosity", "roelands_index",
                                         "dowson_higginson_c1") if getattr(f, k) is not None]
        if given:
            assert len(f.pressure_source) > 20, name
        # liquids' alpha lies below 1e-7 1/Pa (100 1/GPa; mineral oils 20-42 1/GPa) and the
        # Dowson-Higginson density can at most rise by c1/c2 < 1
        assert f.pressure_viscosity is None or 0.0 <= f.pressure_viscosity < 1e-7, name
        if f.has_dowson_higginson:
            assert 0.0 < f.dowson_higginson_c1 / f.dowson_higginson_c2 < 1.0, name


def test_list_materials_shows_the_constants(capsys):
    assert main(["scene", "--list-materials"]) == 0
    out = capsys.readouterr().out
    assert "alpha 5.9 1/GPa" in out and "Roelands Z 0.6" in out and "pressure dependence:" in out


# ---- Scene -> Physics ---------------------------------------------------------------------------
def test_physics_carries_the_laws_constants_scaled_by_the_pressure_scale(table):
    s = scene_from_dict(example(fluid={"name": "mineral_oil"}), table)
    f, ps = s.fluid, s.pressure_scale
    p = s.physics()  # "auto": the fluid's own laws, what the switches turn on
    assert (p.viscosity_law, p.density_law) == ("roelands", "dowson-higginson")
    # one multiplication or division each: float rounding only
    assert p.beta == pytest.approx(f.pressure_viscosity * ps, rel=1e-12) == s.beta
    assert p.roelands_Z == f.roelands_index
    assert p.roelands_PR == pytest.approx(f.roelands_pressure / ps, rel=1e-12)
    assert p.dh_c1 == pytest.approx(f.dowson_higginson_c1 * ps, rel=1e-12)
    assert p.dh_c2 == pytest.approx(f.dowson_higginson_c2 * ps, rel=1e-12)
    # the constant laws are the classic film's Physics exactly (beta = 0: the solver's constant)
    classic = s.physics("off", "constant", "constant")
    assert classic.classic and classic.beta == 0.0
    assert classic == solver.Physics(St=s.stokes, eps=s.eps, Pi=s.Pi, cavitation="off")
    # a fluid with alpha but no Roelands constants gets Barus; alpha = 0 the constant viscosity
    glycerol = scene_from_dict(example(), table).physics()
    assert glycerol.viscosity_law == "barus" and glycerol.density_law == "constant"
    water = scene_from_dict(example(WATER), table).physics()
    assert water.viscosity_law == "constant" and water.beta == 0.0


def test_a_scene_file_brings_its_own_alpha_with_units(table):
    custom = {"viscosity": "1 Pa s", "density": "1200 kg/m^3", "pressure_viscosity": "20 1/GPa"}
    s = scene_from_dict(example(fluid=custom), table)
    # pint's unit conversion and one product: float rounding only
    assert s.fluid.pressure_viscosity == pytest.approx(2e-8, rel=1e-12)
    assert s.beta == pytest.approx(2e-8 * s.pressure_scale, rel=1e-12)
    assert s.fluid.pressure_source == "given in the scene"
    assert s.physics().viscosity_law == "barus"
    s = scene_from_dict(example(fluid={"name": "glycerol", "pressure_viscosity": "5e-9 1/Pa"}),
                        table)
    assert s.fluid.pressure_viscosity == 5e-9 and "given in the scene" in s.fluid.pressure_source
    assert "pressure_viscosity given" in s.fluid.name


def test_scene_file_overrides_the_laws(table):
    s = scene_from_dict(example(viscosity_law="constant"), table)
    assert s.physics().viscosity_law == "constant"
    oil = {"name": "mineral_oil"}
    p = scene_from_dict(example(fluid=oil, viscosity_law="barus", density_law="constant"),
                        table).physics()
    assert (p.viscosity_law, p.density_law) == ("barus", "constant")


# ---- the switches -------------------------------------------------------------------------------
def test_switch_thresholds(table):
    s = scene_from_dict(example(), table)
    alpha = s.fluid.pressure_viscosity
    at = VISCOSITY_SWITCH / alpha  # the peak pressure where alpha p_peak = 0.1
    # 1e-9 relative: far above float rounding, far below any physical difference
    assert checks.viscosity_switch(s, at * (1 + 1e-9))
    assert not checks.viscosity_switch(s, at * (1 - 1e-9))
    assert not checks.viscosity_switch(s, None)  # the classic solve failed: not decided
    water = scene_from_dict(example(WATER), table)
    assert not checks.viscosity_switch(water, 1e12)  # alpha = 0: never
    oil = scene_from_dict(example(fluid={"name": "mineral_oil"}), table)
    c1, c2 = oil.fluid.dowson_higginson_c1, oil.fluid.dowson_higginson_c2
    # c1 p / (1 + c2 p) = 0.01 at p = 0.01 / (c1 - 0.01 c2)
    at = DENSITY_SWITCH / (c1 - DENSITY_SWITCH * c2)
    assert checks.density_rise(oil, at) == pytest.approx(DENSITY_SWITCH, rel=1e-12)
    assert checks.density_switch(oil, at * (1 + 1e-9))
    assert not checks.density_switch(oil, at * (1 - 1e-9))
    assert not checks.density_switch(s, 1e12)  # glycerol: no constants


def test_glycerol_example_switches_the_piezoviscous_film_on_by_itself(solves, capsys):
    assert main(["scene", str(GLYCEROL), "--json", "--accuracy", "fast", "--no-range"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert tuple(d) == RESULT_KEYS and d["status"] == "ok"
    assert d["e_for_dem_range"] is None and d["range_drivers"] == []  # --no-range: none solved
    # decided on the classic film, then solved once more with the law; then once without each
    # piece it switched on (the sensitivity)
    (base, classic), (final, c) = solves[:2]
    assert len(solves) == 2 + len(d["sensitivity"])
    assert base.classic and final == c.physics and final.viscosity_law == "barus"
    alpha = d["inputs"]["fluid"]["pressure_viscosity_per_Pa"]
    p_peak = classic.p_max * p_star(d)
    assert alpha * p_peak >= VISCOSITY_SWITCH
    # the JSON's groups are the Physics solved; beta = alpha p* (a few products: rounding only)
    assert (d["viscosity_law"], d["density_law"], d["cavitation"]) == ("barus", "constant", "off")
    assert d["beta"] == pytest.approx(alpha * p_star(d), rel=1e-12)
    assert d["dimensionless"]["viscosity_law"] == "barus"
    reason = d["viscosity_reason"]
    assert reason.startswith(f"barus viscosity at beta = {d['beta']:.3g}: alpha p_peak = "
                             f"{alpha * p_peak:.3g} at the peak pressure ")
    assert "of the classic film" in reason and f"at least {VISCOSITY_SWITCH:g}" in reason
    assert d["density_reason"].startswith("constant density: glycerol has no Dowson-Higginson")
    assert any(n.startswith("pressure-dependent density not checked") for n in d["notes"])
    # the solver's peak viscosity on approach, also in Pa s (the fluid's mu0 times the ratio)
    ratio = d["dimensionless"]["viscosity_ratio_max_approach"]
    assert d["viscosity_ratio_max_approach"] == ratio > 1.0
    assert d["peak_viscosity_Pa_s"] == pytest.approx(ratio * d["inputs"]["fluid"]["viscosity_Pa_s"],
                                                     rel=1e-12)
    assert d["solidified"] is (ratio >= 1e4)


def test_water_keeps_the_constant_viscosity(solves, capsys):
    assert main(["scene", str(WATER), "--json", "--accuracy", "fast"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["viscosity_law"] == "constant" and d["beta"] == 0.0
    assert d["viscosity_ratio_max_approach"] == 1.0 and d["solidified"] is False
    assert d["viscosity_reason"] == ("constant viscosity: the pressure-viscosity coefficient of "
                                     "water is 0, so the viscosity does not depend on the "
                                     "pressure")
    # the classic film, then the cavitation floor: the viscosity adds no solve (beyond the
    # sensitivity's, without the floor)
    assert [p.classic for p, _ in solves[:2]] == [True, False]
    assert list(d["sensitivity"]) == ["without cavitation"]


def test_mineral_oil_switches_roelands_and_its_density(table, solves):
    r = run_scene(scene_from_dict(example(fluid={"name": "mineral_oil"}), table), accuracy="fast")
    s, d = r.scene, r.to_dict()
    (base, classic), (final, _) = solves[:2]
    assert base.classic and final.viscosity_law == "roelands"
    p_peak = classic.p_max * s.pressure_scale
    rise = checks.density_rise(s, p_peak)
    assert rise > DENSITY_SWITCH and final.density_law == "dowson-higginson"
    assert d["density_reason"].startswith("dowson-higginson density (c1 p* = ")
    assert f"rises by {rise:.2%} at the peak pressure" in d["density_reason"]
    ratio = checks.law_viscosity_ratio(s, "roelands", p_peak)
    assert f"the Roelands viscosity there would be {ratio:.3g} mu0" in d["viscosity_reason"]
    # a Roelands viscosity with the same slope grows slower than Barus' at high pressure (Z < 1)
    assert ratio < math.exp(s.fluid.pressure_viscosity * p_peak)


def test_report_shows_the_laws_and_only_the_constants_in_use(capsys):
    assert main(["scene", str(GLYCEROL), "--accuracy", "fast"]) == 0
    out = capsys.readouterr().out
    assert "alpha = 5.9 1/GPa" in out and "\nviscosity: barus viscosity at beta" in out
    assert "\ndensity: constant density" in out
    rows = {line.split()[0] for line in out.splitlines() if line.startswith("  ")}
    assert {"beta", "viscosity_law", "viscosity_in_tension", "density_law"} <= rows
    assert not {"roelands_Z", "roelands_PR", "dh_c1", "dh_c2"} & rows


def test_fluid_without_alpha_is_not_switched_and_a_warning_says_from_where_it_would(table):
    r = run_scene(scene_from_dict(example(fluid={"name": "silicone_oil_100cst"}), table),
                  accuracy="fast")
    assert r.collision.physics.viscosity_law == "constant"
    assert r.viscosity_reason.startswith("constant viscosity: silicone_oil_100cst has no "
                                         "pressure-viscosity coefficient")
    # the classic film was the only solve: its peak pressure is the result's; an alpha below
    # glycerol's would already switch the law there, so the missing value is a warning
    need = VISCOSITY_SWITCH / r.peak_pressure
    assert need <= checks.ALPHA_KNOWN_LIQUID
    (w,) = [w for w in r.warnings if w.check == "pressure_viscosity"]
    assert w.value == pytest.approx(need) and f"from alpha = {per_gpa(need)} on" in w.message
    assert not [n for n in r.notes if n.startswith("pressure-dependent viscosity not checked")]


def test_fluid_without_alpha_at_a_low_peak_pressure_is_a_note(table):
    # 1e4 times slower than the example: the peak pressure falls below 0.1 / alpha_glycerol = 17 MPa
    r = run_scene(scene_from_dict(example(fluid={"name": "silicone_oil_100cst"}, v0="0.1 mm/s"),
                                  table), accuracy="fast")
    need = VISCOSITY_SWITCH / r.peak_pressure
    assert need > checks.ALPHA_KNOWN_LIQUID
    assert not [w for w in r.warnings if w.check == "pressure_viscosity"]
    (note,) = [n for n in r.notes if n.startswith("pressure-dependent viscosity not checked")]
    assert f"from alpha = {per_gpa(need)} on" in note


# ---- the overrides ------------------------------------------------------------------------------
def test_forced_constant_viscosity_is_one_classic_solve(solves, capsys):
    assert main(["scene", str(GLYCEROL), "--json", "--accuracy", "fast", "--viscosity-law",
                 "constant", "--no-range"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert len(solves) == 1 and solves[0][0].classic
    assert d["viscosity_law"] == "constant" and d["beta"] == 0.0
    assert d["viscosity_ratio_max_approach"] == 1.0 and d["solidified"] is False
    assert d["viscosity_reason"].startswith("constant viscosity, as asked for (viscosity_law = "
                                            "'constant'); alpha = 5.9 1/GPa for glycerol")


def test_forced_laws_through_flags(solves, capsys):
    assert main(["scene", str(GLYCEROL), "--json", "--accuracy", "fast", "--fluid", "mineral_oil",
                 "--viscosity-law", "barus", "--density-law", "constant",
                 "--cavitation", "off"]) == 0
    d = json.loads(capsys.readouterr().out)
    # everything forced: one solve, with what was asked for
    assert len(solves) == 1
    assert (d["viscosity_law"], d["density_law"], d["cavitation"]) == ("barus", "constant", "off")
    assert "as asked for (viscosity_law = 'barus')" in d["viscosity_reason"]
    assert d["density_reason"] == "constant density, as asked for (density_law = 'constant')"
    solves.clear()
    assert main(["scene", str(GLYCEROL), "--json", "--accuracy", "fast", "--viscosity",
                 "0.5 Pa s", "--pressure-viscosity", "10 1/GPa", "--viscosity-law", "barus"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["inputs"]["fluid"]["pressure_viscosity_per_Pa"] == pytest.approx(1e-8, rel=1e-12)
    assert d["beta"] == pytest.approx(1e-8 * p_star(d), rel=1e-12)


# ---- bad input ----------------------------------------------------------------------------------
@pytest.mark.parametrize("change, message", [
    ({"viscosity_law": "quadratic"}, "viscosity_law must be one of"),
    ({"density_law": "tait"}, "density_law must be one of"),
    ({"viscosity_law": "barus", "fluid": {"name": "silicone_oil_10cst"}},
     "needs the fluid's pressure-viscosity coefficient, and the fluid 'silicone_oil_10cst'"),
    ({"viscosity_law": "roelands", "fluid": {"name": "water"}},
     "pressure_viscosity = 0 \\(the fluid .water.\\) is the constant viscosity"),
    ({"viscosity_law": "roelands"}, "needs the fluid's roelands_index and roelands_pressure"),
    ({"density_law": "dowson-higginson"}, "needs the fluid's dowson_higginson_c1"),
    ({"fluid": {"name": "glycerol", "viscosity": "barus"}},
     "fluid.viscosity is the fluid's viscosity .* viscosity_law = 'barus'"),
    ({"fluid": {"name": "glycerol", "pressure_viscosity": "5 Pa"}},
     "fluid.pressure_viscosity: '5 Pa' has units"),
    ({"fluid": {"name": "glycerol", "pressure_viscosity": "-1 1/GPa"}},
     "pressure_viscosity = '-1 1/GPa' is outside its valid range"),
    ({"fluid": {"name": "glycerol", "roelands_index": 0.6}},
     "roelands_index is given without roelands_pressure"),
    ({"fluid": {"name": "glycerol", "dowson_higginson_c2": "1 1/GPa"}},
     "dowson_higginson_c2 is given without dowson_higginson_c1"),
])
def test_bad_law_inputs_name_the_field_and_the_fix(table, change, message):
    with pytest.raises(ValueError, match=message):
        scene_from_dict(example(**change), table)


def test_beta_above_the_solvers_range_says_what_to_do(table):
    # alpha = 1e-7 1/Pa at glycerol's p* ~ 1.3 GPa: beta ~ 130 > 50
    s = scene_from_dict(example(fluid={"name": "glycerol", "pressure_viscosity": "100 1/GPa"}),
                        table)
    assert s.beta > solver.Physics.group("beta").hi
    with pytest.raises(SceneError, match=r"beta = alpha p\* = .* outside the solver's range .*"
                                         "viscosity_law = 'constant'"):
        s.physics()
    assert s.physics(viscosity_law="constant").beta == 0.0  # the way out it names


def test_materials_file_needs_both_constants_of_a_law(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[fluids.oil]\nviscosity = "0.1 Pa s"\ndensity = 870\n'
                   'dowson_higginson_c1 = "0.6 1/GPa"\nsource = "own"\n')
    with pytest.raises(MaterialError, match=r"\[fluids.oil\]: dowson_higginson_c1 is given "
                                            "without dowson_higginson_c2"):
        load_table([bad], user_files=False)


@pytest.mark.parametrize("argv, message", [
    (["--viscosity-law", "quadratic"], "invalid choice"),
    (["--fluid", "silicone_oil_10cst", "--viscosity-law", "barus"], "--pressure-viscosity"),
    (["--viscosity", "barus"], "--viscosity-law"),
])
def test_cli_law_errors_exit_2_with_one_line(capsys, argv, message):
    try:
        code = main(["scene", str(GLYCEROL), "--accuracy", "fast", *argv])
    except SystemExit as exc:  # argparse
        code = exc.code
    assert code == 2
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert len(err) == 1 and message in err[0]
