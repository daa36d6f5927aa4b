"""The result of one collision: ``Collision``, its JSON form and its self-describing Dataset.

Every list of results here is generated from the registry in solver/observables.py. Scales
(docs/model.md, "Scales"): lengths in ``x1`` (suffix ``_x1``) or ``x0`` (``_x0``), times as
``tau = v0 t / x0``, force in ``6 pi mu a^2 v0 / x1``, pressure in ``mu a v0 / x1^2``, energies
relative to the initial kinetic energy.
"""

from __future__ import annotations

import json
import math
from dataclasses import field, make_dataclass

import numpy as np

from .far_field import DEFAULT as _OUTER
from .far_field import OuterFlow
from .observables import LABELS, OBSERVABLES, SERIES
from .physics import Physics
from .settings import Numerics

__all__ = ["Collision", "JSON_KEYS", "SOLVER_VERSION"]

# Bump with any change that can alter numbers: stamped into every result and store.
SOLVER_VERSION = "1.19.1"

# the outer-flow reading of e_far and v_outer_start (solver/far_field.py, OuterFlow)
OUTER_KEYS = ("outer_geometry", "x0_over_a", "x_ref_over_a", "outer_start_over_a",
              "density_ratio")
JSON_KEYS = (*Physics.names(), *LABELS, *(o.name for o in OBSERVABLES), "x_ref_x0",
             *OUTER_KEYS, "solver_version")

SCALING = ("lengths along the axis / x1 (x1 = (4 theta mu a^1.5 v0)^0.4), radius / sqrt(a x1), "
           "tau = v0 t / x0, pressure / (mu a v0 / x1^2), velocity / v0, force / "
           "(6 pi mu a^2 v0 / x1), energies / (m v0^2 / 2)")


def _exp(v):
    if not math.isfinite(v):
        return v
    return math.exp(v) if v < 709.0 else math.inf


