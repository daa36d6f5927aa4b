"""The one place that owns numba's compile flags and cache location.

- ``cache=True``, in a cache folder keyed by a hash of every solver source file: numba checks only
  the defining file's time stamp, so a change in a kernel that another file calls would otherwise
  run stale machine code (numba issues 1833, 9483).
- The cache folder is decided here, once, at import, for every caller (``ehd`` commands, dask
  workers, library users, editable or not, ``make`` or not): ``<root>/numba/solver-<hash>``, with
  ``<root>`` = ``$EHD_CACHE_DIR``, else ``$NUMBA_CACHE_DIR``, else ``$XDG_CACHE_HOME/ehd-collision``
  (``~/.cache/ehd-collision``). An unwritable folder gives one warning line on stderr and a
  per-user temporary folder instead; numba is never left to fall back silently to
  ``__pycache__`` (outside the source-hash folder). ``CACHE_DIR`` is the folder in use.
- ``nogil=True`` so threads can run scenes side by side.
- A NaN-safe fastmath subset: ``fastmath=True`` would make ``np.isfinite`` always true
  (numba issues 2919, 6217), and failure detection depends on it. Without ``reassoc``: it let
  the summation order depend on how a kernel was compiled, so freshly compiled and cache-loaded
  code differed in the last digits (the elastic product uses BLAS instead, linalg.matvec).
- ``error_model="numpy"``: division by zero gives inf (checked by the caller), not an exception.
- ``filled(shape, value)`` instead of ``np.zeros``, ``np.ones`` and ``np.full`` in compiled code:
  numba compiles each of those per form of its arguments, with the allocation it calls
  (``np.empty``) in a form of its own, and a fill: 23 such compiles for the solver's calls;
  ``filled`` allocates in the forms the solver's own ``np.empty`` calls take (one more, for
  bool) and fills in place: 5 compiles.
- ``copy_into`` instead of ``a[...] = b`` between arrays in compiled code: numba's slice
  assignment from an array carries a shape-mismatch error whose message is formatted in compiled
  code (``numba.np.arrayobj.raise_with_shape_context``), and its string machinery, linked into
  every function that assigns a slice and into each of their callers, cost a sixth of the
  solver's cold compile at solver 1.10.0 (45.5 s of CPU before, 38.6 s after; docs/solver.md,
  "Compiled code").
- ``hook``: ``jit`` with numba's ``inline="always"``, for the film contract's small answers on
  the loop's path: inlined, they cost their callers no reference counts (docs/solver.md,
  "Reference counting"), and the cold compile fell with them (0.91x, 3 alternated rounds).
  numba binds an inlined hook's parameters by copying its caller's variables, a count for
  each array or record, which LLVM's pruning leaves where the hook branches on a piece:
  ``_BindingsForwarded`` reads the caller's variables in their place.
- ``leaf``: ``jit`` compiled without numba's reference counting, for the functions called once
  per face or cell that read arrays and return numbers (the liquid's laws, the face flux):
  inlined instead, their bindings of ``phys`` were still counted in every call.
- Only an entry's module holds the code of the compiled functions it calls. numba links each
  compiled function's callees into its module and optimises and emits the whole again, so the
  functions at the top of the call tree paid again for everything below them, though only the
  machine code of what Python calls ever runs (a cached kernel holds all it calls). Here an
  entry (a function the solver calls from Python, marked ``entry``) links in every compiled
  function below it, renamed for it alone, and gets LLVM's whole-module passes (inlining
  across functions, the reference-count pruning); any other function gets numba's passes per
  function, and its module holds its own code only: its callees stay declarations, so it is
  never cached (a caller compiled by numba's own pipeline, a user's ``njit`` function, links
  in a copy with everything below it, as numba's libraries are linked). The classic
  collision's cold compile fell from 43.5 to 27.2 s of CPU (0.63x, 3 alternated rounds,
  0.61-0.64x), the compiled code the same (145 of the 146 regression scenes to the bit, one
  number by 1.8e-12 of itself). docs/solver.md, "Compiled code", says why the renaming. An
  entry links the libraries below it callers first (``_callers_first`` says why).
- An inner function's own machine code never runs, then: it is not emitted, nor the two wrappers
  numba adds to every function for callers outside compiled code (one converts Python's
  arguments, one is a C function pointer). A call from Python runs its twin (``_PythonCall``):
  the same function, compiled as an entry at that call. Its environment (which printing and
  exceptions with values read) is set all the same (``_environments_set``). The classic
  collision's cold compile took 0.76x the CPU time of the code before (3 alternated rounds,
  0.67-0.82x), every result the same to the bit (146 regression scenes, compiled and loaded).
  What an inner function can no longer be: a first-class function value (numba's
  ``FunctionType`` takes the C wrapper's address), or one of two functions that call each
  other (numba resolves that in machine code); the solver has neither.
- A kernel loaded from the cache starts only numba's runtime (``rtsys.initialize``), not a
  refresh of its typing and target contexts, which numba's ``Cache.load_overload`` does before
  every load: the refresh installs every lowering and typing registry, which only a compile
  reads (numba refreshes again before compiling, compiler.py), and cost a warm ``ehd run`` about
  0.12 s of its 0.82 s (benchmarks/startup.md). Our kernels are plain ``njit`` functions (no
  object mode, no ufunc built on load: the cases numba's refresh was added for, numba issue
  2198). Nor does a load import the numba modules whose helper functions were compiled into a
  kernel (array allocation, strings, hashing: 25 modules, 0.03 s): numba rebuilds each compiled
  function's environment with its module's globals, which nopython code never reads (only
  object mode does, numba/core/pylowering.py), so a numba module not yet imported gets its name
  alone (``_environment_without_import``). Where numba lacks the internals this relies on, its
  own loader runs unchanged.
"""

