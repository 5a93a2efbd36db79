"""Figures of a subsurface stress field or a fatigue criterion (matplotlib, no pyplot).

- :func:`plot_stress_section`: a field on the x1-x3 plane through the centre (x2 nearest
  0: the mean of the two middle rows of an even grid), depth downwards from the
  shallowest depth computed (the surface at the top), interpolated between the depths,
  its largest value marked.
- :func:`plot_stress_surface`: the same field on the x1-x2 plane at one depth (the
  shallowest by default).
- :func:`plot_stress`: both side by side (the ``stress`` kind of ``contactpipe plot``).

Each takes a dataset from :func:`contactpipe.subsurface_stress` (field over time, x3,
x1, x2; one instant is drawn, the last by default), from :func:`contactpipe.fatigue`
(field over x3, x1, x2), or a stress file of ``contactpipe stress`` or of the pipeline's
``[stress]`` product (stresses and, when a criterion was asked for, its fields). The
default field is the criterion's main one (attribute ``criterion_field``) when there is
one, else von Mises. Axes in mm, stresses in MPa (dimensionless indices as they are);
the colour bars name the field in mathtext (:data:`MATH_LABELS`).

The conventions of :mod:`contactpipe.pipeline.figures.plot`, which draws these as its ``stress``
kind: every function takes ``ax=None`` / ``fig=None`` and returns the Figure; a new figure
is 8 x 5 in at 100 dpi with a tight layout, never attached to pyplot; figures are written
by :func:`contactpipe.pipeline.figures.plot.save_figure` (atomic, 800 x 500 pixels).
"""
from __future__ import annotations

import numpy as np

from ..inputs import centre_rows

__all__ = ["plot_stress_section", "plot_stress_surface", "plot_stress", "default_field"]

MM = 1e3
#: Rows of the x1-x3 section, linear in depth between the sampled depths.
DEPTH_ROWS = 240
#: Colour-bar labels of the stress and criterion fields, in matplotlib's mathtext (the
#: files keep their plain-text long names); a field not listed shows its long name.
MATH_LABELS = {
    "s11": r"$\sigma_{11}$", "s22": r"$\sigma_{22}$", "s33": r"$\sigma_{33}$",
    "s12": r"$\sigma_{12}$", "s13": r"$\sigma_{13}$", "s23": r"$\sigma_{23}$",
    "von_mises": r"von Mises stress $\sigma_\mathrm{vM}$",
    "equivalent_amplitude": r"equivalent amplitude $\sqrt{3J_{2,a}}$",
    "hydrostatic_mean": r"mean hydrostatic stress $\sigma_{h,\mathrm{mean}}$",
    "hydrostatic_max": r"largest hydrostatic stress $\sigma_{h,\max}$",
    "crossland_index":
        r"Crossland index $(\sqrt{J_{2,a}} + \alpha\,\sigma_{h,\max})/t_{-1}$",
    "crossland_stress": r"Crossland stress $\sqrt{J_{2,a}} + \alpha\,\sigma_{h,\max}$",
    "sqrt_j2_amplitude": r"shear amplitude $\sqrt{J_{2,a}}$",
    "dang_van_index": r"Dang Van index $\mathrm{max}_t(\tau + a\,\sigma_h)/t_{-1}$",
    "dang_van_stress": r"Dang Van stress $\mathrm{max}_t(\tau + a\,\sigma_h)$",
    "mesoscopic_shear": r"mesoscopic shear $\tau$ at the critical instant",
    "hydrostatic": r"hydrostatic stress $\sigma_h$ at the critical instant",
    "swt": r"SWT parameter $\sigma_{n,\max}\,\varepsilon_a$",
    "swt_stress": r"SWT stress $\sqrt{E\,\sigma_{n,\max}\,\varepsilon_a}$",
}


def _new_axes(ax, fig, ncols=1):
    """(Figure, list of Axes): ``ax`` and its figure, or ``ncols`` Axes side by side in
    ``fig`` (a new 8 x 5 in figure at 100 dpi when None, as plot.new_figure)."""
    from matplotlib.figure import Figure  # heavy: only when a figure is drawn
    if ax is not None:
        return ax.get_figure(), [ax]
    if fig is None:
        fig = Figure(figsize=(8.0, 5.0), dpi=100, layout="tight")
    axes = fig.subplots(1, ncols, squeeze=False)[0]
    return fig, list(axes)


def default_field(data) -> str:
    """The field drawn by default: the criterion's main field (``criterion_field``) when
    the dataset holds it, else ``von_mises``."""
    field = data.attrs.get("criterion_field")
    return field if isinstance(field, str) and field in data.data_vars else "von_mises"


