"""The closed-form solutions a scene admits, at an archive's instants and cells.

:func:`closed_form_for` says which closed form applies to a scene (or an archive's
scene), :func:`diagnose` also says why each other candidate does not, and
:func:`closed_form_solution` builds the :class:`ClosedForm` that the comparison
(:mod:`contactpipe.pipeline.compare`) and the figures (:mod:`contactpipe.pipeline.figures.plot`)
draw on. All formulae come from :mod:`contactpipe.analytic`. A scene with ``[wear]`` admits
none: its archive holds the last cycle of a worn contact.

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
``hertz_tilted``
    a sphere, elastic or rigid bodies, no shear, constant W, tilted by a moment
    (``moment1`` / ``moment2``) or a rotation (``rotation1`` / ``rotation2``) program,
    no twist: the Hertz contact moved by e = (M2/W, M1/W), with phi = e/R
    (:func:`contactpipe.analytic.hertz_tilted`; a rotation phi gives M = W R phi).
``lubkin_torsion``
    a sphere, elastic or rigid bodies with beta = 0, mu > 0, constant W, no tangential
    force, no tilt, a twist program under rotation control (``rotation3``): Hertz pressure
    and Lubkin's torque M3(phi3) ([L51]_) after Masing's rules (Deresiewicz's oscillating
    torsion, [D54]_), with the stuck stiffness 16 a^3/(3 C) and the full-slip torque
    3 pi mu W a / 16.
``mindlin_displacement``
    a sphere, elastic or rigid bodies with beta = 0, mu > 0, constant W, no tilt or twist,
    a displacement-controlled tangential program along x1 (``tangential_displacement``)
    from 0: Hertz pressure and the Mindlin-Deresiewicz loop under displacement control
    with gross slip (:func:`contactpipe.analytic.displacement_loop_force`): the first
    branch, the plateaus |T| = mu W, and the energy of each closed cycle,
    E_MD(mu W) + 4 mu W (delta* - delta_gs) beyond gross slip.

Closed-form fields are averaged over each cell (:func:`cell_average_field`), which is
what a piecewise-constant traction should match.

References
----------
.. [L51] J. L. Lubkin, "The torsion of elastic spheres in contact", J. Appl. Mech. 18
   (1951) 183-187.
.. [D54] H. Deresiewicz, "Contact of elastic spheres under an oscillating torsional
   couple", J. Appl. Mech. 21 (1954) 52-56 (and Johnson, *Contact Mechanics*, §7.4).
"""
from __future__ import annotations

import numpy as np

from ... import analytic
from ...exceptions import ArchiveError, SceneError
from ...materials import composite_modulus
from ...planning import pair_couples
from ...post.fretting import loop_cycles
from ..inputs import scene_of

__all__ = ["ClosedForm", "closed_form_for", "closed_form_solution", "diagnose",
           "no_closed_form_message", "cell_average_field", "iwan_dissipation",
           "CLOSED_FORMS", "LOADING_FORMS", "IWAN_ELEMENTS", "LEE_RADOK_SAMPLES",
           "LEE_RADOK_STEPS"]

CLOSED_FORMS = ("hertz", "flat_punch", "lee_radok", "mindlin_deresiewicz", "hertz_tilted",
                "lubkin_torsion", "mindlin_displacement")
#: The closed forms of the general loading (moments, rotations, displacement control).
LOADING_FORMS = ("hertz_tilted", "lubkin_torsion", "mindlin_displacement")
#: Jenkins elements of the Iwan model behind the closed-form dissipation.
IWAN_ELEMENTS = 100_000
#: Radial samples of the tabulated Lee-Radok pressure, and its time steps.
LEE_RADOK_SAMPLES = 1500
LEE_RADOK_STEPS = 1000


def _load_facts(scene):
    b1, b2 = scene.indenter.body(), scene.halfspace.body()
    t, W, T1, T2 = scene.load.knots()
    return b1, b2, t, W, T1, T2


def _program_facts(scene) -> dict:
    """What the six programs do (at the knots): which rows are displacement-controlled,
    whether anything tilts or twists."""
    p = scene.load.programs()
    tilt = [bool(np.any(np.nan_to_num(p.force[i]) != 0) or np.any(np.nan_to_num(p.motion[i])
                                                                 != 0)) for i in (3, 4)]
    twist = bool(np.any(np.nan_to_num(p.force[5]) != 0)
                 or np.any(np.nan_to_num(p.motion[5]) != 0))
    return {"programs": p, "normal_force": p.is_force(0), "tangential_force": p.is_force(1),
            "tilt": any(tilt), "twist": twist, "twist_rotation": not p.is_force(5) and twist}


