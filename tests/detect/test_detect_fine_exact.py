"""The fine pass's compiled local contrast (:func:`smoothed_contrast`, one pass for the smoothing,
the 7 x 7 box mean and their difference) and its one-sort :func:`grow` give the numbers of the
expressions they replaced, bit for bit (kept here as the reference): every frame type, NaN and
infinite pixels, frames narrower or lower than the kernels."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect._compiled import kernels, warm_up_detect
from startrack.detect._fine_pass import (
    COMPILED_DTYPES,
    LOCAL_BOX_PX,
    contrast_significance,
    fine_significance,
    grow,
    local_contrast,
    smoothed_contrast,
    square_offsets,
)
from startrack.detect._label import Regions, label_regions, regions_from_index
from startrack.detect._smooth import detection_image, smooth

SHAPES = [(37, 53), (1, 200), (200, 1), (2, 2), (3, 9), (7, 7), (64, 96)]
KERNELS = [("binomial", 3), ("binomial", 1), ("binomial", 5), ("box", 3), ("box", 5)]


def _frames(shape: tuple[int, int], seed: int = 0, inf: bool = True) -> dict[str, np.ndarray]:
    """A star on Poisson sky as each plane type the detector works on (and a few it converts); NaN
    pixels (and with ``inf`` an infinite one) in the float32 plane "nan"."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0: shape[0], 0: shape[1]]
    sky = rng.poisson(100, shape) + 500 * np.exp(-((xx - shape[1] / 2.3) ** 2 + (yy - shape[0] / 1.7) ** 2) / 1.5)
    with_nan = (sky + rng.normal(0, 1, shape)).astype(np.float32)
    with_nan.flat[rng.choice(with_nan.size, max(1, with_nan.size // 40), replace=False)] = np.nan
    if inf:
        with_nan.flat[0] = np.inf
    return {"uint8": np.clip(sky / 3, 0, 255).astype(np.uint8), "uint16": sky.astype(np.uint16),
            "float32": (sky + rng.normal(0, 1, shape)).astype(np.float32), "nan": with_nan,
            "int32": sky.astype(np.int32), "float64": sky * 1.37, "fortran": np.asfortranarray(sky.astype(np.uint16)),
            "view": np.pad(sky.astype(np.uint16), ((0, 0), (3, 0)))[:, 3:]}


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal float32 arrays, NaN payloads and signed zeros included."""
    return a.dtype == b.dtype == np.float32 and a.shape == b.shape and np.array_equal(a.view(np.uint32),
                                                                                        b.view(np.uint32))


def _reference_contrast(data: np.ndarray, kernel: str, kernel_px: int) -> np.ndarray:
    """The two smoothings and the difference, as numpy expressions of :func:`smooth`."""
    smoothed = smooth(data.astype(np.float32), kernel, kernel_px)
    with np.errstate(invalid="ignore"):  # inf - inf
        return smoothed - smooth(smoothed, "box", LOCAL_BOX_PX)


def _reference_significance(data: np.ndarray, invalid: np.ndarray | None, kernel: str, kernel_px: int,
                            tile_px: int, skewed: bool) -> np.ndarray | None:
    """:func:`fine_significance` as it was written before the compiled local contrast."""
    with np.errstate(invalid="ignore"):  # inf - inf of a plane with NaN and inf given as valid
        det = local_contrast(detection_image(data, 1, kernel, kernel_px, invalid), may_hold_nan=invalid is not None)
    return contrast_significance(det, tile_px, skewed)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kernel,kernel_px", KERNELS)
def test_smoothed_contrast_is_the_two_smoothings_bit_for_bit(shape: tuple[int, int], kernel: str,
                                                             kernel_px: int) -> None:
    for name, data in _frames(shape).items():
        new = smoothed_contrast(data, kernel, kernel_px)
        assert _same_bits(new, _reference_contrast(data, kernel, kernel_px)), name
        with np.errstate(invalid="ignore"):
            old = local_contrast(detection_image(data, 1, kernel, kernel_px), may_hold_nan=False)
        assert _same_bits(new, old), name


def test_smoothed_contrast_of_a_megapixel_frame() -> None:
    data = np.random.default_rng(4).poisson(300, (1024, 1024)).astype(np.uint16)
    assert _same_bits(smoothed_contrast(data, "binomial", 3), _reference_contrast(data, "binomial", 3))


@pytest.mark.parametrize("shape", [(37, 53), (1, 200), (64, 96), (130, 70)])
@pytest.mark.parametrize("skewed", [False, True])
def test_fine_significance_is_unchanged(shape: tuple[int, int], skewed: bool) -> None:
    tile = 32 if min(shape) >= 64 else 4
    for name, data in _frames(shape, seed=1, inf=False).items():
        for invalid in (None, np.isnan(data)) if name == "nan" else (None,):
            new = fine_significance(data, invalid, "binomial", 3, tile, skewed)
            old = _reference_significance(data, invalid, "binomial", 3, tile, skewed)
            assert (new is None) == (old is None), name
            assert new is None or old is None or _same_bits(new, old), name


@pytest.mark.parametrize("value", [0, 7, 1000])
def test_a_constant_plane_is_unchanged(value: int) -> None:
    for data in (np.full((40, 40), value, np.uint16), np.full((40, 40), value, np.float32)):
        new, old = (f(data, None, "binomial", 3, 8, False) for f in (fine_significance, _reference_significance))
        assert (new is None) == (old is None)
        assert new is None or old is None or _same_bits(new, old)


def test_warm_up_prepares_the_contrast_loop_for_every_plane_type() -> None:
    """Every plane type is read as one of COMPILED_DTYPES, which the warm-up compiles: a detection
    compiles nothing more (each type compiled costs about 5 s)."""
    warm_up_detect()
    compiled = {str(signature[0].dtype) for signature in kernels().contrast.signatures}
    assert {np.dtype(t).name for t in COMPILED_DTYPES} <= compiled
    before = len(kernels().contrast.signatures)
    for dtype in (np.uint8, np.uint16, np.int32, np.float32, np.float64):
        smoothed_contrast(np.ones((20, 30), dtype), "binomial", 3)
        smoothed_contrast(np.asfortranarray(np.ones((20, 30), dtype)), "binomial", 3)
    assert len(kernels().contrast.signatures) == before


def _lexsort_grow(regions: Regions, shape: tuple[int, int], which: np.ndarray, steps: int) -> Regions:
    """:func:`grow` as it was: every pixel's every offset, sorted by (pixel, distance, region)."""
    if len(regions) == 0 or steps <= 0 or not which.any():
        return regions
    h, w = shape
    dy, dx, ring = square_offsets(steps)
    offsets = np.where(which[regions.index][:, None], 1, ring[None, :] == 0)
    y, x = (regions.y[:, None] + dy).ravel(), (regions.x[:, None] + dx).ravel()
    index, distance = np.repeat(regions.index, dy.size), np.tile(ring, regions.y.size)
    ok = offsets.ravel().astype(bool) & (y >= 0) & (y < h) & (x >= 0) & (x < w)
    key, index, distance = y[ok] * w + x[ok], index[ok], distance[ok]
    order = np.lexsort((index, distance, key))
    key, index = key[order], index[order]
    first = np.r_[True, np.diff(key) != 0]
    return regions_from_index(index[first], key[first] // w, key[first] % w, len(regions))


@pytest.mark.parametrize("seed", range(6))
def test_grow_is_the_lexsort_of_every_offset(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(1, 50, 2))
        regions = label_regions(rng.random((h, w)) < rng.uniform(0.02, 0.5))
        if len(regions) == 0:
            continue
        if seed % 2:  # overlapping regions: the pixels of a second labelling appended
            regions = regions_from_index(np.concatenate([regions.index, regions.index[::-1]]),
                                         np.concatenate([regions.y, regions.y]),
                                         np.concatenate([regions.x, regions.x[::-1]]), len(regions))
        which = rng.random(len(regions)) < rng.uniform(0.0, 1.0)
        steps = int(rng.integers(0, 4))
        new, old = grow(regions, (h, w), which, steps), _lexsort_grow(regions, (h, w), which, steps)
        for field in ("index", "y", "x", "starts"):
            assert np.array_equal(getattr(new, field), getattr(old, field)), field
            assert getattr(new, field).dtype == getattr(old, field).dtype, field
