"""Checks for users' own tests: the contact laws every correct archive obeys.

    >>> from contactpipe.testing import assert_contact_laws
    >>> assert_contact_laws(ds)          # raises AssertionError naming the law and the step

Laws checked at every recorded instant (docs/conventions.md for the signs):

* equilibrium: Σ p Δ = W and Σ q Δ = T (relative to W), where W and T are those of the
  scene's load program at the archive's instants (not the archive's own W, T series, which
  are themselves sums of the tractions);
* complementarity: p ≥ 0, h ≥ 0, h = 0 where p > 0;
* Coulomb: |q| ≤ μ p (1 + rtol_coulomb);
* dissipation: q · Δs ≥ 0 in slipping cells and the accumulated dissipation never decreases;
* stick: Δs = 0 in stick cells (status 1).
"""
from __future__ import annotations


import numpy as np

from .files import loads_toml

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
    from .scene import Scene
    scene = Scene.from_toml_text(TINY_SCENES[kind])
    return scene.replace(changes) if changes else scene


def contact_law_violations(ds, rtol=1e-9, rtol_coulomb=1e-9) -> list[str]:
    """List of violated laws (empty when the archive obeys them all)."""
    bad = []
    mu = float(loads_toml(ds.attrs["scene"], "the archive's scene attribute").get("friction", {}).get("mu", 0.0))
    d1 = float(ds.x1[1] - ds.x1[0])
    d2 = float(ds.x2[1] - ds.x2[0])
    cell = d1 * d2
    p = np.asarray(ds["p"].values, dtype=float)
    t = ds["time"].values
    from .scene import Scene
    knots_t, knots_W, knots_T1, knots_T2 = Scene.from_toml_text(ds.attrs["scene"]).load.knots()
    W = np.interp(t, knots_t, knots_W)
    applied = {"T1": np.interp(t, knots_t, knots_T1), "T2": np.interp(t, knots_t, knots_T2)}
    scale = max(float(np.abs(W).max()), 1e-300)
    if p.min() < 0:
        bad.append(f"p < 0: min {p.min():.3g} Pa")
    err = np.abs(p.sum(axis=(1, 2)) * cell - W) / scale
    if err.max() > rtol * 10:
        k = int(err.argmax())
        bad.append(f"normal equilibrium at step {k} (t = {t[k]:.6g} s): |ΣpΔ − W|/W = {err[k]:.2e}")
    h = np.asarray(ds["h"].values, dtype=float)
    if h.min() < 0:
        bad.append(f"h < 0: min {h.min():.3g} m")
    if np.any(h[p > 0] != 0):
        bad.append("complementarity: h ≠ 0 under pressure")
    if "q1" in ds:
        q1 = np.asarray(ds["q1"].values, dtype=float)
        q2 = np.asarray(ds["q2"].values, dtype=float)
        for q, name in ((q1, "T1"), (q2, "T2")):
            e = np.abs(q.sum(axis=(1, 2)) * cell - applied[name]) / scale
            if e.max() > rtol * 10:
                k = int(e.argmax())
                bad.append(f"tangential equilibrium ({name}) at step {k}: {e[k]:.2e} of W")
        over = np.hypot(q1, q2) - mu * p * (1 + rtol_coulomb)
        if over.max() > 0:
            k = int(np.unravel_index(over.argmax(), over.shape)[0])
            bad.append(f"Coulomb at step {k} (t = {t[k]:.6g} s): |q| exceeds μp by "
                       f"{over.max():.3g} Pa")
        if ds.sizes["time"] > 1:
            s1 = np.asarray(ds["s1"].values, dtype=float)
            s2 = np.asarray(ds["s2"].values, dtype=float)
            ds1, ds2 = np.diff(s1, axis=0), np.diff(s2, axis=0)
            status = np.asarray(ds["status"].values)[1:]
            work = q1[1:] * ds1 + q2[1:] * ds2
            slipping = status == 2
            qs = max(float(np.abs(q1).max()), 1e-300)
            ss = max(float(np.abs(ds1).max()), 1e-300)
            if slipping.any() and work[slipping].min() < -1e-9 * qs * ss:
                bad.append(f"dissipation: q·Δs < 0 in a slipping cell ({work[slipping].min():.3g})")
            if np.any(np.diff(ds["dissipation"].values) < -1e-12 * max(
                    float(np.abs(ds["dissipation"].values).max()), 1e-300)):
                bad.append("dissipation decreases")
            stick = status == 1
            if np.any(ds1[stick] != 0) or np.any(ds2[stick] != 0):
                bad.append("slip increment in a stick cell")
    return bad


def assert_contact_laws(ds, rtol=1e-9, rtol_coulomb=1e-9) -> None:
    """Raise AssertionError listing every violated contact law of the archive."""
    bad = contact_law_violations(ds, rtol=rtol, rtol_coulomb=rtol_coulomb)
    assert not bad, "contact laws violated:\n  " + "\n  ".join(bad)
