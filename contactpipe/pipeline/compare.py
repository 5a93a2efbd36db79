"""Compare an archive with the closed form its scene admits, or with another archive.

``contactpipe compare ARCHIVE.nc`` checks a simulation against the closed-form solution
of its scene (:func:`closed_form_for` says which one applies); ``contactpipe compare
ARCHIVE.nc REFERENCE.nc`` interpolates a reference archive onto the archive's instants and
cells and compares every variable the two share. Either way the result is an error table,
an :class:`xarray.Dataset` over ``time`` (written as netCDF or CSV with ``-o``).

Closed forms (all from :mod:`contactpipe.analytic`):

``hertz``
    sphere or ellipsoid, both bodies elastic or rigid, no shear (mu = 0, or no tangential
    load on a pair with Dundurs beta = 0), constant W.
``flat_punch``
    the same with a flat punch (pressure averaged exactly over each cell).
``lee_radok``
    a rigid sphere on a viscoelastic body (or the reverse), no shear, a normal force that
    never decreases (a step load in the usual case): contact radius a(t) from the
    hereditary integral; the pressure as well under a step load with phi(0) > 0.
``mindlin_deresiewicz``
    a sphere, both bodies elastic or rigid with beta = 0, mu > 0, a tangential load along
    x1 that starts from 0, constant W: Hertz pressure, the Cattaneo-Mindlin traction of
    the tangential force history after Masing's rules (the history is the archive's own
    T1 series), the stick radius, the tangential compliance loop omega1(T1) and the
    dissipated energy (an Iwan model with the same virgin curve, exact for every Masing
    history: it reproduces Johnson's energy per cycle, eq. 7.64).

Error variables (over ``time`` unless said otherwise): ``err_p_max``, ``err_p_rms``,
``err_contact_radius``, ``err_omega3`` for every closed form (Lee-Radok under a growing
load: no pressure errors); for Mindlin-Deresiewicz also ``err_q1_max`` (leaving out the
cells within one cell of a current or remembered stick/slip circle),
``err_q1_max_interior`` (also leaving out those within one cell of the contact edge,
where q1 = mu p repeats the edge cells' pressure error), ``err_q1_max_all`` (every cell),
``err_q1_rms``, ``err_stick_radius_cells``, ``err_omega1`` and the scalar
``err_dissipation`` (at the last instant). Against a reference archive:
``err_<field>_max`` and ``err_<field>_rms`` per shared field, ``err_status``,
``err_<series>`` per shared series, ``err_contact_radius``, ``err_stick_radius_cells``
and ``err_dissipation``.

Errors are dimensionless: tractions relative to the closed form's peak pressure p0 (the
shear relative to mu p0), radii relative to the closed-form radius, the stick radius in
cells, omega1 relative to the amplitude of the closed-form loop. Closed-form fields are
averaged over each cell (:func:`contactpipe.analytic.cell_average`), which is what a
piecewise-constant traction should match.
"""
from __future__ import annotations

import argparse
import math
import os
import pathlib

import numpy as np
import xarray as xr

from .. import analytic
from ..exceptions import ArchiveError, SceneError
from ..files import atomic_path

__all__ = ["closed_form_for", "compare", "ClosedForm", "closed_form_solution",
           "load_dataset", "add_arguments", "main", "CLOSED_FORMS"]

CLOSED_FORMS = ("hertz", "flat_punch", "lee_radok", "mindlin_deresiewicz")
FIELD = ("time", "x1", "x2")
#: Solver diagnostics: not compared between archives.
DIAGNOSTICS = ("iterations", "fft_pairs", "coupling_passes")
TRACTIONS = ("p", "q1", "q2")
#: Jenkins elements of the Iwan model behind the closed-form dissipation.
IWAN_ELEMENTS = 100_000
#: Radial samples of the tabulated Lee-Radok pressure, and its time steps.
LEE_RADOK_SAMPLES = 1500
LEE_RADOK_STEPS = 1000


# --------------------------------------------------------------------------- inputs

def load_dataset(archive) -> tuple[xr.Dataset, str]:
    """(Dataset, label) of an archive given as a path or a Dataset.

    Raises
    ------
    ArchiveError
        The path is missing, unreadable or not an archive, or ``archive`` is neither.
    """
    if isinstance(archive, xr.Dataset):
        return archive, str(archive.attrs.get("title", "dataset"))
    if isinstance(archive, (str, os.PathLike)):
        from ..archive import open_archive
        return open_archive(archive, verify=True), str(archive)
    raise ArchiveError(f"expected an archive path or an xarray.Dataset, got "
                       f"{type(archive).__name__}")


def _scene_of(ds):
    """The Scene of an archive (or a Scene, or a path)."""
    from ..scene import Scene
    if isinstance(ds, Scene):
        return ds
    if isinstance(ds, (str, os.PathLike)):
        ds, _ = load_dataset(ds)
    text = ds.attrs.get("scene") if isinstance(ds, xr.Dataset) else None
    if not isinstance(text, str):
        raise ArchiveError("the dataset has no 'scene' attribute (the scene as TOML text): "
                           "not a contactpipe archive")
    try:
        return Scene.from_toml_text(text)
    except SceneError as err:
        raise ArchiveError(f"the archive's 'scene' attribute is not a valid scene: {err}") \
            from None


def _load_facts(scene):
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    t, W, T1, T2 = scene.load.knots()
    return b1, b2, t, W, T1, T2


