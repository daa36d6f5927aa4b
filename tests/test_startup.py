"""A newcomer's first commands (issue 20): what ``ehd`` imports before it works, one version,
the files shipped with the package, ``ehd examples``, named sweeps, the figures' quick stamp.
Speed itself is measured in benchmarks/bench_startup.py, not here."""

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parent.parent
HEAVY = ("numba", "scipy", "xarray", "zarr", "distributed", "matplotlib", "pint",
         "solver.collision")


def _modules_after(argv, extra="") -> set[str]:
    """The modules loaded by ``ehd ARGV`` in a fresh interpreter (after it exits: --help)."""
    code = ("import sys\nfrom pipeline.cli import main\n" + extra +
            f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass\n"
            "print('\\n'.join(sorted(sys.modules)), file=sys.stderr)\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                       timeout=120)
    return set(p.stderr.split())


@pytest.mark.parametrize("argv", [["--help"], ["sweep", "--help"], ["figures", "--help"],
                                  ["scene", "--help"], ["examples", "--help"]])
def test_help_loads_neither_numba_nor_the_stack(argv):
    loaded = _modules_after(argv)
    assert "pipeline.cli" in loaded  # the probe worked
    assert not {m for m in HEAVY if m in loaded}, sorted(m for m in HEAVY if m in loaded)


def test_run_help_reads_the_physics_without_compiled_code():
    loaded = _modules_after(["run", "--help"])
    assert "solver.physics" in loaded and "numba" not in loaded and "scipy" not in loaded


# A classic collision in a fresh interpreter: the numba functions it compiles (numba's compile
# event fires on a compile, not on a load from the cache) and which of scipy's packages it loads
WARM_RUN = """
import sys
from numba.core import event
compiled = []
class Compiles(event.Listener):
    def on_start(self, ev): compiled.append(ev.data["dispatcher"].py_func.__qualname__)
    def on_end(self, ev): pass
event.register("numba:compile", Compiles())
from numba.core.base import BaseContext
refreshes = []
refresh = BaseContext.refresh
def counted(self):
    refreshes.append(type(self).__name__)
    refresh(self)
BaseContext.refresh = counted
from solver import Physics, collide
c = collide(Physics(St=10.0, eps=1e-4), accuracy="standard")
print(c.status, compiled, *(f"scipy.{name}" in sys.modules
                            for name in ("integrate", "optimize", "special", "linalg")),
      len(refreshes), "numba.np.arrayobj" in sys.modules)
import numba, numpy
print(numba.njit(lambda n: numpy.ones(n).sum())(2), len(refreshes) > 0,
      "numba.np.arrayobj" in sys.modules,
      collide(Physics(St=10.0, eps=1e-4), accuracy="standard").v_r == c.v_r)
"""


def test_a_warm_collision_compiles_nothing_and_loads_only_what_it_solves_with():
    """Once the cache holds the solver, a collision loads it and compiles nothing: a record built
    from Python (a numba StructRef's own constructor is never cached) was compiled in every
    ``ehd run``. scipy.integrate and scipy.optimize serve only the rigid paths of cavitation,
    the liquid laws and slip; the classic film imports neither (0.2 s for scipy.optimize, whose
    root finder its hand-over had used: benchmarks/startup.md), nor scipy.special (its elliptic
    and exponential integrals are solver/special.py's) nor the package scipy.linalg (its LAPACK
    bindings are loaded from their file: 0.1 s for the two). Nor does loading the kernels
    refresh numba's contexts (solver/_jit.py; 0.12 s) or import the numba modules whose helpers
    they contain (0.03 s); a compile after it still works (it refreshes the contexts and imports
    those modules itself), and the kernels loaded before it give the same answer after it."""
    def run():
        p = subprocess.run([sys.executable, "-c", WARM_RUN], cwd=REPO, capture_output=True,
                           text=True, timeout=600)
        assert p.returncode == 0, p.stderr
        return p.stdout.splitlines()
    run()  # fills the cache if this is the first collision of the suite
    collision, compile_after = run()
    assert collision == "ok [] False False False False 0 False", collision
    assert compile_after == "2.0 True True True", compile_after


# Collisions of every piece of physics and the DEM replica in a fresh interpreter: the compiled
# functions Python called (a dispatcher holds a signature only once it was compiled or loaded,
# and a warm process loads only what Python calls: its callees' code is in its library)
WARM_ENTRIES = """
import sys
from solver import Physics, collide
from pipeline.dem import liggghts
for fields in (dict(), dict(Pi=1e-3, cavitation="jfo"), dict(Pi=1e-3, cavitation="reynolds"),
               dict(beta=2.0), dict(roughness=1e-3, e_dry=0.9), dict(slip_length=0.1)):
    assert collide(Physics(St=10.0, eps=1e-4, **fields), accuracy="fast").status == "ok"
liggghts.replica_restitution(10.0, 0.9, 5.0)
liggghts.replica_many([10.0, 20.0], 0.9, 5.0)
from solver import _jit
called = sorted({f"{d.py_func.__module__}.{d.py_func.__qualname__}"
                 for module in list(sys.modules.values())
                 if module and module.__name__.startswith(("solver", "pipeline"))
                 for d in vars(module).values()
                 if getattr(d, "signatures", None) and getattr(d, "py_func", None)
                 and d.py_func not in _jit._ENTRIES})
print(called)
"""


def test_python_calls_only_the_compiled_entries():
    """Every compiled function the product calls from Python is marked ``entry``
    (solver/_jit.py), so it is the one LLVM optimises whole: one that is not would run code
    optimised function by function. Run twice: the first run may compile (then every callee
    holds a signature too); the second loads from the cache only what Python calls."""
    def run():
        p = subprocess.run([sys.executable, "-c", WARM_ENTRIES], cwd=REPO, capture_output=True,
                           text=True, timeout=900)
        assert p.returncode == 0, p.stderr
        return p.stdout.strip()
    run()
    assert run() == "[]"


def test_only_an_entry_links_in_and_optimises_the_code_below_it():
    """A compiled function that is not an ``entry`` holds its own code only (its callee is a
    declaration) and gets numba's passes per function; an entry's module holds its callees'
    code and gets LLVM's whole-module passes, which inline them. Compiled here (no cache): a
    loaded library is never finalised."""
    import numba

    from solver import _jit

    def twice(x):
        return 2.0 * x

    inner = numba.njit(pipeline_class=_jit._Compiler)(twice)

    def plus_one(x):
        return inner(x) + 1.0

    middle = numba.njit(pipeline_class=_jit._Compiler)(plus_one)

    def thrice_that(x):
        return 3.0 * middle(x)

    outer = _jit.entry(numba.njit(pipeline_class=_jit._Compiler)(thrice_that))
    assert outer(1.5) == 12.0
    assert middle(1.5) == 4.0
    library = {d: d.overloads[d.signatures[0]].library for d in (inner, middle, outer)}
    assert library[middle]._optimize_final_module is _jit._whole_module_passes_skipped
    twice_in_middle = [f for f in library[middle]._final_module.functions if "twice" in f.name]
    assert twice_in_middle and all(f.is_declaration for f in twice_in_middle)
    ir = outer.inspect_llvm(outer.signatures[0])
    assert "twice" in ir and "plus_one" in ir  # linked in (renamed for the entry)
    calls = [line for line in ir.splitlines()
             if "call" in line and ("twice" in line or "plus_one" in line)]
    assert not calls, calls  # inlined


# An entry over three inner functions: ``first`` calls ``doubled`` only in a branch that numba
# keeps and LLVM's passes of ``first`` remove (the inlined hook folds to True), ``second`` calls
# it for real
LINK_ORDER_RUN = """
import numba
from solver import _jit
FLAG = False
compiled = numba.njit(pipeline_class=_jit._Compiler)
always = numba.njit(pipeline_class=_jit._Compiler, inline="always")(lambda x: not FLAG or x > 0.0)
doubled = compiled(lambda x: 2.0 * x)
first = compiled(lambda x: 1.0 if always(x) else doubled(x))
second = compiled(lambda x: doubled(x) + 1.0)
print(_jit.entry(compiled(lambda x: first(x) + second(x)))(1.5))
"""


def test_an_entry_links_a_callee_after_every_caller_that_still_calls_it():
    """An entry links the libraries below it callers first (``_jit._callers_first``): numba hands
    a library's functions over as ``linkonce_odr``, which LLVM links in only where the module
    already calls them. Linked in the order found (``first``, ``doubled``, ``second``), the
    definition of ``doubled`` was dropped (``first`` no longer called it) and ``second``'s call
    went to a null pointer: a segmentation fault, as the loop compiled without the liquid's laws
    had (integration/kinds.py). In a subprocess, so that a crash is this test's failure."""
    p = subprocess.run([sys.executable, "-c", LINK_ORDER_RUN], cwd=REPO, capture_output=True,
                       text=True, timeout=300, env=dict(os.environ, NUMBA_DISABLE_CACHE="1"))
    assert p.returncode == 0, p.stderr[-2000:]
    assert p.stdout.split() == ["5.0"]


def test_an_inner_function_emits_no_machine_code_and_python_runs_its_twin():
    """An inner function is lowered without the wrappers Python calls and never handed to the JIT
    (its machine code would never run: the entries link in its code). A call from Python runs
    its twin, the function compiled as an entry: with its default arguments or keywords, and
    raising what the function raises; from the second call on, as directly as numba calls a
    compiled function (not through the dispatcher's compile path, which takes numba's lock and
    cost a four-element ``copy_into`` 29 us instead of 0.3)."""
    import numba

    from solver import _jit
    from solver._jit import copy_into

    def scaled(x, k=2.0):
        return k * x

    inner = numba.njit(pipeline_class=_jit._Compiler)(scaled)

    def plus_one(x):
        return inner(x) + 1.0

    middle = numba.njit(pipeline_class=_jit._Compiler)(plus_one)
    outer = _jit.entry(numba.njit(pipeline_class=_jit._Compiler)(lambda x: 3.0 * middle(x)))
    assert outer(1.5) == 12.0
    for d in (inner, middle):
        cres = d.overloads[d.signatures[0]]
        assert isinstance(cres.entry_point, _jit._PythonCall)
        defined = {f.name for f in cres.library._final_module.functions if not f.is_declaration}
        assert defined == {cres.fndesc.mangled_name}  # no wrapper
        assert not cres.library._codegen._engine.is_symbol_defined(cres.fndesc.mangled_name)
    compile_paths = []
    middle._compile_for_args = lambda *args: compile_paths.append(args) or (
        type(middle)._compile_for_args(middle, *args))
    assert middle(1.5) == 4.0 and middle(2.5) == 6.0  # compiled at the first call, then run
    assert compile_paths == [(1.5,)]
    assert inner(1.5) == 3.0 and inner(1.5, 3.0) == 4.5 and inner(1.5, k=4.0) == 6.0
    twin = middle.overloads[middle.signatures[0]].entry_point._twin
    ir = twin.inspect_llvm(twin.signatures[0])
    assert "scaled" in ir and not [line for line in ir.splitlines()
                                   if "call" in line and "scaled" in line]  # linked, inlined
    with pytest.raises(ValueError, match="shapes differ"):
        copy_into(np.zeros(2), np.zeros(3))


def test_an_inner_function_that_prints_or_raises_values_runs_in_the_compiling_process(capfd):
    """An inner function's environment (which printing and an exception with values read) is set
    though its module is never loaded (``_jit._environments_set``): in the process that compiles
    an entry, a user's function or a twin. Without it, the print hung the process, and the
    exception came out as a RuntimeError."""
    import numba

    from solver import _jit

    def checked(x):
        if x < 0.0:
            raise ValueError("negative", x)
        print("checked", x)
        return x

    inner = numba.njit(pipeline_class=_jit._Compiler)(checked)
    outer = _jit.entry(numba.njit(pipeline_class=_jit._Compiler)(lambda x: inner(x) + 1.0))
    users = numba.njit(lambda x: inner(x) * 2.0)
    for call, expected in ((outer, 3.0), (users, 4.0), (inner, 2.0)):
        with pytest.raises(ValueError) as raised:
            call(-1.0)
        assert raised.value.args == ("negative", -1.0)
        assert call(2.0) == expected
    assert capfd.readouterr().out.split("\n")[:3] == ["checked 2.0"] * 3


def test_an_entry_prunes_the_reference_counts_of_the_code_it_inlines():
    """An array passed down two calls counts a reference at each; inlined into the entry, those
    counts are redundant, and numba's pruning pass removes them, which finds the runtime's calls
    by their names: an entry renames what it links in except those (``_jit._RUNTIME_KEPT``).
    With them renamed too (1.15.2), two increments and two decrements stayed in this entry."""
    import re

    import numba

    from solver import _jit

    def first_plus_size(a):
        return a[0] + a.size

    inner = numba.njit(pipeline_class=_jit._Compiler)(first_plus_size)

    def doubled(a):
        return 2.0 * inner(a)

    middle = numba.njit(pipeline_class=_jit._Compiler)(doubled)

    def plus_one(a):
        return middle(a) + 1.0

    outer = _jit.entry(numba.njit(pipeline_class=_jit._Compiler)(plus_one))
    assert outer(np.array([1.5, 2.0])) == 8.0
    ir = outer.inspect_llvm(outer.signatures[0])
    assert "define" in ir and "first_plus_size" in ir  # linked in
    assert not re.findall(r"@NRT_(?:incref|decref)\.", ir)  # the runtime's names kept
    assert not re.findall(r"call \w+ @NRT_incref\b", ir)  # every increment pruned


def _hook_chosen(a, flag):  # a module's global: numba inlines a hook it finds there
    if flag:
        return _HOOK_CALLS(a) + a.size
    return a[1]


def _hook_both(a, flag):
    return _HOOK(a, flag) + _HOOK(a, not flag)


def test_an_inlined_hook_reads_its_callers_arrays_without_copying_them():
    """numba binds an inlined hook's parameters by copying its caller's variables, each copy of
    an array a reference count, which the loop with every piece left unpruned (9.0 % of a
    collision's CPU time, docs/solver.md, "Reference counting"); ``_jit._BindingsForwarded``
    reads the caller's variables instead."""
    import numba
    from numba.core import ir, types

    from solver import _jit

    global _HOOK, _HOOK_CALLS
    _HOOK_CALLS = numba.njit(pipeline_class=_jit._Compiler)(lambda a: a[0])  # not inlined
    _HOOK = numba.njit(pipeline_class=_jit._Compiler, inline="always")(_hook_chosen)
    outer = _jit.entry(numba.njit(pipeline_class=_jit._Compiler)(_hook_both))
    assert outer(np.array([1.5, 2.0]), True) == 5.5
    typed = outer.overloads[outer.signatures[0]].type_annotation
    names = {s.target.name for b in typed.blocks.values() for s in b.body
             if isinstance(s, ir.Assign)}
    assert any(n.startswith("_hook_chosen_v") for n in names)  # inlined, its names prefixed
    copies = [(s.target.name, s.value.name) for b in typed.blocks.values()
              for s in b.body if isinstance(s, ir.Assign) and isinstance(s.value, ir.Var)
              and isinstance(typed.typemap[s.target.name], types.Array)]
    assert not copies  # before: _hook_chosen_v2_a = a and _hook_chosen_v3_a = a


def test_a_copy_is_forwarded_only_where_it_holds_the_same_value():
    """``_BindingsForwarded``'s rule on a function's IR: ``b = a`` (a parameter, assigned once
    before it) is forwarded; ``y = x`` is not: ``y`` carries the last iteration's ``x`` into
    the next (forwarded, the sum would read this iteration's: 7 instead of 4). Compiled, the
    function gives Python's answer."""
    from types import SimpleNamespace

    from numba.core import compiler, ir

    from solver import _jit

    def carried(a):
        b = a
        total = 0.0
        y = 0.0
        for i in range(a.size):
            x = a[i]
            if i > 0:
                total += y
            y = x
        return total + b[0]

    state = SimpleNamespace(func_ir=compiler.run_frontend(carried), locals={})
    assert _jit._BindingsForwarded().run_pass(state)
    copies = {(s.target.name, s.value.name) for block in state.func_ir.blocks.values()
              for s in block.body if isinstance(s, ir.Assign) and isinstance(s.value, ir.Var)}
    assert ("b", "a") not in copies and ("y", "x") in copies
    a = np.array([1.0, 2.0, 4.0])
    assert _jit.jit(carried)(a) == carried(a) == 4.0


def test_copies_a_generator_a_literal_unroll_a_print_or_a_declared_type_needs_stay(capfd):
    """Four functions on which a review found the forwarding wrong (``_BindingsForwarded``):
    ``yield t`` read ``s`` where the copy did not come first ([0, 1, 2, 3, 4]); numba's
    ``literal_unroll`` lost the copies it substitutes the tuple's items in (102 instead of
    30507); ``print(*t)`` kept ``t``, which numba's renaming misses there (a TypingError); and a
    type declared for the copy (``locals``) was dropped (3.75 instead of 3). Each now gives
    what Python, or numba's own pipeline, gives."""
    import numba
    from numba import literal_unroll

    from solver import _jit

    def gen(a):
        for i in range(len(a)):
            s = a[i]
            if i % 2 == 0:
                t = s
            yield t

    def unroll(n):
        acc = 0
        for v in literal_unroll((3, 5, n)):
            acc = acc * 100 + v
        return acc

    def star_print(a, n):
        t = (a, n)
        u = t
        print(*u)
        return n

    def declared(n):
        s = n + 0.75
        t = s
        return t

    def compiled(f, **flags):
        return numba.njit(pipeline_class=_jit._Compiler, **flags)(f)

    a = np.arange(5.0)
    assert list(compiled(gen)(a)) == list(gen(a)) == [0.0, 0.0, 2.0, 2.0, 4.0]
    assert compiled(unroll)(7) == unroll(7) == 30507
    assert compiled(star_print)(np.arange(2.0), 3) == 3
    assert capfd.readouterr().out.split() == ["[0.", "1.]", "3"]
    assert compiled(declared, locals={"t": numba.int64})(3) == \
        numba.njit(locals={"t": numba.int64})(declared)(3) == 3


# A user's own numba functions that call the solver's inner compiled functions (linalg's LU,
# which calls another inner function; copy_into on 2-D arrays, which calls numba's helpers)
USER_MODULE = """
import numba
import numpy as np
from solver._jit import copy_into
from solver.integration.linalg import lu_factor, lu_solve


@numba.njit(cache=True)
def user_solve(a, b):
    piv = np.empty(a.shape[0], np.int32)
    lu_factor(a, piv)
    return lu_solve(a, piv, b)


@numba.njit(cache=True)
def user_copy(dst, src):
    copy_into(dst, src)
"""
USER_RUN = """
import json
import numpy as np
import usermod
a = np.array([[4.0, 1.0], [2.0, 3.0]])
x = usermod.user_solve(a.copy(), np.array([1.0, 2.0]))
d = np.zeros((2, 2))
usermod.user_copy(d, a)
print(json.dumps([bool(np.allclose(a @ x, [1.0, 2.0], rtol=1e-15, atol=0.0)), d.tolist(),
                  sum(usermod.user_solve.stats.cache_hits.values())]))
"""


def test_a_users_numba_function_may_call_the_solvers_inner_functions(tmp_path):
    """A function compiled by numba's own pipeline that calls an inner function links in all the
    code below it (as numba's libraries hold it), so it compiles (numba checks that every
    helper it declares was linked in: it raised for copy_into on 2-D arrays) and numba may
    cache it: loaded in the next process, it ran into an unresolved call (a segmentation
    fault) when it held the inner function's own code only."""
    (tmp_path / "usermod.py").write_text(USER_MODULE)
    env = dict(os.environ, EHD_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(REPO)]))
    outputs = []
    for _ in range(2):  # compiled and cached, then loaded
        p = subprocess.run([sys.executable, "-c", USER_RUN], cwd=tmp_path, env=env,
                           capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, p.stderr
        outputs.append(json.loads(p.stdout))
    solved_and_copied = [True, [[4.0, 1.0], [2.0, 3.0]]]
    assert outputs == [solved_and_copied + [0], solved_and_copied + [1]]  # a miss, then a hit


# A collision compiled in a fresh process with an empty cache, after Python called some of the
# loop's inner compiled functions itself (argv[1] == "inner-first"), or not. The inner functions
# the tests call are the solver's as imported, those of the loop with every piece, which a film
# with a piece runs (a JFO film here); the classic film runs a copy of the loop with its own
# functions (solver/integration/kinds.py), which Python never calls, so it is not solved here
ORDER_RUN = """
import sys
import numpy as np
if sys.argv[1] == "inner-first":  # the tests of the film's residual and Jacobian, the steps'
    from tests import test_film, test_stepper  # coefficients, predictor and error norm
    test_film.test_every_films_jacobian_matches_central_differences("classic", 0)
    test_stepper.test_predictor_extrapolates_polynomials_exactly()
    test_stepper.test_bdf_of_order_k_is_exact_for_polynomials_of_degree_k(4)
    test_stepper.test_norm_counts_small_pressures_as_absolute()
from solver import Physics, collide
for fields in (dict(St=10.0, eps=1e-4, Pi=1e-3, cavitation="jfo"),
               dict(St=10.0, eps=1e-4, beta=2.0, roughness=1.0)):
    c = collide(Physics(**fields), accuracy="standard")
    print(c.v_r.hex(), c.h_m_x1.hex(), c.ln_x_e_x1.hex(), c.steps)
"""


def test_a_collision_is_the_same_compiled_or_loaded_and_whatever_was_compiled_before(tmp_path):
    """Every result to the bit is the same whether ``integrate`` was compiled in the process
    (after Python called some of its inner functions, or not) or loaded from the cache another
    process filled: an entry's calls run its own copies of the functions below it, never an
    inner function's own copy, which is optimised differently (solver/_jit.py). With the
    entry's copies not renamed, the compiling process's results differed in the last digits
    from every later process's (118 of the 146 regression scenes)."""
    def start(order, cache):
        env = dict(os.environ, EHD_CACHE_DIR=str(tmp_path / cache))
        return subprocess.Popen([sys.executable, "-c", ORDER_RUN, order], cwd=REPO, env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def output(proc):
        out, err = proc.communicate(timeout=900)
        assert proc.returncode == 0, err
        return out
    # the two compiles side by side (each cache its own), then the load
    after_inner, alone = start("inner-first", "a"), start("collision-only", "b")
    compiled_after_inner = output(after_inner)
    assert output(alone) == compiled_after_inner  # compiled alone
    assert output(start("collision-only", "a")) == compiled_after_inner  # loaded


def test_a_sweep_with_nothing_to_do_loads_neither_dask_nor_the_solver(tmp_path):
    """``make sweep`` on a complete store: no cluster is started, so distributed (and dask, pint,
    numba...) is never imported (benchmarks/startup.md measures what that saves)."""
    from pipeline.sweeps.config import load_sweep
    from pipeline.sweeps.run import run_sweep
    from tests.test_pipeline import fake_solve, sweep_text

    toml = tmp_path / "s.toml"
    toml.write_text(sweep_text([1.0, 3.0], [1e-4, 1e-2], store=str(tmp_path / "s.zarr")))
    assert run_sweep(load_sweep(str(toml)), runner="serial", solve=fake_solve,
                     progress=None).exit_code == 0
    code = ("import sys\nfrom pipeline.cli import main\n"
            f"print('exit', main({['sweep', str(toml)]!r}))\n"
            "print('\\n'.join(sorted(sys.modules)), file=sys.stderr)\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                       timeout=120)
    assert "exit 0" in p.stdout and "cached 4" in p.stdout, p.stdout + p.stderr  # nothing to do
    loaded = set(p.stderr.split())
    heavy = {m for m in HEAVY if m not in ("xarray", "zarr")} | {"dask"}
    assert not heavy & loaded, sorted(heavy & loaded)


def test_a_numba_whose_environments_differ_loads_the_kernels_its_own_way():
    """Where numba's ``_rebuild_env`` is not what solver/_jit.py expects, its loads rebuild the
    environments themselves, importing their modules as numba always did, and give the same
    answer."""
    code = ("import sys\nimport solver._jit as j\nj._SWAP_ENVIRONMENTS = False\n"
            "from solver import Physics, collide\n"
            "c = collide(Physics(St=10.0, eps=1e-4), accuracy='standard')\n"
            "print(c.status, 'numba.np.arrayobj' in sys.modules, c.v_r.hex())\n")
    ours = ("from solver import Physics, collide\n"
            "print(collide(Physics(St=10.0, eps=1e-4), accuracy='standard').v_r.hex())\n")
    runs = [subprocess.run([sys.executable, "-c", text], cwd=REPO, capture_output=True,
                           text=True, timeout=600) for text in (ours, code)]
    assert all(p.returncode == 0 for p in runs), [p.stderr for p in runs]
    status, imported, v_r = runs[1].stdout.split()
    assert (status, imported, v_r) == ("ok", "True", runs[0].stdout.strip())


def test_scipy_linalg_imported_after_the_solver_is_a_plain_import():
    """The solver loads SciPy's LAPACK and BLAS bindings from their files, without the package
    scipy.linalg (solver/integration/linalg.py): a script that imports scipy.linalg afterwards
    finds both as attributes, the same modules, with the functions the solver bound."""
    code = ("import sys\nimport solver.integration.linalg\n"
            "print('scipy.linalg' in sys.modules)\n"
            "import scipy.linalg, scipy.linalg.cython_blas\n"
            "print(scipy.linalg.cython_lapack is sys.modules['scipy.linalg.cython_lapack'],\n"
            "      'dgetrf' in scipy.linalg.cython_lapack.__pyx_capi__,\n"
            "      'dgemv' in scipy.linalg.cython_blas.__pyx_capi__)\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                       timeout=120)
    assert p.stdout.split() == ["False", "True", "True", "True"], p.stdout + p.stderr


def test_the_executable_returns_the_commands_exit_code_and_freezes_the_collector():
    """``ehd`` (the ``executable`` entry point) exits with the command's code and leaves what
    it made frozen out of the garbage collector, so the interpreter's exit does not walk it
    (pipeline/cli.py); ``main``, which tests and scripts call, freezes nothing."""
    from importlib.metadata import entry_points

    (script,) = [e for e in entry_points(group="console_scripts") if e.name == "ehd"]
    assert script.value == "pipeline.cli:executable"
    code = ("import gc, sys\nfrom pipeline.cli import executable, main\n"
            "sys.argv = ['ehd', 'run', '--St', '-1', '--eps', '1e-4']\n"
            "first = main(sys.argv[1:]); frozen_by_main = gc.get_freeze_count()\n"
            "print(first, frozen_by_main, executable(), gc.get_freeze_count() > 0)\n")
    p = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True,
                       timeout=120)
    assert p.stdout.split() == ["2", "0", "2", "True"], p.stdout + p.stderr  # EXIT_USAGE


def test_version_is_the_package_and_the_solver_version(capsys):
    from importlib.metadata import version

    from pipeline.cli import main
    from solver import SOLVER_VERSION

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out == f"ehd-collision {version('ehd-collision')} (solver {SOLVER_VERSION})"
    assert version("ehd-collision") == SOLVER_VERSION  # one number, read from one attribute


def test_pyproject_version_is_dynamic_and_pytest_is_a_test_extra():
    meta = tomllib.loads((REPO / "pyproject.toml").read_text())
    project = meta["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert meta["tool"]["setuptools"]["dynamic"]["version"] == {
        "attr": "solver.result.SOLVER_VERSION"}
    assert not [d for d in project["dependencies"] if d.startswith("pytest")]
    assert [d for d in project["optional-dependencies"]["test"] if d.startswith("pytest")]
    # make install and make test install the extra
    assert "pip install --quiet -e .[test]" in (REPO / "Makefile").read_text()


def test_shipped_files_are_the_clone_folders():
    from pipeline import shipped

    for kind in shipped.FOLDERS:
        assert shipped.folder(kind) == REPO / kind  # an editable install: the clone's own
    assert {"paper", "quick", "cavitation", "piezoviscous"} <= set(shipped.sweep_names())
    assert shipped.resolve_sweep("paper") == str(REPO / "sweeps" / "paper.toml")
    # a path stays a path (the reader names any problem); an unknown bare name is refused
    assert shipped.resolve_sweep("sweeps/quick.toml") == "sweeps/quick.toml"
    assert shipped.resolve_sweep("nosuch.toml") == "nosuch.toml"
    from pipeline.errors import UsageError

    with pytest.raises(UsageError, match="no shipped sweep of that name .*paper"):
        shipped.resolve_sweep("nosuch")


def test_build_hook_ships_the_same_folders():
    """setup.py copies exactly ``shipped.FOLDERS`` into the wheel (one list, two readers)."""
    import ast

    from pipeline import shipped

    tree = ast.parse((REPO / "setup.py").read_text())
    value = next(n.value for n in tree.body if isinstance(n, ast.Assign)
                 and getattr(n.targets[0], "id", "") == "SHIPPED")
    assert ast.literal_eval(value) == shipped.FOLDERS


def test_ehd_examples_copies_the_shipped_files_and_keeps_changed_ones(tmp_path, capsys):
    from pipeline.cli import main

    target = tmp_path / "mine"
    assert main(["examples", str(target)]) == 0
    for kind in ("examples", "sweeps"):
        src = sorted(p.name for p in (REPO / kind).iterdir() if p.suffix in (".toml", ".py"))
        assert sorted(p.name for p in (target / kind).iterdir()) == src
        for name in src:
            assert (target / kind / name).read_bytes() == (REPO / kind / name).read_bytes()
    assert main(["examples", str(target)]) == 0  # the same files again: nothing to refuse
    mine = target / "sweeps" / "quick.toml"
    mine.write_text("# my edits\n")
    capsys.readouterr()
    assert main(["examples", str(target)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "quick.toml" in err and "--force" in err
    assert mine.read_text() == "# my edits\n"  # kept
    assert main(["examples", str(target), "--force"]) == 0
    assert mine.read_bytes() == (REPO / "sweeps" / "quick.toml").read_bytes()


def test_named_sweep_runs_without_a_path(tmp_path, monkeypatch, capsys):
    """``ehd sweep quick`` from a folder without sweep files: the shipped one (its 24 scenes
    are not solved here: --store of a stand-in, exit 2 tells it read the right file)."""
    from pipeline.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "busy.zarr").write_text("not a store")
    assert main(["sweep", "quick", "--store", "busy.zarr"]) == 2
    err = capsys.readouterr().err
    assert "--store busy.zarr: exists and is not a directory" in err  # the file was read
    assert main(["sweep", "nosuch"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no shipped sweep" in err and "quick" in err


def test_figures_stamp_skips_reading_an_unchanged_store(tmp_path, monkeypatch):
    from pipeline.plots import stamp, sweep_maps
    from pipeline.plots.sweep_maps import update_figures
    from tests.test_pipeline import open_results, stand_in_render, synthetic_store

    monkeypatch.setattr(sweep_maps, "render_all", stand_in_render)  # the stamp's logic only
    ds = synthetic_store(tmp_path)
    store = tmp_path / "s.zarr"
    assert stamp.up_to_date(store, tmp_path / "f") is None  # nothing drawn yet
    paths, rendered = update_figures(ds, tmp_path / "f", store=store)
    assert rendered
    quick = stamp.up_to_date(store, tmp_path / "f")
    assert quick is not None and sorted(map(str, quick)) == sorted(map(str, paths))
    data = json.loads((tmp_path / "f" / stamp.STAMP_NAME).read_text())
    assert data["store_state"] == stamp.store_state(store)
    # any file of the store written again (a sweep's merge) sends it to the full check
    chunk = next(p for p in sorted(store.rglob("*")) if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes())
    assert stamp.up_to_date(store, tmp_path / "f") is None
    # the full check finds the contents unchanged: no redraw, and the stamp is current again
    _, rendered = update_figures(open_results(store), tmp_path / "f", store=store)
    assert not rendered and stamp.up_to_date(store, tmp_path / "f") is not None
    (tmp_path / "f" / paths[0].name).unlink()  # a figure deleted: not up to date
    assert stamp.up_to_date(store, tmp_path / "f") is None


def test_scene_figures_carry_si_axes_in_the_scene_units(tmp_path):
    from matplotlib.figure import Figure

    from pipeline.plots.scene_plots import plot_motion, plot_profiles, si_scales
    from pipeline.scenes.commands import load_scene
    from pipeline.scenes.run import run_scene

    scene = load_scene(str(REPO / "examples" / "glass_beads_water.toml"))
    r = run_scene(scene, accuracy="fast", save_profiles=True)
    scales = si_scales(scene)
    assert scales["H"] == scene.x1 and scales["tau"] == scene.x0 / scene.v0
    fig = Figure(layout="constrained")
    ax = fig.subplots()
    plot_profiles(ax, r.collision, "P", scales=scales)
    axes = [*fig.axes, *(c for a in fig.axes for c in a.child_axes)]  # SI axes are children
    labels = [a.get_ylabel() for a in axes] + [a.get_xlabel() for a in axes]
    assert "pressure [MPa]" in labels and "radius [µm]" in labels  # 100s of MPa, um radii
    # the SI axis is the dimensionless one times the scale: the top of both agree
    fig.draw_without_rendering()  # secondary axes take their limits when drawn
    sec = next(a for a in axes if a.get_ylabel() == "pressure [MPa]")
    top = ax.get_ylim()[1]
    assert sec.get_ylim()[1] == pytest.approx(top * scene.pressure_scale / 1e6, rel=1e-9)
    fig = Figure(layout="constrained")
    plot_motion(fig, r.collision, scales=scales)
    axes = [*fig.axes, *(c for a in fig.axes for c in a.child_axes)]
    labels = [a.get_ylabel() for a in axes] + [a.get_xlabel() for a in axes]
    assert "force [µN]" in labels and "time [µs]" in labels
    assert any("= 4.319 nm" in lab for lab in labels)  # the symlog separation: x1 in its label


def test_sticking_threshold_separates_sticking_from_rebounding(tmp_path, capsys):
    from pipeline.cli import main
    from pipeline.dem.export import scene_path
    from pipeline.scenes.commands import load_scene
    from pipeline.scenes.run import run_scene
    from pipeline.scenes.threshold import RTOL, sticking_threshold

    path = str(REPO / "examples" / "glass_beads_water.toml")
    scene = load_scene(path)
    t = sticking_threshold(scene, "v0", "fast", start=0.3, stop=3.0, n=5)
    assert t.St_c is not None and t.bracket[1] / t.bracket[0] - 1.0 <= RTOL
    # just outside the final bracket: one side sticks, the other rebounds
    below, above = scene_path(scene, "v0", [t.bracket[0] * (1 - RTOL), t.bracket[1] * (1 + RTOL)])
    assert run_scene(below, accuracy="fast").collision.e_wet == 0.0
    assert run_scene(above, accuracy="fast").collision.e_wet > 0.0
    assert below.stokes < t.St_c < above.stokes
    assert t.value == pytest.approx(scene.v0 * t.factor)
    # a path that never changes says so
    none = sticking_threshold(scene, "v0", "fast", start=5.0, stop=10.0, n=2)
    assert none.St_c is None and "rebound at every v0" in none.note
    # the command: the table, the threshold line, the figure
    code = main(["restitution", path, "--accuracy", "fast", "--from", "0.3", "--to", "3",
                 "--n", "5", "--threshold", "--plot", str(tmp_path / "fig")])
    out = capsys.readouterr().out
    assert code == 0 and f"St_c = {t.St_c:.4g}" in out
    assert (tmp_path / "fig" / "restitution.png").stat().st_size > 1000
    assert (tmp_path / "fig" / "restitution.pdf").is_file()