class _CollisionMethods:
    """What every ``Collision`` does beyond holding its results (the fields: ``_fields``)."""

    # ---- the physics ----------------------------------------------------------------------------
    @property
    def St(self) -> float:
        return self.physics.St

    @property
    def eps(self) -> float:
        return self.physics.eps

    def __getattr__(self, name):
        """Every physics field (``Pi``, ``cavitation``, ``beta``, ``viscosity_law``...) as read
        from ``physics``, after its defaults are resolved ("auto" becomes the model used)."""
        if name != "physics" and name in Physics.names():
            return getattr(self.physics, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def x0_over_x1(self) -> float:
        return self.physics.x_start

    @property
    def St_ref(self) -> float:
        """The impact Stokes number at x_ref, ``St + ln(x_ref/x0)`` (rigid.impact_stokes)."""
        return self.physics.St + math.log(self.x_ref_x0)

    # ---- the outer-flow reading (solver/far_field.py) --------------------------------------------
    @property
    def outer_geometry(self) -> str:
        return self.outer.geometry

    @property
    def x0_over_a(self) -> float:
        return self.outer.x0_over_a

    @property
    def x_ref_over_a(self) -> float:
        return self.outer.x_ref_over_a

    @property
    def outer_start_over_a(self) -> float:
        return self.outer.start_over_a

    @property
    def density_ratio(self) -> float:
        return self.outer.density_ratio

    # ---- derived quantities ---------------------------------------------------------------------
    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def h_m_x0(self) -> float:
        return self.h_m_x1 / self.x0_over_x1

    @property
    def h_m_approach_x0(self) -> float:
        return self.h_m_approach_x1 / self.x0_over_x1

    @property
    def ln_x_e_x0(self) -> float:
        return self.ln_x_e_x1 - math.log(self.x0_over_x1)

    @property
    def x_e_x1(self) -> float:
        return _exp(self.ln_x_e_x1)

    @property
    def x_e_x0(self) -> float:
        return _exp(self.ln_x_e_x0)

    @property
    def escaped(self) -> bool | None:
        """The rebound carries the spheres back beyond x0: the model's verdict "no sticking"
        (None when the scene failed and x_e is unknown)."""
        ln_x_e = self.ln_x_e_x0
        return None if math.isnan(ln_x_e) else bool(ln_x_e > 0.0)

    @property
    def gap(self) -> np.ndarray | None:
        """Film thickness ``H = X + R^2/2 + W`` at the profile times, (rows, N)."""
        if self.deformation is None:
            return None
        return self.profile_x[:, None] + 0.5 * self.radius[None, :] ** 2 + self.deformation

    def to_dict(self) -> dict:
        """The scalar results (``JSON_KEYS``), non-finite numbers as None."""
        out = {}
        for key in JSON_KEYS:
            value = SOLVER_VERSION if key == "solver_version" else getattr(self, key)
            if isinstance(value, (bool, np.bool_)):
                value = bool(value)
            elif isinstance(value, (int, np.integer)):
                value = int(value)
            elif isinstance(value, (float, np.floating)):
                value = float(value) if math.isfinite(value) else None
            out[key] = value
        return out

    def to_json(self) -> str:
        return json.dumps(self.to_dict())

    def to_xarray(self):
        """Self-describing Dataset: scalars as attrs, time series along ``tau``, profiles
        along ``(profile_tau, R)``."""
        import xarray as xr

        attrs = {k: (int(v) if isinstance(v, bool) else v) for k, v in self.to_dict().items()
                 if v is not None}
        attrs.update({f"numerics_{k}": (int(v) if isinstance(v, bool) else v)
                      for k, v in self.numerics.as_dict().items()})
        attrs["scaling"] = SCALING
        ds = xr.Dataset(attrs=attrs)
        tau = self.series["tau"]
        ds = ds.assign_coords(tau=("tau", tau, {"long_name": "time v0 t / x0"}))
        columns = [(c.name, c.long_name, c.units) for c in SERIES if c.name in self.series]
        columns.append(("phase", "0 rigid approach, 1 coupled, 2 rigid departure", "1"))
        for name, long_name, units in columns:
            ds[name] = ("tau", self.series[name], {"long_name": long_name, "units": units})
        if self.pressure is not None and self.pressure.size:
            ds = ds.assign_coords(
                R=("R", self.radius, {"long_name": "radius", "units": "sqrt(a x1)"}),
                profile_tau=("profile_tau", self.profile_tau, {"long_name": "time v0 t / x0"}))
            ds["P"] = (("profile_tau", "R"), self.pressure,
                       {"long_name": "film pressure", "units": "mu a v0 / x1^2"})
            ds["W"] = (("profile_tau", "R"), self.deformation,
                       {"long_name": "total surface deformation", "units": "x1"})
            ds["H"] = (("profile_tau", "R"), self.gap, {"long_name": "film thickness", "units": "x1"})
            if self.fluid_fraction is not None:
                theta = np.ones_like(self.pressure)  # the boundary node is full
                theta[:, :-1] = self.fluid_fraction
                ds["theta"] = (("profile_tau", "R"), theta,
                               {"long_name": "fluid fraction of the gap (JFO cavity < 1)",
                                "units": "1"})
        return ds


def _fields():
    """The fields of ``Collision``: what the scene was, then every observable of the registry
    that is not derived (solver/observables.py: its ``initial`` value until the solve sets it),
    then the phases' times and the arrays."""
    kinds = {"float": float, "flag": bool, "count": int}
    arrays = dict(default=None, repr=False)
    return [
        ("physics", Physics), ("accuracy", str), ("numerics", Numerics),
        ("model", str),  # "rigid" (no coupled solve needed), "ehd", or "master" (the fast path)
        ("status", str),  # "ok" or a failure code (observables.STATUS)
        ("message", str),
        *((o.name, kinds[o.kind], field(default=o.initial)) for o in OBSERVABLES if not o.derived),
        ("p_max_approach", float, field(default=math.nan)),  # largest pressure until v = 0
        ("tau_handover", float, field(default=math.nan)),  # rigid -> coupled
        ("tau_release", float, field(default=math.nan)),  # coupled -> rigid
        ("x_ref_x0", float, field(default=1.0)),  # where e_wet is seen, over x0 (>= 1)
        ("e_x0", float, field(default=math.nan)),  # departure speed at x0 / v0 (e_wet at x0)
        ("outer", OuterFlow, field(default=_OUTER)),  # how e_far reads the result
        ("series", dict, field(default_factory=dict, repr=False)),  # SERIES, tau, phase
        ("radius", np.ndarray, field(**arrays)),  # (N,) grid radii R
        ("profile_tau", np.ndarray, field(**arrays)),  # (rows,)
        ("pressure", np.ndarray, field(**arrays)),  # (rows, N) P
        ("deformation", np.ndarray, field(**arrays)),  # (rows, N) W
        ("fluid_fraction", np.ndarray, field(**arrays)),  # (rows, N-1) theta of the cells, JFO
        ("profile_x", np.ndarray, field(**arrays)),  # (rows,) X at profile times
        # the coupled phase's step attempts, one entry per attempt, when collide(...,
        # attempt_log=True) asked (docs/solver.md, "The attempt log"); empty otherwise
        ("attempts", dict, field(default_factory=dict, repr=False)),
    ]


Collision = make_dataclass(
    "Collision", _fields(), bases=(_CollisionMethods,),
    namespace={"__module__": __name__, "__qualname__": "Collision", "__doc__": """Result of one
    collision. Failures are data: ``status != "ok"`` with a ``message`` and NaN observables
    (never a guess). Its observables, with their units and meaning, are the registry's
    (solver/observables.py: ``OBSERVABLES``); the derived ones are properties."""})