def _diagnose(scene) -> tuple[str | None, dict]:
    """The closed form a scene admits, and for each candidate why it does not apply."""
    from ..planning import pair_couples
    b1, b2, t, W, T1, T2 = _load_facts(scene)
    shape = scene.geometry.shape
    mu = float(scene.friction.mu)
    has_t = bool(np.any(T1 != 0) or np.any(T2 != 0))
    couples = pair_couples(b1, b2)
    kinds = (b1.kind, b2.kind)
    elastic = all(k in ("rigid", "elastic") for k in kinds)
    constant_w = bool(np.all(W == W[0]))
    shear_free = mu == 0 or (not has_t and not couples)
    mat = f"indenter.material = {kinds[0]!r}, halfspace.material = {kinds[1]!r}"
    shear_why = ("shear: friction.mu = {:g} with {}".format(
        mu, "a tangential load" if has_t else "a coupled pair (Dundurs beta != 0)"))
    why = {}

    def need(name, conds):
        bad = [msg for ok, msg in conds if not ok]
        if bad:
            why[name] = bad
        return not bad

    if need("hertz", [
            (shape in ("sphere", "ellipsoid"), f"needs a sphere or an ellipsoid, got "
                                               f"geometry.shape = {shape!r}"),
            (elastic, f"needs elastic or rigid bodies, got {mat}"),
            (shear_free, f"needs no shear, got {shear_why}"),
            (constant_w, "needs a constant load.normal_force")]):
        return "hertz", why
    if need("flat_punch", [
            (shape == "flat_punch", f"needs geometry.shape = 'flat_punch', got {shape!r}"),
            (elastic, f"needs elastic or rigid bodies, got {mat}"),
            (shear_free, f"needs no shear, got {shear_why}"),
            (constant_w, "needs a constant load.normal_force")]):
        return "flat_punch", why
    one_rigid_one_visco = sorted(kinds) == ["rigid", "viscoelastic"]
    if need("lee_radok", [
            (shape == "sphere", f"needs a sphere, got geometry.shape = {shape!r}"),
            (one_rigid_one_visco, f"needs a rigid body on a viscoelastic one, got {mat}"),
            (not has_t, "needs no tangential load"),
            (shear_free, f"needs no shear, got {shear_why}"),
            (bool(np.all(np.diff(W) >= 0)), "needs a normal force that never decreases "
                                             "(a shrinking contact is Ting's problem)")]):
        return "lee_radok", why
    if need("mindlin_deresiewicz", [
            (shape == "sphere", f"needs a sphere, got geometry.shape = {shape!r}"),
            (elastic, f"needs elastic or rigid bodies, got {mat}"),
            (not couples, "needs Dundurs beta = 0 (identical materials, or incompressible)"),
            (mu > 0, "needs friction.mu > 0"),
            (has_t, "needs a tangential load"),
            (not np.any(T2 != 0), "needs the tangential load along x1 (T2 = 0)"),
            (T1[0] == 0, f"needs the tangential load to start from 0, got "
                         f"{T1[0]:g} N at time[0]"),
            (constant_w, "needs a constant load.normal_force")]):
        return "mindlin_deresiewicz", why
    return None, why


def closed_form_for(ds) -> str | None:
    """Which closed form the archive's scene admits.

    Parameters
    ----------
    ds : xarray.Dataset, path or Scene
        An archive (its ``scene`` attribute is read), or a scene.

    Returns
    -------
    {"hertz", "flat_punch", "lee_radok", "mindlin_deresiewicz"} or None
        See the module docstring for the conditions of each.
    """
    return _diagnose(_scene_of(ds))[0]


def _no_closed_form_message(scene, why, label) -> str:
    reasons = "; ".join(f"{name} {', '.join(msgs)}" for name, msgs in why.items())
    return (f"{label}: no closed form applies to scene {scene.name!r} ({reasons}); "
            f"compare it with a reference archive instead: contactpipe compare ARCHIVE.nc "
            f"REFERENCE.nc")


# --------------------------------------------------------------------------- closed forms

def _grid(ds):
    x1 = np.asarray(ds["x1"].values, float)
    x2 = np.asarray(ds["x2"].values, float)
    sp = ds.attrs.get("grid_spacing_m")
    if x1.size > 1 and x2.size > 1:
        d1, d2 = float(x1[1] - x1[0]), float(x2[1] - x2[0])
    elif sp is not None and np.size(sp) == 2:
        d1, d2 = (float(v) for v in np.asarray(sp).ravel())
    else:
        scene = _scene_of(ds)
        d1, d2 = scene.resolved_grid().spacing()
    return x1, x2, d1, d2


def cell_average_field(f, x1, x2, d1, d2, radius=np.inf, order=8, rows=64):
    """Cell averages of a field ``f(x1, x2)`` [any unit] on the grid ``x1`` x ``x2``.

    Only cells that come within ``radius`` [m] of the origin are evaluated (the others
    are 0); rows are processed in blocks to bound memory.
    """
    x1 = np.asarray(x1, float)
    x2 = np.asarray(x2, float)
    out = np.zeros((x1.size, x2.size))
    n1 = np.maximum(np.abs(x1) - 0.5 * d1, 0.0)
    n2 = np.maximum(np.abs(x2) - 0.5 * d2, 0.0)
    rows_in = np.flatnonzero(n1 < radius)
    cols_in = np.flatnonzero(n2 < radius)
    if rows_in.size == 0 or cols_in.size == 0:
        return out
    c0, c1 = cols_in[0], cols_in[-1] + 1
    for start in range(rows_in[0], rows_in[-1] + 1, rows):
        stop = min(start + rows, rows_in[-1] + 1)
        out[start:stop, c0:c1] = analytic.cell_average(
            f, x1[start:stop, None], x2[None, c0:c1], d1, d2, order=order)
    return out


