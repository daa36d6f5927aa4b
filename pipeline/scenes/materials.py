"""Named solids and fluids for scenes: the shipped table plus the user's own.

The shipped table is ``pipeline/scenes/data/materials.toml``; every entry has a ``source``. Users add or
replace entries without editing code, with TOML files of the same form (``[materials.NAME]``,
``[fluids.NAME]`` and ``[pairs.NAME]`` tables), found in this order (later files override earlier
ones):

1. ``~/.config/ehd/materials.toml`` (``$XDG_CONFIG_HOME/ehd/materials.toml`` if that is set),
2. the files listed in ``$EHD_MATERIALS`` (separated by ``os.pathsep``),
3. files passed with ``ehd scene --materials FILE`` (repeatable),
4. ``[materials.*]`` / ``[fluids.*]`` tables inside the scene file itself.

All values are stored in SI units: solids ``youngs_modulus`` [Pa], ``poisson_ratio`` [-],
``density`` [kg/m^3], optional ``yield_strength`` [Pa]; fluids ``viscosity`` [Pa s], ``density``
[kg/m^3], optional ``vapour_pressure`` [Pa] and ``mean_free_path`` [m], and the optional
pressure dependence (docs/scenes.md, "Pressure-dependent viscosity and density"):
``pressure_viscosity`` alpha [1/Pa] (``d ln mu / dp`` at ambient pressure), the Roelands
``roelands_index`` Z [-] and ``roelands_pressure`` p_R [Pa] (given together), the
Dowson-Higginson ``dowson_higginson_c1``, ``dowson_higginson_c2`` [1/Pa] (given together), with
their ``pressure_source``. A pair group ``[pairs.NAME]`` gives the dry coefficient of restitution
``e_dry`` of any two of its ``materials`` (a property of the pair, not of one solid): the scene's
``e_dry`` where it gives none (``MaterialTable.dry_restitution``).
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from ..errors import UsageError
from .units import FieldSpec, UnitError, to_si

__all__ = ["Solid", "FluidProps", "DryPair", "MaterialTable", "SOLID_FIELDS", "FLUID_FIELDS",
           "PRESSURE_FIELDS", "PRESSURE_PAIRS", "load_table", "user_table_paths", "MaterialError",
           "check_pairs", "unknown_name", "ROUGHNESS_CLASSES", "roughness_class_value"]


class MaterialError(UsageError, ValueError):
    """A materials file or entry that cannot be used (the message names file and field)."""


# Field name -> (spec, required). Ranges are those of the physics: a Poisson ratio of an isotropic
# solid lies in (-1, 0.5]; pressures and moduli are positive.
SOLID_FIELDS = {
    "youngs_modulus": (FieldSpec("[pressure]", "70 GPa", si_unit="Pa"), True),
    "poisson_ratio": (FieldSpec("", "0.22", -1.0, 0.5, hi_open=False), True),
    "density": (FieldSpec("[mass] / [length] ** 3", "2500 kg/m^3", si_unit="kg/m^3"), True),
    "yield_strength": (FieldSpec("[pressure]", "250 MPa", si_unit="Pa"), False),
    # rms surface roughness (checks.roughness_check: contact mechanics instead of the film)
    "roughness": (FieldSpec("[length]", "0.1 um", lo_open=False, si_unit="m"), False),
}
FLUID_FIELDS = {
    "viscosity": (FieldSpec("[pressure] * [time]", "1 mPa s", si_unit="Pa*s"), True),
    "density": (FieldSpec("[mass] / [length] ** 3", "998 kg/m^3", si_unit="kg/m^3"), True),
    "vapour_pressure": (FieldSpec("[pressure]", "2.34 kPa", lo_open=False, si_unit="Pa"), False),
    "mean_free_path": (FieldSpec("[length]", "67 nm", si_unit="m"), False),
    # the pressure dependence (Physics.beta, roelands_*, dh_*): alpha >= 0 (a liquid whose
    # viscosity falls with pressure, cold water, is entered as 0), Z in the solver's (0, 2]
    "pressure_viscosity": (FieldSpec("1 / [pressure]", "20 1/GPa", lo_open=False, si_unit="1/Pa"),
                           False),
    "roelands_index": (FieldSpec("", "0.6", 0.0, 2.0, hi_open=False), False),
    "roelands_pressure": (FieldSpec("[pressure]", "196 MPa", si_unit="Pa"), False),
    "dowson_higginson_c1": (FieldSpec("1 / [pressure]", "0.6 1/GPa", lo_open=False,
                                      si_unit="1/Pa"), False),
    "dowson_higginson_c2": (FieldSpec("1 / [pressure]", "1.7 1/GPa", lo_open=False,
                                      si_unit="1/Pa"), False),
}
# the fluid fields of the pressure dependence, and those that only make sense together
PRESSURE_FIELDS = ("pressure_viscosity", "roelands_index", "roelands_pressure",
                   "dowson_higginson_c1", "dowson_higginson_c2")
PRESSURE_PAIRS = (("roelands_index", "roelands_pressure"),
                  ("dowson_higginson_c1", "dowson_higginson_c2"))
_TEXT_FIELDS = {"materials": ("description", "source"),
                "fluids": ("description", "source", "pressure_source")}


# A fluid less dense than this [kg/m^3] is a gas, with or without a mean free path: liquids at
# room temperature are denser than 600 kg/m^3 (pentane 626), gases at 1 atm lighter than
# 10 kg/m^3 (sulphur hexafluoride 6.1, the densest common one); so a gas typed by its viscosity
# and density gets a gas's physics (no cavitation floor), as the named air does
GAS_DENSITY_BELOW = 100.0


# Surface classes a body's roughness can be given as, instead of a value (docs/scenes.md,
# "Surface roughness"): rms bands [m]. A class is solved at the band's geometric middle, and the
# report's range spans the band. "polished": from optically polished or float glass (about 1 nm,
# the glass entry of the materials table) to ISO 1302 roughness grade N2 (Ra 0.05 um, rms ~ 1.25
# Ra for a Gaussian profile: ~60 nm); "as received": ISO 1302 grades N3-N7 (Ra 0.1-1.6 um:
# ground, cold-rolled, fine-turned engineering surfaces, rms 0.125-2 um); "unknown": both.
ROUGHNESS_CLASSES = {
    "polished": (1e-9, 60e-9),
    "as received": (0.125e-6, 2e-6),
    "unknown": (1e-9, 2e-6),
}


def roughness_class_value(name: str) -> float:
    """The rms roughness [m] a surface class is solved at: its band's geometric middle."""
    lo, hi = ROUGHNESS_CLASSES[name]
    return math.sqrt(lo * hi)


