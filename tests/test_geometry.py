"""Gap builders of contactpipe.scene.geometry and Geometry.gap."""
import numpy as np
import pytest
import xarray as xr

from contactpipe.exceptions import SceneError
from contactpipe.scene import Geometry, Grid
from contactpipe.scene import geometry as g

GRID = Grid(points=(16, 12), size=(2e-3, 1.5e-3))
X1, X2 = GRID.coordinates()


def odd_axis(n=9, half=1e-3):
    """An axis with a node at the origin."""
    return np.linspace(-half, half, n)


def test_grid_coordinates_are_cell_centres():
    d1, d2 = GRID.spacing()
    assert d1 == pytest.approx(2e-3 / 16) and d2 == pytest.approx(1.5e-3 / 12)
    assert X1[0] == pytest.approx(-1e-3 + d1 / 2) and X1[-1] == pytest.approx(1e-3 - d1 / 2)
    assert np.all(np.diff(X1) > 0) and X1.shape == (16,) and X2.shape == (12,)
    np.testing.assert_allclose(X1 + X1[::-1], 0.0, atol=1e-18)


def test_sphere_is_the_hertz_paraboloid():
    R = 0.018
    h = g.sphere_gap(X1, X2, R)
    assert h.shape == (16, 12)
    np.testing.assert_allclose(h, (X1[:, None] ** 2 + X2[None, :] ** 2) / (2 * R), rtol=1e-15)
    x = odd_axis()
    h0 = g.sphere_gap(x, x, R)
    assert h0[4, 4] == 0.0 and h0.min() == 0.0
    # the paraboloid agrees with the exact cap to O(r^4 / R^3)
    r = 1e-3
    assert g.sphere_gap([r], [0.0], R)[0, 0] == pytest.approx(R - np.sqrt(R**2 - r**2), rel=1e-3)


def test_ellipsoid_has_its_radii_along_the_axes():
    R1, R2 = 0.02, 0.005
    x = odd_axis()
    h = g.ellipsoid_gap(x, x, (R1, R2))
    assert h[4, 4] == 0.0 and h.min() == 0.0
    np.testing.assert_allclose(h[:, 4], x**2 / (2 * R1))
    np.testing.assert_allclose(h[4, :], x**2 / (2 * R2))
    np.testing.assert_allclose(g.ellipsoid_gap(x, x, (0.01, 0.01)), g.sphere_gap(x, x, 0.01))


def test_flat_punch_is_flat_inside_and_finite_outside():
    x = odd_axis(21)
    a = 5.2e-4  # not on a node
    h = g.flat_punch_gap(x, x, a)
    r = np.hypot(x[:, None], x[None, :])
    assert np.all(h[r <= a] == 0.0)
    assert np.all(h[r > a] == a)  # default height = radius
    assert np.all(np.isfinite(h))
    h2 = g.flat_punch_gap(x, x, a, height=1e-2)
    assert h2.max() == 1e-2 and h2[10, 10] == 0.0


def test_geometry_gap_dispatches():
    x = odd_axis()
    assert np.array_equal(Geometry("sphere", radius=0.01).gap(x, x), g.sphere_gap(x, x, 0.01))
    assert np.array_equal(Geometry("ellipsoid", radii=[0.01, 0.02]).gap(x, x),
                          g.ellipsoid_gap(x, x, (0.01, 0.02)))
    punch = Geometry("flat_punch", radius=1e-4)
    assert punch.height == 1e-4  # resolved default
    assert np.array_equal(punch.gap(x, x), g.flat_punch_gap(x, x, 1e-4))


def write_nc(path, x1, x2, values, dims=("x1", "x2"), name="gap", units="m"):
    coords = {"x1": x1, "x2": x2}
    da = xr.DataArray(values, dims=dims, coords={d: coords[d] for d in dims},
                      attrs={"units": units})
    xr.Dataset({name: da}).to_netcdf(path)
    return path


def test_surface_from_netcdf_interpolates_linearly(tmp_path):
    # a plane is reproduced exactly by linear interpolation, on a coarser, wider grid
    fx1 = np.linspace(-2e-3, 2e-3, 41)
    fx2 = np.linspace(-1e-3, 1e-3, 21)
    plane = 3.0 * fx1[:, None] + 0.5 * fx2[None, :] + 1e-3
    f = write_nc(tmp_path / "plane.nc", fx1, fx2, plane)
    h = g.surface_gap(X1, X2, f)
    np.testing.assert_allclose(h, 3.0 * X1[:, None] + 0.5 * X2[None, :] + 1e-3, rtol=1e-12)
    # transposed storage and descending coordinates read the same
    f2 = write_nc(tmp_path / "t.nc", fx1[::-1], fx2, plane[::-1].T, dims=("x2", "x1"))
    np.testing.assert_allclose(g.surface_gap(X1, X2, f2), h, rtol=1e-12)
    assert np.array_equal(Geometry("surface", file=str(f)).gap(X1, X2), h)


