"""The regime table of a fretting sweep: each member's loop classified (a fretting map).

:func:`fretting_map` opens every finished member of a sweep folder, reads its fretting
loop (T1 against the imposed omega1) and classifies it by Fouvry's energy ratio
(:mod:`contactpipe.post.fretting`: partial slip, mixed or gross slip), beside the closed-form
regime of Mindlin's elastic sphere (delta* against delta_gs). :func:`write_regime_table`
writes the table as CSV; :mod:`contactpipe.pipeline.figures.fretting` draws the map.

A sweep for a map varies the displacement amplitude (the derived parameters
``delta_amplitude`` [m] or ``delta_ratio`` = delta*/delta_gs of
:mod:`contactpipe.pipeline.sweep.parameters`) against ``friction.mu`` or
``load.normal_force``, on a base scene with a displacement-controlled program such as
``tangential_displacement = [0, 1, -1, 1]`` (x 1e-6 m) over ``time = [0, 1, 3, 5]``.
"""
from __future__ import annotations

import json
import math
import pathlib

import numpy as np
import xarray as xr

from ..._util.files import atomic_path, check_output_dir, check_output_path, make_folder
from ...exceptions import ArchiveError
from ...post.fretting import boundary_constants, fretting_regime
from ..inputs import scene_of
from ..sweep.combine import open_member
from ..sweep.manifest import read_manifest
from ..sweep.members import coord_value, label_of

__all__ = ["fretting_map", "write_regime_table", "COLUMNS"]

#: The table's variables over ``member``: (name, units, long name).
COLUMNS = (
    ("mu", "1", "friction coefficient"),
    ("W", "N", "normal force"),
    ("delta_star", "m", "displacement amplitude of the last cycle"),
    ("force_amplitude", "N", "tangential force amplitude T* of the last cycle"),
    ("energy", "J", "energy dissipated in the last cycle (loop area)"),
    ("energy_ratio", "1", "Fouvry's A = E / (4 T* delta*) of the last cycle"),
    ("delta_gs", "m", "closed-form partial / gross slip boundary 3 mu W C / (16 a)"),
    ("delta_ratio", "1", "delta* / delta_gs"),
    ("energy_ratio_closed_form", "1", "Mindlin-Deresiewicz A at delta* / delta_gs"),
    ("cycles", "1", "closed cycles in the loop"),
)


def _classified(sweep_dir, done):
    """[(member, its FrettingRegime)] of the finished members, and the set of their
    boundary constants (:func:`boundary_constants`)."""
    rows, constants = [], set()
    for m in done:
        ds = open_member(sweep_dir, m)
        try:
            try:
                r = fretting_regime(ds)
            except ArchiveError as err:
                raise ArchiveError(f"sweep member {label_of(m['values'])} ({m['file']}): "
                                   f"{err}") from None
            constants.add(boundary_constants(scene_of(ds)))
        finally:
            ds.close()
        rows.append((m, r))
    return rows, constants


def fretting_map(sweep_dir) -> xr.Dataset:
    """Classify every finished member of a fretting sweep.

    Parameters
    ----------
    sweep_dir : path
        A sweep folder (``manifest.json`` and the member archives).

    Returns
    -------
    xarray.Dataset
        Over the dimension ``member`` (in sweep order): one coordinate per sweep axis
        (``axis_<name>``, e.g. ``axis_friction.mu``, the member's value), the variables of
        :data:`COLUMNS`, ``regime`` and ``regime_closed_form`` (strings; "" where no closed form
        applies) and ``file``.
        Attributes: ``sweep_axes`` (JSON), ``members_not_done``, and where every member
        shares them the boundary's constants ``radius_m``, ``composite_modulus_Pa``,
        ``compliance_sum_per_Pa``.

    Raises
    ------
    ArchiveError
        Not a sweep folder, no finished member, or a member whose archive cannot be read
        or holds no closed fretting cycle (the message names the member).
    """
    sweep_dir = pathlib.Path(sweep_dir)
    manifest = read_manifest(sweep_dir)
    names = list(manifest["axes"])
    done = [m for m in manifest["members"] if m["status"] == "done"]
    if not done:
        raise ArchiveError(f"{sweep_dir}: no member of the sweep is done; run the sweep "
                           f"first")
    rows, constants = _classified(sweep_dir, done)
    data = {}
    values = {
        "mu": [r.friction_coefficient for _, r in rows],
        "W": [r.normal_force for _, r in rows],
        "delta_star": [r.delta_star for _, r in rows],
        "force_amplitude": [r.force_amplitude for _, r in rows],
        "energy": [r.energy for _, r in rows],
        "energy_ratio": [r.ratio for _, r in rows],
        "delta_gs": [r.delta_gs for _, r in rows],
        "delta_ratio": [r.delta_star / r.delta_gs if r.delta_gs > 0 else math.nan
                        for _, r in rows],
        "energy_ratio_closed_form": [r.ratio_closed_form for _, r in rows],
        "cycles": [len(r.cycles) for _, r in rows],
    }
    for name, units, long in COLUMNS:
        data[name] = ("member", np.asarray(values[name], float if name != "cycles" else int),
                      {"units": units, "long_name": long})
    data["regime"] = ("member", np.array([r.regime for _, r in rows], dtype=object),
                      {"long_name": "regime from the energy ratio (A < 0.2 partial slip)"})
    data["regime_closed_form"] = ("member", np.array([r.regime_closed_form for _, r in rows],
                                                     dtype=object),
                                  {"long_name": "regime from delta* against delta_gs"})
    data["file"] = ("member", np.array([m["file"] for m, _ in rows], dtype=object), {})
    coords = {"member": ("member", np.array([m["index"] for m, _ in rows]))}
    for n in names:
        coords[f"axis_{n}"] = ("member", np.array([coord_value(m["values"][n]) for m, _ in rows]),
                     {"long_name": f"sweep axis {n}"})
    table = xr.Dataset(data, coords=coords)
    table.attrs = {"title": "contactpipe fretting map: the regime of each sweep member",
                   "sweep_axes": json.dumps(names),
                   "members_not_done": len(manifest["members"]) - len(done),
                   "criterion": "Fouvry's energy ratio A = E / (4 T* delta*): partial slip "
                                "A < 0.2, gross slip A >= 0.2, mixed when the cycles "
                                "differ"}
    if len(constants) == 1 and None not in constants:
        (radius, e_star, c_sum), = constants
        table.attrs.update({"radius_m": radius, "composite_modulus_Pa": e_star,
                            "compliance_sum_per_Pa": c_sum})
    return table


def write_regime_table(table: xr.Dataset, out) -> pathlib.Path:
    """Write a regime table (:func:`fretting_map`) as CSV, atomically: ``#`` comment lines
    (the attributes), then one row per member (``pandas.read_csv(path, comment="#")``).

    Raises
    ------
    OutputPathError
        ``out`` cannot be written (empty, a directory, a device).
    ArchiveError
        ``out`` does not end in ``.csv``.
    """
    out = check_output_path(out, "regime table")
    if out.suffix.lower() != ".csv":
        raise ArchiveError(f"{out}: the regime table is written as CSV (.csv), got suffix "
                           f"{out.suffix!r}")
    check_output_dir(out.parent, "folder of the regime table")
    make_folder(out.parent)
    lines = [f"# {k}: {' '.join(str(v).split())}" for k, v in table.attrs.items()]
    frame = table.reset_coords().to_dataframe()
    with atomic_path(out) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            f.write("\n".join(lines) + "\n")
            frame.to_csv(f, float_format="%.10g")
    return out
