"""Each piece of physics declared once (issue 28, item 1): the collision's phases, the shortcuts and
the scene layer's code name none (solver/pieces.py, pipeline/scenes/pieces.py declare them), and
every scene input a piece declares (``pipeline.scenes.pieces.ScenePiece``) reaches the scene."""

import io
import re
import tokenize
from pathlib import Path

import pytest

from pipeline.scenes.pieces import PIECES

# the shipped table, and no user materials (~/.config/ehd, $EHD_MATERIALS)
from tests.test_scene import _no_user_materials  # noqa: F401

REPO = Path(__file__).resolve().parent.parent
# the words that name a piece (issue 28, "Done when"), as its grep spells them
PIECE_WORDS = re.compile(r"rough|jfo|cavit|barus|piezo")
# the files that must name no piece outside comments (docstrings are code here)
NAMING_NONE = ("solver/collision.py", "solver/shortcuts.py", "pipeline/scenes/run.py",
               "pipeline/scenes/commands.py")


def piece_words(source: str) -> list[str]:
    """``"line: text"`` of every line of ``source`` that names a piece outside its ``#``
    comments (the issue's grep, with the comments taken out by the tokenizer)."""
    lines = source.splitlines()
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:  # one comment per line, ending it
            row, col = tok.start
            lines[row - 1] = lines[row - 1][:col]
    return [f"{n}: {line.strip()}" for n, line in enumerate(lines, 1)
            if PIECE_WORDS.search(line)]


def test_the_check_finds_a_piece_in_code_and_docstrings_but_not_in_comments():
    source = ('"""Solves with cavitation."""\n'
              "# the JFO floor: a comment\n"
              "x = 1  # barus: a comment too\n"
              "y = 'piezoviscous'\n")
    assert piece_words(source) == ['1: """Solves with cavitation."""', "4: y = 'piezoviscous'"]


@pytest.mark.parametrize("path", NAMING_NONE)
def test_the_phases_the_shortcuts_and_the_scene_layer_name_no_piece(path):
    found = piece_words((REPO / path).read_text())
    assert not found, f"{path} names a piece (declare it in solver/pieces.py or " \
        "pipeline/scenes/pieces.py):\n" + \
        "\n".join(found)


def _dests(flags):
    return [dest for flag in flags for _, dest, _, _ in flag.options()]


def test_declarations_are_whole():
    from solver.physics import Physics

    from pipeline.scenes import commands
    from pipeline.scenes.flags import GROUPS
    from pipeline.scenes.run import RESULT_KEYS

    dests = _dests(commands._SCENE_FLAGS)
    assert len(dests) == len(set(dests))  # one flag per dest: none shadows another
    assert {flag.help_group for flag in commands._SCENE_FLAGS} <= set(GROUPS)
    for piece in PIECES:
        switch = [flag for flag in piece.flags if flag.where == piece.field]
        assert len(switch) == 1 and "auto" in switch[0].choices, piece.field
        for name, laws in piece.law_rows.items():
            assert name in Physics.names() and set(laws) <= set(switch[0].choices), name
        assert set(piece.quantities) <= set(RESULT_KEYS), piece.field


SCENE = str(REPO / "examples" / "steel_ball_glass_wall_glycerol.toml")
_DH = ["--dowson-higginson-c1", "0.6 1/GPa", "--dowson-higginson-c2", "1.7 1/GPa"]
_ROELANDS = ["--roelands-index", "0.6", "--roelands-pressure", "196 MPa"]
# per declared flag (its dest): the flags given (with the partners it needs), where it lands in
# the Scene, and the value there (SI). Every value differs from the example's own, so a flag that
# did not reach the scene fails.
CASES = {
    "cavitation_pressure": (["--cavitation-pressure", "1 kPa"],
                            lambda s: s.cavitation_pressure, 1e3),
    "tensile_strength": (["--tensile-strength", "10 MPa"],
                         lambda s: s.ambient_pressure - s.cavitation_pressure, 1e7),
    "cavitation": (["--cavitation", "jfo"], lambda s: s.cavitation, "jfo"),
    "pressure_viscosity": (["--pressure-viscosity", "20 1/GPa"],
                           lambda s: s.fluid.pressure_viscosity, 20e-9),
    "roelands_index": (_ROELANDS, lambda s: s.fluid.roelands_index, 0.6),
    "roelands_pressure": (_ROELANDS, lambda s: s.fluid.roelands_pressure, 196e6),
    "viscosity_law": (["--viscosity-law", "barus"], lambda s: s.viscosity_law, "barus"),
    "dowson_higginson_c1": (_DH, lambda s: s.fluid.dowson_higginson_c1, 0.6e-9),
    "dowson_higginson_c2": (_DH, lambda s: s.fluid.dowson_higginson_c2, 1.7e-9),
    "density_law": ([*_DH, "--density-law", "dowson-higginson"], lambda s: s.density_law,
                    "dowson-higginson"),
    "roughness1": (["--roughness1", "0.3 um"], lambda s: s.body1.solid.roughness, 0.3e-6),
    "roughness2": (["--roughness2", "0.2 um"], lambda s: s.body2.solid.roughness, 0.2e-6),
    "asperity_contact": (["--asperity-contact", "on", "--roughness1", "0.3 um"],
                         lambda s: s.asperity_contact, "on"),
    "e_dry": (["--e-dry", "0.5"], lambda s: s.e_dry, 0.5),
}


def test_every_declared_flag_has_a_case():
    assert set(CASES) == set(_dests(f for piece in PIECES for f in piece.flags))


@pytest.mark.parametrize("dest", sorted(CASES))
def test_every_declared_flag_reaches_the_scene(dest):
    from pipeline.cli import _parser
    from pipeline.scenes.commands import flag_values, load_scene

    argv, where, value = CASES[dest]
    args = _parser(["scene"]).parse_args(["scene", SCENE, *argv])
    before, after = where(load_scene(SCENE)), where(load_scene(SCENE, flag_values(args)))
    # rel 1e-12: a unit's conversion to SI rounds in the last digits, nothing more
    assert after == (value if isinstance(value, str) else pytest.approx(value, rel=1e-12))
    assert before != after
