"""The annotated frame of a solve job: what the detector kept and refused, what was identified.

Drawn on the display stretch of :func:`startrack.analysis._plots.display_stretch` with the object
API of matplotlib (a :class:`~matplotlib.figure.Figure`, no pyplot state):

- detections kept: grey circles; refused: crosses coloured by the filter that refused them
  (:mod:`._rejects`);
- matched stars: green circles labelled with the HIP number and the catalog V magnitude; those
  measured where the solution predicts them (the ``guided`` option): cyan diamonds as well;
- residual vectors: from each matched spot to where the fitted attitude puts its catalog star,
  magnified (the factor is in the legend) so that the median vector is about 4 % of the width;
- an RA / Dec grid (dotted, labelled in degrees) and a compass (north and east at the image
  centre) from the fitted attitude and camera;
- the true star positions of a simulated image (red plus signs) when the file carries them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..analysis import display_stretch, solution_title
from ..camera import Camera
from ..catalog import load_catalog
from ..errors import require
from ..frames import radec_to_vector
from ..io import atomic_path
from ..plotting import new_figure
from ..results import AttitudeSolution, Detections

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation

REJECT_COLOURS = {"area": "tab:orange", "elongation": "tab:purple", "edge": "tab:brown", "hot pixel": "magenta",
                  "peak SNR": "tab:olive", "clutter": "tab:red", "other": "tab:pink"}
MAX_LABELS = 30
LONG_SIDE_IN = 9.0
DPI = 110
GRID_STEPS_DEG = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 30.0)


def write_annotated(path: Path, image: NDArray, solution: AttitudeSolution, detections: Detections,
                    rejects: dict[str, list], truth_xy: tuple[NDArray, NDArray] | None = None) -> None:
    """Draw the annotated frame (module docstring) and save it as PNG, atomically."""
    height, width = image.shape[:2]
    long_side = max(width, height)
    w_in, h_in = LONG_SIDE_IN * width / long_side, LONG_SIDE_IN * height / long_side
    fig = new_figure(figsize=(w_in + 0.9, h_in + 0.8), dpi=DPI)
    ax = fig.add_axes((0.7 / (w_in + 0.9), 0.5 / (h_in + 0.8), w_in / (w_in + 0.9), h_in / (h_in + 0.8)))
    ax.imshow(display_stretch(image), cmap="gray", origin="upper", extent=(-0.5, width - 0.5, height - 0.5, -0.5),
              interpolation="nearest" if long_side <= DPI * LONG_SIDE_IN else "antialiased")
    kept = len(detections) - solution.guided_stars  # the guided stars, last, were not detected
    ax.scatter(detections.x[:kept], detections.y[:kept], s=70, facecolors="none", edgecolors="0.7", linewidths=0.7,
               label=f"kept ({kept})")
    _draw_rejects(ax, rejects)
    if truth_xy is not None:
        ax.scatter(*truth_xy, s=30, marker="+", color="red", linewidths=0.8, label="truth")
    if solution.solved:
        _draw_grid(ax, solution)
        _draw_matches(ax, solution, detections)
        _draw_guided(ax, solution, detections)
        _draw_compass(ax, solution, width, height)
    ax.set_xlim(-0.5, width - 0.5)
    ax.set_ylim(height - 0.5, -0.5)
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    ax.set_title(solution_title(solution), fontsize=9)
    ax.legend(loc="lower left", fontsize=7, framealpha=0.7, ncols=2)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", pil_kwargs={"compress_level": 1})


def _camera(solution: AttitudeSolution) -> Camera:
    return require(solution.camera, "a solved frame's camera")


def _rotation(solution: AttitudeSolution) -> Rotation:
    return require(solution.rot_cam_from_icrs, "a solved frame's attitude")


def _draw_rejects(ax, rejects: dict[str, list]) -> None:
    categories = np.asarray(rejects.get("category", []), dtype=object)
    for category, colour in REJECT_COLOURS.items():
        mask = categories == category
        if np.any(mask):
            ax.scatter(np.asarray(rejects["x"])[mask], np.asarray(rejects["y"])[mask], s=28, marker="x",
                       color=colour, linewidths=0.9, label=f"refused: {category} ({int(mask.sum())})")


def _draw_matches(ax, solution: AttitudeSolution, det: Detections) -> None:
    idx, hip = solution.matches.det_index, solution.matches.hip
    x, y = det.x[idx], det.y[idx]
    ax.scatter(x, y, s=150, facecolors="none", edgecolors="lime", linewidths=1.1, label=f"matched ({len(idx)})")
    catalog = load_catalog()
    mags = catalog.v_mag[np.searchsorted(catalog.hip, hip)]
    for i in range(min(len(idx), MAX_LABELS)):
        ax.annotate(f"HIP {hip[i]}  V{mags[i]:.1f}", (x[i], y[i]), xytext=(7, -7), textcoords="offset points",
                    color="lime", fontsize=6.5)
    px, py = _camera(solution).vector_to_pixel(_rotation(solution).apply(solution.matches.cat_vectors))
    dx, dy = px - x, py - y
    gain = residual_gain(np.hypot(dx, dy), det.width or int(ax.get_xlim()[1]))
    ax.quiver(x, y, dx * gain, dy * gain, angles="xy", scale_units="xy", scale=1.0, color="yellow", width=0.003,
              label=f"residual x {gain:g}")


def _draw_guided(ax, solution: AttitudeSolution, det: Detections) -> None:
    """The stars measured where the solution predicts them (its detections' last rows)."""
    n = solution.guided_stars
    if n:
        ax.scatter(det.x[-n:], det.y[-n:], s=60, marker="D", facecolors="none", edgecolors="cyan", linewidths=0.9,
                   label=f"measured where predicted ({n})")


def residual_gain(lengths_px: NDArray, width_px: int) -> float:
    """A round magnification (1, 2, 5 x 10^k) that makes the median residual ~4 % of the width."""
    median = float(np.median(lengths_px)) if len(lengths_px) else 0.0
    if not median > 0:
        return 1.0
    target = 0.04 * width_px / median
    exponent = math.floor(math.log10(target))
    mantissa = max((m for m in (1, 2, 5) if m * 10**exponent <= target), default=1)
    return float(max(1.0, mantissa * 10**exponent))


def grid_step_deg(fov_deg: float) -> float:
    """A round grid spacing giving about four lines across the field."""
    return min((s for s in GRID_STEPS_DEG if s >= fov_deg / 5), default=GRID_STEPS_DEG[-1])


def _project(solution: AttitudeSolution, ra_deg: NDArray, dec_deg: NDArray) -> tuple[NDArray, NDArray]:
    vectors = radec_to_vector(np.radians(ra_deg), np.radians(dec_deg))
    return _camera(solution).vector_to_pixel(_rotation(solution).apply(vectors))


def _draw_grid(ax, solution: AttitudeSolution) -> None:
    """Lines of constant RA and Dec at a round spacing, labelled where they cross the frame's middle."""
    step = grid_step_deg(solution.fov_deg)
    span = _camera(solution).fov_diagonal_deg
    dec0 = solution.dec_deg
    near_pole = abs(dec0) + span > 80
    ra_span = 180.0 if near_pole else min(180.0, span / max(math.cos(math.radians(abs(dec0) + span / 2)), 0.05))
    ra_step = step if near_pole or ra_span < 90 else max(step, 15.0)
    decs = np.arange(math.floor((dec0 - span) / step) * step, dec0 + span + step, step)
    ras = np.arange(math.floor((solution.ra_deg - ra_span) / ra_step) * ra_step, solution.ra_deg + ra_span + ra_step,
                    ra_step)
    fine = np.linspace(0.0, 1.0, 200)
    lines = [(np.full_like(fine, ra), decs[0] + fine * (decs[-1] - decs[0]), f"RA {ra % 360:g}°") for ra in ras]
    lines += [(ras[0] + fine * (ras[-1] - ras[0]), np.full_like(fine, dec), f"Dec {dec:+g}°")
              for dec in decs if abs(dec) < 90]
    for ra, dec, label in lines:
        x, y = _project(solution, ra, np.clip(dec, -90, 90))
        inside = _camera(solution).in_image(x, y)
        if np.count_nonzero(inside) < 2:
            continue
        ax.plot(np.where(inside, x, np.nan), np.where(inside, y, np.nan), ":", color="deepskyblue", linewidth=0.7)
        k = int(np.flatnonzero(inside)[np.count_nonzero(inside) // 2])
        ax.text(x[k], y[k], label, color="deepskyblue", fontsize=6.5, ha="center", va="center",
                bbox={"boxstyle": "round,pad=0.1", "fc": "black", "alpha": 0.4, "lw": 0})


def _draw_compass(ax, solution: AttitudeSolution, width: int, height: int) -> None:
    """North and east arrows of ~1/8 of the width at the image centre."""
    cx, cy = (width - 1) / 2, (height - 1) / 2
    centre_icrs = _rotation(solution).inv().apply(_camera(solution).pixel_to_vector(cx, cy))
    ra, dec = math.atan2(centre_icrs[1], centre_icrs[0]), math.asin(np.clip(centre_icrs[2], -1, 1))
    arm = 0.12 * width / _camera(solution).fx  # radians
    for name, (dra, ddec) in (("N", (0.0, arm)), ("E", (arm / max(math.cos(dec), 1e-3), 0.0))):
        tip = radec_to_vector(ra + dra, np.clip(dec + ddec, -math.pi / 2, math.pi / 2))
        x, y = _camera(solution).vector_to_pixel(_rotation(solution).apply(tip))
        ax.annotate("", xy=(float(x), float(y)), xytext=(cx, cy),
                    arrowprops={"arrowstyle": "->", "color": "orange", "lw": 1.4})
        ax.text(float(x), float(y), name, color="orange", fontsize=9, fontweight="bold", ha="center", va="center")
