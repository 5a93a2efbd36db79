"""The grid must hold the largest contact of the window: ``grid.size = "auto"`` sizes it
from the estimate (the Hertz semi-axes with the most compliant creep factor, plus a tilt's
shift of the contact), and a given size that the estimate does not fit a cell inside its
edge is refused when the scene is read, not at the step where the contact reaches it.

Small runs (16² - 32², 4-8 steps): each scene of a kind that stopped with a GridError
(a moment or a rotation moving the contact, Kelvin-Voigt, Prony, ``bulk = "elastic"``, a
fitted table) runs to its end on the automatic grid.
"""
import math

import numpy as np
import pytest

import contactpipe as cp
from contactpipe.materials import Body, kelvin_voigt
from contactpipe.testing import assert_contact_laws

RIGID = {"material": "rigid"}


def prony(young, poisson, terms, relaxation_time=None, **kw):
    d = {"material": "viscoelastic", "young": young, "poisson": poisson, "creep": "prony",
         "terms": terms, **kw}
    if relaxation_time is not None:
        d["relaxation_time"] = relaxation_time
    return d


def kv(young, poisson, tau, **kw):
    return {"material": "viscoelastic", "young": young, "poisson": poisson,
            "creep": "kelvin_voigt", "retardation_time": tau, **kw}


def scene(indenter, halfspace, load, radius=0.01, points=16, steps=4, mu=0.0, size="auto",
          **grid):
    return cp.Scene(geometry={"shape": "sphere", "radius": radius}, indenter=indenter,
                    halfspace=halfspace, friction={"mu": mu}, load=load,
                    grid={"points": [points, points], "size": size, **grid},
                    time={"steps": steps})


# ------------------------------------------------------------------------- automatic grid

def test_auto_grid_holds_the_shift_of_a_moment():
    """Steel pair, W = 1 kN, M2 = 0.3 N m: the contact (Hertz a = 0.4891 mm) moves by
    e = M2/W = 0.3 mm along x1, so L1 = 3 (a + e) and L2 = 3 a."""
    steel = {"material": "elastic", "young": 210e9, "poisson": 0.3}
    s = scene(steel, steel, {"time": [0.0, 1.0], "normal_force": 1000.0, "moment2": 0.3},
              radius=0.018)
    e_star = 210e9 / (2 * (1 - 0.3 ** 2))
    a = (3 * 1000.0 * 0.018 / (4 * e_star)) ** (1 / 3)
    L1, L2 = s.resolved_grid_size()
    assert L1 == pytest.approx(3 * (a + 0.3e-3), rel=1e-12)
    assert L2 == pytest.approx(3 * a, rel=1e-12)
    # a rotation phi1 moves it by R phi1 along x2
    r = scene(steel, steel, {"time": [0.0, 1.0], "normal_force": 1000.0,
                             "rotation1": [0.0, -0.01]}, radius=0.018)
    assert r.resolved_grid_size() == pytest.approx((3 * a, 3 * (a + 0.018 * 0.01)),
                                                   rel=1e-12)


# Each stopped with "the contact reached the edge of the grid (grid.size = auto)" before
# the automatic grid counted the tilt's shift (at step 8 and step 4).
TILTED = {
    "moment2 on a Prony indenter": (
        prony(1e9, 0.2, [[8.0, 90.0], [0.2, 1.7]], relaxation_time=4.0), RIGID,
        {"time": [0.0, 5.4], "normal_force": 2.0, "moment2": -2.6e-4}, 0.0075, 8, 0.1),
    "rotation1 on a Prony half-space": (
        RIGID, prony(2.9e8, 0.0, [[3.2, 7.6], [0.24, 1.05], [0.19, 5.6]]),
        {"time": [0.0, 0.475], "normal_force": 833.0, "rotation1": 0.042}, 0.048, 4, 0.0),
}
# Kinds named with the GridErrors: creep laws whose largest compliance over the window
# the estimate must take (Kelvin-Voigt's long-term one, a Prony sum, the normal
# compliance of bulk = "elastic", a fitted table), with and without a tilt.
KINDS = {
    # (no tilt: at t0 Kelvin-Voigt has no instantaneous elasticity to carry one)
    "Kelvin-Voigt, a falling load and a tangential force": (
        RIGID, kv(5e8, 0.3, 0.5),
        {"time": [0.0, 1.0, 2.0], "normal_force": [5.0, 20.0, 10.0],
         "tangential_force": [0.0, 1.0, -0.5]}, 0.01, 8, 0.1),
    "Prony with a dashpot, tangential force": (
        RIGID, prony(1e9, 0.3, [[1.5, 0.2], [4.0, 3.0]], relaxation_time=2.0),
        {"time": [0.0, 0.5, 1.5, 2.0], "normal_force": 10.0,
         "tangential_force": [0.0, 0.5, -0.5, 0.5]}, 0.01, 8, 0.1),
    "bulk = elastic Kelvin-Voigt on steel, short window": (
        {"material": "elastic", "young": 210e9, "poisson": 0.3},
        kv(1e9, 0.0, 1.0, bulk="elastic"),
        {"time": [0.0, 0.2], "normal_force": 10.0}, 0.01, 4, 0.0),
    "bulk = elastic Zener pair, moment2": (
        {"material": "viscoelastic", "young": 3e9, "poisson": 0.2, "creep": "zener",
         "relaxed_young": 3e8, "retardation_time": 0.3, "bulk": "elastic"},
        RIGID, {"time": [0.0, 1.0], "normal_force": 50.0, "moment2": 2e-3}, 0.01, 4, 0.0),
}


