"""The detector's compiled loops (:mod:`.frame_kernels`, numba), loaded on first use.

Importing :mod:`startrack.cache` points numba's disk cache at startrack's cache folder before
numba is imported (:mod:`startrack.numba_cache`), and the folder's files are checked once per
process before the first compiled function is loaded from it. :func:`warm_up_detect` compiles
(once after an install) or loads every specialization a detection of a uint8, uint16 or float32
frame uses, so that no detection time includes it.
"""

from __future__ import annotations

import functools
from types import ModuleType

import numpy as np


@functools.cache
def kernels() -> ModuleType:
    """The module of compiled loops, :mod:`.frame_kernels` (numba imported on first call)."""
    from .. import cache, numba_cache  # noqa: F401 - cache configures numba's folder on import

    numba_cache.heal(numba_cache.configured_dir())
    from . import frame_kernels

    return frame_kernels


def warm_up_detect() -> None:
    """Run the default detector on small uint8, uint16 and float32 frames with a star and a NaN
    pixel, so that the compiled loops they use are compiled or loaded (free after the first
    call of a process)."""
    from .detector import StarDetector

    yy, xx = np.mgrid[0:96, 0:96]
    star = 200.0 * np.exp(-((xx - 40.3) ** 2 + (yy - 50.6) ** 2) / 4.5)
    noise = np.random.default_rng(0).normal(20.0, 2.0, (96, 96))
    frame = np.clip(noise + star, 0, 255)
    float_frame = frame.astype(np.float32)
    float_frame[3, 5] = np.nan
    for image in (frame.astype(np.uint8), frame.astype(np.uint16), float_frame):
        StarDetector().detect(image)