import collections
import functools
import hashlib
import inspect
import os
import sys
import tempfile
import threading
from pathlib import Path

import llvmlite.binding as llvm
import numba
import numpy as np
from numba.core import (codegen, compiler, environment, ir, ir_utils, registry, typed_passes,
                        untyped_passes)
from numba.core import dispatcher as numba_dispatcher
from numba.core.caching import FunctionCache
from numba.core.compiler_machinery import AnalysisPass, FunctionPass, register_pass
from numba.core.runtime import rtsys
from numba.extending import overload

FASTMATH = {"nsz", "arcp", "contract", "afn"}
# numba's flags that leave out an inner function's two wrappers and its machine code
_WITHOUT_MACHINE_CODE = ("no_cpython_wrapper", "no_cfunc_wrapper", "no_compile")


def _source_hash() -> str:
    digest = hashlib.sha256()
    root = Path(__file__).parent
    for path in sorted(root.rglob("*.py")):  # sub-packages too: a kernel may call any of them
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def cache_root() -> Path:
    """The documented cache root: ``EHD_CACHE_DIR``, else ``NUMBA_CACHE_DIR`` (respected for
    users who set numba's own variable), else ``$XDG_CACHE_HOME/ehd-collision``, else
    ``~/.cache/ehd-collision``."""
    for var in ("EHD_CACHE_DIR", "NUMBA_CACHE_DIR"):
        if os.environ.get(var):
            return Path(os.environ[var]).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base).expanduser() / "ehd-collision"


def _kernel_dir(root: Path) -> Path:
    return root / "numba" / f"solver-{_source_hash()}"