def test_surface_from_netcdf_on_the_same_grid_is_exact(tmp_path):
    sphere = g.sphere_gap(X1, X2, 0.01)
    f = write_nc(tmp_path / "s.nc", X1, X2, sphere)
    np.testing.assert_allclose(g.surface_gap(X1, X2, f), sphere, rtol=1e-12, atol=1e-20)


def test_surface_from_npy(tmp_path):
    arr = np.random.default_rng(0).random((16, 12)) * 1e-6
    f = tmp_path / "gap.npy"
    np.save(f, arr)
    assert np.array_equal(g.surface_gap(X1, X2, f), arr)
    assert g.check_surface(f, X1, X2) == []


def test_surface_npy_of_the_wrong_shape(tmp_path):
    f = tmp_path / "gap.npy"
    np.save(f, np.zeros((12, 16)))
    with pytest.raises(SceneError, match=r"geometry\.file .*gap\.npy.*shape \(12, 16\)"):
        g.surface_gap(X1, X2, f)


def test_surface_netcdf_not_covering_the_grid(tmp_path):
    x = np.linspace(-5e-4, 5e-4, 11)
    f = write_nc(tmp_path / "small.nc", x, x, np.zeros((11, 11)))
    with pytest.raises(SceneError, match=r"geometry\.file .*small\.nc.*does not cover the grid: "
                                         r"the grid's x1 runs from .* outside the file's x1"):
        g.surface_gap(X1, X2, f)


@pytest.mark.parametrize("kwargs, match", [
    ({"name": "height"}, r"no variable 'gap' \(found: height\)"),
    ({"units": "mm"}, r"units 'mm', expected 'm'"),
])
def test_surface_netcdf_wrong_content(tmp_path, kwargs, match):
    x = np.linspace(-2e-3, 2e-3, 5)
    f = write_nc(tmp_path / "bad.nc", x, x, np.zeros((5, 5)), **kwargs)
    with pytest.raises(SceneError, match=match):
        g.surface_gap(X1, X2, f)


def test_surface_nan_is_refused(tmp_path):
    arr = np.zeros((16, 12))
    arr[3, 4] = np.nan
    f = tmp_path / "nan.npy"
    np.save(f, arr)
    with pytest.raises(SceneError, match=r"NaN or inf at 1 of 192"):
        g.surface_gap(X1, X2, f)


def test_surface_missing_or_unreadable(tmp_path):
    with pytest.raises(SceneError, match=r"geometry\.file .*nope\.nc.*no such file"):
        g.surface_gap(X1, X2, tmp_path / "nope.nc")
    junk = tmp_path / "junk.nc"
    junk.write_text("not netcdf")
    with pytest.raises(SceneError, match=r"not a readable netCDF file"):
        g.surface_gap(X1, X2, junk)


@pytest.mark.parametrize("arr, match", [
    (np.full((16, 12), 1e-6 + 1e-7j), r"2-D array of real numbers .*complex128 \(a complex "
                                      r"gap has no meaning\)"),
    (np.zeros((16, 12), dtype=bool), r"real numbers .*got shape \(16, 12\) of bool"),
    (np.zeros((16, 12, 2)), r"real numbers .*got shape \(16, 12, 2\)"),
    (np.zeros(192), r"real numbers .*got shape \(192,\)"),
    (np.full((16, 12), np.inf), r"the gap holds NaN or inf at 192 of 192 points"),
    (np.array([[None] * 12] * 16, dtype=object), r"not a readable \.npy array"),
    (np.zeros((16, 12), dtype=[("a", float), ("b", float)]), r"real numbers"),
])
def test_surface_npy_must_be_a_real_finite_array(tmp_path, arr, match):
    """Refused at validation, naming geometry.file (a complex gap used to lose its
    imaginary part silently)."""
    f = tmp_path / "gap.npy"
    np.save(f, arr, allow_pickle=True)
    for check in (lambda: Geometry("surface", file=str(f)), lambda: g.surface_gap(X1, X2, f)):
        with pytest.raises(SceneError, match=r"^geometry\.file '.*gap\.npy': .*" + match):
            check()


def test_surface_netcdf_gap_must_be_real_numbers(tmp_path):
    x = np.linspace(-2e-3, 2e-3, 5)
    f = write_nc(tmp_path / "b.nc", x, x, np.zeros((5, 5), dtype=bool))
    with pytest.raises(SceneError, match=r"variable 'gap' holds bool values; the gap must be "
                                         r"real numbers \[m\]"):
        Geometry("surface", file=str(f))


def test_surface_npy_integers_are_metres(tmp_path):
    f = tmp_path / "gap.npy"
    np.save(f, np.arange(192, dtype=np.int32).reshape(16, 12))
    assert Geometry("surface", file=str(f)).gap(X1, X2).dtype == float