def _worn() -> dict:
    """Why no closed form applies to a wear run: the worn surface changes the geometry
    cycle by cycle, and the archive holds the last cycle of the life."""
    return {name: ["needs no [wear] (the worn geometry changes cycle by cycle)"]
            for name in CLOSED_FORMS}


def diagnose(scene) -> tuple[str | None, dict]:
    """The closed form a scene admits, and for each candidate why it does not apply.

    Returns
    -------
    name : str or None
        The first of :data:`CLOSED_FORMS` whose conditions the scene meets, or None.
    why : dict
        ``{candidate: [reasons]}`` for each candidate tried before ``name`` (all of them
        when ``name`` is None): what the scene would need to admit it.
    """
    if getattr(scene, "wear", None) is not None:
        return None, _worn()
    b1, b2, t, W, T1, T2 = _load_facts(scene)
    f = _program_facts(scene)
    shape = scene.geometry.shape
    mapped = scene.friction.mapped
    mu = float(scene.friction.largest)
    force_w = f["normal_force"]
    has_t = bool(np.any(np.nan_to_num(T1, nan=1.0) != 0)
                 or np.any(np.nan_to_num(T2, nan=1.0) != 0))
    couples = pair_couples(b1, b2)
    kinds = (b1.kind, b2.kind)
    elastic = all(k in ("rigid", "elastic") for k in kinds)
    constant_w = force_w and bool(np.all(W == W[0]))
    shear_free = mu == 0 or (not has_t and not couples and not f["twist"])
    mat = f"indenter.material = {kinds[0]!r}, halfspace.material = {kinds[1]!r}"
    shear_why = ("shear: friction.mu = {:g} with {}".format(
        mu, "a tangential load" if has_t else "a twist" if f["twist"]
        else "a coupled pair (Dundurs beta != 0)"))
    plain = (not f["tilt"], "needs no tilt (moment1 / moment2, rotation1 / rotation2 "
                            "absent or 0)")
    scalar_mu = (not mapped, "needs a scalar friction.mu (not a map)")
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
            (constant_w, "needs a constant load.normal_force"), plain]):
        return "hertz", why
    if need("flat_punch", [
            (shape == "flat_punch", f"needs geometry.shape = 'flat_punch', got {shape!r}"),
            (elastic, f"needs elastic or rigid bodies, got {mat}"),
            (shear_free, f"needs no shear, got {shear_why}"),
            (constant_w, "needs a constant load.normal_force"), plain]):
        return "flat_punch", why
    one_rigid_one_visco = sorted(kinds) == ["rigid", "viscoelastic"]
    if need("lee_radok", [
            (shape == "sphere", f"needs a sphere, got geometry.shape = {shape!r}"),
            (one_rigid_one_visco, f"needs a rigid body on a viscoelastic one, got {mat}"),
            (not has_t, "needs no tangential load"),
            (shear_free, f"needs no shear, got {shear_why}"),
            (force_w and bool(np.all(np.diff(W) >= 0)),
             "needs a normal force that never decreases (a shrinking contact is Ting's "
             "problem)"), plain]):
        return "lee_radok", why
    sphere = (shape == "sphere", f"needs a sphere, got geometry.shape = {shape!r}")
    if need("mindlin_deresiewicz", [
            sphere, (elastic, f"needs elastic or rigid bodies, got {mat}"),
            (not couples, "needs Dundurs beta = 0 (identical materials, or incompressible)"),
            (mu > 0, "needs friction.mu > 0"), scalar_mu,
            (f["tangential_force"], "needs a force-controlled tangential load"),
            (has_t, "needs a tangential load"),
            (not np.any(np.nan_to_num(T2) != 0), "needs the tangential load along x1 (T2 = 0)"),
            (T1[0] == 0, f"needs the tangential load to start from 0, got "
                         f"{T1[0]:g} N at time[0]"),
            (constant_w, "needs a constant load.normal_force"),
            (not f["tilt"] and not f["twist"], "needs no tilt or twist")]):
        return "mindlin_deresiewicz", why
    return _diagnose_loading(scene, f, need, why, sphere, elastic, mat, couples, mu,
                             scalar_mu, has_t, constant_w, shear_free, shear_why)