@dataclass(frozen=True)
class Solid:
    """Elastic properties of one body's material (SI)."""

    name: str
    youngs_modulus: float  # Pa
    poisson_ratio: float
    density: float | None  # kg/m^3 (None only for a wall given without one)
    yield_strength: float | None = None  # Pa, None = not known / not applicable
    roughness: float | None = None  # m, rms surface roughness; None = not known
    # a surface class (ROUGHNESS_CLASSES) the roughness stands for ("": a value, or none given)
    roughness_class: str = ""
    source: str = ""
    description: str = ""
    material: str = ""  # the named entry it comes from ("" for a solid given in full)

    @property
    def compliance(self) -> float:
        """This solid's share of ``theta``: ``(1 - nu^2) / (pi E)`` [1/Pa]."""
        return (1.0 - self.poisson_ratio**2) / (math.pi * self.youngs_modulus)

    @property
    def sound_speed(self) -> float | None:
        """Bar wave speed ``c = sqrt(E / rho)`` [m/s] (None without a density)."""
        if self.density is None:
            return None
        return math.sqrt(self.youngs_modulus / self.density)


@dataclass(frozen=True)
class FluidProps:
    """Properties of the fluid filling the gap (SI)."""

    name: str
    viscosity: float  # Pa s
    density: float  # kg/m^3
    vapour_pressure: float | None = None  # Pa
    mean_free_path: float | None = None  # m
    pressure_viscosity: float | None = None  # 1/Pa, alpha = d ln(mu)/dp at ambient pressure
    roelands_index: float | None = None  # Roelands Z
    roelands_pressure: float | None = None  # Pa, Roelands p_R
    dowson_higginson_c1: float | None = None  # 1/Pa: rho/rho0 = 1 + c1 p / (1 + c2 p)
    dowson_higginson_c2: float | None = None  # 1/Pa
    source: str = ""
    description: str = ""
    pressure_source: str = ""  # where the pressure-dependence values come from

    @property
    def gas(self) -> bool:
        """A gas: it has a mean free path (the fluids table gives one to gases only), or a
        density below ``GAS_DENSITY_BELOW`` (a gas typed by its numbers)."""
        return self.mean_free_path is not None or (
            self.density is not None and self.density < GAS_DENSITY_BELOW)

    @property
    def has_roelands(self) -> bool:
        return self.roelands_index is not None and self.roelands_pressure is not None

    @property
    def has_dowson_higginson(self) -> bool:
        return self.dowson_higginson_c1 is not None and self.dowson_higginson_c2 is not None


@dataclass(frozen=True)
class DryPair:
    """The dry coefficient of restitution of any two of ``materials`` (in air or vacuum, at
    speeds where the solids stay elastic)."""

    name: str
    materials: frozenset
    e_dry: float
    source: str


