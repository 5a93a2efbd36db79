"""Standard figures of an archive, a stress file or a sweep (matplotlib, never pyplot).

``contactpipe plot ARCHIVE.nc -o FIG.png --kind profiles|maps|hysteresis|radii|wear|rough|all``;
``contactpipe plot STRESS.nc -o FIG.png [--kind stress] [--variable FIELD]`` for a stress
file (written by ``contactpipe stress`` or the pipeline's ``[stress]`` product);
``contactpipe plot SWEEP_DIR/ -o FIG.png [--kind sweep] [--variable NAME]`` for a sweep
folder, ``contactpipe plot SWEEP_DIR/ -o FIG.png --kind fretting-map [--against mu|W]`` for
the fretting map of a displacement-controlled fretting sweep. Each kind of input takes its
own kinds (:data:`INPUTS`); a kind that does not apply to the input is one line on stderr
and exit status 2, nothing written.

- :func:`plot_profiles`: p/pH and q1/pH against x1/aH through the centre at a few
  instants, the closed form (black dashes) or a reference archive (black dots) drawn
  on top of the numerical curves (as the paper's figures 2 and 3); pH, aH are the Hertz
  peak pressure and contact radius of the scene with its instantaneous moduli.
- :func:`plot_maps`: p, |q| and the stick/slip status at one instant, axes in mm, side by
  side with their colour bars beneath.
- :func:`plot_hysteresis`: the fretting loop T1 against omega1.
- :func:`plot_radii`: contact and stick radii against time.
- :func:`plot_wear`: the wear figure of a wear run (worn profile at several cycles, wear
  depth map, pressure, worn volume and dissipated energy against cycles;
  :mod:`contactpipe.pipeline.figures.wear`).
- :func:`plot_rough`: maps of h0, p and the status with its clusters at one instant, the
  contact-area and stick fractions against W (or time) and the cluster counts against
  time, readable at 512^2 and more (:mod:`contactpipe.pipeline.figures.rough`).
- :func:`plot_sweep`: one curve per member of a combined sweep Dataset.
- :func:`plot_fretting_map`: the regime of each member of a fretting sweep over the
  displacement amplitude and mu or W, with the closed-form boundary
  (:mod:`contactpipe.pipeline.figures.fretting`); :func:`plot_energy_ratio` its energy ratios.
- :func:`plot_stress`: a stress field or fatigue criterion (von Mises, or the criterion's
  main field when the file holds one) on the x1-x3 plane through the centre and on the
  surface (:mod:`contactpipe.pipeline.figures.stress` draws the panels).
- :func:`standard_figures`: every figure that applies to an archive, written to a folder.

Every plotting function draws into the axes it is given (``ax=``, or ``fig=`` for the
figures with several axes) or into a new :class:`matplotlib.figure.Figure` (8 x 5 in at
100 dpi, tight layout; never pyplot: no global state, no window), and returns the
Figure, so a notebook shows it and a script saves it. :func:`save_figure` is the one
place a figure is written: a PNG of 800 x 500 pixels, written atomically (a temporary
file renamed onto the target) after the path is checked. Inputs given as paths are opened
one way (:func:`open_input`): an archive (verified), a stress file or a sweep folder, told
apart by what the path holds.

    >>> fig = plot_profiles("run.nc")
    >>> save_figure(fig, "profiles.png")
"""
from __future__ import annotations

import argparse
import contextlib
import pathlib
import sys
import warnings

import numpy as np

from ..._util.files import atomic_path, check_output_dir, check_output_path, make_folder
from ..._util.interrupts import raise_if_signalled
from ...exceptions import ArchiveError, ContactpipeError, SceneError, one_line
from ..inputs import centre_rows, grid_of, local_reads, scene_of
from ..sweep.combine import MANIFEST
from .canvas import DPI, FIGSIZE, new_figure
from .common import (
    CLOSED_STYLE,
    INPUTS,
    KINDS,
    _dataset,
    _default_instants,
    _index,
    _opened,
    _profile,
    _scales,
    _scene_title,
    _solution,
    _time_label,
    figure_applies,
    has_tangential_load,
    input_kind,
    is_rough_archive,
    open_input,
)
from .fretting import plot_energy_ratio, plot_fretting_map
from .rough import plot_rough
from .series import plot_hysteresis, plot_radii
from .stress import plot_stress as draw_stress
from .stress import plot_stress_section, plot_stress_surface
from .sweeps import plot_sweep
from .wear import is_wear_archive, plot_wear

