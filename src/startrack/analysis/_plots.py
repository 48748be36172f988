"""Pictures of results: an image annotated with its detections and identified stars.

Plotting only: no I/O beyond saving the figure, no maths beyond display scaling.
"""

from __future__ import annotations

import os
from typing import IO

import numpy as np

from ..catalog import constellation_of
from ..plotting import new_figure
from ..results import AttitudeSolution, Detections


def display_stretch(image: np.ndarray) -> np.ndarray:
    """Image scaled for display: asinh of the counts above the median, clipped at the 99.9th percentile."""
    data = np.asarray(image, dtype=float)
    if data.ndim == 3:
        data = data[..., :3].mean(axis=2)
    lo = np.nanmedian(data)
    hi = max(np.nanpercentile(data, 99.9), lo + 1e-9)
    scaled = np.clip((data - lo) / (hi - lo), 0, 1)
    return np.arcsinh(10 * scaled) / np.arcsinh(10)


def plot_solution(image: np.ndarray, detections: Detections, solution: AttitudeSolution,
                  path: str | os.PathLike, *, truth_xy: tuple[np.ndarray, np.ndarray] | None = None,
                  title: str | None = None) -> None:
    """Save a PNG of the image with detections (grey), identified stars (green, HIP numbers) and,
    optionally, the true star positions (red crosses)."""
    height, width = np.asarray(image).shape[:2]
    fig = new_figure(figsize=(8, 8 * height / width), dpi=110)
    ax = fig.subplots()
    ax.imshow(display_stretch(image), cmap="gray", origin="upper", extent=(-0.5, width - 0.5, height - 0.5, -0.5))
    ax.scatter(detections.x, detections.y, s=90, facecolors="none", edgecolors="0.6", linewidths=0.8)
    if truth_xy is not None:
        ax.scatter(*truth_xy, s=25, marker="x", color="tab:red", linewidths=0.8, label="truth")
    if solution.solved:
        idx = solution.matches.det_index
        ax.scatter(detections.x[idx], detections.y[idx], s=160, facecolors="none", edgecolors="lime", linewidths=1.2)
        for i, hip in zip(idx[:25], solution.matches.hip[:25], strict=False):
            ax.annotate(f"HIP {hip}", (detections.x[i], detections.y[i]), xytext=(6, -6),
                        textcoords="offset points", color="lime", fontsize=7)
    ax.set_title(title or solution_title(solution), fontsize=9)
    ax.set_xlim(-0.5, width - 0.5)
    ax.set_ylim(height - 0.5, -0.5)
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    fig.tight_layout()
    fig.savefig(path, format="png")  # whatever the name ends with: a command's temporary file


def solution_title(solution: AttitudeSolution) -> str:
    """One line for a picture of a solve: the boresight (deg, ICRS) and its constellation, roll,
    field of view and stars matched; or why it was not solved."""
    if not solution.solved:
        return f"not solved: {solution.reason}"
    where = constellation_of(solution.ra_deg, solution.dec_deg)
    return (f"RA {solution.ra_deg:.4f}  Dec {solution.dec_deg:+.4f}  ({where})  roll {solution.roll_deg:.3f} deg  "
            f"FOV {solution.fov_deg:.3f} deg  {len(solution.matches)} stars matched")


def plot_star_counts(availability, path: str | os.PathLike | IO, *, title: str = "") -> None:
    """Save a histogram of stars in the field over random pointings (Jacobs 1995 Fig. 5-1) to a
    PNG file (a path or a binary file object)."""
    hist = availability.histogram
    fig = new_figure(figsize=(7, 4), dpi=110)
    ax = fig.subplots()
    ax.bar(np.arange(hist.size), hist / hist.sum(), width=0.9, color="tab:blue")
    ax.set_xlabel("stars in the image")
    ax.set_ylabel("fraction of pointings")
    ax.set_title(title or f"{availability.counts.size} random pointings, V <= {availability.max_mag:g} "
                          f"({availability.n_catalog} stars); P(< 3) = {availability.probability_below(3):.4f}",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path)
