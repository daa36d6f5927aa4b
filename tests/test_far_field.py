"""The far-field restitution e_far (solver/far_field.py) and the outer phase's added mass
(solver/model/outer_flow.py) against closed forms, limits, an independent integration of the
equation of motion, and bad input (docs/model.md, "Outer flow: the far-field restitution")."""

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from scipy import integrate

from solver import collide
from solver import far_field as ff
from solver.model import outer_flow as of


def _images(gap):
    # the chain of image dipoles built one by one (independent of the sinh closed form): the
    # image of an axial dipole at distance f from the centre of a sphere of radius 1 is (1/f)^3
    # times as strong at distance 1/f; the mirror sphere's chain is the mirror image
    h, offset, strength, total = 1.0 + gap, 0.0, 1.0, 0.0
    while strength > 1e-18:
        f = 2.0 * h - offset
        strength *= f ** -3
        offset = 1.0 / f
        total += strength
    return 0.5 + 1.5 * total


@pytest.mark.parametrize("gap", [1e-3, 0.05, 0.5, 2.0, 10.0])
def test_added_mass_series_is_the_image_chain(gap):
    # 1e-13: round-off of a sum of ~1/alpha terms of size <= 1
    assert of.wall_added_mass(gap) == pytest.approx(_images(gap), rel=1e-13)


def test_added_mass_limits():
    # contact: 1/2 + (3/2)(zeta(3) - 1) = 0.80309; at gap 1e-8 (alpha = 1.4e-4) the terms
    # differ from 1/n^3 by O(n^2 alpha^2) relative, which summed up to n ~ 1/alpha is
    # O(alpha) = 1.4e-4 of C: 1e-3 bounds it with margin
    assert of.wall_added_mass(1e-8) == pytest.approx(0.5 + 1.5 * (of.ZETA3 - 1.0), rel=1e-3)
    assert 0.5 + 1.5 * (of.ZETA3 - 1.0) == pytest.approx(0.80309, abs=1e-5)
    # far away: 1/2 + (3/16)(a/h)^3 (the first image); the next image is (a/h)^6 / 2^6 smaller
    # again, so the remainder is below (3/2)(a/(2h))^6 (1 + ...) < 1e-7 at h = 11 a
    for gap in (10.0, 30.0, 100.0):
        h = 1.0 + gap
        assert abs(of.wall_added_mass(gap) - (0.5 + 3.0 / 16.0 / h**3)) < 2.0 * 1.5 / (2 * h) ** 6
    # it decreases monotonically from contact to 1/2
    gaps = np.geomspace(1e-6, 1e3, 40)
    c = [of.wall_added_mass(g) for g in gaps]
    assert all(a > b for a, b in zip(c, c[1:])) and c[-1] > 0.5


def test_equal_spheres_added_mass_is_the_wall_at_the_midplane():
    # symmetry: two equal spheres (radius 2a) approaching each other see the midplane as a wall
    # at gap x/2, i.e. x/(4a) in their own radius (cosh alpha = 1 + x/(4a), alpha_equal)
    for gap in (1e-3, 0.4, 8.0):
        assert of.equal_spheres_added_mass(gap) == of.wall_added_mass(gap / 4.0)
        assert math.cosh(of.alpha_equal(gap)) == pytest.approx(1.0 + gap / 4.0, rel=1e-14)


def _quad(geometry, g0, g1, phi=0.0):
    # independent quadrature of Int R (1 + phi C)^(-1/2) dy (scipy's adaptive quad in ln y)
    def f(u):
        y = math.exp(u)
        w = 1.0 if phi == 0.0 else (1.0 + phi * of.added_mass(geometry, y)) ** -0.5
        return y * of.resistance(geometry, y) * w
    value, err = integrate.quad(f, math.log(g0), math.log(g1), epsabs=1e-12, epsrel=1e-12,
                                limit=200)
    return value


@pytest.mark.parametrize("geometry", of.GEOMETRIES)
@pytest.mark.parametrize("phi", [0.0, 0.125, 3.0])
def test_resistance_integral_against_adaptive_quadrature(geometry, phi):
    # the Gauss-Legendre panels against scipy's adaptive rule: 1e-9 relative (both converge
    # to ~1e-12; the series themselves to 1e-12 absolute per point)
    for g0, g1 in ((0.01, 0.1), (0.01, 1.0), (1e-4, 3.0)):
        got = ff.resistance_integral(geometry, g0, g1, phi)
        assert got == pytest.approx(_quad(geometry, g0, g1, phi), rel=1e-9)
        # panels twice as fine change nothing (converged)
        assert got == pytest.approx(ff.resistance_integral(geometry, g0, g1, phi, panel=0.25),
                                    rel=1e-12)


