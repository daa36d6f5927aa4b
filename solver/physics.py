"""The physics of one scene: every dimensionless group, validated, in one object.

A scene is fully described by its dimensionless groups (docs/model.md, "The parameters"): the
Stokes number ``St`` and the elasticity parameter ``eps`` of Davis, Serayssol & Hinch (1986), the
*classic model*, and the groups of the physics a scene may switch on: the cavitation number ``Pi``
with the cavitation model (docs/model.md, "Cavitation"). Each piece of physics adds a field here
(with its metadata in ``GROUPS``), and everything downstream follows from this declaration:
validation, the flat array the compiled kernels read (``as_array``, indices ``ST``, ``EPS``,
``PI``, ``CAVITATION``), the sweep axes and fixed values of a sweep file, the store's coordinates
and its cache key, the command-line flags.

Values travel to the kernels as arguments (a float array), never as closure constants: a new
value must not recompile anything.
"""

from __future__ import annotations

import math
import numbers
import textwrap
from dataclasses import asdict, dataclass, field, make_dataclass, replace

import numpy as np

__all__ = ["Physics", "Group", "GROUPS", "ST", "EPS", "PI", "CAVITATION", "CAVITATION_MODELS",
           "DEFAULT_CAVITATION", "BETA", "VISCOSITY", "ROELANDS_Z", "ROELANDS_PR", "DENSITY",
           "DH_C1", "DH_C2", "TABLE", "ROUGHNESS", "ASPERITY_K", "E_DRY", "SLIP", "TENSION",
           "TENSION_CHOICES", "VISCOSITY_LAWS", "DENSITY_LAWS",
           "INDEX", "codes"]


@dataclass(frozen=True)
class Group:
    """Metadata of one dimensionless group: what it is, its unit and its valid range."""

    name: str
    long_name: str
    symbol: str  # short name in messages, e.g. "St (Stokes number) must be finite"
    lo: float  # valid range (lo, hi] (open below unless closed_lo)
    hi: float
    closed_lo: bool = False
    units: str = "1"
    default: float | str | None = None  # value when a sweep file omits the group (None: required)
    allow_inf: bool = False  # +inf is a valid value (the physics switched off)
    choices: tuple = ()  # a named choice instead of a number (e.g. a model)
    flag: str = ""  # the command-line flag, when not ``--name``
    table: bool = False  # a table of (P, value) points as text "P:value, ..." instead of a number
    off: float | str | None = None  # the value that switches the physics off (None: always on)
    doc: str = ""  # what the docstring of Physics says beyond the long name and range

    @property
    def numeric(self) -> bool:
        """A number (a sweep axis may span it), not a named choice or a table."""
        return not (self.choices or self.table)

    @property
    def option(self) -> str:
        """The command-line flag of the group, e.g. ``--St``, ``--viscosity`` or ``--dh-c1``
        (words joined by hyphens, as the other flags)."""
        return "--" + (self.flag or self.name.replace("_", "-"))

    @property
    def options(self) -> tuple:
        """``option``, and the field's own name as a flag where it differs (``--dh_c1``)."""
        own = "--" + self.name
        return (self.option,) if own == self.option else (self.option, own)

    def check(self, value):
        """``value`` as a float (or one of ``choices``), or ValueError naming the group and its
        valid range."""
        label = f"{self.name} ({self.symbol})"
        if self.table:
            return format_table(parse_table(value, label))
        if self.choices:
            if not isinstance(value, str) or value not in self.choices:  # an array too
                raise ValueError(f"{label} must be one of {list(self.choices)}, got {value!r}")
            return value
        try:
            if isinstance(value, (bool, np.bool_, str, bytes)):  # "5" is refused like True
                raise TypeError
            v = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{label} must be a number, got {value!r}") from None
        except OverflowError:  # an int beyond any float: 10**400
            raise ValueError(f"{label} is a number beyond a float's range, outside its valid "
                             f"range {'[' if self.closed_lo else '('}{self.lo:g}, {self.hi:g}]"
                             ) from None
        if math.isnan(v) or (math.isinf(v) and not (self.allow_inf and v > 0)):
            raise ValueError(f"{label} must be finite{' or inf' if self.allow_inf else ''}, "
                             f"got {value!r}")
        ok_lo = v >= self.lo if self.closed_lo else v > self.lo
        if not ok_lo or v > self.hi:
            lb = "[" if self.closed_lo else "("
            raise ValueError(f"{label} = {value!r} is outside its valid range "
                             f"{lb}{self.lo:g}, {self.hi:g}]")
        return v


