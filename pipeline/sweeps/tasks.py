"""The task a worker runs: one scene -> one plain record (a dict of numbers and strings).

This is the only code that runs on workers. It is a plain importable function (dask pickles it by
reference; no numba dispatchers or closures are shipped), and it never raises: an exception inside
the solver becomes a record with status ``"error"`` and the exception text, so a sweep with a bad
scene finishes and stores the failure.
"""

from __future__ import annotations

import math
import traceback
from pathlib import Path

from solver.observables import OBSERVABLES

from ..errors import interrupt_cause

__all__ = ["solve_scene", "warm", "one_scene_per_set", "collision_record", "error_record",
           "MasterSolve", "RECORD_FIELDS", "DIAGNOSTIC_FIELDS"]

# the record of a scene: every observable of the registry (solver/observables.py) plus labels;
# the scene's physics is not in it (the store's coordinates and fixed physics hold it)
RECORD_FIELDS = tuple(o.name for o in OBSERVABLES)
# what a failed scene keeps besides model/status/message: the solver's observables of a failed
# scene are defaults (v_r = 0, escaped = False, ...), not measurements, so they are missing
DIAGNOSTIC_FIELDS = tuple(o.name for o in OBSERVABLES if o.diagnostic)


def solve_scene(physics: dict, accuracy: str, overrides: dict) -> dict:
    """Solve one scene with the real solver and return its record.

    Parameters
    ----------
    physics : dict
        The scene: ``{name: value}`` for every field of ``solver.Physics``.
    accuracy : str
        Solver preset.
    overrides : dict
        ``solver.Numerics`` overrides (``save_profiles`` is forced off).

    Returns
    -------
    dict
        ``status`` ("ok", a solver failure code, or "error"), ``message``, ``model``,
        ``cache_key`` and the observables of ``solver.observables.OBSERVABLES`` (a failed scene:
        only the diagnostic ones). Floats keep ``inf`` (``tau_v_zero = inf``: the spheres never
        stop; ``x_e_x1 = inf``: exp overflow, see ``ln_x_e_x1``), which ``Collision.to_dict``
        would turn into None.
    """
    try:
        from solver import collide
        from solver.physics import Physics

        scene = Physics.from_mapping(physics)
        c = collide(scene, accuracy=accuracy, **{**overrides, "save_profiles": False})
        return collision_record(c)
    except Exception as exc:  # a bug or a bad scene must not stop the sweep: store it as data
        return error_record(exc)


def error_record(exc: BaseException) -> dict:
    """The record of a scene whose solve raised: status "error" and where it happened. An
    interrupt that came back wrapped (numba's ``SystemError`` around a Ctrl-C or SIGTERM) is
    not the scene's failure: it is raised again, so the scene is not stored and a resume
    recomputes it."""
    interrupt = interrupt_cause(exc)
    if interrupt is not None:
        raise interrupt from None
    tb = traceback.extract_tb(exc.__traceback__)
    where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
    return {"status": "error", "model": "unknown", "wall_s": math.nan,
            "message": f"{type(exc).__name__}: {exc}{where}"}


def collision_record(c, extra_numerics: dict | None = None) -> dict:
    """The record of a ``solver.Collision`` (see :func:`solve_scene`), with the cache key of the
    solver version and numerics that computed it *on this worker* (the store checks it: a worker
    with another installation must not slip its results in). ``extra_numerics``: settings
    outside ``solver.Numerics`` that are part of the key (``fast_path``). This is the key of the
    installation (``Sweep.worker_key``); the scene's physics is checked by the store."""
    from solver import SOLVER_VERSION

    from .config import cache_key

    numerics = {**c.numerics.as_dict(), **(extra_numerics or {})}
    record = {"status": c.status, "message": c.message, "model": c.model,
              "cache_key": cache_key(SOLVER_VERSION, numerics)}
    ok = c.status == "ok"
    for o in OBSERVABLES:
        if not (ok or o.diagnostic):
            continue
        value = getattr(c, o.name)
        if o.kind == "float":
            record[o.name] = float(value)
        elif o.kind == "flag":
            record[o.name] = None if value is None else bool(value)
        else:
            record[o.name] = int(value)
    reason = nonfinite_reason(record.get) if ok else ""
    if reason:  # never stored as ok
        record.update(status="error", message=reason)
    return record