__all__ = ["plot_profiles", "plot_maps", "plot_hysteresis", "plot_radii", "plot_sweep",
           "plot_stress", "plot_stress_section", "plot_stress_surface", "plot_fretting_map",
           "plot_energy_ratio", "plot_wear", "plot_rough", "standard_figures",
           "save_figure", "new_figure", "has_tangential_load", "figure_applies",
           "input_kind", "open_input", "add_arguments", "main", "FIGSIZE", "DPI", "KINDS",
           "INPUTS"]

#: The figures of an archive (``all``: every one that applies, into a folder).
#: Each kind of input: what it is called, and the figure kinds that apply (default first).
#: The closed form: black dashes on top of the numerical curves (never hidden under them).
#: A reference archive: black dots on top.
REFERENCE_STYLE = {"color": "k", "ls": ":", "lw": 1.4, "zorder": 4}
STATUS_COLOURS = ("#e6e6e6", "#2c7bb6", "#d7191c")     # separated, stick, slip
#: A map's colour bar under it (the maps side by side then take the figure's width).
COLORBAR_BELOW = {"location": "bottom", "fraction": 0.05, "pad": 0.1, "aspect": 30}


# --------------------------------------------------------------------------- figures

def _grid_axes(fig, nrows, ncols, **kw):
    """(Figure, 2-D array of Axes) drawn into ``fig`` (a new figure when None)."""
    fig = new_figure() if fig is None else fig
    return fig, fig.subplots(nrows, ncols, squeeze=False, **kw)


def save_figure(fig, path) -> pathlib.Path:
    """Write ``fig`` as a PNG (800 x 500 pixels for a figure of :func:`new_figure`).

    The one place figures are written: the path is checked first
    (:func:`contactpipe._util.files.check_output_path`: not empty, not a directory, not a
    device), its folder is created, and the file is written atomically.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    OutputPathError
        ``path`` cannot be written.
    """
    path = check_output_path(path, "figure")
    check_output_dir(path.parent, "folder of the figure")
    make_folder(path.parent)
    with warnings.catch_warnings():
        # the tight layout gives up (with a warning) on axes it cannot fit: drawn as is
        warnings.filterwarnings("ignore", message=".*[Tt]ight.?layout", category=UserWarning)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=DPI)
            raise_if_signalled()     # a signal that waited (a deferred one): not published
    return path


# --------------------------------------------------------------------------- profiles

def _instants(ds, instants) -> list:
    if instants is None:
        return _default_instants(ds)
    if isinstance(instants, (int, np.integer, float, np.floating)):
        return [_index(ds, instants)]
    return [_index(ds, i) for i in instants]


def _draw_closed_form(sol, k, xf, x2_row, scale, ax_p, ax_q):
    """The closed-form profiles at instant k, dashed on top of the numerical ones."""
    with np.errstate(all="ignore"):
        if sol.has_field_pressure():
            pc = sol.pressure(k, xf, x2_row) / scale[0]
            pc = np.where(np.isfinite(pc), pc, np.nan)
            ax_p.plot(xf / scale[1], pc, **CLOSED_STYLE)
        if ax_q is not None and sol.has_field_shear():
            ax_q.plot(xf / scale[1], sol.shear(k, xf, x2_row) / scale[0], **CLOSED_STYLE)


