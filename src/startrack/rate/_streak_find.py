"""Fast search for the streaks of a frame: the windows the streak fit (:mod:`._streak_fit`) works in.

The segmentation of :mod:`._streak_detect` (line filters at 12 orientations on the full image)
keeps faint streaks whole but costs about a second on a 1024 x 1024 frame. Here the frame is
summed over ``bin_px`` x ``bin_px`` blocks first (a 1024 x 1024 frame becomes 256 x 256 at 4 px),
which keeps a streak's light per block while the noise adds in quadrature, then filtered by a
compiled line filter (:func:`.streak_kernel.line_filter`: the mean over ``line_bins`` blocks
along 8 directions, a matched filter for a streak at least that long), thresholded at
``threshold_sigma`` robust sigmas of the filtered image and labelled (8-connected). Each blob
with enough signal (``min_snr``) gives a candidate: its intensity centroid, major axis and the
length ``sqrt(12 (var_along - var_across))`` of its second moments (a uniform segment of length
L has variance L^2 / 12 along), the first guess of the fit. Background and noise are the median
and the MAD of every eighth pixel in each direction (a star field's light is a small share);
where the sky slopes (:func:`._streak_sky.sloped_sky`: stray light, glow, vignetting), the blocks
are taken about its level under them (32 px tiles), and the noise is the MAD about that level.
A frame whose MAD is 0 (constant, or noise-free) has nothing to set the threshold by and gives no
candidate.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from ..errors import InvalidInputError
from ._streak_sky import sloped_sky

BIN_PX = 4
LINE_BINS = 7
ORIENTATIONS = 8
THRESHOLD_SIGMA = 4.0
MIN_SNR = 12.0
"""Smallest summed signal of a blob over its pixels' noise (blocks of the binned frame)."""
MAX_CANDIDATES = 60
ROUNDING_SIGMA = 1.0 / 12.0**0.5
"""The noise (counts) given to a frame whose robust sigma is 0 (:func:`robust_level`): the rounding
of its pixels to whole counts (a uniform error of one count has this sigma), the least noise a
digitised frame has."""
_EIGHT = np.ones((3, 3), dtype=bool)
COMPILED_DTYPES = tuple(np.dtype(t) for t in (np.uint8, np.uint16, np.uint32, np.int16, np.int32, np.float32,
                                              np.float64))
"""Pixel types the compiled block sums take as they are (native byte order); others become float64."""


@functools.cache
def kernel() -> ModuleType:
    """The compiled functions, :mod:`._streak_kernel` (numba is imported on first use, its disk
    cache pointed at startrack's folder first: :func:`startrack.numba_cache.prepare`)."""
    from ..numba_cache import prepare

    prepare()
    from . import _streak_kernel as streak_kernel

    return streak_kernel


@dataclass(frozen=True)
class StreakCandidates:
    """The streak-like blobs of a frame, brightest first (K of them).

    Attributes
    ----------
    background, noise : float
        Robust background level and per-pixel noise sigma of the frame (image units).
    labels : ndarray of int32, shape (H // bin_px, W // bin_px)
        The blobs on the binned grid (0: none); candidate k is ``label[k]``.
    bin_px : int
    label : ndarray of int32, shape (K,)
    centroid_xy : ndarray, shape (K, 2)
        Intensity centroid (x, y), full-frame pixels (our convention).
    direction : ndarray, shape (K, 2)
        Unit major axis (x, y).
    length_px, width_px : ndarray, shape (K,)
        Moment length (module docstring) and rms width across, full-frame pixels.
    extent_px : ndarray, shape (K, 2)
        First and last position of the blob along its axis from the centroid (px; its blocks'
        outer edges).
    flux, snr : ndarray, shape (K,)
        Background-subtracted sum over the blob (image units) and its signal-to-noise ratio.
    sky : ndarray, shape (K,)
        The sky level under each candidate's centroid, per pixel (image units): ``background``
        unless the sky slopes (module docstring).
    """

    background: float
    noise: float
    labels: NDArray[np.int32]
    bin_px: int
    label: NDArray[np.int32]
    centroid_xy: NDArray[np.float64]
    direction: NDArray[np.float64]
    length_px: NDArray[np.float64]
    width_px: NDArray[np.float64]
    extent_px: NDArray[np.float64]
    flux: NDArray[np.float64]
    snr: NDArray[np.float64]
    sky: NDArray[np.float64]

    def __len__(self) -> int:
        return int(self.label.shape[0])


