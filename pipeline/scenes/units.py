"""Physical input values: SI numbers or strings with units, read with pint.

Scene files and the materials table accept either a plain number, taken as SI (``radius = 5e-5``),
or a string with units (``radius = "50 um"``, ``v0 = "10 cm/s"``, ``viscosity = "1 mPa s"``).
Strings are parsed by pint's unit registry (a maintained units library; no hand-written parser),
checked against the dimension the field needs, and converted to SI. Every error names the field.
"""

from __future__ import annotations

import math
from functools import lru_cache

__all__ = ["UnitError", "FieldSpec", "to_si", "format_quantity"]


from ..errors import UsageError


class UnitError(UsageError, ValueError):
    """A value that is not a number or quantity of the right dimension or range."""


class FieldSpec:
    """What one physical input field accepts.

    Parameters
    ----------
    dimension : str
        pint dimensionality, e.g. ``"[length]"``, ``"[mass] / [length] ** 3"``, or ``""`` for a
        pure number.
    example : str
        Shown in error messages (``'50 um'``).
    lo, hi : float
        Valid range of the SI value.
    lo_open, hi_open : bool
        Whether the bounds are excluded.
    """

    __slots__ = ("dimension", "example", "lo", "hi", "lo_open", "hi_open", "si_unit")

    def __init__(self, dimension, example, lo=0.0, hi=math.inf, *, lo_open=True, hi_open=True,
                 si_unit=""):
        self.dimension = dimension
        self.example = example
        self.lo, self.hi, self.lo_open, self.hi_open = lo, hi, lo_open, hi_open
        self.si_unit = si_unit

    def range_text(self) -> str:
        lb = "(" if self.lo_open else "["
        rb = ")" if self.hi_open else "]"
        unit = f" {self.si_unit}" if self.si_unit else ""
        return f"{lb}{self.lo:g}, {self.hi:g}{rb}{unit}"


@lru_cache(maxsize=1)
def _registry():
    import pint

    return pint.UnitRegistry()


def to_si(value, spec: FieldSpec, where: str) -> float:
    """Convert one input value to a float in SI units, or raise ``UnitError`` naming ``where``.

    Parameters
    ----------
    value : float, int or str
        A number (SI) or a string with units.
    spec : FieldSpec
        Dimension and valid range of the field.
    where : str
        Field name used in messages, e.g. ``"body1.radius"``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise UnitError(f"{where}: expected a number (SI) or a string with units such as "
                        f"'{spec.example}', got {value!r}")
    if isinstance(value, str):
        try:  # a quoted plain number (e.g. from a command-line flag) is SI, like a bare one
            value = float(value)
        except ValueError:
            pass
    if isinstance(value, str):
        import pint

        ureg = _registry()
        try:
            q = ureg.Quantity(value.strip())
        except (pint.errors.PintError, ValueError, TypeError, AttributeError,
                SyntaxError) as exc:  # pint raises a mix of these for unreadable strings
            raise UnitError(f"{where}: cannot read {value!r} as a quantity ({exc}); "
                            f"write e.g. '{spec.example}'") from None
        if not isinstance(q, ureg.Quantity):  # a bare number string such as "5"
            q = ureg.Quantity(float(q))
        expected = ureg.Quantity(1.0, spec.si_unit or "") if spec.dimension else None
        if spec.dimension:
            if q.dimensionality != expected.dimensionality:
                got = "no units" if q.dimensionless else f"units of {q.dimensionality}"
                raise UnitError(f"{where}: {value!r} has {got}; expected {spec.dimension} "
                                f"(e.g. '{spec.example}')")
            v = float(q.to(spec.si_unit).magnitude)
        else:
            if not q.dimensionless:
                raise UnitError(f"{where}: {value!r} must be a pure number (e.g. {spec.example})")
            v = float(q.to("").magnitude)
    else:
        v = float(value)
    if math.isnan(v):
        raise UnitError(f"{where}: value is NaN")
    ok_lo = v > spec.lo if spec.lo_open else v >= spec.lo
    ok_hi = v < spec.hi if spec.hi_open else v <= spec.hi
    if not (ok_lo and ok_hi):
        raise UnitError(f"{where} = {value!r} is outside its valid range {spec.range_text()}")
    return v


def format_quantity(value, unit: str, spec: str = ".4g") -> str:
    """``value`` (in SI ``unit``) with a readable prefix, e.g. ``format_quantity(2.5e-5, "m")``
    gives ``'25 µm'``; non-finite values and None as text."""
    if value is None:
        return "-"
    if not math.isfinite(value):
        return str(value)
    if value == 0:
        return f"0 {unit}"
    q = _registry().Quantity(value, unit).to_compact()
    return format(q, f"{spec}~P")