def _iwan_dissipation(omega, mu_w, delta_max, n=IWAN_ELEMENTS):
    """Dissipated energy [J] after each sample of a tangential displacement history.

    An Iwan model (parallel Jenkins elements) with Mindlin's virgin curve
    ``T = mu W [1 - (1 - delta/delta_max)^(3/2)]``: with ``s = delta_max (1 - v^2)`` the
    elements' stiffness is uniform in v in [0, 1] (total 3 mu W / (2 delta_max)). It
    follows Masing's rules exactly, so its force-displacement loops are those of
    Mindlin-Deresiewicz; an element slips a known distance between monotonic samples.
    """
    v = (np.arange(n) + 0.5) / n
    s = delta_max * (1.0 - v * v)
    k = 1.5 * mu_w / (delta_max * n)
    f = k * s
    e = np.zeros(n)
    prev, total = 0.0, 0.0
    out = np.empty(len(omega))
    for i, w in enumerate(omega):
        trial = e + (w - prev)
        slipped = np.maximum(np.abs(trial) - s, 0.0)
        e = np.clip(trial, -s, s)
        total += float(f @ slipped)
        prev = w
        out[i] = total
    return out


class ClosedForm:
    """The closed-form solution of an archive's scene at the archive's instants.

    Built by :func:`closed_form_solution`. Methods take the instant index ``k`` of the
    archive; positions in m.

    Attributes
    ----------
    name : str
        One of :data:`CLOSED_FORMS`.
    scene : Scene
    times : ndarray
        The archive's instants [s].
    normal_force : float
        W [N] (the largest, for a growing load).
    """

    def __init__(self, name, scene, ds):
        from ..materials import composite_modulus
        self.name = name
        self.scene = scene
        self.times = np.asarray(ds["time"].values, float)
        b1, b2, tk, W, T1, _ = _load_facts(scene)
        self._knots = (tk, W)
        self.t0 = float(tk[0])
        self.window = float(tk[-1] - tk[0])
        self.normal_force = float(np.max(W))
        self.mu = float(scene.friction.mu)
        geo = scene.geometry
        self.hertz = self.punch = None
        self.has_pressure = True
        self._lr_cache = {}
        if name in ("hertz", "mindlin_deresiewicz"):
            e_star = composite_modulus(b1, b2)
            if geo.shape == "sphere":
                self.hertz = analytic.hertz_sphere(self.normal_force, geo.radius, e_star)
            else:
                self.hertz = analytic.hertz_ellipsoid(self.normal_force, geo.radii, e_star)
        elif name == "flat_punch":
            self.punch = analytic.flat_punch(self.normal_force, geo.radius,
                                             composite_modulus(b1, b2))
        elif name == "lee_radok":
            self.body = b2 if b2.kind == "viscoelastic" else b1
            self.radius = geo.radius
            self._a = analytic.lee_radok_radius(
                self.times, tk, W, geo.radius, self.body.young, self.body.poisson,
                self.body.creep)
            self.step_load = bool(np.all(W == W[0]))
            self.has_pressure = self.step_load and self.body.creep.phi0 > 0
        if name == "mindlin_deresiewicz":
            self._setup_md(ds, b1, b2)

    # -- Mindlin-Deresiewicz -------------------------------------------------------------

    def _setup_md(self, ds, b1, b2):
        scene = self.scene
        t_mesh, _, T_mesh, _ = scene.instants()
        t_mesh = np.atleast_1d(t_mesh)
        T_mesh = np.broadcast_to(np.asarray(T_mesh, float), t_mesh.shape).copy()
        mu_w = self.mu * self.normal_force
        if "T1" in ds and ds.sizes["time"] == t_mesh.size:
            # the archive's own history, snapped to the program where they agree: the
            # solver's round-off must not read a hold as a reversal (Masing memory)
            T_arch = np.asarray(ds["T1"].values, float)
            T_mesh = np.where(np.abs(T_arch - T_mesh) <= 1e-9 * mu_w, T_mesh, T_arch)
        idx = np.searchsorted(t_mesh, self.times - 1e-9 * max(self.window, 1e-300))
        idx = np.clip(idx, 0, t_mesh.size - 1)
        if not np.allclose(t_mesh[idx], self.times, rtol=0,
                           atol=1e-9 * max(self.window, 1.0)):
            raise ArchiveError("the archive's instants are not on its scene's time mesh; "
                               "cannot rebuild the tangential force history")
        self._T = np.clip(T_mesh, -mu_w, mu_w)
        self._idx = idx
        h = self.hertz
        self.compliance = analytic.tangential_compliance_sum(
            b1.young, b1.poisson, b2.young, b2.poisson)
        omega = analytic.tangential_displacement(self._T, self.mu, self.normal_force,
                                                 h.contact_radius, self.compliance,
                                                 all_instants=True)
        self._omega = omega
        delta_max = 3.0 * mu_w * self.compliance / (16.0 * h.contact_radius)
        self._dissipation = (_iwan_dissipation(omega, mu_w, delta_max)
                             if delta_max > 0 else np.zeros_like(omega))

    def history(self, k):
        """Tangential force samples [N] up to instant ``k`` (Mindlin-Deresiewicz)."""
        return self._T[:self._idx[k] + 1]

    def tangential_force(self, k):
        """T1 [N] at instant ``k`` (Mindlin-Deresiewicz)."""
        return float(self._T[self._idx[k]])

    def boundaries(self, k):
        """Radii [m] of the current and remembered stick/slip circles at instant ``k``."""
        if self.name != "mindlin_deresiewicz":
            return []
        rev, t = analytic.masing_memory(self.history(k))
        points = list(rev) + [t]
        forces = [rev[0]] + [0.5 * (b - a) for a, b in zip(points, points[1:])] \
            if rev else [t]
        mu_w = self.mu * self.normal_force
        a = self.hertz.contact_radius
        return [a * max(1.0 - abs(f) / mu_w, 0.0) ** (1.0 / 3.0) for f in forces if f != 0]

    # -- fields ----------------------------------------------------------------------------

    def p0(self, k=0):
        """Peak pressure [Pa] the errors are relative to (flat punch: mean pressure)."""
        if self.hertz is not None:
            return self.hertz.max_pressure
        if self.punch is not None:
            return self.punch.normal_force / (np.pi * self.punch.contact_radius ** 2)
        if self.has_pressure:
            return float(self._lr_table(k)[1][0])
        a = self._a[k]
        return 3.0 * self._load_at(k) / (2.0 * np.pi * a * a) if a > 0 else np.nan

    def _load_at(self, k):
        tk, W = self._knots
        return float(np.interp(self.times[k], tk, W))

    def _lr_table(self, k):
        if k not in self._lr_cache:
            b = self.body
            r = np.linspace(0.0, 1.05 * float(np.max(self._a)), LEE_RADOK_SAMPLES)
            p = analytic.lee_radok_pressure(r, self.times[k] - self.t0, self.normal_force,
                                            self.radius, b.young, b.poisson, b.creep,
                                            n_steps=LEE_RADOK_STEPS)
            self._lr_cache[k] = (r, p)
        return self._lr_cache[k]

    def has_field_pressure(self) -> bool:
        return self.name != "lee_radok" or self.has_pressure

    def pressure(self, k, x1, x2):
        """Closed-form pressure [Pa] at positions (x1, x2) [m] (broadcast) at instant k."""
        x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
        if self.hertz is not None:
            if isinstance(self.hertz, analytic.HertzSphere):
                return self.hertz.pressure(np.hypot(x1, x2))
            return self.hertz.pressure(x1, x2)
        if self.punch is not None:
            return self.punch.pressure(np.hypot(x1, x2))
        if not self.has_pressure:
            raise ArchiveError("no closed-form pressure for this Lee-Radok scene (a growing "
                               "load, or phi(0) = 0): only the contact radius")
        r, p = self._lr_table(k)
        return np.interp(np.hypot(x1, x2), r, p, right=0.0)

    def shear(self, k, x1, x2):
        """Closed-form q1 [Pa] at (x1, x2) [m] at instant k (0 without shear)."""
        x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
        if self.name != "mindlin_deresiewicz":
            return np.zeros(x1.shape)
        h = self.hertz
        return analytic.mindlin_deresiewicz_traction(
            np.hypot(x1, x2), self.history(k), self.mu, self.normal_force,
            h.contact_radius, h.max_pressure)

    def cell_pressure(self, k, x1, x2, d1, d2):
        """Cell averages of the pressure [Pa] on the grid x1 x x2 (1-D, m)."""
        if self.punch is not None:
            return self.punch.cell_average_pressure(x1[:, None], x2[None, :], d1, d2)
        reach = self.contact_radius(k) if self.hertz is None else \
            max(getattr(self.hertz, "semi_axes", (self.hertz_radius(),) * 2))
        return cell_average_field(lambda a, b: self.pressure(k, a, b), x1, x2, d1, d2,
                                  radius=1.05 * reach)

    def cell_shear(self, k, x1, x2, d1, d2):
        """Cell averages of q1 [Pa] on the grid (Mindlin-Deresiewicz)."""
        return cell_average_field(lambda a, b: self.shear(k, a, b), x1, x2, d1, d2,
                                  radius=self.hertz.contact_radius)

    # -- series ----------------------------------------------------------------------------

    def hertz_radius(self):
        h = self.hertz
        return h.contact_radius if isinstance(h, analytic.HertzSphere) \
            else h.equivalent_radius

    def contact_radius(self, k):
        """Radius [m] of the circle of the closed-form contact area at instant k."""
        if self.hertz is not None:
            return self.hertz_radius()
        if self.punch is not None:
            return self.punch.contact_radius
        return float(self._a[k])

    def approach(self, k):
        """Normal approach omega3 [m] at instant k."""
        if self.hertz is not None:
            return self.hertz.approach
        if self.punch is not None:
            return self.punch.approach
        return float(self._a[k]) ** 2 / self.radius

    def stick_radius(self, k):
        """Radius [m] of the current stick zone (Mindlin-Deresiewicz), else NaN."""
        if self.name != "mindlin_deresiewicz":
            return np.nan
        return analytic.stick_radius(self.history(k), self.mu, self.normal_force,
                                     self.hertz.contact_radius)

    def omega1(self):
        """Tangential rigid displacement [m] at every archive instant (MD), else None."""
        return None if self.name != "mindlin_deresiewicz" else self._omega[self._idx]

    def loop(self, per_step=8):
        """(T1 [N], omega1 [m]) of the closed-form loop, ``per_step`` samples per archive
        step, up to the last instant (Mindlin-Deresiewicz), else None."""
        if self.name != "mindlin_deresiewicz":
            return None
        hist = self._T[:self._idx[-1] + 1]
        fine = np.concatenate([hist[:1]] + [np.linspace(a, b, per_step + 1)[1:]
                                            for a, b in zip(hist[:-1], hist[1:])])
        omega = analytic.tangential_displacement(fine, self.mu, self.normal_force,
                                                 self.hertz.contact_radius, self.compliance,
                                                 all_instants=True)
        return fine, omega

    def dissipation(self):
        """Dissipated energy [J] at every archive instant (MD), else None."""
        return None if self.name != "mindlin_deresiewicz" else self._dissipation[self._idx]


