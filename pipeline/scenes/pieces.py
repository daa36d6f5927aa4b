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

A new piece the scene switches: one ``ScenePiece`` here, its rule and reason in checks.py, and
its field in ``Scene`` (with ``Scene.physics`` taking the field as a keyword).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from . import checks

__all__ = ["BaseFilm", "ScenePiece", "PIECES", "REASON_KEYS", "STIFFNESS_LABELS"]

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
    # further sensitivity variants of the Physics solved: physics -> {label: Physics}
    variants: Callable = lambda physics: {}


PIECES = (
    ScenePiece("cavitation", "off", "auto",
               lambda s, b: checks.cavitation_crosses(s, b.p_min), "cavitation_reason",
               lambda s, p, b, forced, base: checks.cavitation_reason(
                   s, p, b.p_min, forced=forced, base=base), "physics",
               ("without cavitation", lambda p: p.cavitation != "off", dict(cavitation="off"))),
    ScenePiece("viscosity_law", "constant", "auto",
               lambda s, b: checks.viscosity_switch(s, b.p_max), "viscosity_reason",
               lambda s, p, b, forced, base: checks.viscosity_reason(
                   s, p, b.p_max, forced=forced, base=base), "viscosity",
               ("without pressure-dependent viscosity", lambda p: p.viscosity_law != "constant",
                dict(viscosity_law="constant", beta=0.0, viscosity_table=""))),
    ScenePiece("density_law", "constant", "auto",
               lambda s, b: checks.density_switch(s, b.p_max), "density_reason",
               lambda s, p, b, forced, base: checks.density_reason(
                   s, p, b.p_max, forced=forced, base=base), "density",
               ("without pressure-dependent density", lambda p: p.density_law != "constant",
                dict(density_law="constant"))),
    ScenePiece("asperity_contact", "off", "on",
               lambda s, b: checks.contact_switch(s, b.collision), "roughness_reason",
               lambda s, p, b, forced, base: checks.roughness_reason(s, p, b.h_m, forced=forced),
               "contact", ("without roughness", lambda p: not p.smooth, dict(roughness=0.0)),
               _stiffness_variants),
)

REASON_KEYS = tuple(p.reason_key for p in PIECES)
