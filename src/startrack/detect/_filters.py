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
  fourth power is, or a block of k = 4 to 6 whose share to the power 2^(k - 1) is
  (:func:`peak_fraction`, :func:`hot_pixels_abound`);
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

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ._compiled import region_kernels
from ._label import Regions

NEIGHBOURS_3X3 = np.stack(np.divmod(np.arange(9), 3), axis=1) - 1
"""Offsets (dy, dx) of a pixel's 3 x 3 neighbourhood, shape (9, 2)."""


def neighbourhoods_3x3(shape: tuple[int, ...], y: NDArray, x: NDArray,
                       offsets: NDArray = NEIGHBOURS_3X3) -> tuple[NDArray, NDArray]:
    """Rows and columns (K, M) of the 3 x 3 neighbourhoods of the pixels (y, x) (K,) of an image
    of ``shape`` (H, W), or of other ``offsets`` (M, 2) (dy, dx), clipped to the image (a border
    pixel repeats its edge neighbours)."""
    h, w = shape[:2]
    return np.clip(y[:, None] + offsets[:, 0], 0, h - 1), np.clip(x[:, None] + offsets[:, 1], 0, w - 1)


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


def peak_fraction(signal_image: NDArray, level: NDArray, peak_x: NDArray, peak_y: NDArray, pairs: bool = False,
                  blocks: bool = False, noise: NDArray | float = 0.0) -> NDArray[np.float64]:
    """The hot-pixel measure: the peak value over the sum of the 3 x 3 neighbourhood, both
    background-subtracted; with ``pairs``, where they are larger, the square of the two brightest
    pixels' share of that sum (two hot pixels side by side, or one diagonal from the other) and
    the fourth power of the three brightest pixels' share (three together, as a demosaiced
    colour photo turns one hot pixel into); with ``blocks`` as well, the k brightest pixels' share
    to the power 2^(k - 1) for k = 4, 5, 6 (a block: pairs or triples that touch).

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

    Blocks break that rule: a star centred near a pixel corner puts nearly all its light in the
    four pixels about it, as two touching pairs of hot pixels do. Over the same 3,000 positions,
    the measure with ``blocks`` is over 0.75 for 64 % of the stars of sd 0.35 px, 27 % at 0.4 px
    and 1.7 % at 0.45 px (four pixels alone: 42 %, 15 % and 1.7 %), and none from 0.5 px
    (largest 0.68; 0.2 at 1 px); seven pixels would refuse 6.8 % at 0.45 px. So the detector
    refuses blocks where hot pixels abound but does not count them when it decides whether they
    do (:func:`._pipeline.spot_filters`); and only where the 3 x 3 sum is bright enough for the
    measure to tell a star of sd 0.5 px from a block (:data:`BLOCK_MIN_SNR`).

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
    blocks : bool
        Take four to six as one too (implies ``pairs``), k of them where the 3 x 3 sum is at
        least ``BLOCK_MIN_SNR[k - 4]`` times ``noise``.
    noise : ndarray, shape (N,), or float
        Pixel noise at each peak, in the image's units (0: blocks judged everywhere).

    Returns
    -------
    ndarray, shape (N,)
        About 1 for an isolated hot pixel, a pair or a triple (or a block, with ``blocks``),
        0.1-0.5 for a star image of sd 0.5 px or more.
    """
    measures = peak_fractions(signal_image, level, peak_x, peak_y, noise=noise)
    return measures.block if blocks else measures.cluster if pairs else measures.single


class HotMeasures(NamedTuple):
    """The hot-pixel measures of N spots (:func:`peak_fraction`), shape (N,) each; a spot whose
    3 x 3 sum is not positive has ``single`` (negative or NaN) in all three."""

    single: NDArray[np.float64]
    """The peak's share of the 3 x 3 sum."""
    cluster: NDArray[np.float64]
    """The largest of the k brightest pixels' shares to the power 2^(k - 1), k = 1, 2, 3."""
    block: NDArray[np.float64]
    """The same for k = 1 to 6 (each k from 4 on only where the sum reaches its
    :data:`BLOCK_MIN_SNR` times the noise)."""


