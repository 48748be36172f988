"""Spot filters: reject clusters that are not star images.

From Fowler 2013 §II.B ("Noise-removal techniques" 5-7) and Huffman 2006 §4.1:

* **area** -- fewer than ``min_area_px`` pixels (speckle noise) or more than ``max_area_px``
  (banding, compression blobs, the Moon, lit trees);
* **peak** -- peak pixel below ``min_peak_snr`` times the pixel noise;
* **elongation** -- principal-axis ratio above ``max_elongation`` (lines, edges, streaks of
  roofs); Fowler 2013 gives no number, we use the ratio rather than the eccentricity
  e = sqrt(1 - 1 / elongation^2);
* **flatness** -- std / peak below ``min_flatness`` (plateaus of nearly equal pixels; Fowler 2013
  finds > 0.10 for focused stars);
* **hot pixels** -- a single bright pixel: its value is more than ``max_peak_fraction`` of the
  sum of the 3 x 3 pixels around it (a focused star with a 0.5 px sigma puts under half of
  that sum in its peak; a hot pixel puts nearly all); or, where hot pixels abound, two side by
  side (or diagonal) whose share of that sum, squared, is more, or three whose share to the
  fourth power is (:func:`peak_fraction`, :func:`hot_pixels_abound`);
* **clutter** -- the background's lower-half noise there is more than ``max_clutter`` times
  that of the clean sky (lit leaves, roof texture: structure, not stars; stars do not raise
  the lower half); the clean sky is checked against a dark foreground (:func:`clutter_ok`);
* **edge** -- the cluster's core (its pixels above the detection threshold) touches the image
  border, so part of the star may be cut off and the centroid pulled inwards; the detector
  keeps a small spot whose peak is inside (:func:`peak_away_from_edge`): a star whose centre is
  two pixels inside is measured well.

Each function returns a boolean "keep" array of shape (N,); the detector ANDs them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._compiled import region_kernels
from ._label import Regions

NEIGHBOURS_3X3 = np.stack(np.divmod(np.arange(9), 3), axis=1) - 1
"""Offsets (dy, dx) of a pixel's 3 x 3 neighbourhood, shape (9, 2)."""


def neighbourhoods_3x3(shape: tuple[int, ...], y: NDArray, x: NDArray) -> tuple[NDArray, NDArray]:
    """Rows and columns (K, 9) of the 3 x 3 neighbourhoods of the pixels (y, x) (K,) of an image
    of ``shape`` (H, W), clipped to the image (a border pixel repeats its edge neighbours)."""
    h, w = shape[:2]
    return (np.clip(y[:, None] + NEIGHBOURS_3X3[:, 0], 0, h - 1),
            np.clip(x[:, None] + NEIGHBOURS_3X3[:, 1], 0, w - 1))


def area_ok(area_px: NDArray, min_area_px: int, max_area_px: int | None) -> NDArray[np.bool_]:
    """Area within [min_area_px, max_area_px] (no upper limit when None)."""
    keep = area_px >= min_area_px
    if max_area_px is not None:
        keep &= area_px <= max_area_px
    return keep


def peak_ok(peak_snr: NDArray, min_peak_snr: float) -> NDArray[np.bool_]:
    """Peak pixel at least ``min_peak_snr`` pixel-noise units above the background."""
    return peak_snr >= min_peak_snr


def elongation_ok(elongation: NDArray, max_elongation: float | None) -> NDArray[np.bool_]:
    """Principal-axis ratio at most ``max_elongation`` (no limit when None)."""
    if max_elongation is None:
        return np.ones(elongation.shape, dtype=bool)
    return elongation <= max_elongation


def flatness_ok(flatness: NDArray, min_flatness: float) -> NDArray[np.bool_]:
    """Flatness factor (std / peak) at least ``min_flatness``."""
    return flatness >= min_flatness