def test_resistance_integral_limits():
    # small gaps: R - a/x = (1/5) ln(a/x) + 0.97128 + O((x/a) ln(a/x)) (Cox & Brenner 1967), so
    # Int_{x_a}^{x_b} (R - a/x) = [y ((1/5)(ln(1/y) + 1) + 0.97128)]; the O(y ln y) remainder
    # integrates to O(x_b^2 ln(1/x_b)) = 1e-7 at x_b = 1e-4 a
    lo, hi = 1e-5, 1e-4

    def primitive(y):
        return y * (0.2 * (math.log(1.0 / y) + 1.0) + 0.97128)

    outer_part = ff.resistance_integral("wall", lo, hi, 0.0, False)
    assert outer_part == pytest.approx(primitive(hi) - primitive(lo), abs=2e-7)
    assert ff.resistance_integral("wall", lo, hi) == pytest.approx(
        math.log(hi / lo) + outer_part, rel=1e-14)
    # far away: R = 1 + (9/8)/h + (81/64)/h^2 + O(1/h^3) (h = 1 + x/a; the first reflections),
    # integrated from h = 51 to 101; the O(0.92/h^3) term integrates to < 1.4e-4
    far = ff.resistance_integral("wall", 50.0, 100.0)
    expected = 50.0 + 9.0 / 8.0 * math.log(101.0 / 51.0) + 81.0 / 64.0 * (1 / 51.0 - 1 / 101.0)
    assert far == pytest.approx(expected, abs=1.4e-4)


def test_handover_defect():
    # what the film's a/x leaves out inside x0 = 0.01 a: Int_0^x0 (R - a/y) dy, against the
    # small-gap closed form y ((1/5)(ln(a/y) + 1) + 0.971) at y = x0 (its O(x0^2 ln) remainder:
    # 1e-3 of the value at most)
    d = ff.handover_defect("wall", 0.01)
    assert d == pytest.approx(0.01 * (0.2 * (math.log(100.0) + 1.0) + 0.97128), rel=2e-2)
    assert 0.0 < d < 0.025
    assert ff.handover_defect("spheres", 0.01) > d  # its logarithm is 9/20 instead of 1/5


def test_rigid_limit_with_the_film_resistance_is_e_wet_at_x_ref():
    # with R = a/x and no added mass J = ln(x_ref/x0), and e_far is exactly the solver's e_wet
    # seen at x_ref (rigid.restitution: ln(x_e/x_ref)/St_ref): the same departure law; 1e-6:
    # e_wet at x_ref > x0 takes the departure from the last coupled row inside x_ref (an
    # O(release) difference, docs/model.md, "Observables")
    for stokes, ratio in ((50.0, 10.0), (200.0, 30.0)):
        c = collide(stokes, 1e-4, accuracy="fast")
        c_ref = collide(stokes, 1e-4, accuracy="fast", x_ref_x0=ratio)
        assert c.e_x0 == c.e_wet and c_ref.e_x0 == pytest.approx(c.e_x0, abs=1e-12)
        assert ff.far_restitution(c.e_x0, stokes, math.log(ratio)) == pytest.approx(
            c_ref.e_wet, abs=1e-6)
        # and its closed form, (St e0 - L)/(St + L), L = ln(x_ref/x0)
        lg = math.log(ratio)
        assert ff.far_restitution(c.e_x0, stokes, lg) == pytest.approx(
            (stokes * c.e_x0 - lg) / (stokes + lg), rel=1e-14)


