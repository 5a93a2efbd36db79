"""Compare an archive with the closed form its scene admits, or with another archive.

``compare(archive)`` checks a simulation against the closed-form solution of its scene
(:func:`contactpipe.pipeline.compare.reference.closed_form_for` says which one applies, the
module :mod:`contactpipe.pipeline.compare.reference` lists the closed forms and their
conditions); ``compare(archive, reference)`` interpolates a reference archive onto the
archive's instants and cells and compares every variable the two share. Either way the
result is an error table, an :class:`xarray.Dataset` over ``time`` (written as netCDF or
CSV by :func:`write_table`). The command line (``contactpipe compare``) is
:mod:`contactpipe.pipeline.cli.compare`.

Error variables (over ``time`` unless said otherwise): ``err_p_max``, ``err_p_rms``,
``err_contact_radius``, ``err_omega3`` for every closed form (Lee-Radok under a growing
load: no pressure errors); for Mindlin-Deresiewicz also ``err_q1_max`` (max over every
cell of |q1 - q1_MD| / (mu p0); its largest value over the instants is the figure the
summary line and the README give for a fretting loop), ``err_q1_max_interior`` (the same
leaving out the cells within one cell of a current or remembered stick/slip circle or of
the contact edge: the square-root kinks of the closed form, and q1 = mu p repeating the
edge cells' pressure error), ``err_q1_rms``, ``err_stick_radius_cells``, ``err_omega1``
and the scalar ``err_dissipation`` (at the last instant). Against a reference archive:
``err_<field>_max`` and ``err_<field>_rms`` per shared field, ``err_status``,
``err_<series>`` per shared series, ``err_contact_radius``, ``err_stick_radius_cells``
and ``err_dissipation``.

Errors are dimensionless: tractions relative to the closed form's peak pressure p0 (the
shear relative to mu p0), radii relative to the closed-form radius, the stick radius in
cells, omega1 relative to the amplitude of the closed-form loop. Against a reference
archive each difference is relative to max |reference| (tractions: its max p), floored at
``NOISE`` (1e-6) times the contact's own scale of the quantity's unit
(:func:`physical_scales`: p0, W, W a, the approach, ...; the table's ``scale_floors``), so
that a quantity that is rounding noise in both archives (a torque without twist) reads as
noise, not as an O(1) error, while a quantity of real size (a tangential force of 0.09 W)
is still measured against its own size. Closed-form
fields are averaged over each cell (:func:`contactpipe.analytic.cell_average`), which is
what a piecewise-constant traction should match.
"""
from __future__ import annotations

import math
import os

import numpy as np
import xarray as xr

from ...archive import open_archive
from ...exceptions import ArchiveError
from ..inputs import grid_of, local_reads, radius_of_area, scene_of
from .output import TABLE_SUFFIXES, check_table_path, format_table, write_table
from .reference import LOADING_FORMS, closed_form_solution

__all__ = ["compare", "load_dataset", "write_table", "format_table", "check_table_path",
           "physical_scales", "TABLE_SUFFIXES"]

FIELD = ("time", "x1", "x2")
#: Solver diagnostics: not compared between archives.
DIAGNOSTICS = ("iterations", "fft_pairs", "coupling_passes")
TRACTIONS = ("p", "q1", "q2")


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
        return open_archive(archive, verify=True), str(archive)
    raise ArchiveError(f"expected an archive path or an xarray.Dataset, got "
                       f"{type(archive).__name__}")


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


def _rel(num, ref, floor=0.0):
    """|num - ref| / max(|ref|, floor)."""
    den = max(abs(ref), floor)
    if den == 0:
        return 0.0 if num == ref else np.nan
    return abs(num - ref) / den


def _near(r, radii, width):
    out = np.zeros(r.shape, bool)
    for c in radii:
        out |= np.abs(r - c) <= width
    return out


