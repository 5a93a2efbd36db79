"""Measured and generated surfaces: reading each height format (heights, orientation,
sign, units), resampling, missing points, the generated self-affine surfaces' statistics,
and the refusals of bad input (one line naming the key and the file)."""
import numpy as np
import pytest
from surface_files import QUANTUM_UM, WRITERS, write_plu, write_sdf, write_xyz

import contactpipe as cp
from contactpipe.scene import rough
from contactpipe.scene.parts import Geometry
from contactpipe.scene.topography import read_heights

NX, NY, DX, DY = 6, 5, 2.0, 3.0           # points and spacing [um] of the test files


def _field():
    """Heights [um] that tell x from y and up from down: a slope along each axis (0.5 um
    a point along x, 0.1 um along y) and one peak of 7 um at (i, j) = (4, 1)."""
    i, j = np.meshgrid(np.arange(NX), np.arange(NY), indexing="ij")
    z = 0.5 * i + 0.1 * j
    z[4, 1] = 7.0
    return z


def _axes(n, d):
    """The scene's cell centres [m] of n cells of d um, centred."""
    return (np.arange(n) + 0.5 - n / 2) * d * 1e-6


@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_each_format_gives_its_heights_in_metres(tmp_path, fmt):
    """A file of each format, written per its specification, reads back as the heights
    it holds, in metres (um -> m), z[i, j] at the i-th x and j-th y ascending: the error
    is at most half a stored count (int16 formats: 1 nm) or float32 rounding."""
    z = _field()
    path = tmp_path / f"surface.{fmt}"
    WRITERS[fmt](path, z, DX, DY)
    h = read_heights(path)
    assert h.z.shape == (NX, NY)
    tol = QUANTUM_UM[fmt] / 2 + 1e-6 * 7.0
    assert np.max(np.abs(h.z * 1e6 - z)) <= tol
    assert h.spacing == pytest.approx((DX * 1e-6, DY * 1e-6), rel=1e-6)


@pytest.mark.parametrize("fmt", sorted(WRITERS))
def test_a_peak_closes_the_gap(tmp_path, fmt):
    """On the file's own grid (resample = false) the gap is max(z) - z: 0 at the peak
    (4, 1), 7 um minus the slope elsewhere, in metres."""
    z = _field()
    path = tmp_path / f"surface.{fmt}"
    WRITERS[fmt](path, z, DX, DY)
    geo = Geometry("surface", file=str(path), resample=False)
    gap = geo.gap(_axes(NX, DX), _axes(NY, DY))
    assert np.unravel_index(np.argmin(gap), gap.shape) == (4, 1)
    tol = (QUANTUM_UM[fmt] + 2e-6 * 7.0) * 1e-6
    np.testing.assert_allclose(gap, (7.0 - z) * 1e-6, rtol=0, atol=tol)


def test_resampling_is_bilinear_and_exact_on_a_plane(tmp_path):
    """A plane z = 0.3 x + 0.2 y (x, y in um) on a 21 x 17 file of 1 um, resampled onto an
    8 x 8 grid of 14 um sides: bilinear interpolation reproduces a plane, so the gap is
    max - z at the grid's own centres to 1e-12 of the relief."""
    n1, n2 = 21, 17
    i, j = np.meshgrid(np.arange(n1), np.arange(n2), indexing="ij")
    z = 0.3 * i + 0.2 * j
    path = tmp_path / "plane.xyz"
    write_xyz(path, z, 1.0, 1.0)
    x1, x2 = _axes(8, 14 / 8), _axes(8, 14 / 8)
    gap = Geometry("surface", file=str(path)).gap(x1, x2)
    plane = 0.3 * x1[:, None] + 0.2 * x2[None, :]          # um per um: dimensionless
    want = plane.max() - plane
    np.testing.assert_allclose(gap, want, rtol=0, atol=1e-12 * np.ptp(want))


def test_heights_ride_on_a_sphere(tmp_path):
    """A flat file (all heights 1 um) with form = "sphere": the gap is the paraboloid
    r^2 / (2 R) less its least value on the grid."""
    path = tmp_path / "flat.xyz"
    write_xyz(path, np.ones((10, 10)), 1.0, 1.0)
    x = _axes(8, 1.0)
    gap = Geometry("surface", file=str(path), form="sphere", radius=0.01).gap(x, x)
    r2 = x[:, None] ** 2 + x[None, :] ** 2
    np.testing.assert_allclose(gap, (r2 - r2.min()) / 0.02, rtol=1e-12, atol=1e-20)