def is_real_number(value) -> bool:
    """Whether ``value`` is a real number as an input takes one: a Python or numpy int or float,
    never a bool (Python's or numpy's)."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def parse_table(text, label="viscosity_table"):
    """Points ``((P_0, r_0), ...)`` of a viscosity table written ``"P:mu/mu0, ..."`` (``""``: no
    table), or ValueError naming what is wrong: it starts at ``P = 0`` with ``mu/mu0 = 1``, its
    pressures increase and its ratios are positive and finite."""
    if not isinstance(text, str):
        raise ValueError(f"{label} must be text \"P:mu/mu0, P:mu/mu0, ...\", got {text!r}")
    if not text.strip():
        return ()
    points = []
    for item in text.split(","):
        try:
            p, r = (float(v) for v in item.split(":"))
        except ValueError:
            raise ValueError(f"{label}: {item.strip()!r} is not a point \"P:mu/mu0\" (two numbers "
                             "and a colon)") from None
        if not (math.isfinite(p) and math.isfinite(r) and r > 0.0):
            raise ValueError(f"{label}: {item.strip()!r} needs a finite P and a finite ratio > 0")
        if r > MAX_TABLE_RATIO:  # 1e308 overflowed to an infinite peak viscosity, status ok
            raise ValueError(f"{label}: {item.strip()!r}: a ratio above {MAX_TABLE_RATIO:g} "
                             "overflows the film's products (a liquid is solid by 1e4)")
        points.append((p, r))
    if len(points) < 2 or points[0] != (0.0, 1.0):
        raise ValueError(f"{label} must start with the point 0:1 (mu = mu0 at ambient pressure) "
                         "and have at least one more point")
    if any(b[0] <= a[0] for a, b in zip(points, points[1:])):
        raise ValueError(f"{label}: the pressures must increase")
    if len(points) > MAX_TABLE_POINTS:
        raise ValueError(f"{label} has {len(points)} points; at most {MAX_TABLE_POINTS}")
    return tuple(points)


def format_table(points) -> str:
    """The canonical text of a table's points (what a Physics holds, and stores)."""
    return ", ".join(f"{p:.17g}:{r:.17g}" for p, r in points)


MAX_TABLE_POINTS = 64
MAX_TABLE_RATIO = 1e30  # largest mu/mu0 of a table (the tests reach exp(60) ~ 1e26)