def _diagnose_loading(scene, f, need, why, sphere, elastic, mat, couples, mu, scalar_mu,
                      has_t, constant_w, shear_free, shear_why):
    """The closed forms of the general loading (:data:`LOADING_FORMS`), in order."""
    p = f["programs"]
    elastic_ = (elastic, f"needs elastic or rigid bodies, got {mat}")
    w_const = (constant_w, "needs a constant, force-controlled load.normal_force")
    if need("hertz_tilted", [
            sphere, elastic_, (shear_free, f"needs no shear, got {shear_why}"), w_const,
            (f["tilt"], "needs a tilt (moment1 / moment2 or rotation1 / rotation2 != 0)"),
            (not f["twist"], "needs no twist (moment3 / rotation3 absent or 0)")]):
        return "hertz_tilted", why
    beta0 = (not couples, "needs Dundurs beta = 0 (identical materials, or incompressible)")
    if need("lubkin_torsion", [
            sphere, elastic_, beta0, (mu > 0, "needs friction.mu > 0"), scalar_mu, w_const,
            (f["twist_rotation"], "needs a twist under rotation control (load.rotation3)"),
            (f["tangential_force"] and not has_t, "needs no tangential load"),
            (not f["tilt"], "needs no tilt")]):
        return "lubkin_torsion", why
    om1, om2 = p.motion[1], p.motion[2]
    if need("mindlin_displacement", [
            sphere, elastic_, beta0, (mu > 0, "needs friction.mu > 0"), scalar_mu, w_const,
            (not f["tangential_force"], "needs load.tangential_displacement"),
            (f["tangential_force"] or not np.any(om2 != 0),
             "needs the displacement along x1 (omega2 = 0)"),
            (f["tangential_force"] or om1[0] == 0,
             f"needs the displacement to start from 0, got {om1[0]:g} m at time[0]"),
            (not f["tilt"] and not f["twist"], "needs no tilt or twist")]):
        return "mindlin_displacement", why
    return None, why


def closed_form_for(ds) -> str | None:
    """Which closed form the archive's scene admits.

    Parameters
    ----------
    ds : xarray.Dataset, path or Scene
        An archive (its ``scene`` attribute is read), or a scene.

    Returns
    -------
    str or None
        One of :data:`CLOSED_FORMS`
        See the module docstring for the conditions of each.
    """
    return diagnose(scene_of(ds))[0]


def no_closed_form_message(scene, why, label) -> str:
    """The one-line refusal when :func:`diagnose` finds no closed form: the nearest
    candidate (the one that misses fewest conditions) and its first unmet condition,
    and what to do instead. :func:`diagnose` gives every candidate's reasons."""
    hint = "compare with a reference archive: contactpipe compare ARCHIVE.nc REFERENCE.nc"
    if not why:
        return f"{label}: no closed form applies; {hint}"
    name = min(why, key=lambda k: len(why[k]))          # ties: the first in CLOSED_FORMS
    more = len(why[name]) - 1
    reason = why[name][0].split(", got ")[0] + (f" (+{more} more)" if more else "")
    return f"{label}: no closed form applies (nearest: {name} {reason}); {hint}"


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


