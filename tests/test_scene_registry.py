"""``ehd scene``'s SI keys and report rows come from the observable registry (issue 28 item 3)."""

import tomllib
from pathlib import Path

import pytest

from pipeline.scenes.run import run_scene
from pipeline.scenes.scene_file import scene_from_dict

# the shipped table, and no user materials (~/.config/ehd, $EHD_MATERIALS)
from tests.test_scene import _no_user_materials, table  # noqa: F401

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def _example(name: str, **changes) -> dict:
    data = tomllib.loads((EXAMPLES / name).read_text())
    for key, value in changes.items():
        section, _, field = key.rpartition("__")
        (data.setdefault(section, {}) if section else data)[field] = value
    return data


# a film with every conditional row (cavity, pressure-dependent viscosity), the classic film,
# two unequal spheres (no outer flow), a failed solve
SCENES = {
    "classic": (_example("sandstone_water.toml", cavitation="off",
                         body1__roughness="0 m", body2__roughness="0 m"), {}),
    "roelands+dowson-higginson": (_example("steel_ball_glass_wall_glycerol.toml",
                                           fluid={"name": "mineral_oil"}), {}),
    "unequal spheres": (_example("sandstone_water.toml", body2__radius="120 um"), {}),
    "failed": (_example("sandstone_water.toml", cavitation="off"), {"max_steps": 12}),
}


@pytest.fixture(scope="module")
def solved():
    from pipeline.scenes.materials import load_table

    t = load_table(user_files=False)
    return {name: run_scene(scene_from_dict(data, t), accuracy="fast", sensitivity_solves=False,
                            **overrides)
            for name, (data, overrides) in SCENES.items()}


def test_unequal_spheres_read_e_far_and_a_failed_scene_has_null_keys(solved):
    from pipeline.scenes.commands import format_report

    # two unequal spheres: their own outer flow (geometry "pair") reads e_far
    d = solved["unequal spheres"].to_dict()
    assert d["outer_geometry"] == "pair" and d["e_far"] is not None
    assert d["outer_start_speed_m_per_s"] > 0.0
    assert d["e_wet"] is not None and d["closest_approach_nm"] > 0.0
    assert "far-field restitution e_far" in format_report(d)
    # a failed scene: the film's results null (flags unknown too), the report says why; the
    # outer path's speed does not depend on the film
    r = solved["failed"]
    assert r.collision.status == "max_steps"
    d = r.to_dict()
    for key in ("v_r", "e_wet", "e_far", "closest_approach_nm", "peak_force_N", "time_to_stop_s",
                "escaped", "dimple", "equilibrium_separation_m"):
        assert d[key] is None, key
    assert d["outer_start_speed_m_per_s"] > 0.0
    assert "solve FAILED (max_steps)" in format_report(d)


# ---- the registry is the one list -------------------------------------------------------------
def test_every_scene_key_of_the_registry_is_in_the_json_and_its_scale_is_known(solved):
    from pipeline.scenes.run import RESULT_KEYS, SCALES, scene_keys

    keys = scene_keys()
    assert len(keys) >= 28  # the observables ehd scene shows in SI; a broken walk finds none
    for o, k in keys:
        assert k.key in RESULT_KEYS, k.key
        assert (k.scale or o.units) in SCALES, (o.name, k.scale or o.units)
        assert k.form in ("", "exp", "log10") and (k.form == "" or o.units == "1"), o.name
    d = solved["classic"].to_dict()
    for o, k in keys:
        assert k.key in d, k.key


def test_a_report_row_per_labelled_key_where_its_condition_holds(solved):
    from pipeline.scenes.commands import format_report
    from pipeline.scenes.run import scene_keys

    d = solved["roelands+dowson-higginson"].to_dict()
    assert d["cavitated"] and d["viscosity_law"] == "roelands"  # every condition holds
    report = format_report(d).splitlines()
    for _, k in scene_keys():
        if k.label:
            assert any(line.startswith(f"  {k.label}  ") for line in report), k.label
    # the classic film has no cavity rows and no viscosity rows
    classic = format_report(solved["classic"].to_dict())
    assert "largest cavity radius" not in classic and "peak viscosity" not in classic


@pytest.fixture
def test_observable(monkeypatch):
    """A test-only observable, declared as docs/developer.md says: one registry entry (and the
    code computing it, here a property of Collision)."""
    from solver import observables
    from solver.observables import Observable, SceneKey
    from solver.result import Collision

    extra = Observable("tau_rebound_test", "float", "test only: time from v = 0 to the largest "
                       "rebound speed", "x0/v0", derived=True,
                       scene=(SceneKey("rebound_duration_test_s", label="rebound duration (test)"),))
    monkeypatch.setattr(observables, "OBSERVABLES", (*observables.OBSERVABLES, extra))
    monkeypatch.setattr(Collision, extra.name,
                        property(lambda c: c.tau_max_rebound - c.tau_v_zero), raising=False)
    return extra


def test_a_new_observable_is_one_entry_for_ehd_scene_too(table, test_observable):
    from pipeline.scenes.commands import format_report

    r = run_scene(scene_from_dict(SCENES["classic"][0], table), accuracy="fast",
                  sensitivity_solves=False)
    c, s = r.collision, r.scene
    d = r.to_dict()
    assert list(d)[-5] == "rebound_duration_test_s"  # after the registry's, before the last four
    # the value is the observable times its scene scale x0/v0, bit for bit (one product)
    want = (c.tau_max_rebound - c.tau_v_zero) * s.time_scale
    assert want > 0.0 and d["rebound_duration_test_s"] == want
    row = next(line for line in format_report(d).splitlines()
               if line.startswith("  rebound duration (test)  "))
    from pipeline.scenes.units import format_quantity

    assert row.split("  ")[-1].strip() == format_quantity(want, "s")