GROUPS = (
    Group("St", "Stokes number m v0 / (6 pi mu a^2)", "Stokes number", 0.0, 1.0e4),
    # eps << 1 is the model's premise; at 0.1 the start x0 is only 2.5 x1
    Group("eps", "elasticity parameter 4 theta mu v0 a^1.5 / x0^2.5", "elasticity parameter",
          0.0, 0.1, doc="``(x1/x0)^2.5``."),
    # the film cannot pull harder than the liquid allows: P >= -Pi (inf: unlimited tension)
    Group("Pi", "cavitation number (p_amb - p_cav) x1^2 / (mu a v0)", "cavitation number",
          0.0, math.inf, closed_lo=True, default=math.inf, allow_inf=True, off=math.inf,
          doc="The film pressure cannot fall below ``-Pi`` (gauge, in ``mu a v0 / x1^2``); inf "
              "is the classic film, which carries any tension."),
    Group("cavitation", "cavitation model: off, reynolds (Swift-Stieber) or jfo (mass-conserving "
          "Elrod-Adams); auto: the default model where Pi is finite", "cavitation model",
          math.nan, math.nan, default="auto", choices=("auto", "off", "reynolds", "jfo"),
          off="off", doc="\"auto\" becomes ``DEFAULT_CAVITATION`` where ``Pi`` is finite and "
                         "\"off\" where it is inf; \"off\" ignores ``Pi``."),
    # the liquid thickens under pressure: d ln(mu)/dp = alpha at p = 0 (0: constant viscosity)
    Group("beta", "piezoviscous number alpha mu a v0 / x1^2 (alpha = d ln mu / dp at p = 0)",
          "piezoviscous number", 0.0, 50.0, closed_lo=True, default=0.0, off=0.0,
          doc="The slope of ``ln(mu/mu0)`` against the dimensionless pressure at ``P = 0`` "
              "(docs/model.md, \"Pressure-dependent viscosity and density\")."),
    Group("viscosity_law", "viscosity against pressure: constant, barus (exp(beta P)), roelands "
          "or table (viscosity_table); auto: table where one is given, else barus where "
          "beta > 0", "viscosity law", math.nan, math.nan, default="auto",
          choices=("auto", "constant", "barus", "roelands", "table"), flag="viscosity",
          off="constant", doc="With ``beta = 0`` and no table every law is \"constant\"."),
    # a liquid in tension keeps its ambient viscosity (the default) or, for comparison, the law's
    Group("viscosity_in_tension", "viscosity where the gauge pressure is negative: ambient (mu0, "
          "the default; a liquid cavitates long before the law's thinning) or law (the law's "
          "formula read at P < 0, for comparison)", "viscosity in tension", math.nan, math.nan,
          default="ambient", choices=("ambient", "law"),
          doc="The density's compressibility fades in tension over ``0.01`` (model/liquid.py)."),
    # Roelands: ln(mu/mu0) = (beta P_R / Z) ((1 + P/P_R)^Z - 1), slope beta at P = 0; defaults:
    # a mineral oil's Z = 0.6 and p_R = 1.96e8 Pa at the pressure scale p* = 5e8 Pa
    Group("roelands_Z", "Roelands pressure-viscosity index Z", "Roelands index", 0.0, 2.0,
          default=0.6),
    Group("roelands_PR", "Roelands reference pressure p_R x1^2 / (mu a v0)",
          "Roelands reference pressure", 0.0, 1.0e6, default=0.392,
          doc="Default: a mineral oil's 1.96e8 Pa at ``p* = 5e8 Pa``."),
    Group("density_law", "density against pressure: constant or dowson-higginson "
          "(1 + c1 P / (1 + c2 P))", "density law", math.nan, math.nan, default="constant",
          choices=("constant", "dowson-higginson"), flag="density", off="constant",
          doc="In tension the compressibility ``c1`` fades over ``P = -0.01``; with "
              "``dh_c1 = 0`` the law is \"constant\"."),
    # Dowson-Higginson: rho/rho0 = 1 + c1 P / (1 + c2 P); defaults: 0.6e-9 and 1.7e-9 1/Pa
    # at p* = 5e8 Pa
    Group("dh_c1", "Dowson-Higginson c1 p* (0.6e-9 1/Pa times the pressure scale)",
          "Dowson-Higginson c1", 0.0, 100.0, closed_lo=True, default=0.3),
    Group("dh_c2", "Dowson-Higginson c2 p* (1.7e-9 1/Pa times the pressure scale)",
          "Dowson-Higginson c2", 0.0, 100.0, closed_lo=True, default=0.85),
    # rough surfaces: asperities of the combined rms roughness sigma carry load where the gap
    # falls below it (docs/model.md, "Surface roughness"); 0: smooth surfaces, the classic film
    # at most the start gap (checked with eps below); 1e8 x1 is that gap at eps 1e-20
    Group("roughness", "combined rms surface roughness sigma / x1 (asperity contact below it)",
          "roughness", 0.0, 1.0e8, closed_lo=True, default=0.0, off=0.0,
          doc="Where the local gap ``H`` falls below it the asperities carry the pressure "
              "of Hertzian summits spread over heights 0 to sigma, ``(24/35) k (sigma - H)^3.5 "
              "/ sigma^2`` near first touch (model/contact.py)."),
    Group("asperity_stiffness", "asperity stiffness k: the Greenwood-Williamson pressure of "
          "the summits, in mu a v0 / x1^2.5", "asperity stiffness", 0.0, 1.0e8,
          default=10.0, doc="Scenes derive it from the materials (Greenwood-Williamson, "
                            "docs/model.md); not used without roughness."),
    Group("e_dry", "dry coefficient of restitution of the solids (losses where they touch)",
          "dry restitution", 0.0, 1.0, default=1.0, off=1.0,
          doc="Acts only where the asperities touch: a smooth collision never loses energy in "
              "the solids (docs/model.md, \"Losses in the solids\")."),
    # slip at the surfaces (docs/model.md, "Slip"): a gas's mean free path, or a liquid's slip
    # length on a slippery surface; 1e8 x1 is the start gap at eps 1e-20, as for the roughness
    Group("slip_length", "slip length l / x1 of each surface (Maxwell-Navier slip, u_wall = l "
          "du/dz)", "slip length", 0.0, 1.0e8, closed_lo=True, default=0.0, off=0.0,
          doc="The film's mobility becomes ``H^3 + 6 l H^2`` (model/slip.py). A gas film's slip "
              "length is its mean free path; no cavitation floor acts with it."),
    # measured mu(p): ln(mu/mu0) linear between the points, extended with the last slope
    Group("viscosity_table", "measured viscosity against pressure, \"P:mu/mu0, ...\" from 0:1 "
          "with P increasing (P in mu a v0 / x1^2)", "viscosity table", math.nan, math.nan,
          default="", table=True, off="",
          doc=f"At most {MAX_TABLE_POINTS} points; ``ln(mu/mu0)`` is linear between them and "
              "extended beyond the last with its slope. Used by ``viscosity_law = \"table\"`` "
              "(\"auto\" where a table is given; ``beta`` is then not used)."),
)
# positions in Physics.as_array(), read by the compiled kernels: one slot per group in GROUPS
# order; the table (which must be the last group) takes its number of points K there, then K
# pressures, then K values ln(mu/mu0)
INDEX = {g.name: k for k, g in enumerate(GROUPS)}
assert [g.name for g in GROUPS if g.table] == [GROUPS[-1].name], "a table group must be last"
ST, EPS, PI, CAVITATION = INDEX["St"], INDEX["eps"], INDEX["Pi"], INDEX["cavitation"]
BETA, VISCOSITY, TENSION = INDEX["beta"], INDEX["viscosity_law"], INDEX["viscosity_in_tension"]
ROELANDS_Z, ROELANDS_PR = INDEX["roelands_Z"], INDEX["roelands_PR"]
DENSITY, DH_C1, DH_C2 = INDEX["density_law"], INDEX["dh_c1"], INDEX["dh_c2"]
TABLE = INDEX["viscosity_table"]
ROUGHNESS, ASPERITY_K, E_DRY = INDEX["roughness"], INDEX["asperity_stiffness"], INDEX["e_dry"]
SLIP = INDEX["slip_length"]


