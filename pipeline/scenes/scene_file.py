"""Building a scene from a parsed TOML scene document (see docs/scenes.md for the format).

Every field is checked and converted to SI; an error names the field and its valid range
(``SceneError``). No file I/O here: ``scene_from_dict`` takes an already-parsed TOML document.
"""

from __future__ import annotations

import math

from .materials import (FLUID_FIELDS, GAS_DENSITY_BELOW, PRESSURE_FIELDS, ROUGHNESS_CLASSES,
                        SOLID_FIELDS, FluidProps, MaterialTable, Solid, check_pairs,
                        roughness_class_value)
from .scene import (CAVITATION_CHOICES, DENSITY_CHOICES, ROUGHNESS_CHOICES, STANDARD_ATMOSPHERE,
                    VISCOSITY_CHOICES, Body, Scene, SceneError, _reduced)
from .units import FieldSpec, format_quantity, to_si

__all__ = ["scene_from_dict", "DEFAULT_X0_OVER_A", "at_approach_speed", "at_settling"]

DEFAULT_X0_OVER_A = 0.01  # docs/model.md "Setting": the close stage starts at x0 ~ 0.01 a

_LENGTH = FieldSpec("[length]", "50 um", hi_open=False, si_unit="m")  # radius: inf = plane wall
_SPEED = FieldSpec("[length] / [time]", "10 cm/s", si_unit="m/s")
_GAP = FieldSpec("[length]", "500 nm", si_unit="m")
_RATIO = FieldSpec("", "0.01")
# the pair's dry coefficient of restitution: (0, 1], named in every refusal (e_dry = 0 was
# refused by _RATIO's own range, "(0, inf)", which 1.5 is in)
_E_DRY = FieldSpec("", "0.9", 0.0, 1.0, hi_open=False)
_PRESSURE = FieldSpec("[pressure]", "101.325 kPa", si_unit="Pa")

_TOP_KEYS = ("title", "v0", "approach_speed", "x0", "x0_over_a", "outer_start", "outer_start_over_a", "x_ref",
             "x_ref_over_a", "cavitation", "viscosity_law", "density_law", "asperity_contact",
             "e_dry", "body1", "body2", "fluid", "materials", "fluids")
_BODY_KEYS = ("material", "radius", "wall", *SOLID_FIELDS)
_FLUID_KEYS = ("name", "ambient_pressure", "cavitation_pressure", "tensile_strength",
               *FLUID_FIELDS)
_TENSILE = FieldSpec("[pressure]", "10 MPa", si_unit="Pa")
# The cavitation pressure of a liquid that gives no vapour pressure (a liquid by its numbers):
# 0 Pa absolute, the least a liquid's vapour pressure can be. Every liquid of the materials table
# has its vapour pressure at room temperature between 0 and 2.34 kPa (water), which moves
# p_amb - p_cav at 1 atm by under 2.5 %; so a liquid given by numbers takes the same cavitation
# switch as the named one (docs/scenes.md, "Cavitation"), and the report's range spans the onset
# (gas-saturated to full tension)
ASSUMED_CAVITATION_PRESSURE = 0.0
# fluid.cavitation_pressure presets (docs/scenes.md, "Cavitation")
CAVITATION_PRESETS = ("vapour", "gas-saturated")


def _check_keys(raw, valid, where):
    if not isinstance(raw, dict):
        raise SceneError(f"{where} must be a table (e.g. [{where}])")
    unknown = sorted(set(raw) - set(valid))
    if unknown:
        raise SceneError(f"{where}: unknown field(s) {unknown}; valid fields: {sorted(valid)}")