# observables an ok scene has finite (v_r, h_m) or at least not NaN: ln_x_e may be inf, and so
# may the peak viscosity ratio (1 for the classic film), which is inf where the law's viscosity
# passes the double range (docs/pipeline.md, Variables: Barus beta 10 at St 1.44, eps 1e-2, whose
# film the solver resolves in the Kirchhoff pressure: v_r 0.0108); anything else is an
# overflow, not a result
FINITE_WHEN_OK = ("v_r", "h_m_x1", "h_m_x0", "energy_error")
NOT_NAN_WHEN_OK = ("ln_x_e_x1", "ln_x_e_x0", "viscosity_ratio_max_approach")


def nonfinite_reason(get) -> str:
    """Why a scene the solver called ok is not a result (``get(name)`` gives an observable), or
    "" when it is one."""
    bad = [f"{n} = {get(n)}" for n in FINITE_WHEN_OK
           if get(n) is not None and not math.isfinite(float(get(n)))]
    bad += [f"{n} = nan" for n in NOT_NAN_WHEN_OK
            if get(n) is not None and math.isnan(float(get(n)))]
    if not bad:
        return ""
    return (f"non-finite result ({', '.join(bad)}): an overflow, the inputs are beyond what the "
            "solver resolves")


class MasterSolve:
    """``solve`` for sweeps with ``fast_path = true``: scenes on the master curve are answered
    by interpolation in ``S = St V_switch`` (solver/master.py), the others by a direct solve.
    Picklable: the curve (a few kB of arrays) travels with the tasks."""

    def __init__(self, curve):
        self.curve = curve

    def __call__(self, physics: dict, accuracy: str, overrides: dict) -> dict:
        try:
            from solver.physics import Physics
            from solver.shortcuts import plan

            scene = Physics.from_mapping(physics)
            if plan(scene).classic:
                c = self.curve.collide(scene)
            else:  # the master curve holds the classic film only: never answer with it
                from solver import collide

                c = collide(scene, accuracy=accuracy, **{**overrides, "save_profiles": False})
            return collision_record(c, {"fast_path": True})
        except Exception as exc:  # stored as data, as in solve_scene
            return error_record(exc)


def warm(accuracy: str = "fast", overrides: dict | None = None, scenes=()) -> float:
    """Compile (or load from the on-disk cache) the solver's kernels in this process.

    Runs one small scene that takes the coupled (EHD) path, and one more per scene of ``scenes``
    (``one_scene_per_set``: a scene for each loop the sweep runs on beyond the classic film's,
    each compiled apart, solver/integration/kinds.py) with its St and eps
    made those of the small scene, so every kernel a sweep uses is compiled. Returns the wall
    time in seconds.
    """
    import time

    t = time.perf_counter()
    from solver import Physics, collide

    # eps = 0.01, St = 5 deforms early, so the coupled solve runs (a rigid-only scene would not
    # touch the compiled code; with presets where even this one were rigid, workers would only
    # compile on their own: slower, never wrong)
    kw = {**(overrides or {}), "save_profiles": False}
    collide(5.0, 0.01, accuracy=accuracy, **kw)
    for scene in scenes:
        try:
            collide(Physics.from_mapping({**scene, "St": 5.0, "eps": 0.01}), accuracy=accuracy,
                    **kw)
        except ValueError:  # not a valid scene there (e.g. a roughness beyond its start gap):
            pass  # its workers compile its loop on their own
    return time.perf_counter() - t


def one_scene_per_set(scenes) -> list[dict]:
    """The first scene (``{name: value}``) of ``scenes`` for each compiled loop beyond the classic
    film's that they run on (solver/integration/kinds.py: ``compiled_pieces``), for ``warm``."""
    from solver import Physics
    from solver.integration.kinds import compiled_pieces

    first = {}
    for scene in scenes:
        try:
            codes = compiled_pieces(Physics.from_mapping(scene).as_array())
        except ValueError:  # an invalid scene is stored as failed by its solve
            continue
        if codes:
            first.setdefault(codes, scene)
    return list(first.values())
