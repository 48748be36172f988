"""A second, full-resolution detection pass for sharp stars, and for blends.

The default detection image (2 x 2 binning + 3 x 3 binomial, :mod:`._smooth`) is a matched
filter for stars of about 1.5 px standard deviation under white noise. Photographs break both
assumptions: their stars are often sharper (0.5-1 px on small phone and DSLR JPEGs and on the
openstartracker frames) and their noise is correlated over a few pixels (demosaicing, JPEG's
8 x 8 blocks), so averaging over a 6 x 6 px window divides the noise by much less than its
width while it spreads a sharp star's peak over it: on ``../shared/realdata``'s JPEGs the stars
astrometry.net matched but the binned image missed stand 1.5-2 times higher above their noise
at full resolution (``benchmarks/detect_realdata.py``).

This pass (run by :func:`.pipeline.with_fine_pass` on frames whose stars are sharp) works on
the full-resolution image smoothed by the 3 x 3 kernel less its mean over 7 x 7 px boxes
(:func:`local_contrast`, a difference of kernels: gradients, the edges of roofs and trees and
the low-frequency part of JPEG noise go, a sharp star stays), thresholded at ``fine_sigma``
(6.5 by default: its pixels are four times as many, and noise peaks of a correlated or skewed
noise are more frequent than a Gaussian's). Its spots then pass the detector's spot filters
and, to join the binned pass's:

* a spot that shares no pixel with any spot the binned pass found is a star it missed, kept
  when its own surroundings (the ring 4-8 px about it, :func:`ring_noise_ratio`) are quiet:
  a spot among lit leaves has other leaves there, which the tile statistics of the clutter
  filter average away; or, where they are not, when it stands 1.5 times the threshold above its
  ring's spread in the fine image (:func:`quiet_surroundings`: the raw ring of an 8-bit frame
  whose noise is half a count is coarse, its spread 1.4-1.6 times the pixel noise on open sky);
* a binned spot that holds the peaks of two or more of its spots is a blend (a close pair, a
  cluster) and is replaced by them, unless it is saturated (a clipped core has a ring of peaks
  in this image) or its wider surroundings (9-13 px) are busy (a clump of leaves);
* the spots taken are grown by two pixels (:func:`grow`) so that their fluxes are summed over
  about the binned pass's footprint.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from ._background import last_axis_quantiles, tiled_background
from ._compiled import kernels
from ._deblend import split_regions
from ._filters import peak_away_from_edge
from ._label import Regions, label_regions, regions_from_index
from ._smooth import detection_image, empty_apart, kernel_weights, smooth
from ._threshold import significance
from ._windows import extract_windows

GROW_STEPS = 2
"""Rings of pixels added around each fine-pass spot before it is measured (:func:`grow`)."""

EDGE_CORE_PX = 64
"""A spot touching the border with a larger core than this (px) is cut off (see
:func:`.filters.peak_away_from_edge`)."""

RING_PX = (4, 8)
BLEND_RING_PX = (9, 13)
MAX_BLEND_RING_NOISE = 1.2
"""A blend is split when the ring 9-13 px about it is at most this noisy: beyond the members of
a close pair or a small group the sky is open (0.7-1.1 about the stars of
``../shared/realdata``), while a cluster of lit leaves has more leaves there (1.25-1.65)."""
MAX_RING_NOISE = 1.4
"""A spot only the fine pass found is kept when its surroundings are at most this noisy
(:func:`ring_noise_ratio`); stars on the sky of ``../shared/realdata`` are at 0.4-1.2, lit leaves
at 1.3-3.6."""
BUSY_RING_SIGMA_FACTOR = 1.5
"""... or, its surroundings busier, when its peak stands this many times the pass's threshold
above the spread of its ring in the fine image itself (:func:`quiet_surroundings`): a threshold
set from the spot's own clutter."""

LOCAL_BOX_PX = 7
"""Side of the box whose mean is taken off the fine image: several times a sharp star's width,
smaller than the structures of a photograph's foreground."""