def _writable(folder: Path) -> str | None:
    """None if ``folder`` can be created and written to, else why not."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".write-test-"):
            pass
    except OSError as exc:
        return f"{type(exc).__name__}: {exc.strerror or exc}"
    return None


def _fallback_root() -> Path:
    try:
        user = str(os.getuid())
    except AttributeError:  # pragma: no cover - not POSIX
        import getpass

        user = getpass.getuser()
    return Path(tempfile.gettempdir()) / f"ehd-collision-{user}"


def _resolve_cache_dir() -> str | None:
    wanted = _kernel_dir(cache_root())
    why = _writable(wanted)
    if why is None:
        return str(wanted)
    fallback = _kernel_dir(_fallback_root())
    ok = _writable(fallback) is None
    instead = f"using {fallback} instead" if ok else "compiled code is not cached (slow start)"
    print(f"ehd-collision: warning: numba cache folder {wanted} is not writable ({why}); "
          f"{instead}. Set EHD_CACHE_DIR to a writable folder.", file=sys.stderr, flush=True)
    return str(fallback) if ok else None


# Every kernel's cache locator is fixed when it is decorated (below, at solver import), so this
# holds for the process whatever happens to the environment later.
CACHE_DIR = _resolve_cache_dir()
if CACHE_DIR is not None:
    numba.config.CACHE_DIR = CACHE_DIR


# no cache at all rather than numba's silent fallback to __pycache__ (no source-hash guard)
_FLAGS = dict(cache=CACHE_DIR is not None, nogil=True, fastmath=FASTMATH, error_model="numpy")


_rebuild_environment = getattr(environment, "_rebuild_env", None)  # numba's, which pickle calls
# whether numba rebuilds an environment as _environment_without_import expects (as numba 0.68
# does: from its module's name, constants and name); otherwise loads import the modules as before
_SWAP_ENVIRONMENTS = (
    _rebuild_environment is not None
    and list(inspect.signature(_rebuild_environment).parameters)
    == ["modname", "consts", "env_name"]
    and all(hasattr(environment, name) for name in ("lookup_environment", "Environment"))
    and hasattr(environment.Environment, "_memo"))


def _environment_without_import(module_name, consts, env_name):
    """numba's ``_rebuild_env`` (numba/core/environment.py), except that the environment of a
    function of a numba module not imported yet holds the module's name, not its globals (the
    module docstring says why)."""
    if module_name in sys.modules or not module_name.startswith("numba."):
        return _rebuild_environment(module_name, consts, env_name)
    env = environment.lookup_environment(env_name)
    if env is None:
        env = environment.Environment({"__name__": module_name})
        env.consts[:] = consts
        env.env_name = env_name
        environment.Environment._memo[env_name] = env
    return env


def _load_without_refresh(cache, sig, target_context):
    """numba's ``Cache.load_overload`` (numba/core/caching.py) less its ``refresh()`` of the
    target context, its environments rebuilt by ``_environment_without_import`` (the module
    docstring says why): the runtime a loaded kernel calls into is started, the rest is numba's
    own code path. Called under numba's compiler lock (``Dispatcher.compile`` holds it), which
    the swap of ``_rebuild_env`` relies on."""
    rtsys.initialize(target_context)
    if _SWAP_ENVIRONMENTS:
        environment._rebuild_env = _environment_without_import
    try:
        with cache._guard_against_spurious_io_errors():
            return cache._load_overload(sig, target_context)
    finally:
        if _SWAP_ENVIRONMENTS:
            environment._rebuild_env = _rebuild_environment


def _loaded_without_refresh(dispatcher):
    """``dispatcher``, its cache loading through ``_load_without_refresh`` where numba has the
    internals it calls, and saving only self-contained libraries (``_save_if_self_contained``);
    an uncached dispatcher is left as it is."""
    cache = dispatcher._cache
    if isinstance(cache, FunctionCache):
        needs = ("_load_overload", "_guard_against_spurious_io_errors")
        if all(hasattr(cache, name) for name in needs):
            cache.load_overload = functools.partial(_load_without_refresh, cache)
        cache.save_overload = functools.partial(_save_if_self_contained, cache.save_overload)
    return dispatcher


_ENTRIES = set()  # the Python functions of the compiled functions Python calls (``entry``)


def entry(dispatcher):
    """Marks a compiled function (``jit``, ``leaf``) that the solver calls from Python as an entry
    (the module docstring says what that is): the cache holds it, and a warm process loads it
    instead of compiling it. Any other compiled function can be called from Python too (tests
    do): that call compiles its twin, an entry never cached, in each process (``_PythonCall``)."""
    _ENTRIES.add(dispatcher.py_func)
    return dispatcher


def _whole_module_passes_skipped():
    """In place of a code library's ``_optimize_final_module`` (numba/core/codegen.py)."""


def _declarations_expected():
    """In place of an inner library's ``_verify_declare_only_symbols``: numba's check that every
    function its module declares was linked in, which an inner library leaves to the JIT."""


