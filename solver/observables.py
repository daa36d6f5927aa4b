"""One registry of what a collision reports: observables, status codes, models, series columns.

Everything that lists results is generated from these declarations: the JSON keys of
``Collision.to_dict`` (``JSON_KEYS``), the record a sweep task returns, the store's variables
(with ``long_name`` and ``units``), the quantities the master-curve fast path interpolates, and the
rows ``ehd run`` prints; with its ``scene`` keys, the SI keys of ``ehd scene --json`` and the rows
of its report (pipeline/scenes/run.py, ``si_results``; commands.py, ``result_rows``). Adding an
observable is one entry here plus the code that computes it.

Units (docs/model.md, "Scales"): lengths along the axis in ``x1`` (suffix ``_x1``) or ``x0``
(``_x0``), times ``tau = v0 t / x0``, velocities in ``v0``, force in ``6 pi mu a^2 v0 / x1``,
pressure in ``mu a v0 / x1^2``, energies relative to the initial kinetic energy ``m v0^2 / 2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Observable", "SceneKey", "si_unit", "OBSERVABLES", "OBSERVABLE", "STATUS",
           "STATUS_CODES", "MODEL_CODES",
           "LABELS", "Column", "SERIES", "SERIES_INDEX", "failure_message"]


@dataclass(frozen=True)
class SceneKey:
    """One SI key of ``ehd scene --json`` made from an observable, and its report row.

    key
        The JSON key; its suffix names the SI unit (``SI_UNITS``: ``_nm``, ``_m``, ``_m3``,
        ``_s``, ``_N``, ``_Pa``, ``_Pa_s``, ``_m_per_s``; none: a pure number).
    scale
        The scene scale that makes the observable SI (pipeline/scenes/run.py, ``SCALES``): a
        units string of this module (``"x1"``, ``"x0/v0"``, ``"sqrt(a x1)"``...), ``"mu0"`` (the
        ambient viscosity) or ``"v(x_ref)"`` (the approach speed at x_ref); ``""``: the
        observable's own ``units``.
    label
        Its row in the scene report; ``""``: JSON only.
    form
        ``""``: the observable times the scale. ``"exp"`` and ``"log10"``: the observable is the
        natural log of a quantity over the scale, the key holds that quantity in SI (null where
        it passes e^700) or its log10.
    null
        What the report shows where the value is null (``""``: ``-``).
    when
        The row is shown only where this key of the scene's JSON is true (``"cavitated"``) or
        is not the value after ``!=`` (``"viscosity_law!=constant"``); ``""``: always.
    outer
        Read through the outer flow (solver/far_field.py): null for a scene without one (two
        unequal spheres).
    """

    key: str
    scale: str = ""
    label: str = ""
    form: str = ""
    null: str = ""
    when: str = ""
    outer: bool = False


# JSON key suffix -> (unit printed, factor from the SI base unit); the longest suffix wins
SI_UNITS = {"_m_per_s": ("m/s", 1.0), "_Pa_s": ("Pa*s", 1.0), "_nm": ("nm", 1e9),
            "_m3": ("m^3", 1.0), "_m": ("m", 1.0), "_s": ("s", 1.0), "_N": ("N", 1.0),
            "_Pa": ("Pa", 1.0)}


def si_unit(key: str) -> tuple[str, float]:
    """``(unit, factor)`` of a scene key from its suffix (``SI_UNITS``); ``("", 1.0)``: a
    pure number."""
    return next((v for s, v in SI_UNITS.items() if key.endswith(s)), ("", 1.0))


@dataclass(frozen=True)
class Observable:
    """One scalar result of a collision.

    kind
        ``"float"``, ``"flag"`` (bool; None when unknown), ``"count"`` (int).
    label
        Row label in the printed report; empty: not printed.
    diagnostic
        Kept when the scene failed (cost counters, wall time); every other observable of a failed
        scene is missing (NaN), never a guess.
    master
        How the master-curve fast path carries it from the tabulated scene (solver/master.py):
        ``"<interpolation> <scaling>"``, interpolation ``log`` (positive values spanning decades)
        or ``lin``; scaling ``length``, ``velocity``, ``force``, ``pressure``, ``log_length``,
        ``energy``, ``time`` or ``none`` (docs/model.md, "Similarity"); ``""`` when it is derived from other
        observables or not available on that path.
    derived, start
        A derived observable is a property of ``Collision`` computed from the others; every
        other one is a field of it (solver/result.py), starting at ``initial``.
    scene
        Its SI keys in ``ehd scene`` (``SceneKey``: key, scale, report row); ``()``: it is in
        ``ehd scene``'s ``dimensionless`` object only.
    """

    name: str
    kind: str
    long_name: str
    units: str
    label: str = ""
    diagnostic: bool = False
    master: str = ""
    derived: bool = False  # computed from other observables (a property of Collision, no field)
    start: object = None  # a Collision's value before its solve sets it (None: by kind)
    scene: tuple = ()  # SceneKey: the SI keys of `ehd scene` and their report rows

    @property
    def initial(self):
        """The value a ``Collision`` holds until the solve sets it: ``start``, else NaN for a
        float, False for a flag, 0 for a count."""
        if self.start is not None:
            return self.start
        return {"float": math.nan, "flag": False, "count": 0}[self.kind]


_P = "mu a v0 / x1^2"
OBSERVABLES = (
    Observable("v_r", "float", "maximum rebound (separation) velocity max(-v)/v0, 0 without "
               "rebound", "v0", "rebound velocity v_r/v0", master="lin velocity",
               start=0.0,
               scene=(SceneKey("v_r", "1"),
                      SceneKey("rebound_speed_m_per_s", label="max rebound speed"))),
    Observable("e_wet", "float", "wet coefficient of restitution: separation speed where the "
               "spheres pass back out through x_ref (default x0) over the approach speed there; "
               "0 when they stick", "v0/v0", "wet restitution e_wet (at x_ref)",
               # a scene reads e_wet at x0 (its x_ref is e_far's, docs/scenes.md)
               scene=(SceneKey("e_wet", "1", "wet restitution e_wet"),
                      SceneKey("departure_speed_m_per_s", "v(x_ref)",
                               "  departure speed at x0"))),
    Observable("h_m_x1", "float", "closest approach of the deformed surfaces, whole collision",
               "x1", "closest approach h_m/x1", master="log length",
               scene=(SceneKey("closest_approach_nm", label="closest approach"),)),
    Observable("h_m_x0", "float", "closest approach of the deformed surfaces, whole collision",
               "x0", "  h_m/x0", derived=True),
    Observable("h_m_approach_x1", "float", "closest approach until v first reaches 0", "x1",
               "closest approach on approach /x1", master="log length",
               scene=(SceneKey("closest_approach_on_approach_nm", label="  during approach"),)),
    Observable("h_m_approach_x0", "float", "closest approach until v first reaches 0", "x0",
               derived=True),
    Observable("x_e_x1", "float", "equilibrium separation of the undeformed surfaces (inf: exp "
               "overflow, see ln_x_e_x1)", "x1", "equilibrium separation x_e/x1", derived=True),
    Observable("x_e_x0", "float", "equilibrium separation of the undeformed surfaces (inf: exp "
               "overflow, see ln_x_e_x0)", "x0", "  x_e/x0", derived=True),
    Observable("ln_x_e_x1", "float", "natural log of x_e/x1 (finite where x_e/x1 overflows)", "1",
               "  ln(x_e/x1)", master="lin log_length",
               scene=(SceneKey("equilibrium_separation_m", "x1", "equilibrium separation x_e",
                               "exp",
                               null="beyond e^700 m"),
                      SceneKey("log10_equilibrium_separation_m", "x1", "  log10(x_e / m)",
                               "log10"))),
    Observable("ln_x_e_x0", "float", "natural log of x_e/x0; > 0 means escaped", "1", derived=True),
    Observable("tau_max_deformation", "float", "time of the largest central deformation W(0)",
               "x0/v0", "tau at max deformation", master="lin time"),
    Observable("tau_v_zero", "float", "first time v = 0 (inf: the spheres never stop in finite "
               "time)", "x0/v0", "tau at v = 0", master="lin time",
               scene=(SceneKey("time_to_stop_s", label="time to stop (v = 0)",
                               null="never in finite time (creeps to rest)"),)),
    Observable("tau_max_rebound", "float", "time of the largest rebound speed (NaN: no rebound)",
               "x0/v0", "tau at max rebound", master="lin time",
               scene=(SceneKey("time_of_max_rebound_s", label="time of max rebound",
                               null="no rebound"),)),
    Observable("tau_peak_force", "float", "time of the peak film force", "x0/v0",
               master="lin time"),
    Observable("peak_force", "float", "peak film force", "6 pi mu a^2 v0 / x1",
               "peak force / (6 pi mu a^2 v0/x1)", master="log force",
               scene=(SceneKey("peak_force_N", label="peak force"),)),
    Observable("p_max", "float", "largest film pressure over the collision (a pressure-dependent "
               "liquid: until v first reaches 0)", _P,
               "peak film pressure / (mu a v0/x1^2)", master="log pressure",
               scene=(SceneKey("peak_pressure_Pa", label="peak film pressure"),)),
    Observable("p_min", "float", "lowest film pressure over the collision (< 0: tension)", _P,
               "lowest film pressure (< 0: tension)", master="lin pressure",
               scene=(SceneKey("min_pressure_Pa", label="min film pressure (< 0: tension)"),)),
    Observable("w0_max_x1", "float", "largest central deformation W(0)", "x1",
               "max central deformation W(0)/x1", master="log length",
               scene=(SceneKey("max_central_deformation_nm", label="max central deformation"),)),
    Observable("x_min_x1", "float", "smallest separation X of the undeformed surfaces (< 0: "
               "overlap)", "x1", "min separation X/x1 (<0: overlap)", master="lin length",
               scene=(SceneKey("min_separation_nm", label="min separation x (< 0: overlap)"),)),
    Observable("dimple", "flag", "a dimple forms (central gap above the minimum by more than "
               "1e-3 x1)", "1", "dimple",
               scene=(SceneKey("dimple", label="dimple"),)),
    Observable("dimple_depth_x1", "float", "largest dimple depth H(0) - min_R H", "x1",
               "  depth /x1", master="lin length", start=0.0,
               scene=(SceneKey("dimple_depth_nm", label="  depth", when="dimple"),)),
    Observable("tau_dimple", "float", "first time the dimple is deeper than 1e-3 x1", "x0/v0"),
    Observable("escaped", "flag", "rebound carries the spheres back beyond x0 (x_e > x0): no "
               "sticking", "1", "escaped (x_e > x0: no sticking)", derived=True,
               scene=(SceneKey("escaped", label="escaped (x_e > x0: no sticking)"),)),
    Observable("energy_error", "float", "max energy-closure error of the coupled phase (void "
               "work included)",
               "m v0^2 / 2", "energy closure error", master="lin energy"),
    Observable("extrapolated", "flag", "the grid-smooth observables are Richardson-extrapolated "
               "from this grid and the one with half the cells (the fine preset: "
               "solver/extrapolation.py); false for a single grid, or where the coarser solve "
               "failed", "1", "extrapolated (two grids)"),
    Observable("cavitated", "flag", "the film cavitated (its pressure reached the floor -Pi)", "1",
               "cavitated",
               scene=(SceneKey("cavitated", label="cavitated", when="cavitation!=off"),)),
    Observable("cavity_radius_max", "float", "largest cavity radius (outermost cavitated node)",
               "sqrt(a x1)", "  largest cavity radius /sqrt(a x1)", start=0.0,
               scene=(SceneKey("cavity_radius_max_m", label="  largest cavity radius",
                               when="cavitated"),)),
    Observable("tau_cavitation_onset", "float", "time the film first cavitates (NaN: never)",
               "x0/v0", "  tau at cavitation onset",
               scene=(SceneKey("cavitation_onset_s", label="  cavitation onset",
                               when="cavitated"),)),
    Observable("void_volume_max", "float", "largest void volume Int_cav (H - H_onset) ds",
               "2 pi a x1^2", "  largest void volume /(2 pi a x1^2)", start=0.0,
               scene=(SceneKey("void_volume_max_m3", label="  largest void volume",
                               when="cavitated"),)),
    Observable("viscosity_ratio_max_approach", "float", "largest viscosity over ambient mu/mu0 "
               "until v first reaches 0 (at the approach's peak film pressure)", "1",
               "peak viscosity ratio on approach mu/mu0",
               scene=(SceneKey("viscosity_ratio_max_approach",
                               label="peak viscosity on approach mu/mu0",
                               when="viscosity_law!=constant"),
                      SceneKey("peak_viscosity_Pa_s", "mu0", "  peak viscosity",
                               when="viscosity_law!=constant"))),
    Observable("h_axis_at_peak_pressure_x1", "float", "central gap H(0) when the film pressure "
               "peaks on approach (the trapped lens of a piezoviscous film)", "x1",
               "  central gap at peak pressure /x1",
               scene=(SceneKey("central_gap_at_peak_pressure_nm",
                               label="  central gap at peak pressure",
                               when="viscosity_law!=constant"),)),
    Observable("solidified", "flag", "the film solidified on approach: its viscosity rose "
               "beyond 1e4 mu0", "1", "  solidified (mu > 1e4 mu0)",
               scene=(SceneKey("solidified", label="  solidified (mu > 1e4 mu0)",
                               when="viscosity_law!=constant"),)),
    Observable("start_strain_energy", "float", "strain energy where the coupled phase starts, "
               "over the kinetic energy", "1", start=0.0),
    Observable("e_far", "float", "far-field restitution: departure over approach speed, both "
               "read at x_ref_over_a on the rigid outer path with the exact Stokes resistance "
               "and the added mass (solver/far_field.py; defaults: sphere and wall, x0 = 0.01 a, "
               "x_ref = 0.1 a, no added mass); 0 when the spheres stop before x_ref", "v/v",
               "far-field restitution e_far",
               scene=(SceneKey("e_far", "1", "far-field restitution e_far", outer=True,
                               null="not computed (no outer flow)"),)),
    Observable("v_outer_start", "float", "approach speed at the outer start (outer_start_over_a) "
               "that arrives at x0 with v0, on the same outer path", "v0",
               "  approach speed at outer start /v0",
               scene=(SceneKey("outer_start_speed_m_per_s",
                               label="  approach speed at the outer start",
                               outer=True, null="none (no outer flow, or a release inside "
                                                "the outer start)"),)),
    Observable("steps", "count", "accepted time steps of the coupled solve (a pair's: both)",
               "1", "steps", diagnostic=True),
    Observable("rejected_steps", "count",
               "rejected time steps of the coupled solve (a pair's: both)", "1", "  rejected",
               diagnostic=True),
    Observable("newton_iterations", "count",
               "Newton iterations of the coupled solve (a pair's: both)", "1", diagnostic=True),
    Observable("lu_factorizations", "count",
               "LU factorisations of the coupled solve (a pair's: both)", "1", diagnostic=True),
    Observable("higher_order_steps", "count",
               "accepted time steps of the coupled solve at a BDF order above 2 (max_order; a "
               "pair's: both)", "1", diagnostic=True),
    Observable("wall_s", "float", "wall time of the scene", "s", "wall time [s]",
               diagnostic=True, start=0.0),
)
OBSERVABLE = {o.name: o for o in OBSERVABLES}

# Status of a scene: name -> (code, message). One table for the solver, the store and the docs.
STATUS = {
    "not_run": (0, "not computed yet (stores only)"),
    "ok": (1, ""),
    "max_steps": (2, "step budget (max_steps) exhausted before the deformation relaxed"),
    "step_underflow": (3, "time step fell below its minimum (nonlinear solve or error control "
                          "failed)"),
    "nonfinite": (4, "non-finite values or a singular Newton matrix in the coupled solve"),
    "error": (5, "the solve raised an exception (sweeps store its text as the message)"),
    # Not a numerical failure: the model's premise fails (collision.START_STRAIN_LIMIT).
    "start_deformed": (6, "eps is not small for this St: the assumed starting deformation "
                          "already stores {ratio:.3g} of the kinetic energy (limit {limit:g})"),
    # Not a result: the solve finished but what it computed breaks the energy balance
    # (collision.ENERGY_CLOSURE_LIMIT); its observables are withheld (NaN) like a failure's.
    "unphysical": (7, "the result breaks the energy balance ({why}): the numerics did not "
                      "resolve this scene; a finer accuracy may"),
}
STATUS_CODES = {name: code for name, (code, _) in STATUS.items()}
# Which model answered a scene
MODEL_CODES = {"unknown": 0, "rigid": 1, "ehd": 2, "master": 3}
# Labels of a result that are not observables (JSON keys; the store keeps them as codes/attrs)
LABELS = ("accuracy", "model", "status", "message")


def failure_message(name: str, **fields) -> str:
    return STATUS[name][1].format(**fields)


@dataclass(frozen=True)
class Column:
    """One column of a collision's time series. A rigid phase's rows hold the rigid film's values
    of the classic columns and 0 in every other (solver/rigid_phases.py: ``rigid_block``)."""

    name: str
    long_name: str
    units: str
    kept: bool = True  # part of a result's series (False: the coupled phase's, for observables)


SERIES = (
    Column("T", "time v0 t / x1", "x1/v0"),
    Column("X", "separation of undeformed surfaces", "x1"),
    Column("V", "approach velocity", "v0"),
    Column("F", "force on the spheres (film and asperity contact)", "6 pi mu a^2 v0 / x1"),
    Column("W0", "central deformation W(0)", "x1"),
    Column("H_min", "minimum gap", "x1"),
    Column("R_H_min", "radius of the minimum gap", "sqrt(a x1)"),
    Column("E_k", "kinetic energy", "m v0^2/2"),
    Column("E_s", "strain energy", "m v0^2/2"),
    Column("dissipated", "viscous dissipation so far", "m v0^2/2"),
    Column("H0", "central gap H(0)", "x1", kept=False),
    Column("W_absmax", "largest |W| over the radius", "x1", kept=False),
    Column("order", "BDF order of the step that ended at this row (0: the first row)", "1",
           kept=False),
    Column("H_min_step", "minimum gap over the cells and the step that ended at this row, on "
           "the step's interpolating polynomial above order 2 (H_min at orders 0-2)", "x1",
           kept=False),
    Column("P_max_step", "largest film pressure over the cells and the step that ended at this "
           "row, on the step's interpolating polynomial above order 2 (P_max at orders 0-2)", _P,
           kept=False),
    Column("H0_at_P_max_step", "central gap when P_max_step is reached (H0 at orders 0-2)", "x1",
           kept=False),
    Column("T_at_v0", "time where V falls through 0 inside the step that ended at this row, on "
           "the step's interpolating polynomial above order 2 (else NaN)", "x1/v0", kept=False),
    Column("H_min_at_v0", "minimum gap there (else H_min)", "x1", kept=False),
    Column("P_max_at_v0", "largest film pressure there (else P_max)", _P, kept=False),
    Column("H0_at_v0", "central gap there (else H0)", "x1", kept=False),
    Column("P_max", "largest film pressure over the radius", _P),
    Column("P_min", "lowest film pressure over the radius", _P),
    Column("cavity_radius", "radius of the outermost cavitated node (0: no cavity)", "sqrt(a x1)"),
    Column("void_volume", "void volume Int_cav (H - H_onset) ds", "2 pi a x1^2"),
    Column("void_work", "work done against the cavitation floor so far", "m v0^2/2"),
    Column("E_c", "energy stored in the compressed liquid", "m v0^2/2"),
    Column("F_contact", "asperity contact force (part of F)", "6 pi mu a^2 v0 / x1"),
    Column("E_a", "energy stored in the asperities", "m v0^2/2"),
    Column("solid_loss", "energy lost in the solids so far (e_dry)", "m v0^2/2"),
)
SERIES_INDEX = {c.name: k for k, c in enumerate(SERIES)}