def test_e_far_of_a_collision():
    # collide reads e_far with the default outer flow (wall, x0 = 0.01 a, x_ref = 0.1 a, no
    # added mass): the exact resistance brakes more than a/x, so e_far < e_wet at x_ref
    c = collide(50.0, 1e-4, accuracy="fast")
    j = _quad("wall", 0.01, 0.1)
    assert c.e_far == pytest.approx(ff.far_restitution(c.e_x0, 50.0, j), rel=1e-9)
    lg = math.log(10.0)
    assert c.e_far < ff.far_restitution(c.e_x0, 50.0, lg) < c.e_x0
    d = c.to_dict()
    assert d["e_far"] == c.e_far and d["outer_geometry"] == "wall"
    assert d["x_ref_over_a"] == 0.1 and d["x0_over_a"] == 0.01 and d["density_ratio"] == 0.0
    # the approach speed at the outer start that arrives at x0 with v0
    assert c.v_outer_start == pytest.approx(1.0 + _quad("wall", 0.01, 1.0) / 50.0, rel=1e-9)
    # a scene that sticks in the near field sticks far out too
    stuck = collide(2.0, 1e-4, accuracy="fast")
    assert stuck.e_wet == 0.0 and stuck.e_far == 0.0


def _integrate_motion(outer, e0, stokes):
    # the equation of motion itself, Lagrange's with the kinetic energy M(x) (dx/dt)^2 / 2,
    # M(x) = m (1 + phi C(x)): M x'' + (1/2) M'(x) x'^2 = -R x' / St (dimensionless: x in a,
    # v in v0, t in a/v0), integrated in x from x0 outwards for the approach (backwards in
    # time) and the departure; M' by central differences of C (step 1e-6 x)
    g, phi, ratios = outer.geometry, outer.density_ratio, outer.ratios

    def mass(x):
        return 1.0 + phi * of.added_mass(g, x, ratios=ratios)

    def dmass(x):
        dx = 1e-6 * x
        return (mass(x + dx) - mass(x - dx)) / (2.0 * dx)

    def approach(x, v):  # x' = -v, x'' = v dv/dx: M v dv/dx + (1/2) M' v^2 = R v / St
        return [-0.5 * dmass(x) / mass(x) * v[0]
                + of.resistance(g, x, ratios=ratios) / (stokes * mass(x))]

    def departure(x, u):  # x' = +u, x'' = u du/dx: M u du/dx + (1/2) M' u^2 = -R u / St
        return [-0.5 * dmass(x) / mass(x) * u[0]
                - of.resistance(g, x, ratios=ratios) / (stokes * mass(x))]

    span = (outer.x0_over_a, outer.x_ref_over_a)
    v = integrate.solve_ivp(approach, span, [1.0], rtol=1e-11, atol=1e-13).y[0, -1]
    u = integrate.solve_ivp(departure, span, [e0], rtol=1e-11, atol=1e-13).y[0, -1]
    return max(0.0, u) / v


@pytest.mark.parametrize("geometry", of.GEOMETRIES)
@pytest.mark.parametrize("phi", [0.0, 1.0 / 8.08, 2.0])
def test_e_far_solves_the_equation_of_motion_with_added_mass(geometry, phi):
    # sqrt(M/m) v linear in Int R (m/M)^(1/2) dx (the energy equation) against a direct ODE
    # integration of the variable-mass equation: 1e-7 (the ODE's tolerance and the
    # finite-difference M', 1e-12 relative in C)
    outer = ff.OuterFlow(geometry=geometry, x0_over_a=0.01, x_ref_over_a=0.3, start_over_a=1.0,
                         density_ratio=phi)
    for e0, stokes in ((0.6, 30.0), (0.9, 150.0)):
        assert outer.restitution(e0, stokes) == pytest.approx(
            _integrate_motion(outer, e0, stokes), abs=1e-7)


@pytest.mark.parametrize("ratios", [(0.25, 0.1), (3.0, 40.0)])
def test_e_far_of_an_unequal_pair_solves_its_equation_of_motion(ratios):
    # the pair's R and C (outer_flow.pair_resistance, pair_added_mass) in the same energy
    # equation, against the direct integration: 1e-7 as above
    outer = ff.OuterFlow(geometry="pair", x0_over_a=0.01, x_ref_over_a=0.3, density_ratio=0.2,
                         radius_ratio=ratios[0], mass_ratio=ratios[1])
    assert outer.restitution(0.6, 30.0) == pytest.approx(_integrate_motion(outer, 0.6, 30.0),
                                                         abs=1e-7)


def test_e_far_of_an_equal_pair_is_the_equal_spheres():
    # equal radii and masses through pair_forces and the image chain: the equal spheres' e_far
    # (1e-9: pair_forces' precision, module docstring of outer_flow)
    for phi in (0.0, 0.5):
        pair = ff.OuterFlow(geometry="pair", density_ratio=phi)
        assert pair.restitution(0.7, 40.0) == pytest.approx(
            ff.OuterFlow(geometry="spheres", density_ratio=phi).restitution(0.7, 40.0), rel=1e-9)
        assert pair.approach_speed(40.0) == pytest.approx(
            ff.OuterFlow(geometry="spheres", density_ratio=phi).approach_speed(40.0), rel=1e-9)