def _link_inner(library, callee):
    """In place of an inner library's ``add_linking_library``: no callee's code is linked in (its
    functions stay declarations, the callee finalised first); it is remembered for the entries
    above (``_link_closure``)."""
    callee._ensure_finalized()
    library._inner_callees.append(callee)


def _callers_first(roots):
    """The libraries ``roots`` run: themselves and, below an inner library, every library it calls
    (an entry's, a loaded one's, numba's own hold their callees), each once and after every one
    among them that calls it (the reverse of a depth-first search's finishing order; the calls
    form no cycle). The order in which a module must link them: numba hands a library's
    functions over as ``linkonce_odr``, which LLVM's linker brings in only where the module
    already refers to them, so a library linked before a caller that still calls it left that
    call to nothing (a null pointer, once numba pruned another caller's call to it away: the
    loop compiled without the liquid's laws, integration/kinds.py)."""
    finished, seen = [], set()
    for root in roots:
        if root in seen:
            continue
        seen.add(root)
        stack = [(root, iter(getattr(root, "_inner_callees", ())))]
        while stack:
            lib, callees = stack[-1]
            for callee in callees:
                if callee not in seen:
                    seen.add(callee)
                    stack.append((callee, iter(getattr(callee, "_inner_callees", ()))))
                    break
            else:
                stack.pop()
                finished.append(lib)
    return finished[::-1]


class _OwnCode:
    """An inner library as an entry links it: its own code (the entry links the rest)."""

    def __init__(self, library):
        self.library = library
        self._reload_init = library._reload_init

    def _ensure_finalized(self):
        self.library._ensure_finalized()

    def _get_module_for_linking(self):
        return type(self.library)._get_module_for_linking(self.library)


def _as_linked(library):
    """``library`` as it is linked into a module that holds everything below it: an inner
    library's own code (the rest comes with the closure), any other library whole."""
    return _OwnCode(library) if hasattr(library, "_inner_callees") else library


def _link_closure(library, callee):
    """In place of an entry's ``add_linking_library``: the callee is remembered, and linked in with
    every library below it when the entry is finalised (``_finalize_entry``), so the entry's
    module holds all it runs."""
    library._callees.append(callee)


def _self_contained_module(library):
    """In place of an inner library's ``_get_module_for_linking``, for a caller compiled by numba's
    own pipeline (a user's ``njit`` function): its own code with everything below it linked
    in, as numba's libraries are (the caller's machine code, which numba may cache, must hold
    all it runs). The solver's entries link ``_OwnCode`` instead."""
    if library._self_contained is None:
        closure = _callers_first([library])
        _environments_set(closure)
        module = _OwnCode(library)._get_module_for_linking().clone()
        for lib in closure[1:]:
            module.link_in(_as_linked(lib)._get_module_for_linking(), preserve=True)
        library._self_contained = module
    return library._self_contained


def _finalize_entry(library):
    """In place of an entry's ``finalize``: remembers the functions of its own code before numba
    links the others in (``_renamed_then_optimised``), and sets the environments of the inner
    functions it runs first (``_environments_set``)."""
    library._own = {f.name for f in library._final_module.functions if not f.is_declaration}
    linked = _callers_first(library._callees)
    for lib in linked:
        type(library).add_linking_library(library, _as_linked(lib))
    _environments_set(linked)
    type(library).finalize(library)


def _environments_set(libraries):
    """Sets the environment of every inner function among ``libraries`` in the JIT, as numba's
    lowering would have (``get_executable``), before a caller that links in their code is
    loaded: the code of a function that raises an exception with values, or prints, reads its
    environment from a global variable named after it, which numba sets once a module that
    defines it is loaded. An inner function's module never is, so a module defining those
    variables alone is loaded instead (a caller's own definition of one is the same symbol: the
    JIT binds a name that two modules define to the first it loaded). Without it, an inner
    function's ``print`` hung the compiling process, and an exception with values came out as
    a RuntimeError (a loaded entry sets them as numba's loader does)."""
    pending = [lib for lib in libraries if getattr(lib, "_environment", None) is not None
               and not lib._environment_set]
    if not pending:
        return
    jit_codegen = pending[0].codegen
    module = jit_codegen._create_empty_module("ehd_environments")
    for lib in pending:
        if not jit_codegen._engine.is_symbol_defined(lib._environment.env_name):
            registry.cpu_target.target_context.declare_env_global(module,
                                                                  lib._environment.env_name)
    if module.global_values:
        jit_codegen._engine.add_module(llvm.parse_assembly(str(module)))
        jit_codegen._engine.finalize_object()
    for lib in pending:
        jit_codegen.set_env(lib._environment.env_name, lib._environment)
        lib._environment_set = True