def peak_fraction(signal_image: NDArray, level: NDArray, peak_x: NDArray, peak_y: NDArray, pairs: bool = False
                  ) -> NDArray[np.float64]:
    """The hot-pixel measure: the peak value over the sum of the 3 x 3 neighbourhood, both
    background-subtracted; with ``pairs``, where they are larger, the square of the two brightest
    pixels' share of that sum (two hot pixels side by side, or one diagonal from the other) and
    the fourth power of the three brightest pixels' share (three together, as a demosaiced
    colour photo turns one hot pixel into).

    The square makes one limit serve both: a star centred on the border of two pixels puts in
    them the square root of what it puts in its peak pixel when centred on one (the share of its
    light in one row, squared), so a limit on the measure with ``pairs`` refuses the same
    sharpness of star wherever it falls on the pixel grid. The fourth power does the same for
    three pixels, measured: over 3,000 random sub-pixel positions of a Gaussian star, its largest
    value was 0.706 at a PSF sd of 0.35 px and 0.576 at 0.4 px, against 0.717 and 0.622 for the
    single pixel (the cube had reached 0.770 at 0.35 px). Hot pixels give about 1 either way. The
    detector applies the measure with ``pairs`` only where hot pixels abound
    (:func:`hot_pixels_abound`): undersampled stars, as in a reduced photo, fall on the border of
    two pixels as often as on one.

    Parameters
    ----------
    signal_image : ndarray, shape (H, W)
        The full-resolution image.
    level : ndarray, shape (N,)
        Background level at each peak.
    peak_x, peak_y : ndarray of int, shape (N,)
        Peak pixels. Neighbours beyond the border are replaced by the nearest pixel inside.
    pairs : bool
        Take two or three hot pixels side by side as one (above).

    Returns
    -------
    ndarray, shape (N,)
        About 1 for an isolated hot pixel, a pair or a triple, 0.1-0.5 for a star image.
    """
    single, clusters = peak_fractions(signal_image, level, peak_x, peak_y, clusters=pairs)
    return clusters if pairs else single