def fine_regions(data: NDArray, invalid: NDArray[np.bool_] | None, kernel: str, kernel_px: int,
                 tile_px: int, fine_sigma: float, grow_sigma: float, edge_margin_px: int,
                 deblend: bool = True, skewed: bool = False, snr: NDArray | None = None) -> Regions:
    """Spots of the full-resolution, ``kernel``-smoothed image above ``fine_sigma`` (grown to
    ``grow_sigma``), deblended, with their peaks at least ``edge_margin_px`` inside the border.

    Parameters
    ----------
    data : ndarray, shape (H, W)
        The prepared plane.
    invalid : ndarray of bool, shape (H, W), or None
    kernel, kernel_px, tile_px
        As the detector's settings.
    fine_sigma, grow_sigma : float
        Detection and growing thresholds, noise units of the fine image.
    edge_margin_px : int
        0 keeps spots at the border.
    deblend : bool
        Split regions with several separate peaks (:mod:`._deblend`).
    skewed : bool
        The frame's low side is clipped (:func:`.background.tiled_background`).
    snr : ndarray, shape (H, W), or None
        The significance image (:func:`fine_significance`) when the caller has made it.

    Returns
    -------
    Regions
        Full-resolution regions (may be empty).
    """
    if snr is None:
        snr = fine_significance(data, invalid, kernel, kernel_px, tile_px, skewed)
    if snr is None:
        return label_regions(np.zeros(data.shape, dtype=bool))
    regions = label_regions(snr > min(grow_sigma, fine_sigma))
    if len(regions) == 0:
        return regions
    regions = regions.select(regions.max(snr[regions.y, regions.x]) > fine_sigma)
    if deblend and len(regions):
        regions = split_regions(regions, snr, fine_sigma)
    if edge_margin_px and len(regions):
        values = snr[regions.y, regions.x]
        regions = regions.select(peak_away_from_edge(regions, values, snr.shape, edge_margin_px, values > fine_sigma,
                                                     EDGE_CORE_PX))
    return regions


def fine_significance(data: NDArray, invalid: NDArray[np.bool_] | None, kernel: str, kernel_px: int,
                      tile_px: int, skewed: bool = False) -> NDArray[np.float32] | None:
    """The full-resolution pass's significance image, shape (H, W): the ``kernel``-smoothed
    plane's local contrast (:func:`local_contrast`) over its tiled noise, in noise units; None
    when the image has no noise (a constant plane). Arguments as :func:`fine_regions`'s."""
    if invalid is None:
        det = smoothed_contrast(data, kernel, kernel_px)
    else:
        det = local_contrast(detection_image(data, 1, kernel, kernel_px, invalid))
    return contrast_significance(det, tile_px, skewed)


def contrast_significance(det: NDArray[np.float32], tile_px: int, skewed: bool = False) -> NDArray[np.float32] | None:
    """The local contrast ``det`` (H, W) over its tiled noise (``tile_px`` tiles), in noise units;
    None when it has no noise (:func:`fine_significance`)."""
    model = tiled_background(det, tile_px, skewed=skewed)
    if model.noise <= 0:
        return None
    # the local contrast has one level over the frame (its median, below 0 for skewed noise): the
    # tiles' level grid is replaced by that constant, and only the noise is interpolated
    tiles = model.tiles
    if tiles is not None:
        tiles = replace(tiles, level=np.full_like(tiles.level, np.float32(model.level)))
    return significance(det, replace(model, tiles=tiles, level_map=None))


def local_contrast(image: NDArray[np.float32], may_hold_nan: bool = True) -> NDArray[np.float32]:
    """``image`` less its mean over :data:`LOCAL_BOX_PX`-pixel boxes (a difference of kernels):
    what a gradient, the edge of a roof or a tree, or the low-frequency part of a JPEG's noise
    adds to the neighbourhood of a sharp star goes; NaN pixels stay NaN (the box mean is taken
    over the valid pixels). ``may_hold_nan`` False: the caller knows every pixel is finite (no
    scan for NaN)."""
    if not may_hold_nan:
        return _less_box_mean(image)
    valid = np.isfinite(image)
    if valid.all():
        return _less_box_mean(image)
    total = smooth(np.where(valid, image, 0.0).astype(np.float32), "box", LOCAL_BOX_PX)
    weight = smooth(valid.astype(np.float32), "box", LOCAL_BOX_PX)
    with np.errstate(invalid="ignore", divide="ignore"):
        return image - total / weight