def _parse_pair(name, raw, where):
    label = f"{where}: [pairs.{name}]"
    if not isinstance(raw, dict):
        raise MaterialError(f"{label} must be a table of values")
    unknown = sorted(set(raw) - {"materials", "e_dry", "source", "description"})
    if unknown:
        raise MaterialError(f"{label} has unknown field(s) {unknown}; valid fields: "
                            "['description', 'e_dry', 'materials', 'source']")
    names = raw.get("materials")
    if not (isinstance(names, list) and names and all(isinstance(n, str) for n in names)):
        raise MaterialError(f"{label}: materials must be a list of material names, e.g. "
                            "materials = ['glass', 'chrome_steel']")
    e_dry = raw.get("e_dry")
    if isinstance(e_dry, bool) or not isinstance(e_dry, (int, float)) \
            or not 0.0 < e_dry <= 1.0:
        raise MaterialError(f"{label}: e_dry = {e_dry!r} must be a number in (0, 1] (the pair's "
                            "dry coefficient of restitution)")
    if not str(raw.get("source", "")).strip():
        raise MaterialError(f"{label} needs a 'source' saying where its e_dry comes from")
    return DryPair(name, frozenset(names), float(e_dry), str(raw["source"]))


def check_pairs(values: dict, where: str, error=None) -> None:
    """Raise ``error`` (MaterialError) when only one field of a ``PRESSURE_PAIRS`` pair is
    given: the Roelands law needs Z and p_R, the Dowson-Higginson law c1 and c2."""
    for a, b in PRESSURE_PAIRS:
        if (values.get(a) is None) != (values.get(b) is None):
            have, miss = (a, b) if values.get(a) is not None else (b, a)
            spec = FLUID_FIELDS[miss][0]
            raise (error or MaterialError)(f"{where}: {have} is given without {miss}; the law "
                                           f"needs both (e.g. {miss} = '{spec.example}')")


def _parse_entry(kind, name, raw, where):
    fields = SOLID_FIELDS if kind == "materials" else FLUID_FIELDS
    if not isinstance(raw, dict):
        raise MaterialError(f"{where}: [{kind}.{name}] must be a table of values")
    texts = _TEXT_FIELDS[kind]
    unknown = sorted(set(raw) - set(fields) - set(texts))
    if unknown:
        raise MaterialError(f"{where}: [{kind}.{name}] has unknown field(s) {unknown}; valid fields: "
                            f"{sorted([*fields, *texts])}")
    if not str(raw.get("source", "")).strip():
        raise MaterialError(f"{where}: [{kind}.{name}] needs a 'source' saying where its values "
                            "come from (a reference, a data sheet, or 'own measurement')")
    values = {}
    for field, (spec, required) in fields.items():
        if field not in raw:
            if required:
                raise MaterialError(f"{where}: [{kind}.{name}] is missing the field '{field}' "
                                    f"(e.g. {field} = '{spec.example}')")
            values[field] = None
            continue
        try:
            values[field] = to_si(raw[field], spec, f"{kind}.{name}.{field}")
        except UnitError as exc:
            raise MaterialError(f"{where}: {exc}") from None
    if kind == "fluids":
        check_pairs(values, f"{where}: [{kind}.{name}]")
    text = {k: str(raw.get(k, "")) for k in texts}
    if kind == "fluids":
        return FluidProps(name=name, **values, **text)
    return Solid(name=name, material=name, **values, **text)


def unknown_name(kind: str, name: str, known, where: str) -> MaterialError:
    """The one line for an unknown material or fluid ``name``: the nearest known name where one
    is close (a typo), then all of them."""
    from ..errors import did_you_mean

    return MaterialError(f"{where}: unknown {kind} {name!r}{did_you_mean(name, known)}; known "
                         f"{kind}s: {sorted(known)} "
                         "(add your own with --materials FILE)")