def _compare_closed_form(ds, label):
    sol = closed_form_solution(ds, label)
    x1, x2, d1, d2 = grid_of(ds)
    cell = math.sqrt(d1 * d2)
    r = np.hypot(x1[:, None], x2[None, :])
    nt = ds.sizes["time"]
    md = sol.name == "mindlin_deresiewicz"
    cols = {k: np.full(nt, np.nan) for k in
            ("err_p_max", "err_p_rms", "err_contact_radius", "err_omega3")}
    if md:
        for k in ("err_q1_max", "err_q1_max_interior", "err_q1_rms",
                  "err_stick_radius_cells", "err_omega1"):
            cols[k] = np.full(nt, np.nan)
    area = np.asarray(ds["contact_area"].values, float)
    omega3 = np.asarray(ds["omega3"].values, float)
    frames_p = _Frames(ds["p"])
    frames_q = _Frames(ds["q1"]) if md else None
    stick_area = np.asarray(ds["stick_area"].values, float) if md else None
    p_ref_static = None
    for k in range(nt):
        cols["err_contact_radius"][k] = _rel(radius_of_area(area[k]), sol.contact_radius(k))
        cols["err_omega3"][k] = _rel(omega3[k], sol.approach(k))
        if sol.has_field_pressure():
            if sol.name in ("hertz", "mindlin_deresiewicz", "flat_punch", "lubkin_torsion",
                            "mindlin_displacement"):
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
            inner = ~_near(r, list(sol.boundaries(k)) + [sol.hertz.contact_radius], cell)
            cols["err_q1_max"][k] = _nanmax(dq) / scale
            cols["err_q1_max_interior"][k] = _nanmax(np.where(inner, dq, np.nan)) / scale
            cols["err_q1_rms"][k] = _rms(dq, contact) / scale
            c_num = radius_of_area(stick_area[k])
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
    attrs = {}
    if sol.name in LOADING_FORMS:
        attrs = _loading_errors(ds, sol, cols, scalars, cell, x1, x2)
    table = _table(ds, cols, scalars)
    table.attrs.update(attrs)
    table.attrs["closed_form"] = sol.name
    table.attrs["reference"] = f"closed form: {sol.name}"
    radius = sol.contact_radius(nt - 1)
    table.attrs["cells_per_contact_radius"] = float(radius / cell) if radius > 0 else 0.0
    if md:
        table.attrs["q1_exclusion"] = (
            "err_q1_max takes every cell; err_q1_max_interior leaves out cells whose "
            "centre lies within one cell of a current or remembered stick/slip circle or "
            "of the contact edge r = a, where q1 = mu p repeats the pressure error of the "
            "cells the edge cuts (err_p_max)")
    return table