COMPILED_DTYPES = (np.float32,)
"""Types :func:`smoothed_contrast` reads as they are (those :func:`.compiled.warm_up_detect`
prepares the compiled loop for); other planes are converted to float32 first (each type compiled
costs about 5 s once; an integer plane's float32 copy, about 0.3 ms on a 1 MP frame)."""


def smoothed_contrast(data: NDArray, kernel: str, kernel_px: int) -> NDArray[np.float32]:
    """``local_contrast(detection_image(data, 1, kernel, kernel_px), may_hold_nan=False)`` in one
    compiled pass (:func:`.frame_kernels.contrast`): the same float32 values, without the two
    frame-sized intermediate images (a plane of another type than :data:`COMPILED_DTYPES` is still
    copied to float32 first).

    Parameters
    ----------
    data : ndarray, shape (H, W)
        The prepared plane, any real type (NaN pixels give NaN about them, as the two steps do).
    kernel, kernel_px
        The smoothing (:func:`.smooth.kernel_weights`).

    Returns
    -------
    ndarray of float32, shape (H, W)
    """
    if data.dtype not in COMPILED_DTYPES or not data.flags.c_contiguous:
        data = np.ascontiguousarray(data, dtype=np.float32)
    inner, box = kernel_weights(kernel, kernel_px), kernel_weights("box", LOCAL_BOX_PX)
    out = empty_apart(data.shape, data)
    ring = empty_apart((2 * box.size, data.shape[1]), data, out).reshape(2, box.size, -1)
    pads = empty_apart((2, data.shape[1] + 2 * (max(inner.size, box.size) // 2)), data, out, ring)
    return kernels().contrast(data, inner, box[0], out, ring, pads[:, None, :])


def _less_box_mean(image: NDArray[np.float32]) -> NDArray[np.float32]:
    """``image - smooth(image, "box", LOCAL_BOX_PX)``, the difference written over the smoothed
    array (no second frame-sized temporary)."""
    box = smooth(image, "box", LOCAL_BOX_PX)
    return np.subtract(image, box, out=box)


def add_new_regions(base: Regions, extra: Regions, values: NDArray, unsplit: NDArray[np.bool_],
                    quiet: NDArray[np.bool_]) -> Regions:
    """``base`` combined with the fine pass's regions ``extra``.

    A region of ``extra`` that shares no pixel with ``base`` is added when ``quiet`` (shape
    (K,), see :func:`ring_noise_ratio`) allows: a star the binned pass missed. A region of
    ``base`` that holds the peaks of two or more regions of ``extra`` is replaced by them (a
    blend that only the full resolution separates: close pairs, clusters), unless ``unsplit``
    (shape (N,)) says no: deblending is off, or the region is saturated (the flat core of a
    clipped star has a ring of peaks in the fine image, not several stars). The other regions
    of ``extra`` are dropped (the same star). The regions taken from ``extra`` are grown
    (:func:`grow`). ``values`` (the frame, shape (H, W)) ranks each region's pixels to find its
    peak.
    """
    if len(base) == 0:
        return grow(extra.select(quiet), values.shape, np.ones(int(quiet.sum()), dtype=bool))
    if len(extra) == 0:
        return base
    owner = owners(base, extra.y, extra.x, values.shape[1])
    overlap = extra.max(owner)  # a base region touching it, or -1
    home = owner[extra.argmax(values[extra.y, extra.x])]
    blended = (np.bincount(home[home >= 0], minlength=len(base)) >= 2) & ~unsplit
    from_extra = ((overlap < 0) & quiet) | ((home >= 0) & blended[np.maximum(home, 0)])
    keep_base = ~blended
    if not from_extra.any():
        return base
    kept = base.select(keep_base)
    combined = _concat(kept, extra.select(from_extra))
    return grow(combined, values.shape, np.arange(len(combined)) >= len(kept))


def owners(regions: Regions, y: NDArray, x: NDArray, width: int) -> NDArray[np.int64]:
    """The region of ``regions`` (whose pixels are distinct) holding each pixel (y, x) (shape
    (M,)), -1 for a pixel of none; found among the regions' pixels (sorted by their index in a
    frame ``width`` pixels wide), not in a frame-sized map (64 MB of int64 for an 8 Mpx strip)."""
    if len(regions.y) == 0:
        return np.full(np.shape(y), -1, dtype=np.int64)
    keys = regions.y.astype(np.int64) * width + regions.x
    order = np.argsort(keys, kind="stable")
    query = np.asarray(y, dtype=np.int64) * width + x
    at = np.minimum(np.searchsorted(keys[order], query), keys.size - 1)
    return np.where(keys[order][at] == query, regions.index[order][at].astype(np.int64), -1)


def ring_noise_ratio(data: NDArray, x: NDArray, y: NDArray, pixel_noise: float,
                     radii_px: tuple[int, int] = RING_PX) -> NDArray[np.float64]:
    """Spread of the pixels ``radii_px`` (inner, outer) from each spot (half the 15.87-84.13 %
    range) over the frame's pixel noise, shape (N,): about 1 for a star on open sky, 2-4 for a
    bright spot among lit leaves or a roof's texture, where the binned pass's tile statistics
    (the clutter filter) see a tile's average and not the spot's own surroundings."""
    inner, outer = radii_px
    if len(x) == 0:
        return np.zeros(0)
    windows = extract_windows(data, np.rint(x), np.rint(y), outer)
    k = np.arange(-outer, outer + 1)
    r = np.hypot(k[None, :], k[:, None])
    ring = windows.values[:, (r >= inner) & (r <= outer)]
    lo, hi = last_axis_quantiles(ring, (0.1587, 0.8413))  # ring is a copy: sorted in place
    with np.errstate(all="ignore"):
        return 0.5 * (hi - lo) / pixel_noise


def quiet_surroundings(data: NDArray, snr: NDArray | None, regions: Regions, x: NDArray, y: NDArray,
                       pixel_noise: float, fine_sigma: float) -> NDArray[np.bool_]:
    """Which spots the fine pass alone found stand on surroundings quiet enough to keep them,
    shape (N,).

    A spot is kept when the ring 4-8 px about it in the frame is at most :data:`MAX_RING_NOISE`
    times the pixel noise (:func:`ring_noise_ratio`), or else when its peak significance (its
    largest value of ``snr``) stands :data:`BUSY_RING_SIGMA_FACTOR` times ``fine_sigma`` above
    the spread of the same ring in the fine image (taken as at least 1, the image being in noise
    units). The second test is a threshold set
    from the spot's own clutter: lit leaves and a roof's texture are busy in both images, while
    the raw ring of an 8-bit frame whose noise is half a count is busy only through rounding
    (on the openstartracker frames with the dark, open sky's raw rings spread 1.36-1.59 times
    the pixel noise in the median, its fine rings 0.86-0.87; on the JPEGs 0.71-0.91 and
    0.98-0.99).

    Parameters
    ----------
    data : ndarray, shape (H, W)
        The prepared plane.
    snr : ndarray, shape (H, W), or None
        The fine pass's significance image (:func:`fine_significance`); None: the first test only.
    regions : Regions
        The N spots' pixels.
    x, y : ndarray, shape (N,)
        Their centroids, px.
    pixel_noise : float
        The frame's pixel noise (``data`` units).
    fine_sigma : float
        The fine pass's detection threshold (noise units).
    """
    quiet = ring_noise_ratio(data, x, y, pixel_noise) <= MAX_RING_NOISE
    if snr is None or len(x) == 0:
        return quiet
    return quiet | stands_above_ring(snr, x, y, regions.max(snr[regions.y, regions.x]), fine_sigma)


def stands_above_ring(snr: NDArray, x: NDArray, y: NDArray, peak_snr: NDArray, fine_sigma: float
                      ) -> NDArray[np.bool_]:
    """Shape (N,): whether each spot's ``peak_snr`` (noise units) is at least
    :data:`BUSY_RING_SIGMA_FACTOR` times ``fine_sigma`` over the spread of the ring 4-8 px about
    its centroid ``x``, ``y`` (px) in the significance image ``snr`` (shape (H, W); the spread
    taken as at least 1); False where either is NaN. See :func:`quiet_surroundings`."""
    local = np.fmax(ring_noise_ratio(snr, x, y, 1.0), 1.0)
    with np.errstate(invalid="ignore"):
        return np.asarray(peak_snr, dtype=np.float64) / local >= BUSY_RING_SIGMA_FACTOR * fine_sigma


def square_offsets(steps: int) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Row and column offsets of the (2 steps + 1)^2 pixels about a pixel, row by row, and the
    ring (Chebyshev distance, 0 .. ``steps``) of each: three arrays of shape ((2 steps + 1)^2,)."""
    k = np.arange(-steps, steps + 1)
    dy, dx = (v.ravel() for v in np.meshgrid(k, k, indexing="ij"))
    return dy, dx, np.maximum(np.abs(dy), np.abs(dx))


def grow(regions: Regions, shape: tuple[int, int], which: NDArray[np.bool_], steps: int = GROW_STEPS) -> Regions:
    """The regions ``which`` (shape (N,)) grown by ``steps`` rings of 8-connected pixels into
    pixels of no region (a pixel two could take goes to the nearer, then the lower-numbered).

    The fine pass cuts its spots at ``grow_sigma`` of the sharper image, a smaller footprint than
    the binned pass's for a star of the same brightness; grown by two pixels, a faint star's
    summed flux is measured over about the same area whichever pass found it. Works on the
    pixel lists (the spots are small), not on the frame.
    """
    if len(regions) == 0 or steps <= 0 or not which.any():
        return regions
    h, w = shape
    dy, dx, ring = square_offsets(steps)
    grown = which[regions.index]
    stay = ~grown  # the others keep their pixels, at distance 0
    y = np.concatenate([regions.y[stay], (regions.y[grown][:, None] + dy).ravel()])
    x = np.concatenate([regions.x[stay], (regions.x[grown][:, None] + dx).ravel()])
    index = np.concatenate([regions.index[stay], np.repeat(regions.index[grown], dy.size)])
    distance = np.concatenate([np.zeros(int(stay.sum()), np.int64), np.tile(ring, int(grown.sum()))])
    ok = (y >= 0) & (y < h) & (x >= 0) & (x < w)
    key, index, distance = y[ok] * w + x[ok], index[ok].astype(np.int64), distance[ok]
    n, near = len(regions), steps + 1
    if h * w * near * n < 2**62:  # each pixel's nearest, then lowest-numbered region: one sort of one code
        code = np.sort((key * near + distance) * n + index)
        key, index = code // (near * n), code % n
    else:
        order = np.lexsort((index, distance, key))
        key, index = key[order], index[order]
    first = np.r_[True, np.diff(key) != 0]
    return regions_from_index(index[first], key[first] // w, key[first] % w, len(regions))


def touches(regions: Regions, mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Shape (N,): True for the regions with a pixel where ``mask`` (shape (H, W)) is True."""
    if len(regions) == 0:
        return np.zeros(0, dtype=bool)
    return regions.max(mask[regions.y, regions.x].astype(np.int8)) > 0


def _concat(a: Regions, b: Regions) -> Regions:
    """The regions of ``a`` followed by those of ``b``."""
    index = np.concatenate([a.index, b.index + len(a)])
    return regions_from_index(index, np.concatenate([a.y, b.y]), np.concatenate([a.x, b.x]), len(a) + len(b))
