"""Huffman 2006's statistical pre-filters and proximity filter (§4.1, §4.2.2).

At a low threshold (1-3 sigma on single pixels) pure noise puts many pixels above it; a star's
pixels come in dense clumps. The pre-filter keeps a candidate pixel only when at least ``count``
of the 25 pixels of a 5 x 5 window are above the threshold too. The seed states it twice:

* **per candidate** (``starCentroid2``, "window" form): the window centred on each candidate
  pixel; its cost grows with the number of candidates, so it is fast at high k, slow at low k;
* **grid of tiles** (``starCentroid3``, "grid" form): the image cut into fixed 5 x 5 tiles, a
  tile's candidates kept when the tile holds ``count`` or more; its cost is about constant in k.

The seed's count is "at least 9 of 25" in §4.1 and "more than half" (13) in §4.2.2 (errata item
3); :data:`DEFAULT_COUNT` is 9, with the proximity filter behind it as in §4.1.

**Proximity filter** (§4.1, "removes proposed stars whose above-threshold pixels are not closely
packed"; the seed gives no rule): a cluster's *packing* is its pixel count over the area of the
filled ellipse with the same second moments, ``n / (4 pi sqrt(det C))`` (C the unweighted
covariance of its pixel centres plus 1/12 px^2 per axis). A filled disc or ellipse of any
orientation has about 1; a straggly chain of noise pixels much less.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._label import Regions

WINDOW = 5
DEFAULT_COUNT = 9
PREFILTER_FORMS = ("window", "grid")


def prefilter_window(mask: NDArray[np.bool_], count: int = DEFAULT_COUNT) -> NDArray[np.bool_]:
    """Per-candidate 5 x 5 pre-filter: True where ``mask`` is True and at least ``count`` of the
    25 pixels of the window centred there are True (pixels beyond the border count as False).
    Only the candidate pixels are visited."""
    h, w = mask.shape
    ys, xs = np.nonzero(mask)
    out = np.zeros_like(mask)
    if ys.size == 0:
        return out
    half = WINDOW // 2
    padded = np.pad(mask, half)
    total = np.zeros(ys.size, dtype=np.int32)
    for dy in range(WINDOW):
        for dx in range(WINDOW):
            total += padded[ys + dy, xs + dx]
    keep = total >= count
    out[ys[keep], xs[keep]] = True
    return out


def prefilter_grid(mask: NDArray[np.bool_], count: int = DEFAULT_COUNT) -> NDArray[np.bool_]:
    """Grid-of-tiles pre-filter: the True pixels of the 5 x 5 tiles (a fixed grid from the top
    left; partial tiles at the right and bottom edges are tiles too) that hold at least
    ``count`` True pixels."""
    h, w = mask.shape
    th, tw = -(-h // WINDOW), -(-w // WINDOW)
    padded = np.zeros((th * WINDOW, tw * WINDOW), dtype=bool)
    padded[:h, :w] = mask
    counts = padded.reshape(th, WINDOW, tw, WINDOW).sum(axis=(1, 3))
    keep_tile = np.repeat(np.repeat(counts >= count, WINDOW, axis=0), WINDOW, axis=1)
    return mask & keep_tile[:h, :w]


def prefilter(mask: NDArray[np.bool_], form: str, count: int = DEFAULT_COUNT) -> NDArray[np.bool_]:
    """The named pre-filter form, ``"window"`` or ``"grid"``."""
    return prefilter_window(mask, count) if form == "window" else prefilter_grid(mask, count)


def packing(regions: Regions) -> NDArray[np.float64]:
    """Pixel count over the area of the same-moment filled ellipse (module docstring), (N,)."""
    x, y = regions.x.astype(np.float64), regions.y.astype(np.float64)
    n = regions.counts
    mx, my = regions.sum(x) / n, regions.sum(y) / n
    dx, dy = x - mx[regions.index], y - my[regions.index]
    cxx = regions.sum(dx * dx) / n + 1.0 / 12.0
    cyy = regions.sum(dy * dy) / n + 1.0 / 12.0
    cxy = regions.sum(dx * dy) / n
    det = np.maximum(cxx * cyy - cxy * cxy, 1e-12)
    return n / (4.0 * np.pi * np.sqrt(det))