def _body(data, label, table: MaterialTable) -> Body:
    if label not in data:
        raise SceneError(f"missing the table [{label}]: give a radius and a material "
                         "(or youngs_modulus, poisson_ratio and density)")
    raw = data[label]
    _check_keys(raw, _BODY_KEYS, label)
    wall = raw.get("wall", False)
    if not isinstance(wall, bool):
        raise SceneError(f"{label}.wall must be true or false, got {wall!r}")
    if "radius" in raw:
        r = raw["radius"]
        if isinstance(r, str) and r.strip().lower() in ("inf", "infinity"):
            r = math.inf
        radius = to_si(r, _LENGTH, f"{label}.radius")
        if wall and not math.isinf(radius):
            raise SceneError(f"{label}: wall = true but radius = {raw['radius']!r}; a plane wall "
                             "has an infinite radius (leave radius out)")
    elif wall:
        radius = math.inf
    else:
        raise SceneError(f"{label}: missing the field 'radius' (e.g. radius = '50 um'; "
                         "or wall = true for a plane wall)")
    base = None
    if "material" in raw:
        if not isinstance(raw["material"], str):
            raise SceneError(f"{label}.material must be a name, got {raw['material']!r}")
        base = table.solid(raw["material"], f"{label}.material")
    # a plane wall needs no density (its mass is infinite)
    optional = {"density"} if math.isinf(radius) else set()
    raw, surface = _roughness_class(raw, label)
    values, name, source = _properties(raw, SOLID_FIELDS, base, label, "material", optional)
    if surface:
        values["roughness"] = roughness_class_value(surface)
    solid = Solid(name=name, source=source, description=base.description if base else "",
                  material=base.material if base else "", roughness_class=surface, **values)
    return Body(label=label, radius=radius, solid=solid)


def _roughness_class(raw, label):
    """``(raw without a class roughness, the class or "")``: a body's roughness given as a surface
    class (``materials.ROUGHNESS_CLASSES``: "polished", "as received", "unknown") instead of a
    value."""
    given = raw.get("roughness")
    if not isinstance(given, str) or any(ch.isdigit() for ch in given):
        return raw, ""
    name = " ".join(given.strip().lower().replace("_", " ").replace("-", " ").split())
    if name not in ROUGHNESS_CLASSES:
        raise SceneError(f"{label}.roughness must be an rms roughness (e.g. '0.3 um') or a surface "
                         f"class, one of {list(ROUGHNESS_CLASSES)}, got {given!r}")
    return {k: v for k, v in raw.items() if k != "roughness"}, name


def _properties(raw, fields, base, label, kind, optional=frozenset()):
    """Field values of a solid or fluid: given in ``raw``, else from the named ``base`` entry,
    else None for optional fields; returns ``(values, name, source)``."""
    values = {}
    for field_name, (spec, required) in fields.items():
        if field_name in raw:
            values[field_name] = to_si(raw[field_name], spec, f"{label}.{field_name}")
        elif base is not None:
            values[field_name] = getattr(base, field_name)
        elif required and field_name not in optional:
            raise SceneError(f"{label}: missing the field '{field_name}' (e.g. {field_name} = "
                             f"'{spec.example}'), or name a {kind} = '...'")
        else:
            values[field_name] = None
    overridden = sorted(set(raw) & set(fields))
    if base is None:
        return values, "custom", "given in the scene"
    name = base.name + (f" (with {', '.join(overridden)} given)" if overridden else "")
    source = base.source + ("; overrides given in the scene" if overridden else "")
    return values, name, source


def _fluid(data, table: MaterialTable):
    if "fluid" not in data:
        raise SceneError("missing the table [fluid]: give name = 'water' (or viscosity and density)")
    raw = data["fluid"]
    _check_keys(raw, _FLUID_KEYS, "fluid")
    for key, law, choices in (("viscosity", "viscosity_law", VISCOSITY_CHOICES),
                              ("density", "density_law", DENSITY_CHOICES)):
        given = raw.get(key)
        if isinstance(given, str) and given.strip().lower() in choices:
            # `ehd scene --viscosity barus`: the flag of `ehd run` that names the law is the
            # fluid's own viscosity here
            raise SceneError(f"fluid.{key} is the fluid's {key} (e.g. "
                             f"'{FLUID_FIELDS[key][0].example}'), got {given!r}: the {key} law "
                             f"is {law} = {given.strip()!r} at the top of the scene file (flag "
                             f"--{law.replace('_', '-')})")
    base = None
    if "name" in raw:
        if not isinstance(raw["name"], str):
            raise SceneError(f"fluid.name must be a name, got {raw['name']!r}")
        base = table.fluid(raw["name"], "fluid.name")
    values, name, source = _properties(raw, FLUID_FIELDS, base, "fluid", "fluid")
    check_pairs(values, "fluid", SceneError)
    given = sorted(set(raw) & set(PRESSURE_FIELDS))
    if base is None:
        pressure_source = "given in the scene" if given else ""
    else:
        pressure_source = base.pressure_source + (f"; {', '.join(given)} given in the scene"
                                                  if given else "")
    fluid = FluidProps(name=name, source=source, description=base.description if base else "",
                       pressure_source=pressure_source.lstrip("; "), **values)
    ambient = STANDARD_ATMOSPHERE
    if "ambient_pressure" in raw:
        ambient = to_si(raw["ambient_pressure"], _PRESSURE, "fluid.ambient_pressure")
    p_cav, how = _cavitation_pressure(raw, fluid, ambient)
    return fluid, ambient, p_cav, how


