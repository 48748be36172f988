"""The noise floor of a JPEG: its blocks' quantization makes star-sized blobs out of sky noise.

JPEG codes each 8 x 8 block by its orthonormal discrete cosine transform, every coefficient
rounded to a multiple of its step in the quantization table (ITU-T T.81, Annex A.3). On a dark,
noisy sky most coefficients round to zero: the file's sky is smoother than the sensor's (at
quality 50 the measured noise of the openstartracker frames of ``../shared/realdata`` falls to
three fifths of the lossless file's), while the noise that does round up to one step of a low
frequency becomes a smooth pattern over the whole block, the size of a star. Measured against the smoothed
noise, hundreds of those pass the threshold, and in blocks flattened to their mean the clutter
filter's clean sky is quieter than any sky with content.

The floor keeps the smallest such pattern under the threshold. With the block's basis functions
``C(u) C(v) / 4 cos((2x + 1) u pi / 16) cos((2y + 1) v pi / 16)`` (``C(0) = 1 / sqrt(2)``, else 1),
one step ``Q`` of the (0, 1) or (1, 0) coefficient peaks at the block's edge at
``Q cos(pi / 16) / (4 sqrt(2))``, and the two together (a noise excursion rounds both) at the
block's corner at twice that. The detection image (2 x 2 mean, then the 3 x 3 binomial kernel)
keeps :data:`KEPT_BY_DETECTION_IMAGE` of that peak when the next block holds its mirror image,
the largest it can keep; :data:`ARTEFACT_PER_STEP` ``Q`` is the peak that is left, and the floor
is that over the detection threshold ``sigma``: 0.055 Q at the default 5 sigma. The clutter
filter's clean sky (:func:`.background.with_clutter_floor`) is held to the same floor always.

The noise floor is a trade: where the compression has left no noise to round up (8-bit frames
with 1 grey level of sky noise at quality 50-60), there are no such patterns, and the floor only
takes faint stars. So it applies when the unfloored threshold finds more than
:data:`CROWDED_SPOTS` spots (:func:`crowded`): 14-22 on those frames, 330-2050 on simulated
frames whose noise was rounded into patterns. For R + G + B the step is three times the
luminance's (:attr:`startrack.io.Image.compression_step`); the chroma planes' own steps, coarser
and on a subsampled grid, are not counted. ``benchmarks/jpeg_quality.py`` measures what the floor
does to photos and star-camera frames saved at JPEG qualities 40-95.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ._label import label_regions

CROWDED_SPOTS = 100
"""More spots than this above the unfloored threshold call for a JPEG's noise floor."""

_HALF_BLOCK = [math.cos((2 * x + 1) * math.pi / 16) for x in range(4)]
"""The (0, 1) basis function across the first half of a block, from its edge, per unit amplitude."""
KEPT_BY_DETECTION_IMAGE = (0.75 * (_HALF_BLOCK[0] + _HALF_BLOCK[1]) / 2
                           + 0.25 * (_HALF_BLOCK[2] + _HALF_BLOCK[3]) / 2) / _HALF_BLOCK[0]
"""The share of the pattern's peak at the block's edge that the detection image keeps: the 2 x 2
means at the edge and next to it weighted 1/4 + 1/2 and 1/4 by the binomial kernel, the block
across the edge mirroring them (0.789)."""
ARTEFACT_PER_STEP = KEPT_BY_DETECTION_IMAGE * 2 * _HALF_BLOCK[0] / (4 * math.sqrt(2))
"""Peak in the detection image of one quantization step in each of a block's two lowest
frequencies, per unit step (0.274)."""


def compression_noise_floor(step: float, sigma: float) -> float:
    """The least noise (image units) at which one quantization step of a JPEG's lowest
    frequencies stays below a threshold of ``sigma`` times the noise (module docstring).

    Parameters
    ----------
    step : float
        :attr:`startrack.io.Image.compression_step`: the JPEG's quantization step at its lowest
        frequencies, image units (0 for a lossless image).
    sigma : float
        The detection threshold, noise units.

    Returns
    -------
    float
        ``ARTEFACT_PER_STEP * step / sigma``; 0 for a lossless image.
    """
    return ARTEFACT_PER_STEP * step / sigma if step > 0 else 0.0


def crowded(snr: NDArray[np.float32], sigma: float) -> bool:
    """Whether more than :data:`CROWDED_SPOTS` 8-connected spots of the detection image's
    significance ``snr`` (shape (h, w), noise units) pass ``sigma``."""
    return len(label_regions(snr > sigma)) > CROWDED_SPOTS