def test_missing_points_refused_or_filled(tmp_path):
    """A missing point (the int16 marker of sdf) is refused by default, naming
    geometry.missing and the file; missing = "fill" gives it the height of a nearest
    measured point (an x neighbour: x spacing 2 um < y spacing 3 um)."""
    z = _field()
    path = tmp_path / "hole.sdf"
    write_sdf(path, z, DX, DY, missing=(2, 3))
    with pytest.raises(cp.SceneError, match="geometry.missing") as err:
        Geometry("surface", file=str(path))
    assert str(path) in str(err.value) and "\n" not in str(err.value)
    h = Geometry("surface", file=str(path), missing="fill", resample=False)
    gap = h.gap(_axes(NX, DX), _axes(NY, DY))
    filled = 7.0 - gap[2, 3] * 1e6
    assert min(abs(filled - z[1, 3]), abs(filled - z[3, 3])) < 1e-3
    assert np.all(np.isfinite(gap))


@pytest.mark.parametrize("case", ["all-missing", "truncated-plu", "truncated-sdf",
                                  "garbage-x3p", "units-xyz", "ragged-xyz"])
def test_bad_files_get_one_line_naming_key_and_file(tmp_path, case):
    """Unreadable, truncated, NaN-only files and unknown units: one SceneError line
    naming geometry.file and the file."""
    z = _field()
    if case == "all-missing":
        path = tmp_path / "empty.plu"
        write_plu(path, z, DX, DY, missing=np.ones(z.shape, bool))
        want = "no measured point"
    elif case.startswith("truncated"):
        ext = case.split("-")[1]
        path = tmp_path / f"cut.{ext}"
        WRITERS[ext](path, z, DX, DY)
        data = path.read_bytes()
        path.write_bytes(data[: len(data) - 20])
        want = "truncated"
    elif case == "garbage-x3p":
        path = tmp_path / "junk.x3p"
        path.write_bytes(b"not a zip archive at all")
        want = "not a readable x3p"
    elif case == "units-xyz":
        path = tmp_path / "furlong.xyz"
        write_xyz(path, z, DX, DY, unit="furlong")
        want = "unknown units 'furlong'"
    else:
        path = tmp_path / "ragged.xyz"
        write_xyz(path, z, DX, DY)
        path.write_text("\n".join(path.read_text().splitlines()[:-3]) + "\n")
        want = "rectangular grid"
    with pytest.raises(cp.SceneError, match=want) as err:
        Geometry("surface", file=str(path))
    msg = str(err.value)
    assert "geometry.file" in msg and str(path) in msg and "\n" not in msg


def test_resample_false_needs_the_files_grid(tmp_path):
    """resample = false on a grid of other points is refused with the file's figures."""
    path = tmp_path / "s.sdf"
    write_sdf(path, _field(), DX, DY)
    with pytest.raises(cp.SceneError, match=r"grid.points\[0\] = 6 and grid.size\[0\]"):
        Geometry("surface", file=str(path), resample=False).gap(_axes(8, DX), _axes(NY, DY))


# ------------------------------------------------------------------- generated surfaces

def _hurst_fit(h, side, roll, short):
    """Hurst exponent from the slope of the radially averaged PSD over the self-affine
    band (a fifth of a decade inside each end): C ~ q^(-2 (1 + H))."""
    q, c = rough.radial_psd(h, side, side, bins=40)
    band = (q > 2 * np.pi / roll * 1.6) & (q < 2 * np.pi / short / 1.6)
    slope = np.polyfit(np.log(q[band]), np.log(c[band]), 1)[0]
    return -slope / 2 - 1, int(band.sum())


@pytest.mark.parametrize("hurst", [0.3, 0.5, 0.8])
def test_generated_statistics_match_the_request(hurst):
    """512^2 cells on a 1 mm side, roll-off 0.5 mm, cut-off 16 cells, rms slope 0.1:
    the rms slope by forward differences (an independent estimate, which the cut-off at
    16 cells keeps within 1 % of the band-limited one) within 5 %; the Hurst exponent
    fitted to the radially averaged PSD within 0.05; the mean height 0."""
    n, side = 512, 1e-3
    roll, short = side / 2, 16 * side / n
    h = rough.self_affine(n, n, side, side, hurst, (roll, short), seed=3, rms_slope_=0.1)
    d = side / n
    fd = np.sqrt(np.mean(((np.roll(h, -1, 0) - h) / d) ** 2 + ((np.roll(h, -1, 1) - h) / d)
                         ** 2))
    assert fd == pytest.approx(0.1, rel=0.05)
    assert rough.rms_slope(h, side, side) == pytest.approx(0.1, rel=1e-12)
    fitted, points = _hurst_fit(h, side, roll, short)
    assert points >= 8
    assert abs(fitted - hurst) <= 0.05
    assert abs(h.mean()) <= 1e-12 * np.sqrt(np.mean(h ** 2))