def _cavitation_pressure(raw, fluid: FluidProps, ambient: float):
    """``(p_cav [Pa] or None, how it was set)`` from ``fluid.cavitation_pressure`` (a pressure or
    a preset) or ``fluid.tensile_strength``; by default the vapour pressure of a liquid, none for
    a gas (a fluid with a mean free path) or a liquid without a vapour pressure."""
    if "cavitation_pressure" in raw and "tensile_strength" in raw:
        raise SceneError("fluid: give either cavitation_pressure or tensile_strength, not both")
    if "tensile_strength" in raw:
        t = to_si(raw["tensile_strength"], _TENSILE, "fluid.tensile_strength")
        p_cav = ambient - t
        return p_cav, (f"tensile strength {format_quantity(t, 'Pa')} below the ambient "
                       f"{format_quantity(ambient, 'Pa')}")
    given = raw.get("cavitation_pressure", None if fluid.gas else "vapour")
    if given is None:
        return None, "a gas film does not cavitate" + (
            "" if fluid.mean_free_path is not None else
            f" (a density below {GAS_DENSITY_BELOW:g} kg/m^3 is a gas's; give its mean_free_path "
            "for the continuum check)")
    preset = given.strip().lower().replace("vapor", "vapour") if isinstance(given, str) else None
    if preset in CAVITATION_PRESETS:
        if preset == "gas-saturated":
            # a liquid equilibrated with gas at the ambient pressure releases it as soon as the
            # pressure falls below that saturation pressure (Henry's law): p_cav = p_amb, Pi = 0
            return ambient, "gas-saturated: the ambient pressure, where dissolved gas comes out"
        if fluid.vapour_pressure is None:
            if "cavitation_pressure" in raw:
                raise SceneError(f"fluid.cavitation_pressure = 'vapour' but the fluid "
                                 f"{fluid.name!r} has no vapour_pressure: give fluid."
                                 "vapour_pressure, or the cavitation pressure itself")
            return ASSUMED_CAVITATION_PRESSURE, (
                f"assumed {format_quantity(ASSUMED_CAVITATION_PRESSURE, 'Pa')}: the fluid "
                f"{fluid.name!r} gives no vapour pressure, and a liquid's at room temperature is "
                "0-2.3 kPa; give fluid.vapour_pressure or fluid.cavitation_pressure")
        p_cav, how = fluid.vapour_pressure, f"the vapour pressure of {fluid.name}"
    else:
        if isinstance(given, str) and not any(ch.isdigit() for ch in given):
            raise SceneError(f"fluid.cavitation_pressure must be a pressure (e.g. '2.3 kPa') or "
                             f"one of {list(CAVITATION_PRESETS)}, got {given!r}")
        p_cav = to_si(given, FieldSpec("[pressure]", "2.3 kPa", lo_open=False, si_unit="Pa"),
                      "fluid.cavitation_pressure")
        how = "given in the scene"
    if p_cav > ambient:
        raise SceneError(f"the cavitation pressure {format_quantity(p_cav, 'Pa')} ({how}) is "
                         f"above the ambient pressure {format_quantity(ambient, 'Pa')}: the liquid "
                         "would boil or degas at rest; raise fluid.ambient_pressure")
    return p_cav, how


def _outer_length(data, name, a):
    """``data[name]`` (a length) or ``data[name + '_over_a']`` (a ratio) in m; None if neither."""
    if name in data and f"{name}_over_a" in data:
        raise SceneError(f"give either {name} (a length) or {name}_over_a (a ratio), not both")
    if name in data:
        return to_si(data[name], _GAP, name), name
    if f"{name}_over_a" in data:
        return to_si(data[f"{name}_over_a"], _RATIO, f"{name}_over_a") * a, f"{name}_over_a"
    return None, name