def iwan_dissipation(omega, mu_w, delta_max, n=IWAN_ELEMENTS):
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
        self.tilts = None
        if name in ("hertz", "mindlin_deresiewicz") + LOADING_FORMS:
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
        elif name in LOADING_FORMS:
            self._setup_loading(ds, b1, b2, e_star)

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
        self._dissipation = (iwan_dissipation(omega, mu_w, delta_max)
                             if delta_max > 0 else np.zeros_like(omega))

    # -- general loading ---------------------------------------------------------------

    def _mesh(self, ds):
        """The six programs on the scene's time mesh, and each archive instant's index
        into it."""
        p = self.scene.load.programs(self.scene.time.steps)
        idx = np.searchsorted(p.t, self.times - 1e-9 * max(self.window, 1e-300))
        idx = np.clip(idx, 0, p.t.size - 1)
        if not np.allclose(p.t[idx], self.times, rtol=0,
                           atol=1e-9 * max(self.window, 1.0)):
            raise ArchiveError("the archive's instants are not on its scene's time mesh; "
                               "cannot rebuild the load history")
        return p, idx

    def _setup_loading(self, ds, b1, b2, e_star):
        p, idx = self._mesh(ds)
        W, R, a = self.normal_force, self.scene.geometry.radius, self.hertz.contact_radius
        self._idx = idx
        mu_w = self.mu * W
        if self.name == "hertz_tilted":
            # a moment where given, else the moment of the imposed (or held) rotation
            m = [np.where(np.isnan(p.force[i]), W * R * np.nan_to_num(p.motion[j]),
                          p.force[i]) for i, j in ((3, 3), (4, 4))]
            self.tilts = [analytic.hertz_tilted(W, m[0][i], m[1][i], R, e_star) for i in idx]
        elif self.name == "lubkin_torsion":
            self.torsion_compliance = analytic.torsional_compliance(
                b1.young, b1.poisson, b2.young, b2.poisson)
            self.twist = p.motion[5][idx]
            self.torque = analytic.torsion_loop_moment(
                p.motion[5][:idx[-1] + 1], self.mu, W, a, self.torsion_compliance)[idx]
            self.full_slip_torque = analytic.full_slip_torque(self.mu, W, a)
            self.stuck_stiffness = analytic.torsional_stiffness(a, self.torsion_compliance)
        else:
            self.compliance = analytic.tangential_compliance_sum(
                b1.young, b1.poisson, b2.young, b2.poisson)
            self.delta_gs = analytic.gross_slip_displacement(self.mu, W, a, self.compliance)
            om = p.motion[1][:idx[-1] + 1]
            self.displacement = p.motion[1][idx]
            self._T = analytic.displacement_loop_force(om, self.mu, W, a, self.compliance)
            self.displacement_force = self._T[idx]
            self.plateau = np.isclose(np.abs(self._T[idx]), mu_w, rtol=1e-12, atol=0) \
                & (idx > 0)

    def cycle_energy(self, start, stop, per_step=200):
        """Closed-form energy [J] of the cycle between archive instants ``start`` and
        ``stop`` (displacement control): E_MD(mu W) + 4 mu W (delta* - delta_gs) beyond gross
        slip, E_MD(T(delta*)) below (:func:`analytic.displacement_energy_per_cycle`) for a
        cycle symmetric about 0; otherwise the area of the closed-form loop, the
        displacement sampled ``per_step`` times per archive step."""
        om = self.displacement[start:stop + 1]
        lo, hi = float(om.min()), float(om.max())
        c = self.compliance
        a = self.hertz.contact_radius
        if abs(hi + lo) <= 1e-9 * (hi - lo):
            return analytic.displacement_energy_per_cycle(0.5 * (hi - lo), self.mu,
                                                          self.normal_force, a, c)
        head = self.displacement[:start + 1]
        fine = np.concatenate([np.linspace(x, y, per_step + 1)[1:]
                               for x, y in zip(om[:-1], om[1:], strict=True)])
        T = analytic.displacement_loop_force(np.concatenate([head, fine]), self.mu,
                                             self.normal_force, a, c)
        path = np.concatenate([om[:1], fine])
        T = T[head.size - 1:]
        return abs(float(np.sum(0.5 * (T[1:] + T[:-1]) * np.diff(path))))

    def displacement_cycles(self):
        """(start, stop) archive instants of each closed cycle of the imposed displacement
        (:func:`contactpipe.post.fretting.loop_cycles`)."""
        return loop_cycles(self.displacement)

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
        forces = [rev[0]] + [0.5 * (b - a) for a, b in zip(points, points[1:], strict=False)] \
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

    def has_field_shear(self) -> bool:
        """Whether :meth:`shear` is the closed-form q1 (Mindlin-Deresiewicz, or 0 without
        shear); False for torsion and displacement control, whose shear field has no
        closed form here."""
        return self.name not in ("lubkin_torsion", "mindlin_displacement")

    def pressure(self, k, x1, x2):
        """Closed-form pressure [Pa] at positions (x1, x2) [m] (broadcast) at instant k."""
        x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
        if self.tilts is not None:
            return self.tilts[k].pressure(x1, x2)
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
        if self.tilts is not None:
            reach += float(np.hypot(*self.tilts[k].centre))
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
        if self.tilts is not None:
            return self.tilts[k].approach
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
                                            for a, b in zip(hist[:-1], hist[1:], strict=True)])
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
    scene = scene_of(ds)
    name, why = diagnose(scene)
    if name is None:
        raise SceneError(no_closed_form_message(scene, why, label or "archive"))
    return ClosedForm(name, scene, ds)

