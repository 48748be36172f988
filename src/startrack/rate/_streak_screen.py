"""Which fitted streaks take part in the identification of a streaked frame: the typical ones
(neither two streaks fitted as one nor two guesses grown into one streak)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._streak_fit import StreakFits

TYPICAL_LENGTH = (1.25, 3.0)
TYPICAL_BLUR = 1.25


def typical(fits: StreakFits) -> NDArray[np.bool_]:
    """Clean fits (K,) whose length is at most 1.25 x the median + 3 px and whose blur at most 1.25
    x the median: a longer or wider one is usually two streaks in line, or side by side, fitted as
    one (its light centroid is then between two stars); they stay out of the identification."""
    out = np.zeros(len(fits), dtype=bool)
    if not np.any(fits.ok):
        return out
    length, blur = fits.length_px, fits.blur_px
    out = fits.ok & (length <= TYPICAL_LENGTH[0] * np.median(length[fits.ok]) + TYPICAL_LENGTH[1])
    return out & (blur <= TYPICAL_BLUR * np.median(blur[fits.ok])) & ~duplicates(fits)


DUPLICATE_PX = 3.0


def duplicates(fits: StreakFits) -> NDArray[np.bool_]:
    """Fits (K,) whose light centroid is within :data:`DUPLICATE_PX` of a brighter clean fit's:
    two first guesses (pieces of one faint streak) that grew into the same streak."""
    centroid = fits.measurements()[0][:, 4:6]
    order = np.argsort(-fits.flux, kind="stable")
    out = np.zeros(len(fits), dtype=bool)
    for rank, i in enumerate(order):
        if not fits.ok[i]:
            continue
        brighter = order[:rank]
        brighter = brighter[fits.ok[brighter] & ~out[brighter]]
        out[i] = bool(np.any(np.linalg.norm(centroid[brighter] - centroid[i], axis=1) < DUPLICATE_PX))
    return out
