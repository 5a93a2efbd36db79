"""A mapped friction coefficient mu(x1, x2) (``[friction] mu`` = a netCDF file).

The paper's elastic fretting loop (steel on steel, R = 18 mm, W = 1 kN, T = 0 -> 90 ->
-90 -> 90 N, 32² cells over 3 a, 10 steps), with mu from a file.
"""
import os

import numpy as np
import pytest
import xarray as xr
from helpers import fretting_scene

import contactpipe as cp
from contactpipe.nomenclature import STATUS_SLIP, STATUS_STICK
from contactpipe.testing import assert_contact_laws, contact_law_violations

SCENE = fretting_scene(n=32, steps=10, mu=0.1).replace({"solver.fft": "scipy"})
X1, X2 = SCENE.grid.coordinates()


def write_map(path, values, x1=X1, x2=X2, name="mu"):
    xr.Dataset({name: (("x1", "x2"), np.asarray(values, float))},
               coords={"x1": x1, "x2": x2}).to_netcdf(path)
    return str(path)


def test_a_uniform_map_is_the_scalar_mu(tmp_path):
    """mu = 0.1 everywhere from a file (given on the grid, and on a coarser grid that
    covers it, interpolated): every variable equals the scalar-mu run's exactly; the
    archive stores the map as 'mu' (x1, x2)."""
    scalar = cp.simulate(SCENE)
    on_grid = write_map(tmp_path / "uniform.nc", np.full((32, 32), 0.1))
    coarse = write_map(tmp_path / "coarse.nc", np.full((5, 7), 0.1),
                       np.linspace(-2e-3, 2e-3, 5), np.linspace(-3e-3, 3e-3, 7))
    for file in (on_grid, coarse):
        mapped = cp.simulate(SCENE.replace({"friction.mu": file}))
        for name in scalar.data_vars:
            if name != "fft_pairs":
                np.testing.assert_array_equal(mapped[name].values, scalar[name].values,
                                              err_msg=name)
        assert mapped["mu"].dims == ("x1", "x2") and np.all(mapped["mu"].values == 0.1)
        assert mapped["mu"].attrs["units"] == "1"


def test_two_halves(tmp_path):
    """mu = 0.1 for x1 < 0, 0.2 for x1 > 0: Coulomb holds pointwise with the map
    (|q| <= mu p (1 + 1e-9), and |q| = mu p in the slip cells of each half), the
    contact-law checker passes with the map, and the stick zone leans toward the higher
    mu: its centroid lies at x1 > 0 at the extremes of the loop (measured +1.58 cells at
    T = +-90 N) and never at x1 < 0."""
    file = write_map(tmp_path / "halves.nc", np.where(X1[:, None] < 0, 0.1, 0.2)
                     * np.ones((1, 32)))
    ds = cp.simulate(SCENE.replace({"friction.mu": file}))
    mu = ds["mu"].values
    p, q = ds.p.values, np.hypot(ds.q1.values, ds.q2.values)
    assert np.all(q <= mu * p * (1 + 1e-9))
    slip = ds.status.values == STATUS_SLIP
    np.testing.assert_allclose(q[slip], (mu * p)[slip], rtol=1e-9)
    assert slip[:, X1 < 0].any() and slip[:, X1 > 0].any()
    assert_contact_laws(ds)
    cell = X1[1] - X1[0]
    x1 = np.broadcast_to(X1[:, None], (32, 32))
    for k in range(1, ds.sizes["time"]):
        stick = ds.status.values[k] == STATUS_STICK
        lean = x1[stick].mean() / cell
        assert lean > 0.0
        if k in (2, 6, 10):                         # T = +90, -90, +90 N
            assert lean > 1.0


def test_the_checker_uses_the_map(tmp_path):
    """A shear that breaks Coulomb on the low-mu half only (0.15 p where mu = 0.1) is
    flagged, though it would pass against the larger mu."""
    file = write_map(tmp_path / "halves.nc", np.where(X1[:, None] < 0, 0.1, 0.2)
                     * np.ones((1, 32)))
    ds = cp.simulate(SCENE.replace({"friction.mu": file})).load()
    q1 = ds.q1.values.copy()
    i, j = 12, 16                                   # x1 < 0, in contact
    assert X1[i] < 0 and ds.p.values[2, i, j] > 0
    q1[2, i, j] = 0.15 * ds.p.values[2, i, j]
    ds["q1"] = ds.q1.copy(data=q1)
    assert any(v.startswith("Coulomb at step 2") for v in contact_law_violations(ds))


def test_the_map_round_trips_an_archive(tmp_path):
    """Written to a file and opened again (verify=True), the map is there and checked."""
    file = write_map(tmp_path / "halves.nc", np.where(X1[:, None] < 0, 0.1, 0.2)
                     * np.ones((1, 32)))
    ds = cp.simulate(SCENE.replace({"friction.mu": file}), tmp_path / "run.nc")
    back = cp.open_archive(tmp_path / "run.nc", verify=True)
    np.testing.assert_array_equal(back["mu"].values, ds["mu"].values)


def test_relative_path_and_digest(tmp_path):
    """A relative file name is taken relative to the scene file; the digest counts the
    file's content: the same content elsewhere gives the same digest, other content
    another."""
    d = tmp_path / "a"
    d.mkdir()
    write_map(d / "mu.nc", np.full((32, 32), 0.1))
    text = SCENE.to_toml().replace("mu = 0.1", 'mu = "mu.nc"')
    (d / "scene.toml").write_text(text)
    scene = cp.Scene.from_toml(d / "scene.toml")
    assert scene.friction.mu == str(d / "mu.nc") and scene.friction.mapped
    digest = scene.digest()
    e = tmp_path / "b"
    e.mkdir()
    os.replace(d / "mu.nc", e / "mu.nc")
    moved = scene.replace({"friction.mu": str(e / "mu.nc")})
    assert moved.digest() == digest
    write_map(e / "mu.nc", np.full((32, 32), 0.2))
    assert moved.digest() != digest


@pytest.mark.parametrize("case, message", [
    ("nan", r"'mu' holds NaN or inf at 1 of 1024 points; every value must be finite"),
    ("negative", r"'mu' is negative at 1 of 1024 points \(min -0\.1\); mu must be >= 0"),
    ("small", r"does not cover the grid: the grid's x1 runs from -0\.000710\d* to "
              r"0\.000710\d* m, outside the file's x1 from -0\.0005 to 0\.0005 m; shrink "
              r"grid\.size or extend the file$"),
    ("no variable", r"no variable 'mu' \(found: friction\)"),
    ("missing", r"no such file"),
])
def test_bad_maps(tmp_path, case, message):
    """One line naming friction.mu and the problem."""
    values = np.full((32, 32), 0.1)
    path = tmp_path / "mu.nc"
    if case == "nan":
        values[3, 4] = np.nan
    if case == "negative":
        values[3, 4] = -0.1
    if case == "small":
        write_map(path, np.full((4, 4), 0.1), np.linspace(-5e-4, 5e-4, 4),
                  np.linspace(-1e-3, 1e-3, 4))
    elif case == "no variable":
        write_map(path, values, name="friction")
    elif case != "missing":
        write_map(path, values)
    with pytest.raises(cp.SceneError, match=rf"^friction\.mu = '{path}': {message}") as err:
        SCENE.replace({"friction.mu": str(path)})
    assert "\n" not in str(err.value)