@pytest.mark.parametrize("case", list(TILTED) + list(KINDS))
def test_auto_grid_runs_to_the_end(case):
    ind, half, load, radius, steps, mu = {**TILTED, **KINDS}[case]
    s = scene(ind, half, load, radius=radius, steps=steps, mu=mu)
    ds = cp.simulate(s)                        # a GridError here fails the test
    assert ds.sizes["time"] == steps + 1
    assert_contact_laws(ds)
    # the contact kept clear of the outermost cells
    p = ds.p.values
    assert not np.any(p[:, [0, -1], :] > 0) and not np.any(p[:, :, [0, -1]] > 0)


def test_auto_grid_runs_a_fitted_table(tmp_path):
    """creep = "fit" (a tensile creep table, 1 to 5 times the glassy compliance over
    100 s) under a moment: the fitted Prony series' largest value sizes the grid."""
    table = tmp_path / "creep.csv"
    t = [0.0, 0.01, 0.1, 1.0, 10.0, 100.0]
    D = [1e-9 * f for f in (1.0, 1.2, 1.6, 2.5, 4.0, 5.0)]
    table.write_text("time,compliance\n" + "".join(f"{a},{b}\n" for a, b in zip(t, D, strict=True)))
    body = {"material": "viscoelastic", "poisson": 0.3, "creep": "fit",
            "file": str(table), "table_kind": "creep"}
    s = scene(RIGID, body, {"time": [0.0, 5.0, 10.0], "normal_force": [2.0, 4.0, 4.0],
                            "moment2": [0.0, 1e-3, -1e-3]}, steps=4)
    ds = cp.simulate(s)
    assert ds.sizes["time"] == 5
    p = ds.p.values
    assert not np.any(p[:, [0, -1], :] > 0) and not np.any(p[:, :, [0, -1]] > 0)


def test_bulk_elastic_estimate_follows_the_normal_compliance():
    """Rigid sphere (R = 10 mm, W = 10 N held) on Kelvin-Voigt with bulk = "elastic",
    nu = 0, tau = 1 s, over 0.2 s: the Hertz contact follows (1 - nu(t))/G(t), whose creep
    factor at 0.2 s is 0.316, not phi = 0.181 (a 1.20 times larger radius). The estimate
    matches the run's last contact radius sqrt(A / pi) (32², 8 steps) within 3 %."""
    half = kv(1e9, 0.0, 1.0, bulk="elastic")
    s = scene(RIGID, half, {"time": [0.0, 0.2], "normal_force": 10.0}, points=32, steps=8)
    n = Body("viscoelastic", 1e9, 0.0, kelvin_voigt(1.0), "elastic").normal_creep
    assert float(n(0.2)) == pytest.approx(0.3162, abs=1e-4)
    a_est = s.hertz_semi_axes()[0]
    assert a_est == pytest.approx((3 * 10.0 * 0.01 * float(n(0.2)) / (4 * 1e9)) ** (1 / 3),
                                  rel=1e-9)
    ds = cp.simulate(s)
    a_run = math.sqrt(float(ds.contact_area[-1]) / math.pi)
    assert abs(a_run / a_est - 1) < 0.03, (a_run, a_est)


# ------------------------------------------------------------------------- a given size

def test_a_given_size_too_small_is_refused_when_read():
    """Rigid sphere on Prony, phi(2 s) = 1 + 1.5 (1 - e^-10) + 4 (1 - e^-2/3) + 2/2 = 5.45:
    a 1 mm grid is refused, naming grid.size, the reach, the source of the estimate and the
    least size; that size runs to the end (16², 4 steps); size_check = false leaves it to
    the run (a GridError)."""
    half = prony(1e9, 0.3, [[1.5, 0.2], [4.0, 3.0]], relaxation_time=2.0)
    load = {"time": [0.0, 2.0], "normal_force": 10.0}
    auto = scene(RIGID, half, load)
    a = auto.hertz_semi_axes()[0]
    with pytest.raises(cp.SceneError) as err:
        scene(RIGID, half, load, size=[1e-3, 1e-3])
    text = str(err.value)
    allowed = 0.5e-3 - 1e-3 / 16
    need = a / (0.5 - 1 / 16)
    assert text == (
        f"grid.size = [0.001, 0.001] m is too small for grid.points = [16, 16]: the largest "
        f"contact is estimated to reach {a:.4g} m from the centre along x1 (the Hertz "
        f"semi-axis of the largest load.normal_force, W = 10 N at t = 0 s, with each body's "
        f"largest creep factor over the 2 s window), past the {allowed:.4g} m the grid "
        f"allows (its half-side less one cell: the contact must stay a cell inside the "
        f"edge, or it opens there); give grid.size = [{need:.4g}, {need:.4g}] m or more, or "
        f"\"auto\" (grid.size_check = false leaves it to the run)")
    fits = scene(RIGID, half, load, size=[need * 1.0001] * 2, steps=4)
    ds = cp.simulate(fits)
    assert ds.sizes["time"] == 5
    left = scene(RIGID, half, load, size=[1e-3, 1e-3], size_check=False)
    assert left.grid.size_check is False and "size_check = false" in left.to_toml()
    with pytest.raises(cp.GridError, match="edge of the grid"):
        cp.simulate(left)