def _loading_errors(ds, sol, cols, scalars, cell, x1, x2) -> dict:
    """The errors of the general loading's closed forms (tilt, torsion, displacement
    control) added to ``cols`` (over time) and ``scalars``; returns table attributes."""
    nt = ds.sizes["time"]
    W = sol.normal_force
    if sol.name == "hertz_tilted":
        frames = _Frames(ds["p"])
        a = sol.hertz.contact_radius
        R = sol.scene.geometry.radius
        for k in ("err_p0", "err_centroid_cells", "err_phi", "err_moment"):
            cols[k] = np.full(nt, np.nan)
        phi = np.stack([np.asarray(ds[v].values, float) for v in ("phi1", "phi2")], 1)
        mom = np.stack([np.asarray(ds[v].values, float) for v in ("M1", "M2")], 1)
        for k in range(nt):
            p = frames[k]
            tz = sol.tilts[k]
            e = np.array(tz.centre)
            total = float(p.sum())
            centroid = np.array([(p.sum(1) @ x1) / total, (p.sum(0) @ x2) / total]) \
                if total > 0 else np.full(2, np.nan)
            cols["err_p0"][k] = _rel(float(p.max()), tz.max_pressure)
            cols["err_centroid_cells"][k] = float(np.hypot(*(centroid - e))) / cell
            phi_ref = np.array(tz.rotation)
            m_ref = np.array(tz.moments)
            cols["err_phi"][k] = float(np.hypot(*(phi[k] - phi_ref))) / max(
                float(np.hypot(*phi_ref)), a / R)
            cols["err_moment"][k] = float(np.hypot(*(mom[k] - m_ref))) / max(
                float(np.hypot(*m_ref)), W * a)
        return {"tilt_scales": "err_phi relative to |phi_ref| (a/R when phi_ref = 0), "
                               "err_moment to |M_ref| (W a when M_ref = 0), the centroid "
                               "of p against e = (M2/W, M1/W) in cells"}
    if sol.name == "lubkin_torsion":
        m = np.asarray(ds["M3"].values, float)
        m_full = sol.full_slip_torque
        cols["err_M3"] = np.abs(m - sol.torque) / m_full
        attrs = {"full_slip_torque_Nm": m_full, "stuck_stiffness_Nm_per_rad":
                 sol.stuck_stiffness}
        first = _first_branch(sol.twist)
        small = [k for k in first if sol.twist[k] != 0]
        if small:
            k = min(small, key=lambda i: abs(sol.twist[i]))
            scalars["err_stuck_stiffness"] = _rel(m[k] / sol.twist[k], sol.stuck_stiffness)
            attrs["stiffness_twist_rad"] = float(sol.twist[k])
            attrs["stiffness_lubkin_over_stuck"] = float(
                sol.torque[k] / sol.twist[k] / sol.stuck_stiffness)
        k = int(np.argmax(np.abs(sol.twist)))
        if abs(sol.torque[k]) >= 0.99 * m_full:
            scalars["err_full_slip_torque"] = abs(abs(m[k]) - m_full) / m_full
        return attrs
    mu_w = sol.mu * W
    T = np.asarray(ds["T1"].values, float)
    t_ref = sol.displacement_force
    cols["err_T1"] = np.abs(T - t_ref) / mu_w
    first = [k for k in _first_branch(sol.displacement) if abs(sol.displacement[k]) <= sol.delta_gs]
    scalars["err_first_branch"] = float(np.max(cols["err_T1"][first]))
    if np.any(sol.plateau):
        scalars["err_plateau"] = float(np.max(np.abs(np.abs(T[sol.plateau]) / mu_w - 1)))
    attrs = {"delta_gs_m": sol.delta_gs}
    cycles = sol.displacement_cycles()
    if cycles:
        start, stop = cycles[-1]
        e_ref = sol.cycle_energy(start, stop)
        d = np.asarray(ds["dissipation"].values, float)
        om = np.asarray(ds["omega1"].values, float)
        loop = abs(float(np.sum(0.5 * (T[start + 1:stop + 1] + T[start:stop])
                                * np.diff(om[start:stop + 1]))))
        scalars["err_cycle_energy"] = _rel(float(d[stop] - d[start]), e_ref)
        scalars["err_loop_energy"] = _rel(loop, e_ref)
        attrs.update({"cycle_instants": np.array([start, stop], dtype=np.int32),
                      "cycle_energy_J": e_ref})
    return attrs


def _first_branch(series) -> list:
    """The instants of the first monotonic branch from rest: up to the first reversal."""
    v = np.asarray(series, float)
    out, direction = [0], 0
    for k in range(1, v.size):
        step = v[k] - v[k - 1]
        s = 0 if step == 0 else (1 if step > 0 else -1)
        if s and direction and s != direction:
            break
        direction = direction or s
        out.append(k)
    return out


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


def _series_absmax(pair, name) -> float:
    """The largest |name| of the first of ``pair`` that has it, finite and > 0; else 0."""
    for src in pair:
        if name in src:
            s = _absmax(src[name])
            if s > 0 and np.isfinite(s):
                return s
    return 0.0


#: the floor of a relative error, as a fraction of the contact's scale of its unit: far
#: above the rounding of a converged run (the solver's tolerance is ~1e-9 of those scales),
#: far below any quantity of physical size, so only noise meets the floor
NOISE = 1e-6