def robust_level(image: NDArray, step: int = 8) -> tuple[float, float]:
    """Median and MAD-based sigma of every ``step``-th pixel in each direction; a sigma of 0 (a
    constant frame, or a noise-free one mostly at its background) is raised to
    :data:`ROUNDING_SIGMA`, so that fits weighted by it stay defined. NaN for non-finite pixels."""
    centre, sigma = _median_sigma(image, step)
    return centre, ROUNDING_SIGMA if sigma == 0 else sigma


def _median_sigma(image: NDArray, step: int) -> tuple[float, float]:
    """Median and MAD-based sigma (as measured, 0 included) of every ``step``-th pixel in each direction."""
    return _centre_sigma(np.asarray(image[::step, ::step], dtype=np.float64))


def _centre_sigma(sample: NDArray[np.float64]) -> tuple[float, float]:
    """Median and MAD-based sigma (0 included) of the values of ``sample``."""
    centre = float(np.median(sample))
    return centre, float(1.4826 * np.median(np.abs(sample - centre)))


def binned(image: NDArray, bin_px: int) -> NDArray[np.float64]:
    """Sums over ``bin_px`` x ``bin_px`` blocks (trailing rows and columns that do not fill a block
    are dropped), in one compiled pass over the frame (:func:`._streak_kernel.block_sums`)."""
    img = np.ascontiguousarray(image)
    if img.dtype not in COMPILED_DTYPES:  # e.g. a FITS file's big-endian integers, float16, bool
        img = img.astype(np.float64)
    out = np.empty((img.shape[0] // bin_px, img.shape[1] // bin_px))
    kernel().block_sums(img, int(bin_px), out)
    return out


def _axes(cov: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Variances along and across (K,) and the unit major axes (K, 2; x, y) of 2 x 2 covariances (K, 2, 2)."""
    var, vec = np.linalg.eigh(cov)
    return var[:, 1], var[:, 0], vec[:, :, 1]


def find_streak_candidates(image: ArrayLike, *, bin_px: int = BIN_PX, line_bins: int = LINE_BINS,
                           threshold_sigma: float = THRESHOLD_SIGMA, min_snr: float = MIN_SNR,
                           max_candidates: int = MAX_CANDIDATES) -> StreakCandidates:
    """The streak-like blobs of a frame (module docstring).

    Parameters
    ----------
    image : array_like, shape (H, W)
        The frame in counts (ADU or electrons); at least 8 ``bin_px`` blocks on each side.
    bin_px, line_bins : int
        Block size (px) and line-filter length (blocks, odd).
    threshold_sigma, min_snr : float
        Threshold of the filtered image (robust sigmas) and the least summed SNR of a blob.
    max_candidates : int
        The brightest this many blobs are kept.

    Returns
    -------
    StreakCandidates
        No candidate when the frame has no noise to set the threshold by (its robust sigma is 0:
        a constant frame, or a noise-free simulated one, most of whose pixels are its background;
        ``noise`` is then :data:`ROUNDING_SIGMA`): its streaks, if any, are not measured.

    Raises
    ------
    InvalidInputError
        The frame is not 2-D, is smaller than 8 blocks a side, or has non-finite pixels (a NaN
        background or noise); ``line_bins`` is not a positive odd number.
    """
    img, background, noise = _checked_frame(image, bin_px, line_bins)
    if noise == 0:  # a constant frame, or a noise-free one mostly at its background: no threshold to set
        empty_labels = np.zeros((img.shape[0] // bin_px, img.shape[1] // bin_px), dtype=np.int32)
        return _empty(background, ROUNDING_SIGMA, empty_labels, bin_px)
    blocks, noise, sky = _above_sky(img, bin_px, background, noise)
    filtered = np.empty_like(blocks)
    kernel().line_filter(blocks, line_bins, ORIENTATIONS, filtered)
    centre, spread = _median_sigma(filtered, 2)
    labels, count = ndimage.label(filtered > centre + threshold_sigma * spread, structure=_EIGHT)
    labels = labels.astype(np.int32)
    if count == 0:
        return _empty(background, noise, labels, bin_px)
    flat = labels.ravel()
    area = np.bincount(flat, minlength=count + 1)[1:]
    total = np.bincount(flat, weights=blocks.ravel(), minlength=count + 1)[1:]
    snr = total / (noise * bin_px * np.sqrt(np.maximum(area, 1)))
    keep = np.flatnonzero(snr >= min_snr)
    keep = keep[np.argsort(-total[keep], kind="stable")][:max_candidates]
    table, good = _candidates(blocks, labels, keep + 1, bin_px)
    if not good.any():
        return _empty(background, noise, labels, bin_px)
    index, table = keep[good], table[good]
    return StreakCandidates(background, noise, labels, bin_px, (index + 1).astype(np.int32), table[:, 0:2],
                            table[:, 2:4], table[:, 4], table[:, 5], table[:, 6:8], total[index], snr[index],
                            _sky_at(sky, table[:, 0:2], bin_px, background))


def _above_sky(img: NDArray, bin_px: int, background: float, noise: float) -> tuple[NDArray, float, NDArray | None]:
    """The frame's block sums above the sky (counts per block), the pixel noise about it, and the
    sky level per block where it slopes (None where it is flat: ``background`` and ``noise`` hold)."""
    sums = binned(img, bin_px)
    sky = sloped_sky(sums, noise * bin_px)
    if sky is None:
        return sums - background * bin_px**2, noise, None
    return sums - sky, _sky_noise(img, sky, bin_px, noise), sky


def _sky_at(sky: NDArray | None, xy: NDArray, bin_px: int, background: float) -> NDArray[np.float64]:
    """The sky level per pixel (K,) at the points ``xy`` (K, 2; px) from the per-block ``sky``, or
    ``background`` everywhere when the sky is flat (``sky`` None)."""
    if sky is None:
        return np.full(xy.shape[0], float(background))
    col = np.clip((xy[:, 0] // bin_px).astype(np.intp), 0, sky.shape[1] - 1)
    row = np.clip((xy[:, 1] // bin_px).astype(np.intp), 0, sky.shape[0] - 1)
    return sky[row, col] / bin_px**2


def _candidates(blocks: NDArray, labels: NDArray, wanted: NDArray, bin_px: int) -> tuple[NDArray, NDArray]:
    """(cx, cy, ux, uy, length, width, t_first, t_last) (K, 8) of the blobs ``wanted`` (labels,
    K) in full-frame pixels, from their blocks' moments (the blocks' positive sums as weights)
    and extent along the major axis, and which are usable (K,: some light on two blocks or more)."""
    lookup = np.full(int(labels.max()) + 1, -1, dtype=np.intp)
    lookup[wanted] = np.arange(wanted.size)
    row, col = np.nonzero(lookup[labels] >= 0)
    k = lookup[labels[row, col]]
    values = np.clip(blocks[row, col], 0.0, None)
    # block (i, j) covers pixels bin_px*i .. bin_px*i + bin_px - 1: its centre is at bin_px*i + (bin_px - 1) / 2
    fx, fy = col * bin_px + 0.5 * (bin_px - 1), row * bin_px + 0.5 * (bin_px - 1)

    def sums(weights):
        return np.bincount(k, weights=weights, minlength=wanted.size)

    total = sums(values)
    good = (total > 0) & (np.bincount(k, minlength=wanted.size) >= 2)
    safe = np.where(good, total, 1.0)
    cx, cy = sums(values * fx) / safe, sums(values * fy) / safe
    dx, dy = fx - cx[k], fy - cy[k]
    cross = sums(values * dx * dy)
    cov = np.stack([sums(values * dx * dx), cross, cross, sums(values * dy * dy)], axis=1).reshape(-1, 2, 2)
    var_along, var_across, axis = _axes(cov / safe[:, None, None])
    block_var = bin_px**2 / 12.0  # a block's own extent, in both directions
    length = np.sqrt(np.maximum(12.0 * (var_along - np.maximum(var_across, block_var)), 0.0))
    width = np.sqrt(np.maximum(var_across - block_var, 0.0))
    t = dx * axis[k, 0] + dy * axis[k, 1]
    first, last = np.full(wanted.size, np.inf), np.full(wanted.size, -np.inf)
    np.minimum.at(first, k, t)
    np.maximum.at(last, k, t)
    corner = 0.5 * bin_px * (np.abs(axis[:, 0]) + np.abs(axis[:, 1]))  # a block's half-extent along the axis
    table = np.column_stack([cx, cy, axis[:, 0], axis[:, 1], length, width, first - corner, last + corner])
    return table, good


def _sky_noise(img: NDArray, sky: NDArray, bin_px: int, fallback: float) -> float:
    """MAD-based sigma of every eighth pixel in each direction about its block's sky level
    (``sky``, per block, from :func:`._streak_sky.block_sky`): the noise without the sky's slopes;
    ``fallback`` (the frame's own) when that is 0."""
    rows, cols = np.arange(0, sky.shape[0] * bin_px, 8), np.arange(0, sky.shape[1] * bin_px, 8)
    sample = img[np.ix_(rows, cols)].astype(np.float64) - sky[np.ix_(rows // bin_px, cols // bin_px)] / bin_px**2
    sigma = _centre_sigma(sample)[1]
    return sigma if sigma > 0 else fallback


def finite_frame(image: NDArray) -> NDArray:
    """``image`` itself when every pixel is finite, else a float copy whose NaN and infinite pixels
    (a file's blank or masked pixels, a dead column) take the median of the finite ones: the streak
    search and fits have no mask, and one such pixel made their sky statistics NaN.

    Raises
    ------
    InvalidInputError
        If no pixel is finite.
    """
    finite = np.isfinite(image)
    if finite.all():
        return image
    if not finite.any():
        raise InvalidInputError("image has no finite pixel value (every pixel is NaN or infinite)")
    filled = np.array(image, dtype=np.float64 if image.dtype == np.float64 else np.float32)
    filled[~finite] = np.median(filled[finite])
    return filled


def _checked_frame(image: ArrayLike, bin_px: int, line_bins: int) -> tuple[NDArray, float, float]:
    """The frame as an array with its background and robust noise (counts), after the checks of
    :func:`find_streak_candidates` (its Raises)."""
    img = np.asarray(image)
    if img.ndim != 2 or min(img.shape) < 8 * bin_px:
        raise InvalidInputError(f"image must be a 2-D frame of at least {8 * bin_px} px a side, got {img.shape}")
    img = finite_frame(img)
    if line_bins < 1 or line_bins % 2 == 0:
        raise InvalidInputError(f"line_bins must be a positive odd number of blocks, got {line_bins}")
    background, noise = _median_sigma(img, 8)
    if not (np.isfinite(background) and np.isfinite(noise)):
        raise InvalidInputError(f"image must hold finite pixel values, got a background of {background!r} and a "
                                f"noise of {noise!r} (NaN or infinite pixels)")
    return img, background, noise


def _empty(background: float, noise: float, labels: NDArray, bin_px: int) -> StreakCandidates:
    return StreakCandidates(background, noise, labels, bin_px, np.zeros(0, dtype=np.int32), np.zeros((0, 2)),
                            np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros((0, 2)), np.zeros(0), np.zeros(0),
                            np.zeros(0))