def _draw_reference(ref, tn, scale, ax_p, ax_q):
    """The reference archive's profiles at its instant nearest t_norm = tn, dotted."""
    tr = np.asarray(ref["time"].values, float)
    ref_t = (tr - tr[0]) / (tr[-1] - tr[0]) if tr[-1] > tr[0] else np.zeros_like(tr)
    j = int(np.argmin(np.abs(ref_t - tn)))
    rows = centre_rows(ref["x2"].values)
    xr1 = np.asarray(ref["x1"].values, float) / scale[1]
    ax_p.plot(xr1, _profile(ref["p"], j, rows) / scale[0], **REFERENCE_STYLE)
    if ax_q is not None and "q1" in ref:
        ax_q.plot(xr1, _profile(ref["q1"], j, rows) / scale[0], **REFERENCE_STYLE)


def _profiles(ds, ks, sol, ref, fig):
    """Draw the profiles of ``ds`` at the instants ``ks`` into ``fig`` (closed form
    ``sol`` dashed or reference Dataset ``ref`` dotted, on top); returns the figure."""
    pH, aH, (pn, an) = _scales(ds)
    x1, x2, _, _ = grid_of(ds)
    rows = centre_rows(x2)
    x2_row = float(np.mean(np.abs(x2[rows])))
    shear = "q1" in ds
    fig, axes = _grid_axes(fig, 2 if shear else 1, 1, sharex=True)
    ax_p = axes[0, 0]
    ax_q = axes[1, 0] if shear else None
    panels = (ax_p, ax_q) if shear else (ax_p,)
    xf = np.linspace(x1[0], x1[-1], 601)
    t_all = np.asarray(ds["time"].values, float)
    span = t_all[-1] - t_all[0]
    for n, k in enumerate(ks):
        c, label = f"C{n % 10}", _time_label(ds, k)
        for ax, name in zip(panels, ("p", "q1"), strict=False):
            ax.plot(x1 / aH, _profile(ds[name], k, rows) / pH, "o-", ms=3, lw=1.2,
                    color=c, label=label)
        if sol is not None:
            _draw_closed_form(sol, k, xf, x2_row, (pH, aH), ax_p, ax_q)
        if ref is not None:
            tn = (t_all[k] - t_all[0]) / span if span > 0 else 0.0
            _draw_reference(ref, tn, (pH, aH), ax_p, ax_q)
    grey_label = (f"closed form ({sol.name.replace('_', '-')})" if sol is not None else
                  "reference archive" if ref is not None else None)
    grey_style = CLOSED_STYLE if sol is not None else REFERENCE_STYLE
    for ax, name in zip(panels, ("p", "q1"), strict=False):
        if grey_label:
            ax.plot([], [], **grey_style, label=grey_label)
        ax.set_ylabel(f"{name} / {pn}")
        ax.axhline(0.0, color="0.85", lw=0.6, zorder=-1)
        ax.grid(True, lw=0.3, alpha=0.5)
    if sol is not None and sol.name == "flat_punch":
        top = float(np.max(ds["p"].isel(time=ks).values)) / pH
        ax_p.set_ylim(0.0, 1.3 * top if top > 0 else 1.0)
    ax_p.set_title(f"{_scene_title(ds)}: profiles along x1 through the centre "
                   f"({pn} = {pH / 1e9:.4g} GPa, {an} = {aH * 1e3:.4g} mm)", fontsize=9)
    ax_p.legend(fontsize=7, ncol=2, loc="lower center")
    panels[-1].set_xlabel(f"x1 / {an}")
    return fig


def plot_profiles(ds, instants=None, *, closed_form=True, reference=None, fig=None):
    """p/pH and q1/pH against x1/aH through the centre, at a few instants.

    Parameters
    ----------
    ds : xarray.Dataset or path
        An archive.
    instants : int, float or sequence, optional
        Indices (int, negative from the end) or times [s] (float, the nearest instant).
        Default: about five instants spread over the run, the turning points of T1
        included.
    closed_form : bool
        Draw the closed form (black dashes, on top) where
        :func:`contactpipe.pipeline.compare.reference.closed_form_for` gives one.
    reference : xarray.Dataset or path, optional
        A reference archive drawn (black dots) instead of the closed form, at its instants
        nearest in t_norm = (t - t0)/window.
    fig : matplotlib.figure.Figure, optional
        Draw into it (one axes for p, a second for q1 if the archive has shear); default
        a new figure.

    Returns
    -------
    matplotlib.figure.Figure
        pH, aH are the Hertz peak pressure and contact radius with the scene's
        instantaneous moduli (flat punch: mean pressure and punch radius). An even grid
        has no centre row: the two middle rows are averaged.
    """
    with contextlib.ExitStack() as stack:
        ds = stack.enter_context(_dataset(ds))
        ks = _instants(ds, instants)
        ref = None if reference is None else stack.enter_context(_dataset(reference))
        sol = _solution(ds) if (closed_form and ref is None) else None
        return _profiles(ds, ks, sol, ref, fig)


