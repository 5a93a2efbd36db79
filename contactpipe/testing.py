"""Checks for users' own tests: the contact laws every correct archive obeys.

    >>> from contactpipe.testing import assert_contact_laws
    >>> assert_contact_laws(ds)          # raises AssertionError naming the law and the step

Laws checked at every recorded instant (docs/conventions.md for the signs):

* equilibrium of all six freedoms: a force-controlled one (W, T1, T2, M1, M2, M3) carried
  by the tractions as the scene's load program says at the archive's instants (Σ p Δ,
  Σ q Δ, Σ p x2 Δ, Σ p x1 Δ, Σ (q2 x1 − q1 x2) Δ; forces relative to W, moments to W times
  the grid's half length); a displacement-controlled one reached as the program says (the
  archive's omega3, omega1, omega2, phi1, phi2, phi3); and the archive's own W, T1, T2,
  M1, M2, M3 series equal to the sums of its tractions;
* complementarity: p ≥ 0, h ≥ 0, h = 0 where p > 0;
* Coulomb: |q| ≤ μ p (1 + rtol_coulomb), with the archive's map ``mu`` where it has one;
* dissipation: q · Δs ≥ 0 in slipping cells and the accumulated dissipation never
  decreases, each up to what the solver resolves (solver.tolerance × the traction scale ×
  the largest slip, per cell; × μ W, accumulated);
* stick: Δs = 0 in stick cells (status 1).
"""
from __future__ import annotations

import numpy as np

from . import analytic
from .materials import kelvin_voigt, maxwell, prony, zener
from .nomenclature import STATUS_SLIP, STATUS_STICK
from .scene import Scene
from .scene.loading import FREEDOMS

__all__ = ["contact_law_violations", "assert_contact_laws", "tiny_scene", "TINY_SCENES",
           "creep_laws", "zigzag", "lee_radok_measures"]

#: Two tiny scenes (24 x 24 cells, a rigid sphere on a compressible Maxwell half-space):
#: "creep" is frictionless under a constant load; "fretting" runs every sub-model
#: (tangential, coupling, memory) over a fretting loop. Each simulates in well under a second.
TINY_SCENES = {
    "creep": """
name = "tiny-creep"
[geometry]
shape = "sphere"
radius = 0.018
[indenter]
material = "rigid"
[halfspace]
material = "viscoelastic"
young = 105e9
poisson = 0.3
creep = "maxwell"
relaxation_time = 1.0
[friction]
mu = 0.0
[load]
time = [0.0, 1.0]
normal_force = 1000.0
[grid]
points = [24, 24]
size = [2.4e-3, 2.4e-3]
[time]
steps = 10
""",
    "fretting": """
name = "tiny-fretting"
[geometry]
shape = "sphere"
radius = 0.018
[indenter]
material = "rigid"
[halfspace]
material = "viscoelastic"
young = 105e9
poisson = 0.3
creep = "maxwell"
relaxation_time = 1.0
[friction]
mu = 0.1
[load]
time = [0.0, 0.2, 0.6, 1.0]
normal_force = 1000.0
tangential_force = [0.0, 90.0, -90.0, 90.0]
[grid]
points = [24, 24]
size = [2.0e-3, 2.0e-3]
[time]
steps = 20
""",
}


def tiny_scene(kind="fretting", **changes):
    """A tiny scene for tests (:data:`TINY_SCENES`), with optional dotted-path changes:
    ``tiny_scene("fretting", **{"time.steps": 40})``."""
    scene = Scene.from_toml_text(TINY_SCENES[kind])
    return scene.replace(changes) if changes else scene


def _scene_of(ds):
    return Scene.from_toml_text(ds.attrs["scene"])


def _friction(ds, scene):
    """mu [1]: the archive's map (x1, x2) when it has one, else the scene's number."""
    if "mu" in ds.data_vars and ds["mu"].dims == ("x1", "x2"):
        return np.asarray(ds["mu"].values, dtype=float)
    return float(scene.friction.mu) if not scene.friction.mapped else None