# The functions an entry links in that keep their names: numba's reference-count pruning pass
# (llvmlite's refprune, in the whole-module passes) recognises the calls to these by name alone.
# Renamed (1.15.2), the pruning found none: a classic collision spent 4.2 % of its samples in
# reference counting against 2.9 % at 1.15.1 (benchmarks/bench_refcount.py, 3 rounds each).
_RUNTIME_KEPT = frozenset({"NRT_incref", "NRT_decref"})


def _renamed_then_optimised(library):
    """In place of an entry's ``_optimize_final_module``: every function linked in is renamed for
    this entry alone (for this signature of it: the suffix is a digest of its own functions'
    names, which carry the argument types), so its calls run its own copies, optimised with it,
    never another module's (the JIT binds a call to a function that two modules define to the
    first it loaded, and an inner function's own copy is optimised function by function); then
    numba's passes. A name does not change the machine code, as a linkage would (``internal``
    let LLVM inline far more, 1.3x the compile). The runtime's reference counting keeps its
    names (``_RUNTIME_KEPT``): numba's pass that prunes redundant reference counts finds its
    calls by them, and every module's copy of them is the same code."""
    suffix = "." + hashlib.sha256("\n".join(sorted(library._own)).encode()).hexdigest()[:16]
    for function in library._final_module.functions:
        if not (function.is_declaration or function.name in library._own
                or function.name in _RUNTIME_KEPT):
            function.name = function.name + suffix
    type(library)._optimize_final_module(library)


@register_pass(mutates_CFG=False, analysis_only=True)
class _InnerLibrary(AnalysisPass):
    """Creates the function's code library as numba's lowering would. An entry (``entry``) links
    in every compiled function below it and is optimised as a whole. Any other function gets
    numba's passes per function, and its module holds its own code only: its compiled callees
    are declarations, so it is never cached, and it is lowered without the wrappers Python
    calls and never emitted as machine code (``_without_machine_code``). Which it is depends on
    the function alone, never on what was compiled before it in the process, so an entry's
    code (and every result) is the same wherever it was compiled."""

    _name = "ehd_inner_library"
    _always_entry = False

    def __init__(self):
        AnalysisPass.__init__(self)

    def run_pass(self, state):
        if state.library is not None:
            return False
        library = state.targetctx.codegen().create_library(state.func_id.func_qualname)
        library.enable_object_caching()  # as numba's NativeLowering does
        state.library = library
        if not _INNER_LIBRARIES:
            return False
        if self._always_entry or state.func_id.func in _ENTRIES:
            library._callees = []
            library.add_linking_library = functools.partial(_link_closure, library)
            library.finalize = functools.partial(_finalize_entry, library)
            library._optimize_final_module = functools.partial(_renamed_then_optimised,
                                                               library)
        else:
            library._inner_callees = []
            library._self_contained = None
            library._get_module_for_linking = functools.partial(_self_contained_module, library)
            library._optimize_final_module = _whole_module_passes_skipped
            library._verify_declare_only_symbols = _declarations_expected
            library.add_linking_library = functools.partial(_link_inner, library)
            library._finalize_final_module = functools.partial(_without_machine_code, library)
            for flag in _WITHOUT_MACHINE_CODE:
                setattr(state.flags, flag, True)
        return False


@register_pass(mutates_CFG=False, analysis_only=True)
class _Twin(_InnerLibrary):
    """``_InnerLibrary`` for a twin (``_PythonCall``): an entry whatever its function."""

    _name = "ehd_twin_library"
    _always_entry = True


