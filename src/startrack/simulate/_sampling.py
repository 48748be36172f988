"""Where point sources are during an exposure: pixel positions at sub-step times, and which
sources reach the image.

A source is given by its ICRS direction as a function of time (fixed for a star, the line of
sight for a satellite); the attitude profile (:mod:`._motion`) rotates it into the camera frame
and the camera model (distortion included) projects it. :func:`sample_sources` picks the
sub-steps (:mod:`._streaks`), keeps the sources whose PSF stamp reaches the image at some sub-step,
and returns the samples with the start, mid and end positions for the truth.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera
from ._motion import AttitudeProfile
from ._streaks import Samples, Shutter, path_length_px, sub_intervals, substeps

COARSE_SAMPLES = 9
"""Samples of the first pass that estimates the path length and visibility."""
ROW_TIME_ITERATIONS = 3



class Directions(Protocol):
    """ICRS unit vectors of N sources as functions of time."""

    def __len__(self) -> int: ...

    def __call__(self, times: NDArray[np.float64]) -> NDArray[np.float64]:
        """Directions (N, m, 3) at ``times`` (N, m)."""

    def take(self, index: NDArray[np.intp]) -> Directions:
        """The sources ``index`` only."""


@dataclass(frozen=True)
class FixedDirections:
    """Sources fixed in ICRS (stars): ``vectors`` (N, 3)."""

    vectors: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.vectors.shape[0])

    def __call__(self, times: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.broadcast_to(self.vectors[:, None, :], (len(self), times.shape[-1], 3))

    def take(self, index: NDArray[np.intp]) -> FixedDirections:
        return FixedDirections(self.vectors[index])


@dataclass(frozen=True)
class SourcePaths:
    """The sources that reach the image and their samples.

    Attributes
    ----------
    keep : ndarray of int, shape (K,)
        Indices of those sources among the N given.
    samples : Samples
        Their sub-step positions, shape (K, n).
    start, mid, end : tuple of ndarray (x, y), each (K,)
        Positions at the start, middle and end of each source's exposure.
    """

    keep: NDArray[np.intp]
    samples: Samples
    start: tuple[NDArray[np.float64], NDArray[np.float64]]
    mid: tuple[NDArray[np.float64], NDArray[np.float64]]
    end: tuple[NDArray[np.float64], NDArray[np.float64]]


def camera_vectors(profile: AttitudeProfile, times: NDArray, directions: NDArray) -> NDArray[np.float64]:
    """Camera-frame vectors (N, m, 3) of ICRS directions (N, m, 3) at ``times`` (m,) or (N, m)."""
    if times.ndim == 1:
        mats = profile.attitudes(times).as_matrix()  # (m, 3, 3)
        return np.einsum("mij,nmj->nmi", mats, directions)
    mats = profile.attitudes(times.ravel()).as_matrix().reshape(*times.shape, 3, 3)
    return np.einsum("nmij,nmj->nmi", mats, directions)


def project(camera: Camera, v_cam: NDArray, max_off_axis_rad: float) -> tuple[NDArray, NDArray]:
    """Pixels (N, m) of camera vectors; NaN behind the camera or beyond ``max_off_axis_rad``
    (where a distortion polynomial could fold a direction back into the image)."""
    x, y = camera.vector_to_pixel(v_cam)
    off_axis = np.arctan2(np.hypot(v_cam[..., 0], v_cam[..., 1]), v_cam[..., 2])
    far = ~(off_axis <= max_off_axis_rad)
    return np.where(far, np.nan, x), np.where(far, np.nan, y)


def positions(camera, profile, directions: Directions, times: NDArray,
               max_off_axis_rad: float) -> tuple[NDArray, NDArray]:
    """Pixels (N, m) of the sources at ``times``: (m,) shared by all, or (N, m)."""
    if len(directions) == 0:
        return np.zeros((0, times.shape[-1])), np.zeros((0, times.shape[-1]))
    grid = np.broadcast_to(times, (len(directions), times.shape[-1]))
    v_cam = camera_vectors(profile, times, directions(grid))
    return project(camera, v_cam, max_off_axis_rad)


def _near_image(camera: Camera, x: NDArray, y: NDArray, margin: NDArray | float) -> NDArray[np.bool_]:
    """Sources (rows) with a sample within ``margin`` px (per source or common) of the image."""
    margin = np.broadcast_to(np.asarray(margin, dtype=float), (x.shape[0],))[:, None]
    return np.any(camera.in_image(x, y, margin_px=-margin), axis=1)


def sample_sources(camera: Camera, profile: AttitudeProfile, shutter: Shutter, directions: Directions,
                   radius_px: int, substep_px: float, max_off_axis_rad: float, moving: bool) -> SourcePaths:
    """Sub-step samples of the sources whose stamps reach the image (see the module docstring).

    ``moving`` False (no rotation, no relative motion) takes one sample at the frame's mid time.
    """
    t_mid = shutter.mid_s(camera.height)
    if not moving:
        x, y = positions(camera, profile, directions, np.array([t_mid]), max_off_axis_rad)
        keep = np.flatnonzero(_near_image(camera, x, y, radius_px))
        t_lo = np.full((keep.size, 1), shutter.start_s)  # one sample covering every row's exposure
        span = shutter.exposure_s + (camera.height - 1) * shutter.line_time_s
        samples = Samples(x[keep], y[keep], t_lo, t_lo + span)
        point = (x[keep, 0], y[keep, 0])
        return SourcePaths(keep, samples, point, point, point)
    keep, rate_px_s = _candidates(camera, profile, shutter, directions, radius_px, max_off_axis_rad)
    sub = directions.take(keep)
    t_start, t_end, t_row = _exposure_windows(camera, profile, shutter, sub, radius_px, max_off_axis_rad)
    n = substeps(float(np.max(rate_px_s * (t_end - t_start), initial=0.0)), substep_px)
    t_lo, t_mids, t_hi = sub_intervals(t_start, t_end, n)
    shared = not shutter.rolling and keep.size > 0  # every source has the same sample times
    x, y = positions(camera, profile, sub, t_mids[0] if shared else t_mids, max_off_axis_rad)
    lit = _near_image(camera, x, y, radius_px)
    marks = np.stack([t_row, t_row + 0.5 * shutter.exposure_s, t_row + shutter.exposure_s], axis=1)
    ex, ey = positions(camera, profile, sub, marks[0] if shared else marks, max_off_axis_rad)
    samples = _without_gaps(Samples(x[lit], y[lit], t_lo[lit], t_hi[lit]))
    (xs, xm, xe), (ys, ym, ye) = ex[lit].T, ey[lit].T
    return SourcePaths(keep[lit], samples, (xs, ys), (xm, ym), (xe, ye))


def _without_gaps(samples: Samples) -> Samples:
    """Samples where a source is behind the camera or far outside the field (NaN) get no light:
    their interval is emptied and their position set to one of the source's valid ones."""
    bad = np.isnan(samples.x) | np.isnan(samples.y)
    if not bad.any():
        return samples
    first_good = np.argmax(~bad, axis=1)[:, None]
    x = np.where(bad, np.take_along_axis(samples.x, first_good, axis=1), samples.x)
    y = np.where(bad, np.take_along_axis(samples.y, first_good, axis=1), samples.y)
    return Samples(x, y, samples.t_lo, np.where(bad, samples.t_lo, samples.t_hi))


