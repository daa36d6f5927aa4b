"""Which analytic shortcuts are exact for a scene's physics: the one place that decides.

A collision is a rigid approach, a coupled phase and a rigid departure (solver/collision.py);
each analytic shortcut is exact only for some physics. ``plan(physics)`` says, for one scene,
which applies where; collision.py, master.py and the sweeps' tasks ask it, and the modules that
hold the closed forms refuse a scene their plan does not give them.

What each piece of physics does to the shortcuts it declares in solver/pieces.py (docs/model.md,
"Rigid solution" and each piece's section): the classic film takes every shortcut (the closed-form
approach up to the hand-over, the release, the closed-form departure, the master curve); a piece
may stop the classic rigid approach earlier (``Piece.approach_stop``,
collision.handover_separation), bring a rigid approach or a departure of its own where that is
exact, or keep the coupled phase running until its film is full again (``events.RELAXED_FULL``);
a departure that starts from spheres apart ends the coupled phase there
(``events.RELAXED_APART``), and where it does not hold from that state the coupled phase runs on
until the film is full again (``run_on``); any piece that is on takes the master curve away.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from .integration.events import RELAXED, RELAXED_APART, RELAXED_FULL
from .model import rigid
from . import pieces
from .pieces import Piece

__all__ = ["Shortcuts", "plan", "run_on"]


@dataclass(frozen=True)
class Shortcuts:
    """The analytic pieces of one scene's collision.

    approach_piece
        The piece whose own rigid approach is exact (``Piece.rigid_approach``), or None: the
        classic closed form of model/rigid.py, up to the hand-over or to where a piece stops it.
    end_event
        The coupled phase's terminal event (integration/events.py): ``RELAXED``;
        ``RELAXED_FULL`` where the departure is exact only once the film is full again;
        ``RELAXED_APART`` where the departure piece's starts from spheres apart
        (``Piece.departs_apart``).
    departure_piece
        The piece whose own rigid departure is exact (``Piece.depart``), or None: the classic
        closed form (rigid.restitution).
    reader
        The piece that reads ``e`` at a reference separation from the coupled phase's end (its
        departure's or its refill's, ``Piece.restitution``), or None: the classic departure.
    classic
        Every shortcut of the classic model is exact, the master curve (solver/master.py) among
        them: the classic film only.
    """

    approach_piece: Piece | None
    end_event: int
    departure_piece: Piece | None
    reader: Piece | None
    classic: bool

    @property
    def approach(self) -> str:
        """The rigid approach's label: ``"classic"`` or the piece's own (``Piece.approach``)."""
        return self.approach_piece.approach if self.approach_piece else "classic"

    @property
    def departure(self) -> str:
        """The rigid departure's label: ``"classic"`` or the piece's own (``Piece.departure``)."""
        return self.departure_piece.departure if self.departure_piece else "classic"


def plan(physics) -> Shortcuts:
    """The shortcuts that are exact for ``physics`` (a ``solver.Physics``), from what each piece
    says its own shortcuts are exact for (solver/pieces.py) and model/rigid.py's ``exact_for``."""
    approach = next((p for p in pieces.PIECES if p.approach_exact(physics)), None)
    departure = next((p for p in pieces.PIECES if p.departure_exact(physics)), None)
    refill = next((p for p in pieces.PIECES if p.refills(physics)), None)
    apart = departure is not None and departure.departs_apart(physics)
    return Shortcuts(
        approach_piece=approach,
        end_event=RELAXED_FULL if refill else RELAXED_APART if apart else RELAXED,
        departure_piece=departure,
        reader=departure or refill,
        classic=rigid.exact_for(physics),
    )


def run_on(shortcuts: Shortcuts) -> Shortcuts:
    """The plan where the departure piece's own departure does not hold from the release state
    (its ``depart`` answered ``pieces.RUN_ON``; the time loop has asked it already where the
    phase ended, so this is a safety net, not seen in use): the coupled phase is solved again
    until the film is full, and the classic departure follows; the piece still reads ``e``."""
    return replace(shortcuts, end_event=RELAXED_FULL, departure_piece=None)