def _sums(ds, cell):
    """The six sums of the tractions per instant: W, T1, T2, M1, M2, M3."""
    p = np.asarray(ds["p"].values, dtype=float)
    x1 = np.asarray(ds.x1.values, dtype=float)[:, None]
    x2 = np.asarray(ds.x2.values, dtype=float)[None, :]
    out = {"W": p.sum(axis=(1, 2)) * cell, "M1": (p * x2).sum(axis=(1, 2)) * cell,
           "M2": (p * x1).sum(axis=(1, 2)) * cell}
    if "q1" in ds:
        q1 = np.asarray(ds["q1"].values, dtype=float)
        q2 = np.asarray(ds["q2"].values, dtype=float)
        out.update({"T1": q1.sum(axis=(1, 2)) * cell, "T2": q2.sum(axis=(1, 2)) * cell,
                    "M3": (q2 * x1 - q1 * x2).sum(axis=(1, 2)) * cell})
    else:
        out.update({k: np.zeros_like(out["W"]) for k in ("T1", "T2", "M3")})
    return out


def _equilibrium(ds, scene, cell, rtol, bad):
    """Each freedom: a force-controlled one carried by the tractions as the program says,
    a displacement-controlled one reached as it says; and the archive's series equal to
    the sums of its tractions. Forces relative to W, moments to W times the grid's half
    length, motions to the largest motion of their kind."""
    t = ds["time"].values
    prog = scene.load.programs().on(t)
    sums = _sums(ds, cell)
    W = np.where(np.isnan(prog.force[0]), sums["W"], prog.force[0])
    scale = max(float(np.abs(W).max()), 1e-300)
    arm = max(float(np.abs(ds.x1.values).max()), float(np.abs(ds.x2.values).max()))
    tang = "q1" in ds
    for i, (fname, mname) in enumerate(FREEDOMS):
        size = scale * (arm if i >= 3 else 1.0)
        if prog.is_force(i):
            if i in (1, 2, 5) and not tang and not np.any(prog.force[i]):
                continue
            e = np.abs(sums[fname] - prog.force[i]) / size
            if e.max() > rtol * 10:
                k = int(e.argmax())
                bad.append(f"equilibrium of {fname} at step {k} (t = {t[k]:.6g} s): "
                           f"|sum - program| = {e[k]:.2e} of W{' a' if i >= 3 else ''}")
        elif mname in ds and (tang or i not in (1, 2, 5)):
            reached = np.asarray(ds[mname].values, dtype=float)
            ref = max(float(np.abs(prog.motion[i]).max()), 1e-300)
            e = np.abs(reached - prog.motion[i]) / ref
            if e.max() > rtol * 10:
                k = int(e.argmax())
                bad.append(f"{mname} at step {k} (t = {t[k]:.6g} s) is not the imposed "
                           f"value: off by {e[k]:.2e} of its largest")
        if fname in ds:
            e = np.abs(np.asarray(ds[fname].values, dtype=float) - sums[fname]) / size
            if e.max() > rtol * 10:
                k = int(e.argmax())
                bad.append(f"the archive's {fname} at step {k} is not the sum of its "
                           f"tractions ({e[k]:.2e} of W)")


def _dissipation(ds, scene, mu, bad):
    """q·Δs ≥ 0 in slipping cells, no slip increment in stick cells, and an accumulated
    dissipation that never decreases, each up to what the solver resolves: its tolerance
    times the traction and slip scales (the rounding of a step that dissipates nothing;
    per cell at least 1e-9 of the largest q times the largest slip increment), and for the
    accumulated dissipation tolerance x mu W x the slip scale, or 1e-12 of its largest."""
    q1 = np.asarray(ds["q1"].values, dtype=float)
    q2 = np.asarray(ds["q2"].values, dtype=float)
    s1 = np.asarray(ds["s1"].values, dtype=float)
    s2 = np.asarray(ds["s2"].values, dtype=float)
    ds1, ds2 = np.diff(s1, axis=0), np.diff(s2, axis=0)
    status = np.asarray(ds["status"].values)[1:]
    work = q1[1:] * ds1 + q2[1:] * ds2
    slipping = status == STATUS_SLIP
    tol = scene.solver.tolerance
    slip_scale = max(float(np.abs(ds["omega1"].values).max()),
                     float(np.abs(ds["omega2"].values).max()),
                     float(np.abs(s1).max()), float(np.abs(s2).max()))
    qs = max(float(np.abs(q1).max()), float(np.abs(q2).max()), 1e-300)
    ss = max(float(np.abs(ds1).max()), float(np.abs(ds2).max()), 1e-300)
    if slipping.any() and work[slipping].min() < -max(1e-9 * qs * ss, tol * qs * slip_scale):
        bad.append(f"dissipation: q·Δs < 0 in a slipping cell ({work[slipping].min():.3g})")
    d = np.asarray(ds["dissipation"].values, dtype=float)
    W = float(np.abs(ds["W"].values).max())
    resolved = tol * float(np.max(mu)) * W * slip_scale
    allowed = max(resolved, 1e-12 * max(float(np.abs(d).max()), 1e-300))
    if np.any(np.diff(d) < -allowed):
        bad.append(f"dissipation decreases (by {-np.diff(d).min():.3g} J, more than the "
                   f"{allowed:.3g} J the solver resolves)")
    stick = status == STATUS_STICK
    if np.any(ds1[stick] != 0) or np.any(ds2[stick] != 0):
        bad.append("slip increment in a stick cell")


