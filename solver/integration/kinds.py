"""The time loop compiled for the pieces of physics a scene asks for.

``stepper`` as imported holds every piece's code (model/kind.py), and compiling it cold takes
18-20 s of CPU where the classic film's own code takes 11-12 s (benchmarks/compile.md).
``loop_for`` hands out a copy of the loop compiled for the pieces the physics asks for alone:
the modules that read model/kind.py's ``*_CODE`` constants, and every one between them and the
loop's entry (``_COPIED``), loaded anew under a package of their own (``solver._loop_<pieces>``,
``solver._loop_classic`` for none) with the pieces it lacks set False before they load; every
other module a copy imports is the solver's own (``_SharedModules``), so the copy shares its
records, grids and linear algebra. numba prunes the branches of the pieces a copy lacks, and
their code is never compiled. The loop with every piece is imported only when a physics asks for
it: a classic film's process never builds its dispatchers (about 20 ms of a warm ``ehd run``:
docs/solver.md, "Compiled code").

Each copy has its own folder in the compile cache (``loop-<pieces>`` in ``_jit.CACHE_DIR``):
numba names a cached kernel by its source file and function, which the copies share. A copy is
loaded once per process, when a scene first asks for its pieces. Only the classic film gets a
copy (``MOST_PIECES`` = 0); a physics with any piece runs ``stepper`` itself, which holds every
piece. Each copy compiles apart: a copy per piece alone (solver 1.16.0) took 13.6-14.8 s each
against 18.8-20.4 s for the loop with every piece once (in one run), so a sweep or a process
that met two pieces compiled more than it saved, and a fresh clone's ``.ci/run`` met the
classic film, each piece and the combinations (1.16.1, docs/solver.md "Compiled code").

A collision that asks for the attempt log (``collide(..., attempt_log=True)``) runs a copy with
model/kind.py's ``LOG_CODE`` True too (``loop-<pieces>_log``, every piece's included): the log's
code is in no other loop.
"""

import importlib
import importlib.abc
import importlib.util
import os
import sys
import threading
import types

import numba

from .. import _jit
from ..model import kind

# the modules a copy loads anew (relative to the solver package): model/kind.py, whose constants
# are set before the others load (they import them), and those whose compiled code reads them or
# calls one that does, up to the loop's entry (only the first two are loaded by name; the rest
# come with the copy's stepper, by the relative imports, in the order they need each other)
_COPIED = ("model.kind", "model.liquid", "model.slip", "model.film", "model.cavity_step",
           "model.contact_step", "model.step", "integration.stepper")
_PACKAGES = ("model", "integration")  # loaded anew too: a package holds its modules by name

MOST_PIECES = 0  # the most pieces a copy is compiled for; more run the loop as imported

_lock = threading.Lock()
_loops = {}  # (pieces (model/kind.py: CODES), with the attempt log) -> the copy's stepper module


def compiled_pieces(phys) -> tuple:
    """The pieces (model/kind.py: ``CODES``) the loop that runs the physics array ``phys`` is
    compiled for: those it asks for (``kind.asked_codes``), or every piece where it asks for more
    than ``MOST_PIECES``. Two physics with the same answer run the same compiled code."""
    codes = kind.asked_codes(phys)
    return kind.CODES if len(codes) > MOST_PIECES else codes


def loop_for(phys, log=False):
    """The stepper module (``integrate``, ``Start``, ``Control``) compiled for
    ``compiled_pieces(phys)``: ``stepper`` itself for every piece, else a copy loaded the first
    time a process asks for it; with ``log``, a copy that keeps the attempt log (model/kind.py:
    ``LOG_CODE``; every piece's too)."""
    codes = compiled_pieces(phys)
    if codes == kind.CODES and not log:
        from . import stepper  # the loop with every piece, imported when first asked for

        return stepper
    with _lock:
        if (codes, log) not in _loops:
            _loops[codes, log] = _load(codes, log)
        return _loops[codes, log]


def cache_folder(codes, log=False) -> str | None:
    """The compile cache folder of the loop compiled for ``codes`` (``compiled_pieces``): the
    solver's own (``_jit.CACHE_DIR``) for the loop with every piece, its ``loop-<pieces>`` for a
    copy (``loop-<pieces>_log`` with the attempt log); None where nothing is cached."""
    if _jit.CACHE_DIR is None:
        return None
    if codes == kind.CODES and not log:
        return _jit.CACHE_DIR
    return f"{_jit.CACHE_DIR}/loop-{_tag(codes, log)}"


def is_cached(codes) -> bool:
    """Whether the cache holds the loop for ``codes`` (its entry ``integrate``'s index file,
    numba's ``<module>.<function>-<line>.py<XY>.nbi`` in a folder named after the source's
    folder, ``<folder>_<hash of its path>``), so a solve with it loads rather than compiles."""
    import glob

    folder = cache_folder(codes)
    if folder is None:
        return False
    here = os.path.dirname(os.path.abspath(__file__))  # the loop's source: stepper.py beside this
    python = f"py{sys.version_info.major}{sys.version_info.minor}"
    pattern = (f"{glob.escape(folder)}/{os.path.basename(here)}_*/"
               f"stepper.{_ENTRY}-*.{python}.nbi")
    return bool(glob.glob(pattern))


_ENTRY = "integrate"  # the loop's entry in stepper.py, whose cache index ``is_cached`` looks for


class _SharedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """While a copy loads (``_load``): its import of a module it does not copy
    (``solver._loop_<tag>.<name>``, ``<name>`` not in ``_COPIED`` or ``_PACKAGES``) is the
    solver's own ``solver.<name>``, imported then if no one has yet; the copied modules load
    anew from their files (None: the next finder's)."""

    def __init__(self, package: str):
        self.prefix = package + "."
        self.own_specs = {}  # the copy's name -> the solver module's own spec

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith(self.prefix) or \
                fullname[len(self.prefix):] in _COPIED + _PACKAGES:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        module = importlib.import_module("solver." + spec.name[len(self.prefix):])
        self.own_specs[spec.name] = module.__spec__
        return module

    def exec_module(self, module):
        # the solver's own module, already executed; the import system has just set its
        # ``__spec__`` to the copy's (the one attribute it sets on a module that has one): its own
        # back, or the module would name itself after the copy (importlib.reload, -m)
        module.__spec__ = self.own_specs.pop(module.__spec__.name)


def _tag(codes, log=False) -> str:
    return ("_".join(codes) or "classic") + ("_log" if log else "")


def _load(codes, log=False):
    root = sys.modules["solver"]
    tag = _tag(codes, log)
    name = f"solver._loop_{tag}"
    package = types.ModuleType(name, f"The time loop compiled for {codes or 'the classic film'}.")
    package.__path__ = list(root.__path__)
    package.__package__ = name
    sys.modules[name] = package
    folder = cache_folder(codes, log)
    saved = numba.config.CACHE_DIR
    shared = _SharedModules(name)
    sys.meta_path.insert(0, shared)
    try:
        if folder is not None:
            numba.config.CACHE_DIR = folder  # a kernel's cache locator is fixed as it is decorated
        constants = importlib.import_module(f"{name}.model.kind")
        for code in kind.CODES:
            setattr(constants, f"{code.upper()}_CODE", code in codes)
        constants.LOG_CODE = log
        loop = importlib.import_module(f"{name}.integration.stepper")
    except BaseException:
        for full in [full for full in sys.modules if full == name or full.startswith(name + ".")]:
            del sys.modules[full]
        raise
    finally:
        sys.meta_path.remove(shared)
        numba.config.CACHE_DIR = saved
    return loop
