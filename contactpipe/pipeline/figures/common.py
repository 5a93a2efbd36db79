"""What the figures share: an input opened one way (archive, stress file or sweep
folder), the closed form an archive admits, time labels, scales and rows."""
from __future__ import annotations

import contextlib
import math
import os
import pathlib

import numpy as np
import xarray as xr

from ... import analytic
from ...exceptions import ArchiveError, ContactpipeError
from ...materials import composite_modulus
from ...post.stress import is_stress_file, open_stress
from ..compare import load_dataset
from ..compare.reference import ClosedForm, closed_form_for, closed_form_solution
from ..inputs import radius_of_area, scene_of
from ..sweep.combine import open_sweep

__all__ = ["input_kind", "open_input", "has_tangential_load", "figure_applies",
           "is_rough_archive"]

KINDS = ("profiles", "maps", "hysteresis", "radii")
INPUTS = {
    "archive": ("an archive", KINDS + ("wear", "rough", "all")),
    "stress": ("a stress file", ("stress",)),
    "sweep": ("a sweep folder", ("sweep", "fretting-map")),
}
CLOSED_STYLE = {"color": "k", "ls": "--", "lw": 1.1, "zorder": 4}


# --------------------------------------------------------------------------- inputs

def input_kind(path) -> str:
    """What a figure input is: ``"sweep"`` (a folder), ``"stress"`` (a netCDF file holding
    a stress field, :func:`contactpipe.post.stress.is_stress_file`) or ``"archive"`` (anything
    else; opening it says when it is not one)."""
    path = pathlib.Path(path)
    if path.is_dir():
        return "sweep"
    return "stress" if is_stress_file(path) else "archive"


@contextlib.contextmanager
def open_input(path, expect: str | None = None):
    """Open a figure input: yields (kind, Dataset) and closes it after.

    An archive is opened verified (:func:`contactpipe.open_archive`), a stress file
    verified too (:func:`contactpipe.post.stress.open_stress`: NaN, inf and checksum errors
    refused), a sweep folder by :func:`open_sweep`; all lazily.

    Raises
    ------
    ArchiveError
        The input cannot be opened, or it is not of the kind ``expect`` (a key of
        :data:`INPUTS`).
    """
    kind = input_kind(path)
    if expect is not None and kind != expect:
        raise ArchiveError(f"{path} is {INPUTS[kind][0]}, not {INPUTS[expect][0]}")
    opener = {"archive": lambda p: load_dataset(p)[0],
              "stress": lambda p: open_stress(p, verify=True), "sweep": open_sweep}[kind]
    ds = opener(path)
    try:
        yield kind, ds
    finally:
        ds.close()


@contextlib.contextmanager
def _opened(obj, expect: str):
    """The Dataset of ``obj``: a Dataset as it is, or a path opened by :func:`open_input`
    as ``expect`` (and closed after)."""
    if isinstance(obj, xr.Dataset):
        yield obj
        return
    if not isinstance(obj, (str, os.PathLike)):
        raise ArchiveError(f"expected a path or an xarray.Dataset, got {type(obj).__name__}")
    with open_input(obj, expect) as (_, ds):
        yield ds


def _dataset(obj):
    """The archive ``obj`` (a Dataset or a path), closed after if opened here."""
    return _opened(obj, "archive")


# --------------------------------------------------------------------------- helpers


def _frictional(ds) -> bool:
    return all(v in ds for v in ("q1", "T1", "omega1"))


def has_tangential_load(ds) -> bool:
    """True for a frictional archive (q1, T1, omega1) whose T1 is not all zero: the
    archives whose fretting loop :func:`plot_hysteresis` draws."""
    return _frictional(ds) and bool(np.any(np.abs(np.asarray(ds["T1"].values)) > 0))


def is_rough_archive(ds) -> bool:
    """True for the archive of a rough or measured surface: it holds the initial gap
    ``h0`` (written for ``geometry.shape = "rough"`` or ``"surface"``)."""
    return "h0" in ds.data_vars


def figure_applies(kind: str, ds) -> bool:
    """Whether the figure ``kind`` (one of :data:`KINDS`, ``wear`` or ``rough``) applies to
    an archive: the fretting loop needs a tangential load, the wear figure a wear run (a
    ``cycle`` dimension), the rough figure an initial gap ``h0``, the others always
    apply."""
    if kind == "wear":
        return "cycle" in ds.dims
    if kind == "rough":
        return is_rough_archive(ds)
    return has_tangential_load(ds) if kind == "hysteresis" else True


def _window(ds):
    """(t0, tau) [s]: the start and length of the load window."""
    t = np.asarray(ds["time"].values, float)
    try:
        scene = scene_of(ds)
        tk = scene.load.knots()[0]
        t0, tau = float(tk[0]), float(tk[-1] - tk[0])
    except ArchiveError:
        t0, tau = float(t[0]), float(t[-1] - t[0])
    return t0, tau