def test_added_mass_raises_e_far():
    # the added mass carries momentum through the outer phase: at the same near-field result
    # the spheres keep more of it (the resistance integral is divided by sqrt(M/m) > 1)
    light = ff.OuterFlow(density_ratio=0.0).restitution(0.6, 30.0)
    heavy = ff.OuterFlow(density_ratio=1.0).restitution(0.6, 30.0)
    assert heavy > light
    assert math.isnan(ff.OuterFlow().restitution(math.nan, 30.0))  # a failed scene stays NaN


@pytest.mark.parametrize("kwargs, needle", [
    (dict(start_over_a=0.005), "outer_start_over_a = 0.005: the outer start must lie beyond"),
    (dict(x_ref_over_a=2.0), "x_ref_over_a = 2: the reference distance must be in [0.01, 1]"),
    (dict(x_ref_over_a=0.001), "x_ref_over_a = 0.001"),
    (dict(x0_over_a=0.0), "x0_over_a = 0"),
    (dict(density_ratio=-1.0), "density_ratio = -1: must be in [0, 1e6]"),
    (dict(density_ratio=math.nan), "density_ratio = nan: must be a finite number"),
    (dict(start_over_a=math.inf), "start_over_a = inf: must be a finite number"),
    (dict(geometry="cylinder"), "outer geometry = 'cylinder'"),
    (dict(geometry="pair", radius_ratio=0.0), "radius_ratio = 0: must be > 0"),
    (dict(geometry="pair", mass_ratio=math.inf), "mass_ratio = inf: must be a finite number"),
    (dict(geometry="wall", mass_ratio=2.0), "mass_ratio = 2: only the 'pair' outer geometry"),
])
def test_bad_outer_flow(kwargs, needle):
    with pytest.raises(ValueError) as info:
        ff.OuterFlow(**kwargs)
    assert needle in str(info.value)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "pipeline.cli", *args], capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize("args, needle", [
    (["run", "--St", "5", "--eps", "0.01", "--outer-start-over-a", "0.005"],
     "outer_start_over_a = 0.005"),
    (["run", "--St", "5", "--eps", "0.01", "--x-ref-over-a", "3"], "x_ref_over_a = 3"),
    (["run", "--St", "5", "--eps", "0.01", "--density-ratio", "-2"], "density_ratio = -2"),
    (["scene", "examples/steel_ball_glass_wall_glycerol.toml", "--outer-start", "10 um"],
     "outer_start = 10 µm"),
    (["scene", "examples/steel_ball_glass_wall_glycerol.toml", "--x-ref-over-a", "2"],
     "x_ref_over_a = "),
    (["scene", "examples/steel_ball_glass_wall_glycerol.toml", "--x-ref-over-a", "0.001"],
     "the reference distance of e_far must be in"),
])
def test_cli_outer_bad_input_exits_2_with_one_line(args, needle):
    out = _cli(*args)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and "Traceback" not in out.stderr


def test_cli_run_json_has_e_far():
    out = _cli("run", "--St", "50", "--eps", "1e-4", "--accuracy", "fast", "--json",
               "--outer-geometry", "spheres", "--density-ratio", "0.5")
    assert out.returncode == 0, out.stderr
    d = json.loads(out.stdout)
    assert d["outer_geometry"] == "spheres" and d["density_ratio"] == 0.5
    outer = ff.OuterFlow(geometry="spheres", density_ratio=0.5)
    assert d["e_far"] == pytest.approx(outer.restitution(d["e_wet"], 50.0), rel=1e-12)


def _scene(**fields):
    from pipeline.scenes.materials import load_table
    from pipeline.scenes.scene_file import scene_from_dict

    data = {"v0": "0.518 m/s", "body1": {"material": "chrome_steel", "radius": "3 mm",
                                         "density": "7797 kg/m^3"},
            "body2": {"material": "glass", "wall": True},
            "fluid": {"name": "silicone_oil_100cst", "viscosity": "0.09997 Pa s"}, **fields}
    return scene_from_dict(data, load_table((), user_files=False))