def _outer(data, a, x0):
    """The outer start and ``x_ref`` [m] (None: the defaults, ``far_field.START_OVER_A`` a and
    ``X_REF_OVER_A`` a), checked: ``x0 < outer_start <= MAX_OVER_A a`` and
    ``x0 <= x_ref <= outer_start`` (docs/scenes.md, "The approach from far away")."""
    from solver.far_field import MAX_OVER_A, START_OVER_A, X_REF_OVER_A

    start, start_name = _outer_length(data, "outer_start", a)
    ref, ref_name = _outer_length(data, "x_ref", a)
    s = START_OVER_A * a if start is None else start
    r = X_REF_OVER_A * a if ref is None else ref

    def q(v):
        return f"{format_quantity(v, 'm')} = {v / a:.4g} a"

    if start is None and not x0 < s:  # the default outer start: x0 is what is out of place
        x0_name = "x0_over_a" if "x0_over_a" in data else "x0"
        raise SceneError(f"{x0_name} = {q(x0)}: the close stage must start inside the outer "
                         f"start (default {q(s)}): give a smaller {x0_name}, or an outer_start "
                         f"beyond it (up to {q(MAX_OVER_A * a)})")
    if not x0 < s <= MAX_OVER_A * a:
        raise SceneError(f"{start_name} = {q(s)}: the outer start must lie beyond the start of "
                         f"the close stage x0 = {q(x0)}, in ({q(x0)}, {q(MAX_OVER_A * a)}]")
    if not x0 <= r <= s:
        raise SceneError(f"{ref_name} = {q(r)}: the reference distance of e_far must be in "
                         f"[{q(x0)}, {q(s)}] (between x0 and the outer start)")
    return start, ref


def _e_dry(data, body1, body2, contact, table) -> tuple:
    """``(e_dry, where it came from)``: the scene's, the materials table's pair, else 1 (elastic
    solids); a given e_dry that could never act (no roughness, or the contact off) is refused."""
    e_dry, e_dry_source = 1.0, "not given, and no pair group of the materials table holds both " \
        "solids: elastic solids (1)"
    materials = body1.solid.material, body2.solid.material
    pair = table.dry_restitution(*materials) if all(materials) else None
    if pair is not None:
        e_dry = pair.e_dry
        e_dry_source = f"the pair {materials[0]}/{materials[1]}: [pairs.{pair.name}] of the " \
            "materials table, whose source ehd scene --list-materials shows"
    if "e_dry" in data:
        e_dry = to_si(data["e_dry"], _E_DRY, "e_dry")
        if not any(b.solid.roughness for b in (body1, body2)):
            # smooth surfaces never touch: the given e_dry would silently do nothing
            raise SceneError(f"e_dry = {data['e_dry']!r} acts only where rough surfaces touch, "
                             "and neither body has a roughness: give one (e.g. body1.roughness "
                             "= '0.3 um', --roughness1), or leave e_dry out")
        if contact == "off":  # the contact is never modelled: e_dry would do nothing either
            raise SceneError(f"e_dry = {data['e_dry']!r} acts only where the asperities touch, "
                             "and asperity_contact is off: give asperity_contact auto or on "
                             "(--asperity-contact), or leave e_dry out")
        e_dry_source = "the scene's e_dry"
    return e_dry, e_dry_source


