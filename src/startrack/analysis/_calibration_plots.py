"""Pictures of a calibration: residual maps, residual against radius, distortion field, and the
fixed-mount repeatability errors over time (Fowler 2013 Ch. 9 and App. C).

Plotting only: the numbers come from :mod:`startrack.calibrate`.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np

from ..calibrate import Repeatability, distortion_field_px
from ..camera import Camera
from ..plotting import new_figure
from ..units import ARCMIN
from .postprocess._figures import draw_radial_fit, draw_repeatability

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _save(fig: Figure, path: str | os.PathLike) -> None:
    fig.tight_layout()
    fig.savefig(path)


def plot_residuals(x: np.ndarray, y: np.ndarray, residuals_px: np.ndarray, camera: Camera,
                   path: str | os.PathLike, *, scale: float = 200.0, title: str = "") -> None:
    """Residual vectors on the image (magnified ``scale`` times) and residual distance against the
    distance from the principal point with a 2nd-order fit (Fowler 2013 §VIII.C: an even-order trend
    means radial distortion is left)."""
    fig = new_figure(figsize=(12, 5), dpi=100)
    ax_map, ax_rad = fig.subplots(1, 2)
    ax_map.quiver(x, y, residuals_px[:, 0] * scale, residuals_px[:, 1] * scale, angles="xy", scale_units="xy",
                  scale=1.0, width=0.003)
    ax_map.set_xlim(-0.5, camera.width - 0.5)
    ax_map.set_ylim(camera.height - 0.5, -0.5)
    ax_map.set_aspect("equal")
    ax_map.set_title(f"residuals x {scale:g}" + (f" - {title}" if title else ""))
    radius = np.hypot(x - camera.cx, y - camera.cy)
    dist = np.hypot(residuals_px[:, 0], residuals_px[:, 1])
    draw_radial_fit(ax_rad, radius, dist, np.polyfit(radius, dist, 2) if radius.size >= 3 else None)
    ax_rad.set_xlabel("distance from the principal point, px")
    ax_rad.set_ylabel("residual, px")
    _save(fig, path)


def plot_distortion(camera: Camera, path: str | os.PathLike, *, n: int = 21, title: str = "") -> None:
    """The lens displacement (measured minus pinhole) over the image, arrows and magnitude."""
    x, y, d = distortion_field_px(camera, n)
    fig = new_figure(figsize=(7, 7 * camera.height / camera.width), dpi=100)
    ax = fig.subplots()
    mag = np.hypot(d[:, 0], d[:, 1]).reshape(n, n)
    im = ax.imshow(mag, extent=(-0.5, camera.width - 0.5, camera.height - 0.5, -0.5), cmap="viridis")
    ax.quiver(x, y, d[:, 0], d[:, 1], angles="xy", color="white", width=0.003)
    fig.colorbar(im, ax=ax, label="displacement, px")
    ax.set_title(title or f"distortion of {camera.name or 'camera'}")
    _save(fig, path)


def plot_repeatability(result: Repeatability, path: str | os.PathLike, *, title: str = "") -> None:
    """Total, pointing and roll error of each image against the mean mount, arcmin, over time."""
    fig = new_figure(figsize=(9, 4), dpi=100)
    ax = fig.subplots()
    draw_repeatability(ax, result)
    ax.set_title(title or f"fixed-mount repeatability (mount s.e. {result.mount_standard_error_rad / ARCMIN:.3f}')")
    _save(fig, path)