def _candidates(camera, profile, shutter: Shutter, directions: Directions, radius_px: int,
                max_off_axis_rad: float) -> tuple[NDArray[np.intp], NDArray[np.float64]]:
    """Sources whose coarse path passes near the image, and their mean speed (px/s)."""
    span_end = shutter.start_s + shutter.exposure_s + (camera.height - 1) * shutter.line_time_s
    coarse_t = np.linspace(shutter.start_s, span_end, COARSE_SAMPLES)
    xc, yc = positions(camera, profile, directions, coarse_t, max_off_axis_rad)
    step = np.nan_to_num(np.hypot(np.diff(xc, axis=1), np.diff(yc, axis=1)), nan=0.0)
    keep = np.flatnonzero(_near_image(camera, xc, yc, radius_px + step.max(axis=1, initial=0.0)))
    return keep, path_length_px(xc[keep], yc[keep]) / (span_end - shutter.start_s)


def _exposure_windows(camera, profile, shutter: Shutter, directions: Directions, radius_px: int,
                      max_off_axis_rad: float) -> tuple[NDArray, NDArray, NDArray]:
    """Per source: the times its light can reach a row (start, end) and its own row's start.

    Global shutter: [start, start + T] for every source. Rolling shutter: the source's row is
    found by fixed-point iteration (row time -> position at mid-exposure -> row), and the span
    covers every row its stamp touches during that exposure.
    """
    n_src = len(directions)
    start = np.full(n_src, shutter.start_s)
    if not shutter.rolling or n_src == 0:
        return start, start + shutter.exposure_s, start
    half = 0.5 * shutter.exposure_s
    t_row = np.full(n_src, shutter.mid_s(camera.height) - half)
    for _ in range(ROW_TIME_ITERATIONS):
        _, y = positions(camera, profile, directions, (t_row + half)[:, None], max_off_axis_rad)
        t_row = shutter.row_start_s(np.clip(np.nan_to_num(y[:, 0], nan=camera.cy), 0.0, camera.height - 1.0))
    ends = np.stack([t_row, t_row + shutter.exposure_s], axis=1)
    _, ys = positions(camera, profile, directions, ends, max_off_axis_rad)
    ys = np.where(np.isnan(ys), camera.cy, ys)
    lo = np.clip(ys.min(axis=1) - radius_px - 1, 0, camera.height - 1)
    hi = np.clip(ys.max(axis=1) + radius_px + 1, 0, camera.height - 1)
    return shutter.row_start_s(lo), shutter.row_start_s(hi) + shutter.exposure_s, t_row
