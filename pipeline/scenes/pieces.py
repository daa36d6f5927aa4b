"""The pieces of physics a scene switches by itself, declared once (issue 28, item 1: the scene
layer iterates over them and names none).

A scene field set to "auto" is a switch: ``run.run_scene`` solves the film first with every
automatic piece at its ``base`` (the classic film's choice), then asks each piece whether that
first film needs it (``switch``, from the ``BaseFilm``), and solves again with the pieces that
fired at ``on``. Each piece says why in one sentence (``reason``, JSON ``reason_key``, report
line ``report``), and how it is switched off for the sensitivity (``without``). The rules and
sentences themselves are in :mod:`pipeline.scenes.checks`; docs/scenes.md ("Which model, and
why", "Cavitation", "Pressure-dependent viscosity and density", "Surface roughness") has them
in words.

Each piece also declares the scene inputs it reads and what it adds to the results:

- ``flags``: its ``ehd scene`` flags (``flags.SceneFlag``: flag, the scene-file key it fills,
  help, choices, group), the switch's own flag among them; ``commands.py`` adds them to the
  parser and merges them into the scene file;
- ``law_rows``: the ``Physics`` fields that are constants of one of its laws, with the laws
  that use them: the report shows such a row only where the scene solved with one of those laws
  (the JSON has them all);
- ``quantities``: its JSON keys of the scene's inputs in SI, ``{key: scene -> value}``, which
  ``run.SceneResult.to_dict`` writes after the reasons.

A new piece the scene switches: one ``ScenePiece`` here, its rule and reason in checks.py, its
field in ``Scene`` (with ``Scene.physics`` taking the field as a keyword), and the keys its flags
fill read in ``scene_file.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field as dataclass_field
from typing import Callable

from .flags import SceneFlag
from .scene import CAVITATION_CHOICES, DENSITY_CHOICES, ROUGHNESS_CHOICES, VISCOSITY_CHOICES

__all__ = ["BaseFilm", "ScenePiece", "PIECES", "REASON_KEYS", "QUANTITY_KEYS", "STIFFNESS_LABELS"]

# the sensitivity's labels of the asperity layer's stiffness, 10x either way (the least known
# input of the asperity contact; answer.py reads them as a driver of the range)
STIFFNESS_LABELS = ("asperities 10x stiffer", "asperities 10x softer")


def _stiffness_variants(physics) -> dict:
    if physics.smooth:
        return {}
    return {label: physics.replace(asperity_stiffness=physics.asperity_stiffness * factor)
            for factor, label in zip((10.0, 0.1), STIFFNESS_LABELS)}


@dataclass(frozen=True)
class BaseFilm:
    """What the film solved first says: its collision, pressure extremes [Pa, gauge] and
    closest approach [m] (None where it failed)."""

    collision: object
    p_min: float | None
    p_max: float | None
    h_m: float | None

    @classmethod
    def of(cls, scene, c) -> "BaseFilm":
        if not c.ok:
            return cls(c, None, None, None)
        p_star = scene.pressure_scale
        return cls(c, c.p_min * p_star, c.p_max * p_star, c.h_m_x1 * scene.x1)


def _checks():
    """:mod:`pipeline.scenes.checks`, imported where a rule or reason is asked for: it loads
    the solver's rigid phases, which ``ehd scene --help`` (reading the flags here) must not."""
    from . import checks

    return checks


@dataclass(frozen=True)
class ScenePiece:
    """A piece of physics a scene switches (module docstring)."""

    field: str  # the Scene's switch, and Scene.physics' keyword
    base: str  # where the automatic switch starts: the classic film's choice
    on: str  # what "auto" becomes where the switch fires
    switch: Callable  # (scene, BaseFilm) -> bool: the first film needs the piece
    reason_key: str  # the JSON key of the one-sentence reason
    reason: Callable  # (scene, physics solved, BaseFilm, forced: bool, base physics) -> str
    report: str  # the label of its line in the report
    # the sensitivity's variant without it: (label, is the piece on in this Physics, the groups
    # that switch it off)
    without: tuple
    # the ehd scene flags of the scene inputs it reads, its switch's among them
    flags: tuple[SceneFlag, ...]
    # the Physics fields that are constants of one of its laws -> the laws (values of ``field``)
    # that use them: their report rows are shown only where one of those laws was solved
    law_rows: dict = dataclass_field(default_factory=dict)
    # its JSON keys of the scene's inputs in SI: {key: scene -> value}
    quantities: dict = dataclass_field(default_factory=dict)
    # further sensitivity variants of the Physics solved: physics -> {label: Physics}
    variants: Callable = lambda physics: {}