def physical_scales(ref, ds=None) -> dict:
    """The scales [SI] of a contact that errors are relative to, from the reference
    archive (``ds`` where the reference lacks a variable), by unit: ``Pa`` the peak
    pressure p0, ``N`` the normal force W, ``N m`` W a (a the contact radius
    sqrt(max contact_area / pi)), ``m`` the approach delta (max |omega3|), ``rad``
    delta / a, ``m2`` pi a^2 and ``J`` mu W delta (W delta without friction).

    A difference is divided by max(max |reference|, ``NOISE`` times the scale of its
    unit), so a quantity that is rounding noise in both archives (a torque without twist,
    1e-18 N m) compares as the noise it is, not as an O(1) relative error."""
    pair = (ref,) if ds is None else (ref, ds)
    p0 = _series_absmax(pair, "p")
    W = _series_absmax(pair, "W")
    a = radius_of_area(_series_absmax(pair, "contact_area"))
    delta = _series_absmax(pair, "omega3")
    try:
        mu = float(scene_of(ref).friction.largest)
    except (ArchiveError, AttributeError, TypeError):
        mu = 0.0
    return {"Pa": p0, "N": W, "N m": W * a, "m": delta,
            "rad": delta / a if a > 0 else 0.0, "m2": math.pi * a * a,
            "J": (mu if mu > 0 else 1.0) * W * delta}


def _scale(ds, ref, name, floors) -> float:
    """The scale errors of ``name`` are relative to: max |reference| (tractions: max p),
    floored at ``NOISE`` times the contact's scale of its unit (:func:`physical_scales`)."""
    base = "p" if name in TRACTIONS else name
    unit = str((ref[base] if base in ref else ds[base]).attrs.get("units", ""))
    s = max(_series_absmax((ref, ds), base), NOISE * floors.get(unit, 0.0))
    return s if s > 0 and np.isfinite(s) else 1.0


def _radius_errors(ds, ref_series, floors, cell_side) -> dict:
    """The contact radius's relative error and the stick radius's error in cells, per
    instant, from the areas of ``ds`` and the reference's areas at its instants."""
    a_floor = NOISE * math.sqrt(floors["m2"] / math.pi)
    cols = {}
    for area, name, rel in (("contact_area", "err_contact_radius", True),
                            ("stick_area", "err_stick_radius_cells", False)):
        if area in ref_series:
            mine = np.asarray(ds[area].values, float)
            out = np.full(mine.size, np.nan)
            for k in range(mine.size):
                if np.isfinite(ref_series[area][k]):
                    a, b = radius_of_area(mine[k]), radius_of_area(ref_series[area][k])
                    out[k] = _rel(a, b, a_floor) if rel else abs(a - b) / cell_side
            cols[name] = out
    return cols


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
    x1, x2, d1, d2 = grid_of(ds)
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
    floors = physical_scales(ref, ds)
    scales = {v: _scale(ds, ref, v, floors) for v in fields + series if v != "status"}
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
    cols.update(_radius_errors(ds, ref_series, floors, math.sqrt(d1 * d2)))
    scalars = {}
    if "dissipation" in ref_series:
        last = [k for k in range(nt) if where[k] is not None][-1]
        scalars["err_dissipation"] = _rel(float(ds["dissipation"].values[last]),
                                          float(ref_series["dissipation"][last]),
                                          NOISE * floors["J"])
    table = _table(ds, cols, scalars)
    table.attrs["closed_form"] = "none"
    table.attrs["reference"] = ref_label
    table.attrs["scale_floors"] = ", ".join(f"{u} {v:.4g}" for u, v in floors.items())
    table.attrs["time_axis"] = axis
    table.attrs["interpolated"] = "false" if same_grid else \
        "true (linear in x1, x2; status nearest; cells outside the reference grid left out)"
    return table


