"""The compiled quantization step and clipped level and noise (:mod:`startrack.detect._robust_kernels`)
against the numpy computations they replace."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect import _robust as robust


def _numpy_step(values):
    if values.size < 2 or not np.array_equal(values, np.round(values)):
        return 0.0
    lo, hi = float(values.min()), float(values.max())
    if hi - lo > robust.MAX_QUANTIZED_RANGE:
        return 1.0
    present = np.flatnonzero(np.bincount((values - lo).astype(np.int64)))
    if present.size < 2:
        return 1.0
    return float(max(1, np.gcd.reduce(np.diff(present))))


def _numpy_clipped(values, step, upper_half):
    values = values.ravel()
    level, noise = 0.0, 0.0
    for _ in range(robust.CLIP_ITERATIONS):
        q_lo, level, q_hi = robust.quantiles(values, np.array([robust.GAUSS_LO, 0.5, robust.GAUSS_HI]), step)
        noise = (q_hi - level) if upper_half else 0.5 * (q_hi - q_lo)
        noise = np.sqrt(max(noise**2 - step**2 / 12.0, 0.0))
        if noise <= 0:
            break
        kept = values[np.abs(values - level) <= robust.CLIP_SIGMA * noise]
        if kept.size == values.size or kept.size < 3:
            break
        values = kept
    return float(level), float(max(noise, 0.0))


def _samples():
    """Quantized samples: sky noise of 0.3-40 DN with stars and hot pixels, on steps 1, 4 and
    16, offset or not, one value, two values, a wide span; and samples off any grid."""
    rng = np.random.default_rng(11)
    out = []
    for sigma in (0.3, 1.0, 3.0, 40.0):
        for q in (1, 4, 16):
            v = q * np.round(rng.normal(100.0, sigma, 3000) / q)
            v[rng.integers(0, v.size, 30)] = q * rng.integers(50, 4000, 30)
            out += [v, v - q * 7.0]
    out += [np.full(10, 5.0), np.array([3.0, 3.0, 7.0]), np.array([0.0, 3e6]), rng.normal(0, 1, 100),
            np.array([1.0, 2.5]), np.round(rng.normal(0, 5, 1000)).astype(np.float32)]
    return out


@pytest.mark.parametrize("index", range(len(_samples())))
def test_compiled_step_and_statistics_are_numpys(index):
    values = _samples()[index]
    step = robust.quantization_step(values)
    assert step == _numpy_step(values)
    for upper_half in (False, True):
        assert robust.clipped_level_noise(values, step, upper_half) == _numpy_clipped(values, step, upper_half)


@pytest.mark.parametrize("step", [1.0, 0.5, 3.0])
def test_values_off_the_callers_grid_are_clipped_as_numpy_does(step):
    values = np.random.default_rng(12).normal(10.0, 3.0, 500)  # binned by rounding, not on the grid
    values[:5] = 80.0
    for upper_half in (False, True):
        assert robust.clipped_level_noise(values, step, upper_half) == _numpy_clipped(values, step, upper_half)


def test_grid_steps_found():
    assert robust.quantization_step(np.array([4.0, 12.0, 20.0, 8.0])) == 4.0
    assert robust.quantization_step(np.array([4.0, 4.5])) == 0.0
    assert robust.quantization_step(np.array([4.0, np.nan])) == 0.0
