"""Which analytic shortcuts are exact for a scene's physics: the one place that decides.

A collision is a rigid approach, a coupled phase and a rigid departure (solver/collision.py);
each analytic piece is exact only for some physics. ``plan(physics)`` says, for one scene, which
piece applies where; collision.py, master.py and the sweeps' tasks ask it, and the modules that
hold the closed forms (model/rigid.py, model/piezoviscous.py, model/cavitation.py) refuse a scene
their plan does not give them. A new piece of physics states here what it does to each shortcut.

What each piece of physics does (docs/model.md, "Rigid solution", "Cavitation",
"Pressure-dependent viscosity and density"):

- the classic film: every shortcut is exact: the closed-form approach up to the hand-over, the
  release, the closed-form departure, the master curve;
- a pressure-dependent liquid: the Barus law at constant density has its own rigid approach (a
  scalar ODE, model/piezoviscous.py); any other law takes the classic approach only up to where
  it changes the rigid film by ``switch`` (collision.handover_separation), and the release waits
  until it no longer matters (rigid.release_event), after which the classic departure is exact;
  the master curve is not;
- a cavitation floor: the approach is unchanged (the film is in compression); the Reynolds
  condition (no memory), and any model at ``Pi = 0``, depart by the floor's own ODE
  (model/cavitation.py); a JFO cavity has a memory, so its coupled phase goes on until the film
  is full again (``events.RELAXED_FULL``), after which the classic departure is exact; the grid
  must reach the widest cavity; the master curve is not exact.
"""

from __future__ import annotations

from dataclasses import dataclass

from .integration.events import RELAXED, RELAXED_FULL
from .model import cavitation, piezoviscous, rigid

__all__ = ["Shortcuts", "plan"]


@dataclass(frozen=True)
class Shortcuts:
    """The analytic pieces of one scene's collision.

    approach
        ``"classic"``: the closed form of model/rigid.py (up to the hand-over, or to where the
        liquid's law starts to matter); ``"barus"``: the Barus film's rigid ODE
        (model/piezoviscous.py).
    end_event
        The coupled phase's terminal event (integration/events.py): ``RELAXED``, or
        ``RELAXED_FULL`` where the departure is exact only once a cavity has refilled.
    departure
        ``"classic"``: the closed form (rigid.restitution); ``"floor"``: the floor's ODE
        (model/cavitation.py) until the cavity closes, then the closed form.
    floor
        The film has a cavitation floor: the grid reaches its widest cavity.
    classic
        Every shortcut of the classic model is exact, the master curve (solver/master.py) among
        them: the classic film only.
    """

    approach: str
    end_event: int
    departure: str
    floor: bool
    classic: bool


def plan(physics) -> Shortcuts:
    """The shortcuts that are exact for ``physics`` (a ``solver.Physics``), from what each closed
    form says it is exact for (each module's ``exact_for``)."""
    barus = physics.viscosity_law == "barus" and piezoviscous.exact_for(physics)
    floor_ode = cavitation.exact_for(physics)
    refill = physics.cavitation == "jfo" and not floor_ode  # a cavity with a memory
    return Shortcuts(
        approach="barus" if barus else "classic",
        end_event=RELAXED_FULL if refill else RELAXED,
        departure="floor" if floor_ode else "classic",
        floor=physics.cavitation != "off",
        classic=rigid.exact_for(physics),
    )