def codes(name: str) -> tuple:
    """The named choices of a group in the order of their codes in the kernels' array (a choice's
    code is its place here; "auto" is resolved before and has none): e.g. ``codes("cavitation")``
    is ``("off", "reynolds", "jfo")``, code 0 the classic film."""
    return tuple(c for c in GROUPS[INDEX[name]].choices if c != "auto")


VISCOSITY_LAWS = codes("viscosity_law")
DENSITY_LAWS = codes("density_law")
TENSION_CHOICES = codes("viscosity_in_tension")
CAVITATION_MODELS = codes("cavitation")
# the model "auto" resolves to where Pi is finite: the mass-conserving one, which the measured
# difference decides (docs/model.md, "Cavitation": the two agree while a cavity grows and differ
# where it refills, which only JFO conserves; benchmarks/cavitation.md)
DEFAULT_CAVITATION = "jfo"


def _docstring() -> str:
    """The docstring of ``Physics``, from ``GROUPS``."""
    lines = ["Every dimensionless group of one scene (docs/model.md).", "",
             "Generated from ``solver.physics.GROUPS``, which declares each group once.", "",
             "Parameters", "----------"]
    for g in GROUPS:
        if g.choices:
            kind = "{" + ", ".join(f'"{c}"' for c in g.choices) + "}"
        else:
            kind = "str" if g.table else "float"
        lines.append(f"{g.name} : {kind}")
        text = g.long_name[0].upper() + g.long_name[1:] + "."
        if g.numeric:
            lb = "[" if g.closed_lo else "("
            text += f" In {lb}{g.lo:g}, {g.hi:g}]."
        if g.default is not None:
            text += f" Default {g.default!r}."
        if g.off is not None:
            text += f" {g.off!r} switches it off."
        if g.doc:
            text += " " + g.doc
        lines += ["    " + line for line in textwrap.wrap(text, 92)]
    lines += ["", "Raises", "------", "ValueError",
              "    A value that is not a valid number (or choice) or lies outside its group's "
              "range; the", "    message names the group."]
    return "\n".join(lines)