def test_size_check_true_is_the_default_and_keeps_the_digest():
    half = prony(1e9, 0.3, [[1.5, 0.2]])
    load = {"time": [0.0, 1.0], "normal_force": 10.0}
    plain = scene(RIGID, half, load)
    said = scene(RIGID, half, load, size_check=True)
    assert said == plain and said.digest() == plain.digest()
    assert "size_check" not in plain.to_toml()
    with pytest.raises(cp.SceneError, match=r"grid\.size_check must be"):
        scene(RIGID, half, load, size_check="no")


def test_a_moment_refused_names_the_largest_shift_the_grid_allows():
    """Steel pair, 32 cells over 2 mm: a = 0.4891 mm, the grid allows 1 - 2/32 mm, so
    e = M1/W = 0.5 mm is refused naming the shift below 0.4484 mm."""
    steel = {"material": "elastic", "young": 210e9, "poisson": 0.3}
    with pytest.raises(cp.SceneError) as err:
        scene(steel, steel, {"time": [0.0, 1.0], "normal_force": 1000.0, "moment1": 0.5},
              radius=0.018, points=32, size=[2e-3, 2e-3])
    assert "load.moment1 = 0.5 at t = 0 s moves its pressure centre M/W 0.0005 m along x2" \
        in str(err.value)
    assert "keep the shift below 0.0004484 m" in str(err.value)
    ok = scene(steel, steel, {"time": [0.0, 1.0], "normal_force": 1000.0, "moment1": 0.44},
               radius=0.018, points=32, size=[2e-3, 2e-3])
    assert ok.load.moment1 == 0.44


def test_a_moment_where_no_normal_force_carries_it_is_refused():
    steel = {"material": "elastic", "young": 210e9, "poisson": 0.3}
    with pytest.raises(cp.SceneError, match=r"^load\.moment2 = 0\.1 at t = 1 s meets "
                                            r"load\.normal_force W = 0 there: no normal force "
                                            r"carries the moment"):
        scene(steel, steel, {"time": [0.0, 1.0], "normal_force": [1000.0, 0.0],
                             "moment2": [0.0, 0.1]}, radius=0.018, size=[2e-3, 2e-3])


# ------------------------------------------------------------------------- a surface

def test_a_surface_under_an_approach_is_checked_at_its_edge(tmp_path):
    """The steel sphere's paraboloid as a .npy surface (16 cells over 2 mm, R = 18 mm):
    under an approach omega its contact reaches a = sqrt(R omega), where the gap is
    omega / 2. With a = 1 mm the outermost cells (the nearest at 0.9396 mm) would be in
    contact: refused; with a = 0.7 mm it runs without reaching the edge."""
    from contactpipe.scene import Grid
    from contactpipe.scene.geometry import sphere_gap

    steel = {"material": "elastic", "young": 210e9, "poisson": 0.3}
    grid = Grid.make(points=(16, 16), size=(2e-3, 2e-3))
    gap = tmp_path / "sphere.npy"
    np.save(gap, sphere_gap(*grid.coordinates(), 0.018))

    def surface(a, **kw):
        return cp.Scene(geometry={"shape": "surface", "file": str(gap)}, indenter=steel,
                        halfspace=steel, load={"time": [0.0, 1.0],
                                               "normal_approach": [0.0, a * a / 0.018]},
                        grid={"points": [16, 16], "size": [2e-3, 2e-3], **kw},
                        time={"steps": 2})

    with pytest.raises(cp.SceneError, match=r"^grid\.size = \[0\.002, 0\.002\] m is too "
                                            r"small for load\.normal_approach = 5\.556e-05 m "
                                            r"at t = 1 s: at the grid's outermost cell"):
        surface(1e-3)
    ds = cp.simulate(surface(0.7e-3))
    assert ds.sizes["time"] == 3
    # the contact radius sqrt(A / pi) within a cell (0.125 mm) of a = sqrt(R omega)
    assert abs(math.sqrt(float(ds.contact_area[-1]) / math.pi) - 0.7e-3) < 0.125e-3
    assert not np.any(ds.p.values[:, [0, -1], :] > 0)
    assert not np.any(ds.p.values[:, :, [0, -1]] > 0)
    left = surface(1e-3, size_check=False)
    with pytest.raises(cp.GridError, match="edge of the grid"):
        cp.simulate(left)