@register_pass(mutates_CFG=False, analysis_only=True)
class _CalledFromCompiledCode(AnalysisPass):
    """After the lowering of an inner function, which ``_InnerLibrary`` told to make no wrapper and
    no machine code (numba's ``no_compile``, which also leaves out the registration below):
    registers the function for its compiled callers, as numba's lowering does, with a
    ``_PythonCall`` in place of the callable Python would run. A caller's lowering finds the
    function's library by that callable (numba's ``insert_user_function``)."""

    _name = "ehd_called_from_compiled_code"

    def __init__(self):
        AnalysisPass.__init__(self)

    def run_pass(self, state):
        if getattr(state.library, "_inner_callees", None) is None:
            return False
        call = _PythonCall(state.func_id.func, state.locals, state.flags, tuple(state.args))
        state.targetctx.insert_user_function(call, state.cr.fndesc, [state.library])
        state.library._environment = state.cr.env
        state.library._environment_set = False
        state.cr = state.cr._replace(cfunc=call)
        return False


@register_pass(mutates_CFG=False, analysis_only=False)
class _BindingsForwarded(FunctionPass):
    """After numba has inlined the hooks (``hook``) and unrolled its literal loops: each use of
    a variable that is only ever a copy of another is a use of that other one. numba binds an
    inlined function's parameters by copying its caller's variables (``param = var``), and
    lowers each copy of an array or a record as a reference count (an increment, a decrement
    after the last use). In the loop with every piece a hook's test of ``phys`` puts the two in
    different blocks, where LLVM's pruning of reference counts leaves them (docs/solver.md,
    "Reference counting").

    A copy ``t = s`` is forwarded where ``t`` has no other assignment, ``s`` has one that comes
    before the copy on every path (dominates it), and the copy comes before every use of ``t``:
    then ``s`` still holds the copied value at each use, since a path that assigned ``s`` again
    after the copy passes the copy again before the use. A value carried from one iteration of
    a loop to the next (``t`` assigned before the loop too) stays a copy. So does a variable
    with a declared type (numba's ``locals``), and one that numba's renaming would miss in a
    statement (a ``print(*t)``'s argument). numba's own copy propagation (``ir_utils.
    copy_propagate``, the parallel accelerator's) reads the typed IR and leaves the copies in
    place for a later dead-code pass; this one runs before the typing, so neither the typing
    nor the lowering sees them."""

    _name = "ehd_bindings_forwarded"

    def __init__(self):
        FunctionPass.__init__(self)

    def run_pass(self, state):
        blocks = state.func_ir.blocks
        assigned, read, kept = _assignments_and_reads(blocks)
        kept |= set(state.locals or ())
        dominators = ir_utils.compute_cfg_from_blocks(blocks).dominators()

        def before(first, then):  # position ``first`` comes before ``then`` on every path
            return (then[1] > first[1] if then[0] == first[0]
                    else first[0] in dominators[then[0]])

        forwarded = {}
        for label, block in blocks.items():
            for i, stmt in enumerate(block.body):
                if not (isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Var)):
                    continue
                copy, source = stmt.target.name, stmt.value.name
                if (copy != source and copy not in kept and source not in kept
                        and len(assigned[copy]) == 1 and len(assigned.get(source, ())) == 1
                        and before(assigned[source][0], (label, i))
                        and all(before((label, i), at) for at in read.get(copy, ()))):
                    forwarded[copy] = source
        if not forwarded:
            return False
        ir_utils.replace_var_names(blocks, forwarded)  # the copies become ``s = s``: dropped
        for block in blocks.values():
            block.body = [stmt for stmt in block.body if not (
                isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Var)
                and stmt.target.name == stmt.value.name)]
        state.func_ir._definitions = ir_utils.build_definitions(blocks)
        return True


