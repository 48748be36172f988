"""Streak identification and separation: threshold, label, one region of interest per streak.

Sease 2013 §3 "Streak Identification & Separation": threshold the
image, label connected components, keep a bounding box per blob as its region of interest (ROI),
and do all later work on the ROIs of the original grey image. The thesis thresholds at the
global image mean, which lets about half of a noisy background through; here the threshold is
``background + k sigma`` with a robust (median, MAD) background and noise, on an image lightly
smoothed by a Gaussian (the thesis' optional smoothing step), with a minimum area (notes'
implementation advice). ``rule="mean"`` keeps the thesis' mean threshold.

Each region also carries its intensity moments: a uniform line of length L blurred by a Gaussian
of sigma s has variances ``L^2 / 12 + s^2`` along and ``s^2`` across, so
``length_moments_px = sqrt(12 (var_along - var_across))`` measures the streak without its ends,
the reference for calibrating the endpoint detectors' bias (:func:`.endpoints.calibrate_bias`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage, signal

from ..errors import InvalidInputError, as_float_array, checked_count, checked_number
from ._segment_fit import line_kernel
from ._streak_find import finite_frame

RULES = ("robust", "mean")
MIN_SNR = 10.0
"""Smallest summed signal-to-noise of a blob. Noise alone (sky + read noise, 3-sigma threshold
on the smoothed image) makes blobs of up to ~15 px reaching 7 sigmas on a 1024^2 frame, whose
cornerness peaks would pass for a 6-px streak; real streaks and stars here have hundreds."""
LINE_ORIENTATIONS = 12
"""Orientations of the line filter (15 degrees apart: a 15-px kernel stays within a pixel of a
streak at 7.5 degrees)."""


@dataclass(frozen=True)
class StreakRegion:
    """One labelled blob and its region of interest.

    Attributes
    ----------
    rows, cols : slice
        The ROI in the full image (padded by ``margin_px``), ``image[rows, cols]``.
    area_px : int
        Pixels above the threshold.
    flux : float
        Background-subtracted sum over the blob (image units).
    centroid_xy : ndarray, shape (2,)
        Intensity centroid (x, y), our pixel convention.
    length_moments_px, width_px : float
        Length from the second moments (module docstring) and the rms width across.
    direction : ndarray, shape (2,)
        Unit vector (x, y) of the major axis.
    """

    rows: slice
    cols: slice
    area_px: int
    flux: float
    centroid_xy: NDArray[np.float64]
    length_moments_px: float
    width_px: float
    direction: NDArray[np.float64]

    @property
    def origin_xy(self) -> NDArray[np.float64]:
        """Pixel (x, y) of the ROI's first column and row."""
        return np.array([self.cols.start, self.rows.start], dtype=float)


@dataclass(frozen=True)
class StreakField:
    """The regions found in an image, with the background and noise used."""

    regions: list[StreakRegion]
    background: float
    noise: float
    labels: NDArray[np.int32]


def robust_background(image: NDArray[np.float64]) -> tuple[float, float]:
    """Median and MAD-based standard deviation of an image (star light is a small fraction)."""
    med = float(np.median(image))
    return med, float(1.4826 * np.median(np.abs(image - med)))


def _moments(weights: NDArray, ys: NDArray, xs: NDArray):
    """Centroid, eigenvalues (descending) and major axis of intensity moments."""
    total = weights.sum()
    cx, cy = (weights @ xs) / total, (weights @ ys) / total
    dx, dy = xs - cx, ys - cy
    cov = np.array([[weights @ (dx * dx), weights @ (dx * dy)], [weights @ (dx * dy), weights @ (dy * dy)]]) / total
    values, vectors = np.linalg.eigh(cov)
    return np.array([cx, cy]), values[::-1], vectors[:, 1]


def _region(image, labels, index, box, background, margin) -> StreakRegion:
    rows = slice(max(box[0].start - margin, 0), min(box[0].stop + margin, image.shape[0]))
    cols = slice(max(box[1].start - margin, 0), min(box[1].stop + margin, image.shape[1]))
    mask = ndimage.binary_dilation(labels[rows, cols] == index, iterations=2)
    ys, xs = np.nonzero(mask)
    weights = np.clip(image[rows, cols][mask] - background, 0.0, None)
    centroid, var, direction = _moments(weights, ys + rows.start, xs + cols.start)
    length = float(np.sqrt(max(12.0 * (var[0] - var[1]), 0.0)))
    area = int(np.count_nonzero(labels[rows, cols] == index))
    return StreakRegion(rows, cols, area, float(weights.sum()), centroid, length, float(np.sqrt(var[1])), direction)


MAX_SMOOTH_PX = 50.0
"""The widest smoothing and line filter of the streak search (px): their cost grows with the width."""