# --------------------------------------------------------------------------- maps

def _prefixed(value):
    """(factor, unit) to show a stress of magnitude ``value`` [Pa]."""
    for factor, unit in ((1e9, "GPa"), (1e6, "MPa"), (1e3, "kPa")):
        if abs(value) >= factor:
            return factor, unit
    return 1.0, "Pa"


def _map_shear(fig, ax, ds, k, extent, p_max):
    if "q1" in ds:
        q = np.hypot(np.asarray(ds["q1"].isel(time=k).values, float),
                     np.asarray(ds["q2"].isel(time=k).values, float) if "q2" in ds else 0.0)
        fq, uq = _prefixed(float(q.max()) if q.max() > 0 else p_max)
        im = ax.imshow(q.T / fq, origin="lower", extent=extent, cmap="magma",
                       interpolation="nearest")
        fig.colorbar(im, ax=ax, **COLORBAR_BELOW, label=f"|q| [{uq}]")
    else:
        im = ax.imshow(np.zeros((ds.sizes["x2"], ds.sizes["x1"])), origin="lower",
                       extent=extent, cmap="Greys", vmin=0, vmax=1, interpolation="nearest")
        fig.colorbar(im, ax=ax, **COLORBAR_BELOW).ax.set_visible(False)    # aligned maps
        ax.text(0.5, 0.5, "frictionless:\nno shear", transform=ax.transAxes,
                ha="center", va="center", fontsize=9)
    ax.set_title("shear traction |q|", fontsize=9)


def _map_status(fig, ax, ds, k, extent):
    # matplotlib is imported here, not at the top: a heavy import that only drawing needs
    from matplotlib.colors import BoundaryNorm, ListedColormap
    status = np.asarray(ds["status"].isel(time=k).values, float)
    mu = None
    if "mu" in ds.data_vars:                 # a friction map: the archive holds it
        mu = float(np.max(ds["mu"].values))
    else:
        with contextlib.suppress(ArchiveError, SceneError):
            mu = scene_of(ds).friction.largest
    if mu != 0:
        colours, bounds, ticks = STATUS_COLOURS, [-0.5, 0.5, 1.5, 2.5], [0, 1, 2]
        names = ("separated", "stick", "slip")
    else:                                  # frictionless: every contact cell slips
        colours, bounds, ticks = STATUS_COLOURS[::2], [-0.5, 0.5, 2.5], [0, 1.5]
        names = ("separated", "contact")
    cmap = ListedColormap(colours)
    im = ax.imshow(status.T, origin="lower", extent=extent, cmap=cmap,
                   norm=BoundaryNorm(bounds, cmap.N), interpolation="nearest")
    bar = fig.colorbar(im, ax=ax, **COLORBAR_BELOW, ticks=ticks)
    bar.ax.set_xticklabels(names, fontsize=8)
    bar.ax.tick_params(length=0)
    ax.set_title("status", fontsize=9)