def test_scene_outer_flow():
    s = _scene()
    outer = s.outer_flow()
    # defaults: outer start 1 a, x_ref 0.1 a; the wall's density ratio rho_f / rho_p
    assert outer.geometry == "wall" and outer.start_over_a == 1.0
    assert outer.x_ref_over_a == pytest.approx(0.1, rel=1e-14)
    assert outer.density_ratio == pytest.approx(965.0 / 7797.0, rel=1e-12)
    assert s.x_ref_distance == pytest.approx(3e-4, rel=1e-12)
    given = _scene(x_ref="0.6 mm", outer_start_over_a=2.0).outer_flow()
    assert given.x_ref_over_a == pytest.approx(0.2) and given.start_over_a == 2.0
    # two equal spheres: each displaces rho_f V, the reduced mass is m1/2
    spheres = _scene(body2={"material": "chrome_steel", "radius": "3 mm",
                            "density": "7797 kg/m^3"}).outer_flow()
    assert spheres.geometry == "spheres"
    assert spheres.density_ratio == pytest.approx(965.0 / 7797.0, rel=1e-12)
    # unequal spheres: the pair's relative motion, the larger sphere over the smaller, whichever
    # the scene lists first (the added mass is measured on the smaller one's volume: with the
    # larger first, a 2 cm glass sphere and a 100 um grain in water made phi 1.6e6, beyond
    # OuterFlow's range, and the scene was refused one way round and solved the other)
    pair = _scene(body2={"material": "glass", "radius": "1 mm"}).outer_flow()
    assert pair.geometry == "pair" and pair.radius_ratio == pytest.approx(3.0, rel=1e-12)
    assert pair.mass_ratio == pytest.approx(7797.0 * 27.0 / 2480.0, rel=1e-12)
    swapped = _scene(body1={"material": "glass", "radius": "1 mm"},
                     body2={"material": "chrome_steel", "radius": "3 mm",
                            "density": "7797 kg/m^3"}).outer_flow()
    assert swapped == pair
    grain = {"material": "glass", "radius": "100 um"}
    big_first = _scene(body1={"material": "glass", "radius": "2 cm"}, body2=grain)
    assert big_first.outer_flow().density_ratio < 1.0  # the grain's: rho_f V/(2m) ~ 0.2
    # equal radii, unequal masses: the pair too (the equal-spheres resistance assumes symmetry)
    heavy = _scene(body2={"material": "chrome_steel", "radius": "3 mm",
                          "density": "9000 kg/m^3"}).outer_flow()
    assert heavy.geometry == "pair" and heavy.radius_ratio == pytest.approx(1.0, rel=1e-12)


def test_scene_json_says_which_e_for_which_dem_code():
    from pipeline.scenes.run import RESULT_KEYS, run_scene

    r = run_scene(_scene(), accuracy="fast", cavitation=None)
    d = r.to_dict()
    assert tuple(d) == RESULT_KEYS
    assert d["e_far"] == pytest.approx(r.outer.restitution(r.collision.e_x0, r.collision.St))
    assert 0.0 < d["e_far"] < d["e_wet"]
    dem = d["dem_restitution"]
    assert dem["resolved_cfd_dem"]["key"] == "e_wet" and dem["dry_dem"]["key"] == "e_far"
    assert dem["dry_dem"]["value"] == d["e_far"] and dem["resolved_cfd_dem"]["value"] == d["e_wet"]
    from pipeline.scenes.commands import format_report

    text = format_report(d)
    assert "far-field restitution e_far" in text and "dry DEM takes e_far" in text
    assert "resolved CFD-DEM takes e_wet" in text


def test_scene_json_has_e_far_for_unequal_spheres():
    # two unequal spheres: e_far through the pair's resistance and added mass (no longer null),
    # the same reading of the same near-field result, below e_wet (the outer flow only takes)
    from pipeline.scenes.run import run_scene

    r = run_scene(_scene(body2={"material": "chrome_steel", "radius": "6 mm"}), accuracy="fast",
                  cavitation=None)  # St 54: it rebounds
    d = r.to_dict()
    assert d["outer_geometry"] == "pair" and r.outer.geometry == "pair"
    assert d["e_far"] == pytest.approx(r.outer.restitution(r.collision.e_x0, r.collision.St),
                                       rel=1e-12)
    assert 0.0 < d["e_far"] < d["e_wet"] and d["outer_start_speed_m_per_s"] > 0.0
    assert any("two unequal spheres" in n for n in r.notes)