def _check_search(threshold_sigma, smooth_sigma_px, min_area_px, margin_px, line_filter_px, min_snr) -> None:
    """The streak search's settings in their ranges (InvalidInputError naming the first that is not)."""
    checked_number(threshold_sigma, "threshold_sigma", low=0.0, above_low=True)
    checked_number(smooth_sigma_px, "smooth_sigma_px", low=0.0, high=MAX_SMOOTH_PX)
    checked_number(line_filter_px, "line_filter_px", low=0.0, high=MAX_SMOOTH_PX)
    checked_number(min_snr, "min_snr", low=0.0)
    checked_count(min_area_px, "min_area_px", 1)
    checked_count(margin_px, "margin_px", 0)


def find_streaks(
    image: ArrayLike,
    *,
    threshold_sigma: float = 3.0,
    smooth_sigma_px: float = 1.0,
    min_area_px: int = 12,
    margin_px: int = 4,
    rule: str = "robust",
    line_filter_px: float = 0.0,
    min_snr: float = MIN_SNR,
) -> StreakField:
    """Label the streaks (or point stars) of an image and measure each one.

    Parameters
    ----------
    image : array_like, shape (H, W)
        Grey image in counts (ADU or electrons).
    threshold_sigma : float
        Threshold above the robust background, in noise sigmas (of the unsmoothed image).
    smooth_sigma_px : float
        Gaussian smoothing before thresholding (0 for none).
    min_area_px : int
        Smaller blobs are dropped (hot pixels, noise).
    margin_px : int
        Padding of each ROI around its blob.
    rule : {"robust", "mean"}
        ``"mean"`` thresholds at the image mean as Sease 2013 does.
    line_filter_px : float
        When > 0, threshold the largest response of blurred-segment filters of this length at
        :data:`LINE_ORIENTATIONS` orientations instead of the Gaussian-smoothed image
        (:func:`line_filtered`): a matched filter along the streak that keeps faint streaks
        in one piece, at ``threshold_sigma`` robust sigmas of the filtered image itself.
    min_snr : float
        Blobs whose summed signal over their pixels is below this many noise sigmas (of that
        sum) are dropped: clumps of noise that pass the per-pixel threshold (:data:`MIN_SNR`).

    Returns
    -------
    StreakField
        Regions sorted by decreasing flux.
    """
    img = as_float_array(image, "image")
    if img.ndim != 2:
        raise InvalidInputError(f"image must be a 2-D array (H, W), got shape {img.shape}")
    img = finite_frame(img)  # NaN and infinite pixels filled with the median
    _check_search(threshold_sigma, smooth_sigma_px, min_area_px, margin_px, line_filter_px, min_snr)
    if not (isinstance(rule, str) and rule in RULES):
        raise InvalidInputError(f"rule must be one of {', '.join(RULES)}, got {rule!r}")
    background, noise = robust_background(img)
    smooth = ndimage.gaussian_filter(img, smooth_sigma_px) if smooth_sigma_px > 0 else img
    level = background + threshold_sigma * noise * _smoothing_gain(smooth_sigma_px)
    if line_filter_px > 0:
        smooth = line_filtered(img - background, line_filter_px, max(smooth_sigma_px, 0.5))
        centre, spread = robust_background(smooth)
        level = centre + threshold_sigma * spread
    if rule == "mean":
        level = float(img.mean())
    labels, count = ndimage.label(smooth > level)
    index = np.arange(1, count + 1)
    area = ndimage.sum_labels(np.ones_like(img), labels, index)
    snr = ndimage.sum_labels(img - background, labels, index) / (max(noise, 1e-12) * np.sqrt(np.maximum(area, 1)))
    regions = []
    for i, box in enumerate(ndimage.find_objects(labels)):
        if box is not None and area[i] >= min_area_px and snr[i] >= min_snr:
            regions.append(_region(img, labels, i + 1, box, background, margin_px))
    regions.sort(key=lambda r: -r.flux)
    return StreakField(regions, background, noise, labels)


def median_length_px(image: ArrayLike, brightest: int = 20) -> float:
    """The median ``length_moments_px`` of the ``brightest`` spots :func:`find_streaks` labels in
    ``image`` (H, W), px: a point star's size, or a streak's length; NaN when it finds none."""
    regions = find_streaks(np.asarray(image, dtype=float)).regions[:brightest]
    return float(np.median([r.length_moments_px for r in regions])) if regions else float("nan")


def line_filtered(image: NDArray[np.float64], length_px: float, sigma_px: float = 1.0,
                  orientations: int | None = None) -> NDArray[np.float64]:
    """Largest response (H, W) of unit-sum blurred-segment kernels over orientations in [0, pi)."""
    count = orientations or LINE_ORIENTATIONS
    angles = np.arange(count) * np.pi / count
    responses = [signal.fftconvolve(image, line_kernel(length_px, a, sigma_px), mode="same") for a in angles]
    return np.max(responses, axis=0)


def _smoothing_gain(sigma_px: float) -> float:
    """Noise reduction of a Gaussian smoothing of white noise (1 for none): 1 / (2 sqrt(pi) sigma)."""
    return 1.0 if sigma_px <= 0 else min(1.0, 1.0 / (2.0 * np.sqrt(np.pi) * sigma_px))
