"""Two grids, one answer (solver/extrapolation.py, ``Numerics.extrapolate``; the fine preset).

The pair's values against a converged reference (three single grids, Richardson-extrapolated with
their observed order), the contract of ``collide(..., extrapolate=True)`` (its values are its two
solves combined, its counts both solves', its profiles the finer solve's), and the rules where a
pair is not combined."""

import dataclasses
import json
import math

import pytest

from solver import Physics, collide
from solver.extrapolation import COUNTS, EXTRAPOLATED, combine, extrapolated
from solver.settings import PRESETS, resolve

SCENE = Physics(St=10.0, eps=1e-2)  # coupled from the start: no hand-over threshold involved


def _single(n_inner, **extra):
    """The fine preset's settings on one grid of ``n_inner`` inner cells (a member of the family
    ``Numerics.halved`` steps through: stretch - 1 and max_rel in proportion to 1/n_inner), at a
    time tolerance whose error is far below the grid's."""
    base = resolve("fine", extrapolate=False, rtol=1e-9)
    scale = base.n_inner / n_inner
    return collide(SCENE, accuracy="fine", save_profiles=False, extrapolate=False, rtol=1e-9,
                   n_inner=n_inner, stretch=1.0 + (base.stretch - 1.0) * scale,
                   max_rel=min(1.0, base.max_rel * scale), **extra)


def test_a_pair_is_closer_to_the_converged_value_than_a_grid_with_twice_its_cells():
    """Against the limit of three single grids (64, 128, 256 inner cells, Richardson with their
    observed order, 1.9-2.0 here), the pair (64 + 32 cells) is off by at most a quarter of the
    single 64-cell grid's error: the leading grid error removed, it must beat what one more
    halving of the cells gives a second-order grid (a quarter); measured 0.05-0.16."""
    runs = {n: _single(n) for n in (32, 64, 128, 256)}
    assert all(c.status == "ok" for c in runs.values())
    for key in ("v_r", "h_m_x1", "h_m_approach_x1", "ln_x_e_x1", "e_wet", "peak_force",
                "w0_max_x1"):
        f = {n: getattr(c, key) for n, c in runs.items()}
        d1, d2 = f[128] - f[64], f[256] - f[128]
        order = math.log2(abs(d1 / d2))
        limit = f[256] + d2 / (2.0 ** order - 1.0)
        pair = extrapolated(f[64], f[32])
        assert abs(pair - limit) <= 0.25 * abs(f[64] - limit), key


def test_extrapolate_combines_the_grid_and_its_half_and_counts_both():
    numerics = resolve("standard", extrapolate=True)
    half = numerics.halved()
    assert (half.n_inner, half.stretch, half.max_rel) == (32, pytest.approx(1.4), 0.6)
    assert (half.rtol, half.switch, half.release, half.axis_ratio) == (
        numerics.rtol, numerics.switch, numerics.release, numerics.axis_ratio)
    pair = collide(SCENE, extrapolate=True)
    fine = collide(SCENE, extrapolate=False)
    coarse = collide(SCENE, **{f.name: getattr(half, f.name) for f in dataclasses.fields(half)})
    assert pair.extrapolated and not fine.extrapolated
    for key in EXTRAPOLATED:
        # the same solves, the same bits: the pair is exactly its two solves combined
        assert getattr(pair, key) == pytest.approx(
            extrapolated(getattr(fine, key), getattr(coarse, key)), rel=1e-13, abs=1e-15), key
    for key in COUNTS:
        assert getattr(pair, key) == getattr(fine, key) + getattr(coarse, key)
    assert pair.p_min == fine.p_min  # not extrapolated: the finer solve's
    assert pair.radius.size == fine.radius.size  # the profiles are the finer grid's
    assert pair.x_e_x1 == pytest.approx(math.exp(pair.ln_x_e_x1))  # derived from the extrapolated


