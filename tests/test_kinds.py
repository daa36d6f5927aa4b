"""The time loop compiled for the pieces a scene asks for (solver/integration/kinds.py,
solver/model/kind.py): which copy a physics runs, what a copy shares with the solver as imported,
that a copy refuses a physics whose code it lacks, and that a copy's results are the loop's own."""

import math
import subprocess
import sys
from pathlib import Path

import pytest

from solver import Physics, collide
from solver.integration import kinds, stepper
from solver.model import kind

REPO = Path(__file__).resolve().parents[1]

# one physics per piece, alone and as the solver's tests combine them
PHYSICS = {
    (): dict(),
    ("cavitation",): dict(Pi=1e-3, cavitation="reynolds"),
    ("contact",): dict(roughness=1.0),
    ("liquid",): dict(density_law="dowson-higginson"),
    ("slip",): dict(slip_length=0.1),
    ("cavitation", "contact", "liquid"): dict(Pi=1e-3, cavitation="jfo", roughness=1.0,
                                              viscosity_table="0:1, 1:2"),
    ("contact", "liquid", "slip"): dict(roughness=1.0, beta=1.0, slip_length=0.1),
}


@pytest.mark.parametrize("codes", list(PHYSICS))
def test_the_pieces_asked_are_the_physics_switched_on(codes):
    """``asked_codes`` reads the physics array as the compiled hooks do, and names the pieces the
    physics switches on (solver/physics.py's own account of them)."""
    physics = Physics(St=10.0, eps=1e-4, **PHYSICS[codes])
    assert kind.asked_codes(physics.as_array()) == codes
    switched_on = tuple(name for name, on in (
        ("cavitation", physics.cavitation != "off"), ("contact", not physics.smooth),
        ("liquid", not physics.isoviscous), ("slip", physics.slip_length > 0.0)) if on)
    assert switched_on == codes


def test_a_copy_holds_the_pieces_asked_and_shares_the_rest_of_the_solver():
    """The classic film's copy is loaded once, under its own package, with every piece's constant
    False; the modules it does not copy are the solver's own (one ``Physics``, one grid record),
    and the solver as imported keeps every piece."""
    phys = Physics(St=10.0, eps=1e-4).as_array()
    loop = kinds.loop_for(phys)
    assert loop is kinds.loop_for(phys)
    assert loop.__name__ == "solver._loop_classic.integration.stepper"
    constants = sys.modules["solver._loop_classic.model.kind"]
    assert [getattr(constants, f"{c.upper()}_CODE") for c in kind.CODES] == [False] * 4
    assert [getattr(kind, f"{c.upper()}_CODE") for c in kind.CODES] == [True] * 4
    copied = {f"solver._loop_classic.{name}" for name in kinds._COPIED + kinds._PACKAGES}
    for name, module in sys.modules.items():
        if name.startswith("solver._loop_classic.") and name not in copied:
            assert module is sys.modules["solver." + name[len("solver._loop_classic."):]], name
    assert loop.model.has_active_set is not stepper.model.has_active_set
    assert loop.holds_asked is constants.holds_asked is not kind.holds_asked


# a classic collision in a fresh interpreter: the solver's modules it imported, and which of the
# copy's modules are not the solver's own though not copied either
FRESH_CLASSIC = """
import sys
from solver import Physics, collide
from solver.integration import kinds
assert collide(Physics(St=10.0, eps=1e-4), accuracy="fast").status == "ok"
copied = {f"solver._loop_classic.{name}" for name in kinds._COPIED + kinds._PACKAGES}
print(sorted(name for name in sys.modules if name.startswith("solver.")
             and not name.startswith("solver._loop_")))
print(sorted(name for name, module in sys.modules.items()
             if name.startswith("solver._loop_classic.") and name not in copied
             and module is not sys.modules.get("solver." + name[len("solver._loop_classic."):])))
print(sorted(name for name, module in sys.modules.items() if name.startswith("solver.")
             and not name.startswith("solver._loop_") and module.__spec__.name != name))
"""