def test_rms_height_and_seeds():
    """rms_height sets the rms of the heights (1 um to 1e-12); the same seed gives the
    same surface bit for bit, another seed another (their correlation below 0.3)."""
    n, side = 64, 1e-3
    x = _axes(n, side / n * 1e6)
    geo = dict(hurst=0.7, wavelengths=[side / 2, 4 * side / n], rms_height=1e-6)
    a = Geometry("rough", seed=1, **geo).gap(x, x)
    b = Geometry("rough", seed=1, **geo).gap(x, x)
    c = Geometry("rough", seed=2, **geo).gap(x, x)
    np.testing.assert_array_equal(a, b)
    assert a.min() == 0.0
    assert np.std(a) == pytest.approx(1e-6, rel=1e-12)
    assert abs(np.corrcoef(a.ravel(), c.ravel())[0, 1]) < 0.3


@pytest.mark.parametrize("keys, want", [
    ({"hurst": 1.0}, "geometry.hurst must be a number strictly between 0 and 1"),
    ({"hurst": 0.0}, "geometry.hurst must be a number strictly between 0 and 1"),
    ({"rms_height": 1e-6}, "give exactly one of the two for shape = 'rough' \\(got both"),
    ({"rms_slope": None}, "give exactly one of the two for shape = 'rough' \\(got neither"),
    ({"wavelengths": [1e-5, 1e-4]}, "roll-off \\(first\\) must be longer"),
    ({"form": "sphere"}, "geometry.radius is required for form = 'sphere'"),
    ({"radius": 0.01}, "geometry.radius = 0.01 is not used"),
])
def test_bad_rough_keys_are_refused(keys, want):
    geo = {"hurst": 0.8, "rms_slope": 0.1, "wavelengths": [1e-4, 1e-5], "seed": 0, **keys}
    with pytest.raises(cp.SceneError, match=want):
        Geometry("rough", **{k: v for k, v in geo.items() if v is not None})


@pytest.mark.parametrize("wavelengths, want", [
    ([1e-4, 1.5e-5], "short cut-off 1.5e-05 m is below two cells"),
    ([2e-4, 2e-5], "roll-off 0.0002 m is longer than the grid's side 0.00016 m"),
])
def test_rough_wavelengths_against_the_grid(wavelengths, want):
    """A 16^2 grid of 1.6e-4 m sides (cells of 1e-5 m): a cut-off under two cells and a
    roll-off beyond the side are refused when the scene is read."""
    from helpers import make_scene

    geo = {"shape": "rough", "hurst": 0.8, "rms_slope": 0.05, "wavelengths": wavelengths,
           "seed": 0, "form": "sphere", "radius": 0.018}
    with pytest.raises(cp.SceneError, match=want):
        make_scene(geometry=geo, grid={"points": [16, 16], "size": [1.6e-4, 1.6e-4]})


def test_rough_and_surface_scenes_round_trip_through_toml(tmp_path):
    """The stored scene text of a rough and of a measured surface reads back to the same
    scene (same digest), its keys as given; the digest follows the height file's
    content."""
    from helpers import make_scene

    geo = {"shape": "rough", "hurst": 0.7, "rms_height": 1e-7, "wavelengths": [1e-4, 2e-5],
           "seed": 5, "form": "sphere", "radius": 0.018}
    grid = {"points": [16, 16], "size": [1.6e-4, 1.6e-4]}
    a = make_scene(geometry=geo, grid=grid)
    assert cp.Scene.from_toml_text(a.to_toml()).digest() == a.digest()
    path = tmp_path / "s.sdf"
    z = np.add.outer(0.5 * np.arange(8), 0.1 * np.arange(8))       # 8 x 8: the least grid
    write_sdf(path, z, DX, DY)
    surf = {"shape": "surface", "file": str(path), "resample": False, "missing": "fill"}
    b = make_scene(geometry=surf, grid={"points": [8, 8], "size": [8 * DX * 1e-6,
                                                                    8 * DY * 1e-6]})
    again, before = cp.Scene.from_toml_text(b.to_toml()), b.digest()
    assert again.geometry == b.geometry and again.digest() == before
    write_sdf(path, z + 1.0, DX, DY)
    assert cp.Scene.from_toml_text(b.to_toml()).digest() != before
