"""The code stays readable (issue 28, "Done when"): no function in solver/ or pipeline/ longer
than 80 lines, no compiled function (decorated with the project's jit wrapper, solver/_jit.py) with
more than 12 arguments: the loop's functions take a few named records (model/state.py,
integration/stepper.py) instead of tens of positional arrays.

Read from the source with ``ast``, so a new function is checked the day it is written."""

import ast
from pathlib import Path

SOLVER = Path(__file__).resolve().parent.parent / "solver"
PIPELINE = SOLVER.parent / "pipeline"
MAX_LINES = 80  # the project guide's limit on a function's length
MAX_COMPILED_ARGUMENTS = 12  # issue 28: named records instead of positional arrays


def _functions(root=SOLVER):
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield path.relative_to(SOLVER.parent).as_posix(), node


def _compiled(node):
    """Decorated with ``jit`` (``from .._jit import jit``) or ``_jit.jit``."""
    for d in node.decorator_list:
        if isinstance(d, ast.Name) and d.id == "jit":
            return True
        if isinstance(d, ast.Attribute) and d.attr == "jit":
            return True
    return False


def _arguments(node):
    a = node.args
    return len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) \
        + bool(a.kwarg)


def test_the_check_sees_the_solvers_functions():
    """The walk finds the compiled loop (a check that read nothing would pass)."""
    names = {(path, node.name) for path, node in _functions() if _compiled(node)}
    assert ("solver/integration/stepper.py", "integrate") in names
    assert ("solver/model/film.py", "jacobian") in names
    assert len(names) > 50


def test_no_function_in_the_solver_or_the_pipeline_is_longer_than_80_lines():
    long = [f"{path}:{node.lineno} {node.name} ({node.end_lineno - node.lineno + 1} lines)"
            for root in (SOLVER, PIPELINE) for path, node in _functions(root)
            if node.end_lineno - node.lineno + 1 > MAX_LINES]
    assert not long, "split these functions: " + "; ".join(long)


def test_no_compiled_function_takes_more_than_12_arguments():
    many = [f"{path}:{node.lineno} {node.name} ({_arguments(node)} arguments)"
            for path, node in _functions()
            if _compiled(node) and _arguments(node) > MAX_COMPILED_ARGUMENTS]
    assert not many, "pass named records instead: " + "; ".join(many)