def _field(data, field, time):
    """(DataArray over (x3, x1, x2), label, scale, unit) of the field to draw."""
    if field is None:
        field = default_field(data)
    if field not in data.data_vars:
        raise ValueError(f"field {field!r} is not in the dataset (it has "
                         f"{', '.join(v for v in data.data_vars if data[v].ndim >= 3)})")
    da = data[field]
    title = ""
    if "time" in da.dims:
        if time is None:
            k = da.sizes["time"] - 1
        else:
            t = np.asarray(data["time"].values, float)
            k = int(np.argmin(np.abs(t - float(time))))
        da = da.isel(time=k)
        title = f"t = {float(data['time'].values[k]):.4g} s"
    if tuple(da.dims) != ("x3", "x1", "x2"):
        raise ValueError(f"field {field!r} has dims {da.dims}: expected (x3, x1, x2) "
                         "(after the instant is chosen)")
    unit = da.attrs.get("units", "")
    scale, shown = (1e-6, "MPa") if unit == "Pa" else (1.0, unit)
    label = MATH_LABELS.get(field, da.attrs.get("long_name", field)) \
        + (f" [{shown}]" if shown and shown != "1" else "")
    return da, field, label, scale, title


def plot_stress_section(data, field=None, time=None, ax=None):
    """A field on the x1-x3 plane through the centre of the grid.

    Parameters
    ----------
    data : xarray.Dataset
        A stress dataset (:func:`contactpipe.subsurface_stress`) or a fatigue result
        (:func:`contactpipe.fatigue`).
    field : str, optional
        Variable to draw; default von Mises, or the fatigue criterion's main field.
    time : float, optional
        Instant [s] (the nearest one) of a stress dataset; default the last.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    da, name, label, scale, title = _field(data, field, time)
    fig, (ax,) = _new_axes(ax, None)
    rows = centre_rows(da["x2"].values)
    sec = np.asarray(da.isel(x2=rows).values, float).mean(axis=2) * scale    # (x3, x1)
    x1 = da["x1"].values * MM
    x3 = da["x3"].values * MM
    if len(x3) > 1:
        # linear between the sampled depths: the plane runs from the shallowest depth
        # (the surface, x3 = 0, at the top) to the deepest, no block above the surface
        fine = np.linspace(x3[0], x3[-1], DEPTH_ROWS)
        j = np.clip(np.searchsorted(x3, fine, side="right") - 1, 0, len(x3) - 2)
        w = ((fine - x3[j]) / (x3[j + 1] - x3[j]))[:, None]
        half = 0.5 * (x1[1] - x1[0]) if len(x1) > 1 else 0.5
        mesh = ax.imshow((1.0 - w) * sec[j] + w * sec[j + 1], origin="upper",
                         extent=(x1[0] - half, x1[-1] + half, x3[-1], x3[0]),
                         aspect="auto", interpolation="nearest", cmap="viridis")
    else:
        mesh = None
        ax.plot(x1, sec[0])
    k3, k1 = np.unravel_index(int(np.nanargmax(sec)), sec.shape)
    if mesh is not None:
        fig.colorbar(mesh, ax=ax, label=label)
        from matplotlib.patheffects import withStroke  # heavy: only when drawing
        # outlined and not clipped: whole, and seen on white, when it lies at x3 = 0
        ax.plot(x1[k1], x3[k3], "w+", ms=12, mew=2, clip_on=False,
                path_effects=[withStroke(linewidth=4, foreground="k")])
        ax.set_ylabel("depth x3 [mm]")
    else:
        ax.set_ylabel(label)
    ax.set_xlabel("x1 [mm]")
    x2c = float(np.mean(da["x2"].values[rows])) * MM
    x2c = 0.0 if abs(x2c) < 1e-9 else x2c
    ax.set_title(f"{name} at x2 = {x2c:.3g} mm" + (f", {title}" if title else "")
                 + f"\nmax {sec[k3, k1]:.4g} at x1 = {x1[k1]:.3g} mm, x3 = {x3[k3]:.3g} mm",
                 fontsize=9)
    return fig


def plot_stress_surface(data, field=None, x3=None, time=None, ax=None):
    """A field on the x1-x2 plane at one depth (default: the shallowest).

    Parameters are those of :func:`plot_stress_section`, and ``x3`` [m] (the nearest
    depth of the dataset). Returns the Figure.
    """
    da, name, label, scale, title = _field(data, field, time)
    fig, (ax,) = _new_axes(ax, None)
    z = np.asarray(da["x3"].values, float)
    k = 0 if x3 is None else int(np.argmin(np.abs(z - float(x3))))
    m = np.asarray(da.isel(x3=k).values, float) * scale                     # (x1, x2)
    mesh = ax.pcolormesh(da["x1"].values * MM, da["x2"].values * MM, m.T,
                         shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_aspect("equal")
    ax.set_xlabel("x1 [mm]")
    ax.set_ylabel("x2 [mm]")
    ax.set_title(f"{name} at x3 = {z[k] * MM:.3g} mm" + (f", {title}" if title else ""),
                 fontsize=9)
    return fig


def plot_stress(data, field=None, time=None, fig=None):
    """The x1-x3 section through the centre and the surface map, side by side.

    Returns the Figure (a new one unless ``fig`` is given).
    """
    fig, axes = _new_axes(None, fig, ncols=2)
    from matplotlib.layout_engine import TightLayoutEngine  # heavy: only when drawing
    if isinstance(fig.get_layout_engine(), TightLayoutEngine):
        fig.get_layout_engine().set(w_pad=4.0)   # the section's colour-bar label clear of
    plot_stress_section(data, field, time, ax=axes[0])         # the map's x2 label
    plot_stress_surface(data, field, None, time, ax=axes[1])
    return fig

