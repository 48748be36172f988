"""The detection image: the frame binned and smoothed, a cheap matched filter.

Thresholding single pixels at k sigma either misses faint spread-out stars (high k) or accepts
noise spikes (low k); Huffman 2006 §4.1 fights the noise spikes with 5 x 5 "at least
9 of 25 pixels above threshold" pre-filters. Averaging the image over a window about the size
of the star image does the same job better: it keeps most of a star's flux while it divides
the noise by the window's width (a box approximation of the matched filter), and a lone hot
pixel is diluted instead of detected. The mask is found on this small image; centroids are
measured on the original pixels.

The default, 2 x 2 mean binning followed by the 3 x 3 binomial kernel [1, 2, 1] / 4 (per
axis), weighs a 6 x 6 px window with a taper, close to a Gaussian of 1.5 px sd sampled every
2 px: a good match to star images of about 1-2 px sd, and 4 times fewer pixels to threshold
and label. On real JPEG photographs, whose noise is correlated over several pixels, it also
beats the wider box: averaging does not divide correlated noise by the window width.
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ._compiled import kernels


def bin_mean(image: NDArray, factor: int) -> NDArray[np.float32]:
    """Mean over ``factor`` x ``factor`` blocks, as float32 (any numeric input); trailing rows /
    columns that do not fill a block are dropped. Returns shape (H // factor, W // factor).

    One compiled pass (:func:`.frame_kernels.bin_mean`): each block's rows are summed first,
    then its columns, so the values do not depend on the frame's layout."""
    if factor == 1:
        return image.astype(np.float32, copy=False)
    if image.dtype == np.bool_:
        image = image.view(np.uint8)
    out = empty_apart((image.shape[0] // factor, image.shape[1] // factor), image)
    exact = image.dtype in (np.uint8, np.int8, np.uint16, np.int16) and factor <= 16  # sums < 2**24
    return kernels().bin_mean(image, factor, out, scratch_row(out.shape[1] * factor, image, out), exact)


SmoothingKernel = Literal["binomial", "box"]
"""The detection image's smoothing kernels (a binomial or a flat box of ``kernel_px`` pixels)."""
KERNELS: tuple[SmoothingKernel, ...] = get_args(SmoothingKernel)


def kernel_weights(kernel: str, size: int) -> NDArray[np.float32]:
    """1-D weights, summing to 1, of a ``size``-tap ``"box"`` or ``"binomial"`` kernel
    (binomial 3 = [1, 2, 1] / 4, a sampled Gaussian of sd 0.71 px; 5 = [1, 4, 6, 4, 1] / 16)."""
    if kernel == "box":
        weights = np.ones(size)
    else:
        weights = np.array([1.0])
        for _ in range(size - 1):
            weights = np.convolve(weights, [1.0, 1.0])
    return (weights / weights.sum()).astype(np.float32)


def smooth(image: NDArray[np.float32], kernel: str, size: int) -> NDArray[np.float32]:
    """Separable ``size`` x ``size`` smoothing with :func:`kernel_weights`, edges repeated;
    same shape as the input (the input itself when ``size`` is 1).

    One compiled pass per axis (:func:`.frame_kernels.smooth`), rows first, each output the
    float32 sum ``sum_k weights[k] * shifted_k`` from k = 0 (other float inputs are taken as
    float32).
    """
    if size == 1:
        return image
    image = np.asarray(image, dtype=np.float32)
    out = empty_apart(image.shape, image)
    return kernels().smooth(image, kernel_weights(kernel, size), out, scratch_row(image.shape[1], image, out))


PAGE_BYTES = 4096
"""Loads and stores whose addresses agree modulo this many bytes are taken for the same one
until the store's address is known (x86 "4K aliasing"): a loop that reads one frame row and
writes another, both at the start of a 4 KiB-strided row, waits on false dependences and runs
much slower (``benchmarks/detect_speed.py`` times the detector)."""


def _apart(n: int, dtype, arrays: tuple[NDArray, ...]) -> NDArray:
    """A new 1-D array of ``n`` values of ``dtype`` that starts at least 1 KiB (modulo 4 KiB)
    from where ``arrays`` start (rows of a stride that is a multiple of 4 KiB all start there)."""
    itemsize = np.dtype(dtype).itemsize
    buffer = np.empty(n + PAGE_BYTES // itemsize, dtype)
    base = buffer.ctypes.data
    starts = [a.ctypes.data % PAGE_BYTES for a in arrays]
    for shift in range(0, PAGE_BYTES, 256):
        here = (base + shift) % PAGE_BYTES
        if all(min((here - s) % PAGE_BYTES, (s - here) % PAGE_BYTES) >= 1024 for s in starts):
            return buffer[shift // itemsize: shift // itemsize + n]
    return buffer[:n]


def scratch_row(n: int, *arrays: NDArray) -> NDArray[np.float32]:
    """A float32 work row of ``n`` values placed apart from ``arrays`` (:func:`_apart`)."""
    return _apart(n, np.float32, arrays)


def empty_apart(shape: tuple[int, int], *arrays: NDArray) -> NDArray[np.float32]:
    """An uninitialised float32 array of ``shape`` placed apart from ``arrays`` (:func:`_apart`):
    a loop reading their rows and writing its rows does not wait on false store-to-load
    dependences."""
    return _apart(shape[0] * shape[1], np.float32, arrays).reshape(shape)


MIN_VALID_WEIGHT = 0.5
"""A detection pixel needs at least this fraction of its kernel weight on valid pixels."""


def detection_image(image: NDArray, binning: int, kernel: str, size: int,
                    invalid: NDArray[np.bool_] | None = None) -> NDArray[np.float32]:
    """Bin by ``binning``, then smooth with a ``size``-tap ``kernel``; see the module docstring.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        Any numeric dtype.
    binning : int >= 1
    kernel : {"binomial", "box"}
    size : odd int >= 1
    invalid : ndarray of bool, shape (H, W), optional
        Missing pixels. They are left out by normalised convolution (the smoothed valid
        values divided by the smoothed valid weight); detection pixels with less than
        :data:`MIN_VALID_WEIGHT` of their weight on valid pixels are NaN.

    Returns
    -------
    ndarray of float32, shape (H // binning, W // binning)
        Pixel (i, j) is centred on full-resolution pixel (j * b + (b - 1) / 2,
        i * b + (b - 1) / 2) in (x, y); values stay in the image's units (means, not sums).
    """
    if invalid is None:
        return smooth(bin_mean(image, binning), kernel, size)
    valid = ~invalid
    values = smooth(bin_mean(np.where(valid, image, 0), binning), kernel, size)
    weight = smooth(bin_mean(valid, binning), kernel, size)
    with np.errstate(invalid="ignore", divide="ignore"):
        values /= weight
    values[weight < MIN_VALID_WEIGHT] = np.nan
    return values
