"""A JPEG's quantization: its noise floor keeps block artefacts out of the detections.

On a dark 8-bit sky with a couple of grey levels of noise, a JPEG at quality 50 rounds the sky's
noise into smooth 8 x 8-block patterns the size of a star, hundreds per frame, and flattens its
quietest blocks (:mod:`startrack.detect._compression`). Detecting the file (an
:class:`startrack.io.Image` with its ``compression_step``) raises the noise to the quantization's
floor when the unfloored threshold finds a crowd of spots; the same pixels given as an array are
detected as they are.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image as PILImage

from startrack.detect import StarDetector, compression_noise_floor, detect
from startrack.io import read_image
from startrack.simulate import render_gaussian_psf

SHAPE = (512, 512)
NOISE_DN = 2.0  # grey levels of sky noise before compression
SKY_DN = 8.0


def _stars(seed: int = 3, faintest_dn: float = 15.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, peak) of 25 stars on a jittered grid, px and grey levels, peaks ``faintest_dn``-120 DN."""
    rng = np.random.default_rng(seed)
    gy, gx = np.mgrid[50:470:90, 50:470:90]
    x = gx.ravel() + rng.uniform(-10, 10, gx.size)
    y = gy.ravel() + rng.uniform(-10, 10, gy.size)
    return x, y, np.exp(rng.uniform(np.log(faintest_dn), np.log(120.0), x.size))


def _jpeg(tmp_path, quality: int, colour: bool = False, noise_dn: float = NOISE_DN, faintest_dn: float = 15.0
          ) -> tuple[str, np.ndarray, np.ndarray]:
    """A JPEG file of the stars at ``quality``, grey (or the same grey in R, G and B), with
    ``noise_dn`` grey levels of sky noise before compression."""
    x, y, peak = _stars(faintest_dn=faintest_dn)
    sigma_px = 1.3
    mean = render_gaussian_psf(SHAPE, x, y, peak * 2 * np.pi * sigma_px**2, sigma_px) + SKY_DN
    grey = np.clip(np.rint(mean + np.random.default_rng(5).normal(0.0, noise_dn, SHAPE)), 0, 255).astype(np.uint8)
    pixels = PILImage.fromarray(np.dstack([grey] * 3) if colour else grey)
    path = tmp_path / f"sky_q{quality}_{noise_dn:g}dn{'_rgb' if colour else ''}.jpg"
    pixels.save(path, quality=quality)
    return str(path), x, y


def _counts(found, x, y) -> tuple[int, int]:
    """(stars found, detections near no star) within 1.5 px."""
    near = np.hypot(x[:, None] - found.x[None], y[:, None] - found.y[None]) < 1.5  # px
    return int(near.any(axis=1).sum()), int((~near.any(axis=0)).sum())


def test_the_floor_keeps_block_artefacts_out(tmp_path):
    path, x, y = _jpeg(tmp_path, 50)
    image = read_image(path)
    stars_raw, false_raw = _counts(detect(image.data), x, y)
    stars, false = _counts(detect(image), x, y)
    assert false_raw >= 50, f"the unfloored detection should show the artefacts: {false_raw}"
    assert false <= false_raw / 10, f"{false} artefacts detected with the floor, {false_raw} without"
    assert stars >= 0.8 * x.size and stars >= stars_raw - 3, f"{stars} stars with the floor, {stars_raw} without"


@pytest.mark.parametrize("quality", [50, 60])
def test_a_sky_the_compression_left_flat_keeps_its_faint_stars(tmp_path, quality):
    """At 0.7 grey levels of noise no noise rounds up to a step: there are no patterns, the
    unfloored threshold finds no crowd of spots, and the noise floor is not applied (it would take
    the faint stars, peaks down to 3 grey levels); the clutter filter's floor still is."""
    path, x, y = _jpeg(tmp_path, quality, noise_dn=0.7, faintest_dn=3.0)
    image = read_image(path)
    stars_raw, false_raw = _counts(detect(image.data), x, y)
    stars, false = _counts(detect(image), x, y)
    assert stars >= stars_raw and stars >= 0.8 * x.size, f"{stars} stars with the floor, {stars_raw} without"
    assert false <= false_raw + 2


def test_a_lossless_file_and_an_array_keep_their_settings(tmp_path):
    detector = StarDetector()
    path = tmp_path / "sky.png"
    PILImage.fromarray(np.full((64, 64), 9, np.uint8)).save(path)
    assert read_image(path).compression_step == 0.0
    assert detector.for_image(read_image(path)) is detector
    assert detector.for_image(np.zeros((64, 64))) is detector


def test_the_step_is_read_from_the_luminance_table(tmp_path):
    """Pillow's quality 50 is the T.81 Annex K table itself: (0, 1) = 11 and (1, 0) = 12."""
    path, _, _ = _jpeg(tmp_path, 50)
    image = read_image(path)
    assert image.compression_step == pytest.approx(11.5)
    cfg = StarDetector().for_image(image)
    assert cfg.compression_noise == pytest.approx(compression_noise_floor(11.5, 5.0))
    assert StarDetector(sigma=4.0).for_image(image).compression_noise > cfg.compression_noise  # same artefact, lower k


def test_summed_colour_planes_carry_three_steps(tmp_path):
    path, _, _ = _jpeg(tmp_path, 75, colour=True)
    grey_step = read_image(path, channel="g").compression_step
    assert grey_step > 0
    assert read_image(path).compression_step == pytest.approx(3 * grey_step)


def test_a_higher_floor_set_by_hand_is_kept(tmp_path):
    path, _, _ = _jpeg(tmp_path, 90)
    detector = StarDetector(compression_noise=50.0)
    assert detector.for_image(read_image(path)) is detector


def test_a_negative_floor_is_refused():
    from startrack.errors import InvalidInputError

    with pytest.raises(InvalidInputError, match="compression_noise"):
        StarDetector(compression_noise=-1.0)


def test_the_clutter_reference_is_raised_with_the_floor():
    from startrack.detect._background import tiled_background, with_clutter_floor

    rng = np.random.default_rng(0)
    sky = rng.normal(10.0, 0.2, (128, 128)).astype(np.float32)
    sky[:64] += rng.normal(0.0, 1.0, (64, 128)).astype(np.float32)  # a busier half
    model = tiled_background(sky, 16)
    reference = model.tiles.clutter_reference
    raised = with_clutter_floor(model, 4 * reference)
    np.testing.assert_allclose(raised.tiles.clutter, model.tiles.clutter / 4, rtol=1e-12)
    assert with_clutter_floor(model, reference / 2) is model
