"""Figures of an archive's time series: the hysteresis loop T(delta) and the contact and
stick radii over time."""
from __future__ import annotations

import math

import numpy as np

from ...exceptions import ArchiveError
from .canvas import axes_of
from .common import CLOSED_STYLE, _dataset, _frictional, _scene_title, _solution

__all__ = ["plot_hysteresis", "plot_radii"]

# --------------------------------------------------------------------------- series

def _require_frictional(ds, what):
    if not _frictional(ds):
        raise ArchiveError(f"{what} needs a frictional archive (variables T1, omega1, q1); "
                           f"this one is frictionless (models: "
                           f"{ds.attrs.get('models', '?')})")


def plot_hysteresis(ds, *, ax=None):
    """The fretting loop: T1 [N] against omega1 [um], the closed form (MD) dashed on top.

    Parameters
    ----------
    ds : xarray.Dataset or path
    ax : matplotlib.axes.Axes, optional
        Draw into it; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ArchiveError
        The archive is frictionless (no T1, omega1).
    """
    with _dataset(ds) as ds:
        _require_frictional(ds, "the hysteresis loop")
        fig, ax = axes_of(ax)
        om = np.asarray(ds["omega1"].values, float)
        T = np.asarray(ds["T1"].values, float)
        sol = _solution(ds)
        loop = sol.loop() if sol is not None else None
        if loop is not None:
            ax.plot(loop[1] * 1e6, loop[0], **CLOSED_STYLE,
                    label="closed form (Mindlin-Deresiewicz)")
        ax.plot(om * 1e6, T, "o-", ms=3, lw=1.2, color="C0", label="numerical")
        ax.set_xlabel("omega1 [µm]")
        ax.set_ylabel("T1 [N]")
        ax.axhline(0.0, color="0.85", lw=0.6, zorder=-1)
        ax.axvline(0.0, color="0.85", lw=0.6, zorder=-1)
        if "dissipation" in ds:
            ax.set_title(f"{_scene_title(ds)}: tangential force against rigid displacement "
                         f"(dissipated {float(ds['dissipation'].values[-1]):.4g} J)",
                         fontsize=9)
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(fontsize=8)
    return fig


def plot_radii(ds, *, ax=None):
    """Contact radius sqrt(A/pi) and stick radius sqrt(A_stick/pi) [mm] against time [s],
    closed forms dashed on top where they apply.

    Parameters
    ----------
    ds : xarray.Dataset or path
    ax : matplotlib.axes.Axes, optional
        Draw into it; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    with _dataset(ds) as ds:
        fig, ax = axes_of(ax)
        t = np.asarray(ds["time"].values, float)
        a = np.sqrt(np.asarray(ds["contact_area"].values, float) / math.pi)
        ax.plot(t, a * 1e3, "o-", ms=3, color="C0", label="contact radius")
        if "stick_area" in ds:
            c = np.sqrt(np.asarray(ds["stick_area"].values, float) / math.pi)
            ax.plot(t, c * 1e3, "s-", ms=3, color="C3", label="stick radius")
        sol = _solution(ds)
        if sol is not None:
            n = t.size
            ax.plot(t, [sol.contact_radius(k) * 1e3 for k in range(n)], **CLOSED_STYLE,
                    label=f"closed form ({sol.name.replace('_', '-')})")
            if sol.name == "mindlin_deresiewicz":
                ax.plot(t, [sol.stick_radius(k) * 1e3 for k in range(n)], **CLOSED_STYLE)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("radius [mm]")
        ax.set_ylim(bottom=0.0)
        ax.set_title(f"{_scene_title(ds)}: radii of the circles of equal area", fontsize=9)
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(fontsize=8)
    return fig