_LONG = {
    "err_p_max": "max |p - p_ref| / p0_ref",
    "err_p_rms": "rms of p - p_ref over the contact / p0_ref",
    "err_q1_max": "max |q1 - q1_ref| / (mu p0_ref) over all cells",
    "err_q1_max_interior": "max |q1 - q1_ref| / (mu p0_ref) away from stick/slip "
                           "boundaries and the contact edge",
    "err_q1_rms": "rms of q1 - q1_ref over the contact / (mu p0_ref)",
    "err_contact_radius": "|c_num - c_ref| / c_ref, contact radius sqrt(A / pi)",
    "err_stick_radius_cells": "|c_num - c_ref| / cell, stick radius sqrt(stick_area / pi)",
    "err_omega1": "|omega1 - omega1_ref| / amplitude of the closed-form loop",
    "err_omega3": "|omega3 - omega3_ref| / omega3_ref",
    "err_dissipation": "|D - D_ref| / D_ref at the last instant",
    "err_status": "fraction of cells in contact in either whose status differs",
    "err_p0": "|max p - p0_ref| / p0_ref",
    "err_centroid_cells": "|pressure centroid - e_ref| / cell, e = (M2/W, M1/W)",
    "err_phi": "|(phi1, phi2) - phi_ref| / |phi_ref|",
    "err_moment": "|(M1, M2) - M_ref| / |M_ref|",
    "err_M3": "|M3 - M3_ref| / (3 pi mu W a / 16), Lubkin with Masing's rules",
    "err_stuck_stiffness": "|M3/phi3 - 16 a^3/(3 C)| / (16 a^3/(3 C)) at the smallest "
                           "twist of the first branch",
    "err_full_slip_torque": "||M3| - 3 pi mu W a / 16| / (3 pi mu W a / 16) at the "
                            "largest twist",
    "err_T1": "|T1 - T1_ref| / (mu W), Mindlin-Deresiewicz under displacement control",
    "err_first_branch": "max |T1 - T1_ref| / (mu W) on the first branch up to delta_gs",
    "err_plateau": "max ||T1| / (mu W) - 1| where the closed form slides",
    "err_cycle_energy": "|D - E_ref| / E_ref over the last closed cycle, D the archive's "
                        "dissipation",
    "err_loop_energy": "|loop area - E_ref| / E_ref over the last closed cycle, the area "
                       "of T1 against omega1 by trapezoids",
}


def _table(ds, cols, scalars):
    t = np.asarray(ds["time"].values, float)
    x1, x2, d1, d2 = grid_of(ds)
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
        steps = int(scene_of(ds).time.steps)          # the simulation's, whatever stride
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
                        "err_stick_radius_cells", "err_omega1", "err_dissipation",
                        "err_centroid_cells", "err_phi", "err_M3", "err_stuck_stiffness",
                        "err_full_slip_torque", "err_first_branch", "err_plateau",
                        "err_cycle_energy")
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


# --------------------------------------------------------------------------- public

def _paths(*objs) -> list:
    """The objects that are paths (inputs an output must not overwrite)."""
    return [o for o in objs if isinstance(o, (str, os.PathLike))]


def compare(archive, reference=None, *, out=None) -> xr.Dataset:
    """Errors of an archive against its closed form or against a reference archive.

    Parameters
    ----------
    archive : path or xarray.Dataset
        The archive to check.
    reference : path or xarray.Dataset, optional
        None: the closed form :func:`~contactpipe.pipeline.compare.reference.closed_form_for`
        chooses. An archive: it is interpolated onto ``archive``'s instants (on
        ``t_norm`` = (t - t0)/window when the two windows differ) and cells (linearly;
        status by nearest cell), and every variable the two share is compared (solver
        diagnostics left out).
    out : path, optional
        Write the table there: netCDF if it ends in ``.nc``, CSV if ``.csv`` (atomic).
        Checked before any work (:func:`check_table_path`).

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
        An archive is missing or unreadable, or the two share nothing to compare; ``out``
        has another suffix than ``.nc``, ``.csv``.
    OutputPathError
        ``out`` cannot be written (empty, a directory, a device, one of the inputs).

    See Also
    --------
    contactpipe.pipeline.figures.plot.plot_profiles : the profiles against the closed form or
        the reference (``reference=``).
    """
    if out is not None:
        check_table_path(out, inputs=_paths(archive, reference))
    opened = []
    try:
        ds, label = load_dataset(archive)
        if ds is not archive:
            opened.append(ds)
        with local_reads(synchronous=True):     # many small reads: no thread pool
            if reference is None:
                table = _compare_closed_form(ds, label)
            else:
                ref, ref_label = load_dataset(reference)
                if ref is not reference:
                    opened.append(ref)
                table = _compare_archives(ds, ref, label, ref_label)
    finally:
        for d in opened:
            d.close()
    table.attrs["archive"] = label
    table.attrs["summary"] = _summary(table)
    if out is not None:
        write_table(table, out)
    return table
