"""The configured star detector: every detection method selectable by name, one interface.

See the package docstring of :mod:`startrack.detect` for the pipeline and its defaults, and
``docs/detection.md`` for the methods and how close each comes to the Cramér-Rao bound.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ..results import Detections
from ._blocks import detect_in_strips
from ._compression import compression_noise_floor
from ._details import DetectionDetails
from ._pipeline import detect_frame
from ._predictive import WindowDetections, measure_windows
from ._prepare import pixel_array
from ._settings import DetectionSettings


@dataclass(frozen=True)
class StarDetector(DetectionSettings):
    """Star detector with fixed settings (validated once, when constructed).

    The settings, their defaults and their checks are those of :class:`DetectionSettings`,
    which this class extends with the detection itself (:meth:`detect`, :meth:`detect_details`,
    :meth:`measure_windows`); the pipeline's stages read only the settings. Construct it with
    keywords (``StarDetector(threshold="dynamic", centroid="mle")``) and change a copy with
    :func:`dataclasses.replace`.
    """

    def detect(self, image: NDArray) -> Detections:
        """Find and centroid the stars of ``image``.

        Parameters
        ----------
        image : array_like, shape (H, W) or (H, W, C)
            Raw counts, any integer or float dtype; NaN / inf pixels are ignored. A
            :class:`startrack.io.Image` (or an astropy HDU) is taken for its ``.data``, and a
            JPEG's for its compression too (:meth:`for_image`).

        Returns
        -------
        Detections
            Brightest (largest flux) first; empty for a blank or constant frame.

        Raises
        ------
        InvalidInputError
            Bad shape, dtype or size, no finite pixel, or a dark frame of another shape.
        """
        return self.detect_details(image).detections

    def detect_details(self, image: NDArray) -> DetectionDetails:
        """As :meth:`detect`, with the instrument magnitude, the spot shape, the PSF width and
        the threshold used (:class:`startrack.detect.DetectionDetails`)."""
        cfg, array = self.for_image(image), pixel_array(image)
        h, w = array.shape[:2] if array.ndim >= 2 else (0, 0)
        if h * w > cfg.max_block_px and array.ndim in (2, 3):
            return detect_in_strips(cfg, array)
        return detect_frame(cfg, array, cfg.dark_frame)

    def for_image(self, image: object) -> StarDetector:
        """These settings for ``image``: with the ``compression_noise`` of a
        :class:`startrack.io.Image`'s ``compression_step`` (a JPEG's,
        :func:`startrack.detect.compression_noise_floor`) when that is higher, else ``self`` (an
        array, a lossless file). :meth:`detect` applies it; use it to detect the pixels of a
        JPEG's ``.data`` as :meth:`detect` would the image."""
        floor = compression_noise_floor(float(getattr(image, "compression_step", 0.0)), self.sigma)
        return replace(self, compression_noise=floor) if floor > self.compression_noise else self

    def measure_windows(self, image: NDArray, x: ArrayLike, y: ArrayLike,
                        half_width_px: int = 6) -> WindowDetections:
        """Predictive centroiding: find and centroid stars only in square windows of
        half-width ``half_width_px`` centred on the predicted positions (x, y) (Samaan 2002;
        :mod:`._predictive`). The background of each window is its outer ring.

        Returns
        -------
        WindowDetections
            Detections (brightest first) and the index of the prediction each belongs to;
            predictions with no star in their window are absent.
        """
        x = np.atleast_1d(np.asarray(x, dtype=np.float64))
        y = np.atleast_1d(np.asarray(y, dtype=np.float64))
        if x.shape != y.shape or x.ndim != 1 or not np.all(np.isfinite(x) & np.isfinite(y)):
            raise InvalidInputError("x and y must be 1-D arrays of one length of finite "
                                    "predicted positions")
        if not (isinstance(half_width_px, int | np.integer) and half_width_px >= 2):
            raise InvalidInputError(f"half_width_px must be an integer >= 2, got {half_width_px!r}")
        if x.size == 0:
            return WindowDetections()
        return measure_windows(self, image, x, y, int(half_width_px))


def detect(image: NDArray, **settings) -> Detections:
    """Detect and centroid stars with a :class:`StarDetector` built from ``settings``.

    ``detect(image, sigma=4, centroid="mle")`` is
    ``StarDetector(sigma=4, centroid="mle").detect(image)``; see :class:`StarDetector` for the
    settings and :meth:`StarDetector.detect` for the result.
    """
    return StarDetector(**settings).detect(image)
