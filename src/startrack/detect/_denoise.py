"""Optional noise removal before detection (Fowler 2013 §II.B,
"Noise-removal techniques" 1-3).

* **Linear smoothing** -- convolution with a Gaussian low-pass kernel of ``sigma_px`` (the seed
  names a low-pass mask; the detector's own detection image is already binned and smoothed, so
  this mainly changes what the centroiders see).
* **Anisotropic diffusion** (Perona-Malik) -- ``dI/dt = div(c(|grad I|) grad I)`` with
  ``c(g) = exp(-(g / K)^2)``, an explicit 4-neighbour scheme with step 0.2 (stable below 0.25):
  smooths the flat sky while the steep flanks of stars diffuse little. ``K`` is given in units
  of the image's noise. The seed describes it and leaves it out as too complex for the benefit.
* **Signal combination (stacking)** -- the mean (or median) of several registered frames of the
  same scene: random noise falls as 1 / sqrt(K). Frames must be registered: stars drift (15
  arcsec per second of time on a fixed ground mount).
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

DenoiseMethod = Literal["none", "gaussian", "diffusion"]
"""The ``denoise`` setting of :class:`startrack.detect.StarDetector`: no noise removal, the Gaussian
low-pass filter or Perona-Malik diffusion (module docstring)."""
DENOISE_METHODS: tuple[str, ...] = get_args(DenoiseMethod)
DIFFUSION_STEP = 0.2


def gaussian_smooth(image: NDArray, sigma_px: float) -> NDArray[np.float32]:
    """Gaussian low-pass filter (edges mirrored), float32; NaN pixels are filled with the
    median first and set back to NaN after."""
    from scipy import ndimage  # here, not at import: denoising is optional (issue 20)

    data = np.asarray(image, dtype=np.float32)
    nan = np.isnan(data)
    if nan.any():
        data = np.where(nan, np.nanmedian(data), data)
    out = ndimage.gaussian_filter(data, sigma_px, mode="mirror", truncate=3.0)
    out[nan] = np.nan
    return out


def anisotropic_diffusion(image: NDArray, iterations: int, kappa: float) -> NDArray[np.float32]:
    """Perona-Malik diffusion (module docstring), ``kappa`` in the image's units; float32.

    NaN pixels do not exchange with their neighbours and stay NaN.
    """
    data = np.array(image, dtype=np.float32)
    nan = np.isnan(data)
    inv_k2 = np.float32(1.0 / kappa**2)
    for _ in range(iterations):
        padded = np.pad(data, 1, mode="edge")
        flux = np.zeros_like(data)
        for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            grad = padded[1 + dy: 1 + dy + data.shape[0], 1 + dx: 1 + dx + data.shape[1]] - data
            grad = np.nan_to_num(grad)
            flux += np.exp(-(grad * grad) * inv_k2) * grad
        data += np.float32(DIFFUSION_STEP) * flux
        data[nan] = np.nan
    return data


def stack_frames(frames, method: str = "mean") -> NDArray[np.float32]:
    """Combine K registered frames (K, H, W) into one float32 frame by ``"mean"`` or
    ``"median"`` (NaN pixels left out); the noise of the mean falls as 1 / sqrt(K)."""
    stack = np.asarray(frames)
    if stack.ndim != 3 or stack.shape[0] < 1:
        raise InvalidInputError(f"frames must be K >= 1 frames of shape (H, W), got {stack.shape}")
    if method not in ("mean", "median"):
        raise InvalidInputError(f"method must be 'mean' or 'median', got {method!r}")
    stack = stack.astype(np.float32)
    if method == "median":
        return np.nanmedian(stack, axis=0)
    return np.nanmean(stack, axis=0) if np.isnan(stack).any() else stack.mean(axis=0)