def test_a_classic_film_imports_no_loop_with_every_piece_and_its_copy_shares_the_rest():
    """A process that solves only the classic film never imports the loop with every piece nor
    the modules only it and the copies use (their dispatchers cost a warm ``ehd run`` about
    20 ms: docs/solver.md, "Compiled code"); the copy's imports of what it does not copy are the
    solver's own modules even where nothing had imported them before (kinds._SharedModules), so
    the copy shares its records. In a fresh interpreter: the module list an in-process test
    cannot see."""
    p = subprocess.run([sys.executable, "-c", FRESH_CLASSIC], cwd=REPO, capture_output=True,
                       text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    imported, not_shared, renamed = (eval(line) for line in p.stdout.splitlines())
    # (model/kind.py, liquid.py and slip.py serve the solver's Python too: the rigid paths)
    generic = {f"solver.{name}" for name in kinds._COPIED
               if name not in ("model.kind", "model.liquid", "model.slip")}
    assert len(generic) == 5, generic  # the loop and the film model's contract, as compiled
    assert not generic & set(imported), sorted(generic & set(imported))
    assert "solver.integration.dense" in imported  # the shared module the copy's loop reads
    assert not_shared == [], not_shared
    assert renamed == [], renamed  # a shared module keeps its own __spec__, not the copy's


@pytest.mark.parametrize("codes", list(PHYSICS))
def test_the_classic_film_has_a_copy_and_any_piece_runs_the_loop_with_every_piece(codes):
    """Each copy compiles apart (13.6-14.8 s of CPU for a piece alone against 18.8-20.4 s for
    the loop with every piece, in one run at 1.16.1), so only the classic film gets one; any
    piece runs the loop as imported, which holds them all."""
    loop = kinds.loop_for(Physics(St=10.0, eps=1e-4, **PHYSICS[codes]).as_array())
    assert kinds.MOST_PIECES == 0
    if codes:
        assert loop is stepper
    else:
        assert loop.__name__ == f"solver._loop_{'_'.join(codes) or 'classic'}.integration.stepper"


def test_a_copy_refuses_a_physics_whose_code_it_lacks(monkeypatch):
    """The classic film's copy asked to run a cavitating film raises at its start (its hooks would
    answer as the classic film): ``loop_for`` never hands it one."""
    classic = kinds.loop_for(Physics(St=10.0, eps=1e-4).as_array())
    monkeypatch.setattr(kinds, "loop_for", lambda phys, log=False: classic)
    with pytest.raises(ValueError, match="lacks the code of a piece"):
        collide(Physics(St=10.0, eps=1e-4, Pi=1e-3, cavitation="jfo"), accuracy="fast")


def test_a_copy_gives_the_loop_with_every_piece_its_answer(monkeypatch):
    """A copy is the loop with the absent pieces' branches pruned: the same arithmetic, which
    LLVM inlines and contracts into fused multiply-adds its own way, so the two differ in
    rounding, and where that steers the step control the answers differ by what the control
    accepts as a step's error (rtol 1e-4 at the standard preset). Measured (solver 1.16.0): the
    classic film 4e-13 apart at most (a JFO film's copy, since retired, 2.1e-6 in e_wet, 346
    steps against 347). 1e-5, a tenth of rtol, is far below what a piece answering wrongly
    moves (e_wet 0 here without the floor, 0.265 with it)."""
    physics = Physics(St=10.0, eps=1e-4)
    own = collide(physics, accuracy="standard")
    monkeypatch.setattr(kinds, "loop_for", lambda phys, log=False: stepper)
    general = collide(physics, accuracy="standard")
    assert own.status == general.status == "ok"
    for name in ("e_wet", "v_r", "h_m_x1", "ln_x_e_x1", "p_max"):
        a, b = getattr(own, name), getattr(general, name)
        assert math.isclose(a, b, rel_tol=1e-5), (name, a, b)


def _scene(**fields):
    physics = Physics(St=10.0, eps=1e-4, **fields)
    return {name: getattr(physics, name) for name in Physics.names()}


def test_a_sweeps_warm_up_solves_once_for_every_set_of_pieces_it_asks_for(monkeypatch):
    """A sweep's warm-up (pipeline/sweeps/tasks.py) compiles, before any worker starts, every loop
    its scenes run on (``kinds.compiled_pieces``): each compiles apart, and a worker that met one
    first would compile it on its own (each of a cluster's workers). One scene per loop, at the
    warm-up's St 5 and eps 0.01; one not valid there is left to its workers."""
    import solver
    from pipeline.sweeps.tasks import one_scene_per_set, warm

    scenes = [_scene(), _scene(Pi=1e-3, cavitation="jfo"), _scene(Pi=1e-2, cavitation="jfo"),
              _scene(roughness=1.0), _scene(roughness=20.0, Pi=1e-3, cavitation="reynolds")]
    picked = one_scene_per_set(scenes)
    assert picked == [scenes[1]]  # the classic film: the warm-up's own; every piece: one loop
    solved = []

    def collide(physics, eps=None, **_):
        physics = Physics(St=physics, eps=eps) if eps is not None else physics
        solved.append((physics.St, physics.eps, kind.asked_codes(physics.as_array())))

    monkeypatch.setattr(solver, "collide", collide)
    warm("fast", {}, picked)
    assert solved == [(5.0, 0.01, ()), (5.0, 0.01, ("cavitation",))]
    # a scene not valid at the warm-up's start is left to the workers: roughness 20 lies beyond
    # the start gap at eps 0.01 (6.3 x1), and the loop with every piece is compiled by them
    solved.clear()
    warm("fast", {}, one_scene_per_set([_scene(), scenes[4]]))
    assert solved == [(5.0, 0.01, ())]
