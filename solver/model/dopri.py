"""Dormand and Prince's explicit Runge-Kutta pair of orders 5 and 4 (J. R. Dormand, P. J. Prince,
J. Comput. Appl. Math. 6 (1980) 19-26; the tableau of SciPy's RK45): the coefficients the rigid
departures' compiled ODEs step with (model/cavitation.py, the Reynolds floor; model/refill.py, a
JFO cavity's refill). The seventh stage is the next step's first: the slopes at the new state.

Both control the step the classic way (``after_rejection``, ``after_acceptance``: the error's
fifth root, a safety factor 0.9, at most 10x larger and at most 5x smaller), and locate an event
within a step (the cavity's closing, a cell face the front reaches) by the Illinois variant of
the false position on the step's length, each trial a step of its own length: ``trial`` and
``illinois`` below."""

from .._jit import leaf

C2, C3, C4, C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
A21 = 1.0 / 5.0
A31, A32 = 3.0 / 40.0, 9.0 / 40.0
A41, A42, A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
A51, A52, A53, A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
A61, A62, A63 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0
A64, A65 = 49.0 / 176.0, -5103.0 / 18656.0
# the fifth-order weights
B1, B3, B4, B5, B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
# the fifth-order weights less the fourth-order ones: the local error's estimate
E1, E3, E4 = 71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0
E5, E6, E7 = -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0


@leaf
def trial(lo, hi, f_lo, f_hi):
    """The false position's next step length in the bracket ``(lo, hi)`` of the event function's
    values ``f_lo < 0 <= f_hi``; its midpoint where rounding puts that outside."""
    s = hi - f_hi * (hi - lo) / (f_hi - f_lo)
    return s if lo < s < hi else 0.5 * (lo + hi)


@leaf
def illinois(lo, hi, f_lo, f_hi, side, s, f_s):
    """The bracket after the trial ``s`` with the event function's value ``f_s`` (``>= 0``: at or
    past the event, the new ``hi``), the Illinois way (M. Dowell, P. Jarratt, BIT 11 (1971)
    168-174): an end kept twice in a row has its value halved, so the bracket closes from both
    sides. Returns ``(lo, hi, f_lo, f_hi, side)``, ``side`` 1 where ``s`` became ``hi``."""
    if f_s >= 0.0:
        return lo, s, f_lo * 0.5 if side == 1 else f_lo, f_s, 1
    return s, hi, f_s, f_hi * 0.5 if side == -1 else f_hi, -1


@leaf
def after_rejection(step, error):
    """The next trial after a step ``step`` whose scaled error ``error`` exceeded 1 (NaN: a trial
    stage outside the ODE's domain): at most 5x shorter."""
    return step * max(0.2, 0.9 * error ** -0.2) if error == error else 0.2 * step


@leaf
def after_acceptance(step, error):
    """The next step after an accepted ``step`` with scaled error ``error``: at most 10x longer."""
    return step * min(10.0, 0.9 * max(error, 1e-10) ** -0.2)