def _time_label(ds, k):
    t0, tau = _window(ds)
    t = float(ds["time"].values[k])
    if tau > 0:
        return f"t/τ = {(t - t0) / tau:.3g}"
    return f"t = {t:.3g} s"


def _scales(ds):
    """(pH [Pa], aH [m], names): Hertz peak pressure and radius with instantaneous moduli.

    Sphere: Hertz; ellipsoid: p0 and the semi-axis along x1; flat punch: the mean
    pressure W / (pi a^2) and the punch radius; a surface: the largest pressure and the
    radius of the largest contact area.
    """
    try:
        scene = scene_of(ds)
    except ArchiveError:
        scene = None
    if scene is not None and scene.geometry.shape not in ("surface", "rough"):
        W = float(np.max(scene.load.knots()[1]))
        b1, b2 = scene.indenter.body(), scene.halfspace.body()
        phi = [b.creep.phi0 if b.kind == "viscoelastic" and b.creep.phi0 > 0 else 1.0
               for b in (b1, b2)]
        e_star = composite_modulus(b1, b2, *phi)
        geo = scene.geometry
        if geo.shape == "flat_punch":
            a = geo.radius
            return W / (math.pi * a * a), a, ("p_m", "a")
        if np.isfinite(e_star):
            if geo.shape == "sphere":
                h = analytic.hertz_sphere(W, geo.radius, e_star)
                return h.max_pressure, h.contact_radius, ("p_H", "a_H")
            h = analytic.hertz_ellipsoid(W, geo.radii, e_star)
            return h.max_pressure, h.semi_axes[0], ("p_H", "a_H")
    pmax = float(ds["p"].max())
    amax = radius_of_area(float(ds["contact_area"].max()))
    return (pmax if pmax > 0 else 1.0), (amax if amax > 0 else 1.0), ("p_max", "a_max")


def _profile(da, k, rows):
    """A field's profile along x1 through the centre at instant k."""
    return np.asarray(da.isel(time=k, x2=rows).values, float).reshape(da.sizes["x1"], -1) \
        .mean(axis=1)


def _index(ds, instant) -> int:
    """An instant as an index: an int (negative from the end) or a time [s] (a float,
    the nearest instant)."""
    n = ds.sizes["time"]
    if isinstance(instant, (bool, np.bool_)) or not isinstance(
            instant, (int, np.integer, float, np.floating)):
        raise ValueError(f"instant {instant!r}: expected an index (int) or a time [s] "
                         f"(float)")
    if isinstance(instant, (float, np.floating)):
        t = np.asarray(ds["time"].values, float)
        return int(np.argmin(np.abs(t - float(instant))))
    k = int(instant)
    if not -n <= k < n:
        raise ValueError(f"instant {k} is out of range: the archive has {n} instants "
                         f"(0 to {n - 1}, or negative from the end)")
    return k % n


def _default_instants(ds, count=5):
    """About ``count`` instants spread over the run, the turning points of T1 and the
    last instant included (an unloaded first instant, with no shear, is left out)."""
    n = ds.sizes["time"]
    if n <= count:
        return list(range(n))
    chosen = {n - 1}
    shear_from_zero = False
    if "T1" in ds:
        T = np.asarray(ds["T1"].values, float)
        d = np.sign(np.diff(T))
        turning = [i for i in range(1, n - 1) if d[i - 1] != 0 and d[i] != 0
                   and d[i] != d[i - 1]]
        if len(turning) >= count:
            turning = [turning[int(j)] for j in
                       np.linspace(0, len(turning) - 1, count - 1).round()]
        chosen.update(turning)
        shear_from_zero = bool(np.any(T != 0)) and T[0] == 0
    grid = np.linspace(0, n - 1, count + 1)[1:] if shear_from_zero else \
        np.linspace(0, n - 1, count)
    candidates = sorted(set(int(k) for k in grid.round()) - chosen)
    while len(chosen) < count and candidates:      # the candidate farthest from the rest
        best = max(candidates, key=lambda c: min(abs(c - k) for k in chosen))
        chosen.add(best)
        candidates.remove(best)
    return sorted(chosen)


def _solution(ds) -> ClosedForm | None:
    """The closed form to draw, or None (none applies, or it cannot be built)."""
    try:
        if closed_form_for(ds) is None:
            return None
        return closed_form_solution(ds)
    except (ContactpipeError, ValueError):
        return None


def _scene_title(ds) -> str:
    try:
        return scene_of(ds).name
    except ArchiveError:
        return str(ds.attrs.get("title", "archive"))
