"""The inputs of a scene as ``ehd scene`` flags, declared once: each flag fills one key of the
scene file (docs/scenes.md, "The scene file"), so a flag and the file say the same thing.

``SCENE_FLAGS`` are the scene's own inputs (title, bodies, fluid, approach); each piece of physics
the scene switches declares its own (``pieces.ScenePiece.flags``). ``commands.py`` builds the
parser's groups (``GROUPS``, in that order) and the map from a flag to its scene-file key from
the two, so a new input is one ``SceneFlag`` (and its key in ``scene_file.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SceneFlag", "SCENE_FLAGS", "GROUPS", "group_title"]

# the groups of `ehd scene --help`, in order ("": the parser's own options); "body" is one group
# per body
GROUPS = ("", "body", "fluid", "contact of the solids", "approach")
_BODY_TITLES = {1: "body1 (a sphere)", 2: "body2 (a sphere, or a plane wall with --wall)"}


def group_title(group: str, n: int | None = None) -> str:
    """The title ``--help`` shows for ``group`` (of body ``n`` for the "body" group)."""
    return _BODY_TITLES[n] if group == "body" else group


@dataclass(frozen=True)
class SceneFlag:
    """One ``ehd scene`` flag and the scene-file key it fills (its value as the file would
    hold it; the flag overrides the file)."""

    flag: str  # "--fluid-density"; a body's flag ends in the body's number: --radius1, --radius2
    where: str  # the key it fills: "title" (top level), "fluid.density", "body.radius" (each body)
    help: str
    choices: tuple | None = None
    group: str | None = None  # its group in --help (GROUPS); None: its table's ("" at the top)

    @property
    def section(self) -> str | None:
        """The scene file's table (``"body"``: body1 and body2), None for a top-level key."""
        return self.where.rpartition(".")[0] or None

    @property
    def key(self) -> str:
        return self.where.rpartition(".")[2]

    @property
    def help_group(self) -> str:
        return (self.section or "") if self.group is None else self.group

    def options(self) -> tuple:
        """``((flag, dest, section, key), ...)``: one for a scene's key, one per body for a
        body's (dest as argparse names it: the flag without dashes, ``-`` as ``_``)."""
        ends = ("1", "2") if self.section == "body" else ("",)
        return tuple((f"{self.flag}{n}", f"{self.flag[2:].replace('-', '_')}{n}",
                      f"body{n}" if n else self.section, self.key) for n in ends)


SCENE_FLAGS = (
    SceneFlag("--title", "title", "a line describing the scene"),
    SceneFlag("--material", "body.material", "named material (--list-materials)"),
    SceneFlag("--radius", "body.radius", "sphere radius, e.g. '50 um' (inf: wall)"),
    SceneFlag("--density", "body.density", "density, e.g. '2600 kg/m^3'"),
    SceneFlag("--youngs-modulus", "body.youngs_modulus", "Young's modulus, e.g. '70 GPa'"),
    SceneFlag("--poisson-ratio", "body.poisson_ratio", "Poisson ratio in (-1, 0.5]"),
    SceneFlag("--yield-strength", "body.yield_strength",
              "yield strength (enables the plasticity check)"),
    SceneFlag("--fluid", "fluid.name", "named fluid (--list-materials)"),
    SceneFlag("--viscosity", "fluid.viscosity", "dynamic viscosity, e.g. '1 mPa s'"),
    SceneFlag("--fluid-density", "fluid.density", "e.g. '998 kg/m^3'"),
    SceneFlag("--vapour-pressure", "fluid.vapour_pressure", "e.g. '2.3 kPa'"),
    SceneFlag("--mean-free-path", "fluid.mean_free_path", "gases, e.g. '67 nm'"),
    SceneFlag("--ambient-pressure", "fluid.ambient_pressure",
              "absolute ambient pressure (default 1 atm), e.g. '2 bar'"),
    SceneFlag("--approach-speed", "approach_speed",
              "the speed far from the wall, at the outer start where the sphere has not yet "
              "slowed (the speed experiments report), e.g. '15 cm/s'; v0 is then what arrives "
              "at x0 through the outer flow", group="approach"),
    SceneFlag("--v0", "v0", "the speed at the film's start x0, e.g. '10 cm/s' (instead of "
              "--approach-speed)", group="approach"),
    SceneFlag("--x0", "x0", "starting gap, e.g. '250 nm' (default 0.01 a)", group="approach"),
    SceneFlag("--x0-over-a", "x0_over_a", "starting gap as x0/a", group="approach"),
    SceneFlag("--outer-start", "outer_start",
              "where the outer approach (exact Stokes resistance, added mass) starts, e.g. "
              "'3 mm' (default 1 a)", group="approach"),
    SceneFlag("--outer-start-over-a", "outer_start_over_a", "the outer start over a (default 1)",
              group="approach"),
    SceneFlag("--x-ref", "x_ref", "where e_far reads approach and departure speeds, in [x0, "
              "outer start] (default 0.1 a)", group="approach"),
    SceneFlag("--x-ref-over-a", "x_ref_over_a", "x_ref over a (default 0.1)", group="approach"),
)