def _assignments_and_reads(blocks) -> tuple[dict, dict, set]:
    """``({name: [(block label, statement index), ...]}, same, names)``: where each variable of
    a function's IR is assigned, where it is read (every variable a statement holds but the one
    it assigns), and the variables that numba's renaming (``ir_utils.visit_vars_stmt``) does not
    reach in some statement."""
    assigned, read, kept = {}, {}, set()

    def visited(var, names):
        names.append(var.name)
        return var

    for label, block in blocks.items():
        for i, stmt in enumerate(block.body):
            held = stmt.list_vars()
            target = stmt.target if isinstance(stmt, ir.Assign) else None
            for var in held:
                if var is not target:
                    read.setdefault(var.name, []).append((label, i))
            if target is not None:
                assigned.setdefault(target.name, []).append((label, i))
            names = []
            ir_utils.visit_vars_stmt(stmt, visited, names)
            kept |= set(collections.Counter(var.name for var in held)
                        - collections.Counter(names))
    return assigned, read, kept


class _Compiler(compiler.CompilerBase):
    """numba's nopython pipeline with ``_BindingsForwarded`` after the inlining and unrolling,
    ``_InnerLibrary`` before the lowering (and ``_CalledFromCompiledCode`` after it)."""

    _library_pass = _InnerLibrary

    def define_pipelines(self):
        pipeline = compiler.DefaultPassBuilder.define_nopython_pipeline(self.state)
        pipeline.add_pass_after(_BindingsForwarded, untyped_passes.LiteralUnroll)
        pipeline.add_pass_after(self._library_pass, typed_passes.AnnotateTypes)
        pipeline.add_pass_after(_CalledFromCompiledCode, typed_passes.NativeLowering)
        pipeline.finalize()
        return [pipeline]


class _TwinCompiler(_Compiler):
    """``_Compiler`` for a twin: an entry whatever its function."""

    _library_pass = _Twin


class _PythonCall:
    """What Python runs when it calls an inner function (compiled code calls the function itself):
    its twin, the same function compiled with the same flags as an entry (its callees' code
    linked in, machine code, the wrapper that converts Python's arguments), compiled at the
    first call and never cached (in the cache, the inner function would load it, and an entry
    compiled after that would link a loaded library's calls instead of the code below it).
    numba's C dispatcher calls this through ``Dispatcher._compile_for_args`` the first time,
    since ``_added_for_compiled_callers`` leaves it out of the table of callables it calls
    directly (it takes every callable there for numba's compiled function object); the twin's
    compiled function then goes into that table, so later calls run it as directly as they ran
    the inner function's own machine code before."""

    def __init__(self, py_func, locals, flags, signature):
        self._py_func = py_func
        self.signature = signature  # the argument types
        self._locals = dict(locals)
        self._flags = flags.copy()
        for flag in _WITHOUT_MACHINE_CODE:
            setattr(self._flags, flag, False)
        self._twin = None
        self._lock = threading.Lock()
        self.dispatcher = None  # set by _added_for_compiled_callers

    def __call__(self, *args):
        with self._lock:
            if self._twin is None:
                twin = registry.CPUDispatcher(
                    self._py_func, locals=self._locals, targetoptions={"nopython": True},
                    pipeline_class=_TwinCompiler)
                twin._compiler._customize_flags = lambda flags: self._flags.copy()
                compiled = twin.compile(self.signature)
                self.dispatcher._insert([a._code for a in self.signature], compiled, False)
                self._twin = twin
        return self._twin(*args)


def _without_machine_code(library):
    """In place of an inner library's ``_finalize_final_module``: its module is not handed to the
    JIT. Only its code as an entry links it in ever runs (``_PythonCall`` says what Python
    runs), so its machine code (and its wrappers, which ``_InnerLibrary`` leaves out) would be
    compiled for nothing."""
    library._finalize_dynamic_globals()
    library._finalized = True


_add_overload = numba_dispatcher.Dispatcher.add_overload


def _added_for_compiled_callers(self, cres):
    """numba's ``Dispatcher.add_overload``, except that an inner function's overload (whose
    callable is a ``_PythonCall``) stays out of the table of callables numba's C code calls
    directly: Python's first call finds none there and asks ``_compile_for_args``, which returns
    the ``_PythonCall``, which puts its twin's compiled function there."""
    if not isinstance(cres.entry_point, _PythonCall):
        return _add_overload(self, cres)
    cres.entry_point.dispatcher = self
    self.overloads[tuple(cres.signature.args)] = cres


