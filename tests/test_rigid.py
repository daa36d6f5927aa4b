"""Analytic rigid-sphere motion (the cheap model and the hand-over) against direct integration."""

import math

import numpy as np
import pytest
from scipy import integrate

from solver.model import rigid


@pytest.mark.parametrize("stokes, x_from, v_from", [(2.0, 10.0, 1.0), (30.0, 3.0, 1.0),
                                                     (5.0, 0.5, -0.4), (300.0, 2.0, -0.8)])
def test_velocity_and_time_match_ode(stokes, x_from, v_from):
    # dX/dT = -V, dV/dT = -V/(St X) (force 3V/X, docs/model.md "Rigid solution") integrated to 1e-12
    def rhs(t, y):
        return [-y[1], -y[1] / (stokes * y[0])]

    t_end = 0.5 * abs(rigid.elapsed_time(x_from * math.exp(-0.5 * stokes * v_from), x_from,
                                         v_from, stokes))
    sol = integrate.solve_ivp(rhs, (0.0, t_end), [x_from, v_from], rtol=1e-12, atol=1e-14,
                              dense_output=True)
    t = np.linspace(0.0, t_end, 7)[1:]
    x, v = sol.sol(t)
    assert rigid.velocity(x, x_from, v_from, stokes) == pytest.approx(v, rel=1e-9, abs=1e-11)
    assert rigid.elapsed_time(x, x_from, v_from, stokes) == pytest.approx(t, rel=1e-8)


def test_rest_separation_is_where_velocity_vanishes():
    ln_xe = rigid.rest_separation(4.0, -0.3, 10.0)
    assert rigid.velocity(math.exp(ln_xe), 4.0, -0.3, 10.0) == pytest.approx(0.0, abs=1e-14)
    assert ln_xe == pytest.approx(math.log(4.0) + 3.0)


def test_handover_on_the_rigid_path():
    x0, stokes, threshold = 1e-6**-0.4, 10.0, 0.01
    x = rigid.handover_separation(x0, stokes, threshold)
    v = rigid.velocity(x, x0, 1.0, stokes)
    assert rigid.deformation_ratio(x, v) == pytest.approx(threshold, rel=1e-10)
    # first crossing: before the rigid path's deformation peak at x0 exp(0.4 - St)
    assert x > x0 * math.exp(0.4 - stokes)


@pytest.mark.parametrize("stokes", [0.5, 2.0, 10.0, 300.0, 3000.0])
def test_handover_is_the_first_root_to_the_last_bits(stokes):
    """The hand-over's own root finder (Newton from the start, rigid._rigid_onset) lands on the
    criterion: ``W(0)/X`` equals the threshold to 1e-12 relative (the ratio evaluated through
    ``exp(2.5 u)``, ``u`` up to 25 here: rounding of about 1e-14), from far below the peak to
    just under it, where the slope vanishes and Newton converges only linearly (thresholds up
    to 1: at large St the peak itself overflows)."""
    x0 = 1e-6**-0.4
    u_peak = stokes - 0.4
    if u_peak <= 0.0:  # the ratio only falls from the start
        assert rigid.handover_separation(x0, stokes, 1e-5) is None
        return
    log_peak = math.log(rigid.HANDOVER_COEFF * 0.4 / stokes) - 2.5 * math.log(x0) + 2.5 * u_peak
    for below in (20.0, 1.0, 1e-3, 1e-9):
        threshold = math.exp(min(log_peak - below, 0.0))  # at large St the peak overflows
        x = rigid.handover_separation(x0, stokes, threshold)
        if x == x0:  # reached at the start
            assert rigid.deformation_ratio(x0, 1.0) >= threshold
            continue
        v = rigid.velocity(x, x0, 1.0, stokes)
        assert rigid.deformation_ratio(x, v) == pytest.approx(threshold, rel=1e-12)
        assert x >= x0 * math.exp(-u_peak)  # the first crossing, before the peak


def test_handover_peak_and_never():
    x0 = 1e-6**-0.4
    # docs/model.md "Small deformation": W/X peaks at 3 pi^2 eps exp(2.5 St - 1)/(10 sqrt 2 St) for St > 0.4
    stokes = 5.0
    peak = 3 * math.pi**2 * 1e-6 * math.exp(2.5 * stokes - 1) / (10 * math.sqrt(2) * stokes)
    assert rigid.handover_separation(x0, stokes, 0.999 * peak) is not None
    assert rigid.handover_separation(x0, stokes, 1.001 * peak) is None
    # St <= 0.4: the ratio only falls from its start value 3 I0 eps = 5.2e-6
    assert rigid.handover_separation(x0, 0.3, 1e-5) is None
    assert rigid.handover_separation(1.0, 0.3, 1.0) == 1.0  # already past the threshold


@pytest.mark.parametrize("eps, stokes", [(1e-6, 5.0), (1e-2, 0.3), (1e-3, 0.41), (1e-4, 40.0),
                                         (1e-2, 1.0)])
def test_log_peak_deformation_ratio_is_the_maximum_along_the_rigid_path(eps, stokes):
    x0 = eps**-0.4
    # dense sampling of the whole rigid path, u = ln(X0/X) from 0 to rest at u = St
    u = np.linspace(0.0, stokes, 400001)[:-1]
    x = x0 * np.exp(-u)
    ratio = rigid.deformation_ratio(x, rigid.velocity(x, x0, 1.0, stokes))
    # sampled maximum: within (du)^2 times the curvature of a smooth peak, ~1e-9 relative here
    assert rigid.log_peak_deformation_ratio(x0, stokes) == pytest.approx(
        math.log(ratio.max()), abs=1e-8)
    assert rigid.log_peak_deformation_ratio(x0, stokes) >= math.log(ratio.max()) - 1e-12


def test_start_deformation_ratio_and_its_inverse():
    eps = 3e-3
    x0 = eps**-0.4
    assert rigid.start_deformation_ratio(eps) == pytest.approx(
        rigid.deformation_ratio(x0, 1.0), rel=1e-12)
    assert rigid.eps_for_start_deformation(rigid.start_deformation_ratio(eps)) == pytest.approx(
        eps, rel=1e-14)