def test_export_rows_carry_e_far():
    import xarray as xr

    from pipeline.dem.export import CSV_FIELDS, scene_rows, store_rows
    from pipeline.scenes.run import run_scene

    assert CSV_FIELDS.index("e_far") == CSV_FIELDS.index("e_wet") + 1
    r = run_scene(_scene(), accuracy="fast")
    (row,) = scene_rows([r], "gondret")
    assert row["e_far"] == r.collision.e_far and row["x_ref_over_a"] == pytest.approx(0.1)
    # a store: e_far where it has the variable, an empty column where it was made before it
    grid = {"status": [[1, 1]], "e_wet": [[0.5, 0.0]], "h_m_x1": [[0.3, 0.2]],
            "p_max": [[2.0, 1.0]]}
    ds = xr.Dataset({k: (("eps", "St"), np.array(v, dtype=float)) for k, v in grid.items()},
                    coords={"eps": [1e-4], "St": [30.0, 3.0]})
    assert [row["e_far"] for row in store_rows(ds)] == ["", ""]
    ds["e_far"] = (("eps", "St"), np.array([[0.4, math.nan]]))
    rows = store_rows(ds)
    assert [row["e_far"] for row in rows] == [0.4, ""]
    assert rows[0]["x_ref_over_a"] == ff.DEFAULT.x_ref_over_a


# ---- the history force (far_field.history_restitution): its integration against a closed form,
# its no-history limit against e_far, and what it does -------------------------------------------
class _FarFromWalls:
    """Constant resistance and added mass (an isolated sphere: R = 1, C = 1/2)."""

    def __call__(self, gap):
        return 1.0, 0.5, 0.0


def test_history_integration_matches_the_basset_boussinesq_closed_form():
    """A sphere released at speed 1 in unbounded fluid, ``M V' = -V/St - B Int V'/sqrt(T - t)``:
    by Laplace transform ``V = sum_j C_j q_j exp(q_j^2 T) erfc(-q_j sqrt(T))``, ``q_j`` the roots
    of ``M q^2 + B sqrt(pi) q + 1/St`` (``erfc`` of a complex argument by the Faddeeva function,
    ``exp(c^2 T) erfc(-c sqrt(T)) = w(-i c sqrt(T))``)."""
    from scipy.special import wofz

    stokes, b, phi = 5.0, 0.3, 1.0
    mass = 1.0 + 0.5 * phi
    beta = b * math.sqrt(math.pi) / mass
    root = np.sqrt(complex(beta * beta - 4.0 / (stokes * mass)))
    q = ((-beta + root) / 2.0, (-beta - root) / 2.0)
    c = [(q[j] + beta) / (q[j] * (q[j] - q[1 - j])) for j in (0, 1)]
    times, speeds = [0.0], [1.0]
    ff._advance(times, speeds, 1.0, 4.0, phi, stokes, b, _FarFromWalls(), moving_out=True)
    t = np.array(times)
    exact = sum(c[j] * q[j] * wofz(-1j * q[j] * np.sqrt(t)) for j in (0, 1)).real
    # 1e-4: the implicit first-order steps (at most 2e-3 long; measured 3.5e-5 over T = 3.5)
    assert t[-1] > 3.0
    np.testing.assert_allclose(speeds, exact, rtol=0, atol=1e-4)
    # the history slows the decay of a sphere's speed (it opposes the deceleration) against
    # the plain exponential exp(-T / (M St))
    assert speeds[-1] > math.exp(-t[-1] / (mass * stokes))


def test_history_restitution_without_the_history_force_is_e_far():
    """With ``B = 0`` the time integration (approach shot to arrive at x0 with v0, the near
    field's own speed history, the departure) reproduces e_far's closed form."""
    result = collide(27.0, 4e-5)
    outer = ff.OuterFlow(density_ratio=0.12)
    expected = outer.restitution(result.e_x0, result.physics.St)
    # 1e-3: the first-order steps (at most 1 % of the gap; measured 8e-4 relative)
    assert ff.history_restitution(result, outer, coefficient=0.0) == pytest.approx(expected,
                                                                                   rel=1e-3)


