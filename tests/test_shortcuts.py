"""The one place that decides which analytic shortcut is exact for a scene (solver/shortcuts.py):
each piece of physics against what docs/model.md says of it, and the collision taking the plan's
pieces and no others."""

import math

import numpy as np
import pytest

from solver import Physics, collide
from solver.collision import rigid_head, scene_grid
from solver.integration.events import RELAXED, RELAXED_APART, RELAXED_FULL
from solver.master import MasterCurve
from solver.model import contact
from solver import pieces
from solver.pieces import PIECES, Piece, cavity_reach
from solver.settings import resolve
from solver.shortcuts import plan

CASES = {  # Physics fields: (approach, end event, departure, classic)
    "classic": ({}, ("classic", RELAXED, "classic", True)),
    "barus": (dict(beta=2.0), ("barus", RELAXED, "classic", False)),
    "barus+dh": (dict(beta=2.0, density_law="dowson-higginson"),
                 ("classic", RELAXED, "classic", False)),
    "roelands": (dict(beta=2.0, viscosity_law="roelands"), ("classic", RELAXED, "classic", False)),
    "reynolds": (dict(Pi=1e-3, cavitation="reynolds"), ("classic", RELAXED, "floor", False)),
    "jfo": (dict(Pi=1e-3, cavitation="jfo"), ("classic", RELAXED_APART, "floor", False)),
    # a compressible liquid's cells hold rho theta H, which the refill departure does not
    "jfo+dh": (dict(Pi=1e-3, cavitation="jfo", beta=2.0, density_law="dowson-higginson"),
               ("classic", RELAXED_FULL, "classic", False)),
    "jfo at Pi 0": (dict(Pi=0.0, cavitation="jfo"), ("classic", RELAXED, "floor", False)),
    "barus+jfo": (dict(beta=1.0, Pi=1e-3), ("barus", RELAXED_APART, "floor", False)),
    "no floor at Pi inf": (dict(Pi=math.inf, cavitation="jfo"),
                           ("classic", RELAXED, "classic", True)),
    "rough": (dict(roughness=2.0), ("classic", RELAXED, "classic", False)),
    "rough+barus": (dict(roughness=2.0, beta=1.0), ("barus", RELAXED, "classic", False)),
    "rough+jfo": (dict(roughness=2.0, Pi=1e-3, cavitation="jfo"),
                  ("classic", RELAXED_APART, "floor", False)),
    "slip": (dict(slip_length=1.0), ("slip", RELAXED, "slip", False)),
    "slip+rough": (dict(slip_length=1.0, roughness=2.0), ("slip", RELAXED, "slip", False)),
    # the Barus approach is not exact with slip: slip's stop hands it over at the start
    "slip+barus": (dict(slip_length=1.0, beta=1.0), ("barus", RELAXED, "slip", False)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_each_physics_gets_the_shortcuts_docs_model_gives_it(case):
    fields, expected = CASES[case]
    p = plan(Physics(St=10.0, eps=1e-3, **fields))
    assert (p.approach, p.end_event, p.departure, p.classic) == expected


# each piece switched on alone, and what it must do to the collision's phases beyond the plan
ALONE = {"pressure-dependent liquid": dict(beta=2.0, viscosity_law="roelands"),
         "cavitation": dict(Pi=1e-3, cavitation="jfo"),
         "asperity contact": dict(roughness=2.0),
         "slip": dict(slip_length=1.0)}


def test_every_piece_is_covered_here():
    assert {p.name for p in PIECES} == set(ALONE)


@pytest.mark.parametrize("name", list(ALONE))
def test_a_piece_that_is_off_answers_as_the_classic_film(name):
    """Every hook of a piece that is off for the classic film leaves the classic shortcuts: no
    stop, no own approach or departure, no refill, no grid width or reach, no rest."""
    piece = next(p for p in PIECES if p.name == name)
    classic, numerics = Physics(St=10.0, eps=1e-3), resolve("fast")
    assert piece.approach_stop(classic, numerics) is None
    assert not (piece.approach_exact(classic) or piece.departure_exact(classic)
                or piece.refills(classic) or piece.rests(classic, 0.0)
                or piece.keeps_profile(classic))
    assert piece.film_width(classic) == 0.0 and piece.film_reach(classic) == 0.0


def test_the_rough_pieces_stop_the_rigid_approach_before_the_asperities_touch():
    """The asperity contact stops the classic rigid approach, and a piece's own (Barus) rigid
    approach, at contact.CONTACT_MARGIN roughnesses, where the rigid gap is still clear of the
    asperities (the bug this guards: a rough Barus film handed over inside the asperity layer)."""
    numerics = resolve("fast")
    # roughness 7 x1: the contact onset 14 x1 lies between the smooth hand-overs (12.1 x1 for
    # both at St 10, eps 1e-3) and the start x0 = 15.8 x1
    for fields in (dict(roughness=7.0), dict(roughness=7.0, beta=1.0)):
        physics = Physics(St=10.0, eps=1e-3, **fields)
        head = rigid_head(physics, numerics)
        assert head.x >= contact.CONTACT_MARGIN * physics.roughness * (1.0 - 1e-12)
        smooth = rigid_head(physics.replace(roughness=0.0), numerics)
        assert head.x > smooth.x  # the contact, not the deformation, stopped it


def test_the_grid_covers_what_each_piece_needs():
    """The inner region covers the asperity film sqrt(2 sigma); the grid reaches the widest cavity
    (pieces.cavity_reach) with a floor, and not without one."""
    numerics = resolve("fast")
    rough = Physics(St=10.0, eps=1e-8, roughness=200.0)  # x0 = 1585 x1
    floor = Physics(St=10.0, eps=1e-3, Pi=1e-6, cavitation="jfo")
    for physics in (rough, floor):
        classic = scene_grid(10.0, 5.0, numerics)
        grid = scene_grid(10.0, 5.0, numerics, max(p.film_width(physics) for p in PIECES),
                          max(p.film_reach(physics) for p in PIECES))
        assert grid.radius[-1] > classic.radius[-1]
    assert np.array_equal(scene_grid(10.0, 5.0, numerics, 0.0, cavity_reach(math.inf)).radius,
                          scene_grid(10.0, 5.0, numerics).radius)
    assert scene_grid(10.0, 5.0, numerics, 0.0, cavity_reach(1e-6)).radius[-1] >= cavity_reach(1e-6)


def test_the_master_curve_refuses_what_the_plan_does_not_give_it():
    with pytest.raises(ValueError, match="classic film only"):
        empty = MasterCurve(accuracy="fast", overrides=(), s=np.empty(0), table={})
        empty.collide(Physics(St=10.0, eps=1e-3, Pi=1e-3))


def test_a_collision_ends_its_coupled_phase_as_planned():
    """A JFO cavity with a memory: the coupled phase ends at the release once the spheres separate,
    its last row with the cavity open, and the refill departure (phase 2 rows with a cavity that
    only shrinks) holds it until the front reaches the axis; in a compressible liquid the coupled
    phase goes on until the film is full again, so its last row has no cavity. The Reynolds film
    is released with its cavity open and departs by the floor's ODE (phase 2 rows with a
    cavity)."""
    jfo = collide(Physics(St=10.0, eps=1e-2, Pi=1e-3, cavitation="jfo"), accuracy="fast",
                  save_profiles=False)
    coupled, departure = jfo.series["phase"] == 1, jfo.series["phase"] == 2
    radius = jfo.series["cavity_radius"]
    assert jfo.ok and jfo.cavitated and radius[coupled][-1] > 0.0 > jfo.series["V"][coupled][-1]
    assert radius[departure][0] > 0.0 and np.all(np.diff(radius[departure]) <= 0.0)
    compressible = collide(Physics(St=10.0, eps=1e-2, Pi=1e-3, cavitation="jfo", beta=2.0,
                                   density_law="dowson-higginson"), accuracy="fast",
                           save_profiles=False)
    coupled = compressible.series["phase"] == 1
    assert compressible.ok and compressible.series["cavity_radius"][coupled][-1] == 0.0
    reynolds = collide(Physics(St=10.0, eps=1e-2, Pi=1e-3, cavitation="reynolds"),
                       accuracy="fast", save_profiles=False)
    departure = reynolds.series["phase"] == 2
    assert reynolds.ok and reynolds.series["cavity_radius"][departure].max() > 0.0


def test_a_new_piece_is_one_declaration(monkeypatch):
    """Issue 28, item 4, at the level of the collision's phases: a piece declared here only (no
    source file changes) reaches the hand-over, the shortcuts and the end of the coupled phase,
    because collision.py and shortcuts.py iterate over ``pieces.PIECES``. This test piece stops
    the classic rigid approach at twice the classic hand-over's gap, and holds the spheres at rest
    at the release (as the asperity contact does)."""
    physics = Physics(St=30.0, eps=1e-4)  # rebounds past x0: e_wet 0.51
    numerics = resolve("fast")
    before = collide(physics, accuracy="fast", save_profiles=False)
    x_classic = rigid_head(physics, numerics).x

    early = Piece("test: earlier hand-over",
                  approach_stop=lambda ph, nu: min(2.0 * x_classic, ph.x_start))
    monkeypatch.setattr(pieces, "PIECES", pieces.PIECES + (early,))
    assert rigid_head(physics, numerics).x == min(2.0 * x_classic, physics.x_start)
    after = collide(physics, accuracy="fast", save_profiles=False)
    assert after.ok and after.tau_handover < before.tau_handover
    # the classic rigid approach is exact to `switch` up to its own hand-over, so handing over
    # earlier removes at most the part of fast's error the hand-over causes: 6.4e-3 of v_r, max
    # over the accuracy panel (benchmarks/accuracy.md, "Which error dominates"); measured 1.9e-4
    assert after.v_r == pytest.approx(before.v_r, rel=6.4e-3)
    assert after.e_wet == pytest.approx(before.e_wet, rel=6.4e-3)

    sticky = Piece("test: rest at the release", rests=lambda ph, v: True)
    monkeypatch.setattr(pieces, "PIECES", pieces.PIECES + (sticky,))
    held = collide(physics, accuracy="fast", save_profiles=False)
    assert held.ok and held.e_wet == 0.0 and held.e_x0 == 0.0
