"""Which pieces' code a compiled copy of the time loop holds, and which physics asks for each piece.

A piece of physics (solver/pieces.py) changes the film through hooks that do nothing where its
physics is off (model/step.py). Those hooks ask the physics array ``phys`` at run time, so the
loop compiled for every piece holds every piece's code, and a classic collision compiled all of
it: 18.4 s of CPU at 1.15.6, against 11.4 s for its own code alone (docs/solver.md, "Compiled
code"). Each piece's switch
is therefore also a constant here, ``*_CODE``: a hook that reads it first, in an ``if``
(``if CAVITATION_CODE: return asks_floor(phys)``), is one numba prunes where it is False, with
every call in the branch it guards, so that code is never compiled (a value such as ``not
CAVITATION_CODE or ...`` numba does not prune).

This module, imported as ``solver.model.kind``, holds every piece (``True`` throughout): the loop
as imported (``solver.integration.stepper``) runs any physics. ``solver.integration.kinds`` loads
a copy of the loop with them all False for the classic film, with its own compile cache;
``asked_codes`` says which pieces a physics asks for, and ``holds_asked`` is the loop's own check
that it holds them (``stepper.integrate`` refuses a physics whose code it lacks).

The ``asks_*`` tests are each piece's switch in the physics array, read by the hooks in compiled
code and by ``asked_codes`` in Python (their ``py_func``), so the two cannot disagree.
"""

from .._jit import leaf
from ..physics import (CAVITATION, CAVITATION_MODELS, DENSITY, DENSITY_LAWS, ROUGHNESS, SLIP,
                       VISCOSITY, VISCOSITY_LAWS)

# whether this copy of the loop holds each piece's code (a copy sets them before its modules load)
CAVITATION_CODE = True  # a floor on the pressure (Reynolds, JFO): model/cavity_step.py
CONTACT_CODE = True  # rough surfaces' asperity contact: model/contact_step.py
LIQUID_CODE = True  # a viscosity or density that depends on pressure: model/liquid.py
SLIP_CODE = True  # slip at the surfaces: model/slip.py
# whether this copy keeps the attempt log (integration/stepper.py: ``_log_attempt``): not a piece
# of physics, and False in the loop as imported, so that no loop but one asked for it compiles
# it (compiled into every loop it cost the cold compile 3-6 %); integration/kinds.py loads a
# copy with it where a collision asks for the log
LOG_CODE = False

# the pieces in the order ``asked_codes`` names them, each with its constant's name above
CODES = ("cavitation", "contact", "liquid", "slip")

_NO_FLOOR = float(CAVITATION_MODELS.index("off"))
_CONSTANT_VISCOSITY = float(VISCOSITY_LAWS.index("constant"))
_CONSTANT_DENSITY = float(DENSITY_LAWS.index("constant"))


@leaf
def asks_floor(phys):
    """Whether the physics has a floor on the film pressure (a cavitation model)."""
    return phys[CAVITATION] != _NO_FLOOR


@leaf
def asks_contact(phys):
    """Whether the surfaces are rough (asperity contact)."""
    return phys[ROUGHNESS] != 0.0


@leaf
def asks_liquid_law(phys):
    """Whether the liquid's viscosity or density depends on pressure."""
    return phys[VISCOSITY] != _CONSTANT_VISCOSITY or phys[DENSITY] != _CONSTANT_DENSITY


@leaf
def asks_slip(phys):
    """Whether the surfaces slip."""
    return phys[SLIP] != 0.0


_ASKS = (asks_floor, asks_contact, asks_liquid_law, asks_slip)  # in the order of CODES


def asked_codes(phys) -> tuple:
    """The pieces (names from ``CODES``) whose code the physics array ``phys`` needs, in Python."""
    return tuple(name for name, asks in zip(CODES, _ASKS) if asks.py_func(phys))


@leaf
def holds_asked(phys):
    """Whether this copy of the loop holds the code of every piece ``phys`` asks for."""
    return ((CAVITATION_CODE or not asks_floor(phys)) and (CONTACT_CODE or not asks_contact(phys))
            and (LIQUID_CODE or not asks_liquid_law(phys)) and (SLIP_CODE or not asks_slip(phys)))
