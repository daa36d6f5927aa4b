"""The one place that decides which analytic shortcut is exact for a scene (solver/shortcuts.py):
each piece of physics against what docs/model.md says of it, and the collision taking the plan's
pieces and no others."""

import math

import numpy as np
import pytest

from solver import Physics, collide
from solver.integration.events import RELAXED, RELAXED_FULL
from solver.master import MasterCurve
from solver.shortcuts import plan

CASES = {  # Physics fields: (approach, end event, departure, floor, classic)
    "classic": ({}, ("classic", RELAXED, "classic", False, True)),
    "barus": (dict(beta=2.0), ("barus", RELAXED, "classic", False, False)),
    "barus+dh": (dict(beta=2.0, density_law="dowson-higginson"),
                 ("classic", RELAXED, "classic", False, False)),
    "roelands": (dict(beta=2.0, viscosity_law="roelands"),
                 ("classic", RELAXED, "classic", False, False)),
    "reynolds": (dict(Pi=1e-3, cavitation="reynolds"),
                 ("classic", RELAXED, "floor", True, False)),
    "jfo": (dict(Pi=1e-3, cavitation="jfo"), ("classic", RELAXED_FULL, "classic", True, False)),
    "jfo at Pi 0": (dict(Pi=0.0, cavitation="jfo"), ("classic", RELAXED, "floor", True, False)),
    "barus+jfo": (dict(beta=1.0, Pi=1e-3), ("barus", RELAXED_FULL, "classic", True, False)),
    "no floor at Pi inf": (dict(Pi=math.inf, cavitation="jfo"),
                           ("classic", RELAXED, "classic", False, True)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_each_physics_gets_the_shortcuts_docs_model_gives_it(case):
    fields, expected = CASES[case]
    p = plan(Physics(St=10.0, eps=1e-3, **fields))
    assert (p.approach, p.end_event, p.departure, p.floor, p.classic) == expected


def test_the_master_curve_refuses_what_the_plan_does_not_give_it():
    with pytest.raises(ValueError, match="classic film only"):
        empty = MasterCurve(accuracy="fast", overrides=(), s=np.empty(0), table={})
        empty.collide(Physics(St=10.0, eps=1e-3, Pi=1e-3))


def test_a_collision_ends_its_coupled_phase_as_planned():
    """A JFO cavity with a memory: the coupled phase goes on until the film is full again, so its
    last row has no cavity; the Reynolds film is released with its cavity open and departs by the
    floor's ODE (phase 2 rows with a cavity)."""
    jfo = collide(Physics(St=10.0, eps=1e-2, Pi=1e-3, cavitation="jfo"), accuracy="fast",
                  save_profiles=False)
    coupled = jfo.series["phase"] == 1
    assert jfo.ok and jfo.cavitated and jfo.series["cavity_radius"][coupled][-1] == 0.0
    reynolds = collide(Physics(St=10.0, eps=1e-2, Pi=1e-3, cavitation="reynolds"),
                       accuracy="fast", save_profiles=False)
    departure = reynolds.series["phase"] == 2
    assert reynolds.ok and reynolds.series["cavity_radius"][departure].max() > 0.0
