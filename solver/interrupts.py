"""A Ctrl-C or SIGTERM held off while a block runs that must not be cut short.

Standard library only: ``solver.collision`` holds them around the compiled time loop, and the
sweep's store (pipeline/sweeps/store.py) around its merge of the journal, without importing
numba.
"""

import signal
import threading
from contextlib import contextmanager

# the signals whose Python handlers must not run inside compiled code (Ctrl-C; SIGTERM, which
# ``ehd`` turns into an exception: pipeline/cli.py)
DEFERRED_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextmanager
def deferred_interrupt():
    """Around a long compiled call (or a merge of finished work): a signal whose handler is
    Python code (Ctrl-C's default handler, or SIGTERM's where ``ehd`` raises ``Terminated``)
    that arrives while it runs is handled once the block is done, by the handler that was
    installed (the handler's exception replaces the block's own, if any). Raised inside it
    (Python's handlers run when numba converts the results back to Python objects) a Ctrl-C
    crashed the process with a segmentation fault (measured: ``ehd run`` interrupted mid-solve
    exited -11), and a SIGTERM came back as a ``SystemError`` that a serial sweep stored as the
    scene's failure (3 of 10 tries). Only in the main thread (where Python runs handlers); an
    ignored or default (non-Python) disposition is left as it is (a sweep's worker keeps
    ignoring Ctrl-C; a default SIGTERM ends the process at once, nothing stored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    previous = {}
    for signum in DEFERRED_SIGNALS:
        handler = signal.getsignal(signum)
        if callable(handler):
            previous[signum] = handler
            signal.signal(signum, lambda number, frame: caught.append(number))
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        for signum in dict.fromkeys(caught):  # each once, in the order they came; an
            previous[signum](signum, None)  # exception of the handler replaces the call's