def contact_law_violations(ds, rtol=1e-9, rtol_coulomb=1e-9) -> list[str]:
    """List of violated laws (empty when the archive obeys them all)."""
    bad = []
    scene = _scene_of(ds)
    mu = _friction(ds, scene)
    d1 = float(ds.x1[1] - ds.x1[0])
    d2 = float(ds.x2[1] - ds.x2[0])
    cell = d1 * d2
    p = np.asarray(ds["p"].values, dtype=float)
    t = ds["time"].values
    if p.min() < 0:
        bad.append(f"p < 0: min {p.min():.3g} Pa")
    _equilibrium(ds, scene, cell, rtol, bad)
    h = np.asarray(ds["h"].values, dtype=float)
    if h.min() < 0:
        bad.append(f"h < 0: min {h.min():.3g} m")
    if np.any(h[p > 0] != 0):
        bad.append("complementarity: h ≠ 0 under pressure")
    if "q1" in ds:
        q1 = np.asarray(ds["q1"].values, dtype=float)
        q2 = np.asarray(ds["q2"].values, dtype=float)
        over = np.hypot(q1, q2) - mu * p * (1 + rtol_coulomb)
        if over.max() > 0:
            k = int(np.unravel_index(over.argmax(), over.shape)[0])
            bad.append(f"Coulomb at step {k} (t = {t[k]:.6g} s): |q| exceeds μp by "
                       f"{over.max():.3g} Pa")
        if ds.sizes["time"] > 1:
            _dissipation(ds, scene, mu, bad)
    return bad


def assert_contact_laws(ds, rtol=1e-9, rtol_coulomb=1e-9) -> None:
    """Raise AssertionError listing every violated contact law of the archive."""
    bad = contact_law_violations(ds, rtol=rtol, rtol_coulomb=rtol_coulomb)
    assert not bad, "contact laws violated:\n  " + "\n  ".join(bad)


# ------------------------------------------------------- viscoelastic fields vs Lee-Radok

def creep_laws(young: float) -> dict:
    """The creep laws of the time-integration checks (every time constant 1 s): name ->
    (the body's scene keys, its creep function phi(t) [1]). Maxwell; Zener with
    E0/Einf = 2 and 100; Kelvin-Voigt (``young`` then the long-term modulus); a 3-term
    Prony series with a dashpot of 10 s. ``young`` [Pa] is the body's Young modulus."""
    terms = [[0.5, 0.1], [1.0, 1.0], [2.0, 5.0]]
    return {
        "maxwell": ({"creep": "maxwell", "relaxation_time": 1.0}, maxwell(1.0)),
        "zener2": ({"creep": "zener", "relaxed_young": young / 2, "retardation_time": 1.0},
                   zener(young, young / 2, 1.0)),
        "zener100": ({"creep": "zener", "relaxed_young": young / 100,
                      "retardation_time": 1.0}, zener(young, young / 100, 1.0)),
        "kelvin_voigt": ({"creep": "kelvin_voigt", "retardation_time": 1.0},
                         kelvin_voigt(1.0)),
        "prony3": ({"creep": "prony", "terms": terms, "relaxation_time": 10.0},
                   prony(terms, 10.0)),
    }