PIECES = (
    ScenePiece(
        "cavitation", base="off", on="auto",
        switch=lambda s, b: _checks().cavitation_crosses(s, b.p_min),
        reason_key="cavitation_reason",
        reason=lambda s, p, b, forced, base: _checks().cavitation_reason(
            s, p, b.p_min, forced=forced, base=base),
        report="physics",
        without=("without cavitation", lambda p: p.cavitation != "off", dict(cavitation="off")),
        flags=(
            SceneFlag("--cavitation-pressure", "fluid.cavitation_pressure",
                      "absolute pressure at which the liquid cavitates: a pressure, 'vapour' "
                      "(the default for a liquid) or 'gas-saturated' (the ambient pressure)"),
            SceneFlag("--tensile-strength", "fluid.tensile_strength",
                      "cavitation at the ambient pressure minus this, e.g. '10 MPa'"),
            SceneFlag("--cavitation", "cavitation",
                      "film model: auto (default: the classic film, switched to the JFO "
                      "cavitation floor where its tension would cross the cavitation "
                      "pressure), or forced off / reynolds / jfo",
                      choices=CAVITATION_CHOICES, group="fluid")),
        quantities={"cavitation_pressure_Pa": lambda scene: scene.cavitation_pressure}),
    ScenePiece(
        "viscosity_law", base="constant", on="auto",
        switch=lambda s, b: _checks().viscosity_switch(s, b.p_max),
        reason_key="viscosity_reason",
        reason=lambda s, p, b, forced, base: _checks().viscosity_reason(
            s, p, b.p_max, forced=forced, base=base),
        report="viscosity",
        without=("without pressure-dependent viscosity", lambda p: p.viscosity_law != "constant",
                 dict(viscosity_law="constant", beta=0.0, viscosity_table="")),
        flags=(
            SceneFlag("--pressure-viscosity", "fluid.pressure_viscosity",
                      "pressure-viscosity coefficient alpha = d ln(mu)/dp, e.g. '20 1/GPa'"),
            SceneFlag("--roelands-index", "fluid.roelands_index",
                      "Roelands pressure-viscosity index Z, e.g. 0.6 (with --roelands-pressure)"),
            SceneFlag("--roelands-pressure", "fluid.roelands_pressure",
                      "Roelands reference pressure p_R, e.g. '196 MPa'"),
            SceneFlag("--viscosity-law", "viscosity_law",
                      "viscosity against pressure: auto (default: constant, switched to the "
                      "fluid's law where alpha times the classic peak pressure is >= 0.1; "
                      "roelands where the fluid has Z and p_R, else barus), or forced "
                      "constant / barus / roelands", choices=VISCOSITY_CHOICES, group="fluid")),
        law_rows={"viscosity_in_tension": ("barus", "roelands"), "roelands_Z": ("roelands",),
                  "roelands_PR": ("roelands",)}),
    ScenePiece(
        "density_law", base="constant", on="auto",
        switch=lambda s, b: _checks().density_switch(s, b.p_max),
        reason_key="density_reason",
        reason=lambda s, p, b, forced, base: _checks().density_reason(
            s, p, b.p_max, forced=forced, base=base),
        report="density",
        without=("without pressure-dependent density", lambda p: p.density_law != "constant",
                 dict(density_law="constant")),
        flags=(
            SceneFlag("--dowson-higginson-c1", "fluid.dowson_higginson_c1",
                      "Dowson-Higginson c1 of rho/rho0 = 1 + c1 p/(1 + c2 p), e.g. '0.6 1/GPa'"),
            SceneFlag("--dowson-higginson-c2", "fluid.dowson_higginson_c2",
                      "Dowson-Higginson c2, e.g. '1.7 1/GPa'"),
            SceneFlag("--density-law", "density_law",
                      "density against pressure: auto (default: constant, switched to "
                      "dowson-higginson where the fluid has its constants and the density "
                      "would rise by more than 1%% at the classic peak pressure), or forced "
                      "constant / dowson-higginson", choices=DENSITY_CHOICES, group="fluid")),
        law_rows={"dh_c1": ("dowson-higginson",), "dh_c2": ("dowson-higginson",)}),
    ScenePiece(
        "asperity_contact", base="off", on="on",
        switch=lambda s, b: _checks().contact_switch(s, b.collision),
        reason_key="roughness_reason",
        reason=lambda s, p, b, forced, base: _checks().roughness_reason(
            s, p, b.h_m, forced=forced),
        report="contact",
        without=("without roughness", lambda p: not p.smooth, dict(roughness=0.0)),
        flags=(
            SceneFlag("--roughness", "body.roughness",
                      "rms surface roughness, e.g. '0.3 um' (asperity contact)"),
            SceneFlag("--asperity-contact", "asperity_contact",
                      "surface roughness as physics: auto (default: smooth, switched on where "
                      "the combined rms roughness exceeds a third of the smooth film's closest "
                      "approach), or forced on / off", choices=ROUGHNESS_CHOICES,
                      group="contact of the solids"),
            SceneFlag("--e-dry", "e_dry",
                      "dry coefficient of restitution of the pair, in (0, 1] (default: the "
                      "pair's from the materials table's [pairs], else 1, elastic; acts only "
                      "where the asperities touch)",
                      group="contact of the solids")),
        variants=_stiffness_variants),
)

REASON_KEYS = tuple(p.reason_key for p in PIECES)
QUANTITY_KEYS = tuple(key for p in PIECES for key in p.quantities)
