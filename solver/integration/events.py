"""Terminal events of the time loop, passed in as data (as ``solve_ivp`` takes terminal events).

numba does not cache a compiled loop that takes another compiled function as an argument (it
recompiled in every process when tried), so an event is a kind code plus a parameter array,
evaluated here after each accepted step. The caller chooses the event that ends *its* model's
coupled phase: today the classic model's release (solver/model/rigid.py, ``release_event``).
"""

from .._jit import jit

__all__ = ["RELAXED", "RELAXED_FULL", "RELAXED_APART", "ENDED", "HELD", "reached"]

# The deformation has relaxed and the remaining motion can only relax it further: from here the
# rigid departure is exact (docs/model.md, "Rigid solution"). params = (release, V_peak,
# slope_compression, slope_tension, law_tol): stop once X > 0, max|W| < release X, the spheres
# separate (V < 0) or are past the rigid deformation peak (V < V_peak), and the liquid's law
# changes the rigid film by less than law_tol (slope times the rigid axis pressure |3V/X^2|,
# compression or tension; both slopes 0 for the classic film, docs/model.md "Pressure-dependent
# viscosity and density").
RELAXED = 1
# The same, and no cavity left: for a film whose cavity has a memory (JFO), the rigid departure is
# exact only once the film is full again.
RELAXED_FULL = 2
# The same as RELAXED, but with a cavity open only once the spheres separate: a JFO film's rigid
# departure with its cavity's memory (model/refill.py) starts from spheres apart; approaching,
# the coupled phase runs on. Where it happens the loop asks whether that departure refills the
# cavity (model/step.py: ``departure_holds``); where it does not, the phase goes on as
# RELAXED_FULL (integration/stepper.py).
RELAXED_APART = 3
# what a film may answer instead of its active radius (model/step.py, ``record``): the motion has
# ended (a rough film at rest on its asperities), or the phase must go on whatever the event
# (a rough film near contact)
ENDED, HELD = -1.0, -2.0


@jit
def reached(kind, params, steps, x, v, w_absmax, active_radius):
    """True when the event ``kind`` with ``params`` has happened at the accepted state
    (``steps`` accepted steps so far, separation ``x``, velocity ``v``, largest ``|W|``, radius out
    to which the film's active set reaches, 0 without; or ``ENDED``, ``HELD``: model/step.py,
    ``record``)."""
    relaxed = (steps > 0 and x > 0.0 and w_absmax < params[0] * x
               and (v < 0.0 or v < params[1]))
    slope = params[2] if v > 0.0 else params[3]
    if slope > 0.0:
        relaxed = relaxed and slope * 3.0 * abs(v) / (x * x) < params[4]
    if active_radius == ENDED:  # the film says the motion has ended (at rest in contact)
        return steps > 0
    if active_radius == HELD:  # the film holds the phase (a rough film near contact)
        return False
    if kind == RELAXED:
        return relaxed
    if kind == RELAXED_FULL:
        return relaxed and active_radius == 0.0
    if kind == RELAXED_APART:
        return relaxed and (active_radius == 0.0 or v < 0.0)
    return False
