"""Physical input values: SI numbers or strings with units, read with pint.

Scene files and the materials table accept either a plain number, taken as SI (``radius = 5e-5``),
or a string with units (``radius = "50 um"``, ``v0 = "10 cm/s"``, ``viscosity = "1 mPa s"``).
Strings are parsed by pint's unit registry (a maintained units library; no hand-written parser),
checked against the dimension the field needs, and converted to SI. Every error names the field.

A string is read as a *quantity*, never evaluated as an expression: it must be a number followed
by a unit expression (``QUANTITY``: letters, digits, ``* / ^ ( ) .`` and spaces), which is then
handed to pint, and pint's magnitude must be that number (a number among the units, as in
``'100 um 2'``, which pint would multiply in, is refused); anything else
(``'__import__("os")'``, quotes, brackets, commas) is refused before pint sees it, and any
failure inside pint is one line naming the field. A value whose magnitude in
SI is subnormal or absurd (nonzero and below ``TINY`` or above ``HUGE``) is refused with the
field's range: no length of 1e-320 m reaches the solver to underflow there.
"""

from __future__ import annotations

import math
import re
from functools import lru_cache

from solver.physics import is_real_number

__all__ = ["UnitError", "FieldSpec", "to_si", "format_quantity", "TINY", "HUGE", "QUANTITY"]

# a number, then a unit expression; what pint is given to parse (a number inside the unit
# expression, as in '100 um 2' or '10 cm/s * 2', pint multiplies in: refused by ``to_si``, which
# checks that pint's magnitude is the leading number)
LEADING_NUMBER = re.compile(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
QUANTITY = re.compile(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?"
                      r"(\s*[A-Za-z0-9/(\u00b5\u03bc\u00b0\u2126%][A-Za-z0-9_\u00b5\u03bc\u00b0\u2126%\s*/^().-]*)?\s*")
# nonzero SI magnitudes outside [TINY, HUGE] are no physical input of this solver (the smallest
# are far below a nucleus, 1e-15 m, the largest far above any modulus or speed): a typo, or a value
# that would underflow or overflow in the reduced radius, the scalings or the kernel
TINY, HUGE = 1e-30, 1e30


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
    if not (is_real_number(value) or isinstance(value, str)):
        raise UnitError(f"{where}: expected a number (SI) or a string with units such as "
                        f"'{spec.example}', got {value!r}")
    if isinstance(value, str):
        try:  # a quoted plain number (e.g. from a command-line flag) is SI, like a bare one
            value = float(value)
        except ValueError:
            pass
    if isinstance(value, str):
        ureg = _registry()
        text = value.strip().lstrip("\ufeff")
        if not QUANTITY.fullmatch(text):
            raise UnitError(f"{where}: cannot read {value!r} as a quantity (a number and its "
                            f"units); write e.g. '{spec.example}'")
        try:
            q = ureg.Quantity(text)
        except Exception as exc:  # noqa: BLE001 - pint raises a mix (even AssertionError)
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise UnitError(f"{where}: cannot read {value!r} as a quantity ({reason}); "
                            f"write e.g. '{spec.example}'") from None
        if not isinstance(q, ureg.Quantity):  # a bare number string such as "5"
            q = ureg.Quantity(float(q))
        typed = float(LEADING_NUMBER.match(text).group(0))
        # pint multiplied in a number from the units ('100 um 2'); to round-off, as pint keeps
        # an integer past 2**53 exact where float() rounds it
        if not math.isclose(float(q.magnitude), typed, rel_tol=1e-12):
            raise UnitError(f"{where}: {value!r} has a number among its units (pint reads it "
                            f"as {q.magnitude:g} {q.units:~}); write one number, then the units, "
                            f"e.g. '{spec.example}'")
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
    if v != 0.0 and math.isfinite(v) and not TINY <= abs(v) <= HUGE:
        unit = f" {spec.si_unit}" if spec.si_unit else ""
        subnormal = "subnormal, " if abs(v) < 2.2250738585072014e-308 else ""  # float min
        raise UnitError(f"{where} = {value!r} is {subnormal}outside what this solver takes (its "
                        f"valid range is "
                        f"{spec.range_text()}, and a nonzero value must be within "
                        f"[{TINY:g}, {HUGE:g}]{unit} in magnitude)")
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
    q = _registry().Quantity(value, unit)
    if 1e-18 <= abs(value) < 1e21:  # atto to exa; beyond, the SI unit (not "100 rm/s")
        q = q.to_compact()
    return format(q, f"{spec}~P")