class MaterialTable:
    """Named solids and fluids; later ``add`` calls override earlier entries of the same name."""

    def __init__(self):
        self.solids: dict[str, Solid] = {}
        self.fluids: dict[str, FluidProps] = {}
        self.pairs: dict[str, DryPair] = {}  # in the order added: the last group matching wins
        self.origins: dict[tuple[str, str], str] = {}  # (kind, name) -> file it came from

    def add(self, data: dict, where: str) -> None:
        """Add the ``materials``, ``fluids`` and ``pairs`` tables of one parsed TOML document."""
        pairs = data.get("pairs", {})
        if not isinstance(pairs, dict):
            raise MaterialError(f"{where}: 'pairs' must be a table of named entries")
        for name, raw in pairs.items():
            self.pairs.pop(name, None)  # a replaced group moves to the end: it wins
            self.pairs[name] = _parse_pair(name, raw, where)
            self.origins[("pairs", name)] = where
        for kind in ("materials", "fluids"):
            section = data.get(kind, {})
            if not isinstance(section, dict):
                raise MaterialError(f"{where}: '{kind}' must be a table of named entries")
            target = self.solids if kind == "materials" else self.fluids
            for name, raw in section.items():
                target[name] = _parse_entry(kind, name, raw, where)
                self.origins[(kind, name)] = where

    def solid(self, name: str, where: str) -> Solid:
        if name not in self.solids:
            raise unknown_name("material", name, self.solids, where)
        return self.solids[name]

    def fluid(self, name: str, where: str) -> FluidProps:
        if name not in self.fluids:
            raise unknown_name("fluid", name, self.fluids, where)
        return self.fluids[name]

    def check_pairs(self) -> None:
        """MaterialError when a ``[pairs.NAME]`` group names a material the table does not
        hold: a typo ("sandston") would otherwise never match, and the scene's ``e_dry`` would
        silently be 1 (checked once the table is complete: a group may name a material of a
        later file)."""
        for name, pair in self.pairs.items():
            for material in sorted(pair.materials):
                if material not in self.solids:
                    raise unknown_name("material", material, self.solids,
                                       f"{self.origins[('pairs', name)]}: [pairs.{name}] "
                                       "materials")

    def dry_restitution(self, name1: str, name2: str) -> DryPair | None:
        """The pair group that holds both materials (the one added last), or None."""
        for pair in reversed(self.pairs.values()):
            if name1 in pair.materials and name2 in pair.materials:
                return pair
        return None


def read_toml(path, what: str = "materials file", error=MaterialError) -> dict:
    """Parse a TOML file; a missing, unreadable or invalid file raises ``error`` naming it, and
    so does a FIFO, a device or a file larger than ``reads.MAX_INPUT_BYTES``
    (``pipeline.reads.read_input``)."""
    from ..reads import read_input

    try:  # a UTF-8 byte-order mark (some editors write one) is read
        return tomllib.loads(read_input(path, f"{what} {str(path)!r}", error).decode("utf-8-sig"))
    except FileNotFoundError:
        raise error(f"{what} {str(path)!r} not found") from None
    except IsADirectoryError:
        raise error(f"{what} {str(path)!r} is a directory") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{what} {str(path)!r} is not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise error(f"{what} {str(path)!r} is not a text file (not UTF-8): give a TOML "
                    "file") from None
    except OSError as exc:
        raise error(f"cannot read {what} {str(path)!r}: {exc.strerror}") from None


MATERIALS_SECTIONS = ("materials", "fluids", "pairs")  # a materials file's tables


def _check_sections(data: dict, where: str) -> None:
    """MaterialError when a materials file holds anything but its three tables: ``[material.x]``
    (a typo) or a scene file given as one was read as a file of no materials, and the scene then
    named an unknown material, pointing at the scene instead of the file (a hostile review)."""
    from ..errors import did_you_mean

    unknown = sorted(set(data) - set(MATERIALS_SECTIONS))
    if unknown:
        names = ", ".join(repr(k) + did_you_mean(k, MATERIALS_SECTIONS) for k in unknown[:4])
        raise MaterialError(f"{where}: unknown table or key {names}"
                            f"{' and more' if len(unknown) > 4 else ''}: a materials file holds "
                            "only [materials.NAME], [fluids.NAME] and [pairs.NAME] tables "
                            "(docs/scenes.md, \"Materials and fluids\")")


def user_table_paths(environ=None) -> list[Path]:
    """User materials files that exist in the documented places (see the module docstring)."""
    env = os.environ if environ is None else environ
    config = Path(env.get("XDG_CONFIG_HOME") or Path.home() / ".config")
    paths = []
    default = config / "ehd" / "materials.toml"
    if os.path.lexists(default):  # anything there is read as the user's file, or refused with
        paths.append(default)     # one line (a FIFO, a folder); only a missing one is skipped
    for item in env.get("EHD_MATERIALS", "").split(os.pathsep):
        if item.strip():
            paths.append(Path(item.strip()))  # listed explicitly: a missing one is an error
    return paths


def load_table(extra_files=(), *, user_files: bool = True, environ=None,
               inline: tuple | None = None) -> MaterialTable:
    """The shipped table, then user files, then ``extra_files``, then ``inline`` (a scene
    file's own tables: ``(parsed tables, where)``), each overriding the previous; the complete
    table's ``[pairs]`` are checked against its materials (``MaterialTable.check_pairs``)."""
    table = MaterialTable()
    shipped = resources.files("pipeline.scenes").joinpath("data", "materials.toml")
    table.add(tomllib.loads(shipped.read_text(encoding="utf-8")), "pipeline/scenes/data/materials.toml")
    paths = list(user_table_paths(environ)) if user_files else []
    paths += [Path(p) for p in extra_files]
    for path in paths:
        data = read_toml(path)
        _check_sections(data, str(path))
        table.add(data, str(path))
    if inline is not None:
        table.add(*inline)
    table.check_pairs()
    return table
