"""Seeded star frames with known truth for the detection benchmarks, and matching to the truth.

Frames are in electrons (gain 1): pixel-integrated Gaussian stars
(:func:`startrack.simulate.render_gaussian_psf`) on a flat background, Poisson noise on stars +
background, Gaussian read noise, rounded to integers and stored as uint16. Stars sit on a
jittered grid (no overlaps) at uniformly random sub-pixel phases.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from startrack.detect import _crb as crb
from startrack.simulate import render_gaussian_psf

BACKGROUND_E = 100.0
READ_NOISE_E = 5.0


@dataclass(frozen=True)
class Frame:
    """One simulated frame and its truth (x, y in our pixel convention, flux in electrons)."""

    image: np.ndarray
    x: np.ndarray
    y: np.ndarray
    flux: np.ndarray
    psf_sigma_px: float


def grid_positions(shape: tuple[int, int], spacing: int, rng: np.random.Generator,
                   margin: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """One star per ``spacing`` cell, at a random whole-pixel offset plus a uniform sub-pixel
    phase in [-0.5, 0.5)."""
    h, w = shape
    gy, gx = np.mgrid[margin: h - margin: spacing, margin: w - margin: spacing]
    n = gx.size
    jitter = spacing // 4
    x = gx.ravel() + rng.integers(0, jitter + 1, n) + rng.uniform(-0.5, 0.5, n)
    y = gy.ravel() + rng.integers(0, jitter + 1, n) + rng.uniform(-0.5, 0.5, n)
    return x, y


def render_frame(shape: tuple[int, int], x: np.ndarray, y: np.ndarray, flux: np.ndarray,
                 psf_sigma_px: float, rng: np.random.Generator,
                 background_e: float = BACKGROUND_E, read_noise_e: float = READ_NOISE_E) -> Frame:
    """Stars + background with Poisson and read noise, as uint16 electrons."""
    mean = render_gaussian_psf(shape, x, y, flux, psf_sigma_px) + background_e
    image = rng.poisson(mean).astype(np.float64) + rng.normal(0.0, read_noise_e, shape)
    image = np.clip(np.rint(image), 0, 65535).astype(np.uint16)
    return Frame(image, x, y, flux, psf_sigma_px)


def snr_frame(shape: tuple[int, int], snr: float, psf_sigma_px: float, rng: np.random.Generator,
              spacing: int = 48) -> Frame:
    """A frame of equal stars of integrated SNR ``snr`` (:func:`startrack.detect._crb.integrated_snr`)."""
    x, y = grid_positions(shape, spacing, rng)
    flux = np.full(x.size, float(crb.flux_for_snr(snr, psf_sigma_px, BACKGROUND_E, READ_NOISE_E)))
    return render_frame(shape, x, y, flux, psf_sigma_px, rng)


def match(x_true: np.ndarray, y_true: np.ndarray, x: np.ndarray, y: np.ndarray,
          radius_px: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Nearest detection of each true star within ``radius_px``: (index or -1, matched mask);
    each detection is used at most once (nearest pairs first)."""
    index = np.full(x_true.size, -1)
    if x.size == 0 or x_true.size == 0:
        return index, index >= 0
    d = np.hypot(x_true[:, None] - x[None], y_true[:, None] - y[None])
    pairs = np.argwhere(d < radius_px)
    used = np.zeros(x.size, dtype=bool)
    for i, j in pairs[np.argsort(d[pairs[:, 0], pairs[:, 1]])]:
        if index[i] < 0 and not used[j]:
            index[i], used[j] = j, True
    return index, index >= 0


def crb_of(frame: Frame) -> np.ndarray:
    """Cramér-Rao bound (per axis, px) of each true star, flux and background unknown."""
    return crb.crb_sigma_px(frame.flux, frame.psf_sigma_px, BACKGROUND_E, READ_NOISE_E,
                            x_phase_px=frame.x - np.rint(frame.x),
                            y_phase_px=frame.y - np.rint(frame.y))