def closed_form_solution(ds, label=None) -> ClosedForm:
    """The :class:`ClosedForm` of an archive; a clear error when none applies.

    Raises
    ------
    SceneError
        The scene admits no closed form (the message says, for each candidate, why).
    """
    scene = _scene_of(ds)
    name, why = _diagnose(scene)
    if name is None:
        raise SceneError(_no_closed_form_message(scene, why, label or "archive"))
    return ClosedForm(name, scene, ds)


# --------------------------------------------------------------------------- comparisons

class _Frames:
    """The instants of a (time, x1, x2) variable, read in blocks of time (bounded memory,
    one read per block of a lazy archive instead of one per instant)."""

    def __init__(self, da, budget=64 * 2 ** 20):
        self.da = da
        per = max(1, da.sizes.get("x1", 1) * da.sizes.get("x2", 1) * 8)
        self.block = int(max(1, min(da.sizes["time"], budget // per)))
        self.start = None
        self.data = None

    def __getitem__(self, k):
        if self.data is None or not self.start <= k < self.start + len(self.data):
            self.start = (k // self.block) * self.block
            self.data = np.asarray(
                self.da.isel(time=slice(self.start, self.start + self.block)).values, float)
        return self.data[k - self.start]


def _nanmax(a):
    a = np.asarray(a, float)
    return float(np.nanmax(a)) if a.size and np.any(np.isfinite(a)) else np.nan


def _rms(d, mask):
    d = np.asarray(d, float)[mask]
    d = d[np.isfinite(d)]
    return float(np.sqrt(np.mean(d * d))) if d.size else np.nan


def _rel(num, ref):
    if ref == 0:
        return 0.0 if num == 0 else np.nan
    return abs(num - ref) / abs(ref)


def _radius(area):
    return math.sqrt(max(float(area), 0.0) / math.pi)


def _near(r, radii, width):
    out = np.zeros(r.shape, bool)
    for c in radii:
        out |= np.abs(r - c) <= width
    return out


def _compare_closed_form(ds, label):
    sol = closed_form_solution(ds, label)
    x1, x2, d1, d2 = _grid(ds)
    cell = math.sqrt(d1 * d2)
    r = np.hypot(x1[:, None], x2[None, :])
    nt = ds.sizes["time"]
    md = sol.name == "mindlin_deresiewicz"
    cols = {k: np.full(nt, np.nan) for k in
            ("err_p_max", "err_p_rms", "err_contact_radius", "err_omega3")}
    if md:
        for k in ("err_q1_max", "err_q1_max_interior", "err_q1_max_all", "err_q1_rms",
                  "err_stick_radius_cells", "err_omega1"):
            cols[k] = np.full(nt, np.nan)
    area = np.asarray(ds["contact_area"].values, float)
    omega3 = np.asarray(ds["omega3"].values, float)
    frames_p = _Frames(ds["p"])
    frames_q = _Frames(ds["q1"]) if md else None
    stick_area = np.asarray(ds["stick_area"].values, float) if md else None
    p_ref_static = None
    for k in range(nt):
        cols["err_contact_radius"][k] = _rel(_radius(area[k]), sol.contact_radius(k))
        cols["err_omega3"][k] = _rel(omega3[k], sol.approach(k))
        if sol.has_field_pressure():
            if sol.name in ("hertz", "mindlin_deresiewicz", "flat_punch"):
                if p_ref_static is None:            # constant W: the same at every instant
                    p_ref_static = sol.cell_pressure(0, x1, x2, d1, d2)
                p_ref = p_ref_static
            else:
                p_ref = sol.cell_pressure(k, x1, x2, d1, d2)
            p = frames_p[k]
            p0 = sol.p0(k)
            contact = (p > 0) | (p_ref > 0)
            dp = np.abs(p - p_ref)
            cols["err_p_max"][k] = _nanmax(dp) / p0
            cols["err_p_rms"][k] = _rms(dp, contact) / p0
        if md:
            q = frames_q[k]
            q_ref = sol.cell_shear(k, x1, x2, d1, d2)
            scale = sol.mu * sol.p0()
            dq = np.abs(q - q_ref)
            contact = (frames_p[k] > 0) | (p_ref_static > 0)
            away = ~_near(r, sol.boundaries(k), cell)
            inner = away & ~_near(r, [sol.hertz.contact_radius], cell)
            cols["err_q1_max_all"][k] = _nanmax(dq) / scale
            cols["err_q1_max"][k] = _nanmax(np.where(away, dq, np.nan)) / scale
            cols["err_q1_max_interior"][k] = _nanmax(np.where(inner, dq, np.nan)) / scale
            cols["err_q1_rms"][k] = _rms(dq, contact) / scale
            c_num = _radius(stick_area[k])
            cols["err_stick_radius_cells"][k] = abs(c_num - sol.stick_radius(k)) / cell
    if not sol.has_field_pressure():
        del cols["err_p_max"], cols["err_p_rms"]
    scalars = {}
    if md:
        om_ref = sol.omega1()
        amp = float(np.max(np.abs(om_ref)))
        om = np.asarray(ds["omega1"].values, float)
        cols["err_omega1"] = np.abs(om - om_ref) / amp if amp > 0 else np.abs(om - om_ref)
        d_ref = float(sol.dissipation()[-1])
        d_num = float(ds["dissipation"].values[-1])
        scalars["err_dissipation"] = _rel(d_num, d_ref)
    table = _table(ds, cols, scalars)
    table.attrs["closed_form"] = sol.name
    table.attrs["reference"] = f"closed form: {sol.name}"
    radius = sol.contact_radius(nt - 1)
    table.attrs["cells_per_contact_radius"] = float(radius / cell) if radius > 0 else 0.0
    if md:
        table.attrs["q1_exclusion"] = (
            "err_q1_max leaves out cells whose centre lies within one cell of a current "
            "or remembered stick/slip circle; err_q1_max_interior also those within one "
            "cell of the contact edge r = a, where q1 = mu p repeats the pressure error "
            "of the cells the edge cuts (err_p_max)")
    return table


def _bracket(x, xs, tol):
    """(j0, j1, w) with x = (1 - w) xs[j0] + w xs[j1], or None outside xs."""
    if xs.size == 1:
        return (0, 0, 0.0) if abs(x - xs[0]) <= tol else None
    if x < xs[0] - tol or x > xs[-1] + tol:
        return None
    j = int(np.searchsorted(xs, x))
    if j < xs.size and abs(xs[j] - x) <= tol:
        return j, j, 0.0
    if j > 0 and abs(xs[j - 1] - x) <= tol:
        return j - 1, j - 1, 0.0
    j = min(max(j, 1), xs.size - 1)
    w = (x - xs[j - 1]) / (xs[j] - xs[j - 1])
    return j - 1, j, float(w)


def _time_map(ds, ref):
    """Per archive instant, where it falls among the reference's instants, and how."""
    t = np.asarray(ds["time"].values, float)
    tr = np.asarray(ref["time"].values, float)
    span = max(float(t[-1] - t[0]), float(tr[-1] - tr[0]), 1e-300)
    tol = 1e-9 * span
    same_window = abs(t[0] - tr[0]) <= tol and abs(t[-1] - tr[-1]) <= tol
    if same_window:
        axis, x, xs = "time", t, tr
    else:
        def norm(v):
            w = v[-1] - v[0]
            return (v - v[0]) / w if w > 0 else np.zeros_like(v)
        axis, x, xs = "t_norm", norm(t), norm(tr)
        tol = 1e-9
    return axis, [_bracket(v, xs, tol) for v in x]


def _at(frames, where, nearest=False):
    """A reference field at a bracket (j0, j1, w) of its instants."""
    j0, j1, w = where
    if nearest:
        w = 0.0 if w < 0.5 else 1.0
    if w == 0.0:
        return frames[j0]
    if w == 1.0:
        return frames[j1]
    return (1.0 - w) * frames[j0] + w * frames[j1]


def _absmax(da) -> float:
    """max |da| [its unit], read in blocks of time (a lazy field never loaded whole)."""
    if "time" not in da.dims or da.ndim == 1:
        vals = np.abs(np.asarray(da.values, float))
        return float(np.nanmax(vals)) if vals.size else 0.0
    frames = _Frames(da)
    out = 0.0
    for start in range(0, da.sizes["time"], frames.block):
        frames[start]                              # loads the block that starts there
        if frames.data.size:
            out = max(out, float(np.nanmax(np.abs(frames.data))))
    return out


def _scale(ds, ref, name):
    """The scale errors of ``name`` are relative to: max |reference| (tractions: max p)."""
    base = "p" if name in TRACTIONS else name
    for src in (ref, ds):
        if base in src:
            s = _absmax(src[base])
            if s > 0 and np.isfinite(s):
                return s
    return 1.0


def _compare_archives(ds, ref, label, ref_label):
    shared = [v for v in ds.data_vars if v in ref.data_vars and v not in DIAGNOSTICS]
    fields = [v for v in shared if ds[v].dims == FIELD and ref[v].dims == FIELD]
    series = [v for v in shared if ds[v].dims == ("time",) and ref[v].dims == ("time",)]
    if not fields and not series:
        raise ArchiveError(f"{label} and {ref_label} share no variable to compare")
    axis, where = _time_map(ds, ref)
    if all(w is None for w in where):
        raise ArchiveError(f"{label}: no instant falls within the reference {ref_label}'s "
                           f"time span (compared on {axis})")
    x1, x2, d1, d2 = _grid(ds)
    same_grid = (ref.sizes["x1"] == x1.size and ref.sizes["x2"] == x2.size
                 and np.allclose(ref["x1"].values, x1, rtol=0, atol=1e-9 * d1)
                 and np.allclose(ref["x2"].values, x2, rtol=0, atol=1e-9 * d2))
    nt = ds.sizes["time"]
    cols = {}
    for v in fields:
        if v == "status":
            cols["err_status"] = np.full(nt, np.nan)
        else:
            cols[f"err_{v}_max"] = np.full(nt, np.nan)
            cols[f"err_{v}_rms"] = np.full(nt, np.nan)
    scales = {}
    for v in fields + series:
        if v != "status":
            base = "p" if v in TRACTIONS else v
            scales[v] = scales[base] if base in scales else _scale(ds, ref, v)
    target = {"x1": xr.DataArray(x1, dims="x1"), "x2": xr.DataArray(x2, dims="x2")}

    def on_grid(arr, nearest=False):
        if same_grid:
            return arr
        da = xr.DataArray(arr, dims=("x1", "x2"),
                          coords={"x1": ref["x1"].values, "x2": ref["x2"].values})
        return da.interp(target, method="nearest" if nearest else "linear").values

    mine_f = {v: _Frames(ds[v]) for v in fields}
    ref_f = {v: _Frames(ref[v]) for v in fields}
    for k in range(nt):
        w = where[k]
        if w is None:
            continue
        p_here = mine_f["p"][k] if "p" in fields else None
        p_ref = on_grid(_at(ref_f["p"], w)) if "p" in fields else None
        contact = None
        if p_here is not None:
            contact = (p_here > 0) | (np.nan_to_num(p_ref) > 0)
        for v in fields:
            mine = mine_f[v][k]
            if v == "status":
                other = on_grid(_at(ref_f[v], w, nearest=True), nearest=True)
                valid = np.isfinite(other) & ((mine > 0) | (other > 0))
                n = int(valid.sum())
                cols["err_status"][k] = float(np.sum(mine[valid] != other[valid])) / n \
                    if n else 0.0
                continue
            other = p_ref if v == "p" else on_grid(_at(ref_f[v], w))
            d = np.abs(mine - other)
            mask = contact if (v in TRACTIONS and contact is not None) else np.ones(d.shape, bool)
            cols[f"err_{v}_max"][k] = _nanmax(d) / scales[v]
            cols[f"err_{v}_rms"][k] = _rms(d, mask) / scales[v]
    ref_series = {}
    for v in series:
        vals = np.asarray(ref[v].values, float)
        ref_series[v] = np.array([np.nan if w is None else
                                  (1 - w[2]) * vals[w[0]] + w[2] * vals[w[1]] for w in where])
        mine = np.asarray(ds[v].values, float)
        cols[f"err_{v}"] = np.abs(mine - ref_series[v]) / scales[v]
    for area, name, rel in (("contact_area", "err_contact_radius", True),
                            ("stick_area", "err_stick_radius_cells", False)):
        if area in ref_series:
            mine = np.asarray(ds[area].values, float)
            out = np.full(nt, np.nan)
            for k in range(nt):
                if np.isfinite(ref_series[area][k]):
                    a, b = _radius(mine[k]), _radius(ref_series[area][k])
                    out[k] = _rel(a, b) if rel else abs(a - b) / math.sqrt(d1 * d2)
            cols[name] = out
    scalars = {}
    if "dissipation" in ref_series:
        last = [k for k in range(nt) if where[k] is not None][-1]
        scalars["err_dissipation"] = _rel(float(ds["dissipation"].values[last]),
                                          float(ref_series["dissipation"][last]))
    table = _table(ds, cols, scalars)
    table.attrs["closed_form"] = "none"
    table.attrs["reference"] = ref_label
    table.attrs["time_axis"] = axis
    table.attrs["interpolated"] = "false" if same_grid else \
        "true (linear in x1, x2; status nearest; cells outside the reference grid left out)"
    return table


_LONG = {
    "err_p_max": "max |p - p_ref| / p0_ref",
    "err_p_rms": "rms of p - p_ref over the contact / p0_ref",
    "err_q1_max": "max |q1 - q1_ref| / (mu p0_ref) away from stick/slip boundaries",
    "err_q1_max_interior": "max |q1 - q1_ref| / (mu p0_ref) away from stick/slip "
                           "boundaries and the contact edge",
    "err_q1_max_all": "max |q1 - q1_ref| / (mu p0_ref) over all cells",
    "err_q1_rms": "rms of q1 - q1_ref over the contact / (mu p0_ref)",
    "err_contact_radius": "|c_num - c_ref| / c_ref, contact radius sqrt(A / pi)",
    "err_stick_radius_cells": "|c_num - c_ref| / cell, stick radius sqrt(stick_area / pi)",
    "err_omega1": "|omega1 - omega1_ref| / amplitude of the closed-form loop",
    "err_omega3": "|omega3 - omega3_ref| / omega3_ref",
    "err_dissipation": "|D - D_ref| / D_ref at the last instant",
    "err_status": "fraction of cells in contact in either whose status differs",
}


def _table(ds, cols, scalars):
    t = np.asarray(ds["time"].values, float)
    x1, x2, d1, d2 = _grid(ds)
    window = float(t[-1] - t[0])
    t_norm = (t - t[0]) / window if window > 0 else np.zeros_like(t)
    data = {}
    for name, values in cols.items():
        attrs = {"units": "1", "long_name": _LONG.get(name, _long_of(name))}
        if name == "err_stick_radius_cells":
            attrs["units"] = "1"
            attrs["comment"] = "in cells (sqrt(d1 d2))"
        data[name] = ("time", np.asarray(values, float), attrs)
    for name, value in scalars.items():
        data[name] = ((), float(value), {"units": "1", "long_name": _LONG.get(name, name)})
    table = xr.Dataset(data, coords={
        "time": ("time", t, {"units": "s", "long_name": "time"}),
        "t_norm": ("time", t_norm, {"units": "1",
                                    "long_name": "dimensionless time (t - t0)/window"})})
    try:
        steps = int(_scene_of(ds).time.steps)          # the simulation's, whatever stride
    except (ArchiveError, TypeError):
        steps = int(t.size - 1)
    table.attrs.update({
        "title": "contactpipe comparison: errors of an archive",
        "grid_points": np.array([x1.size, x2.size], dtype=np.int32),
        "grid_spacing_m": np.array([d1, d2]),
        "steps": steps,
        "instants": int(t.size),
    })
    return table


def _long_of(name):
    body = name[4:] if name.startswith("err_") else name
    for suffix, what in (("_max", "max |difference| / scale"),
                         ("_rms", "rms difference / scale")):
        if body.endswith(suffix):
            return f"{body[:-len(suffix)]}: {what}"
    return f"{body}: |difference| / scale"


def _summary(table) -> str:
    keys = [k for k in ("err_p_max", "err_q1_max", "err_contact_radius",
                        "err_stick_radius_cells", "err_omega1", "err_dissipation")
            if k in table]
    if not keys:
        keys = [k for k in table.data_vars][:6]
    n1, n2 = (int(v) for v in table.attrs["grid_points"])
    d1, d2 = (float(v) for v in table.attrs["grid_spacing_m"])
    parts = [f"{k[4:]} {_nanmax(table[k].values):.3g}" for k in keys]
    against = table.attrs.get("closed_form")
    against = against if against and against != "none" else table.attrs.get("reference")
    return (f"vs {against} on {n1}x{n2} cells of {d1 * 1e6:.3g} um x {d2 * 1e6:.3g} um, "
            f"{table.attrs['steps']} steps: max " + ", ".join(parts))


# --------------------------------------------------------------------------- output

def write_table(table: xr.Dataset, out) -> pathlib.Path:
    """Write an error table atomically: netCDF for ``.nc``, CSV for ``.csv``.

    The CSV has ``#`` comment lines first (attributes and scalar errors), then one row
    per instant (read it with ``pandas.read_csv(path, comment="#")``).
    """
    out = pathlib.Path(out)
    suffix = out.suffix.lower()
    if suffix in (".nc", ".csv"):
        out.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".nc":
        with atomic_path(out) as tmp:
            table.to_netcdf(tmp, engine="netcdf4")
    elif suffix == ".csv":
        def write(tmp):
            lines = [f"# {k}: {_attr_text(v)}" for k, v in table.attrs.items()]
            lines += [f"# {k} = {float(table[k]):.17g}" for k in table.data_vars
                      if table[k].ndim == 0]
            series = [k for k in table.data_vars if table[k].dims == ("time",)]
            frame = table[series].to_dataframe()
            with open(tmp, "w", encoding="utf-8", newline="") as f:
                f.write("\n".join(lines) + "\n")
                frame.to_csv(f, float_format="%.10g")
        with atomic_path(out) as tmp:
            write(tmp)
    else:
        raise ArchiveError(f"{out}: the error table is written as netCDF (.nc) or CSV "
                           f"(.csv), got suffix {out.suffix!r}")
    return out


def _attr_text(v):
    if isinstance(v, np.ndarray):
        return " ".join(str(x) for x in v.tolist())
    return " ".join(str(v).split())


# --------------------------------------------------------------------------- public

def compare(archive, reference=None, *, out=None, figure=None) -> xr.Dataset:
    """Errors of an archive against its closed form or against a reference archive.

    Parameters
    ----------
    archive : path or xarray.Dataset
        The archive to check.
    reference : path or xarray.Dataset, optional
        None: the closed form :func:`closed_form_for` chooses. An archive: it is
        interpolated onto ``archive``'s instants (on ``t_norm`` = (t - t0)/window when the
        two windows differ) and cells (linearly; status by nearest cell), and every
        variable the two share is compared (solver diagnostics left out).
    out : path, optional
        Write the table there: netCDF if it ends in ``.nc``, CSV if ``.csv`` (atomic).
    figure : path, optional
        A PNG of the traction profiles through the centre, the closed form or the
        reference in grey.

    Returns
    -------
    xarray.Dataset
        Error variables over ``time`` (``err_p_max``, ``err_p_rms``,
        ``err_contact_radius``, ... see the module docstring), scalar ``err_dissipation``
        where it applies, and attributes ``closed_form``, ``grid_points``,
        ``grid_spacing_m``, ``steps`` and a one-line ``summary``.

    Raises
    ------
    SceneError
        ``reference`` is None and no closed form applies (the message says why).
    ArchiveError
        An archive is missing or unreadable, or the two share nothing to compare.
    """
    if out is not None:
        suffix = pathlib.Path(out).suffix.lower()
        if suffix not in (".nc", ".csv"):
            raise ArchiveError(f"{out}: the error table is written as netCDF (.nc) or CSV "
                               f"(.csv), got suffix {pathlib.Path(out).suffix!r}")
    import dask
    ds, label = load_dataset(archive)
    with dask.config.set(scheduler="synchronous"):     # many small reads: no thread pool
        if reference is None:
            table = _compare_closed_form(ds, label)
            ref = None
        else:
            ref, ref_label = load_dataset(reference)
            table = _compare_archives(ds, ref, label, ref_label)
    table.attrs["archive"] = label
    table.attrs["summary"] = _summary(table)
    if out is not None:
        write_table(table, out)
    if figure is not None:
        from .plot import _profiles_figure
        _profiles_figure(ds, figure, None, closed_form=reference is None, reference=ref)
    return table


# --------------------------------------------------------------------------- CLI

def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("archive", type=pathlib.Path, help="archive to check (netCDF)")
    parser.add_argument("reference", type=pathlib.Path, nargs="?", default=None,
                        help="reference archive (default: the scene's closed form)")
    parser.add_argument("-o", "--output", type=pathlib.Path, default=None,
                        help="write the error table (TABLE.nc or TABLE.csv)")
    parser.add_argument("--figure", type=pathlib.Path, default=None,
                        help="write the profiles against the closed form/reference (PNG)")


def format_table(table: xr.Dataset) -> str:
    """A short text table: the largest value of each error and when it occurs."""
    rows = []
    width = max(len(k) for k in table.data_vars)
    for k, v in table.data_vars.items():
        vals = np.asarray(v.values, float)
        if v.ndim == 0:
            rows.append(f"  {k:<{width}}  {float(vals):10.3g}  (final)")
            continue
        if not np.any(np.isfinite(vals)):
            rows.append(f"  {k:<{width}}  {'n/a':>10}")
            continue
        i = int(np.nanargmax(vals))
        rows.append(f"  {k:<{width}}  {vals[i]:10.3g}  (max, at t = "
                    f"{float(table['time'][i]):.4g} s)")
    return "\n".join([table.attrs.get("summary", "")] + rows)


def main(args) -> int:
    table = compare(args.archive, args.reference, out=args.output, figure=args.figure)
    print(format_table(table))
    for path in (args.output, args.figure):
        if path is not None:
            print(f"wrote {path}")
    return 0
