"""The detector's compiled loops (:mod:`._frame_kernels`, :mod:`._window_kernels`,
:mod:`._region_kernels`, :mod:`._robust_kernels`, numba),
loaded on first use.

Importing :mod:`startrack.cache` points numba's disk cache at startrack's cache folder before
numba is imported (:mod:`startrack.numba_cache`), and the folder's files are checked once per
process before the first compiled function is loaded from it. :func:`warm_up_detect` compiles
(once after an install) or loads every specialization a detection of a uint8, uint16 or float32
frame uses, so that no detection time includes it.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from types import ModuleType

import numpy as np
from numpy.typing import DTypeLike


@functools.cache
def _numba_ready() -> None:
    """Point numba's disk cache at startrack's folder and check its files (once a process)."""
    from ..numba_cache import prepare

    prepare()


@functools.cache
def kernels() -> ModuleType:
    """The module of compiled whole-frame loops, :mod:`._frame_kernels` (numba imported on
    first call)."""
    _numba_ready()
    from . import _frame_kernels as frame_kernels

    return frame_kernels


@functools.cache
def robust_kernels() -> ModuleType:
    """The module of :mod:`._robust`'s compiled loops, :mod:`._robust_kernels`."""
    _numba_ready()
    from . import _robust_kernels as module

    return module


@functools.cache
def window_kernels() -> ModuleType:
    """The module of the windowed centroider's compiled loops, :mod:`._window_kernels`."""
    _numba_ready()
    from . import _window_kernels as module

    return module


@functools.cache
def region_kernels() -> ModuleType:
    """The module of the per-region loops over pixel lists, :mod:`._region_kernels`."""
    _numba_ready()
    from . import _region_kernels as module

    return module


def warm_up_detect(dtypes: Sequence[DTypeLike] = (np.uint8, np.uint16, np.float32), channels: int = 1) -> None:
    """Run the default detector on a small frame of each of ``dtypes`` (with a star, and a NaN
    pixel in a float frame; ``channels`` 3 for a colour frame), so that the compiled loops a
    detection of such frames uses are compiled or loaded (free after the first call of a process)."""
    # the pipeline itself, with the default settings: what StarDetector().detect runs on a frame
    # this small (under max_block_px, no dark frame), without importing the facade
    from ._pipeline import detect_frame
    from ._settings import DetectionSettings

    settings = DetectionSettings()
    yy, xx = np.mgrid[0:96, 0:96]
    star = 200.0 * np.exp(-((xx - 40.3) ** 2 + (yy - 50.6) ** 2) / 4.5)
    noise = np.random.default_rng(0).normal(20.0, 2.0, (96, 96))
    frame = np.clip(noise + star, 0, 255)
    for dtype in dtypes:
        images = [frame.astype(dtype)]
        if np.issubdtype(images[0].dtype, np.floating):  # a float frame with a NaN pixel, and one without
            images.append(images[0].copy())  # (the fine pass's one compiled loop reads the latter's plane)
            images[0][3, 5] = np.nan
        for image in images:
            detect_frame(settings, np.stack([image] * channels, axis=-1) if channels > 1 else image, None)