def plot_maps(ds, instant=-1, *, fig=None):
    """Maps of p, |q| and the contact status at one instant, axes in mm, side by side
    (each colour bar under its map, so that the maps take the figure's width).

    Parameters
    ----------
    ds : xarray.Dataset or path
    instant : int or float
        Index (negative from the end) or time [s]; default the last instant.
    fig : matplotlib.figure.Figure, optional
        Draw into it (three axes side by side); default a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with _dataset(ds) as ds:
        k = _index(ds, instant)
        x1, x2, d1, d2 = grid_of(ds)
        extent = [(x1[0] - d1 / 2) * 1e3, (x1[-1] + d1 / 2) * 1e3,
                  (x2[0] - d2 / 2) * 1e3, (x2[-1] + d2 / 2) * 1e3]
        fig, axes = _grid_axes(fig, 1, 3, sharey=True)
        p = np.asarray(ds["p"].isel(time=k).values, float)
        f, unit = _prefixed(float(p.max()))
        im = axes[0, 0].imshow(p.T / f, origin="lower", extent=extent, cmap="viridis",
                               interpolation="nearest")
        fig.colorbar(im, ax=axes[0, 0], **COLORBAR_BELOW, label=f"p [{unit}]")
        axes[0, 0].set_title("pressure p", fontsize=9)
        _map_shear(fig, axes[0, 1], ds, k, extent, float(p.max()))
        _map_status(fig, axes[0, 2], ds, k, extent)
        for a in axes[0]:
            a.set_aspect("equal")
            a.tick_params(labelsize=7)
            a.set_xlabel("x1 [mm]", fontsize=8, labelpad=1)
        axes[0, 0].set_ylabel("x2 [mm]", fontsize=8)
        t = float(ds["time"].values[k])
        fig.suptitle(f"{_scene_title(ds)} at t = {t:.4g} s ({_time_label(ds, k)})",
                     fontsize=10)
    return fig


# --------------------------------------------------------------------------- stress

def plot_stress(st, field=None, instant=-1, *, fig=None):
    """The ``stress`` kind: a field on the x1-x3 plane through the centre (depth
    downwards, its largest value marked) and on the surface, side by side.

    Parameters
    ----------
    st : xarray.Dataset or path
        A stress dataset (:func:`contactpipe.subsurface_stress`), a fatigue result
        (:func:`contactpipe.fatigue`), or a stress file (``contactpipe stress``, the
        pipeline's ``[stress]`` product).
    field : str, optional
        The variable drawn; default the criterion's main field when the dataset holds
        one (attribute ``criterion_field``), else ``von_mises``.
    instant : int or float
        Index (negative from the end) or time [s] of a field over time; default the
        last instant.
    fig : matplotlib.figure.Figure, optional
        Draw into it (two axes side by side); default a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ArchiveError
        A path that is not a stress file.
    ValueError
        ``field`` is not a field of the dataset over (x3, x1, x2), after the instant.
    """
    with _opened(st, "stress") as st:
        time = None
        if "time" in st.dims:
            time = float(st["time"].values[_index(st, instant)])
        return draw_stress(st, field, time, fig=new_figure() if fig is None else fig)


# --------------------------------------------------------------------------- all

def standard_figures(ds, out_dir, prefix="", instant=None) -> list[pathlib.Path]:
    """Every figure that applies to an archive, written into ``out_dir``.

    ``<prefix>profiles.png`` and ``<prefix>maps.png`` (at ``instant``) always,
    ``<prefix>hysteresis.png`` for a frictional archive with a tangential load,
    ``<prefix>radii.png`` always, ``<prefix>wear.png`` for the archive of a wear run,
    ``<prefix>rough.png`` for the archive of a rough or measured surface (it holds
    ``h0``; at ``instant``, default the peak tangential load) (:func:`save_figure` each).

    Returns
    -------
    list of pathlib.Path
        The files written, in that order.

    Raises
    ------
    OutputPathError
        ``out_dir`` is not a folder (checked before any drawing).
    """
    out_dir = check_output_dir(out_dir, "figure folder")
    with _dataset(ds) as ds:
        drawn = [("profiles", plot_profiles(ds)),
                 ("maps", plot_maps(ds, -1 if instant is None else instant))]
        if has_tangential_load(ds):
            drawn.append(("hysteresis", plot_hysteresis(ds)))
        drawn.append(("radii", plot_radii(ds)))
        if is_wear_archive(ds):
            drawn.append(("wear", plot_wear(ds)))
        if is_rough_archive(ds):
            drawn.append(("rough", plot_rough(ds, instant)))
    return [save_figure(fig, out_dir / f"{prefix}{kind}.png") for kind, fig in drawn]


# --------------------------------------------------------------------------- CLI

def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("archive", type=pathlib.Path, metavar="INPUT",
                        help="an archive, a stress file (contactpipe stress) or a sweep "
                             "folder")
    # str, not pathlib.Path: Path("") is "." and an empty -o must be refused, not the cwd
    parser.add_argument("-o", "--output", required=True, metavar="FIG",
                        help="the PNG to write (a folder with --kind all)")
    parser.add_argument("--kind", choices=sorted({k for _, ks in INPUTS.values() for k in ks}),
                        default=None,
                        help="which figure: for an archive profiles (default), maps, "
                             "hysteresis, radii, wear (a wear run), rough (maps with "
                             "clusters, contact and stick fractions) or all; for a "
                             "stress file stress; for a sweep folder sweep (default) or "
                             "fretting-map")
    parser.add_argument("--instant", type=int, default=None,
                        help="instant index K (negative from the end): the one profile, "
                             "map or stress field shown")
    parser.add_argument("--variable", default=None,
                        help="sweep folder: the series to plot (default contact_area); "
                             "stress file: the field (default the criterion's, else "
                             "von_mises)")
    parser.add_argument("--against", choices=("mu", "W"), default=None,
                        help="fretting-map: the ordinate, mu or W (default the one the "
                             "members vary)")


def _inputs(source: pathlib.Path) -> list:
    """The files an output must not overwrite: the archive, or a sweep folder's manifest
    and member archives."""
    if source.is_dir():
        return [source / MANIFEST] + sorted(source.glob("*.nc"))
    return [source]


def _kind_error(kind, what, source) -> str:
    applies = "; ".join(f"{name} takes {', '.join(kinds)}" for name, kinds in INPUTS.values())
    return (f"contactpipe: error: --kind {kind} does not apply to {INPUTS[what][0]} "
            f"({source}): {applies}")


def _draw(kind, source, args):
    """The figure ``kind`` of ``source`` (one file)."""
    k = -1 if args.instant is None else args.instant
    if kind == "sweep":
        return plot_sweep(source, args.variable or "contact_area")
    if kind == "fretting-map":
        return plot_fretting_map(source, args.against)
    if kind == "stress":
        return plot_stress(source, args.variable, k)
    if kind == "profiles":
        return plot_profiles(source, None if args.instant is None else [args.instant])
    if kind == "maps":
        return plot_maps(source, k)
    if kind == "wear":
        return plot_wear(source)
    if kind == "rough":
        return plot_rough(source, args.instant)
    return plot_hysteresis(source) if kind == "hysteresis" else plot_radii(source)


def main(args) -> int:
    source = args.archive
    what = input_kind(source)
    kind = args.kind or INPUTS[what][1][0]
    if kind not in INPUTS[what][1]:
        print(_kind_error(kind, what, source), file=sys.stderr)
        return 2
    inputs = _inputs(source)
    try:
        with local_reads():
            written = _write(kind, source, args, inputs)
    except ValueError as err:            # --instant, --variable not in this input: bad input
        if getattr(args, "debug", False) or isinstance(err, ContactpipeError):
            raise
        print(f"contactpipe: error: {one_line(err, with_type=False)}", file=sys.stderr)
        return 2
    for path in written:
        print(f"wrote {path}")
    return 0


def _write(kind, source, args, inputs) -> list:
    """Check the output and write the figure(s) ``kind`` of ``source``: their paths."""
    if kind == "all":
        check_output_dir(args.output, "figure folder", inputs=inputs)
        return standard_figures(source, args.output, "", args.instant)
    target = check_output_path(args.output, "figure", inputs=inputs)
    check_output_dir(target.parent, "folder of the figure")
    return [save_figure(_draw(kind, source, args), target)]