def _save_if_self_contained(save, sig, cres):
    """In place of a cache's ``save_overload``: an inner library (its callees not linked in) is
    not saved: loaded in another process, its calls would have nothing to resolve to."""
    if getattr(cres.library, "_inner_callees", None) is None:
        save(sig, cres)


_FLAGS["pipeline_class"] = _Compiler
# whether numba's code libraries have the methods entries and inner libraries replace or call
# (else every function is compiled as numba compiles it)
_INNER_LIBRARIES = all(hasattr(codegen.CPUCodeLibrary, name) for name in (
    "finalize", "_optimize_final_module", "add_linking_library", "_ensure_finalized",
    "_verify_declare_only_symbols", "_get_module_for_linking", "_finalize_dynamic_globals")) and (
    hasattr(numba_dispatcher, "_FunctionCompiler")
    and hasattr(numba_dispatcher._FunctionCompiler, "_customize_flags")
    and hasattr(numba_dispatcher.Dispatcher, "add_overload")
    and hasattr(numba_dispatcher._DispatcherBase, "_insert")
    and all(hasattr(codegen.JITCPUCodegen, name) for name in ("set_env", "_create_empty_module"))
    and set(_WITHOUT_MACHINE_CODE) <= set(compiler.Flags.options))
if _INNER_LIBRARIES:
    numba_dispatcher.Dispatcher.add_overload = _added_for_compiled_callers


def jit(func):
    return _loaded_without_refresh(numba.njit(**_FLAGS)(func))


def leaf(func):
    """``jit`` without numba's reference counting, for the functions a loop calls once per face or
    cell that read arrays (the physics array ``phys``, the grid's arrays) and return only
    numbers: nothing they receive can be freed while they run (their caller holds it), and they
    create no array (numba refuses to compile an allocation, or a record's field read, without
    its runtime: a leaf takes a record's arrays, not the record). With the counts, a
    pressure-dependent liquid's face flux took 5-10 of them per face, 38 % of its collision's
    CPU time (docs/solver.md, "Reference counting"). Never for a function that returns an array
    or a view: its caller would release a reference it was never given."""
    return _loaded_without_refresh(numba.njit(**_FLAGS, _nrt=False)(func))


def hook(func):
    """``jit``, and inlined into every compiled caller by numba itself: for the film contract's
    small hooks that choose between the classic film and a piece (model/step.py). Called rather
    than inlined, such a hook kept the reference counts of everything it received, because its
    piece's branch makes a call (docs/solver.md, "Reference counting")."""
    return _loaded_without_refresh(numba.njit(**_FLAGS, inline="always")(func))


@jit
def copy_into(dst, src):
    """``dst[...] = src`` for C-ordered arrays of one shape, element by element (the reason is in
    the module docstring); a shape mismatch raises ValueError with a fixed message."""
    if dst.shape != src.shape:
        raise ValueError("copy_into: the arrays' shapes differ")
    if dst.ndim == 1:  # no reshaped views: small enough to inline, no references counted
        for i in range(src.size):
            dst[i] = src[i]
        return
    flat_dst = dst.reshape(dst.size)
    flat_src = src.reshape(src.size)
    for i in range(flat_src.size):
        flat_dst[i] = flat_src[i]


def filled(shape, value):
    """A new array of ``shape`` (an int or a tuple of ints) holding ``value`` everywhere, float64,
    int64 or bool as ``value`` is: ``np.full(shape, value)``. In compiled code it is numba's
    ``np.empty`` in the forms the solver's own calls take (the reason is in the module
    docstring), and any float is float64, any integer int64 (where numpy keeps float32 or
    uint64)."""
    return np.full(shape, value)


@overload(filled)
def _filled(shape, value):
    # a float takes np.empty's default dtype, as the solver's own float allocations do (an
    # explicit float64 would be another form of np.empty to compile)
    kind = numba.types.unliteral(value)
    if isinstance(kind, numba.types.Float):
        def impl(shape, value):
            out = np.empty(shape)
            out[...] = value
            return out

        return impl
    dtype = np.bool_ if isinstance(kind, numba.types.Boolean) else np.int64

    def impl(shape, value):
        out = np.empty(shape, dtype=dtype)
        out[...] = value
        return out

    return impl
