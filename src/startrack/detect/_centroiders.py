"""Every centroider by name, behind one call (Fowler 2013 §II.C; Huffman 2006 §4.2.2).

=================  ===========================================================================
name               method (module)
=================  ===========================================================================
``peak``           brightest pixel (:mod:`._centroid_moments`)
``area``           unweighted mean of the spot's pixels (:mod:`._centroid_moments`)
``weighted``       Huffman 2006's weighted sum, background subtracted: the default
``weighted-raw``   the weighted sum with raw pixel values, no background subtraction
``windowed``       iteratively windowed Gaussian-weighted centroid (:mod:`._centroid_windowed`)
``mle``            maximum-likelihood pixel-integrated Gaussian fit, the PSF width fitted, or
                   known when the detector's ``psf_sigma_px`` is set (:mod:`._centroid_mle`)
=================  ===========================================================================

Region methods use the spot's pixels; window methods a square window about the weighted sum,
of half-width ``window_half_px`` or, by default, ``ceil(3 s) + 1`` px for a PSF width ``s``
(given, or estimated from the brighter half of the spots' second moments).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ._centroid import SpotMeasurements
from ._centroid_mle import mle_centroid
from ._centroid_moments import area_centroid, peak_centroid, weighted_centroid, weighted_raw_centroid
from ._centroid_windowed import windowed_centroid
from ._label import Regions
from ._windows import Centroids, extract_windows, fast_median

CentroidMethod = Literal["peak", "area", "weighted", "weighted-raw", "windowed", "mle"]
"""The centroiders by name (module docstring)."""

CENTROIDERS: tuple[str, ...] = get_args(CentroidMethod)
WINDOW_METHODS = ("windowed", "mle")
MIN_PSF_SIGMA_PX, MAX_HALF_PX = 0.5, 16
MIN_PSF_SPOTS = 3
"""Fewest unsaturated spots to estimate the PSF width from them alone."""
SIZE_TO_SIGMA = 1.1
"""A thresholded spot's RMS radius underestimates the PSF width (its wings are cut): about 10 %
at the default thresholds."""


@dataclass(frozen=True)
class CentroidInputs:
    """What the centroiders need about N spots found in an image.

    Attributes
    ----------
    data : ndarray, shape (H, W)
        The image (any dtype; NaN pixels in float images are missing).
    invalid : ndarray of bool, shape (H, W), or None
    regions : Regions
        The spots' pixels.
    spots : SpotMeasurements
        Their weighted-sum measurements.
    raw : ndarray, shape (M,)
        Raw value of every region pixel (NaN where missing).
    level, noise : ndarray, shape (N,)
        Background level and pixel noise at each spot.
    saturated : ndarray of bool, shape (N,), or None
        Spots clipped at the frame's largest value (:func:`.point_source.saturated_spots`): left
        out of the PSF width's estimate (:func:`estimate_psf_sigma`) and centroided in windows of
        their own median size (:func:`clipped_width`); their point-source quality counts the
        fill of their core instead of its size (:mod:`._point_source`).
    extended : ndarray of bool, shape (N,), or None
        Spots that are not point sources (:mod:`._point_source`: lit cloud, glow, a nebula's
        knot): left out of the PSF width's estimate too.
    """

    data: NDArray
    invalid: NDArray[np.bool_] | None
    regions: Regions
    spots: SpotMeasurements
    raw: NDArray[np.float64]
    level: NDArray[np.float64]
    noise: NDArray[np.float64]
    saturated: NDArray[np.bool_] | None = None
    extended: NDArray[np.bool_] | None = None


def estimate_psf_sigma(spots: SpotMeasurements, saturated: NDArray[np.bool_] | None = None,
                       extended: NDArray[np.bool_] | None = None) -> float:
    """PSF standard deviation from the brighter half of the spots' RMS radii, px; the
    ``saturated`` and ``extended`` spots (shape (N,) each) left out when at least
    :data:`MIN_PSF_SPOTS` others remain: a clipped core is wider than the PSF, and the pieces of a
    saturated overlay (a timestamp, a watermark) or of the Moon's limb, brighter than the stars,
    would set the width (6-8 px against 1.2 px on the openstartracker frames with a watermark), as
    would lit clouds brighter than the stars."""
    if len(spots.x) == 0:
        return 1.0
    keep = np.ones(len(spots.x), dtype=bool)
    for left_out in (saturated, extended):
        if left_out is not None and np.count_nonzero(keep & ~left_out) >= MIN_PSF_SPOTS:
            keep &= ~left_out
    flux, size = (spots.flux, spots.size_px) if keep.all() else (spots.flux[keep], spots.size_px[keep])
    # np.median's values, from one partition where there is no NaN (fast_median)
    bright = size[flux >= (np.median(flux) if np.isnan(flux).any() else fast_median(flux))]
    bright = bright[np.isfinite(bright)]
    value = SIZE_TO_SIGMA * float(fast_median(bright)) if bright.size else 1.0
    return max(MIN_PSF_SIGMA_PX, value)


def clipped_width(spots: SpotMeasurements, saturated: NDArray[np.bool_], sigma: float) -> float:
    """The Gaussian window width for the ``saturated`` spots (shape (N,)), px: the width of their
    median size when that is wider than the PSF's ``sigma`` (a clipped core is wider than the PSF,
    and a window as wide centres it, as the width estimated from all spots did), else ``sigma``."""
    sizes = spots.size_px[saturated]
    sizes = sizes[np.isfinite(sizes)]
    return max(sigma, SIZE_TO_SIGMA * float(np.median(sizes))) if sizes.size else sigma


def _with_clipped_windows(first: Centroids, inputs: CentroidInputs, start_x: NDArray, start_y: NDArray,
                          sigma: float, half: int | None, gain_e_per_adu: float | None) -> Centroids:
    """``first`` with the saturated spots centroided again in windows of :func:`clipped_width`."""
    saturated = inputs.saturated
    if saturated is None or not saturated.any():
        return first
    width = clipped_width(inputs.spots, saturated, sigma)
    if width <= sigma:
        return first
    index = np.flatnonzero(saturated)
    windows = extract_windows(inputs.data, np.rint(start_x[index]), np.rint(start_y[index]),
                              window_half_px(width, half), inputs.invalid)
    part = windowed_centroid(windows, inputs.level[index], inputs.noise[index], start_x[index], start_y[index],
                             width, gain_e_per_adu=gain_e_per_adu)
    return first.with_rows(index, part)


def window_half_px(psf_sigma_px: float, half: int | None = None) -> int:
    """Half-width of the windows of the window methods: ``half`` or ceil(3 s) + 1."""
    if half is not None:
        return int(half)
    return int(min(MAX_HALF_PX, math.ceil(3.0 * psf_sigma_px) + 1))


def run_centroider(name: str, inputs: CentroidInputs, *, psf_sigma_px: float | None = None,
                   half: int | None = None, gain_e_per_adu: float | None = None) -> Centroids:
    """Centroid N spots with the named method (see the module table).

    Parameters
    ----------
    name : str
        One of :data:`CENTROIDERS`.
    inputs : CentroidInputs
    psf_sigma_px : float, optional
        Known PSF width (window width of ``windowed``; fixed width of ``mle``); estimated from
        the spots when None (and fitted by ``mle``).
    half : int, optional
        Window half-width of the window methods.
    gain_e_per_adu : float, optional
        Electrons per image unit (shot-noise weights of ``mle`` and ``windowed``).

    Returns
    -------
    Centroids
    """
    spots = inputs.spots
    if name == "peak":
        return peak_centroid(spots)
    if name == "area":
        return area_centroid(inputs.regions, spots, inputs.noise)
    if name == "weighted":
        return weighted_centroid(spots, inputs.noise)
    if name == "weighted-raw":
        return weighted_raw_centroid(inputs.regions, inputs.raw, inputs.noise)
    sigma = float(psf_sigma_px) if psf_sigma_px is not None else \
        estimate_psf_sigma(spots, inputs.saturated, inputs.extended)
    start_x = np.where(np.isfinite(spots.x), spots.x, spots.peak_x)
    start_y = np.where(np.isfinite(spots.y), spots.y, spots.peak_y)
    windows = extract_windows(inputs.data, np.rint(start_x), np.rint(start_y),
                              window_half_px(sigma, half), inputs.invalid)
    first = windowed_centroid(windows, inputs.level, inputs.noise, start_x, start_y, sigma,
                              gain_e_per_adu=gain_e_per_adu)
    if psf_sigma_px is None:
        first = _with_clipped_windows(first, inputs, start_x, start_y, sigma, half, gain_e_per_adu)
    if name == "windowed":
        return first
    fallback = first.where(first.ok, weighted_centroid(spots, inputs.noise))
    return mle_centroid(windows, inputs.level, inputs.noise, fallback.x, fallback.y,
                        spots.flux, sigma, fit_sigma=psf_sigma_px is None,
                        gain_e_per_adu=gain_e_per_adu)