def test_a_pair_whose_coarse_solve_failed_or_does_not_rebound_keeps_the_finer_values():
    fine = collide(SCENE, extrapolate=False)
    coarse = collide(SCENE, **dataclasses.asdict(resolve("standard").halved()))
    failed = dataclasses.replace(coarse, status="max_steps")
    kept = dataclasses.replace(fine)
    assert not combine(kept, failed)
    assert not kept.extrapolated
    assert all(getattr(kept, k) == getattr(fine, k) for k in EXTRAPOLATED)
    assert kept.steps == fine.steps + coarse.steps  # its work is counted all the same
    # one grid sticks: the rebound and the departure keep the finer solve's values together
    # (a threshold between the grids is not smooth); the closest approach is extrapolated
    stuck = dataclasses.replace(coarse, v_r=0.0, tau_max_rebound=math.nan, e_wet=0.0, e_x0=0.0,
                                ln_x_e_x1=math.log(coarse.x0_over_x1) - 1.0)
    mixed = dataclasses.replace(fine)
    assert combine(mixed, stuck) and mixed.extrapolated
    for key in ("v_r", "tau_max_rebound", "e_wet", "e_x0", "ln_x_e_x1"):
        assert getattr(mixed, key) == getattr(fine, key), key
    assert mixed.h_m_x1 == pytest.approx(extrapolated(fine.h_m_x1, coarse.h_m_x1))


def test_a_pair_whose_coarse_solve_raises_or_fails_keeps_the_finer_solve_and_says_why(
        monkeypatch):
    """A defect that raises in the half grid's solve must not take the finer solve with it (the
    whole collision raised before): the result is the finer solve's, ok, not extrapolated, its
    message naming the exception; a half grid that fails is named the same way."""
    from solver import collision

    fine = collide(SCENE, extrapolate=False, save_profiles=False)
    original = collision._coupled

    def coarse_raises(physics, accuracy, numerics, head, x_ref_x0, attempt_log=False):
        if numerics.n_inner < fine.numerics.n_inner:
            raise FloatingPointError("a defect in the half grid")
        return original(physics, accuracy, numerics, head, x_ref_x0, attempt_log)

    monkeypatch.setattr(collision, "_coupled", coarse_raises)
    kept = collide(SCENE, extrapolate=True, save_profiles=False)
    assert kept.status == "ok" and not kept.extrapolated
    assert all(getattr(kept, k) == getattr(fine, k) for k in EXTRAPOLATED)
    assert kept.message == ("not extrapolated: the half grid's solve raised FloatingPointError: "
                            "a defect in the half grid")

    def coarse_fails(physics, accuracy, numerics, head, x_ref_x0, attempt_log=False):
        result = original(physics, accuracy, numerics, head, x_ref_x0, attempt_log)
        if numerics.n_inner < fine.numerics.n_inner:
            result.status, result.message = "max_steps", "no time left"
        return result

    monkeypatch.setattr(collision, "_coupled", coarse_fails)
    kept = collide(SCENE, extrapolate=True, save_profiles=False)
    assert kept.status == "ok" and not kept.extrapolated
    assert all(getattr(kept, k) == getattr(fine, k) for k in EXTRAPOLATED)
    assert kept.message == "not extrapolated: the half grid's solve failed (max_steps)"