def zigzag(pc) -> float:
    """Step-to-step oscillation of a series: the largest min(|D_k|, |D_k+1|, |D_k+2|) over
    three consecutive increments D of ``pc`` that alternate in sign (0 when none do; a
    monotone relaxation, or one jump, gives 0)."""
    d = np.diff(np.asarray(pc, float))
    amp = [min(abs(d[k]), abs(d[k + 1]), abs(d[k + 2])) for k in range(len(d) - 2)
           if d[k] * d[k + 1] < 0 and d[k + 1] * d[k + 2] < 0]
    return max(amp, default=0.0)


def lee_radok_measures(ds, creep, young, poisson, radius, normal_force, *, t_min=0.25,
                       t_field=None, field_every=1, n_steps=1000) -> dict:
    """How a rigid sphere's viscoelastic run (W stepped at the first instant, square grid)
    meets Lee-Radok (:func:`contactpipe.analytic.lee_radok_sphere`, ``lee_radok_pressure``).

    Parameters
    ----------
    ds : xarray.Dataset
        The archive (p, contact_area, omega3 over time; x1, x2).
    creep : callable
        The normal creep function phi(t) [1] Lee-Radok is evaluated with.
    young, poisson, radius, normal_force : float
        E [Pa], nu [1], R [m], W [N].
    t_min : float
        The radius and a³ are compared for t >= t_min [s].
    t_field : float, optional
        The pressure field is compared for t >= t_field [s] (every ``field_every``-th such
        instant); absent: not compared.
    n_steps : int
        Quadrature steps of ``lee_radok_pressure``.

    Returns
    -------
    dict
        ``radius_cells``: largest |a_area − a| over the cell side, a_area = sqrt(area/π);
        ``holes``: the most cells with p = 0 inside 0.8 a(t) at one instant after the
        first; ``zigzag``: :func:`zigzag` of the centre pressure p_c (mean of the four centre
        cells) after the first instant, over its final value; ``a3``: largest
        |(R ω3)^{3/2} / a³ − 1|; ``field`` (with ``t_field``): largest |p − p_LR| inside
        0.8 a over Lee-Radok's centre pressure; ``pc``, ``t``, ``a_exact`` [m].
    """
    E, nu, R, W = young, poisson, radius, normal_force
    t = ds.time.values
    x = ds.x1.values
    d = float(x[1] - x[0])
    r = np.hypot(*np.meshgrid(x, ds.x2.values, indexing="ij"))
    a_ex = analytic.lee_radok_sphere(t, W, R, E, nu, creep).contact_radius
    a_area = np.sqrt(ds.contact_area.values / np.pi)
    p = ds.p.values
    n1, n2 = p.shape[1:]
    pc = p[:, n1 // 2 - 1:n1 // 2 + 1, n2 // 2 - 1:n2 // 2 + 1].mean(axis=(1, 2))
    late = t >= t_min
    a3 = (R * np.clip(ds.omega3.values, 0, None)) ** 1.5
    out = {"radius_cells": float(np.abs(a_area[late] - a_ex[late]).max() / d),
           "holes": max(int(np.sum((p[k] == 0) & (r < 0.8 * a_ex[k])))
                        for k in range(1, t.size)),
           "zigzag": zigzag(pc[1:]) / max(pc[-1], 1e-300),
           "a3": float(np.abs(a3[late] / a_ex[late] ** 3 - 1).max()),
           "pc": pc, "t": t, "a_exact": a_ex}
    if t_field is not None:
        err = 0.0
        for k in np.flatnonzero(t >= t_field)[::field_every]:
            inside = r < 0.8 * a_ex[k]
            ref = analytic.lee_radok_pressure(r[inside], t[k], W, R, E, nu, creep,
                                              n_steps=n_steps)
            centre = float(analytic.lee_radok_pressure(np.array([0.0]), t[k], W, R, E, nu,
                                                       creep, n_steps=n_steps)[0])
            err = max(err, float(np.abs(p[k][inside] - ref).max() / centre))
        out["field"] = err
    return out
