"""The plot of a sky prediction (``cistrack predict``): the predicted path on the sky with its
3-sigma ellipses, and the 3-sigma semi-axes against time.

The left panel shows RA (increasing to the left, as on the sky) against Dec, degrees, with the
3-sigma ellipse at each predicted time. Ellipses of arcseconds would be invisible on a path of
degrees, so they are drawn magnified by one factor that the title states (the right panel gives
their true size). Drawn with matplotlib's object interface (no global backend is changed).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cistrack import units

__all__ = ["plot_sky", "sky_figure"]


def _magnification(sky, a3: np.ndarray) -> float:
    """Factor that makes the largest 3-sigma ellipse about a tenth of the path's extent (at least 1)."""
    cos_dec = np.cos(np.radians(np.mean(sky.dec_deg)))
    extent = max(np.ptp(sky.ra_deg) * cos_dec, np.ptp(sky.dec_deg), 1.0 / 60.0) * 3600.0
    biggest = float(np.max(a3)) if a3.size and np.max(a3) > 0 else 1.0
    return max(1.0, float(10 ** np.floor(np.log10(0.1 * extent / biggest))))


def _ellipse_points(sky, k: int, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """RA, Dec (degrees) of the 3-sigma ellipse of time ``k``, magnified ``scale`` times."""
    w, v = np.linalg.eigh(sky.covariance_arcsec2[k])
    ang = np.linspace(0.0, 2 * np.pi, 73)
    circle = np.stack([np.cos(ang), np.sin(ang)])
    east_north = v @ (3.0 * np.sqrt(np.clip(w, 0, None))[:, None] * circle) * scale / 3600.0
    return (sky.ra_deg[k] + east_north[0] / np.cos(np.radians(sky.dec_deg[k])), sky.dec_deg[k] + east_north[1])


def sky_figure(sky, title: str):
    """The matplotlib Figure of a :class:`~cistrack.fitting.sky_ephemeris.SkyEphemeris`."""
    from matplotlib.figure import Figure

    a, b, _ = sky.ellipse()
    scale = _magnification(sky, 3 * a)
    fig = Figure(figsize=(12, 5.5))
    ax, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.4, 1]})
    ax.plot(sky.ra_deg, sky.dec_deg, ".-", color="0.3", ms=3, lw=0.8, label="predicted path")
    for k in range(len(sky.utc)):
        ra, dec = _ellipse_points(sky, k, scale)
        ax.plot(ra, dec, color="tab:blue" if not sky.linear[k] else "tab:orange", lw=0.8)
    ax.annotate(sky.utc[0][:16], (sky.ra_deg[0], sky.dec_deg[0]), fontsize=8)
    ax.annotate(sky.utc[-1][:16], (sky.ra_deg[-1], sky.dec_deg[-1]), fontsize=8)
    up = sky.elevation_deg > 0
    ax.plot(sky.ra_deg[up], sky.dec_deg[up], "o", color="tab:green", ms=3, label="above the horizon")
    ax.invert_xaxis()
    ax.set_aspect(1.0 / max(np.cos(np.radians(np.mean(sky.dec_deg))), 0.05), adjustable="datalim")
    ax.set_xlabel("RA (deg, ICRF, topocentric astrometric)")
    ax.set_ylabel("Dec (deg)")
    held = ", widened to hold the fit's line of variations" if sky.line_reach_arcsec is not None else ""
    ax.set_title((f"3-sigma ellipses x{scale:g}" if scale > 1 else "3-sigma ellipses (true size)") + held, fontsize=10)
    ax.legend(loc="best", fontsize=8)
    hours = (sky.t_tu - sky.t_tu[0]) * units.TU_S / 3600.0
    ax2.plot(hours, 3 * a, label="3-sigma semi-major")
    ax2.plot(hours, 3 * b, label="3-sigma semi-minor")
    ax2.set_xlabel(f"hours after {sky.utc[0]}")
    ax2.set_ylabel("arcsec")
    ax2.set_ylim(bottom=0)
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    return fig


def plot_sky(sky, path: str | Path, title: str) -> Path:
    """Write the PNG of :func:`sky_figure` to ``path`` (whole or not at all); returns it. Raises
    CistrackError naming ``path`` when it cannot be written."""
    from cistrack.errors import CistrackError
    from cistrack.fitting.residual_plots import save_figure

    try:
        return save_figure(sky_figure(sky, title), Path(path))
    except OSError as exc:
        raise CistrackError(f"{path}: cannot write the sky plot ({exc.strerror or exc}); nothing was "
                            "written there") from None