def peak_fractions(signal_image: NDArray, level: NDArray, peak_x: NDArray, peak_y: NDArray, clusters: bool = True
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`peak_fraction` without and with ``pairs``, from one reading of the 3 x 3
    neighbourhoods (arguments as there); with ``clusters`` False the second is the first."""
    ys, xs = neighbourhoods_3x3(signal_image.shape, peak_y, peak_x)
    window = signal_image[ys, xs].astype(np.float64) - level[:, None]
    peak = signal_image[peak_y, peak_x] - level
    # NaN (missing) neighbours count as 0; an integer frame has none (np.nansum's copy skipped)
    total = window.sum(axis=1) if signal_image.dtype.kind in "biu" else np.nansum(window, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        single = peak / total
        if not clusters or len(window) == 0:
            return single, single
        ordered = np.partition(np.nan_to_num(window, nan=-np.inf), (-3, -2), axis=1)
        second, third = np.maximum(ordered[:, -2], 0.0), np.maximum(ordered[:, -3], 0.0)
        pair, triple = (peak + second) / total, (peak + second + third) / total
        return single, np.where(total > 0, np.maximum(single, np.maximum(pair**2, triple**4)), single)


HOT_PIXELS_ABOUND = 30
"""Fewest hot spots (single hot pixels, pairs or triples) among a frame's spots for
:func:`hot_pixels_abound` (the frames of the tests and benchmarks have 0-6; a camera with hot
pixels over 0.1 % of its pixels, hundreds)."""


def hot_pixels_abound(hot: NDArray[np.bool_], passing: NDArray[np.bool_]) -> bool:
    """Whether the spots the hot-pixel tests would refuse (``hot``: single hot pixels, and
    pairs or triples of them) number at least :data:`HOT_PIXELS_ABOUND` and at least as many as
    those that pass every test (``passing``): then pairs and triples are refused too."""
    n_hot = int(np.count_nonzero(hot))
    return n_hot >= max(HOT_PIXELS_ABOUND, int(np.count_nonzero(passing)))


def hot_pixel_ok(fraction: NDArray, max_peak_fraction: float | None) -> NDArray[np.bool_]:
    """Not a single hot pixel: peak fraction of the 3 x 3 sum at most ``max_peak_fraction``
    (a non-positive sum, i.e. a fraction < 0, counts as a hot pixel)."""
    if max_peak_fraction is None:
        return np.ones(fraction.shape, dtype=bool)
    return (fraction >= 0) & (fraction <= max_peak_fraction)


QUIET_SPOTS_QUANTILE = 0.1
"""The clutter filter's new reference (:func:`clutter_ok`): this quantile of the candidate spots'
clutter ratios."""
MIN_SPOTS_TO_CHECK = 5
"""Fewest candidate spots for the clutter filter's check of its reference."""
MAX_QUIET_SPOTS = 2
"""Most candidate spots at or below ``max_clutter`` for that check to find the reference wrong."""


def clutter_ok(clutter: NDArray, max_clutter: float | None, candidates: NDArray[np.bool_] | None = None
               ) -> NDArray[np.bool_]:
    """Clutter ratio of the background (see :mod:`._background`) at most ``max_clutter`` (no
    limit when None), shape (N,).

    The ratio is relative to the quietest quarter of the frame's tiles, taken to be clean sky. A
    dark, smooth foreground (a horizon, trees in silhouette) over a quarter of the frame or more is
    quieter than the sky and holds no stars; relative to it, all of the sky looks cluttered and no
    star passes. So when at least :data:`MIN_SPOTS_TO_CHECK` ``candidates`` (the spots that pass
    the other filters) are found and at most :data:`MAX_QUIET_SPOTS` of them lie at or below
    ``max_clutter``, the ratios are taken relative to the :data:`QUIET_SPOTS_QUANTILE` of the
    candidates' (when that is above the limit): the quietest tiles that hold spots are the sky. A
    frame whose sky shows a few stars at a ratio near 1 keeps its reference, however many spots
    lit leaves or a roof add.
    """
    if max_clutter is None:
        return np.ones(clutter.shape, dtype=bool)
    quiet = clutter[candidates] if candidates is not None else clutter
    quiet = quiet[np.isfinite(quiet)]
    if quiet.size >= MIN_SPOTS_TO_CHECK and np.count_nonzero(quiet <= max_clutter) <= MAX_QUIET_SPOTS:
        reference = float(np.quantile(quiet, QUIET_SPOTS_QUANTILE))
        if reference > max_clutter:
            return clutter <= max_clutter * reference
    return clutter <= max_clutter


EDGE_PEAK_FRACTION = 0.5
"""The edge filter (:func:`peak_away_from_edge`) looks at the core pixels of at least this fraction
of a region's highest value (its half-maximum core in the significance image): those of a bright
star a few pixels inside stay off the border while its threshold core reaches it (the brightest
star of a 6 deg frame cropped 4 px below it was dropped), those of a star, a glow or a limb that
the border cuts do not."""


def away_from_edge(regions: Regions, shape: tuple[int, int], core: NDArray[np.bool_] | None = None
                   ) -> NDArray[np.bool_]:
    """True for regions whose core does not touch the border of ``shape``.

    Parameters
    ----------
    regions : Regions
        Regions on the image of shape ``shape`` (rows, columns).
    core : ndarray of bool, shape (M,), optional
        Which region pixels count (e.g. those above the detection threshold, not the wings
        grown to a lower one); all of them when None.
    """
    h, w = shape
    on_border = (regions.y == 0) | (regions.y == h - 1) | (regions.x == 0) | (regions.x == w - 1)
    if core is not None:
        on_border &= core
    return regions.max(on_border.astype(np.int8)) == 0


def peak_away_from_edge(regions: Regions, values: NDArray, shape: tuple[int, int], margin: int,
                        core: NDArray[np.bool_], max_core_px: int) -> NDArray[np.bool_]:
    """The edge filter of the detector: a region is rejected when its core's bright part (pixels of
    at least :data:`EDGE_PEAK_FRACTION` of its highest value in ``values``, shape (M,)) touches the
    border of ``shape`` and either that highest pixel lies within ``margin`` pixels of it or the
    core has more than ``max_core_px`` pixels. A star whose centre is a few pixels inside keeps
    its measurable centroid, however bright (its faint wings may be cut); a glow, a limb or a
    bright star cut by the border does not. One compiled loop (:func:`.region_kernels.edge_keep`)."""
    if len(regions) == 0:
        return np.zeros(0, dtype=bool)
    return region_kernels().edge_keep(regions.starts, regions.y, regions.x, values, np.asarray(core, dtype=np.bool_),
                                      shape[0], shape[1], margin, max_core_px, EDGE_PEAK_FRACTION)