class _PhysicsMethods:
    """What every ``Physics`` does beyond holding its groups (the fields come from ``GROUPS``)."""

    __slots__ = ()

    def __post_init__(self):
        for group in GROUPS:
            object.__setattr__(self, group.name, group.check(getattr(self, group.name)))
        model = self.cavitation
        if math.isinf(self.Pi):
            model = "off"
        elif model == "auto":
            model = DEFAULT_CAVITATION
        object.__setattr__(self, "cavitation", model)
        law = self.viscosity_law
        if law == "auto" and self.viscosity_table:
            law = "table"
        if law == "table" and not self.viscosity_table:
            raise ValueError("viscosity_law = 'table' needs a viscosity_table (\"P:mu/mu0, ...\")")
        if law not in ("auto", "table") and self.viscosity_table:
            raise ValueError(f"viscosity_law = {law!r} does not use the viscosity_table: give the "
                             "table (viscosity_law 'table' or 'auto') or the law, not both")
        if self.beta == 0.0 and law != "table":
            law = "constant"
        elif law == "auto":
            law = "barus"
        object.__setattr__(self, "viscosity_law", law)
        if self.density_law == "dowson-higginson" and self.dh_c1 == 0.0:
            object.__setattr__(self, "density_law", "constant")
        if self.roughness >= self.x_start:
            raise ValueError(f"roughness (roughness) = {self.roughness!r} must be smaller than the "
                             f"start gap x0/x1 = eps^-0.4 = {self.x_start:.6g}: the asperities "
                             "would touch before the collision starts (start farther out)")
        if self.slip_length > 0.0 and model != "off":
            raise ValueError(f"slip_length = {self.slip_length!r} with cavitation {model!r}: a "
                             "slipping film with a cavitation floor is not modelled (a gas film "
                             "has no floor: give Pi = inf, or slip_length = 0)")

    # ---- the declaration, for code that iterates over the groups ----------------------------
    @staticmethod
    def names() -> tuple:
        """Field names in kernel-array order."""
        return tuple(g.name for g in GROUPS)

    @staticmethod
    def group(name: str) -> Group:
        if name not in INDEX:
            raise KeyError(f"unknown physics field {name!r}; valid: {list(INDEX)}")
        return GROUPS[INDEX[name]]

    @classmethod
    def from_mapping(cls, values: dict):
        """A Physics from ``{name: value}``; unknown names are refused, naming the valid ones."""
        unknown = set(values) - set(cls.names())
        if unknown:
            raise ValueError(f"unknown physics field(s) {sorted(unknown)}; valid: "
                             f"{list(cls.names())}")
        missing = [n for n in cls.names() if n not in values and cls.group(n).default is None]
        if missing:
            raise ValueError(f"missing physics field(s) {missing}")
        return cls(**values)

    def as_dict(self) -> dict:
        return asdict(self)

    def as_array(self) -> np.ndarray:
        """The groups as a flat float array in ``names()`` order (what the kernels read): a
        number as it is, a choice as its code (``codes``), the table as its points."""
        values = []
        for g in GROUPS:
            value = getattr(self, g.name)
            if g.table:
                values += self._table_array()
            elif g.choices:
                values.append(codes(g.name).index(value))
            else:
                values.append(value)
        return np.array(values, dtype=float)

    def _table_array(self) -> list:
        points = parse_table(self.viscosity_table)
        return [len(points), *(p for p, _ in points), *(math.log(r) for _, r in points)]

    def replace(self, **changes):
        return replace(self, **changes)

    # ---- what the groups imply ---------------------------------------------------------------
    @property
    def classic(self) -> bool:
        """True when no physics beyond Davis, Serayssol & Hinch (1986) is switched on, so every
        analytic shortcut of the classic model (rigid phases, hand-over, release, master curve)
        is exact."""
        return (self.cavitation == "off" and self.isoviscous and self.smooth
                and self.slip_length == 0.0)

    @property
    def smooth(self) -> bool:
        """True when the surfaces are smooth (no asperity contact, so ``e_dry`` never acts)."""
        return self.roughness == 0.0

    @property
    def isoviscous(self) -> bool:
        """True when the liquid's viscosity and density do not depend on pressure."""
        return self.viscosity_law == "constant" and self.density_law == "constant"

    @property
    def x_start(self) -> float:
        """Start separation ``x0/x1 = eps^(-2/5)``."""
        return self.eps ** -0.4

    @property
    def tau_per_t(self) -> float:
        """``tau = v0 t / x0`` per ``T = v0 t / x1``: ``x1/x0 = eps^(2/5)``."""
        return self.eps ** 0.4


def _field(g: Group):
    kind = str if (g.choices or g.table) else float
    if g.default is None:
        return (g.name, kind)
    return (g.name, kind, field(default=g.default))


Physics = make_dataclass(
    "Physics", [_field(g) for g in GROUPS], bases=(_PhysicsMethods,), frozen=True,
    namespace={"__module__": __name__, "__qualname__": "Physics", "__doc__": _docstring()})
