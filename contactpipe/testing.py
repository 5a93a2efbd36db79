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

from .loading import FREEDOMS
from .scene import Scene

__all__ = ["contact_law_violations", "assert_contact_laws", "tiny_scene", "TINY_SCENES"]

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
    slipping = status == 2
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
    stick = status == 1
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
