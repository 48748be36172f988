"""8-connected clustering of candidate pixels (Huffman 2006 §4.2.1; Fowler 2013 Fig. 3.2).

A pixel joins the cluster of any of its 8 neighbours that is also above threshold; this is
``scipy.ndimage.label`` with a 3 x 3 structuring element, computed by one compiled scan
(:func:`.frame_kernels.label8`). Clusters are then held as flat pixel lists grouped cluster by
cluster (:class:`Regions`), so that every per-cluster quantity
is one vectorised reduction (``np.add.reduceat``) over only the clustered pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._compiled import kernels, region_kernels
from ._threshold import threshold_mask


@dataclass(frozen=True)
class Regions:
    """The pixels of N regions, stored region after region.

    Attributes
    ----------
    index : ndarray of int, shape (M,)
        Region (0 .. N-1) of each pixel, non-decreasing.
    y, x : ndarray of int, shape (M,)
        Row and column of each pixel.
    starts : ndarray of int, shape (N,)
        Position in the pixel arrays of each region's first pixel.
    """

    index: NDArray[np.int64]
    y: NDArray[np.int64]
    x: NDArray[np.int64]
    starts: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.starts.size)

    @property
    def counts(self) -> NDArray[np.int64]:
        """Number of pixels of each region, shape (N,)."""
        return np.diff(np.append(self.starts, self.index.size))

    def sum(self, values: NDArray) -> NDArray:
        """Sum of per-pixel ``values`` (shape (M,)) over each region, shape (N,)."""
        if len(self) == 0:
            return np.zeros(0, dtype=values.dtype)
        return np.add.reduceat(values, self.starts)

    def max(self, values: NDArray) -> NDArray:
        """Maximum of per-pixel ``values`` over each region, shape (N,)."""
        if len(self) == 0:
            return np.zeros(0, dtype=values.dtype)
        return np.maximum.reduceat(values, self.starts)

    def min(self, values: NDArray) -> NDArray:
        """Minimum of per-pixel ``values`` over each region, shape (N,)."""
        if len(self) == 0:
            return np.zeros(0, dtype=values.dtype)
        return np.minimum.reduceat(values, self.starts)

    def max_of(self, image: NDArray) -> NDArray:
        """Maximum of ``image`` (shape (H, W), the grid of the pixels) over each region, shape (N,):
        ``self.max(image[self.y, self.x])`` in one compiled loop
        (:func:`.region_kernels.image_max`)."""
        if len(self) == 0:
            return np.zeros(0, dtype=image.dtype)
        return region_kernels().image_max(self.starts, self.y, self.x, image)

    def argmax(self, values: NDArray) -> NDArray[np.int64]:
        """Position (into the pixel arrays) of each region's largest value, shape (N,): the last
        of equal largest values (of its NaN values, if it has any)."""
        if len(self) == 0:
            return np.zeros(0, dtype=np.int64)
        largest = self.max(values)[self.index]
        with np.errstate(invalid="ignore"):
            top = (values == largest) | (np.isnan(values) & np.isnan(largest))
        return np.maximum.reduceat(np.where(top, np.arange(values.size), -1), self.starts)

    def select(self, keep: NDArray[np.bool_]) -> Regions:
        """The regions where ``keep`` (shape (N,)) is True, renumbered 0 .. K-1 (``self`` when it
        keeps them all: a Regions is not changed after it is made)."""
        if keep.all():
            return self
        return Regions(*region_kernels().select_pixels(self.index, self.y, self.x, self.starts,
                                                        np.asarray(keep, dtype=np.bool_)))

    def upsample(self, factor: int) -> Regions:
        """The same regions at ``factor`` times the resolution: pixel (y, x) becomes the
        ``factor`` x ``factor`` block of full-resolution pixels it was binned from."""
        if factor == 1:
            return self
        index, y, x = region_kernels().upsample_pixels(self.index, self.y, self.x, factor)
        return Regions(index, y, x, self.starts * factor * factor)


def regions_from_index(index: NDArray, y: NDArray, x: NDArray, n: int) -> Regions:
    """Build :class:`Regions` from unsorted pixels with region numbers ``index`` in 0 .. n-1
    (every number used at least once)."""
    order = np.argsort(index, kind="stable")
    index = index[order].astype(np.int64)
    counts = np.bincount(index, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    return Regions(index, y[order].astype(np.int64), x[order].astype(np.int64), starts[:n])


def label_regions(mask: NDArray[np.bool_]) -> Regions:
    """8-connected regions of the True pixels of ``mask`` (shape (H, W)), as :class:`Regions`:
    numbered in raster order of their first pixels (``scipy.ndimage.label``'s order, with its
    3 x 3 structuring element), each region's pixels in raster order. One compiled
    union-find scan over the True pixels only (:func:`.frame_kernels.label8`)."""
    mask = np.asarray(mask, dtype=np.bool_)
    index, y, x, starts = kernels().label8(np.flatnonzero(mask), mask.shape[1])
    return Regions(index, y, x, starts)


def hysteresis_regions(snr: NDArray, detect_sigma: float, grow_sigma: float) -> Regions:
    """Regions of ``snr > grow_sigma`` that reach ``snr > detect_sigma`` somewhere.

    Detection at a high threshold with segmentation at a lower one (as in ASTROS / DIGISTAR,
    Huffman 2006 §4.2.1: seed on the bright core, grow until the neighbours fall below threshold)
    keeps more of each star's wings for the centroid without admitting more noise spikes.
    """
    regions = label_regions(threshold_mask(snr, min(grow_sigma, detect_sigma)))
    if len(regions) == 0:
        return regions
    peak = regions.max(snr[regions.y, regions.x])
    return regions.select(peak > detect_sigma)