@pytest.mark.parametrize("stokes, eps", [
    (12.149579626020863, 1e-4),  # the finer grid sticks (x_e < x0), the pair's x_e is beyond x0
    (12.150794705491412, 1e-4),  # the finer grid rebounds by 2.5e-10, the coarser not
    (2.0, 1e-2),  # p_max extrapolated alone fell below the approach's peak
])
def test_a_pair_near_a_threshold_keeps_the_invariants_of_one_solve(stokes, eps):
    """Where the two grids straddle the stick-or-rebound threshold the pair reports as one solve
    would: it escapes beyond x0 exactly when it departs with e > 0 (x_ref = x0); the closest
    approach is at most the approach's and at most x_e; p_max is at least the approach's peak.
    (Found by a review: the pair's ln x_e said escaped while its e_wet was 0.)"""
    c = collide(Physics(St=stokes, eps=eps), accuracy="fine", save_profiles=False)
    assert c.status == "ok" and c.extrapolated
    assert c.escaped == (c.e_wet > 0.0) == (c.e_x0 > 0.0)
    assert c.h_m_x1 <= min(c.h_m_approach_x1, c.x_e_x1)
    assert c.x_min_x1 <= c.x_e_x1 and c.p_max >= c.p_max_approach


def test_a_pressure_dependent_pairs_viscosity_is_its_extrapolated_pressures():
    """The peak viscosity and ``solidified`` follow the extrapolated approach pressure as in one
    solve (collision._approach_viscosity), at the threshold of 1e4 (beta 2.875: 9988 with
    ``solidified`` true when the viscosity was extrapolated on its own) and in a glassy lens
    (beta 10, St 1.74: about 1e207)."""
    from solver.model import liquid

    for physics in (Physics(St=30.0, eps=1e-4, beta=2.875115488655865),
                    Physics(St=1.74, eps=1e-2, beta=10.0)):
        c = collide(physics, accuracy="fine", save_profiles=False)
        assert c.status == "ok" and c.extrapolated
        assert c.p_max == c.p_max_approach  # a pressure-dependent film's p_max is the approach's
        ratio = liquid.viscosity_ratio(c.p_max_approach, physics.as_array())
        assert c.viscosity_ratio_max_approach == ratio
        assert c.solidified == (ratio >= 1e4)


def test_extrapolate_needs_an_even_grid_whose_half_is_within_bounds():
    assert PRESETS["fine"].extrapolate and not PRESETS["standard"].extrapolate
    for bad in (dict(n_inner=81), dict(n_inner=8), dict(stretch=1.6), dict(max_rel=0.6)):
        with pytest.raises(ValueError, match="n_inner must be even and at least 10"):
            resolve("fine", **bad)
    for not_a_bool in ("false", 0, "no"):  # a sweep file's "false" must not run pairs
        with pytest.raises(ValueError, match="extrapolate must be true or false"):
            resolve("standard", extrapolate=not_a_bool)


def test_ehd_run_pairs_as_its_preset_says_or_as_the_flag_asks(capsys):
    """``--extrapolate`` / ``--no-extrapolate`` override the preset (the JSON's ``extrapolated``
    says which ran), and the pair's values are the solver's."""
    from pipeline.cli import main

    def run(*flags):
        assert main(["run", "--St", "10", "--eps", "1e-2", "--json", *flags]) == 0
        return json.loads(capsys.readouterr().out)

    assert not run()["extrapolated"]  # standard: one grid
    paired = run("--extrapolate")
    assert paired["extrapolated"]
    assert paired["v_r"] == collide(SCENE, extrapolate=True).v_r
    assert not run("--accuracy", "fine", "--no-extrapolate")["extrapolated"]


def test_the_pair_compares_x_e_with_the_x_ref_asked_for(monkeypatch):
    """Whether the departure's regimes agree depends on ``x_ref`` (``e_wet > 0`` where the
    spheres pass back out through it): both solves reach ``combine`` with the ``x_ref_x0`` of
    the call (each coupled solve carried the default 1 until ``collide`` set it after the pair
    was combined)."""
    from solver import extrapolation

    seen = []
    original = extrapolation.combine

    def spy(result, coarse):
        seen.append((result.x_ref_x0, coarse.x_ref_x0))
        return original(result, coarse)

    monkeypatch.setattr(extrapolation, "combine", spy)
    c = collide(SCENE, extrapolate=True, x_ref_x0=2.0, save_profiles=False)
    assert c.extrapolated and seen == [(2.0, 2.0)]