def scene_from_dict(data: dict, table: MaterialTable) -> Scene:
    """Build a ``Scene`` from a parsed scene document (see docs/scenes.md for the format).

    Parameters
    ----------
    data : dict
        Top-level keys ``title``, ``v0``, ``x0`` or ``x0_over_a``, ``cavitation``,
        ``viscosity_law``, ``density_law``, tables ``body1``, ``body2``,
        ``fluid`` (and optionally ``materials`` / ``fluids``, already merged into ``table``).
    table : MaterialTable
        Named materials and fluids.

    Raises
    ------
    SceneError, ValueError
        With a message naming the offending field and its valid range.
    """
    _check_keys(data, _TOP_KEYS, "scene")
    body1 = _body(data, "body1", table)
    body2 = _body(data, "body2", table)
    if body1.wall and body2.wall:
        raise SceneError("body1 and body2 are both plane walls; at least one must be a sphere")
    if body1.wall:  # keep the sphere first: a wall is body2 by convention
        body1, body2 = Body("body1", body2.radius, body2.solid), Body("body2", body1.radius,
                                                                        body1.solid)
    fluid, ambient, p_cav, how = _fluid(data, table)
    cavitation = data.get("cavitation", "auto")
    if cavitation not in CAVITATION_CHOICES:
        raise SceneError(f"cavitation must be one of {list(CAVITATION_CHOICES)}, got {cavitation!r}")
    laws = {}
    for key, choices in (("viscosity_law", VISCOSITY_CHOICES), ("density_law", DENSITY_CHOICES)):
        laws[key] = data.get(key, "auto")
        if laws[key] not in choices:
            raise SceneError(f"{key} must be one of {list(choices)}, got {laws[key]!r}")
    v0, approach = _speeds(data)
    a = _reduced(body1.radius, body2.radius)
    if "x0" in data and "x0_over_a" in data:
        raise SceneError("give either x0 (a length) or x0_over_a (a ratio), not both")
    if "x0" in data:
        x0 = to_si(data["x0"], _GAP, "x0")
    elif "x0_over_a" in data:
        x0 = to_si(data["x0_over_a"], _RATIO, "x0_over_a") * a
    else:
        x0 = DEFAULT_X0_OVER_A * a
    outer_start, x_ref = _outer(data, a, x0)
    title = data.get("title", "")
    if not isinstance(title, str):
        raise SceneError(f"title must be a string, got {title!r}")
    contact = data.get("asperity_contact", "auto")
    if contact not in ROUGHNESS_CHOICES:
        raise SceneError(f"asperity_contact must be one of {list(ROUGHNESS_CHOICES)}, got "
                         f"{contact!r}")
    e_dry, e_dry_source = _e_dry(data, body1, body2, contact, table)
    scene = Scene(title=title, body1=body1, body2=body2, fluid=fluid,
                  # a stand-in speed until at_settling or at_approach_speed maps the approach
                  v0=(1.0 if approach == "settling" else approach) if v0 is None else v0, x0=x0,
                  ambient_pressure=ambient, cavitation_pressure=p_cav,
                  cavitation_pressure_source=how, cavitation=cavitation,
                  outer_start=outer_start, x_ref=x_ref, **laws,
                  asperity_contact=contact, e_dry=e_dry, e_dry_source=e_dry_source)
    if approach == "settling":
        return at_settling(scene)
    return scene if approach is None else at_approach_speed(scene, approach)


def _speeds(data):
    """``(v0, approach_speed)`` [m/s] of the scene document: exactly one is given, the other
    None (docs/scenes.md, "The approach speed")."""
    if "v0" in data and "approach_speed" in data:
        raise SceneError("give either v0 (the speed at the film's start x0) or approach_speed "
                         "(the speed at the outer start, where the sphere has not yet slowed), "
                         "not both")
    if "approach_speed" in data:
        given = data["approach_speed"]
        if isinstance(given, str) and given.strip().lower() == "settling":
            return None, "settling"
        return None, to_si(given, _SPEED, "approach_speed")
    if "v0" not in data:
        raise SceneError("missing the speed: give approach_speed (the speed far from the wall, "
                         "e.g. approach_speed = '15 cm/s') or v0 (the speed at the film's start "
                         "x0, e.g. v0 = '10 cm/s')")
    return to_si(data["v0"], _SPEED, "v0"), None


def at_settling(scene: Scene) -> Scene:
    """The scene with body 1 settling onto body 2 (``approach_speed = "settling"``): the
    approach speed is the drag law's terminal speed, ``v0`` what arrives at ``x0`` through the
    whole outer motion with gravity (``trajectory.settling_arrival``)."""
    import dataclasses

    from .trajectory import DEFAULT_RELEASE_GAP_OVER_A, settling_arrival

    terminal, v0, at_start, law = settling_arrival(dataclasses.replace(scene, v0=1.0))
    return dataclasses.replace(scene, v0=v0, approach_speed=terminal,
                               settling_outer_start_speed=at_start,
                               approach_speed_source=f"settling ({law} drag, from "
                                                     f"{DEFAULT_RELEASE_GAP_OVER_A:g} a)")


def at_approach_speed(scene: Scene, approach: float) -> Scene:
    """The scene with ``v0`` mapped from the approach speed at the outer start through the outer
    flow (``far_field.OuterFlow.arrival_speed``); ``v0 = 0`` when the outer flow stops the
    spheres before ``x0`` (``Scene.stops_outside``)."""
    import dataclasses

    outer = scene.outer_flow()
    v0 = approach * max(0.0, outer.arrival_speed(scene.stokes_of(approach)))
    return dataclasses.replace(scene, v0=v0, approach_speed=approach,
                               approach_speed_source="given")