def test_history_force_lowers_e_far_more_in_a_lighter_sphere():
    """``B = (3/sqrt(2 pi)) sqrt(phi/St)``: the lighter the sphere against the fluid, the more
    the history force takes off; none without a fluid density."""
    result = collide(27.0, 4e-5)
    dropped = []
    for phi in (0.05, 0.12, 0.5):
        outer = ff.OuterFlow(density_ratio=phi)
        dropped.append(outer.restitution(result.e_x0, result.physics.St)
                       - ff.history_restitution(result, outer))
    assert 0.0 < dropped[0] < dropped[1] < dropped[2]
    bare = ff.OuterFlow(density_ratio=0.0)
    assert ff.history_restitution(result, bare) == bare.restitution(result.e_x0, 27.0)
    assert ff.history_coefficient(27.0, 0.12) == pytest.approx(
        3.0 / math.sqrt(2.0 * math.pi) * math.sqrt(0.12 / 27.0), rel=1e-15)


def test_history_restitution_from_far_outer_starts():
    """An outer start far out (10 a, 100 a: the approach's own deceleration enters the history)
    changes the bound little, and a rebound that dies before x_ref is 0, not an endless march
    (the approach shot below the arrival speed stops short of x0)."""
    result = collide(27.0, 4e-5)
    near = ff.history_restitution(result, ff.OuterFlow(density_ratio=0.12))
    for start in (10.0, 100.0):
        outer = ff.OuterFlow(start_over_a=start, density_ratio=0.12)
        far = ff.history_restitution(result, outer)
        # measured 0.264, 0.261, 0.257: the far approach adds a little history
        assert far < outer.restitution(result.e_x0, 27.0) and abs(far - near) < 0.01
    dying = collide(10.0, 1e-3)
    assert ff.history_restitution(dying, ff.OuterFlow(start_over_a=100.0,
                                                      density_ratio=5.0)) == 0.0


# ---- inputs the outer flow cannot serve, and numpy scalars (a hostile scan) --------------------
def test_inputs_beyond_the_outer_series_reach_are_refused():
    """x0/a below MIN_X0_OVER_A took minutes (1e-12: 244 s) or raised MemoryError (1e-20); a
    pair whose radii differ by over PAIR_RATIO_MAX took minutes (1e4) or raised
    FloatingPointError (1e6): refused with their ranges, and the wall named for the pair."""
    from solver.far_field import MIN_X0_OVER_A, PAIR_RATIO_MAX, OuterFlow

    for tiny in (MIN_X0_OVER_A / 10, 1e-20):
        with pytest.raises(ValueError, match=r"x0_over_a = .*\[1e-08, 1\]"):
            OuterFlow(x0_over_a=tiny)
    for ratio in (PAIR_RATIO_MAX * 10, 1.0 / (PAIR_RATIO_MAX * 10), 1e6):
        with pytest.raises(ValueError, match="radius_ratio .* use geometry 'wall'"):
            OuterFlow(geometry="pair", radius_ratio=ratio, mass_ratio=1.0)
    OuterFlow(x0_over_a=MIN_X0_OVER_A)  # the ends themselves are taken, and so is 1 mm / 1 um
    OuterFlow(geometry="pair", radius_ratio=PAIR_RATIO_MAX, mass_ratio=1e9)
    assert 1e-3 / 1e-6 > PAIR_RATIO_MAX  # 1000.0000000000001: refused by the first mend
    OuterFlow(geometry="pair", radius_ratio=1e-3 / 1e-6, mass_ratio=1e9)


def test_numpy_scalars_are_numbers_and_bools_are_not():
    """np.float32(0.01) was refused as "must be a finite number" (Physics takes it); a numpy
    bool is refused in OuterFlow, Physics and collide's x_ref_x0 as Python's bool is."""
    from solver import Physics, collide
    from solver.far_field import OuterFlow

    assert OuterFlow(x0_over_a=np.float32(0.01)).x0_over_a == float(np.float32(0.01))
    assert OuterFlow(start_over_a=np.int64(2)).start_over_a == 2.0
    with pytest.raises(ValueError, match="x0_over_a"):
        OuterFlow(x0_over_a=np.bool_(True))
    with pytest.raises(ValueError, match="St"):
        Physics(St=np.bool_(True), eps=0.01)
    for bad in (True, np.bool_(True), "2", None):
        with pytest.raises(ValueError, match="x_ref_x0"):
            collide(5.0, 0.01, accuracy="fast", x_ref_x0=bad)
    c = collide(5.0, 0.01, accuracy="fast", x_ref_x0=np.int64(2))
    assert type(c.x_ref_x0) is float and c.to_dict()["x_ref_x0"] == 2.0