CLUSTER_PIXELS = 3
"""The most pixels of :attr:`HotMeasures.cluster`."""
BLOCK_PIXELS = 6
"""The most pixels of :attr:`HotMeasures.block`."""
BLOCK_MIN_SNR = (150.0, 175.0, 225.0)
"""A block of k = 4, 5, 6 pixels is judged only where its 3 x 3 sum is at least this many times
the pixel noise. A star of sd 0.5 px leaves at least 4.7, 3.5 and 2.3 % of that sum outside its
k brightest pixels (3,000 random sub-pixel positions); from these sums on, that is 3 times the
noise of the other 9 - k pixels' sum (sqrt(9 - k) times the pixel noise), and the measure tells
the two apart. Below them, a faint star's few pixels above the noise hold most of a sum whose
other pixels are noise about 0: judged everywhere, blocks of four cost 1-5 of the 30-43 stars of
each of three openstartracker frames with hot pixels at 1 %, and of four to six 2-7 more."""


def peak_fractions(signal_image: NDArray, level: NDArray | float, peak_x: NDArray, peak_y: NDArray,
                   noise: NDArray | float = 0.0) -> HotMeasures:
    """The three measures of :func:`peak_fraction` from one reading of the 3 x 3 neighbourhoods
    (arguments as there; ``level`` and ``noise`` a number or one per spot). The neighbourhoods are
    read with numpy and measured in one compiled loop (:func:`.region_kernels.hot_measures`, of
    one type whatever the image's): about 30 us for the 30 spots of a
    ``benchmarks/detect_speed.py`` frame, 75 us all in numpy; the powered shares are numpy's to
    1 ulp (``tests/detect/test_detect_region_kernels.py``)."""
    n = len(peak_x)
    out = np.empty((3, n))
    if n:
        level = _per_spot(level, n)
        ys, xs = neighbourhoods_3x3(signal_image.shape, peak_y, peak_x)
        window = signal_image[ys, xs].astype(np.float64) - level[:, None]
        peak = np.asarray(signal_image[peak_y, peak_x] - level, dtype=np.float64)
        region_kernels().hot_measures(window, peak, _per_spot(noise, n), CLUSTER_PIXELS, _BLOCK_MIN_SNR, out)
    return HotMeasures(*out)


_BLOCK_MIN_SNR = np.array(BLOCK_MIN_SNR)
"""The block limits as the compiled loop takes them, one per block size from ``CLUSTER_PIXELS + 1``
to :data:`BLOCK_PIXELS`."""


def _per_spot(values: NDArray | float, n: int) -> NDArray[np.float64]:
    """``values`` as float64 of shape (n,) (a number repeated)."""
    array = np.asarray(values, dtype=np.float64)
    return array if array.shape == (n,) else np.full(n, array)


HOT_PIXELS_ABOUND = 30
"""Fewest hot spots (single hot pixels, pairs or triples) among a frame's spots for
:func:`hot_pixels_abound` (the frames of the tests and benchmarks have 0-6; a camera with hot
pixels over 0.1 % of its pixels, hundreds)."""


def clusters_abound(hot: NDArray[np.bool_], cluster: NDArray, keep: NDArray[np.bool_],
                    max_peak_fraction: float | None) -> bool:
    """Whether hot pixels abound (:func:`hot_pixels_abound`) among N spots: the single ones
    (``hot``) and the pairs and triples (their ``cluster`` measure over ``max_peak_fraction``)
    among the spots ``keep`` (those the other filters pass, single hot pixels left out), against
    the rest of ``keep``; all shape (N,). Then the detector refuses pairs, triples and blocks."""
    clustered = keep & ~hot_pixel_ok(cluster, max_peak_fraction)
    return hot_pixels_abound(hot | clustered, keep & ~clustered)


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
